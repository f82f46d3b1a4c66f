//! The planner benchmark: algorithms x budgets x seeds on given buildings, summarised as
//! Markdown and CSV tables (used by `trailprint bench` and `docs/benchmark-planners.md`).
//!
//! Deterministic algorithms (greedy, recursive greedy, exact) run once per budget; the
//! seeded ones (genetic, ERO, auto) once per seed.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::sync::Arc;
use std::time::Duration;

use crate::Result;
use crate::building::Building;
use crate::gp::Kernel;
use crate::surveyor::Surveyor;

use super::{Algorithm, Control, Params, PlanRequest, Termination, plan};

/// One instance: a building, its kernel, the end points and the budgets to run.
#[derive(Debug, Clone)]
pub struct BenchCase {
    pub building: Arc<Building>,
    pub kernel: Kernel,
    pub start: String,
    pub end: String,
    pub budgets: Vec<f64>,
}

/// What to run.
#[derive(Debug, Clone)]
pub struct BenchConfig {
    pub algorithms: Vec<Algorithm>,
    pub seeds: Vec<u64>,
    pub params: Params,
    pub model: Surveyor,
    /// Time limit per algorithm (`None`: the algorithm's default).
    pub time_limits: BTreeMap<String, Duration>,
}

impl BenchConfig {
    fn limit(&self, a: Algorithm) -> Option<Duration> {
        self.time_limits
            .get(a.name())
            .copied()
            .or_else(|| a.default_time_limit())
    }
}

/// Whether an algorithm uses its seed.
pub fn seeded(a: Algorithm) -> bool {
    matches!(a, Algorithm::Genetic | Algorithm::Ero | Algorithm::Auto)
}

/// One run.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchRow {
    pub building: String,
    pub start: String,
    pub end: String,
    pub budget: f64,
    pub algorithm: Algorithm,
    pub seed: u64,
    pub utility: f64,
    pub length: f64,
    pub samples: usize,
    pub elapsed_ms: u64,
    pub termination: Termination,
    pub optimal: Option<bool>,
    pub nodes: Option<u64>,
}

/// Runs every case; `on_row` sees each row as it is produced (for progress output).
pub fn run_bench(
    cases: &[BenchCase],
    cfg: &BenchConfig,
    control: &Control,
    mut on_row: impl FnMut(&BenchRow),
) -> Result<Vec<BenchRow>> {
    let mut rows = Vec::new();
    for case in cases {
        for &budget in &case.budgets {
            for &alg in &cfg.algorithms {
                let seeds: Vec<u64> = if seeded(alg) {
                    cfg.seeds.clone()
                } else {
                    cfg.seeds.iter().take(1).copied().collect()
                };
                for seed in seeds {
                    let settings = crate::plan::PlanSettings::for_run(
                        cfg.model,
                        cfg.params,
                        alg,
                        seed,
                        cfg.limit(alg),
                    );
                    let req = PlanRequest::with_settings(
                        &case.start,
                        &case.end,
                        budget,
                        case.kernel,
                        &settings,
                    );
                    let r = plan(case.building.clone(), &req, control)?;
                    let row = BenchRow {
                        building: case.building.name.clone(),
                        start: case.start.clone(),
                        end: case.end.clone(),
                        budget,
                        algorithm: alg,
                        seed,
                        utility: r.utility_nats,
                        length: r.length_m,
                        samples: r.samples,
                        elapsed_ms: r.elapsed_ms,
                        termination: r.termination,
                        optimal: r.optimal,
                        nodes: r.nodes,
                    };
                    on_row(&row);
                    rows.push(row);
                }
            }
        }
    }
    Ok(rows)
}

/// CSV of the raw rows.
pub fn to_csv(rows: &[BenchRow]) -> String {
    let mut s = String::from(
        "building,start,end,budget_m,algorithm,seed,utility_nats,length_m,samples,elapsed_ms,termination,optimal,nodes\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{:.6},{:.3},{},{},{:?},{},{}",
            r.building.replace(',', ";"),
            r.start,
            r.end,
            r.budget,
            r.algorithm,
            r.seed,
            r.utility,
            r.length,
            r.samples,
            r.elapsed_ms,
            r.termination,
            r.optimal.map_or(String::new(), |o| o.to_string()),
            r.nodes.map_or(String::new(), |n| n.to_string()),
        );
    }
    s
}

/// Summary of the runs of one (building, budget, algorithm).
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    pub building: String,
    pub budget: f64,
    pub algorithm: Algorithm,
    pub runs: usize,
    pub mean: f64,
    pub min: f64,
    pub max: f64,
    pub length: f64,
    pub time_ms: f64,
    pub max_time_ms: u64,
    pub optimal: usize,
}

/// Groups rows by building, budget and algorithm (in order of appearance).
pub fn summarise(rows: &[BenchRow]) -> Vec<Summary> {
    let mut out: Vec<Summary> = Vec::new();
    for r in rows {
        let i = match out.iter().position(|s| {
            s.building == r.building && s.budget == r.budget && s.algorithm == r.algorithm
        }) {
            Some(i) => i,
            None => {
                out.push(Summary {
                    building: r.building.clone(),
                    budget: r.budget,
                    algorithm: r.algorithm,
                    runs: 0,
                    mean: 0.0,
                    min: f64::INFINITY,
                    max: f64::NEG_INFINITY,
                    length: 0.0,
                    time_ms: 0.0,
                    max_time_ms: 0,
                    optimal: 0,
                });
                out.len() - 1
            }
        };
        let s = &mut out[i];
        s.runs += 1;
        s.mean += r.utility;
        s.min = s.min.min(r.utility);
        s.max = s.max.max(r.utility);
        s.length += r.length;
        s.time_ms += r.elapsed_ms as f64;
        s.max_time_ms = s.max_time_ms.max(r.elapsed_ms);
        s.optimal += usize::from(r.optimal == Some(true));
    }
    for s in &mut out {
        let n = s.runs.max(1) as f64;
        s.mean /= n;
        s.length /= n;
        s.time_ms /= n;
    }
    out
}

/// A Markdown table per building: one row per budget and algorithm, with the gap of the
/// mean to the best mean of that budget.
pub fn to_markdown(sum: &[Summary]) -> String {
    let mut s = String::new();
    let mut buildings: Vec<&str> = Vec::new();
    for x in sum {
        if !buildings.contains(&x.building.as_str()) {
            buildings.push(&x.building);
        }
    }
    for b in buildings {
        let _ = writeln!(s, "\n### {b}\n");
        s.push_str("| budget (m) | algorithm | runs | utility mean (nats) | min | max | gap to best | length (m) | time mean (ms) | time max (ms) | proved optimal |\n");
        s.push_str("|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        let rows: Vec<&Summary> = sum.iter().filter(|x| x.building == b).collect();
        for r in &rows {
            let best = rows
                .iter()
                .filter(|x| x.budget == r.budget)
                .map(|x| x.max)
                .fold(f64::NEG_INFINITY, f64::max);
            let gap = if best > 0.0 {
                (100.0 * (best - r.mean) / best).max(0.0)
            } else {
                0.0
            };
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.4} | {:.4} | {:.4} | {:.2}% | {:.1} | {:.0} | {} | {} |",
                r.budget,
                r.algorithm,
                r.runs,
                r.mean,
                r.min,
                r.max,
                gap,
                r.length,
                r.time_ms,
                r.max_time_ms,
                if r.algorithm == Algorithm::Exact || r.optimal > 0 {
                    format!("{}/{}", r.optimal, r.runs)
                } else {
                    String::new()
                }
            );
        }
    }
    s
}
