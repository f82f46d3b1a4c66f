//! One planning instance ([`Problem`]: building, engine, metric closure, end points and
//! budget as indices) and what a solver returns ([`Outcome`]).

use std::sync::{Arc, OnceLock};

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use crate::building::Building;
use crate::gp::Kernel;
use crate::surveyor::Surveyor;
use crate::utility::UtilityEngine;
use crate::{Error, Result};

use super::coverage::{EdgeOrder, NearEdges};
use super::{BUDGET_EPS, Metric, Run, Termination};

/// Share of a walk's value that one reversal costs a person's walk
/// ([`Problem::objective`]): a walk that paces back and forth must be worth 1% more per
/// reversal to be preferred. Walking straight back is what testers noticed first in
/// person's plans (issue 13); the robot keeps reversals where they pay. On the small
/// floors of `scripts/sweep_generated.py 61 12 --vary-radio --small` (21 person rows)
/// 2% and 4% left 2.7 and 1.0 reversals per 100 m (1%: 5.4; judged by utility alone:
/// 13.4) at 2.1% and 4.7% less utility than 1% does.
pub const REVERSAL_PENALTY: f64 = 0.01;

/// One planning instance: the building with its engine and metric closure, and the
/// request's end points and budget (as indices).
#[derive(Debug, Clone)]
pub struct Problem {
    pub building: Arc<Building>,
    pub engine: UtilityEngine,
    pub metric: Arc<Metric>,
    pub start: usize,
    pub end: usize,
    pub budget: f64,
    /// The spread constructions' table of nearby edges, built on first use and shared by
    /// clones (see [`Problem::near_edges`]).
    pub near: Arc<OnceLock<Option<NearEdges>>>,
    /// Each vertex's nearest edges in order, built per vertex on first use and shared by
    /// clones (see [`Problem::nearest_edges`]).
    pub order: Arc<OnceLock<EdgeOrder>>,
    /// What an exact evaluation costs on this device, timed once by
    /// [`super::scale::exact_time_estimate`] and shared by clones: a baseline's held walk
    /// and then genetic's population each timed two prefixes of a walk before (about
    /// 0.15 s each on a 3,161-vertex floor, out of a limit the set-up has mostly used).
    pub(in crate::plan) exact_cost: Arc<OnceLock<super::scale::ExactCost>>,
    /// Most doubles the large-building search may keep of its walk's factorisation to
    /// score walks near it ([`crate::utility::NearBase`]): the headroom the request's
    /// memory budget leaves beyond its estimate, at most
    /// [`crate::utility::engine::NEAR_BASE_MAX`] (so that it is not counted in the
    /// estimate, and a request the budget just holds is not refused for it).
    pub near_base_max: usize,
}

impl Problem {
    /// Builds the engine (conditioned on the pilot data) and the metric closure.
    pub fn new(
        building: Arc<Building>,
        kernel: Kernel,
        model: Surveyor,
        start: usize,
        end: usize,
        budget: f64,
    ) -> Result<Self> {
        // The two are independent: with more than one thread the metric's Dijkstras run
        // beside the engine's factorisation, which is one thread's work. The generated
        // 3,161-vertex floor, least of 5 (`examples/problem_timing.rs`, an idle machine):
        // 0.52-0.53 s one after the other on two cores, 0.34-0.36 s side by side; on one
        // thread 0.68 s either way (there `rayon::join` was measured slower, on a busy
        // machine, so one thread builds them one after the other). Since the closure
        // runs on buckets (decision record 0005, session 59), 0.42-0.44 s on one thread.
        let build_engine = || UtilityEngine::new(building.clone(), kernel, model);
        let build_metric = || Arc::new(Metric::new(&building));
        let (engine, metric) = if rayon::current_num_threads() > 1 {
            rayon::join(build_engine, build_metric)
        } else {
            (build_engine(), build_metric())
        };
        let engine = engine?;
        Ok(Problem {
            building,
            engine,
            metric,
            start,
            end,
            budget,
            near: Arc::default(),
            order: Arc::default(),
            exact_cost: Arc::default(),
            near_base_max: crate::utility::engine::NEAR_BASE_MAX,
        })
    }

    /// Same building, engine and metric, other end points or budget.
    pub fn with_ends(&self, start: usize, end: usize, budget: f64) -> Self {
        Problem {
            start,
            end,
            budget,
            ..self.clone()
        }
    }

    /// For each edge, the edges whose midpoints lie within the kernel's length scale of it
    /// (what a spread construction of novelty radius up to `ell` marks as near), or within
    /// a half, a quarter or an eighth of it where the whole would be too big to keep
    /// ([`NearEdges::largest`]), built on first use; `None` when even that is too big
    /// (then a construction scans every edge instead).
    pub fn near_edges(&self) -> Option<&NearEdges> {
        self.near
            .get_or_init(|| NearEdges::largest(&self.building, self.engine.kernel().ell))
            .as_ref()
    }

    /// The edges nearest to vertex `v` ([`EdgeOrder`]): at most
    /// [`super::coverage::ORDER_LEN`] of them, by the distance from `v` to their nearer
    /// end, then by index.
    pub fn nearest_edges(&self, v: usize) -> &[u32] {
        self.order
            .get_or_init(|| EdgeOrder::new(self.building.len()))
            .of(self, v)
    }

    /// Whether a length fits the budget.
    pub fn fits(&self, length: f64) -> bool {
        length <= self.budget + BUDGET_EPS
    }

    /// One step of a random walk from `v`: a neighbour drawn uniformly from those that
    /// `admits(neighbour, edge length)` accepts, with the edge's length; `None` when it
    /// accepts none. `opts` is scratch space, kept by the caller across steps.
    pub fn random_step(
        &self,
        v: usize,
        rng: &mut ChaCha8Rng,
        opts: &mut Vec<(usize, f64)>,
        admits: impl Fn(usize, f64) -> bool,
    ) -> Option<(usize, f64)> {
        opts.clear();
        for &(w, e) in self.building.neighbours(v) {
            let l = self.building.edges[e].length;
            if admits(w, l) {
                opts.push((w, l));
            }
        }
        if opts.is_empty() {
            return None;
        }
        Some(opts[rng.random_range(0..opts.len())])
    }

    /// `C(P)` of a walk of adjacent vertices.
    pub fn length(&self, walk: &[usize]) -> f64 {
        self.building.walk_length(walk)
    }

    /// `f_D(P)`.
    pub fn utility(&self, walk: &[usize]) -> Result<f64> {
        self.engine.utility(walk)
    }

    /// What `auto` maximises: a walk's `utility` (its exact `f_D`, or a surrogate's value
    /// of it), less [`REVERSAL_PENALTY`] of it per reversal for a person
    /// ([`reversals`](super::coverage::reversals): walking straight back along the edge
    /// just walked, not at a dead end). A robot is judged by `utility` alone. The utility
    /// reported and saved is always the exact `f_D`; this only chooses between walks.
    pub fn objective(&self, walk: &[usize], utility: f64) -> f64 {
        if matches!(self.engine.model(), Surveyor::Human { .. }) {
            let r = super::coverage::reversals(self, walk) as f64;
            utility * (1.0 - REVERSAL_PENALTY * r).max(0.0)
        } else {
            utility
        }
    }

    /// Offers a feasible walk to the run as its best so far (see [`Run::offer`]), ranked
    /// by its [`objective`](Self::objective); infeasible walks are ignored.
    pub fn offer(&self, run: &Run, walk: &[usize], utility: f64) {
        let len = self.length(walk);
        if walk.first() == Some(&self.start) && walk.last() == Some(&self.end) && self.fits(len) {
            run.offer(walk, utility, self.objective(walk, utility), len);
        }
    }

    /// `f_D` of many walks in parallel.
    pub fn utilities(&self, walks: &[Vec<usize>]) -> Result<Vec<f64>> {
        self.engine.utilities(walks).into_iter().collect()
    }

    /// The shortest walk from start to end.
    pub fn shortest_walk(&self) -> Vec<usize> {
        self.metric.path(self.start, self.end)
    }

    /// Whether `walk` is a feasible answer: real edges, right ends, within budget.
    pub fn check(&self, walk: &[usize]) -> Result<()> {
        self.building.check_walk(walk)?;
        let bad = |m: String| {
            Err(Error::InvalidWalk {
                step: 0,
                message: m,
            })
        };
        match (walk.first(), walk.last()) {
            (Some(&a), Some(&b)) if a == self.start && b == self.end => {}
            _ => return bad("the walk does not run from the start to the end".into()),
        }
        let len = self.length(walk);
        if !self.fits(len) {
            return bad(format!(
                "the walk is {len} m long, over the budget of {} m",
                self.budget
            ));
        }
        Ok(())
    }
}

/// A solver's answer before it is dressed as a [`PlanResult`](super::PlanResult).
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    pub walk: Vec<usize>,
    pub utility: f64,
    pub termination: Termination,
    pub optimal: Option<bool>,
    pub nodes: Option<u64>,
}

impl Outcome {
    /// A heuristic's answer.
    pub fn new(walk: Vec<usize>, utility: f64, termination: Termination) -> Self {
        Outcome {
            walk,
            utility,
            termination,
            optimal: None,
            nodes: None,
        }
    }
}
