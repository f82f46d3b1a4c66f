//! The run loop: plan, sample, evaluate, for every budget, algorithm and run; then the
//! reference errors.

use std::sync::Arc;

use super::seeds::{eval_seed, plan_seed, seeded};
use super::stats::{correlations, mean, summarise};
use super::{Baseline, Experiment, ExperimentConfig, RunRecord};
use crate::building::Building;
use crate::eval::{Evaluator, LocalizationReport, Localizer};
use crate::plan::{Control, PlanRequest, PlanResult, plan};
use crate::samples::sample_walk;
use crate::{Error, Result};

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
                        let limit = config.time_limit_for(algorithm);
                        let settings = crate::plan::PlanSettings::for_run(
                            config.model,
                            config.params,
                            algorithm,
                            ps,
                            limit,
                        );
                        let req = PlanRequest::with_settings(
                            &config.start,
                            &config.end,
                            budget,
                            config.kernel,
                            &settings,
                        );
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

/// The pilot-only and dense-survey errors, averaged over the runs' evaluation seeds.
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
