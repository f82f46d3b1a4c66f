//! The paper's greedy planner (Wei, Frincu, Zheng, Algorithm 1).
//!
//! Start from the shortest path `v_s -> v_t`. In each round, for every vertex `v` not on
//! the walk, solve the Steiner TSP path through the walk's vertices plus `v`
//! ([`steiner`](super::steiner): exact Held-Karp up to 12 required vertices, cheapest
//! insertion with 2-opt / or-opt beyond) and score it by the ratio
//! `(f(P_v) - f(P)) / (C(P_v) - C(P))`. Take the best; stop when it no longer fits the
//! budget ([`Greedy::paper`]) or, in the variant [`Greedy::feasible`] used by `auto`,
//! take the best among the candidates that fit and stop when none does.
//!
//! # Complexity
//! `O(R n)` Steiner TSP solutions and utility evaluations for `R` rounds and `n`
//! vertices; the candidates of a round are evaluated in parallel (rayon).

use rayon::prelude::*;

use super::steiner::steiner_order_with;
use super::{Algorithm, Outcome, Problem, Run, Solver, Termination};
use crate::{Error, Result};

/// The greedy solver.
#[derive(Debug, Clone, Copy)]
pub struct Greedy {
    /// Choose among feasible candidates only (instead of stopping when the best ratio is
    /// infeasible).
    pub feasible_only: bool,
}

impl Greedy {
    /// Exactly the paper's rule: stop when the best-ratio candidate does not fit.
    pub fn paper() -> Self {
        Greedy {
            feasible_only: false,
        }
    }

    /// Skip candidates that do not fit; stop when none fits.
    pub fn feasible() -> Self {
        Greedy {
            feasible_only: true,
        }
    }
}

struct Candidate {
    walk: Vec<usize>,
    length: f64,
    utility: f64,
    ratio: f64,
}

/// Distinct vertices of a walk in first-visit order.
fn first_visits(walk: &[usize], n: usize) -> Vec<usize> {
    let mut seen = vec![false; n];
    let mut out = Vec::new();
    for &v in walk {
        if !seen[v] {
            seen[v] = true;
            out.push(v);
        }
    }
    out
}

impl Solver for Greedy {
    fn algorithm(&self) -> Algorithm {
        Algorithm::Greedy
    }

    fn solve(&self, p: &Problem, run: &Run) -> Result<Outcome> {
        let m = &p.metric;
        let n = p.building.len();
        let mut walk = p.shortest_walk();
        let mut length = p.length(&walk);
        let mut utility = p.utility(&walk)?;
        let mut order: Vec<usize> = first_visits(&walk, n)
            .into_iter()
            .filter(|&v| v != p.start && v != p.end)
            .collect();
        let mut round = 0usize;
        loop {
            run.check()?;
            if run.out_of_time() {
                return Ok(Outcome::new(walk, utility, Termination::TimeLimit));
            }
            let mut on = vec![false; n];
            for &v in &walk {
                on[v] = true;
            }
            let cands: Vec<usize> = (0..n).filter(|&v| !on[v]).collect();
            if cands.is_empty() {
                break;
            }
            let results: Vec<Result<Option<Candidate>>> = cands
                .par_iter()
                .map(|&v| {
                    if run.should_stop() {
                        return Ok(None);
                    }
                    let (o, _) = steiner_order_with(m, p.start, p.end, &order, v);
                    let w = m.expand(p.start, &o, p.end);
                    let len = p.length(&w);
                    if self.feasible_only && !p.fits(len) {
                        return Ok(None);
                    }
                    let u = p.utility(&w)?;
                    let dl = len - length;
                    let du = u - utility;
                    let ratio = if dl > 1e-9 {
                        du / dl
                    } else if du > 0.0 {
                        f64::MAX
                    } else {
                        f64::MIN
                    };
                    Ok(Some(Candidate {
                        walk: w,
                        length: len,
                        utility: u,
                        ratio,
                    }))
                })
                .collect();
            run.check()?;
            let mut best: Option<Candidate> = None;
            for r in results {
                if let Some(c) = r? {
                    // Ties: keep the earlier (lower-index) candidate: deterministic.
                    if best.as_ref().is_none_or(|b| c.ratio > b.ratio) {
                        best = Some(c);
                    }
                }
            }
            let Some(best) = best else { break };
            if !p.fits(best.length) || best.utility <= utility {
                // Paper rule: the best no longer fits; or nothing gains any more.
                break;
            }
            walk = best.walk;
            length = best.length;
            utility = best.utility;
            order = first_visits(&walk, n)
                .into_iter()
                .filter(|&v| v != p.start && v != p.end)
                .collect();
            round += 1;
            p.offer(run, &walk, utility);
            run.report(
                Algorithm::Greedy,
                (length / p.budget).min(1.0),
                Some(utility),
                format!("round {round}: {length:.1} m"),
            );
        }
        if !p.fits(length) {
            return Err(Error::Numerical("greedy walk over budget".into()));
        }
        Ok(Outcome::new(walk, utility, Termination::Completed))
    }
}
