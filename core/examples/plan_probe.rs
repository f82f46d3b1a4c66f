//! Timing probe for the planners (development aid).
use std::sync::Arc;
use std::time::Instant;

use rand::SeedableRng;
use trailprint::Building;
use trailprint::gp::fit_kernel;
use trailprint::plan::genetic::{Fitness, Genetic, random_walk};
use trailprint::plan::{Control, Params, Problem, Run};

fn main() -> trailprint::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let b = Arc::new(Building::load(std::path::Path::new(&args[1]))?);
    let k = fit_kernel(&b.pilot)?.kernel;
    let s = b.require_vertex(&args[2])?;
    let budget: f64 = args[3].parse().unwrap_or(140.0);
    let p = Problem::new(
        b.clone(),
        k,
        trailprint::samples::SurveyorModel::robot(),
        s,
        s,
        budget,
    )?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let walks: Vec<Vec<usize>> = (0..200).map(|_| random_walk(&p, &mut rng)).collect();
    let t = Instant::now();
    for w in &walks {
        p.utility(w)?;
    }
    println!(
        "200 sequential evals: {:?} (mean len {:.1})",
        t.elapsed(),
        walks.iter().map(|w| p.length(w)).sum::<f64>() / 200.0
    );
    let t = Instant::now();
    p.utilities(&walks)?;
    println!("200 parallel evals: {:?}", t.elapsed());
    let run = Run::new(Control::new(), None);
    let t = Instant::now();
    let g = Genetic::new(Params::default(), 1);
    let (pop, _) = g.evolve(&p, &run)?;
    println!("genetic: {:?} best {:.4}", t.elapsed(), pop[0].utility);
    let mut f = Fitness::new(&p);
    let _ = f.eval(&walks, &run)?;
    Ok(())
}
