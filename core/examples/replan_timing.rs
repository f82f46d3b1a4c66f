//! Replans on one building from one replanner against a fresh replanner each time
//! (development aid): the replanner keeps the building's metric closure between replans
//! (`plan::SharedMetric`), so every replan after the first skips it. Prints each
//! replan's time and its walk's utility (no prior), from five starts on the walk of
//! 600 m back to vertex 0, with the session's 1 s limit.
//!
//! `cargo run --release -p trailprint-core --example replan_timing -- FILE ALGORITHM
//! [fresh]` (`SEED` in the environment, default 1; one core: `taskset -c 0 env
//! RAYON_NUM_THREADS=1 ...`). Decision record 0005 (last addendum) has the figures.
use std::time::{Duration, Instant};

use trailprint::plan::Algorithm;
use trailprint::session::{PlannerReplanner, ReplanRequest, Replanner};
use trailprint::utility::UtilityEngine;

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(3, "replan_timing FILE ALGORITHM [fresh]")?;
    let (b, kernel) = cases::load_with_kernel(&a[1])?;
    let algorithm = Algorithm::from_name(&a[2])?;
    let fresh_each = a.get(3).is_some_and(|s| s == "fresh");
    let seed = std::env::var("SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let model = cases::model_named("human");
    let engine = UtilityEngine::new(b.clone(), kernel, model)?;
    let replanner = || {
        let mut r = PlannerReplanner::new(algorithm);
        r.time_limit = Some(Duration::from_secs(1));
        r
    };
    let mut r = replanner();
    for (k, &start) in [0usize, 40, 80, 120, 160].iter().enumerate() {
        if fresh_each {
            r = replanner();
        }
        let req = ReplanRequest {
            building: &b,
            kernel,
            model,
            prior: &[],
            start: start.min(b.len() - 1),
            end: 0,
            budget_m: 600.0,
            seed,
            memory_budget: 512 << 20,
        };
        let t = Instant::now();
        let w = r.replan(&req)?;
        let dt = t.elapsed();
        println!(
            "replan {k}: {dt:?}, {:.1} m, {:.3} nats",
            b.walk_length(&w),
            engine.utility(&w)?
        );
    }
    Ok(())
}
