//! How long `Problem::new` takes on a building (the engine and the metric closure, built
//! side by side when rayon has more than one thread), the least of five runs:
//! `cargo run --release -p trailprint-core --example problem_timing -- FILE`
use std::time::Instant;
use trailprint::plan::Problem;
#[path = "common/cases.rs"]
mod cases;
fn main() -> trailprint::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let (b, kernel) = cases::load_with_kernel(&a[1])?;
    let model = cases::model_named("human");
    let mut best = f64::MAX;
    for _ in 0..5 {
        let t = Instant::now();
        let p = Problem::new(b.clone(), kernel, model, 0, 0, 100.0)?;
        best = best.min(t.elapsed().as_secs_f64());
        drop(p);
    }
    println!("{:.3}", best);
    Ok(())
}
