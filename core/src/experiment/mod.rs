//! The paper's evaluation (Wei, Frincu, Zheng, section V): for every algorithm and budget,
//! plan several times, score each walk by its utility and by the localization error of
//! the fingerprint map built from its samples (SPEC section 5), and relate the two.
//!
//! # What one run is
//! Run `r` (0-based) of every algorithm and budget uses the planner seed
//! [`plan_seed`]`(seed, r)` and the evaluation seed [`eval_seed`]`(seed, r)`: all
//! algorithms of a run see the same noise in the drawn fingerprints (common random
//! numbers), so that differences between algorithms are not differences of luck.
//!
//! Greedy, recursive greedy and the exact search ignore the seed: unless
//! [`ExperimentConfig::replan_deterministic`] is set, they plan once per budget and the
//! later runs reuse that walk (and its run time), marked `reused` in the CSV; the
//! evaluation seed still changes from run to run.
//!
//! # Output
//! [`Experiment`] holds one [`RunRecord`] per run, a [`SummaryRow`] per algorithm and
//! budget, the Pearson correlations of utility against localization error (over all runs
//! and per budget) and two reference errors ([`Baseline`]: the pilot data alone, and every
//! position of the dense survey). [`Experiment::write`] writes them as CSV plus four SVG
//! charts ([`chart`]).
//!
//! Everything but the run times is a function of the building, the configuration and the
//! seed; the run-time columns come last in the CSV files so that a comparison can drop
//! them. A plan stopped by its time limit also depends on the machine's speed.
//!
//! # Layout
//! `config` (what to run), `seeds` (the seeds of every run), `run` (the run loop and the
//! reference errors), `stats` (means, correlations), `csv` (the CSV files), `figures` (the
//! four charts, drawn by [`chart`]); this file holds the output types and writes them.

pub mod chart;
mod config;
mod csv;
mod figures;
mod run;
mod seeds;
mod stats;

use std::path::Path;

use serde::Serialize;

use crate::plan::{Algorithm, Termination};
use crate::{Error, Result};

pub use config::ExperimentConfig;
pub use csv::{BASELINES_HEADER, CORRELATION_HEADER, FILES, RUNS_HEADER, SUMMARY_HEADER};
pub use run::run_experiment;
pub use seeds::{eval_seed, plan_seed};
pub use stats::pearson;

/// One plan and its evaluation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunRecord {
    pub algorithm: Algorithm,
    pub budget_m: f64,
    /// 0-based run index.
    pub run: usize,
    pub plan_seed: u64,
    pub eval_seed: u64,
    pub length_m: f64,
    pub samples: usize,
    pub utility_nats: f64,
    pub mean_error_m: f64,
    pub median_error_m: f64,
    pub p90_error_m: f64,
    /// Mean localization error of the same fingerprints located by weighted kNN (k = 3)
    /// instead of the GP likelihood, metres.
    pub knn_mean_error_m: f64,
    pub termination: Termination,
    /// Whether the walk was reused from run 0 (seed-independent algorithms).
    pub reused: bool,
    /// Vertex ids of the walk.
    pub walk: Vec<String>,
    /// Planning time, milliseconds (of run 0 when reused).
    pub elapsed_ms: u64,
}

/// Means over the runs of one algorithm and budget.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SummaryRow {
    pub algorithm: Algorithm,
    pub budget_m: f64,
    pub runs: usize,
    pub utility_mean: f64,
    /// Sample standard deviation (0 for one run).
    pub utility_sd: f64,
    pub utility_min: f64,
    pub utility_max: f64,
    pub length_mean_m: f64,
    pub error_mean_m: f64,
    pub error_sd_m: f64,
    pub median_error_mean_m: f64,
    pub p90_error_mean_m: f64,
    /// Mean over the runs of the kNN (k = 3) mean error, metres.
    pub knn_error_mean_m: f64,
    /// Runs stopped by the time limit.
    pub time_limited: usize,
    pub elapsed_mean_ms: f64,
    pub elapsed_max_ms: u64,
}

/// Pearson correlation of utility and mean localization error over a set of runs: all
/// runs, the runs of each budget, and the runs of each algorithm (in that order).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Correlation {
    /// `all`, `budget=<B>` (all algorithms at one budget) or `algorithm=<A>` (one
    /// algorithm over all budgets).
    pub scope: String,
    pub n: usize,
    /// `None` when undefined (fewer than two runs, or no spread in one of the two).
    pub pearson_r: Option<f64>,
}

/// A reference localization error, averaged over the runs' evaluation seeds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Baseline {
    /// `pilot-only` or `dense-survey`.
    pub name: String,
    /// Sample positions used besides the pilot data.
    pub samples: usize,
    pub mean_error_m: f64,
    pub median_error_m: f64,
    pub p90_error_m: f64,
    /// Mean error with weighted kNN (k = 3) instead of the GP likelihood, metres.
    pub knn_mean_error_m: f64,
}

/// Everything an experiment produced.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Experiment {
    pub building: String,
    pub config: ExperimentConfig,
    pub runs: Vec<RunRecord>,
    pub summary: Vec<SummaryRow>,
    pub correlations: Vec<Correlation>,
    pub baselines: Vec<Baseline>,
}
impl Experiment {
    /// The overall correlation (all runs).
    pub fn overall_correlation(&self) -> Option<f64> {
        self.correlations.first().and_then(|c| c.pearson_r)
    }

    /// The reference error called `name`.
    fn baseline(&self, name: &str) -> Option<&Baseline> {
        self.baselines.iter().find(|b| b.name == name)
    }

    /// The configuration, kernel and results as pretty JSON.
    pub fn to_json(&self) -> String {
        // Plain data with string keys: serialising cannot fail; an empty object if it did.
        serde_json::to_string_pretty(self).unwrap_or_else(|_| "{}".into())
    }

    /// Writes [`FILES`] into `dir` (created if missing).
    pub fn write(&self, dir: &Path) -> Result<()> {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let contents = [
            self.runs_csv(),
            self.summary_csv(),
            self.correlation_csv(),
            self.baselines_csv(),
            self.to_json() + "\n",
            self.utility_chart(),
            self.error_chart(),
            self.runtime_chart(),
            self.scatter_chart(),
        ];
        for (name, text) in FILES.iter().zip(contents) {
            let path = dir.join(name);
            std::fs::write(&path, text).map_err(|e| Error::io(&path, e))?;
        }
        Ok(())
    }
}
