//! Time of the metric closure (all-pairs shortest paths, `plan::metric::Metric::new`) of a
//! building, the least of several runs, on the threads rayon is given:
//! `cargo run --release -p trailprint-core --example metric_timing -- FILE [RUNS]`
//! (one core: `taskset -c 0 env RAYON_NUM_THREADS=1 ...`).
use std::time::{Duration, Instant};

use trailprint::plan::metric::Metric;

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(2, "metric_timing FILE [RUNS]")?;
    let (b, _) = cases::load_with_kernel(&a[1])?;
    let runs: usize = a.get(2).and_then(|r| r.parse().ok()).unwrap_or(5);
    let mut best = Duration::MAX;
    let mut check = 0.0;
    for _ in 0..runs {
        let t0 = Instant::now();
        let m = Metric::new(&b);
        best = best.min(t0.elapsed());
        check = m.dist(0, b.len() - 1);
    }
    println!(
        "{} vertices: {:.1} ms (least of {runs}); dist(first, last) {check:.3} m",
        b.len(),
        best.as_secs_f64() * 1e3
    );
    Ok(())
}
