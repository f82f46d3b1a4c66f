//! `auto`, the default planner: a portfolio that spends a fixed amount of work in stages,
//! each starting from the best walk so far, all capped by the time limit (2 s by
//! default).
//!
//! 1. **Greedy** (feasible-candidates variant of the paper's Algorithm 1): a good walk in
//!    a fraction of the time.
//! 2. **Genetic** (the paper's operators and defaults) with the greedy walk in the initial
//!    population, so it can only improve on it.
//! 3. **Local search** ([`LocalSearch`]): detour insert / segment replace / shortcut /
//!    2-opt moves, from the best walk, then from a few other distinct walks of the final
//!    population (restarts), keeping the best.
//! 4. **Exact** branch and bound seeded with that walk, when a quick count shows the
//!    search tree is small (at most [`EXACT_NODE_CAP`] nodes under the feasibility rule):
//!    if it finishes, the walk is proved optimal (`optimal: true`).
//!
//! The work of each stage is fixed (generations, rounds, restarts), so the same seed gives
//! the same walk unless the time limit cuts a stage short (`termination: time_limit`).

use super::exact::Exact;
use super::genetic::Genetic;
use super::greedy::Greedy;
use super::local_search::LocalSearch;
use super::{Algorithm, Outcome, Params, Problem, Run, Solver, Termination, better};
use crate::Result;

/// Largest feasibility-pruned tree for which `auto` runs the exact search.
pub const EXACT_NODE_CAP: u64 = 200_000;

/// The `auto` solver.
#[derive(Debug, Clone)]
pub struct Auto {
    pub params: Params,
    pub seed: u64,
    /// Local-search restarts from other members of the genetic population.
    pub restarts: usize,
}

impl Auto {
    pub fn new(params: Params, seed: u64) -> Self {
        Auto {
            params,
            seed,
            restarts: 3,
        }
    }
}

/// Number of nodes of the walk tree under the feasibility rule alone, counting up to
/// `cap` (returns `cap + 1` if there are more).
pub fn count_nodes(p: &Problem, cap: u64) -> u64 {
    fn rec(p: &Problem, v: usize, len: f64, count: &mut u64, cap: u64) {
        *count += 1;
        if *count > cap {
            return;
        }
        for &(w, e) in p.building.neighbours(v) {
            let l = len + p.building.edges[e].length;
            if p.fits(l + p.metric.dist(w, p.end)) {
                rec(p, w, l, count, cap);
                if *count > cap {
                    return;
                }
            }
        }
    }
    let mut count = 0;
    rec(p, p.start, 0.0, &mut count, cap);
    count
}

impl Solver for Auto {
    fn algorithm(&self) -> Algorithm {
        Algorithm::Auto
    }

    fn solve(&self, p: &Problem, run: &Run) -> Result<Outcome> {
        let g = Greedy::feasible().solve(p, run)?;
        let (mut walk, mut util) = (g.walk, g.utility);
        run.report(Algorithm::Greedy, 0.1, Some(util), "greedy done".into());
        let ga = Genetic::new(self.params, self.seed).with_seeds(vec![walk.clone()]);
        let (pop, _) = ga.evolve(p, run)?;
        if let Some(b) = pop.first()
            && better((&b.walk, b.utility), (&walk, util))
        {
            walk = b.walk.clone();
            util = b.utility;
        }
        run.report(Algorithm::Genetic, 0.4, Some(util), "genetic done".into());
        // Local search from the best, then from other distinct members of the population.
        let mut starts: Vec<(Vec<usize>, f64)> = vec![(walk.clone(), util)];
        for ind in pop.iter() {
            if starts.len() > self.restarts {
                break;
            }
            if !starts.iter().any(|(w, _)| *w == ind.walk) {
                starts.push((ind.walk.clone(), ind.utility));
            }
        }
        for (k, (w, u)) in starts.into_iter().enumerate() {
            if run.should_stop() {
                break;
            }
            let ls = LocalSearch::new(self.seed.wrapping_add(k as u64 + 1));
            let (w2, u2) = ls.improve(p, run, w, u)?;
            if better((&w2, u2), (&walk, util)) {
                walk = w2;
                util = u2;
            }
            run.report(
                Algorithm::Auto,
                0.4 + 0.1 * (k + 1) as f64,
                Some(util),
                format!("local search {}", k + 1),
            );
        }
        run.check()?;
        let mut out = Outcome::new(walk.clone(), util, Termination::Completed);
        if !run.should_stop() && count_nodes(p, EXACT_NODE_CAP) <= EXACT_NODE_CAP {
            let ex = Exact::new().with_incumbent(walk.clone()).solve(p, run)?;
            if ex.optimal == Some(true) {
                out.optimal = Some(true);
                out.nodes = ex.nodes;
            }
            if better((&ex.walk, ex.utility), (&walk, util)) {
                out.walk = ex.walk;
                out.utility = ex.utility;
            }
        }
        if run.out_of_time() && out.optimal != Some(true) {
            out.termination = Termination::TimeLimit;
        }
        Ok(out)
    }
}
