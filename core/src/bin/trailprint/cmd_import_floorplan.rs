//! `trailprint import-floorplan FILE`: an indoor map (OpenStreetMap indoor GeoJSON, IMDF
//! folder or zip) to a survey-building/1 building, into the database or a file.

use std::path::{Path, PathBuf};

use trailprint::Building;
use trailprint::floorplan::{DEFAULT_SPACING_M, Format, ImportOptions, import_path};
use trailprint::store::ImportOptions as StoreImport;

use crate::store_cli::{open_store, write_output};

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum FormatArg {
    /// OpenStreetMap indoor data as GeoJSON (Simple Indoor Tagging, Overpass exports)
    OsmIndoor,
    /// IMDF: a folder of GeoJSON files or a zip archive of one
    Imdf,
}

#[derive(clap::Args)]
pub struct Args {
    /// The floor plan: a GeoJSON file, an IMDF folder or an IMDF .zip
    file: PathBuf,
    /// Input format [default: guessed: a folder or .zip is IMDF, so is GeoJSON whose
    /// features carry `feature_type`; anything else OSM indoor]
    #[arg(long, value_enum)]
    format: Option<FormatArg>,
    /// Building name [default: the venue or building name in the plan, else the file name]
    #[arg(long)]
    name: Option<String>,
    /// Grid spacing of the walkable network inside corridors, areas and rooms, metres
    #[arg(long, default_value_t = DEFAULT_SPACING_M, value_name = "M")]
    spacing: f64,
    /// Write the building to this file (`-`: standard output) instead of the database
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
    /// Replace a building of the same name in the database
    #[arg(long, conflicts_with = "output")]
    replace: bool,
}

pub fn run(args: &Args, db: Option<&Path>) -> trailprint::Result<()> {
    let options = ImportOptions {
        format: args.format.map(|f| match f {
            FormatArg::OsmIndoor => Format::OsmIndoor,
            FormatArg::Imdf => Format::Imdf,
        }),
        name: args.name.clone(),
        spacing_m: args.spacing,
        ..ImportOptions::default()
    };
    let result = import_path(&args.file, &options)?;
    let origin = args.file.display().to_string();
    for w in &result.warnings {
        eprintln!("warning: {w}");
    }
    for d in &result.dropped {
        eprintln!("warning: dropped a part not connected to the rest: {d}");
    }
    let s = &result.stats;
    let what = format!(
        "{} floors, {} walkable spaces, {} doors, {} stairs/elevators, {} vertices, {} edges",
        s.floors, s.spaces, s.doors, s.connectors, s.vertices, s.edges
    );
    let hint = "no pilot data: plan with --kernel SF2,ELL,SN2, or add pilot fingerprints with \
                `trailprint pilot add NAME FILE.json`";
    if let Some(out) = &args.output {
        let mut text = result.file.to_json();
        text.push('\n');
        write_output(out, &text)?;
        if out != Path::new("-") {
            println!("wrote {:?} to {}: {what}", result.file.name, out.display());
            println!("{hint}");
        }
        return Ok(());
    }
    let building = Building::from_file(result.file, &origin)?;
    let store = open_store(db)?;
    let report = store.import_building(
        &building,
        Some(&origin),
        &StoreImport {
            replace: args.replace,
            progress: None,
        },
    )?;
    match report.replaced {
        Some(old) => println!(
            "replaced building {old} by building {} {:?}: {what}",
            report.id, report.name
        ),
        None => println!("imported building {} {:?}: {what}", report.id, report.name),
    }
    println!("{hint}");
    Ok(())
}
