//! `trailprint experiment`: the paper's evaluation (algorithms x budgets x runs: utility,
//! run time, localization error, and the utility-error correlation), written as CSV and
//! SVG charts into a directory.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use clap::Args as ClapArgs;
use trailprint::eval::EvalOptions;
use trailprint::experiment::{ExperimentConfig, FILES, run_experiment};
use trailprint::plan::{Algorithm, Control, Params};
use trailprint::{Error, Result};

use crate::opts::{BuildingOpts, KernelOpts, ModelOpts};

#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    building: BuildingOpts,
    /// Start vertex id.
    #[arg(long)]
    start: String,
    /// End vertex id [default: the start, a walk back to where it began].
    #[arg(long)]
    end: Option<String>,
    /// Budgets, metres, comma-separated (for example 30,35,40,45,50).
    #[arg(long, value_name = "B1,B2,...", value_delimiter = ',', required = true)]
    budgets: Vec<f64>,
    /// Algorithms, comma-separated: greedy, genetic, recursive-greedy, ero, exact, auto.
    #[arg(long, value_name = "A1,A2,...", value_delimiter = ',', value_parser = parse_algorithm,
          default_value = "greedy,genetic,recursive-greedy,ero,auto")]
    algorithms: Vec<Algorithm>,
    /// Runs per algorithm and budget; each run has its own planner and evaluation seed.
    #[arg(long, default_value_t = 3)]
    runs: usize,
    /// Output directory (runs.csv, summary.csv, correlation.csv, baselines.csv,
    /// experiment.json and four SVG charts).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Master seed; the seeds of every run derive from it.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Time limit per plan in seconds: `SECONDS` for every algorithm and/or
    /// `ALGORITHM=SECONDS` for one, comma-separated (for example
    /// `recursive-greedy=60,exact=120`). Without one an algorithm has its default
    /// (2 s for auto, none for the others).
    #[arg(long, value_name = "SPEC")]
    time_limit: Option<String>,
    /// Genetic: population size (paper: 100 and 200).
    #[arg(long, default_value_t = 200)]
    population: usize,
    /// Genetic: generations (paper: 5).
    #[arg(long, default_value_t = 5)]
    generations: usize,
    /// Recursive greedy: recursion depth.
    #[arg(long, default_value_t = 2)]
    depth: usize,
    /// ERO: iterations (0 = until the time limit).
    #[arg(long, default_value_t = 2000)]
    ero_iterations: usize,
    /// Plan greedy, recursive greedy and exact in every run instead of reusing the walk of
    /// the first run (they ignore the seed).
    #[arg(long)]
    replan_deterministic: bool,
    /// Reference grid spacing of the localization evaluation, metres.
    #[arg(long, default_value_t = 0.5)]
    grid_step: f64,
    #[command(flatten)]
    model: ModelOpts,
    #[command(flatten)]
    kernel: KernelOpts,
    /// No progress lines on standard error.
    #[arg(long, short)]
    quiet: bool,
}

fn parse_algorithm(s: &str) -> std::result::Result<Algorithm, String> {
    Algorithm::from_name(s.trim()).map_err(|e| e.to_string())
}

fn seconds(s: &str, what: &str) -> Result<Duration> {
    match s.trim().parse::<f64>() {
        Ok(t) if t.is_finite() && t >= 0.0 => Ok(Duration::from_secs_f64(t)),
        _ => Err(Error::InvalidRequest(format!(
            "--time-limit: {what} must be a non-negative number of seconds, got {s:?}"
        ))),
    }
}

/// The common time limit and the per-algorithm ones.
type TimeLimits = (Option<Duration>, Vec<(Algorithm, Duration)>);

/// Parses `--time-limit`: `SECONDS` and/or `ALGORITHM=SECONDS`, comma-separated.
fn parse_time_limits(spec: &str) -> Result<TimeLimits> {
    let mut all = None;
    let mut per = Vec::new();
    for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match item.split_once('=') {
            None => all = Some(seconds(item, "the time limit")?),
            Some((a, t)) => {
                let alg = Algorithm::from_name(a.trim())
                    .map_err(|e| Error::InvalidRequest(format!("--time-limit: {e}")))?;
                per.push((alg, seconds(t, &format!("the time limit of {alg}"))?));
            }
        }
    }
    Ok((all, per))
}

pub fn run(a: Args, db: Option<&std::path::Path>) -> Result<()> {
    let b = Arc::new(a.building.load(db)?);
    let model = a.model.model()?;
    let (kernel, source) = a.kernel.resolve(&b)?;
    let (time_limit, time_limits) = match &a.time_limit {
        Some(spec) => parse_time_limits(spec)?,
        None => (None, Vec::new()),
    };
    let mut config = ExperimentConfig::new(
        &a.start,
        a.end.as_deref().unwrap_or(&a.start),
        a.budgets.clone(),
        a.algorithms.clone(),
        a.runs,
        kernel,
    );
    config.model = model;
    config.seed = a.seed;
    config.time_limit = time_limit;
    config.time_limits = time_limits;
    config.params = Params {
        population: a.population,
        generations: a.generations,
        depth: a.depth,
        iterations: a.ero_iterations,
        ..Params::default()
    };
    config.eval = EvalOptions {
        grid_step_m: a.grid_step,
        ..EvalOptions::default()
    };
    config.replan_deterministic = a.replan_deterministic;

    let total = a.budgets.len() * a.algorithms.len() * a.runs;
    if !a.quiet {
        eprintln!(
            "{}: kernel sf2={:.4} ell={:.4} sn2={:.4} ({source}); {total} runs",
            b.name, kernel.sf2, kernel.ell, kernel.sn2
        );
    }
    let mut done = 0usize;
    let quiet = a.quiet;
    let mut progress = |r: &trailprint::experiment::RunRecord| {
        done += 1;
        if !quiet {
            eprintln!(
                "[{done}/{total}] {} B={} run {}: utility {:.3} nats, error {:.3} m, {} ms{}",
                r.algorithm,
                r.budget_m,
                r.run,
                r.utility_nats,
                r.mean_error_m,
                r.elapsed_ms,
                if r.reused { " (reused)" } else { "" }
            );
        }
    };
    let exp = run_experiment(b.clone(), &config, &Control::new(), &mut progress)?;
    exp.write(&a.out)?;

    println!(
        "{} (kernel {source}); {} runs",
        exp.building,
        exp.runs.len()
    );
    println!(
        "{:<17} {:>8} {:>12} {:>10} {:>10} {:>11}",
        "algorithm", "budget", "utility", "error m", "knn m", "time ms"
    );
    for r in &exp.summary {
        println!(
            "{:<17} {:>8} {:>12.3} {:>10.3} {:>10.3} {:>11.1}",
            r.algorithm.name(),
            r.budget_m,
            r.utility_mean,
            r.error_mean_m,
            r.knn_error_mean_m,
            r.elapsed_mean_ms
        );
    }
    for bl in &exp.baselines {
        println!(
            "baseline {:<13} {:>5} samples, error {:.3} m (knn {:.3} m)",
            bl.name, bl.samples, bl.mean_error_m, bl.knn_mean_error_m
        );
    }
    for c in &exp.correlations {
        let r = c
            .pearson_r
            .map_or("undefined".into(), |x| format!("{x:.3}"));
        println!("pearson r ({}, n={}): {r}", c.scope, c.n);
    }
    println!("wrote {} files to {}", FILES.len(), a.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_limit_spec() {
        let (all, per) = parse_time_limits("10, recursive-greedy=60,exact=1.5").unwrap();
        assert_eq!(all, Some(Duration::from_secs(10)));
        assert_eq!(
            per,
            vec![
                (Algorithm::RecursiveGreedy, Duration::from_secs(60)),
                (Algorithm::Exact, Duration::from_millis(1500))
            ]
        );
        assert!(parse_time_limits("fast").is_err());
        assert!(parse_time_limits("greedy=-1").is_err());
        assert!(parse_time_limits("nope=3").is_err());
    }
}
