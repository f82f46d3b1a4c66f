//! Planners: walks from `v_s` to `v_t` within a budget that maximise the utility `f_D(P)`
//! of SPEC section 3.
//!
//! # Layout (argmin style)
//! * The **problem** ([`Problem`]) holds the building, the fast [`UtilityEngine`], the
//!   metric closure ([`metric::Metric`]) and the request's start, end and budget.
//! * Each **solver** is a type implementing [`Solver`] in its own file: [`greedy`] (the
//!   paper's Algorithm 1), [`genetic`] (paper IV-B), [`recursive_greedy`] (Chekuri and Pal),
//!   [`ero`] (edge-based random orienteering), [`exact`] (branch and bound) and [`auto`]
//!   (ours, the default).
//! * The **run state** ([`Run`]) carries the caller's [`Control`] (cancel token, progress
//!   observer), the deadline from the time limit and the seeded random generator is
//!   created by each solver from [`PlanRequest::seed`] (`ChaCha8Rng::seed_from_u64`).
//! * **Termination** is an enum ([`Termination`]): completed, proved optimal, time limit,
//!   cancelled. Solvers [`offer`](Run::offer) their best walk as they go, so a plan that
//!   is cancelled (or a solver that runs out of time deep inside a step) returns the best
//!   walk so far, `termination: cancelled`, never nothing.
//!
//! Every returned walk follows real edges, starts at `v_s`, ends at `v_t` and satisfies
//! `C(P) <= B + BUDGET_EPS` (1e-9 m); [`plan`] checks this before returning.

pub mod auto;
#[cfg(feature = "research")]
pub mod bench;
pub mod coverage;
pub mod ero;
pub mod exact;
pub mod genetic;
pub mod greedy;
pub mod local_search;
pub mod metric;
pub mod recursive_greedy;
pub mod scale;
pub mod steiner;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::building::Building;
use crate::gp::Kernel;
use crate::samples::{SurveyorModel, sample_walk};
use crate::utility::UtilityEngine;
use crate::{Error, Result};

pub use metric::Metric;

/// Feasibility tolerance of SPEC section 3: a walk fits when `C(P) <= B + BUDGET_EPS`.
pub const BUDGET_EPS: f64 = 1e-9;

/// The planning algorithms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Algorithm {
    /// Ours: greedy, then a genetic search seeded with it, then local search, and an
    /// exact search when the instance is small enough (see [`auto`]).
    #[default]
    Auto,
    /// The paper's Algorithm 1 (ratio greedy over Steiner TSP paths).
    Greedy,
    /// The paper's genetic algorithm (section IV-B).
    Genetic,
    /// Chekuri and Pal's recursive greedy (depth [`Params::depth`]).
    RecursiveGreedy,
    /// Edge-based random orienteering.
    Ero,
    /// Branch and bound; proves optimality when it finishes.
    Exact,
    /// The systematic walk without any utility: nearest unwalked edge first (the
    /// baseline a surveyor without Trailprint achieves, see [`coverage`]).
    Coverage,
}

impl Algorithm {
    /// All algorithms, in the order the benchmark lists them.
    pub const ALL: [Algorithm; 7] = [
        Algorithm::Coverage,
        Algorithm::Greedy,
        Algorithm::Genetic,
        Algorithm::RecursiveGreedy,
        Algorithm::Ero,
        Algorithm::Exact,
        Algorithm::Auto,
    ];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Auto => "auto",
            Algorithm::Greedy => "greedy",
            Algorithm::Genetic => "genetic",
            Algorithm::RecursiveGreedy => "recursive-greedy",
            Algorithm::Ero => "ero",
            Algorithm::Exact => "exact",
            Algorithm::Coverage => "coverage",
        }
    }

    /// Parses a name as written by [`name`](Self::name).
    pub fn from_name(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| {
                Error::InvalidRequest(format!(
                    "unknown algorithm {s:?}, expected one of auto, greedy, genetic, recursive-greedy, ero, exact, coverage"
                ))
            })
    }

    /// Default time limit when the request gives none: 2 s for `auto`, none otherwise.
    pub fn default_time_limit(self) -> Option<Duration> {
        match self {
            Algorithm::Auto => Some(Duration::from_secs(2)),
            _ => None,
        }
    }
}

impl std::fmt::Display for Algorithm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Tuning parameters; each algorithm reads the ones it needs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Params {
    /// Genetic: population size (paper: 100 and 200).
    pub population: usize,
    /// Genetic: number of generations (paper: 5).
    pub generations: usize,
    /// Genetic: tournament size (paper: 10).
    pub tournament: usize,
    /// Genetic: probability that an offspring is mutated (paper: 0.9).
    pub mutation: f64,
    /// Recursive greedy: recursion depth `I` (default 2).
    pub depth: usize,
    /// Recursive greedy: budget discretisation step in metres (0 = automatic, `B / 12`
    /// rounded up to a multiple of the sample spacing).
    pub budget_step: f64,
    /// ERO: number of iterations (0 = until the time limit, or 2,000 without one).
    pub iterations: usize,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            population: 200,
            generations: 5,
            tournament: 10,
            mutation: 0.9,
            depth: 2,
            budget_step: 0.0,
            iterations: 0,
        }
    }
}

/// `Option<Duration>` as fractional seconds in JSON.
mod opt_secs {
    use std::time::Duration;

    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(d: &Option<Duration>, s: S) -> Result<S::Ok, S::Error> {
        match d {
            Some(d) => s.serialize_some(&d.as_secs_f64()),
            None => s.serialize_none(),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Duration>, D::Error> {
        let v: Option<f64> = Option::deserialize(d)?;
        match v {
            None => Ok(None),
            Some(x) if x.is_finite() && x >= 0.0 => Ok(Some(Duration::from_secs_f64(x))),
            Some(x) => Err(serde::de::Error::custom(format!(
                "time_limit must be a non-negative number of seconds, got {x}"
            ))),
        }
    }
}

/// What to plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanRequest {
    /// Start vertex id `v_s`.
    pub start: String,
    /// End vertex id `v_t` (may equal the start: a closed walk).
    pub end: String,
    /// Budget `B`, metres.
    pub budget: f64,
    /// Who walks.
    #[serde(default)]
    pub model: SurveyorModel,
    /// Kernel hyperparameters.
    pub kernel: Kernel,
    #[serde(default)]
    pub algorithm: Algorithm,
    /// Seed of every random choice.
    #[serde(default)]
    pub seed: u64,
    /// Stop with the best walk so far after this long (`auto`: 2 s when `None`).
    #[serde(default, with = "opt_secs")]
    pub time_limit: Option<Duration>,
    #[serde(default)]
    pub params: Params,
    /// Most memory the plan may use, bytes (default [`DEFAULT_MEMORY_BUDGET`]): a request
    /// whose working set would exceed it is refused before anything is allocated
    /// ([`Error::InvalidRequest`] naming the size and what to change).
    #[serde(default = "default_memory_budget")]
    pub memory_budget: u64,
}

/// How to plan, apart from where and with which kernel: what a team's members share, and
/// what a caller that lets the store choose the kernel
/// ([`Store::plan_and_save`](crate::store::Store::plan_and_save)) passes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlanSettings {
    /// Who walks.
    #[serde(default)]
    pub model: SurveyorModel,
    #[serde(default)]
    pub algorithm: Algorithm,
    /// Seed of every random choice.
    #[serde(default)]
    pub seed: u64,
    /// Stop with the best walk so far after this long (`auto`: 2 s when `None`).
    #[serde(default, with = "opt_secs")]
    pub time_limit: Option<Duration>,
    #[serde(default)]
    pub params: Params,
    /// Most memory the plan may use, bytes (default [`DEFAULT_MEMORY_BUDGET`]).
    #[serde(default = "default_memory_budget")]
    pub memory_budget: u64,
}

impl Default for PlanSettings {
    /// The defaults of [`PlanRequest::new`]: `auto`, robot model, seed 0.
    fn default() -> Self {
        PlanSettings {
            model: SurveyorModel::default(),
            algorithm: Algorithm::default(),
            seed: 0,
            time_limit: None,
            params: Params::default(),
            memory_budget: DEFAULT_MEMORY_BUDGET,
        }
    }
}

/// Largest genetic population a request may ask for (the paper uses 100 and 200).
pub const MAX_POPULATION: usize = 10_000;

/// Most genetic generations a request may ask for (the paper uses 5).
pub const MAX_GENERATIONS: usize = 10_000;

/// Default memory budget of a plan: 512 MiB, what a mid-range phone lets an app use.
pub const DEFAULT_MEMORY_BUDGET: u64 = 512 << 20;

fn default_memory_budget() -> u64 {
    DEFAULT_MEMORY_BUDGET
}

/// A budget may be at most this many times the building's total edge length (plus the
/// shortest way from the start to the end): a longer walk only repeats edges it has
/// walked, and the planners size populations and tables from the budget.
pub const MAX_BUDGET_FACTOR: f64 = 4.0;

impl PlanRequest {
    /// A request with default algorithm (`auto`), robot model, seed 0 and default parameters.
    pub fn new(start: &str, end: &str, budget: f64, kernel: Kernel) -> Self {
        Self::with_settings(start, end, budget, kernel, &PlanSettings::default())
    }

    /// A request for the route `start` to `end` within `budget`, with `kernel` and the
    /// planner settings `s`.
    pub fn with_settings(
        start: &str,
        end: &str,
        budget: f64,
        kernel: Kernel,
        s: &PlanSettings,
    ) -> Self {
        PlanRequest {
            start: start.to_string(),
            end: end.to_string(),
            budget,
            model: s.model,
            kernel,
            algorithm: s.algorithm,
            seed: s.seed,
            time_limit: s.time_limit,
            params: s.params,
            memory_budget: s.memory_budget,
        }
    }

    /// The planner settings of this request (everything but the route and the kernel).
    pub fn settings(&self) -> PlanSettings {
        PlanSettings {
            model: self.model,
            algorithm: self.algorithm,
            seed: self.seed,
            time_limit: self.time_limit,
            params: self.params,
            memory_budget: self.memory_budget,
        }
    }

    /// The time limit in effect (the request's, else the algorithm's default).
    pub fn effective_time_limit(&self) -> Option<Duration> {
        self.time_limit
            .or_else(|| self.algorithm.default_time_limit())
    }
}

/// Why a planner stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The algorithm ran to its natural end.
    Completed,
    /// The exact search finished: the walk is optimal.
    Optimal,
    /// The time limit was reached; the walk is the best found so far.
    TimeLimit,
    /// The caller cancelled; the walk is the best found so far.
    Cancelled,
}

impl Termination {
    /// The name used in JSON and CSV (`completed`, `optimal`, `time_limit`, `cancelled`).
    pub fn name(self) -> &'static str {
        match self {
            Termination::Completed => "completed",
            Termination::Optimal => "optimal",
            Termination::TimeLimit => "time_limit",
            Termination::Cancelled => "cancelled",
        }
    }
}

/// The outcome of a plan, in the JSON shape of SPEC section 7 (plus `optimal`, `nodes`
/// for the exact search and `termination`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanResult {
    pub algorithm: Algorithm,
    /// Vertex ids of the walk.
    pub walk: Vec<String>,
    /// Vertex indices of the walk (not serialised: indices never leave the process).
    #[serde(skip)]
    pub walk_indices: Vec<usize>,
    pub length_m: f64,
    pub budget_m: f64,
    pub samples: usize,
    pub utility_nats: f64,
    pub elapsed_ms: u64,
    pub seed: u64,
    pub kernel: Kernel,
    /// Exact search: whether the walk is proved optimal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimal: Option<bool>,
    /// Exact search: number of search nodes explored.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nodes: Option<u64>,
    pub termination: Termination,
}

/// A progress report.
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// The algorithm reporting (for `auto`, the phase's algorithm).
    pub algorithm: Algorithm,
    /// Estimated fraction of the work done, in `[0, 1]` (a time fraction under a limit).
    pub fraction: f64,
    /// Utility of the best walk so far, nats, if there is one.
    pub best_utility: Option<f64>,
    /// Length of the best walk so far, metres, if there is one.
    pub best_length: Option<f64>,
    /// A short human-readable note (`generation 3/5`, `1234 nodes`).
    pub message: String,
}

/// Receives progress reports; called from the planning thread (or a rayon worker), so it
/// must be cheap and thread-safe.
pub trait Observer: Send + Sync {
    fn progress(&self, p: &Progress);
}

/// An observer that ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoObserver;

impl Observer for NoObserver {
    fn progress(&self, _: &Progress) {}
}

/// How the caller steers a running plan: a cancel token another thread may set, and an
/// optional progress observer.
#[derive(Clone, Default)]
pub struct Control {
    cancel: Arc<AtomicBool>,
    observer: Option<Arc<dyn Observer>>,
}

impl std::fmt::Debug for Control {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Control")
            .field("cancelled", &self.is_cancelled())
            .field("observer", &self.observer.is_some())
            .finish()
    }
}

impl Control {
    /// No observer, a fresh cancel token.
    pub fn new() -> Self {
        Self::default()
    }

    /// Uses `token` as the cancel token (set it to `true` to cancel).
    pub fn with_cancel_token(mut self, token: Arc<AtomicBool>) -> Self {
        self.cancel = token;
        self
    }

    /// Sends progress reports to `observer`.
    pub fn with_observer(mut self, observer: Arc<dyn Observer>) -> Self {
        self.observer = Some(observer);
        self
    }

    /// The cancel token, to hand to another thread.
    pub fn cancel_token(&self) -> Arc<AtomicBool> {
        self.cancel.clone()
    }

    /// Asks the running plan to stop; it returns [`Error::Cancelled`] promptly.
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// Whether cancellation was requested.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
}

/// The best walk a run has found so far: what a cancelled or timed-out plan returns.
#[derive(Debug, Clone, Default)]
struct Incumbent {
    walk: Vec<usize>,
    utility: f64,
}

/// The run state shared by a solver's threads: control, start time, deadline and the
/// best walk so far (solvers [`offer`](Run::offer) theirs as they go).
#[derive(Debug, Clone)]
pub struct Run {
    control: Control,
    started: Instant,
    deadline: Option<Instant>,
    best: Arc<std::sync::Mutex<Option<Incumbent>>>,
    /// Length of the best walk so far, for progress reports (f64 bits; NaN: none).
    best_length: Arc<std::sync::atomic::AtomicU64>,
    /// The algorithm the user asked for: every report carries it, whichever stage or
    /// sub-search sends it (set by [`plan_with_prior`]).
    algorithm: Option<Algorithm>,
    /// Highest fraction and best utility reported so far (f64 bits): what a progress bar
    /// shows never goes back, though stages and parallel subtrees report out of order.
    reported: Arc<std::sync::Mutex<(f64, Option<f64>)>>,
}

impl Run {
    /// Starts the clock now.
    pub fn new(control: Control, time_limit: Option<Duration>) -> Self {
        Self::starting_at(control, time_limit, Instant::now())
    }

    /// Starts the clock at `started` (when the request arrived, so that set-up counts
    /// against the time limit).
    pub fn starting_at(control: Control, time_limit: Option<Duration>, started: Instant) -> Self {
        Run {
            control,
            started,
            deadline: time_limit.map(|t| started + t),
            best: Arc::default(),
            best_length: Arc::new(std::sync::atomic::AtomicU64::new(f64::NAN.to_bits())),
            algorithm: None,
            reported: Arc::new(std::sync::Mutex::new((0.0, None))),
        }
    }

    /// Reports of this run name `algorithm`, whatever stage sends them.
    pub fn for_algorithm(mut self, algorithm: Algorithm) -> Self {
        self.algorithm = Some(algorithm);
        self
    }

    /// Offers a feasible walk (start to end, within budget) with its exact utility; the
    /// run keeps the best offered (ties: see [`better`]) and returns it if the plan is
    /// cancelled or runs out of time before the solver returns.
    pub fn offer(&self, walk: &[usize], utility: f64, length: f64) {
        let Ok(mut g) = self.best.lock() else {
            return;
        };
        let replace = match &*g {
            None => true,
            Some(b) => better((walk, utility), (&b.walk, b.utility)),
        };
        if replace && utility.is_finite() {
            *g = Some(Incumbent {
                walk: walk.to_vec(),
                utility,
            });
            self.best_length.store(length.to_bits(), Ordering::Relaxed);
        }
    }

    /// The best walk offered so far and its utility.
    pub fn incumbent(&self) -> Option<(Vec<usize>, f64)> {
        self.best
            .lock()
            .ok()
            .and_then(|g| g.as_ref().map(|b| (b.walk.clone(), b.utility)))
    }

    /// The same control with an earlier deadline (for a phase of `auto`).
    pub fn with_deadline(&self, deadline: Option<Instant>) -> Self {
        let deadline = match (self.deadline, deadline) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        Run {
            control: self.control.clone(),
            started: self.started,
            deadline,
            best: self.best.clone(),
            best_length: self.best_length.clone(),
            algorithm: self.algorithm,
            reported: self.reported.clone(),
        }
    }

    /// `Err(Cancelled)` if the caller cancelled.
    pub fn check(&self) -> Result<()> {
        if self.control.is_cancelled() {
            Err(Error::Cancelled)
        } else {
            Ok(())
        }
    }

    /// Whether the caller cancelled.
    pub fn control_cancelled(&self) -> bool {
        self.control.is_cancelled()
    }

    /// Whether the deadline has passed.
    pub fn out_of_time(&self) -> bool {
        self.deadline.is_some_and(|d| Instant::now() >= d)
    }

    /// Whether to stop now (cancelled or out of time).
    pub fn should_stop(&self) -> bool {
        self.control.is_cancelled() || self.out_of_time()
    }

    /// The time limit (deadline minus start), if any.
    pub fn time_limit(&self) -> Option<Duration> {
        self.deadline
            .map(|d| d.saturating_duration_since(self.started))
    }

    /// The deadline, if any.
    pub fn deadline(&self) -> Option<Instant> {
        self.deadline
    }

    /// Time since the start.
    pub fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    /// Fraction of the time limit used, if there is one.
    pub fn time_fraction(&self) -> Option<f64> {
        self.deadline.map(|d| {
            let total = d.saturating_duration_since(self.started).as_secs_f64();
            if total <= 0.0 {
                1.0
            } else {
                (self.started.elapsed().as_secs_f64() / total).min(1.0)
            }
        })
    }

    /// Sends a progress report to the observer, if any.
    ///
    /// What the observer sees is consistent whatever the stage: the requested algorithm,
    /// a fraction that never goes back, and the best utility so far (the larger of the
    /// stage's own figure, the best walk offered, and what was reported before).
    pub fn report(&self, algorithm: Algorithm, fraction: f64, best: Option<f64>, msg: String) {
        if let Some(o) = &self.control.observer {
            let len = f64::from_bits(self.best_length.load(Ordering::Relaxed));
            let offered = self.incumbent().map(|(_, u)| u);
            let (fraction, best) = {
                let mut r = self.reported.lock().unwrap_or_else(|e| e.into_inner());
                r.0 = r.0.max(fraction.clamp(0.0, 1.0));
                for u in [best, offered].into_iter().flatten() {
                    r.1 = Some(r.1.map_or(u, |b: f64| b.max(u)));
                }
                *r
            };
            o.progress(&Progress {
                algorithm: self.algorithm.unwrap_or(algorithm),
                fraction,
                best_utility: best,
                best_length: (best.is_some() && len.is_finite()).then_some(len),
                message: msg,
            });
        }
    }
}

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
}

impl Problem {
    /// Builds the engine (conditioned on the pilot data) and the metric closure.
    pub fn new(
        building: Arc<Building>,
        kernel: Kernel,
        model: SurveyorModel,
        start: usize,
        end: usize,
        budget: f64,
    ) -> Result<Self> {
        let engine = UtilityEngine::new(building.clone(), kernel, model)?;
        let metric = Arc::new(Metric::new(&building));
        Ok(Problem {
            building,
            engine,
            metric,
            start,
            end,
            budget,
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

    /// Whether a length fits the budget.
    pub fn fits(&self, length: f64) -> bool {
        length <= self.budget + BUDGET_EPS
    }

    /// `C(P)` of a walk of adjacent vertices.
    pub fn length(&self, walk: &[usize]) -> f64 {
        self.building.walk_length(walk)
    }

    /// `f_D(P)`.
    pub fn utility(&self, walk: &[usize]) -> Result<f64> {
        self.engine.utility(walk)
    }

    /// Offers a feasible walk to the run as its best so far (see [`Run::offer`]);
    /// infeasible walks are ignored.
    pub fn offer(&self, run: &Run, walk: &[usize], utility: f64) {
        let len = self.length(walk);
        if walk.first() == Some(&self.start) && walk.last() == Some(&self.end) && self.fits(len) {
            run.offer(walk, utility, len);
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

/// A solver's answer before it is dressed as a [`PlanResult`].
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

/// A planning algorithm.
pub trait Solver {
    /// Which algorithm this is.
    fn algorithm(&self) -> Algorithm;

    /// Plans on `problem`. Returns the best walk found; [`Error::Cancelled`] if `run` was
    /// cancelled.
    fn solve(&self, problem: &Problem, run: &Run) -> Result<Outcome>;
}

/// The solver for a request's algorithm, seed and parameters.
pub fn solver_for(
    algorithm: Algorithm,
    seed: u64,
    params: &Params,
) -> Box<dyn Solver + Send + Sync> {
    match algorithm {
        Algorithm::Greedy => Box::new(greedy::Greedy::paper()),
        Algorithm::Genetic => Box::new(genetic::Genetic::new(*params, seed)),
        Algorithm::RecursiveGreedy => Box::new(recursive_greedy::RecursiveGreedy::new(
            params.depth,
            params.budget_step,
        )),
        Algorithm::Ero => Box::new(ero::Ero::new(params.iterations, seed)),
        Algorithm::Exact => Box::new(exact::Exact::new()),
        Algorithm::Auto => Box::new(auto::Auto::new(*params, seed)),
        Algorithm::Coverage => Box::new(coverage::Coverage),
    }
}

/// Checks a request against a building and resolves its end points.
///
/// # Errors
/// One clear [`Error`] per problem: an unknown vertex ([`Error::InvalidRequest`] naming
/// it), a budget that is not a positive finite number, invalid kernel or model or
/// parameters, or an end that cannot be reached within the budget ([`Error::Unreachable`]
/// with the shortest distance).
pub fn validate(building: &Building, req: &PlanRequest) -> Result<(usize, usize)> {
    let start = building
        .require_vertex(&req.start)
        .map_err(|e| Error::InvalidRequest(format!("start: {e}")))?;
    let end = building
        .require_vertex(&req.end)
        .map_err(|e| Error::InvalidRequest(format!("end: {e}")))?;
    if !req.budget.is_finite() || req.budget <= 0.0 {
        return Err(Error::InvalidRequest(format!(
            "budget must be a positive finite number of metres, got {}",
            req.budget
        )));
    }
    let total = building.total_edge_length();
    if req.budget > MAX_BUDGET_FACTOR * total + BUDGET_EPS {
        return Err(Error::InvalidRequest(format!(
            "budget {} m is more than {MAX_BUDGET_FACTOR} times the {total:.1} m of edges of \
             {:?}: a walk that long only repeats what it has walked; ask for at most {:.1} m \
             (a budget of {total:.1} m or more lets a planner walk every edge)",
            req.budget,
            building.name,
            MAX_BUDGET_FACTOR * total
        )));
    }
    if req.memory_budget == 0 {
        return Err(Error::InvalidRequest(
            "memory budget must be a positive number of bytes".into(),
        ));
    }
    req.kernel.validate("kernel")?;
    req.model.validate()?;
    let p = &req.params;
    let bad = |m: String| Err(Error::InvalidRequest(m));
    if p.population < 2 {
        return bad(format!(
            "population must be at least 2, got {}",
            p.population
        ));
    }
    if p.tournament < 1 {
        return bad(format!(
            "tournament must be at least 1, got {}",
            p.tournament
        ));
    }
    if !(0.0..=1.0).contains(&p.mutation) {
        return bad(format!(
            "mutation must be a probability in [0, 1], got {}",
            p.mutation
        ));
    }
    if p.population > MAX_POPULATION {
        return bad(format!(
            "population must be at most {MAX_POPULATION}, got {}",
            p.population
        ));
    }
    if p.generations > MAX_GENERATIONS {
        return bad(format!(
            "generations must be at most {MAX_GENERATIONS}, got {}",
            p.generations
        ));
    }
    if p.depth > 5 {
        return bad(format!("depth must be at most 5, got {}", p.depth));
    }
    if !p.budget_step.is_finite() || p.budget_step < 0.0 {
        return bad(format!(
            "budget step must be a non-negative number of metres, got {}",
            p.budget_step
        ));
    }
    Ok((start, end))
}

/// Plans a walk.
///
/// # Arguments
/// * `building` - the building (shared with the engine).
/// * `req` - start, end, budget, model, kernel, algorithm, seed, time limit, parameters.
/// * `control` - cancel token and progress observer.
///
/// # Returns
/// The walk and its figures. With a time limit the best walk found so far is returned
/// when the limit is reached (`termination: time_limit`).
///
/// # Errors
/// See [`validate`]; [`Error::Cancelled`] when cancelled through `control`.
pub fn plan(building: Arc<Building>, req: &PlanRequest, control: &Control) -> Result<PlanResult> {
    plan_with_prior(building, req, &[], control)
}

/// Plans a walk whose utility is conditioned on the pilot data plus `prior`
/// observations: samples already collected (replanning a survey in progress) or the walks
/// of other surveyors (team planning). The utility reported is then `f_{D + prior}(P)`:
/// SPEC section 3 with `S = R(P) ∪ D ∪ prior`, so it counts what the prior already knows;
/// what the walk adds on top is that minus [`UtilityEngine::prior_utility`] of an engine
/// built with the same prior.
pub fn plan_with_prior(
    building: Arc<Building>,
    req: &PlanRequest,
    prior: &[crate::utility::Observation],
    control: &Control,
) -> Result<PlanResult> {
    // The clock starts now: set-up (shortest paths, the engine) counts against the limit.
    let started = Instant::now();
    let (start, end) = validate(&building, req)?;
    check_memory(&building, req, prior.len())?;
    let run = Run::starting_at(control.clone(), req.effective_time_limit(), started)
        .for_algorithm(req.algorithm);
    let metric = Arc::new(Metric::new(&building));
    let shortest = metric.dist(start, end);
    if !shortest.is_finite() || shortest > req.budget + BUDGET_EPS {
        return Err(Error::Unreachable {
            start: req.start.clone(),
            end: req.end.clone(),
            budget: req.budget,
            shortest,
        });
    }
    let engine = UtilityEngine::with_prior(building.clone(), req.kernel, req.model, prior)?;
    let problem = Problem {
        building: building.clone(),
        engine,
        metric,
        start,
        end,
        budget: req.budget,
    };
    let solver = solver_for(req.algorithm, req.seed, &req.params);
    let out = match solver.solve(&problem, &run) {
        Ok(mut out) => {
            if run.control.is_cancelled() {
                out.termination = Termination::Cancelled;
            }
            out
        }
        Err(Error::Cancelled) => best_so_far(&problem, &run, Termination::Cancelled)?,
        Err(e) => return Err(e),
    };
    finish(&problem, req, out, &run)
}

/// The run's best offered walk, else the shortest walk from the start to the end (the
/// answer of a plan stopped before any solver offered one).
fn best_so_far(problem: &Problem, run: &Run, termination: Termination) -> Result<Outcome> {
    if let Some((walk, utility)) = run.incumbent() {
        return Ok(Outcome::new(walk, utility, termination));
    }
    let walk = problem.shortest_walk();
    let utility = problem.utility(&walk)?;
    Ok(Outcome::new(walk, utility, termination))
}

/// Estimated peak working set of planning `req` on `building` with `prior` extra
/// observations, in bytes: the shortest-path table (12 bytes per vertex pair), the engine's
/// vertex covariance and its factor (two `|V| x |V|` matrices), the pilot rows, and per
/// planning thread one dense matrix of `[pilot + prior, samples of a full-budget walk,
/// vertices]` plus the incremental rows of such a walk.
pub fn estimate_memory(building: &Building, req: &PlanRequest, prior: usize) -> u64 {
    let nv = building.len() as f64;
    let nd = (building.pilot.len() + prior) as f64;
    let budget = if req.budget.is_finite() {
        req.budget
    } else {
        0.0
    };
    let ns = budget / req.model.spacing().max(1e-3) + 2.0;
    let metric = 12.0 * nv * nv;
    let engine = 8.0 * (2.0 * nv * nv + nd * nd + 2.0 * nd * nv);
    let n = nd + ns + nv + 16.0;
    let threads = rayon::current_num_threads().max(1) as f64;
    // The large-building search (auto and coverage beyond `auto::LARGE_VERTICES`) only
    // evaluates whole walks; the other planners also grow walks incrementally (rows of
    // `L` and `W` per sample).
    let whole_walks = matches!(req.algorithm, Algorithm::Auto | Algorithm::Coverage)
        && building.len() > auto::LARGE_VERTICES;
    let incremental = if whole_walks {
        0.0
    } else {
        2.0 * ns * (nd + ns + nv)
    };
    // Branch and bound keeps a saved posterior (`|V| x |V|`) per level of its depth-first
    // search, one level per edge of the deepest walk.
    let min_edge = building
        .edges
        .iter()
        .map(|e| e.length)
        .fold(f64::INFINITY, f64::min)
        .max(1e-3);
    let marks = if req.algorithm == Algorithm::Exact {
        (budget / min_edge).min(1e6) * nv * nv
    } else {
        0.0
    };
    let per_thread = 8.0 * (n * n + incremental + marks);
    // A fixed allowance for the process, the building and the search's own tables.
    let fixed = 16.0 * 1024.0 * 1024.0;
    (metric + engine + threads * per_thread + fixed).min(u64::MAX as f64) as u64
}

/// Refuses a request whose estimated working set exceeds its memory budget.
fn check_memory(building: &Building, req: &PlanRequest, prior: usize) -> Result<()> {
    let need = estimate_memory(building, req, prior);
    if need <= req.memory_budget {
        return Ok(());
    }
    let mib = |b: u64| b.div_ceil(1 << 20);
    Err(Error::InvalidRequest(format!(
        "planning on {:?} ({} vertices, budget {} m) needs about {} MiB, more than the memory \
         budget of {} MiB: the vertex covariance and the shortest-path table grow with the \
         square of the vertex count and a walk's matrix with its samples; plan one floor or \
         part of the building, use a shorter budget or a sparser sample interval, or raise \
         the memory budget (--memory-budget MIB, PlanRequest.memory_budget) if the device has \
         {} MiB to spare",
        building.name,
        building.len(),
        req.budget,
        mib(need),
        mib(req.memory_budget),
        mib(need)
    )))
}

/// Checks an outcome and dresses it as a result.
fn finish(problem: &Problem, req: &PlanRequest, out: Outcome, run: &Run) -> Result<PlanResult> {
    problem.check(&out.walk).map_err(|e| {
        Error::Numerical(format!(
            "internal error: {} returned an infeasible walk: {e}",
            req.algorithm
        ))
    })?;
    let b = &problem.building;
    let samples = sample_walk(b, &out.walk, &req.model, &req.kernel)?.len();
    // The last report is the result itself, so that "best so far" ends at what is returned.
    problem.offer(run, &out.walk, out.utility);
    run.report(req.algorithm, 1.0, Some(out.utility), "done".into());
    Ok(PlanResult {
        algorithm: req.algorithm,
        walk: b.walk_ids(&out.walk),
        length_m: problem.length(&out.walk),
        budget_m: req.budget,
        samples,
        utility_nats: out.utility,
        elapsed_ms: run.elapsed().as_millis() as u64,
        seed: req.seed,
        kernel: req.kernel,
        optimal: out.optimal,
        nodes: out.nodes,
        termination: out.termination,
        walk_indices: out.walk,
    })
}

/// Keeps the better of two (walk, utility) pairs; ties go to the shorter, then the
/// lexicographically smaller walk, so that parallel searches stay deterministic.
pub(crate) fn better(a: (&[usize], f64), b: (&[usize], f64)) -> bool {
    // true if a is better than b
    if a.1 != b.1 {
        return a.1 > b.1;
    }
    if a.0.len() != b.0.len() {
        return a.0.len() < b.0.len();
    }
    a.0 < b.0
}
