//! `trailprint import FILE [--replace]`: a building file into the database, all or nothing.

use std::path::{Path, PathBuf};
use std::time::Duration;

use trailprint::Building;
use trailprint::store::{ImportOptions, read_import_text};

use crate::store_cli::open_store;

/// Hidden test hook: when set to a number of microseconds, the import prints
/// `progress <rows>` on stderr every 100 rows and sleeps that long, inside its transaction,
/// so that the kill tests (core/tests/store_kill.rs) can SIGKILL it mid-way. Unset, or not
/// a number, it does nothing.
pub const TEST_DELAY_ENV: &str = "TRAILPRINT_TEST_IMPORT_DELAY_US";

#[derive(clap::Args)]
pub struct Args {
    /// Building file (survey-building/1 JSON, at most 64 MiB); `-` reads standard input
    file: PathBuf,
    /// Replace a building of the same name (refused if it has survey sessions)
    #[arg(long)]
    replace: bool,
}

pub fn run(args: &Args, db: Option<&Path>) -> trailprint::Result<()> {
    let origin = if args.file == Path::new("-") {
        "<stdin>".to_string()
    } else {
        args.file.display().to_string()
    };
    // Parse and validate before opening the database: a bad file never touches it.
    let text = read_import_text(&args.file)?;
    let building = Building::from_json(&text, &origin)?;
    drop(text);
    let store = open_store(db)?;

    let delay = std::env::var(TEST_DELAY_ENV)
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
        .map(Duration::from_micros);
    let hook = move |rows: u64| {
        if let Some(d) = delay
            && rows.is_multiple_of(100)
        {
            eprintln!("progress {rows}");
            std::thread::sleep(d);
        }
    };
    let options = ImportOptions {
        replace: args.replace,
        progress: delay.is_some().then_some(&hook as &dyn Fn(u64)),
    };
    let report = store.import_building(&building, Some(&origin), &options)?;
    let what = format!(
        "{} vertices, {} edges, {} pilot, {} test points, {} dense survey fingerprints",
        building.vertices.len(),
        building.edges.len(),
        building.pilot.len(),
        building.test_points.len(),
        building.dense_survey.len()
    );
    match report.replaced {
        Some(old) => println!(
            "replaced building {old} by building {} {:?}: {what}",
            report.id, report.name
        ),
        None => println!("imported building {} {:?}: {what}", report.id, report.name),
    }
    Ok(())
}
