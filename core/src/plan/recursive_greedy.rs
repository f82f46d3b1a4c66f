//! Recursive greedy for submodular orienteering (Chekuri and Pal), the paper's baseline.
//!
//! `RG(s, t, B, X, i)`: start with the shortest path `s -> t`; if `i > 0`, for every
//! middle vertex `v` and every first-half budget `B1` (discretised in steps of
//! [`RecursiveGreedy::step`] metres), take `P1 = RG(s, v, B1, X, i - 1)`, then
//! `P2 = RG(v, t, B - C(P1), X + P1, i - 1)` conditioned on the first half's samples, and
//! keep the concatenation if it has the highest utility so far. `RG(.., 0)` is the
//! shortest path. (Chekuri and Pal give the second half `B - B1`; the unused part of `B1`
//! is passed on here, which never hurts.)
//!
//! Conditioning on `X` is exact: the context is the engine state of the walk so far
//! ([`WalkState`]), so the second half is scored by the true utility of the concatenated
//! walk, sample positions included.
//!
//! Reference: C. Chekuri, M. Pal, "A recursive greedy algorithm for walks in directed
//! graphs", FOCS 2005.
//!
//! # Complexity
//! `O((n K)^I)` utility evaluations for `n` vertices, `K` budget steps and depth `I`
//! (at depth 1 the budget split does not matter, so depth 2 costs `O(n^2 K)`). The top
//! level runs in parallel; the time limit returns the best walk found so far.

use rayon::prelude::*;

use super::{Algorithm, Outcome, Problem, Run, Solver, Termination};
use crate::Result;
use crate::utility::WalkState;

/// The recursive greedy solver.
#[derive(Debug, Clone, Copy)]
pub struct RecursiveGreedy {
    /// Recursion depth `I`.
    pub depth: usize,
    /// Budget step in metres; `0` for automatic (`B / 12`, at least one sample spacing).
    pub step: f64,
}

impl RecursiveGreedy {
    pub fn new(depth: usize, step: f64) -> Self {
        RecursiveGreedy { depth, step }
    }
}

/// A walk and its utility, if one exists.
type Found = Option<(Vec<usize>, f64)>;

struct Ctx<'a> {
    p: &'a Problem,
    run: &'a Run,
    step: f64,
}

/// Utility of `ctx` followed by `walk[1..]`; `None` if `run` stops first. On a building of
/// thousands of vertices one step costs a rank update of the vertices' posterior and the
/// score a factorisation of it (a quarter of a second at 3,161 vertices), so the stop is
/// checked between them.
fn eval(ctx: &WalkState<'_>, walk: &[usize], run: &Run) -> Result<Option<f64>> {
    let mut st = ctx.clone();
    for &v in &walk[1..] {
        if run.should_stop() {
            return Ok(None);
        }
        st.push(v)?;
    }
    if run.should_stop() {
        return Ok(None);
    }
    st.utility().map(Some)
}

/// First-half budgets from `lo` to `hi` in steps.
fn budgets(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut b = lo;
    while b < hi - super::BUDGET_EPS {
        out.push(b);
        b += step;
    }
    out.push(hi);
    out
}

impl Ctx<'_> {
    fn rg(
        &self,
        ctx: &WalkState<'_>,
        s: usize,
        t: usize,
        budget: f64,
        depth: usize,
    ) -> Result<Found> {
        let m = &self.p.metric;
        if m.dist(s, t) > budget + super::BUDGET_EPS {
            return Ok(None);
        }
        let sp = m.path(s, t);
        let Some(u) = eval(ctx, &sp, self.run)? else {
            return Ok(None);
        };
        let mut best = (sp, u);
        if depth == 0 {
            return Ok(Some(best));
        }
        for v in 0..self.p.building.len() {
            if self.run.should_stop() {
                break;
            }
            if let Some((w, u)) = self.split(ctx, s, t, budget, depth, v, None)?
                && u > best.1
            {
                best = (w, u);
            }
        }
        Ok(Some(best))
    }

    /// Best `P1 . P2` through `v` (over the budget splits, or the one given).
    #[allow(clippy::too_many_arguments)]
    fn split(
        &self,
        ctx: &WalkState<'_>,
        s: usize,
        t: usize,
        budget: f64,
        depth: usize,
        v: usize,
        b1: Option<f64>,
    ) -> Result<Found> {
        let m = &self.p.metric;
        let (lo, hi) = (m.dist(s, v), budget - m.dist(v, t));
        if lo > hi + super::BUDGET_EPS {
            return Ok(None);
        }
        let list = match b1 {
            Some(b) => vec![b],
            // With depth - 1 = 0 the first half is the shortest path whatever its budget.
            None if depth == 1 => vec![hi],
            None => budgets(lo, hi, self.step),
        };
        let mut best: Option<(Vec<usize>, f64)> = None;
        for b1 in list {
            if self.run.should_stop() {
                break;
            }
            let Some((p1, _)) = self.rg(ctx, s, v, b1, depth - 1)? else {
                continue;
            };
            let mut ctx2 = ctx.clone();
            for &x in &p1[1..] {
                if self.run.should_stop() {
                    return Ok(best);
                }
                ctx2.push(x)?;
            }
            let rest = budget - self.p.length(&p1);
            let Some((p2, u)) = self.rg(&ctx2, v, t, rest, depth - 1)? else {
                continue;
            };
            if best.as_ref().is_none_or(|b| u > b.1) {
                let mut w = p1;
                w.extend_from_slice(&p2[1..]);
                best = Some((w, u));
            }
        }
        Ok(best)
    }
}

impl Solver for RecursiveGreedy {
    fn algorithm(&self) -> Algorithm {
        Algorithm::RecursiveGreedy
    }

    fn solve(&self, p: &Problem, run: &Run) -> Result<Outcome> {
        let step = if self.step > 0.0 {
            self.step
        } else {
            let d = p.engine.model().spacing();
            ((p.budget / 12.0) / d).ceil().max(1.0) * d
        };
        let c = Ctx { p, run, step };
        let root = p.engine.start(p.start)?;
        let sp = p.shortest_walk();
        let u0 = p.utility(&sp)?;
        let mut best = (sp, u0);
        if self.depth > 0 {
            let m = &p.metric;
            // Top level: all (v, B1) pairs in parallel.
            let mut jobs = Vec::new();
            for v in 0..p.building.len() {
                let (lo, hi) = (m.dist(p.start, v), p.budget - m.dist(v, p.end));
                if lo > hi + super::BUDGET_EPS {
                    continue;
                }
                if self.depth == 1 {
                    jobs.push((v, hi));
                } else {
                    for b in budgets(lo, hi, step) {
                        jobs.push((v, b));
                    }
                }
            }
            let total = jobs.len().max(1);
            let done = std::sync::atomic::AtomicUsize::new(0);
            let results: Vec<Result<Found>> = jobs
                .par_iter()
                .map(|&(v, b1)| {
                    if run.should_stop() {
                        return Ok(None);
                    }
                    let r = c.split(&root, p.start, p.end, p.budget, self.depth, v, Some(b1));
                    if let Ok(Some((w, u))) = &r {
                        p.offer(run, w, *u);
                    }
                    let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                    run.report(
                        Algorithm::RecursiveGreedy,
                        k as f64 / total as f64,
                        None,
                        format!("split {k}/{total}"),
                    );
                    r
                })
                .collect();
            run.check()?;
            for r in results {
                if let Some((w, u)) = r?
                    && u > best.1
                    && p.fits(p.length(&w))
                {
                    best = (w, u);
                }
            }
        }
        let term = if run.out_of_time() {
            Termination::TimeLimit
        } else {
            Termination::Completed
        };
        Ok(Outcome::new(best.0, best.1, term))
    }
}
