//! `trailprint export NAME -o FILE`: a building back to survey-building/1, or its collected
//! fingerprints as CSV or JSON.

use std::path::{Path, PathBuf};

use trailprint::store::{collected_csv, collected_json};

use crate::store_cli::{building_ref, is_file_spec, load_building, open_store, write_output};

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum Collected {
    Csv,
    Json,
}

#[derive(clap::Args)]
pub struct Args {
    /// Building name (or store id); a building file is read, validated and written back
    /// in canonical form
    name: String,
    /// Output file; `-` writes to standard output. Written atomically.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Export the fingerprints collected in survey sessions instead of the building
    #[arg(long, value_name = "FORMAT")]
    collected: Option<Collected>,
    /// With --collected: only this session
    #[arg(long, value_name = "ID", requires = "collected")]
    session: Option<i64>,
}

pub fn run(args: &Args, db: Option<&Path>) -> trailprint::Result<()> {
    if args.collected.is_none() && is_file_spec(&args.name) {
        let mut text = load_building(&args.name, db)?.to_file().to_json();
        text.push('\n');
        return write_output(&args.output, &text);
    }
    let store = open_store(db)?;
    let building = building_ref(&store, &args.name)?;
    let text = match args.collected {
        None => {
            let mut text = store.export_building(building)?.to_json();
            text.push('\n');
            text
        }
        Some(format) => {
            let info = store.building_info(building)?;
            let list = store.list_collected(building, args.session)?;
            match format {
                Collected::Csv => collected_csv(&list),
                Collected::Json => collected_json(&info.name, &list) + "\n",
            }
        }
    };
    write_output(&args.output, &text)
}
