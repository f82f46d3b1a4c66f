//! The experiment of issue 8 on a small scale: tiny budgets, two runs, greedy and genetic
//! on Area One. The CSV files have the documented columns, the correlation is a number in
//! [-1, 1], and the same seed gives the same files (run times aside).

use crate::store_common::trailprint;
use std::path::Path;
use std::sync::Arc;

use trailprint::Building;
use trailprint::experiment::{
    BASELINES_HEADER, CORRELATION_HEADER, ExperimentConfig, FILES, RUNS_HEADER, SUMMARY_HEADER,
    run_experiment,
};
use trailprint::gp::fit_kernel;
use trailprint::plan::{Algorithm, Control};

const AREA_ONE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/area-one.json");

fn area_one() -> Arc<Building> {
    Arc::new(Building::load(Path::new(AREA_ONE)).expect("fixture loads"))
}

fn config(b: &Building, seed: u64) -> ExperimentConfig {
    let kernel = fit_kernel(&b.pilot).expect("fit").kernel;
    let mut c = ExperimentConfig::new(
        "r0c0",
        "r0c0",
        vec![12.0, 18.0],
        vec![Algorithm::Greedy, Algorithm::Genetic],
        2,
        kernel,
    );
    c.seed = seed;
    c.params.population = 30;
    c
}

/// Drops the last `n` comma-separated fields of every line (the run-time columns).
fn without_last(csv: &str, n: usize) -> String {
    csv.lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            f[..f.len() - n].join(",")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn check_table(csv: &str, header: &str, rows: usize) -> Vec<Vec<String>> {
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some(header));
    let width = header.split(',').count();
    let body: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(body.len(), rows, "{csv}");
    for row in &body {
        assert_eq!(row.len(), width, "{row:?}");
    }
    body
}

#[test]
fn small_experiment_writes_the_documented_tables() {
    let b = area_one();
    let cfg = config(&b, 7);
    let mut seen = 0;
    let exp = run_experiment(b.clone(), &cfg, &Control::new(), &mut |_| seen += 1)
        .expect("experiment runs");
    assert_eq!(seen, 8);

    let runs = check_table(&exp.runs_csv(), RUNS_HEADER, 8);
    for row in &runs {
        let utility: f64 = row[7].parse().expect("utility");
        let error: f64 = row[8].parse().expect("mean error");
        let length: f64 = row[5].parse().expect("length");
        let budget: f64 = row[1].parse().expect("budget");
        assert!(
            utility > 0.0 && error >= 0.0 && length <= budget + 1e-9,
            "{row:?}"
        );
        assert!(["completed", "optimal", "time_limit"].contains(&row[11].as_str()));
        // Both localizers are reported: the GP likelihood and weighted kNN.
        let knn: f64 = row[14].parse().expect("knn mean error");
        assert!(knn.is_finite() && knn >= 0.0, "{row:?}");
        let walk: Vec<&str> = row[13].split(' ').collect();
        assert_eq!((walk[0], walk[walk.len() - 1]), ("r0c0", "r0c0"));
    }
    // Greedy ignores the seed: run 1 reuses the walk of run 0, with a new evaluation seed.
    let greedy: Vec<&Vec<String>> = runs.iter().filter(|r| r[0] == "greedy").collect();
    assert_eq!(greedy[0][12], "false");
    assert_eq!(greedy[1][12], "true");
    assert_eq!(greedy[0][13], greedy[1][13]);
    assert_ne!(greedy[0][4], greedy[1][4]);
    // Genetic plans with a different seed in every run.
    let genetic: Vec<&Vec<String>> = runs.iter().filter(|r| r[0] == "genetic").collect();
    assert_ne!(genetic[0][3], genetic[1][3]);

    let summary = check_table(&exp.summary_csv(), SUMMARY_HEADER, 4);
    for row in &summary {
        assert_eq!(row[2], "2");
        let (lo, mean, hi): (f64, f64, f64) = (
            row[5].parse().expect("min"),
            row[3].parse().expect("mean"),
            row[6].parse().expect("max"),
        );
        assert!(lo <= mean + 1e-6 && mean <= hi + 1e-6, "{row:?}");
    }

    // all, two budgets, two algorithms.
    let corr = check_table(&exp.correlation_csv(), CORRELATION_HEADER, 5);
    assert_eq!(corr[1][0], "budget=12");
    assert_eq!(corr[4][0], "algorithm=genetic");
    assert_eq!(corr[0][0], "all");
    assert_eq!(corr[0][1], "8");
    let r: f64 = corr[0][2].parse().expect("overall correlation is defined");
    assert!((-1.0..=1.0).contains(&r), "{r}");
    let r_exact = exp.overall_correlation().expect("defined");
    assert!((-1.0..=1.0).contains(&r_exact));

    let base = check_table(&exp.baselines_csv(), BASELINES_HEADER, 2);
    assert_eq!(base[0][0], "pilot-only");
    assert_eq!(base[1][0], "dense-survey");
    assert_eq!(base[1][1], b.dense_survey.len().to_string());
    let knn_dense: f64 = base[1][5].parse().expect("knn baseline");
    let knn_pilot: f64 = base[0][5].parse().expect("knn baseline");
    assert!(
        knn_dense < knn_pilot,
        "kNN on the dense survey beats the pilot data: {base:?}"
    );

    let scatter = exp.scatter_chart();
    assert!(
        scatter.contains(&format!("Pearson r = {r_exact:.2}")),
        "{scatter}"
    );
    for svg in [
        exp.utility_chart(),
        exp.error_chart(),
        exp.runtime_chart(),
        scatter,
    ] {
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        assert!(svg.contains(r#"data-name="greedy""#) && svg.contains(r#"data-name="genetic""#));
    }
}

#[test]
fn same_seed_same_tables_other_seed_other_noise() {
    let b = area_one();
    let run = |seed| {
        run_experiment(b.clone(), &config(&b, seed), &Control::new(), &mut |_| {})
            .expect("experiment runs")
    };
    let (a, a2, c) = (run(3), run(3), run(4));
    assert_eq!(
        without_last(&a.runs_csv(), 1),
        without_last(&a2.runs_csv(), 1)
    );
    assert_eq!(
        without_last(&a.summary_csv(), 2),
        without_last(&a2.summary_csv(), 2)
    );
    assert_eq!(a.correlation_csv(), a2.correlation_csv());
    assert_eq!(a.baselines_csv(), a2.baselines_csv());
    assert_eq!(a.scatter_chart(), a2.scatter_chart());
    assert_ne!(
        without_last(&a.runs_csv(), 1),
        without_last(&c.runs_csv(), 1)
    );
}

#[test]
fn unreachable_budget_and_missing_world_model_are_errors() {
    let b = area_one();
    let mut cfg = config(&b, 1);
    cfg.end = "r5c4".into();
    cfg.budgets = vec![5.0];
    let e = run_experiment(b.clone(), &cfg, &Control::new(), &mut |_| {})
        .expect_err("budget too small");
    assert!(e.to_string().contains("fits the budget"), "{e}");

    let mut bare = (*b).clone();
    bare.dense_survey.clear();
    let e = run_experiment(Arc::new(bare), &config(&b, 1), &Control::new(), &mut |_| {})
        .expect_err("no world model");
    assert!(e.to_string().contains("dense_survey"), "{e}");
}

/// `trailprint experiment` on Area One, from r0c0 back to r0c0.
const EXPERIMENT_R0C0: [&str; 7] = [
    "experiment",
    "--building",
    AREA_ONE,
    "--start",
    "r0c0",
    "--end",
    "r0c0",
];

#[test]
fn cli_writes_every_file_and_repeats_itself() {
    let dir = tempfile::tempdir().expect("tempdir");
    let run = |out: &Path| {
        let o = trailprint(
            &[
                &EXPERIMENT_R0C0[..],
                &[
                    "--budgets",
                    "12,18",
                    "--algorithms",
                    "greedy,genetic",
                    "--runs",
                    "2",
                    "--population",
                    "30",
                    "--seed",
                    "5",
                    "--time-limit",
                    "30,genetic=20",
                    "--out",
                    out.to_str().expect("utf-8 path"),
                    "--quiet",
                ],
            ]
            .concat(),
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let (d1, d2) = (dir.path().join("one"), dir.path().join("two"));
    let stdout = run(&d1);
    assert!(stdout.contains("pearson r (all, n=8)"), "{stdout}");
    run(&d2);
    let read = |d: &Path, f: &str| std::fs::read_to_string(d.join(f)).expect("file written");
    for f in FILES {
        assert!(!read(&d1, f).is_empty(), "{f}");
    }
    assert_eq!(
        without_last(&read(&d1, "runs.csv"), 1),
        without_last(&read(&d2, "runs.csv"), 1)
    );
    assert_eq!(
        without_last(&read(&d1, "summary.csv"), 2),
        without_last(&read(&d2, "summary.csv"), 2)
    );
    for f in [
        "correlation.csv",
        "baselines.csv",
        "scatter.svg",
        "utility.svg",
    ] {
        assert_eq!(read(&d1, f), read(&d2, f), "{f}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&read(&d1, "experiment.json")).expect("JSON");
    assert_eq!(json["config"]["seed"], 5);
    assert_eq!(json["config"]["time_limits"]["genetic"], 20.0);
    assert_eq!(json["runs"].as_array().map(Vec::len), Some(8));

    let o = trailprint(
        &[
            &EXPERIMENT_R0C0[..],
            &["--budgets", "12", "--algorithms", "greedy,bogus", "--out"],
            &[d1.to_str().expect("utf-8 path")],
        ]
        .concat(),
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown algorithm"));
}
