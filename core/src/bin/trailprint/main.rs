//! `trailprint`: plan Wi-Fi fingerprint survey walks from the command line.
//!
//! Each subcommand lives in its own `cmd_<name>.rs`; this file holds only the command
//! enum and the dispatch. Errors print as `error: <message>` and exit with status 1.

use clap::{Parser, Subcommand};

mod cmd_bench;
mod cmd_fit;
mod cmd_plan;
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
    /// Plan a survey walk from a start to an end vertex within a budget.
    Plan(cmd_plan::Args),
    /// Benchmark the planners: algorithms x budgets x seeds, Markdown and CSV tables.
    Bench(cmd_bench::Args),
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Fit(a) => cmd_fit::run(a),
        Command::Utility(a) => cmd_utility::run(a),
        Command::Plan(a) => cmd_plan::run(a),
        Command::Bench(a) => cmd_bench::run(a),
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
