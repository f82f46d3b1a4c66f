//! `trailprint buildings [--json]`: what the database holds.

use std::path::Path;

use crate::store_cli::{open_store, printable};

#[derive(clap::Args)]
pub struct Args {
    /// Print a JSON array instead of a table
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args, db: Option<&Path>) -> trailprint::Result<()> {
    let store = open_store(db)?;
    let list = store.list_buildings()?;
    if args.json {
        // Plain data with string keys serialises.
        println!(
            "{}",
            serde_json::to_string_pretty(&list).unwrap_or_default()
        );
        return Ok(());
    }
    if list.is_empty() {
        println!("no buildings (import one with `trailprint import FILE`)");
        return Ok(());
    }
    // Names are printed escaped: a name is data from a file, and one made of terminal
    // escape sequences must not drive the terminal.
    let names: Vec<String> = list.iter().map(|b| printable(&b.name)).collect();
    let width = crate::store_cli::column_width(&names, 4);
    println!(
        "{:>4}  {:<width$}  {:>6} {:>8} {:>6} {:>6} {:>6} {:>6} {:>5} {:>5} {:>8} {:>9}",
        "id",
        "name",
        "floors",
        "vertices",
        "edges",
        "pilot",
        "tests",
        "dense",
        "fits",
        "plans",
        "sessions",
        "collected"
    );
    for (b, name) in list.iter().zip(&names) {
        println!(
            "{:>4}  {:<width$}  {:>6} {:>8} {:>6} {:>6} {:>6} {:>6} {:>5} {:>5} {:>8} {:>9}",
            b.id,
            name,
            b.floors,
            b.vertices,
            b.edges,
            b.pilot,
            b.test_points,
            b.dense_survey,
            b.fits,
            b.plans,
            b.sessions,
            b.collected
        );
    }
    Ok(())
}
