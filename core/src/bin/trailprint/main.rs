//! The `trailprint` command line: one subcommand per file (`cmd_<name>.rs`), each with its
//! clap `Args` and a `run` function. Errors print `error: <message>` and exit with 1.

mod cmd_evaluate;
mod cmd_generate;
mod cmd_render;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "trailprint",
    version,
    about = "Plan Wi-Fi fingerprint site-survey walks"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Generate a synthetic building (graph, access points, pilot, test and dense survey).
    Generate(cmd_generate::Args),
    /// Localization error of a walk (SPEC section 5).
    Evaluate(cmd_evaluate::Args),
    /// Draw a building (and optionally a walk) as SVG.
    Render(cmd_render::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Generate(args) => cmd_generate::run(args),
        Command::Evaluate(args) => cmd_evaluate::run(args),
        Command::Render(args) => cmd_render::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
