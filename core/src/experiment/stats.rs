//! Means over the runs of one algorithm and budget, and the utility-error correlations.

use super::{Correlation, ExperimentConfig, RunRecord, SummaryRow};
use crate::plan::Termination;

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

/// Arithmetic mean (0 for no values).
pub(super) fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// Sample standard deviation (0 for fewer than two values).
fn sample_sd(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    let m = mean(v);
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// One [`SummaryRow`] per algorithm and budget that has runs.
pub(super) fn summarise(config: &ExperimentConfig, runs: &[RunRecord]) -> Vec<SummaryRow> {
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

/// The correlations over all runs, per budget and per algorithm (see [`Correlation`]).
pub(super) fn correlations(config: &ExperimentConfig, runs: &[RunRecord]) -> Vec<Correlation> {
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
}
