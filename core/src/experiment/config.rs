//! What an experiment runs: algorithms, budgets, runs, the model and the limits.

use std::time::Duration;

use serde::Serialize;

use crate::eval::EvalOptions;
use crate::gp::Kernel;
use crate::plan::{Algorithm, Params};
use crate::surveyor::Surveyor;
use crate::{Error, Result};

/// What to run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExperimentConfig {
    /// Start vertex id.
    pub start: String,
    /// End vertex id.
    pub end: String,
    /// Budgets, metres, in the order given.
    pub budgets: Vec<f64>,
    /// Algorithms, in the order given (also the order of the chart legends).
    pub algorithms: Vec<Algorithm>,
    /// Runs per algorithm and budget.
    pub runs: usize,
    pub kernel: Kernel,
    pub model: Surveyor,
    /// Master seed; the seeds of every run derive from it.
    pub seed: u64,
    /// Time limit of every plan (`None`: the algorithm's default, 2 s for `auto`).
    #[serde(serialize_with = "ser_opt_secs")]
    pub time_limit: Option<Duration>,
    /// Per-algorithm time limits, overriding `time_limit` (the first entry of an
    /// algorithm wins).
    #[serde(serialize_with = "ser_limits")]
    pub time_limits: Vec<(Algorithm, Duration)>,
    /// Planner parameters (genetic, recursive greedy, ERO).
    pub params: Params,
    /// Localization evaluation options.
    pub eval: EvalOptions,
    /// Plan seed-independent algorithms in every run instead of reusing the first walk.
    pub replan_deterministic: bool,
}

fn ser_opt_secs<S: serde::Serializer>(
    d: &Option<Duration>,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    match d {
        Some(d) => s.serialize_some(&d.as_secs_f64()),
        None => s.serialize_none(),
    }
}

fn ser_limits<S: serde::Serializer>(
    m: &[(Algorithm, Duration)],
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = s.serialize_map(Some(m.len()))?;
    for (a, d) in m {
        map.serialize_entry(a.name(), &d.as_secs_f64())?;
    }
    map.end()
}

impl ExperimentConfig {
    /// A configuration with the robot model, seed 1, no time limits, default parameters
    /// (the paper's GA: population 200, 5 generations, tournament 10, mutation 0.9; ERO
    /// 2,000 iterations) and default evaluation options.
    pub fn new(
        start: &str,
        end: &str,
        budgets: Vec<f64>,
        algorithms: Vec<Algorithm>,
        runs: usize,
        kernel: Kernel,
    ) -> Self {
        ExperimentConfig {
            start: start.into(),
            end: end.into(),
            budgets,
            algorithms,
            runs,
            kernel,
            model: Surveyor::default(),
            seed: 1,
            time_limit: None,
            time_limits: Vec::new(),
            params: Params {
                iterations: 2000,
                ..Params::default()
            },
            eval: EvalOptions::default(),
            replan_deterministic: false,
        }
    }

    /// The time limit of `algorithm`'s plans (its override, else the common one).
    pub fn time_limit_for(&self, algorithm: Algorithm) -> Option<Duration> {
        self.time_limits
            .iter()
            .find(|(a, _)| *a == algorithm)
            .map(|(_, d)| *d)
            .or(self.time_limit)
    }

    /// Checks the lists and the run count; the error names the bad value.
    pub(super) fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidRequest(m));
        if self.budgets.is_empty() {
            return bad("experiment: give at least one budget".into());
        }
        if let Some(b) = self.budgets.iter().find(|b| !b.is_finite() || **b <= 0.0) {
            return bad(format!(
                "experiment: budgets must be positive numbers of metres, got {b}"
            ));
        }
        if self.algorithms.is_empty() {
            return bad("experiment: give at least one algorithm".into());
        }
        for (i, a) in self.algorithms.iter().enumerate() {
            if self.algorithms[..i].contains(a) {
                return bad(format!("experiment: algorithm {a} is listed twice"));
            }
        }
        for (i, b) in self.budgets.iter().enumerate() {
            if self.budgets[..i].contains(b) {
                return bad(format!("experiment: budget {b} is listed twice"));
            }
        }
        if self.runs == 0 {
            return bad("experiment: runs must be at least 1".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_rejects_empty_and_duplicate_lists() {
        let k = Kernel::new(50.0, 8.0, 4.0);
        let ok = ExperimentConfig::new("a", "a", vec![10.0], vec![Algorithm::Greedy], 1, k);
        assert!(ok.validate().is_ok());
        let mut c = ok.clone();
        c.budgets.clear();
        assert!(c.validate().is_err());
        let mut c = ok.clone();
        c.budgets = vec![10.0, -1.0];
        assert!(c.validate().is_err());
        let mut c = ok.clone();
        c.algorithms = vec![Algorithm::Greedy, Algorithm::Greedy];
        assert!(c.validate().is_err());
        let mut c = ok.clone();
        c.runs = 0;
        assert!(c.validate().is_err());
    }
}
