//! What a caller asks for and gets back: the algorithms, their parameters, a request
//! ([`PlanRequest`], or its route-free part [`PlanSettings`]), and the result
//! ([`PlanResult`], [`Termination`]).

use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::gp::Kernel;
use crate::surveyor::Surveyor;
use crate::{Error, Result};

/// The planning algorithms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Algorithm {
    /// Ours: greedy, then a genetic search seeded with it, then local search, and an
    /// exact search when the instance is small enough (see [`auto`](super::auto)).
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
    /// baseline a surveyor without Trailprint achieves, see [`coverage`](super::coverage)).
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

/// Where a saved walk came from: one of the planners, the session's own replanner, or a
/// caller that handed the session a walk it did not plan. Stored and exchanged as its
/// name (`auto`, `greedy`, ..., `session-greedy`, `given`), the `algorithm` of a plan row
/// and of a bundle's plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlanOrigin {
    /// Planned by [`Algorithm`].
    Planner(Algorithm),
    /// Replanned mid-session by `session::GreedyReplanner`.
    SessionGreedy,
    /// A walk given to the session, not planned.
    Given,
}

impl PlanOrigin {
    /// The stored name.
    pub fn name(self) -> &'static str {
        match self {
            PlanOrigin::Planner(a) => a.name(),
            PlanOrigin::SessionGreedy => "session-greedy",
            PlanOrigin::Given => "given",
        }
    }

    /// Parses a name as written by [`name`](Self::name).
    pub fn from_name(s: &str) -> Result<Self> {
        match s {
            "session-greedy" => Ok(PlanOrigin::SessionGreedy),
            "given" => Ok(PlanOrigin::Given),
            _ => Algorithm::from_name(s)
                .map(PlanOrigin::Planner)
                .map_err(|_| {
                    Error::InvalidRequest(format!(
                        "unknown plan origin {s:?}, expected an algorithm (auto, greedy, genetic, \
                     recursive-greedy, ero, exact, coverage), session-greedy or given"
                    ))
                }),
        }
    }
}

impl From<Algorithm> for PlanOrigin {
    fn from(a: Algorithm) -> Self {
        PlanOrigin::Planner(a)
    }
}

impl std::fmt::Display for PlanOrigin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl PartialEq<&str> for PlanOrigin {
    fn eq(&self, other: &&str) -> bool {
        self.name() == *other
    }
}

impl Serialize for PlanOrigin {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for PlanOrigin {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        PlanOrigin::from_name(&s).map_err(serde::de::Error::custom)
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

/// What to plan: the route, the budget and the kernel, and how to plan it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanRequest {
    /// Start vertex id `v_s`.
    pub start: String,
    /// End vertex id `v_t` (may equal the start: a closed walk).
    pub end: String,
    /// Budget `B`, metres.
    pub budget: f64,
    /// Kernel hyperparameters.
    pub kernel: Kernel,
    /// Who walks, the algorithm and its limits. In JSON its fields stand beside the
    /// others (`{"start": .., "algorithm": "auto", "seed": 3, ..}`), as before it was a
    /// struct of its own.
    #[serde(flatten)]
    pub settings: PlanSettings,
}

/// How to plan, apart from where and with which kernel: what a team's members share, and
/// what a caller that lets the store choose the kernel
/// ([`Store::plan_and_save`](crate::store::Store::plan_and_save)) passes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlanSettings {
    /// Who walks.
    #[serde(default)]
    pub model: Surveyor,
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

impl PlanSettings {
    /// One run of a study that varies the algorithm and the seed over a fixed surveyor and
    /// tuning (the paper's experiment, the planner benchmark); the memory budget is the
    /// default.
    pub fn for_run(
        model: Surveyor,
        params: Params,
        algorithm: Algorithm,
        seed: u64,
        time_limit: Option<Duration>,
    ) -> Self {
        PlanSettings {
            model,
            algorithm,
            seed,
            time_limit,
            params,
            ..PlanSettings::default()
        }
    }
}

impl Default for PlanSettings {
    /// The defaults of [`PlanRequest::new`]: `auto`, robot model, seed 0.
    fn default() -> Self {
        PlanSettings {
            model: Surveyor::default(),
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
            kernel,
            settings: *s,
        }
    }

    /// The time limit in effect (the request's, else the algorithm's default).
    pub fn effective_time_limit(&self) -> Option<Duration> {
        self.settings
            .time_limit
            .or_else(|| self.settings.algorithm.default_time_limit())
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A request's JSON keeps the settings beside the route (the form callers have always
    /// written), reads back equal, and takes the defaults for what it leaves out.
    #[test]
    fn request_json_is_flat_and_round_trips() {
        let mut req = PlanRequest::new("a", "b", 12.5, Kernel::new(40.0, 6.0, 4.0));
        req.settings.seed = 9;
        req.settings.algorithm = Algorithm::Genetic;
        req.settings.time_limit = Some(Duration::from_millis(1500));
        let v = serde_json::to_value(&req).expect("serialise");
        assert!(v.get("settings").is_none(), "{v}");
        assert_eq!(v["seed"], 9);
        assert_eq!(v["algorithm"], "genetic");
        assert_eq!(v["time_limit"], 1.5);
        let back: PlanRequest = serde_json::from_value(v).expect("read back");
        assert_eq!(back, req);

        let short: PlanRequest = serde_json::from_str(
            r#"{"start": "a", "end": "a", "budget": 3, "kernel": {"sf2": 40, "ell": 6, "sn2": 4}}"#,
        )
        .expect("defaults");
        assert_eq!(short.settings, PlanSettings::default());
        let bad = serde_json::from_str::<PlanRequest>(
            r#"{"start": "a", "end": "a", "budget": 3, "kernel": {"sf2": 40, "ell": 6, "sn2": 4},
                "time_limit": -1}"#,
        )
        .expect_err("negative limit");
        assert!(
            bad.to_string()
                .contains("time_limit must be a non-negative"),
            "{bad}"
        );
    }
}
