//! The generated buildings the surrogate examples measure on (`surrogate_error`,
//! `surrogate_near`): a two-floor campus of 290 vertices and a mall floor of 565; and
//! what the examples that take a building file share (`scale_probe`, `replan_compare`).
//! Not every example uses every item.
#![allow(dead_code)]

use std::path::Path;
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use trailprint::building::Building;
use trailprint::gp::{Kernel, Point, fit_kernel};
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

/// The command line, when it has at least `count` words (the program's name included),
/// else an error that shows `usage`.
pub fn args_or_usage(count: usize, usage: &str) -> trailprint::Result<Vec<String>> {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < count {
        return Err(trailprint::Error::InvalidRequest(format!("usage: {usage}")));
    }
    Ok(a)
}

/// Argument `i` of `args` as a number, else an error naming it as `what`.
pub fn number(args: &[String], i: usize, what: &str) -> trailprint::Result<f64> {
    args[i].parse().map_err(|_| {
        trailprint::Error::InvalidRequest(format!("{what}: not a number: {}", args[i]))
    })
}

/// A building file with its kernel: the file's own, else fitted on its pilot data.
pub fn load_with_kernel(path: &str) -> trailprint::Result<(Arc<Building>, Kernel)> {
    let b = Arc::new(Building::load(Path::new(path))?);
    let kernel = match b.kernel {
        Some(k) => k,
        None => fit_kernel(&b.pilot)?.kernel,
    };
    Ok((b, kernel))
}

/// The surveyor an argument names: `human`, else the robot.
pub fn model_named(name: &str) -> Surveyor {
    if name == "human" {
        Surveyor::human()
    } else {
        Surveyor::robot()
    }
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

/// The building file `file` (its kernel as [`load_with_kernel`]), a saved plan's walk on
/// it (`trailprint plan --json`) and the problem from that walk's start to its end with
/// `budget`, for the surveyor named `model`.
pub fn plan_problem(
    file: &str,
    plan: &str,
    model: &str,
    budget: f64,
) -> trailprint::Result<(trailprint::plan::Problem, Vec<usize>)> {
    let (b, kernel) = load_with_kernel(file)?;
    let walk = plan_walk(&b, plan)?;
    let (start, end) = (walk[0], *walk.last().expect("a walk has a vertex"));
    let p = trailprint::plan::Problem::new(b, kernel, model_named(model), start, end, budget)?;
    Ok((p, walk))
}

/// The walk of a saved plan (`trailprint plan --json`) as vertex indices of `b`.
pub fn plan_walk(b: &Building, path: &str) -> trailprint::Result<Vec<usize>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| trailprint::Error::InvalidRequest(format!("{path}: {e}")))?;
    let plan: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| trailprint::Error::InvalidRequest(format!("{path}: {e}")))?;
    plan["walk"]
        .as_array()
        .ok_or_else(|| trailprint::Error::InvalidRequest(format!("{path}: no walk")))?
        .iter()
        .map(|v| b.require_vertex(v.as_str().unwrap_or("")))
        .collect()
}

/// A robot's samples every 0.5 m along a random walk on `b` from vertex 0 (seeded): at
/// least `n` of them, each with the vertex its edge leads to.
pub fn random_walk_samples(b: &Building, seed: u64, n: usize) -> (Vec<Point>, Vec<usize>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut points, mut towards) = (Vec::new(), Vec::new());
    let (mut at, mut carry) = (0usize, 0.0f64);
    while points.len() < n {
        let nb = b.neighbours(at);
        let (next, e) = nb[(rng.next_u64() % nb.len() as u64) as usize];
        let len = b.edges[e].length;
        let (pa, pb) = (b.vertices[at].pos, b.vertices[next].pos);
        let mut s = carry;
        while s < len {
            let t = s / len;
            let floor = if t <= 0.5 { pa.floor } else { pb.floor };
            points.push(Point::new(
                pa.x + t * (pb.x - pa.x),
                pa.y + t * (pb.y - pa.y),
                floor,
            ));
            towards.push(next);
            s += 0.5;
        }
        carry = s - len;
        at = next;
    }
    (points, towards)
}

/// `points` as observations with no extra noise (a robot's samples).
pub fn observations(points: &[Point]) -> Vec<trailprint::utility::Observation> {
    points
        .iter()
        .map(|&pos| trailprint::utility::Observation {
            pos,
            extra_noise: 0.0,
        })
        .collect()
}
