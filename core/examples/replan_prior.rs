//! What a session's replan costs as the samples it conditions on grow (development aid):
//! on a building file, a robot's samples every 0.5 m along a seeded random walk from
//! vertex 0 are the prior; for each prior size it times one exact evaluation of a fixed
//! 500 m walk given that prior (`UtilityEngine::with_prior`, then `utility`), and a
//! replan by `auto` with the session's limit (`session::default_replanner`) from the
//! prior's last vertex back to vertex 0 with 500 m and with 1,800 m, and one more exact
//! evaluation of the replanned walk (what a session paid after each replan until the
//! replanner's own utility came along, `Replanner::replan_scored`).
//!
//! `cargo run --release -p trailprint-core --example replan_prior -- FILE [SIZES...]`
//! (sizes default to 250 1000 2000 4000).
use std::time::Instant;

use trailprint::session::{ReplanRequest, default_replanner};
use trailprint::surveyor::Surveyor;
use trailprint::utility::UtilityEngine;

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(2, "replan_prior FILE [SIZES...]")?;
    let (b, kernel) = cases::load_with_kernel(&a[1])?;
    let mut sizes: Vec<usize> = a[2..].iter().filter_map(|s| s.parse().ok()).collect();
    if sizes.is_empty() {
        sizes = vec![250, 1000, 2000, 4000];
    }
    let max = sizes.iter().copied().max().unwrap_or(0);
    let (pts, ends) = cases::random_walk_samples(&b, 7, max);
    // A fixed walk of about 500 m: the random walk's own first 1,000 samples' vertices.
    let model = Surveyor::robot();
    let replanner = default_replanner(&b);
    println!(
        "{} ({} vertices), robot, replanner {:?}",
        b.name,
        b.len(),
        replanner.origin()
    );
    println!(
        "| prior samples | exact evaluation of a 500 m walk | replan budget | replan | evaluating its walk again | its utility |"
    );
    println!("|---:|---:|---:|---:|---:|---:|");
    let mut walk = vec![0usize];
    for &v in &ends {
        if walk.last() != Some(&v) && b.walk_length(&walk) < 500.0 {
            walk.push(v);
        }
    }
    for &n in &sizes {
        let prior = cases::observations(&pts[..n]);
        let t = Instant::now();
        let engine = UtilityEngine::with_prior(b.clone(), kernel, model, &prior)?;
        std::hint::black_box(engine.utility(&walk)?);
        let eval_s = t.elapsed().as_secs_f64();
        for budget in [500.0, 1800.0] {
            let t = Instant::now();
            let (w, scored) = replanner.replan_scored(&ReplanRequest {
                building: &b,
                kernel,
                model,
                prior: &prior,
                start: ends[n - 1],
                end: 0,
                budget_m: budget,
                seed: 1,
                memory_budget: 512 << 20,
            })?;
            let replan_s = t.elapsed().as_secs_f64();
            // What the session paid after every replan before the replanner's own
            // exact utility came along.
            let t = Instant::now();
            let again = UtilityEngine::with_prior(b.clone(), kernel, model, &prior)?.utility(&w)?;
            let again_s = t.elapsed().as_secs_f64();
            assert!(scored.is_none_or(|u| (u - again).abs() < 1e-9 * again));
            println!(
                "| {n} | {eval_s:.2} s | {budget} m | {replan_s:.2} s | {again_s:.2} s | {again:.2} nats |"
            );
        }
    }
    Ok(())
}
