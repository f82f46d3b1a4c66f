//! Replanning during a session: a walk from the current vertex to the plan's end within the
//! budget left, conditioned on the pilot data plus everything collected so far.
//!
//! The session asks a [`Replanner`]; [`GreedyReplanner`] is the built-in one (best utility
//! gain per metre, always keeping the way to the end within budget). The planners of
//! `trailprint::plan` plug in through the same trait.

use std::sync::Arc;

use crate::building::Building;
use crate::gp::Kernel;
use crate::plan::PlanOrigin;
use crate::surveyor::Surveyor;
use crate::utility::{Observation, UtilityEngine};
use crate::{Error, Result};

/// Slack on the budget (SPEC section 3): the planners' one constant.
pub use crate::plan::BUDGET_EPS;

/// What a replanner is asked for.
#[derive(Debug, Clone)]
pub struct ReplanRequest<'a> {
    pub building: &'a Arc<Building>,
    pub kernel: Kernel,
    pub model: Surveyor,
    /// Samples collected so far with their label noise (pilot data is added by the engine).
    pub prior: &'a [Observation],
    pub start: usize,
    pub end: usize,
    pub budget_m: f64,
    pub seed: u64,
    /// Most memory the replan may use, bytes ([`crate::plan::PlanSettings::memory_budget`]).
    pub memory_budget: u64,
}

/// A walk planner usable for replanning.
pub trait Replanner: Send + Sync {
    /// A walk (vertex indices) from `start` to `end` of length at most `budget_m`, or
    /// [`Error::Unreachable`] when none exists.
    fn replan(&self, request: &ReplanRequest<'_>) -> Result<Vec<usize>>;
    /// [`Replanner::replan`], and the walk's exact utility given the request's prior
    /// (SPEC section 3) when the replanner computed it, so that the session does not
    /// evaluate it again (on the generated mall, a robot's 1,800 m walk is most of a
    /// second per evaluation).
    fn replan_scored(&self, request: &ReplanRequest<'_>) -> Result<(Vec<usize>, Option<f64>)> {
        Ok((self.replan(request)?, None))
    }
    /// Where its walks come from, stored with the plan (`algorithm`).
    fn origin(&self) -> PlanOrigin;
    /// The time a replan may take, when it stops on a clock; `None` for a replanner that
    /// runs to completion (the session then may ask it twice, see `Session::replan`; a
    /// time-limited one is asked once).
    fn time_limit(&self) -> Option<std::time::Duration> {
        None
    }
}

/// Greedy on utility gain per metre with a short look-ahead: at each step it tries every
/// path of up to `depth` edges from the current vertex (the depth grows with the sample
/// spacing, so that a path can reach the next sample), keeps the end reachable within
/// budget, and appends the path of best gain per metre; it stops when nothing gains and
/// closes the walk with a shortest path to the end.
///
/// Complexity: per step `O(degree^depth)` utility evaluations, each `O(|V|^3)` on the
/// engine's `Sigma` plus the samples of the path.
#[derive(Debug, Clone, Copy, Default)]
pub struct GreedyReplanner;

struct Search<'a> {
    b: &'a Building,
    to_end: &'a [f64],
    budget: f64,
    current: f64,
    path: Vec<usize>,
    best: Option<(f64, Vec<usize>, f64)>,
}

impl Search<'_> {
    fn explore(
        &mut self,
        walk: &mut crate::utility::WalkState<'_>,
        depth: usize,
        path_len: f64,
    ) -> Result<()> {
        let at = walk.last();
        let used = walk.length();
        for &(nb, e) in self.b.neighbours(at) {
            let len = self.b.edges[e].length;
            if used + len + self.to_end[nb] > self.budget + BUDGET_EPS {
                continue;
            }
            let mark = walk.mark();
            walk.push(nb)?;
            self.path.push(nb);
            let u = walk.utility()?;
            let gain = (u - self.current) / (path_len + len);
            if self.best.as_ref().is_none_or(|(g, _, _)| gain > *g) {
                self.best = Some((gain, self.path.clone(), u));
            }
            if depth > 1 {
                self.explore(walk, depth - 1, path_len + len)?;
            }
            self.path.pop();
            walk.rewind(&mark);
        }
        Ok(())
    }
}

impl Replanner for GreedyReplanner {
    fn replan(&self, r: &ReplanRequest<'_>) -> Result<Vec<usize>> {
        let b = r.building;
        let to_end = distances_from(b, r.end);
        check_reachable(b, r.start, r.end, r.budget_m, &to_end)?;
        let engine = UtilityEngine::with_prior(b.clone(), r.kernel, r.model, r.prior)?;
        let mean_edge = if b.edges.is_empty() {
            1.0
        } else {
            b.total_edge_length() / b.edges.len() as f64
        };
        let depth = ((r.model.spacing() / mean_edge).ceil() as usize + 1).clamp(2, 5);
        let mut walk = engine.start(r.start)?;
        let mut search = Search {
            b,
            to_end: &to_end,
            budget: r.budget_m,
            current: walk.utility()?,
            path: Vec::new(),
            best: None,
        };
        loop {
            search.best = None;
            search.explore(&mut walk, depth, 0.0)?;
            match search.best.take() {
                Some((gain, path, u)) if gain > 1e-12 => {
                    for v in path {
                        walk.push(v)?;
                    }
                    search.current = u;
                }
                _ => break,
            }
        }
        let mut out = walk.walk().to_vec();
        let tail = shortest_path(b, walk.last(), r.end)?;
        out.extend_from_slice(&tail[1..]);
        Ok(out)
    }

    fn origin(&self) -> PlanOrigin {
        PlanOrigin::SessionGreedy
    }
}

/// Errors with [`Error::Unreachable`] when the shortest way from `start` to `end` does not
/// fit the budget.
pub fn check_reachable(
    b: &Building,
    start: usize,
    end: usize,
    budget_m: f64,
    to_end: &[f64],
) -> Result<()> {
    if to_end[start] > budget_m + BUDGET_EPS {
        return Err(Error::Unreachable {
            start: b.vertices[start].id.clone(),
            end: b.vertices[end].id.clone(),
            budget: budget_m,
            shortest: to_end[start],
        });
    }
    Ok(())
}

fn dijkstra(b: &Building, root: usize) -> (Vec<f64>, Vec<u32>) {
    crate::plan::metric::shortest_path_tree(b, root)
}

/// Shortest walking distance from every vertex to `to` (the graph is undirected).
pub fn distances_from(b: &Building, to: usize) -> Vec<f64> {
    dijkstra(b, to).0
}

/// A shortest walk from `from` to `to` (vertex indices, both included).
pub fn shortest_path(b: &Building, from: usize, to: usize) -> Result<Vec<usize>> {
    // Search from `to` so that following `prev` from `from` yields the walk in order.
    let (dist, prev) = dijkstra(b, to);
    if !dist[from].is_finite() {
        return Err(Error::InvalidRequest(format!(
            "no path from {:?} to {:?}",
            b.vertices[from].id, b.vertices[to].id
        )));
    }
    let mut out = vec![from];
    let mut v = from;
    while v != to {
        v = prev[v] as usize;
        out.push(v);
    }
    Ok(out)
}

/// Time limit of a replan by `auto` on a large building ([`default_replanner`]). Measured with `examples/replan_compare` (one core, from
/// 20%, 50% and 80% of an auto plan): 1 s adds within 3% of what 2 s adds (campus robot
/// 446 m: 117.25 / 72.39 / 24.31 nats against 116.19 / 72.12 / 24.34; mall person
/// 509 m: 45.59 / 24.98 / 6.55 against 46.84 / 24.44 / 6.55).
pub const LARGE_REPLAN_LIMIT: std::time::Duration = std::time::Duration::from_secs(1);

/// Buildings with more vertices than this replan with `auto` by default
/// ([`default_replanner`]). The session-greedy's evaluations factorise the posterior of
/// every vertex for every path it tries, so its time grows with the cube of the vertex
/// count: measured with `examples/replan_compare` from 20%, 50% and 80% of an auto plan
/// (one core), 0.02 to 0.14 s on the generated 125-vertex office (person 201 m), 0.5 to
/// 2.9 s on the 290-vertex campus (person 446 m) and 0.7 to 15.9 s on the 565-vertex mall
/// (person 509 m; a simulated session there spent 30 to 44 s a replan). Below this
/// count it is also the safer choice where wrong turns are very frequent: with a wrong
/// turn at 30% of the vertices (`simulate --deviate 0.3 --seed 2`, office, 225 m) auto's
/// walks, which reach into the rooms, meet more wrong turns per metre, the session's
/// reserve for them grows, and 2 of 4 runs ended after 72 and 82 m (32 nats), where the
/// greedy walks 206 m (55.31 nats); at 10% (seeds 1-3) the two are level there (auto
/// 64.6 nats on average, greedy 63.4).
pub const LARGE_REPLAN_VERTICES: usize = 200;

/// The replanner a session starts with: [`GreedyReplanner`] on buildings of at most
/// [`LARGE_REPLAN_VERTICES`] vertices, where it answers within a third of a second and
/// the same state always gives the same walk; `auto` with [`LARGE_REPLAN_LIMIT`] on
/// larger ones, where the greedy is slow and short-sighted. From 20%, 50% and 80% of an
/// auto plan (`examples/replan_compare`, one core), what the new walk adds: mall person
/// 509 m, greedy 35.48 / 17.40 / 5.59 nats in 15.9 / 6.7 / 0.7 s, auto 47.59 / 27.93 /
/// 6.29 nats in 2 s each; campus robot 446 m, greedy 24.10 / 56.23 / 12.74 nats, auto
/// 116.45 / 77.32 / 24.21. Whole simulated sessions on the campus, person, 446 m, a wrong
/// turn at 10% of the vertices, seeds 1-3: auto collects 115.90 / 106.21 / 117.18 nats,
/// greedy 99.72 / 90.50 / 100.83; at 30% (300 m, seeds 2-4) 82.38 / 81.18 / 70.56
/// against 79.25 / 81.23 / 75.53.
pub fn default_replanner(b: &Building) -> Arc<dyn Replanner> {
    if b.len() > LARGE_REPLAN_VERTICES {
        let mut auto = PlannerReplanner::new(crate::plan::Algorithm::Auto);
        auto.time_limit = Some(LARGE_REPLAN_LIMIT);
        Arc::new(auto)
    } else {
        Arc::new(GreedyReplanner)
    }
}

/// Any planner of [`crate::plan`], conditioned on the collected samples through
/// [`plan_with_prior`](crate::plan::plan_with_prior). Deterministic for a seed unless the
/// algorithm stops on a time limit (`auto` does by default); a resumed session redoes an
/// interrupted replan, so prefer a deterministic algorithm when replays must match bit for
/// bit.
#[derive(Debug, Clone)]
pub struct PlannerReplanner {
    pub algorithm: crate::plan::Algorithm,
    pub time_limit: Option<std::time::Duration>,
    pub params: crate::plan::Params,
    /// The session's building's metric closure, built by the first replan and kept for
    /// the others (shared by clones of this replanner).
    metric: Arc<crate::plan::SharedMetric>,
}

impl PlannerReplanner {
    pub fn new(algorithm: crate::plan::Algorithm) -> Self {
        PlannerReplanner {
            algorithm,
            time_limit: None,
            params: crate::plan::Params::default(),
            metric: Arc::default(),
        }
    }
}

impl Replanner for PlannerReplanner {
    fn replan(&self, r: &ReplanRequest<'_>) -> Result<Vec<usize>> {
        Ok(self.replan_scored(r)?.0)
    }

    /// The planner's own exact utility of its walk comes along.
    fn replan_scored(&self, r: &ReplanRequest<'_>) -> Result<(Vec<usize>, Option<f64>)> {
        let b = r.building;
        let time_limit = self.time_limit;
        let settings = crate::plan::PlanSettings {
            model: r.model,
            algorithm: self.algorithm,
            seed: r.seed,
            time_limit,
            params: self.params,
            memory_budget: r.memory_budget,
        };
        let req = crate::plan::PlanRequest::with_settings(
            &b.vertices[r.start].id,
            &b.vertices[r.end].id,
            r.budget_m,
            r.kernel,
            &settings,
        );
        let control = crate::plan::Control::new();
        let shared = Some(self.metric.as_ref());
        let plan = |req: &crate::plan::PlanRequest| {
            crate::plan::plan_with_prior_sharing(b.clone(), req, r.prior, &control, shared)
        };
        let res = match plan(&req) {
            // A surveyor waiting mid-survey needs a walk: where the limit cannot hold one
            // exact evaluation (a robot's long walk on a large floor), a late answer beats
            // none, so plan again with the time it said it needs and the limit on top.
            Err(crate::Error::TimeLimitTooShort { needed, .. }) => {
                let mut req = req;
                req.settings.time_limit =
                    Some(needed.mul_f64(1.5) + time_limit.unwrap_or_default());
                plan(&req)?
            }
            other => other?,
        };
        Ok((res.walk_indices, Some(res.utility_nats)))
    }

    fn origin(&self) -> PlanOrigin {
        PlanOrigin::Planner(self.algorithm)
    }

    fn time_limit(&self) -> Option<std::time::Duration> {
        self.time_limit
    }
}
