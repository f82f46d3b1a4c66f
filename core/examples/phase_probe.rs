//! How much a saved plan gains from reversing its closed sub-walks (development aid).
//!
//! A closed sub-walk `w[a..=b]` with `w[a] == w[b]` walked the other way has the same
//! edges and length, so the walk keeps its coverage and budget; only where its samples
//! fall inside that stretch changes (a person's every 4.8 m). This hill-climbs on those
//! reversals by exact `f_D` and prints what it reached and how many evaluations it took.
//!
//! `cargo run --release -p trailprint-core --example phase_probe -- FILE BUDGET
//! robot|human PLAN.json`
use std::time::Instant;

use trailprint::plan::coverage::reversals;

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(5, "phase_probe FILE BUDGET robot|human PLAN.json")?;
    let budget = cases::number(&a, 2, "BUDGET")?;
    let (p, mut walk) = cases::plan_problem(&a[1], &a[4], &a[3], budget)?;
    let t0 = Instant::now();
    let mut u = p.utility(&walk)?;
    let rev0 = reversals(&p, &walk);
    println!("start: {u:.3} nats, {} reversals", rev0);
    let mut evals = 0usize;
    loop {
        let n = walk.len();
        let mut best: Option<(Vec<usize>, f64)> = None;
        for i in 0..n {
            for j in i + 2..n {
                if walk[i] != walk[j] {
                    continue;
                }
                let mut w = walk.clone();
                w[i..=j].reverse();
                if w == walk || reversals(&p, &w) > rev0 {
                    continue;
                }
                let x = p.utility(&w)?;
                evals += 1;
                if x > best.as_ref().map_or(u, |b| b.1) + 1e-9 {
                    best = Some((w, x));
                }
            }
        }
        match best {
            Some((w, x)) => {
                println!(
                    "  {x:.3} nats after {evals} evaluations, {:?}",
                    t0.elapsed()
                );
                walk = w;
                u = x;
            }
            None => break,
        }
    }
    println!("end: {u:.3} nats, {evals} evaluations, {:?}", t0.elapsed());
    Ok(())
}
