//! Timing probe for the planners (development aid).
use std::sync::Arc;
use std::time::Instant;

use trailprint::Building;
use trailprint::gp::fit_kernel;
use trailprint::plan::greedy::Greedy;
use trailprint::plan::local_search::LocalSearch;
use trailprint::plan::{Control, Problem, Run, Solver};

fn main() -> trailprint::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let b = Arc::new(Building::load(std::path::Path::new(&args[1]))?);
    let k = fit_kernel(&b.pilot)?.kernel;
    let s = b.require_vertex(&args[2])?;
    let t = b.require_vertex(&args[3])?;
    for budget in args[4]
        .split(',')
        .map(|x| x.parse::<f64>().unwrap_or(100.0))
    {
        let p = Problem::new(
            b.clone(),
            k,
            trailprint::surveyor::Surveyor::robot(),
            s,
            t,
            budget,
        )?;
        let run = Run::new(Control::new(), None);
        let t0 = Instant::now();
        let g = Greedy::feasible().solve(&p, &run)?;
        println!(
            "B={budget} greedy-feasible {:.4} ({:.1} m) in {:?}",
            g.utility,
            p.length(&g.walk),
            t0.elapsed()
        );
        for (patience, batch) in [(12, 32), (40, 32)] {
            let t0 = Instant::now();
            let mut ls = LocalSearch::new(1);
            ls.patience = patience;
            ls.batch = batch;
            let (w, u) = ls.improve(&p, &run, g.walk.clone(), g.utility)?;
            println!(
                "  LS patience {patience} batch {batch}: {u:.4} ({:.1} m) in {:?}",
                p.length(&w),
                t0.elapsed()
            );
        }
    }
    Ok(())
}
