//! The generated buildings the surrogate examples measure on (`surrogate_error`,
//! `surrogate_near`): a two-floor campus of 290 vertices and a mall floor of 565.

use std::sync::Arc;

use trailprint::building::Building;
use trailprint::gp::{Kernel, fit_kernel};
use trailprint::surveyor::Surveyor;
use trailprint::synth::{SynthParams, generate};

/// Who walks: the human model when an argument says `human`, else the robot.
pub fn model_from_args() -> (bool, Surveyor) {
    let human = std::env::args().any(|a| a == "human");
    let model = if human {
        Surveyor::human()
    } else {
        Surveyor::robot()
    };
    (human, model)
}

/// (name, floors, rooms per side, corridor length m, room depth m).
pub const CASES: [(&str, usize, usize, f64, f64); 2] =
    [("campus", 2, 6, 48.0, 8.0), ("mall", 1, 12, 120.0, 12.0)];

/// The generated building of one of [`CASES`].
pub fn building(case: (&str, usize, usize, f64, f64)) -> trailprint::Result<Arc<Building>> {
    let (name, floors, rooms, corridor, depth) = case;
    let params = SynthParams {
        name: name.into(),
        floors,
        rooms_per_side: rooms,
        corridor_length_m: corridor,
        room_depth_m: depth,
        ..SynthParams::default()
    };
    Ok(Arc::new(Building::from_file(
        generate(&params)?.file,
        name,
    )?))
}

/// Every building of [`CASES`] with its name and the kernel fitted on its pilot data.
pub fn fitted() -> trailprint::Result<Vec<(&'static str, Arc<Building>, Kernel)>> {
    CASES
        .iter()
        .map(|&case| {
            let b = building(case)?;
            let kernel = fit_kernel(&b.pilot)?.kernel;
            Ok((case.0, b, kernel))
        })
        .collect()
}

/// Prints the head of a Markdown table with these columns.
pub fn table_head(columns: &[&str]) {
    println!("| {} |", columns.join(" | "));
    println!("|{}", "---|".repeat(columns.len()));
}
