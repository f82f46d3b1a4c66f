//! Edge-based random orienteering (ERO), the paper's random baseline.
//!
//! The search space is a set of edges (edges as nodes). Each iteration adds a random edge
//! (at the position and orientation of cheapest insertion into the current sequence) or
//! removes a random chosen edge; the walk is the Steiner TSP path through the chosen edges:
//! `v_s`, then each chosen edge traversed end to end, in sequence, joined by shortest
//! paths, then `v_t`. The change is kept if the walk fits the budget and its utility is
//! higher. Seeded; runs for a number of iterations (default 2,000) or until the time limit.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{Algorithm, Outcome, Problem, Run, Solver, Termination};
use crate::Result;

/// The ERO solver.
#[derive(Debug, Clone, Copy)]
pub struct Ero {
    /// Iterations; `0` means until the time limit, or 2,000 without one.
    pub iterations: usize,
    pub seed: u64,
}

impl Ero {
    pub fn new(iterations: usize, seed: u64) -> Self {
        Ero { iterations, seed }
    }
}

/// The walk through a sequence of oriented edges `(from, to)`.
fn walk_of(p: &Problem, seq: &[(usize, usize)]) -> Vec<usize> {
    let mut w = vec![p.start];
    for &(a, b) in seq {
        p.metric.extend_path(&mut w, a);
        w.push(b);
    }
    p.metric.extend_path(&mut w, p.end);
    w
}

/// Inserts edge `(a, b)` where it adds the least length, in its better orientation.
fn insert_edge(p: &Problem, seq: &mut Vec<(usize, usize)>, a: usize, b: usize) {
    let m = &p.metric;
    let mut best = (f64::INFINITY, 0, (a, b));
    for i in 0..=seq.len() {
        let prev = if i == 0 { p.start } else { seq[i - 1].1 };
        let next = if i == seq.len() { p.end } else { seq[i].0 };
        let base = m.dist(prev, next);
        for (x, y) in [(a, b), (b, a)] {
            let c = m.dist(prev, x) + m.dist(y, next) - base;
            if c < best.0 {
                best = (c, i, (x, y));
            }
        }
    }
    seq.insert(best.1, best.2);
}

impl Solver for Ero {
    fn algorithm(&self) -> Algorithm {
        Algorithm::Ero
    }

    fn solve(&self, p: &Problem, run: &Run) -> Result<Outcome> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let iters = match (self.iterations, run.deadline()) {
            (0, Some(_)) => usize::MAX,
            (0, None) => 2_000,
            (k, _) => k,
        };
        let ne = p.building.edges.len();
        let mut seq: Vec<(usize, usize)> = Vec::new();
        let mut walk = walk_of(p, &seq);
        let mut util = p.utility(&walk)?;
        let mut term = Termination::Completed;
        let mut it = 0usize;
        while it < iters {
            it += 1;
            // Every iteration: one evaluation costs up to tens of milliseconds on a large
            // building, and the time limit is honoured to within one of them.
            run.check()?;
            if run.out_of_time() {
                term = Termination::TimeLimit;
                break;
            }
            let mut cand = seq.clone();
            if cand.is_empty() || rng.random_bool(0.6) {
                let e = rng.random_range(0..ne);
                let ed = p.building.edges[e];
                if cand
                    .iter()
                    .any(|&(x, y)| (x, y) == (ed.a, ed.b) || (x, y) == (ed.b, ed.a))
                {
                    continue;
                }
                insert_edge(p, &mut cand, ed.a, ed.b);
            } else {
                let i = rng.random_range(0..cand.len());
                cand.remove(i);
            }
            let w = walk_of(p, &cand);
            if !p.fits(p.length(&w)) {
                continue;
            }
            let u = p.utility(&w)?;
            if u > util {
                seq = cand;
                walk = w;
                util = u;
                p.offer(run, &walk, util);
            }
            if it.is_multiple_of(64) {
                let frac = if iters == usize::MAX {
                    run.time_fraction().unwrap_or(0.0)
                } else {
                    it as f64 / iters as f64
                };
                run.report(Algorithm::Ero, frac, Some(util), format!("iteration {it}"));
            }
        }
        Ok(Outcome::new(walk, util, term))
    }
}
