//! The session's replanners side by side (development aid): from points along a planned
//! walk, as if the surveyor had walked that far and then strayed, each replanner plans a
//! walk from there to the end with the budget left, conditioned on the samples collected
//! so far. Prints, per point and replanner, the time taken and what the new walk adds to
//! what is known (`f_{D + collected}(walk) - f_{D + collected}(empty)`, nats).
//!
//! `cargo run --release -p trailprint-core --example replan_compare -- FILE START BUDGET
//! robot|human [FRACTIONS] [REPLANNERS]`, with FRACTIONS of the planned walk walked
//! (default `0.2,0.5,0.8`) and REPLANNERS among `session-greedy` and the planner names
//! (default `session-greedy,auto`; `auto:1` is auto with a 1 s limit). The initial walk is `auto`'s with seed 1 and no time
//! limit beyond its default.
use std::sync::Arc;
use std::time::Instant;

use trailprint::Error;
use trailprint::plan::{Algorithm, Control, PlanRequest, plan};
use trailprint::samples::sample_walk;
use trailprint::session::{GreedyReplanner, PlannerReplanner, ReplanRequest, Replanner};
use trailprint::utility::{Observation, UtilityEngine};

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(
        5,
        "replan_compare FILE START BUDGET robot|human [FRACTIONS] [REPLANNERS]",
    )?;
    let (b, kernel) = cases::load_with_kernel(&a[1])?;
    let model = cases::model_named(&a[4]);
    let budget: f64 = a[3]
        .parse()
        .map_err(|_| Error::InvalidRequest(format!("budget: not a number: {}", a[3])))?;
    let fractions: Vec<f64> = a
        .get(5)
        .map_or("0.2,0.5,0.8", String::as_str)
        .split(',')
        .map(|f| {
            f.parse()
                .map_err(|_| Error::InvalidRequest(format!("fraction: not a number: {f}")))
        })
        .collect::<trailprint::Result<_>>()?;
    let replanners: Vec<Arc<dyn Replanner>> = a
        .get(6)
        .map_or("session-greedy,auto", String::as_str)
        .split(',')
        .map(|name| -> trailprint::Result<Arc<dyn Replanner>> {
            Ok(match name {
                "session-greedy" => Arc::new(GreedyReplanner),
                other => {
                    // `NAME:SECONDS`: the planner with that time limit.
                    let (alg, limit) = other.split_once(':').unwrap_or((other, ""));
                    let mut r = PlannerReplanner::new(Algorithm::from_name(alg)?);
                    if !limit.is_empty() {
                        let s: f64 = limit.parse().map_err(|_| {
                            Error::InvalidRequest(format!("time limit: not a number: {limit}"))
                        })?;
                        r.time_limit = Some(std::time::Duration::from_secs_f64(s));
                    }
                    Arc::new(r)
                }
            })
        })
        .collect::<trailprint::Result<_>>()?;
    let mut req = PlanRequest::new(&a[2], &a[2], budget, kernel);
    req.settings.model = model;
    let planned = plan(b.clone(), &req, &Control::new())?;
    let walk = planned.walk_indices;
    println!(
        "{}: {} vertices, {model:?}, budget {budget} m; planned walk {:.1} m, {:.2} nats",
        b.name,
        b.len(),
        planned.length_m,
        planned.utility_nats
    );
    let end = walk[walk.len() - 1];
    for frac in fractions {
        // The prefix walked: up to the first vertex at `frac` of the planned length.
        let mut k = 1;
        while k < walk.len() && b.walk_length(&walk[..k]) < frac * planned.length_m {
            k += 1;
        }
        let prefix = &walk[..k];
        let walked = b.walk_length(prefix);
        let collected: Vec<Observation> = sample_walk(&b, prefix, &model, &kernel)?
            .iter()
            .map(Observation::from)
            .collect();
        let engine = UtilityEngine::with_prior(b.clone(), kernel, model, &collected)?;
        let known = engine.prior_utility()?;
        let from = prefix[prefix.len() - 1];
        for r in &replanners {
            let t0 = Instant::now();
            let new = r.replan(&ReplanRequest {
                building: &b,
                kernel,
                model,
                prior: &collected,
                start: from,
                end,
                budget_m: budget - walked,
                seed: 1,
                memory_budget: trailprint::plan::PlanSettings::default().memory_budget,
            })?;
            let secs = t0.elapsed().as_secs_f64();
            println!(
                "walked {walked:.1} m ({} samples), from {}: {:<15} {:>7.2} s  adds {:>7.2} nats  {:.1} of {:.1} m",
                collected.len(),
                b.vertices[from].id,
                r.origin().to_string(),
                secs,
                engine.utility(&new)? - known,
                b.walk_length(&new),
                budget - walked
            );
        }
    }
    Ok(())
}
