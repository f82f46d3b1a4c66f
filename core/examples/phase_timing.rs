//! Where the set-up of a large-building plan goes (development aid): loading the file,
//! the utility engine (the prior's factorisation over every vertex), the metric closure
//! (a shortest-path tree per vertex), the near-edge table, the surrogate, one spread
//! construction (novelty radius an eighth of the length scale), its surrogate value and
//! its exact evaluation, each timed on its own. `auto` pays the first three before it
//! can plan anything: on the generated 3,161-vertex floor (huge-3k, person 3,116 m), one
//! core here, 29-55 ms, 365-468 ms and 356-503 ms of its 2 s (five runs; the VM's speed
//! varies).
//!
//! `cargo run --release -p trailprint-core --example phase_timing -- FILE START END BUDGET robot|human`
//! (run it under `taskset -c 0` with `RAYON_NUM_THREADS=1` for one core's figures)
use std::time::Instant;

use trailprint::plan::coverage::{Leg, leg};
use trailprint::plan::scale::Surrogate;
use trailprint::plan::{Control, Metric, Problem, Run};
use trailprint::utility::UtilityEngine;

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(6, "phase_timing FILE START END BUDGET robot|human")?;
    let budget = cases::number(&a, 4, "BUDGET")?;
    let t = Instant::now();
    let (b, kernel) = cases::load_with_kernel(&a[1])?;
    println!("load           {:?}", t.elapsed());
    let model = cases::model_named(&a[5]);
    let (start, end) = (b.require_vertex(&a[2])?, b.require_vertex(&a[3])?);
    // The engine and the metric, each alone, in the order `Problem::new` builds them;
    // then the problem itself (both again, not timed).
    let t = Instant::now();
    drop(UtilityEngine::new(b.clone(), kernel, model)?);
    println!("engine         {:?}", t.elapsed());
    let t = Instant::now();
    drop(Metric::new(&b));
    println!("metric         {:?}", t.elapsed());
    let p = Problem::new(b.clone(), kernel, model, start, end, budget)?;
    let t = Instant::now();
    let tabled = p.near_edges().is_some();
    println!("near edges     {:?} (table kept: {tabled})", t.elapsed());
    let t = Instant::now();
    let s = Surrogate::new(&p)?;
    println!("surrogate      {:?}", t.elapsed());
    let run = Run::new(Control::new(), None);
    let spec = Leg {
        from: p.start,
        prev: None,
        to: p.end,
        budget: p.budget,
        radius: 0.125 * kernel.ell,
        any_fit: true,
        avoid_reversals: a[5] == "human",
        open_ties: false,
    };
    let t = Instant::now();
    let w = leg(&p, &spec, &[], None, &run);
    println!(
        "construction   {:?} ({} vertices, {:.1} m)",
        t.elapsed(),
        w.len(),
        p.length(&w)
    );
    let t = Instant::now();
    let v = s.value(&w)?;
    println!("its surrogate  {:?} ({v:.3} nats)", t.elapsed());
    let t = Instant::now();
    let u = p.utility(&w)?;
    println!("its exact f_D  {:?} ({u:.3} nats)", t.elapsed());
    Ok(())
}
