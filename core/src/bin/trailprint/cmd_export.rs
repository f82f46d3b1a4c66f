//! `trailprint export NAME -o FILE`: a building back to survey-building/1, its collected
//! fingerprints as CSV or JSON, every scan in the layout positioning engines read
//! (`--fingerprints`, UJIIndoorLoc or JSON lines), or the radio map (`--radio-map`).

use std::path::{Path, PathBuf};

use trailprint::building::PartSpec;
use trailprint::radiomap::{
    SessionPeople, jsonl, radio_map, radio_map_csv, radio_map_geojson, scan_rows, uji_csv,
    walkable_grid,
};
use trailprint::store::{BuildingRef, Store, collected_csv, collected_json};
use trailprint::{Building, Result};

use crate::opts::KernelOpts;
use crate::store_cli::{building_ref, is_file_spec, load_building, open_store, write_output};

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum Collected {
    Csv,
    Json,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum ScanFormat {
    /// The UJIIndoorLoc columns (WAPnnn, LONGITUDE, LATITUDE, FLOOR, ...), plus a
    /// `FILE.waps.csv` table of the access point names
    Uji,
    /// One JSON object per scan and line
    Jsonl,
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
    #[arg(long, value_name = "FORMAT", conflicts_with_all = ["fingerprints", "radio_map"])]
    collected: Option<Collected>,
    /// With --collected or --fingerprints: only this session
    #[arg(long, value_name = "ID")]
    session: Option<i64>,
    /// Export every scan (pilot data and sessions), one row each, for positioning engines
    #[arg(long, conflicts_with = "radio_map")]
    fingerprints: bool,
    /// With --fingerprints: the layout
    #[arg(long, value_enum, default_value = "uji", requires = "fingerprints")]
    format: ScanFormat,
    /// Export the predicted mean and standard deviation of every access point's RSS on a
    /// grid over the walkable space (FILE.csv, or FILE.geojson for buildings with `geo`)
    #[arg(long)]
    radio_map: bool,
    /// With --radio-map: grid spacing, metres
    #[arg(long, default_value_t = 1.0, value_name = "M", requires = "radio_map")]
    grid: f64,
    /// Export only this floor of the building (repeat for several): a part to plan when the
    /// whole building needs more memory than the device has
    #[arg(long = "floor", value_name = "ID", conflicts_with_all = ["collected", "fingerprints", "radio_map"])]
    floors: Vec<i64>,
    /// Export only the vertices within --radius metres' walk of this vertex (on the floors
    /// kept); repeat with a --radius each for the walks of a team (their union)
    #[arg(long, value_name = "VERTEX", requires = "radius", conflicts_with_all = ["collected", "fingerprints", "radio_map"])]
    around: Vec<String>,
    /// With --around: the walking distance, metres (one for each --around, in order)
    #[arg(
        long,
        value_name = "M",
        requires = "around",
        allow_negative_numbers = true
    )]
    radius: Vec<f64>,
    /// With --floor or --around: the part's name [default: the building's, followed by
    /// what was kept]
    #[arg(long, value_name = "NAME")]
    part_name: Option<String>,
    #[command(flatten)]
    kernel: KernelOpts,
}

/// Surveyor name and device of each session of a stored building.
fn people(store: &Store, building_id: i64) -> Result<SessionPeople> {
    Ok(store
        .session_provenance(building_id)?
        .into_iter()
        .map(|p| (p.session_id, (p.surveyor_name, p.device)))
        .collect())
}

pub fn run(args: &Args, db: Option<&Path>) -> Result<()> {
    if args.session.is_some() && args.collected.is_none() && !args.fingerprints {
        return Err(trailprint::Error::InvalidRequest(
            "--session goes with --collected or --fingerprints".into(),
        ));
    }
    if args.fingerprints || args.radio_map {
        return scans(args, db);
    }
    if !args.floors.is_empty() || !args.around.is_empty() {
        return part(args, db);
    }
    if args.part_name.is_some() {
        return Err(trailprint::Error::InvalidRequest(
            "--part-name goes with --floor or --around".into(),
        ));
    }
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

/// `--floor` and `--around`: a part of the building as a building file of its own
/// ([`Building::part`]).
fn part(args: &Args, db: Option<&Path>) -> Result<()> {
    if args.around.len() != args.radius.len() {
        return Err(trailprint::Error::InvalidRequest(format!(
            "each --around takes one --radius: {} --around and {} --radius given",
            args.around.len(),
            args.radius.len()
        )));
    }
    let building = load_building(&args.name, db)?;
    let spec = PartSpec {
        floors: args.floors.clone(),
        around: args
            .around
            .iter()
            .cloned()
            .zip(args.radius.iter().copied())
            .collect(),
        name: args.part_name.clone(),
    };
    let part = building.part(&spec)?;
    let mut text = part.to_file().to_json();
    text.push('\n');
    write_output(&args.output, &text)?;
    eprintln!(
        "{:?}: {} of {} vertices, {:.0} of {:.0} m of edges, {} pilot points",
        part.name,
        part.len(),
        building.len(),
        part.total_edge_length(),
        building.total_edge_length(),
        part.pilot.len()
    );
    Ok(())
}

/// `--fingerprints` and `--radio-map`: the building's scans, from a file (its pilot data)
/// or from the database (pilot data and every session).
fn scans(args: &Args, db: Option<&Path>) -> Result<()> {
    let (building, collected, people): (Building, _, _) = if is_file_spec(&args.name) {
        (
            load_building(&args.name, db)?,
            Vec::new(),
            SessionPeople::new(),
        )
    } else {
        let store = open_store(db)?;
        let bref = building_ref(&store, &args.name)?;
        let id = match bref {
            BuildingRef::Id(id) => id,
            BuildingRef::Name(n) => store.building_info(n)?.id,
        };
        let b = store.get_building(bref)?;
        let list = store.list_collected(bref, args.session)?;
        (b, list, people(&store, id)?)
    };
    let mut rows = scan_rows(&building, &collected, &people);
    if args.session.is_some() {
        rows.retain(|r| r.source == "session");
    }
    if args.fingerprints {
        return match args.format {
            ScanFormat::Jsonl => write_output(&args.output, &jsonl(&rows)),
            ScanFormat::Uji => {
                let (csv, waps) = uji_csv(&rows);
                write_output(&args.output, &csv)?;
                if args.output == Path::new("-") {
                    eprint!("{waps}");
                } else {
                    let table = waps_path(&args.output);
                    write_output(&table, &waps)?;
                    eprintln!(
                        "wrote {} scans to {} and the access point names to {}",
                        rows.len(),
                        args.output.display(),
                        table.display()
                    );
                }
                Ok(())
            }
        };
    }
    let (kernel, _) = args.kernel.resolve(&building)?;
    let grid = walkable_grid(&building, args.grid)?;
    let map = radio_map(&rows, &kernel, grid)?;
    let geojson = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("geojson") || e.eq_ignore_ascii_case("json"));
    let text = if geojson {
        radio_map_geojson(&map, building.geo, &building.name)? + "\n"
    } else {
        radio_map_csv(&map, building.geo)
    };
    write_output(&args.output, &text)?;
    if args.output != Path::new("-") {
        eprintln!(
            "wrote the radio map of {} access points on {} grid points (kernel sf2 {}, ell {}, sn2 {}) to {}",
            map.aps.len(),
            map.points.len(),
            kernel.sf2,
            kernel.ell,
            kernel.sn2,
            args.output.display()
        );
    }
    Ok(())
}

/// `scans.csv` -> `scans.waps.csv`.
fn waps_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "fingerprints".into());
    out.with_file_name(format!("{stem}.waps.csv"))
}
