//! `trailprint generate`: write a synthetic building file.

use std::path::PathBuf;

use trailprint::synth::{SynthParams, generate, to_json_text};
use trailprint::{Error, Result};

/// Generate a synthetic building; unset options take the demo building's values.
#[derive(clap::Args)]
pub struct Args {
    /// Output file (`-` for standard output).
    #[arg(long)]
    out: PathBuf,
    /// Number of floors.
    #[arg(long)]
    floors: Option<usize>,
    /// Rooms on each side of the corridor.
    #[arg(long)]
    rooms: Option<usize>,
    /// Corridor length, metres.
    #[arg(long)]
    corridor_length: Option<f64>,
    /// Number of access points.
    #[arg(long)]
    aps: Option<usize>,
    /// Spacing of the rooms' grid graphs, metres.
    #[arg(long)]
    grid_spacing: Option<f64>,
    /// Room depth, metres.
    #[arg(long)]
    room_depth: Option<f64>,
    /// Number of pilot points.
    #[arg(long)]
    pilot: Option<usize>,
    /// Number of test points.
    #[arg(long)]
    test_points: Option<usize>,
    /// Spacing of the dense survey along edges, metres.
    #[arg(long)]
    dense_spacing: Option<f64>,
    /// Building name [default: the demo building's with the default options, else one
    /// that lists the options, so that two generated buildings can share a database].
    #[arg(long)]
    name: Option<String>,
    /// Seed of every random choice.
    #[arg(long)]
    seed: Option<u64>,
}

pub fn run(args: Args) -> Result<()> {
    let d = SynthParams::default();
    let mut params = SynthParams {
        name: args.name.clone().unwrap_or(d.name.clone()),
        floors: args.floors.unwrap_or(d.floors),
        corridor_length_m: args.corridor_length.unwrap_or(d.corridor_length_m),
        rooms_per_side: args.rooms.unwrap_or(d.rooms_per_side),
        room_depth_m: args.room_depth.unwrap_or(d.room_depth_m),
        grid_spacing_m: args.grid_spacing.unwrap_or(d.grid_spacing_m),
        aps: args.aps.unwrap_or(d.aps),
        pilot: args.pilot.unwrap_or(d.pilot),
        test_points: args.test_points.unwrap_or(d.test_points),
        dense_spacing_m: args.dense_spacing.unwrap_or(d.dense_spacing_m),
        seed: args.seed.unwrap_or(d.seed),
        ..d.clone()
    };
    if args.name.is_none() && params != d {
        params.name = described_name(&params);
    }
    let synth = generate(&params)?;
    let text = to_json_text(&synth.file);
    if args.out.as_os_str() == "-" {
        print!("{text}");
        return Ok(());
    }
    std::fs::write(&args.out, text).map_err(|e| Error::io(&args.out, e))?;
    eprintln!(
        "wrote {}: {} vertices, {} edges, {} access points, {} pilot, {} test, {} dense survey points",
        args.out.display(),
        synth.file.vertices.len(),
        synth.file.edges.len(),
        synth.model.access_points().len(),
        synth.file.pilot.len(),
        synth.file.test_points.len(),
        synth.file.dense_survey.len()
    );
    Ok(())
}

/// The name of a generated building that is not the demo: the options it differs from
/// the demo by, as typed (`Synthetic building (--rooms 40 --corridor-length 400)`), which
/// also says how to generate it again; `trailprint import` refuses a second building of
/// the same name.
fn described_name(p: &SynthParams) -> String {
    let d = SynthParams::default();
    let s = |v: &dyn std::fmt::Display| v.to_string();
    let options = [
        ("floors", s(&p.floors), s(&d.floors)),
        ("rooms", s(&p.rooms_per_side), s(&d.rooms_per_side)),
        (
            "corridor-length",
            s(&p.corridor_length_m),
            s(&d.corridor_length_m),
        ),
        ("room-depth", s(&p.room_depth_m), s(&d.room_depth_m)),
        ("grid-spacing", s(&p.grid_spacing_m), s(&d.grid_spacing_m)),
        ("aps", s(&p.aps), s(&d.aps)),
        ("pilot", s(&p.pilot), s(&d.pilot)),
        ("test-points", s(&p.test_points), s(&d.test_points)),
        (
            "dense-spacing",
            s(&p.dense_spacing_m),
            s(&d.dense_spacing_m),
        ),
        ("seed", s(&p.seed), s(&d.seed)),
    ];
    let given: Vec<String> = options
        .iter()
        .filter(|(_, v, dv)| v != dv)
        .map(|(flag, v, _)| format!("--{flag} {v}"))
        .collect();
    format!("Synthetic building ({})", given.join(" "))
}
