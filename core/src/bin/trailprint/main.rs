//! `trailprint`: plan Wi-Fi fingerprint survey walks from the command line.
//!
//! Each subcommand lives in its own `cmd_<name>.rs`; this file holds only the command
//! enum and the dispatch. Errors print as `error: <message>` on stderr with exit code 1;
//! usage errors are clap's (exit code 2). Commands that touch the database take the global
//! `--db PATH` (helpers in `store_cli.rs`).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cmd_bench;
mod cmd_buildings;
mod cmd_bundle;
mod cmd_delete;
mod cmd_demo;
mod cmd_evaluate;
mod cmd_experiment;
mod cmd_export;
mod cmd_fit;
mod cmd_generate;
mod cmd_import;
mod cmd_import_floorplan;
mod cmd_pilot;
mod cmd_plan;
mod cmd_plans;
mod cmd_render;
mod cmd_sessions;
mod cmd_simulate;
mod cmd_team_plan;
mod cmd_utility;
mod cmd_vertices;
mod opts;
mod progress;
mod store_cli;
mod walk_text;

#[derive(Parser)]
#[command(
    name = "trailprint",
    version,
    about = "Plan informative Wi-Fi fingerprint survey walks"
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
    /// The main job: load the bundled demo building into the database, fit, plan, print.
    Demo(cmd_demo::Args),
    /// Fit the kernel hyperparameters (sf2, ell, sn2) on a building's pilot data.
    Fit(cmd_fit::Args),
    /// Evaluate the utility (mutual information, nats) of one or more walks.
    Utility(cmd_utility::Args),
    /// Generate a synthetic building (graph, access points, pilot, test and dense survey).
    Generate(cmd_generate::Args),
    /// Localization error of a walk's (or a session's) fingerprint map (SPEC section 5).
    Evaluate(cmd_evaluate::Args),
    /// The paper's evaluation: algorithms x budgets x runs, CSV and SVG charts.
    Experiment(cmd_experiment::Args),
    /// Draw a building, a walk and the posterior uncertainty as SVG.
    Render(cmd_render::Args),
    /// Import a survey-building/1 file into the database.
    Import(cmd_import::Args),
    /// Import an indoor map (OpenStreetMap indoor GeoJSON or IMDF) as a building.
    ImportFloorplan(cmd_import_floorplan::Args),
    /// Pilot data: `pilot add NAME FILE.json` adds pilot fingerprints to a building.
    Pilot(cmd_pilot::Args),
    /// List the buildings in the database.
    Buildings(cmd_buildings::Args),
    /// Export a building (or its collected fingerprints) to a file.
    Export(cmd_export::Args),
    /// Delete a building and everything recorded for it.
    Delete(cmd_delete::Args),
    /// Export or import survey bundles (several surveyors, offline merge).
    Bundle(cmd_bundle::Args),
    /// Plan walks for several surveyors that complement each other.
    TeamPlan(cmd_team_plan::Args),
    /// Plan a survey walk from a start to an end vertex within a budget.
    Plan(cmd_plan::Args),
    /// List the saved plans (`plans [NAME]`), or print one (`plans show ID`).
    Plans(cmd_plans::Args),
    /// List a building's vertices (id, label, floor, position) to pick a start and an end.
    Vertices(cmd_vertices::Args),
    /// Benchmark the planners: algorithms x budgets x seeds, Markdown and CSV tables.
    Bench(cmd_bench::Args),
    /// Plan a walk, then walk it as a survey session with a simulated surveyor.
    Simulate(cmd_simulate::Args),
    /// List the survey sessions in the database (building, surveyor, status, walked,
    /// samples, utility).
    Sessions(cmd_sessions::Args),
}

/// Ends quietly when the reader of standard output goes away (`trailprint ... | head`), as
/// Unix tools do. Rust starts programs with SIGPIPE ignored, so a write to a closed pipe
/// would otherwise make `println!` panic. Database writes are transactions, so being
/// killed mid-command loses nothing already committed.
#[cfg(unix)]
fn die_on_closed_pipe() {
    // SAFETY: called first thing in `main`, before any thread exists; SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn main() -> ExitCode {
    #[cfg(unix)]
    die_on_closed_pipe();
    let cli = Cli::parse();
    let db = cli.db.as_deref();
    let result = match cli.command {
        Command::Demo(a) => cmd_demo::run(a, db),
        Command::TeamPlan(a) => cmd_team_plan::run(a, db),
        Command::Bundle(a) => cmd_bundle::run(a, db),
        Command::Fit(a) => cmd_fit::run(a, db),
        Command::Utility(a) => cmd_utility::run(a, db),
        Command::Generate(a) => cmd_generate::run(a),
        Command::Evaluate(a) => cmd_evaluate::run(a, db),
        Command::Experiment(a) => cmd_experiment::run(a, db),
        Command::Render(a) => cmd_render::run(a, db),
        Command::Import(a) => cmd_import::run(&a, db),
        Command::ImportFloorplan(a) => cmd_import_floorplan::run(&a, db),
        Command::Pilot(a) => cmd_pilot::run(a, db),
        Command::Buildings(a) => cmd_buildings::run(&a, db),
        Command::Export(a) => cmd_export::run(&a, db),
        Command::Delete(a) => cmd_delete::run(&a, db),
        Command::Plan(a) => cmd_plan::run(a, db),
        Command::Plans(a) => cmd_plans::run(a, db),
        Command::Vertices(a) => cmd_vertices::run(&a, db),
        Command::Bench(a) => cmd_bench::run(a),
        Command::Simulate(a) => cmd_simulate::run(a, db),
        Command::Sessions(a) => cmd_sessions::run(&a, db),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
