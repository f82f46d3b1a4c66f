//! `trailprint evaluate`: localization error of a fingerprint map (SPEC section 5), built
//! either from a walk re-sampled from the building's world model (`--walk`), or from the
//! fingerprints a survey session really collected (`--session ID`).

use std::time::Instant;

use clap::Args as ClapArgs;
use trailprint::eval::{
    EvalOptions, Evaluator, LabelledFingerprint, Localizer, evaluate_collected,
};
use trailprint::gp::{Kernel, Point};
use trailprint::samples::sample_walk;
use trailprint::session::SessionLog;
use trailprint::store::BuildingRef;
use trailprint::{Error, Result};

use crate::opts::{KernelOpts, ModelOpts, json_line, split_walk};
use crate::store_cli::{load_building, open_store};

/// Localization error of the fingerprint map built from a walk's samples (or a session's
/// collected fingerprints) plus the pilot data, against the building's test points.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The building (a file or a name in the database); with `--session`, the session's
    /// own building.
    #[arg(long, value_name = "FILE|NAME", required_unless_present = "session")]
    building: Option<String>,
    /// Judge the fingerprints survey session ID collected (from `--db`), with their
    /// measured readings and labelled positions, instead of a re-sampled walk.
    #[arg(long, value_name = "ID", conflicts_with_all = ["walk", "building"])]
    session: Option<i64>,
    /// The walk as comma-separated vertex ids. Without it only the pilot data is used.
    #[arg(long)]
    walk: Option<String>,
    /// How test fingerprints are located: `gp` (the paper's GP likelihood on the
    /// reference grid) or `knn` (weighted k nearest neighbours, k = 3; `knn:K` for another
    /// k).
    #[arg(long, default_value = "gp", value_parser = parse_localizer)]
    localizer: Localizer,
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

fn parse_localizer(s: &str) -> std::result::Result<Localizer, String> {
    Localizer::parse(s).map_err(|e| e.to_string())
}

pub fn run(a: Args, db: Option<&std::path::Path>) -> Result<()> {
    if let Some(id) = a.session {
        return run_session(&a, id, db);
    }
    let spec = a
        .building
        .as_deref()
        .ok_or_else(|| Error::InvalidRequest("--building or --session is required".into()))?;
    let b = load_building(spec, db)?;
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
    let options = a.eval_options();
    let started = Instant::now();
    let report = Evaluator::new(&b, &kernel, options)?.evaluate_samples_with(
        &samples,
        a.seed,
        a.localizer,
    )?;
    let elapsed_ms = started.elapsed().as_millis() as u64;
    // `+ 0.0`: the empty sum is -0.0.
    let length = b.walk_length(&walk) + 0.0;
    if a.json {
        let out = serde_json::json!({
            "localizer": a.localizer.name(),
            "mean_error_m": report.mean_error_m,
            "median_error_m": report.median_error_m,
            "p90_error_m": report.p90_error_m,
            "test_points": report.errors_m.len(),
            "samples": report.samples,
            "length_m": length,
            "access_points": report.access_points,
            "grid_points": report.grid_points,
        });
        print_json(out, &a, &kernel, &source, elapsed_ms)?;
    } else {
        println!(
            "localization error ({}): mean {:.2} m, median {:.2} m, p90 {:.2} m",
            a.localizer.name(),
            report.mean_error_m,
            report.median_error_m,
            report.p90_error_m
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

impl Args {
    /// The evaluation options: `--grid-step`, the rest at their defaults.
    fn eval_options(&self) -> EvalOptions {
        EvalOptions {
            grid_step_m: self.grid_step,
            ..EvalOptions::default()
        }
    }
}

/// Prints a `--json` result with the fields both kinds of evaluation end with: the seed,
/// the kernel and where it came from, and the time taken.
fn print_json(
    mut out: serde_json::Value,
    a: &Args,
    kernel: &Kernel,
    source: &str,
    elapsed_ms: u64,
) -> Result<()> {
    if let Some(obj) = out.as_object_mut() {
        obj.insert("seed".into(), a.seed.into());
        obj.insert("kernel".into(), serde_json::json!(kernel));
        obj.insert("kernel_source".into(), source.into());
        obj.insert("elapsed_ms".into(), elapsed_ms.into());
    }
    println!("{}", json_line(&out)?);
    Ok(())
}

/// `evaluate --session ID`: the session's collected fingerprints, as measured.
fn run_session(a: &Args, id: i64, db: Option<&std::path::Path>) -> Result<()> {
    let store = open_store(db)?;
    let row = store.session(id)?;
    let b = store.get_building(BuildingRef::Id(row.building_id))?;
    // The session's own kernel (its plan's) unless one is given.
    let (kernel, source) = match a.kernel.kernel {
        Some(k) => (k, "option"),
        None => (
            SessionLog::load_plan(&store, row.plan_id)?.record.kernel,
            "plan",
        ),
    };
    let collected: Vec<LabelledFingerprint> = store
        .list_collected(BuildingRef::Id(row.building_id), Some(id))?
        .into_iter()
        .map(|c| {
            let f = c.fingerprint;
            LabelledFingerprint {
                pos: Point::new(f.x, f.y, f.floor),
                extra_noise: kernel.label_noise(f.sigma_m),
                rss: f.rss,
            }
        })
        .collect();
    let options = a.eval_options();
    let started = Instant::now();
    let r = evaluate_collected(&b, &kernel, &collected, &options, a.localizer, a.seed)?;
    let elapsed_ms = started.elapsed().as_millis() as u64;
    let loc = r.localization.as_ref();
    if a.json {
        let out = serde_json::json!({
            "session_id": id,
            "building": b.name,
            "localizer": a.localizer.name(),
            "mean_error_m": loc.map(|l| l.mean_error_m),
            "median_error_m": loc.map(|l| l.median_error_m),
            "p90_error_m": loc.map(|l| l.p90_error_m),
            "test_points": loc.map_or(0, |l| l.errors_m.len()),
            "localization_note": r.localization_note,
            "collected": r.collected,
            "pilot": r.pilot,
            "access_points": r.access_points,
            "std_mean_db": r.std_mean_db,
            "std_median_db": r.std_median_db,
            "std_p90_db": r.std_p90_db,
            "std_max_db": r.std_max_db,
            "grid_points": r.grid_points,
        });
        print_json(out, a, &kernel, source, elapsed_ms)?;
    } else {
        match loc {
            Some(l) => println!(
                "session {id} on {:?}: localization error ({}): mean {:.2} m, median {:.2} m, \
                 p90 {:.2} m on {} test points",
                b.name,
                a.localizer.name(),
                l.mean_error_m,
                l.median_error_m,
                l.p90_error_m,
                l.errors_m.len()
            ),
            None => println!(
                "session {id} on {:?}: no localization error ({})",
                b.name,
                r.localization_note.as_deref().unwrap_or("no test points")
            ),
        }
        println!(
            "posterior std on {} grid points: mean {:.2} dB, median {:.2} dB, p90 {:.2} dB, \
             max {:.2} dB",
            r.grid_points, r.std_mean_db, r.std_median_db, r.std_p90_db, r.std_max_db
        );
        println!(
            "{} collected fingerprints + {} pilot; {} access points; kernel sf2={:.4} \
             ell={:.4} sn2={:.4} ({source}); {elapsed_ms} ms",
            r.collected, r.pilot, r.access_points, kernel.sf2, kernel.ell, kernel.sn2
        );
    }
    Ok(())
}
