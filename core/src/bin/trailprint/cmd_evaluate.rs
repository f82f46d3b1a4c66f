//! `trailprint evaluate`: localization error of a walk (SPEC section 5).

use std::path::PathBuf;
use std::time::Instant;

use trailprint::eval::{EvalOptions, Evaluator, robot_samples};
use trailprint::gp::Kernel;
use trailprint::{Building, Error, Result};

/// Localization error of the fingerprint map built from a walk's robot samples plus the
/// pilot data, against the building's test points.
#[derive(clap::Args)]
pub struct Args {
    /// Building file (survey-building/1).
    #[arg(long)]
    building: PathBuf,
    /// The walk: comma-separated vertex ids. Without it only the pilot data is used.
    #[arg(long)]
    walk: Option<String>,
    /// Kernel hyperparameters `SF2,ELL,SN2` (default: the building's `kernel`).
    #[arg(long)]
    kernel: Option<String>,
    /// Distance between robot scans along the walk, metres.
    #[arg(long, default_value_t = 0.5)]
    interval: f64,
    /// Reference grid spacing, metres.
    #[arg(long, default_value_t = 0.5)]
    grid_step: f64,
    /// Seed of the drawn fingerprints.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// Parses `SF2,ELL,SN2`.
pub(crate) fn parse_kernel(text: &str) -> Result<Kernel> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let bad = || {
        Error::InvalidRequest(format!(
            "--kernel {text:?}: expected three numbers SF2,ELL,SN2 such as 40,6,9"
        ))
    };
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut v = [0.0; 3];
    for (slot, p) in v.iter_mut().zip(&parts) {
        *slot = p.parse().map_err(|_| bad())?;
    }
    let k = Kernel::new(v[0], v[1], v[2]);
    k.validate("--kernel")?;
    Ok(k)
}

/// The kernel from `--kernel`, else the building's.
pub(crate) fn choose_kernel(arg: Option<&str>, building: &Building) -> Result<Option<Kernel>> {
    match arg {
        Some(text) => parse_kernel(text).map(Some),
        None => Ok(building.kernel),
    }
}

/// Resolves a comma-separated walk of vertex ids.
pub(crate) fn parse_walk(text: &str, building: &Building) -> Result<Vec<usize>> {
    let ids: Vec<&str> = text.split(',').map(str::trim).collect();
    building.resolve_walk(&ids)
}

pub fn run(args: Args) -> Result<()> {
    let building = Building::load(&args.building)?;
    let kernel = choose_kernel(args.kernel.as_deref(), &building)?
        .ok_or_else(|| Error::InvalidRequest("no kernel: pass --kernel or fit first".into()))?;
    let walk = match &args.walk {
        Some(text) => parse_walk(text, &building)?,
        None => Vec::new(),
    };
    let samples = if walk.is_empty() {
        Vec::new()
    } else {
        robot_samples(&building, &walk, args.interval)?
    };
    let options = EvalOptions {
        grid_step_m: args.grid_step,
        ..EvalOptions::default()
    };
    let started = Instant::now();
    let evaluator = Evaluator::new(&building, &kernel, options)?;
    let report = evaluator.evaluate(&samples, args.seed)?;
    let elapsed_ms = started.elapsed().as_millis() as u64;
    // `+ 0.0`: the empty sum is -0.0.
    let walk_length_m = building.walk_length(&walk) + 0.0;
    if args.json {
        let out = serde_json::json!({
            "mean_error_m": report.mean_error_m,
            "median_error_m": report.median_error_m,
            "p90_error_m": report.p90_error_m,
            "test_points": report.errors_m.len(),
            "samples": report.samples,
            "access_points": report.access_points,
            "grid_points": report.grid_points,
            "walk_length_m": walk_length_m,
            "seed": args.seed,
            "kernel": kernel,
            "elapsed_ms": elapsed_ms,
        });
        println!("{out}");
    } else {
        println!(
            "localization error: mean {:.2} m, median {:.2} m, p90 {:.2} m",
            report.mean_error_m, report.median_error_m, report.p90_error_m
        );
        println!(
            "{} test points, {} samples along {:.1} m + {} pilot, {} access points, {} grid points, {} ms",
            report.errors_m.len(),
            report.samples,
            walk_length_m,
            building.pilot.len(),
            report.access_points,
            report.grid_points,
            elapsed_ms
        );
    }
    Ok(())
}
