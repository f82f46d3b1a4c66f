//! `trailprint simulate` end to end: the JSON summary, plain progress lines when not on a
//! terminal, the session kept in `--db` and its collected fingerprints exported.

use std::process::Command;

use crate::store_common::{BIN, DEMO_BUILDING, demo_route};

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
    let exp = Command::new(BIN)
        .arg("--db")
        .arg(&db)
        .args([
            "export",
            "Demo building (synthetic)",
            "--collected",
            "csv",
            "-o",
        ])
        .arg(&csv)
        .output()
        .expect("export");
    assert!(
        exp.status.success(),
        "{}",
        String::from_utf8_lossy(&exp.stderr)
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
