//! `trailprint simulate` end to end: the JSON summary, plain progress lines when not on a
//! terminal, the session kept in `--db` and its collected fingerprints exported.

use std::process::Command;

use crate::store_common::{BIN, DEMO_BUILDING, demo_name, demo_route, run, run_ok};

fn simulate(db: Option<&std::path::Path>, extra: &[&str]) -> std::process::Output {
    let mut c = Command::new(BIN);
    if let Some(db) = db {
        c.arg("--db").arg(db);
    }
    c.args(["simulate", "--building", DEMO_BUILDING])
        .args(demo_route("50"))
        .args(["--time-limit", "0.3"])
        .args(extra)
        .output()
        .expect("run trailprint simulate")
}

#[test]
fn json_summary_is_the_last_line_and_the_session_is_stored() {
    let dir = tempfile::tempdir().expect("dir");
    let db = dir.path().join("s.db");
    let out = simulate(
        Some(&db),
        &[
            "--surveyor",
            "human",
            "--deviate",
            "0.3",
            "--seed",
            "4",
            "--json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let last = text.lines().last().expect("a line");
    let v: serde_json::Value = serde_json::from_str(last).expect("JSON");
    for key in [
        "walked_m",
        "samples",
        "planned_utility_nats",
        "collected_utility_nats",
        "replans",
        "off_route_events",
    ] {
        assert!(v.get(key).is_some_and(|x| x.is_number()), "{key} in {last}");
    }
    assert_eq!(v["status"], "finished");
    assert!(v["replans"].as_u64().expect("replans") >= 1, "{last}");
    let samples = v["samples"].as_u64().expect("samples");

    // The collected fingerprints are in the database, one CSV row each.
    let csv = dir.path().join("c.csv");
    run_ok(
        &db,
        &[
            "export",
            &demo_name(),
            "--collected",
            "csv",
            "-o",
            csv.to_str().expect("utf-8"),
        ],
    );
    let rows = std::fs::read_to_string(&csv).expect("csv").lines().count() as u64;
    assert_eq!(rows, samples + 1);
}

#[test]
fn plain_lines_without_a_terminal_and_the_robot_collects_what_was_planned() {
    let out = simulate(None, &["--surveyor", "robot", "--seed", "2"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(
        !text.contains('\r'),
        "no progress bar when stdout is not a terminal"
    );
    assert!(text.contains("finish"), "{text}");
    let util = text
        .lines()
        .find(|l| l.starts_with("utility:"))
        .expect("utility line");
    // "utility: planned X nats, collected Y nats": equal for an exact robot walk.
    let nums: Vec<&str> = util
        .split_whitespace()
        .filter(|w| w.parse::<f64>().is_ok())
        .collect();
    assert_eq!(nums.len(), 2, "{util}");
    assert_eq!(nums[0], nums[1], "{util}");
}

#[test]
fn bad_options_fail_with_a_message() {
    let out = simulate(None, &["--surveyor", "human", "--deviate", "1.5"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--deviate"));
    let out = simulate(None, &["--deviate", "0.1"]);
    assert_eq!(out.status.code(), Some(2), "--surveyor is required");
}

/// A building whose dense survey is too large for the simulated world (a GP on one point
/// more than `max_fit_points`, 8,177 points, would take more than 512 MiB) is refused with
/// the count and the size, before a plan is made: the database gets no plan and no session.
#[test]
fn a_dense_survey_too_large_for_the_world_model_is_refused_before_planning() {
    let dir = tempfile::tempdir().expect("dir");
    let db = dir.path().join("s.db");
    let file = dir.path().join("dense.json");
    let n = trailprint::gp::predict::max_fit_points() + 1;
    let mib = trailprint::gp::predict::fit_bytes(n).div_ceil(1 << 20);
    let dense: Vec<String> = (0..n)
        .map(|i| format!(r#"{{"x":{},"y":0,"rss":{{"ap":-60}}}}"#, i as f64 * 0.003))
        .collect();
    let text = format!(
        r#"{{"format":"survey-building/1","name":"dense line",
        "vertices":[{{"id":"a","x":0,"y":0}},{{"id":"b","x":15,"y":0}},{{"id":"c","x":30,"y":0}}],
        "edges":[{{"a":"a","b":"b"}},{{"a":"b","b":"c"}}],
        "kernel":{{"sf2":40,"ell":6,"sn2":2}},
        "dense_survey":[{}]}}"#,
        dense.join(",")
    );
    std::fs::write(&file, text).expect("write");
    let out = run(
        &db,
        &[
            "simulate",
            "--building",
            file.to_str().expect("utf-8"),
            "--start",
            "a",
            "--end",
            "a",
            "--budget",
            "20",
            "--surveyor",
            "robot",
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("\"dense line\"")
            && err.contains(&format!("{n} dense_survey points"))
            && err.contains(&format!("need about {mib} MiB")),
        "{err}"
    );
    let plans = run_ok(&db, &["plans"]);
    assert!(plans.contains("no plans"), "{plans}");
}
