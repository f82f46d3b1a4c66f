//! The four charts of an experiment: utility, error and planning time against budget, and
//! utility against error.

use super::chart::{LineChart, LinePoint, RefLine, ScatterChart, Series};
use super::{Experiment, SummaryRow};
use crate::plan::Algorithm;

impl Experiment {
    /// One series per algorithm, in the configuration's order (the legend's): `points`
    /// gives an algorithm's points.
    fn per_algorithm<P>(&self, points: impl Fn(Algorithm) -> Vec<P>) -> Vec<Series<P>> {
        self.config
            .algorithms
            .iter()
            .enumerate()
            .map(|(i, &a)| Series {
                name: a.name().to_string(),
                colour: i,
                points: points(a),
            })
            .collect()
    }

    /// A chart against budget: one line per algorithm with a point per summary row
    /// (`point`), ticks at the configuration's budgets; `what` ends the title.
    fn budget_chart(
        &self,
        what: &str,
        y_label: &str,
        log_y: bool,
        ref_lines: Vec<RefLine>,
        point: impl Fn(&SummaryRow) -> LinePoint,
    ) -> String {
        LineChart {
            title: format!("{}: {what} vs budget", self.building),
            x_label: "budget (m)".into(),
            y_label: y_label.into(),
            series: self.per_algorithm(|a| {
                self.summary
                    .iter()
                    .filter(|r| r.algorithm == a)
                    .map(&point)
                    .collect()
            }),
            ref_lines,
            log_y,
            x_ticks: self.config.budgets.clone(),
        }
        .to_svg()
    }

    /// Mean utility against budget, bars from the smallest to the largest run.
    pub fn utility_chart(&self) -> String {
        self.budget_chart(
            "utility",
            "utility f_D(P) (nats), mean and range over runs",
            false,
            Vec::new(),
            |r| LinePoint {
                x: r.budget_m,
                y: r.utility_mean,
                bar: Some((r.utility_min, r.utility_max)),
            },
        )
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
        self.budget_chart(
            "localization error",
            "mean localization error (m), ±1 sd over runs",
            false,
            refs,
            |r| LinePoint {
                x: r.budget_m,
                y: r.error_mean_m,
                bar: Some((r.error_mean_m - r.error_sd_m, r.error_mean_m + r.error_sd_m)),
            },
        )
    }

    /// Mean planning time against budget, seconds, logarithmic axis.
    pub fn runtime_chart(&self) -> String {
        self.budget_chart(
            "planning time",
            "planning time (s, log scale), mean over runs",
            true,
            Vec::new(),
            |r| LinePoint {
                // A plan under a millisecond shows at 1 ms rather than vanish off the
                // log axis.
                x: r.budget_m,
                y: (r.elapsed_mean_ms / 1000.0).max(1e-3),
                bar: None,
            },
        )
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
            series: self.per_algorithm(|a| {
                self.runs
                    .iter()
                    .filter(|r| r.algorithm == a)
                    .map(|r| (r.utility_nats, r.mean_error_m))
                    .collect()
            }),
        }
        .to_svg()
    }
}
