//! What an exact evaluation costs whole and from a base walk's factorisation
//! ([`UtilityEngine::utility_near`]), on walks that leave a saved plan's walk at a point
//! spread evenly along it and walk back the way they came (development aid):
//! `cargo run --release -p trailprint-core --example eval_repeat -- FILE robot|human
//! PLAN.json [POINTS]`.
use std::time::Instant;

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(4, "eval_repeat FILE robot|human PLAN.json [POINTS]")?;
    let (p, walk) = cases::plan_problem(&a[1], &a[3], &a[2], 1e9)?;
    let points: usize = a.get(4).and_then(|x| x.parse().ok()).unwrap_or(40);
    let cands: Vec<Vec<usize>> = (1..=points)
        .map(|k| {
            let i = (k * (walk.len() - 1) / (points + 1)).max(1);
            let mut w = walk[..=i].to_vec();
            w.extend(walk[..i].iter().rev());
            w
        })
        .collect();
    let base = p
        .engine
        .near_base(&walk, trailprint::utility::engine::NEAR_BASE_MAX)?;
    let (mut whole, mut near, mut worst) = (0.0, 0.0, 0.0f64);
    for w in &cands {
        let t = Instant::now();
        let x = p.utility(w)?;
        whole += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let y = p.engine.utility_near(&base, w)?;
        near += t.elapsed().as_secs_f64();
        worst = worst.max((x - y).abs() / x.abs().max(1.0));
    }
    let n = cands.len() as f64;
    println!(
        "{} candidates: whole {:.3} ms, near {:.3} ms ({:.2}x); largest relative difference {worst:.1e}",
        cands.len(),
        whole / n * 1e3,
        near / n * 1e3,
        whole / near
    );
    Ok(())
}
