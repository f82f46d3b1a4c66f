//! `trailprint`: the command line of the survey planner.
//!
//! This file holds only the command enum and the dispatch; each command lives in its own
//! `cmd_<name>.rs` with its `Args` and `run`. Errors print as `error: <message>` on stderr
//! with exit code 1; usage errors are clap's (exit code 2).

mod cmd_buildings;
mod cmd_delete;
mod cmd_export;
mod cmd_import;
mod store_cli;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "trailprint",
    version,
    about = "Plans Wi-Fi fingerprint site-survey walks"
)]
struct Cli {
    /// Database file [default: $XDG_DATA_HOME/trailprint/trailprint.db, or
    /// ~/.local/share/trailprint/trailprint.db, created on first use]
    #[arg(long, global = true, value_name = "PATH")]
    db: Option<PathBuf>,

    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Import a survey-building/1 file into the database
    Import(cmd_import::Args),
    /// List the buildings in the database
    Buildings(cmd_buildings::Args),
    /// Export a building (or its collected fingerprints) to a file
    Export(cmd_export::Args),
    /// Delete a building and everything recorded for it
    Delete(cmd_delete::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let db = cli.db.as_deref();
    let result = match &cli.command {
        Command::Import(args) => cmd_import::run(args, db),
        Command::Buildings(args) => cmd_buildings::run(args, db),
        Command::Export(args) => cmd_export::run(args, db),
        Command::Delete(args) => cmd_delete::run(args, db),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
