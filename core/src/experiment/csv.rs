//! The CSV files of an experiment; run times come last so that a comparison can drop them.

use std::fmt::Write as _;

use super::Experiment;
use crate::plan::Termination;
use crate::store::csv_field;

/// An optional number with `digits` decimals; empty when `None`.
fn opt(v: Option<f64>, digits: usize) -> String {
    v.map(|x| format!("{x:.digits$}")).unwrap_or_default()
}

/// The CSV name of a termination.
fn termination_name(t: Termination) -> &'static str {
    t.name()
}

/// The files [`Experiment::write`] writes, in order.
pub const FILES: [&str; 9] = [
    "runs.csv",
    "summary.csv",
    "correlation.csv",
    "baselines.csv",
    "experiment.json",
    "utility.svg",
    "error.svg",
    "runtime.svg",
    "scatter.svg",
];

/// Header of `runs.csv`.
pub const RUNS_HEADER: &str = "algorithm,budget_m,run,plan_seed,eval_seed,length_m,samples,utility_nats,mean_error_m,median_error_m,p90_error_m,termination,reused,walk,knn_mean_error_m,elapsed_ms";
/// Header of `summary.csv`.
pub const SUMMARY_HEADER: &str = "algorithm,budget_m,runs,utility_mean,utility_sd,utility_min,utility_max,length_mean_m,error_mean_m,error_sd_m,median_error_mean_m,p90_error_mean_m,knn_error_mean_m,time_limited,elapsed_mean_ms,elapsed_max_ms";
/// Header of `correlation.csv`.
pub const CORRELATION_HEADER: &str = "scope,n,pearson_r";
/// Header of `baselines.csv`.
pub const BASELINES_HEADER: &str =
    "name,samples,mean_error_m,median_error_m,p90_error_m,knn_mean_error_m";

impl Experiment {
    /// One row per run ([`RUNS_HEADER`]); the walk's ids are separated by spaces.
    pub fn runs_csv(&self) -> String {
        let mut s = format!("{RUNS_HEADER}\n");
        for r in &self.runs {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{:.3},{},{:.6},{:.4},{:.4},{:.4},{},{},{},{:.4},{}",
                r.algorithm,
                r.budget_m,
                r.run,
                r.plan_seed,
                r.eval_seed,
                r.length_m,
                r.samples,
                r.utility_nats,
                r.mean_error_m,
                r.median_error_m,
                r.p90_error_m,
                termination_name(r.termination),
                r.reused,
                csv_field(&r.walk.join(" ")),
                r.knn_mean_error_m,
                r.elapsed_ms
            );
        }
        s
    }

    /// One row per algorithm and budget ([`SUMMARY_HEADER`]).
    pub fn summary_csv(&self) -> String {
        let mut s = format!("{SUMMARY_HEADER}\n");
        for r in &self.summary {
            let _ = writeln!(
                s,
                "{},{},{},{:.6},{:.6},{:.6},{:.6},{:.3},{:.4},{:.4},{:.4},{:.4},{:.4},{},{:.1},{}",
                r.algorithm,
                r.budget_m,
                r.runs,
                r.utility_mean,
                r.utility_sd,
                r.utility_min,
                r.utility_max,
                r.length_mean_m,
                r.error_mean_m,
                r.error_sd_m,
                r.median_error_mean_m,
                r.p90_error_mean_m,
                r.knn_error_mean_m,
                r.time_limited,
                r.elapsed_mean_ms,
                r.elapsed_max_ms
            );
        }
        s
    }

    /// The correlations ([`CORRELATION_HEADER`]); an undefined one is an empty field.
    pub fn correlation_csv(&self) -> String {
        let mut s = format!("{CORRELATION_HEADER}\n");
        for c in &self.correlations {
            let _ = writeln!(s, "{},{},{}", c.scope, c.n, opt(c.pearson_r, 4));
        }
        s
    }

    /// The reference errors ([`BASELINES_HEADER`]).
    pub fn baselines_csv(&self) -> String {
        let mut s = format!("{BASELINES_HEADER}\n");
        for b in &self.baselines {
            let _ = writeln!(
                s,
                "{},{},{:.4},{:.4},{:.4},{:.4}",
                b.name,
                b.samples,
                b.mean_error_m,
                b.median_error_m,
                b.p90_error_m,
                b.knn_mean_error_m
            );
        }
        s
    }
}
