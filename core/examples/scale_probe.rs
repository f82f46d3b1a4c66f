//! What the large-building search of `auto` did on one plan (development aid): its
//! statistics (batches, accepted moves, surrogate and exact evaluations, the batch of the
//! exact phase, kicks, deferral), or, given saved plans (`trailprint plan --json`), their
//! exact and surrogate values side by side.
//!
//! `cargo run --release -p trailprint-core --example scale_probe -- FILE START END BUDGET
//! robot|human LIMIT_S SEED [PLAN.json,PLAN.json...]`
//! (`LIMIT_S` 0: no time limit)
use std::time::{Duration, Instant};

use trailprint::Error;
use trailprint::plan::scale::{Surrogate, plan_large};
use trailprint::plan::{Control, Problem, Run};

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(
        8,
        "scale_probe FILE START END BUDGET robot|human LIMIT_S SEED [PLANS]",
    )?;
    let number = |i: usize| -> trailprint::Result<f64> {
        a[i].parse()
            .map_err(|_| Error::InvalidRequest(format!("argument {i}: not a number: {}", a[i])))
    };
    let (b, kernel) = cases::load_with_kernel(&a[1])?;
    let model = cases::model_named(&a[5]);
    let (start, end) = (b.require_vertex(&a[2])?, b.require_vertex(&a[3])?);
    let p = Problem::new(b.clone(), kernel, model, start, end, number(4)?)?;
    if let Some(files) = a.get(8) {
        let sur = Surrogate::new(&p)?;
        for f in files.split(',') {
            let text = std::fs::read_to_string(f)
                .map_err(|e| Error::InvalidRequest(format!("{f}: {e}")))?;
            let plan: serde_json::Value = serde_json::from_str(&text)
                .map_err(|e| Error::InvalidRequest(format!("{f}: {e}")))?;
            let ids = plan["walk"]
                .as_array()
                .ok_or_else(|| Error::InvalidRequest(format!("{f}: no `walk` array")))?;
            let walk = ids
                .iter()
                .map(|v| b.require_vertex(v.as_str().unwrap_or("")))
                .collect::<trailprint::Result<Vec<usize>>>()?;
            println!(
                "{f}: exact {:.3} nats, surrogate {:.3}, {:.1} m",
                p.utility(&walk)?,
                sur.value(&walk)?,
                p.length(&walk)
            );
        }
        return Ok(());
    }
    // A limit of 0: no time limit (the search's deterministic batch count).
    let limit = number(6)?;
    let run = Run::new(
        Control::new(),
        (limit > 0.0).then(|| Duration::from_secs_f64(limit)),
    );
    let t0 = Instant::now();
    let (out, stats) = plan_large(&p, &run, number(7)? as u64)?;
    println!(
        "{:.3} nats, {:.1} m, {:?}: {stats:?}",
        out.utility,
        p.length(&out.walk),
        t0.elapsed()
    );
    Ok(())
}
