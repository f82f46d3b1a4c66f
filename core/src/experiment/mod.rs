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

pub mod chart;

use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use serde::Serialize;

use crate::building::Building;
use crate::eval::{EvalOptions, Evaluator, LocalizationReport, Localizer};
use crate::gp::Kernel;
use crate::plan::{Algorithm, Control, Params, PlanRequest, PlanResult, Termination, plan};
use crate::samples::{SurveyorModel, sample_walk};
use crate::{Error, Result};

use chart::{LineChart, LinePoint, RefLine, ScatterChart, Series};

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
    pub model: SurveyorModel,
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
            model: SurveyorModel::default(),
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

    fn validate(&self) -> Result<()> {
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

/// SplitMix64 finaliser: a bijective mix of 64 bits.
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A seed for run `run` on stream `stream`, from the master seed.
fn derive_seed(seed: u64, run: usize, stream: u64) -> u64 {
    splitmix64(splitmix64(splitmix64(seed) ^ stream) ^ run as u64)
}

/// The planner seed of run `run` (0-based).
pub fn plan_seed(seed: u64, run: usize) -> u64 {
    derive_seed(seed, run, 0x706c_616e) // "plan"
}

/// The evaluation seed of run `run` (0-based).
pub fn eval_seed(seed: u64, run: usize) -> u64 {
    derive_seed(seed, run, 0x6576_616c) // "eval"
}

/// Whether an algorithm's plan depends on the seed.
fn seeded(a: Algorithm) -> bool {
    matches!(a, Algorithm::Genetic | Algorithm::Ero | Algorithm::Auto)
}

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

/// Pearson's correlation coefficient; `None` for fewer than two pairs or zero variance.
pub fn pearson(x: &[f64], y: &[f64]) -> Option<f64> {
    let n = x.len().min(y.len());
    if n < 2 {
        return None;
    }
    let mx = x[..n].iter().sum::<f64>() / n as f64;
    let my = y[..n].iter().sum::<f64>() / n as f64;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x[..n].iter().zip(&y[..n]) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    // Relative threshold: a spread lost in rounding is no spread.
    let tiny = |s: f64, m: f64| s <= 1e-24 * (n as f64) * m.abs().max(1.0).powi(2);
    if tiny(sxx, mx) || tiny(syy, my) {
        return None;
    }
    Some((sxy / (sxx.sqrt() * syy.sqrt())).clamp(-1.0, 1.0))
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn sample_sd(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    let m = mean(v);
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// Runs the experiment.
///
/// # Arguments
/// * `building` - needs `dense_survey` (the world model) and `test_points`.
/// * `config` - what to run.
/// * `control` - cancel token (checked between and inside plans).
/// * `on_run` - called after every run, in order (progress output).
///
/// # Errors
/// An invalid configuration, a building without dense survey or test points, a budget
/// too small to reach the end ([`Error::Unreachable`]), or [`Error::Cancelled`].
pub fn run_experiment(
    building: Arc<Building>,
    config: &ExperimentConfig,
    control: &Control,
    on_run: &mut dyn FnMut(&RunRecord),
) -> Result<Experiment> {
    config.validate()?;
    let evaluator = Evaluator::new(&building, &config.kernel, config.eval)?;
    let mut runs = Vec::new();
    for &budget in &config.budgets {
        for &algorithm in &config.algorithms {
            let mut first: Option<(PlanResult, usize)> = None;
            for run in 0..config.runs {
                if control.is_cancelled() {
                    return Err(Error::Cancelled);
                }
                let (ps, es) = (plan_seed(config.seed, run), eval_seed(config.seed, run));
                let reuse = !config.replan_deterministic && !seeded(algorithm);
                let (result, samples, reused) = match &first {
                    Some((r, n)) if reuse => (r.clone(), *n, true),
                    _ => {
                        let req = PlanRequest {
                            start: config.start.clone(),
                            end: config.end.clone(),
                            budget,
                            model: config.model,
                            kernel: config.kernel,
                            algorithm,
                            seed: ps,
                            time_limit: config.time_limit_for(algorithm),
                            params: config.params,
                            memory_budget: crate::plan::DEFAULT_MEMORY_BUDGET,
                        };
                        let r = plan(building.clone(), &req, control)?;
                        let n = r.samples;
                        if first.is_none() {
                            first = Some((r.clone(), n));
                        }
                        (r, n, false)
                    }
                };
                let smp = sample_walk(
                    &building,
                    &result.walk_indices,
                    &config.model,
                    &config.kernel,
                )?;
                let rep: LocalizationReport = evaluator.evaluate_samples(&smp, es)?;
                let knn = evaluator.evaluate_samples_with(&smp, es, Localizer::Knn { k: 3 })?;
                let rec = RunRecord {
                    algorithm,
                    budget_m: budget,
                    run,
                    plan_seed: if reused { result.seed } else { ps },
                    eval_seed: es,
                    length_m: result.length_m + 0.0,
                    samples,
                    utility_nats: result.utility_nats,
                    mean_error_m: rep.mean_error_m,
                    median_error_m: rep.median_error_m,
                    p90_error_m: rep.p90_error_m,
                    knn_mean_error_m: knn.mean_error_m,
                    termination: result.termination,
                    reused,
                    walk: result.walk.clone(),
                    elapsed_ms: result.elapsed_ms,
                };
                on_run(&rec);
                runs.push(rec);
            }
        }
    }

    let summary = summarise(config, &runs);
    let correlations = correlations(config, &runs);
    let baselines = baselines(&building, config, &evaluator)?;
    Ok(Experiment {
        building: building.name.clone(),
        config: config.clone(),
        runs,
        summary,
        correlations,
        baselines,
    })
}

fn summarise(config: &ExperimentConfig, runs: &[RunRecord]) -> Vec<SummaryRow> {
    let mut out = Vec::new();
    for &algorithm in &config.algorithms {
        for &budget in &config.budgets {
            let rs: Vec<&RunRecord> = runs
                .iter()
                .filter(|r| r.algorithm == algorithm && r.budget_m == budget)
                .collect();
            if rs.is_empty() {
                continue;
            }
            let u: Vec<f64> = rs.iter().map(|r| r.utility_nats).collect();
            let e: Vec<f64> = rs.iter().map(|r| r.mean_error_m).collect();
            let col = |f: fn(&RunRecord) -> f64| mean(&rs.iter().map(|r| f(r)).collect::<Vec<_>>());
            out.push(SummaryRow {
                algorithm,
                budget_m: budget,
                runs: rs.len(),
                utility_mean: mean(&u),
                utility_sd: sample_sd(&u),
                utility_min: u.iter().copied().fold(f64::INFINITY, f64::min),
                utility_max: u.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                length_mean_m: col(|r| r.length_m),
                error_mean_m: mean(&e),
                error_sd_m: sample_sd(&e),
                median_error_mean_m: col(|r| r.median_error_m),
                p90_error_mean_m: col(|r| r.p90_error_m),
                knn_error_mean_m: col(|r| r.knn_mean_error_m),
                time_limited: rs
                    .iter()
                    .filter(|r| r.termination == Termination::TimeLimit)
                    .count(),
                elapsed_mean_ms: col(|r| r.elapsed_ms as f64),
                elapsed_max_ms: rs.iter().map(|r| r.elapsed_ms).max().unwrap_or(0),
            });
        }
    }
    out
}

fn correlations(config: &ExperimentConfig, runs: &[RunRecord]) -> Vec<Correlation> {
    let corr = |scope: String, rs: Vec<&RunRecord>| {
        let u: Vec<f64> = rs.iter().map(|r| r.utility_nats).collect();
        let e: Vec<f64> = rs.iter().map(|r| r.mean_error_m).collect();
        Correlation {
            scope,
            n: rs.len(),
            pearson_r: pearson(&u, &e),
        }
    };
    let mut out = vec![corr("all".into(), runs.iter().collect())];
    for &b in &config.budgets {
        out.push(corr(
            format!("budget={b}"),
            runs.iter().filter(|r| r.budget_m == b).collect(),
        ));
    }
    for &a in &config.algorithms {
        out.push(corr(
            format!("algorithm={a}"),
            runs.iter().filter(|r| r.algorithm == a).collect(),
        ));
    }
    out
}

fn baselines(
    building: &Building,
    config: &ExperimentConfig,
    evaluator: &Evaluator,
) -> Result<Vec<Baseline>> {
    let dense: Vec<_> = building.dense_survey.iter().map(|f| f.point()).collect();
    let mut out = Vec::new();
    for (name, points) in [("pilot-only", Vec::new()), ("dense-survey", dense)] {
        let mut reps = Vec::new();
        let mut knn = Vec::new();
        for run in 0..config.runs {
            let es = eval_seed(config.seed, run);
            reps.push(evaluator.evaluate(&points, es)?);
            knn.push(
                evaluator
                    .evaluate_with(&points, es, Localizer::Knn { k: 3 })?
                    .mean_error_m,
            );
        }
        let col = |f: fn(&LocalizationReport) -> f64| mean(&reps.iter().map(f).collect::<Vec<_>>());
        out.push(Baseline {
            name: name.into(),
            samples: points.len(),
            mean_error_m: col(|r| r.mean_error_m),
            median_error_m: col(|r| r.median_error_m),
            p90_error_m: col(|r| r.p90_error_m),
            knn_mean_error_m: mean(&knn),
        });
    }
    Ok(out)
}

/// A CSV field: quoted when it holds a comma, a quote or a line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map(|x| format!("{x:.digits$}")).unwrap_or_default()
}

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

    /// The overall correlation (all runs).
    pub fn overall_correlation(&self) -> Option<f64> {
        self.correlations.first().and_then(|c| c.pearson_r)
    }

    fn baseline(&self, name: &str) -> Option<&Baseline> {
        self.baselines.iter().find(|b| b.name == name)
    }

    fn line_series(&self, f: impl Fn(&SummaryRow) -> LinePoint) -> Vec<Series<LinePoint>> {
        self.config
            .algorithms
            .iter()
            .enumerate()
            .map(|(i, a)| Series {
                name: a.name().to_string(),
                colour: i,
                points: self
                    .summary
                    .iter()
                    .filter(|r| r.algorithm == *a)
                    .map(&f)
                    .collect(),
            })
            .collect()
    }

    /// Mean utility against budget, bars from the smallest to the largest run.
    pub fn utility_chart(&self) -> String {
        LineChart {
            title: format!("{}: utility vs budget", self.building),
            x_label: "budget (m)".into(),
            y_label: "utility f_D(P) (nats), mean and range over runs".into(),
            series: self.line_series(|r| LinePoint {
                x: r.budget_m,
                y: r.utility_mean,
                bar: Some((r.utility_min, r.utility_max)),
            }),
            ref_lines: Vec::new(),
            log_y: false,
            x_ticks: self.config.budgets.clone(),
        }
        .to_svg()
    }

    /// Mean localization error against budget (bars: one standard deviation over runs),
    /// with the pilot-only and dense-survey errors as dashed lines.
    pub fn error_chart(&self) -> String {
        let mut refs = Vec::new();
        if let Some(b) = self.baseline("pilot-only") {
            refs.push(RefLine {
                y: b.mean_error_m,
                label: format!("pilot only: {:.2} m", b.mean_error_m),
            });
        }
        if let Some(b) = self.baseline("dense-survey") {
            refs.push(RefLine {
                y: b.mean_error_m,
                label: format!("all {} dense positions: {:.2} m", b.samples, b.mean_error_m),
            });
        }
        LineChart {
            title: format!("{}: localization error vs budget", self.building),
            x_label: "budget (m)".into(),
            y_label: "mean localization error (m), ±1 sd over runs".into(),
            series: self.line_series(|r| LinePoint {
                x: r.budget_m,
                y: r.error_mean_m,
                bar: Some((r.error_mean_m - r.error_sd_m, r.error_mean_m + r.error_sd_m)),
            }),
            ref_lines: refs,
            log_y: false,
            x_ticks: self.config.budgets.clone(),
        }
        .to_svg()
    }

    /// Mean planning time against budget, seconds, logarithmic axis.
    pub fn runtime_chart(&self) -> String {
        LineChart {
            title: format!("{}: planning time vs budget", self.building),
            x_label: "budget (m)".into(),
            y_label: "planning time (s, log scale), mean over runs".into(),
            series: self.line_series(|r| LinePoint {
                // A plan under a millisecond shows at 1 ms rather than vanish off the
                // log axis.
                x: r.budget_m,
                y: (r.elapsed_mean_ms / 1000.0).max(1e-3),
                bar: None,
            }),
            ref_lines: Vec::new(),
            log_y: true,
            x_ticks: self.config.budgets.clone(),
        }
        .to_svg()
    }

    /// Utility against localization error, one point per run, with the correlations in
    /// the title.
    pub fn scatter_chart(&self) -> String {
        let r = |v: Option<f64>| v.map_or("undefined".to_string(), |x| format!("{x:.2}"));
        let per_budget: Vec<String> = self
            .correlations
            .iter()
            .filter_map(|c| {
                let b = c.scope.strip_prefix("budget=")?;
                Some(format!("{b} m: {}", r(c.pearson_r)))
            })
            .collect();
        ScatterChart {
            title: format!(
                "Utility vs localization error: Pearson r = {} (n = {})",
                r(self.overall_correlation()),
                self.runs.len()
            ),
            subtitle: format!("{}; r per budget: {}", self.building, per_budget.join(", ")),
            x_label: "utility f_D(P) (nats)".into(),
            y_label: "mean localization error (m)".into(),
            series: self
                .config
                .algorithms
                .iter()
                .enumerate()
                .map(|(i, a)| Series {
                    name: a.name().to_string(),
                    colour: i,
                    points: self
                        .runs
                        .iter()
                        .filter(|r| r.algorithm == *a)
                        .map(|r| (r.utility_nats, r.mean_error_m))
                        .collect(),
                })
                .collect(),
        }
        .to_svg()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pearson_known_values() {
        let x = [1.0, 2.0, 3.0, 4.0];
        assert!((pearson(&x, &[2.0, 4.0, 6.0, 8.0]).unwrap_or(0.0) - 1.0).abs() < 1e-12);
        assert!((pearson(&x, &[8.0, 6.0, 4.0, 2.0]).unwrap_or(0.0) + 1.0).abs() < 1e-12);
        // x = 1..4, y = 1,3,2,4: r = 0.8.
        assert!((pearson(&x, &[1.0, 3.0, 2.0, 4.0]).unwrap_or(0.0) - 0.8).abs() < 1e-12);
        assert_eq!(pearson(&x, &[5.0; 4]), None);
        assert_eq!(pearson(&[1.0], &[2.0]), None);
    }

    #[test]
    fn seeds_differ_between_runs_and_streams_and_are_stable() {
        let p: Vec<u64> = (0..5).map(|r| plan_seed(1, r)).collect();
        let e: Vec<u64> = (0..5).map(|r| eval_seed(1, r)).collect();
        for i in 0..5 {
            for j in 0..5 {
                assert_ne!(p[i], e[j]);
                if i != j {
                    assert_ne!(p[i], p[j]);
                    assert_ne!(e[i], e[j]);
                }
            }
        }
        assert_eq!(p[0], plan_seed(1, 0));
        assert_ne!(plan_seed(1, 0), plan_seed(2, 0));
    }

    #[test]
    fn csv_fields_are_quoted_when_needed() {
        assert_eq!(csv_field("a b"), "a b");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"x\""), "\"say \"\"x\"\"\"");
    }

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
