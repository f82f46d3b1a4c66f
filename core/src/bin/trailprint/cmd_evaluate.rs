//! `trailprint evaluate`: localization error of a walk's fingerprint map (SPEC section 5).

use std::time::Instant;

use clap::Args as ClapArgs;
use trailprint::Result;
use trailprint::eval::{EvalOptions, Evaluator};
use trailprint::samples::sample_walk;

use crate::opts::{BuildingOpts, KernelOpts, ModelOpts, json_line, split_walk};

/// Localization error of the fingerprint map built from a walk's samples plus the pilot
/// data, against the building's test points.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    building: BuildingOpts,
    /// The walk as comma-separated vertex ids. Without it only the pilot data is used.
    #[arg(long)]
    walk: Option<String>,
    #[command(flatten)]
    model: ModelOpts,
    #[command(flatten)]
    kernel: KernelOpts,
    /// Reference grid spacing, metres.
    #[arg(long, default_value_t = 0.5)]
    grid_step: f64,
    /// Seed of the drawn fingerprints.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args, db: Option<&std::path::Path>) -> Result<()> {
    let b = a.building.load(db)?;
    let model = a.model.model()?;
    let (kernel, source) = a.kernel.resolve(&b)?;
    let walk = match &a.walk {
        Some(w) => b.resolve_walk(&split_walk(w))?,
        None => Vec::new(),
    };
    let samples = if walk.is_empty() {
        Vec::new()
    } else {
        sample_walk(&b, &walk, &model, &kernel)?
    };
    let options = EvalOptions {
        grid_step_m: a.grid_step,
        ..EvalOptions::default()
    };
    let started = Instant::now();
    let report = Evaluator::new(&b, &kernel, options)?.evaluate_samples(&samples, a.seed)?;
    let elapsed_ms = started.elapsed().as_millis() as u64;
    // `+ 0.0`: the empty sum is -0.0.
    let length = b.walk_length(&walk) + 0.0;
    if a.json {
        let out = serde_json::json!({
            "mean_error_m": report.mean_error_m,
            "median_error_m": report.median_error_m,
            "p90_error_m": report.p90_error_m,
            "test_points": report.errors_m.len(),
            "samples": report.samples,
            "length_m": length,
            "access_points": report.access_points,
            "grid_points": report.grid_points,
            "seed": a.seed,
            "kernel": kernel,
            "kernel_source": source,
            "elapsed_ms": elapsed_ms,
        });
        println!("{}", json_line(&out)?);
    } else {
        println!(
            "localization error: mean {:.2} m, median {:.2} m, p90 {:.2} m",
            report.mean_error_m, report.median_error_m, report.p90_error_m
        );
        println!(
            "{} test points; {} samples along {length:.1} m + {} pilot; {} access points; \
             {} grid points; kernel sf2={:.4} ell={:.4} sn2={:.4} ({source}); {elapsed_ms} ms",
            report.errors_m.len(),
            report.samples,
            b.pilot.len(),
            report.access_points,
            report.grid_points,
            kernel.sf2,
            kernel.ell,
            kernel.sn2,
        );
    }
    Ok(())
}
