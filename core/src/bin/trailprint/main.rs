//! `trailprint`: plan Wi-Fi fingerprint survey walks from the command line.
//!
//! Each subcommand lives in its own `cmd_<name>.rs`; this file holds only the command
//! enum and the dispatch. Errors print as `error: <message>` and exit with status 1.

use clap::{Parser, Subcommand};

mod cmd_evaluate;
mod cmd_fit;
mod cmd_generate;
mod cmd_render;
mod cmd_utility;
mod opts;

#[derive(Parser)]
#[command(
    name = "trailprint",
    version,
    about = "Plan informative Wi-Fi fingerprint survey walks"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Fit the kernel hyperparameters (sf2, ell, sn2) on a building's pilot data.
    Fit(cmd_fit::Args),
    /// Evaluate the utility (mutual information, nats) of one or more walks.
    Utility(cmd_utility::Args),
    /// Generate a synthetic building (graph, access points, pilot, test and dense survey).
    Generate(cmd_generate::Args),
    /// Localization error of a walk's fingerprint map (SPEC section 5).
    Evaluate(cmd_evaluate::Args),
    /// Draw a building, a walk and the posterior uncertainty as SVG.
    Render(cmd_render::Args),
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Fit(a) => cmd_fit::run(a),
        Command::Utility(a) => cmd_utility::run(a),
        Command::Generate(a) => cmd_generate::run(a),
        Command::Evaluate(a) => cmd_evaluate::run(a),
        Command::Render(a) => cmd_render::run(a),
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
