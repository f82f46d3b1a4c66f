//! End-to-end: `trailprint generate`, `evaluate` and `render` as a user runs them.

use std::path::Path;
use std::process::Output;

use crate::store_common::{trailprint, words};

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn generate_evaluate_render() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("b.json");
    let file_s = file.to_str().expect("utf-8 path");
    let sizes = words("--floors 2 --rooms 2 --corridor-length 16 --aps 6 --seed 4");
    let o = trailprint(&[&["generate", "--out", file_s][..], &sizes].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let b = trailprint::Building::load(&file).expect("generated file is valid");
    assert_eq!(b.floors.len(), 2);

    let walk = "f0-c02,f0-c01,f0-c00,f1-c00,f1-c01";
    let on_walk = ["--building", file_s, "--walk", walk, "--kernel", "60,8,4"];
    let evaluate = [&["evaluate"][..], &on_walk, &words("--seed 2 --json")].concat();
    let o = trailprint(&evaluate);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).expect("one JSON object");
    for key in ["mean_error_m", "median_error_m", "p90_error_m"] {
        assert!(v[key].as_f64().is_some_and(|x| x >= 0.0), "{key} in {v}");
    }
    assert_eq!(v["samples"], 1 + (4.0 + 8.0 + 2.0) as u64 * 2);
    // Same seed, same answer.
    let again = trailprint(&evaluate);
    let w: serde_json::Value = serde_json::from_str(stdout(&again).trim()).expect("json");
    assert_eq!(v["mean_error_m"], w["mean_error_m"]);

    let svg = dir.path().join("b.svg");
    let o = trailprint(
        &[
            &["render"][..],
            &on_walk,
            &["-o", svg.to_str().expect("utf-8 path")],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&svg).expect("svg written");
    assert_eq!(text.matches("class=\"floor\"").count(), 2);
    // The walk is drawn on both floors, which say in which order they are walked.
    assert!(text.matches("class=\"walk walk-0").count() >= 2);
    assert!(
        text.contains("walked 1st") && text.contains("walked 2nd"),
        "floor order"
    );
    assert!(text.trim_end().ends_with("</svg>"));
}

#[test]
fn errors_are_one_line_and_exit_1() {
    let o = trailprint(&["generate", "--out", "-", "--floors", "0"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).starts_with("error: synthetic building: floors = 0"),
        "{}",
        stderr(&o)
    );

    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/demo-building.json");
    let o = trailprint(&[
        "evaluate",
        "--building",
        demo.to_str().expect("utf-8"),
        "--walk",
        "f0-c00,f0-c05",
        "--kernel",
        "60,8,4",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("no edge between \"f0-c00\" and \"f0-c05\""),
        "{}",
        stderr(&o)
    );
}

#[test]
fn generate_to_stdout_is_the_demo_with_default_options() {
    let o = trailprint(&["generate", "--out", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o) == trailprint::synth::DEMO_BUILDING_JSON);
}

#[test]
fn generated_buildings_are_named_by_their_options_and_share_a_database() {
    let (dir, db) = crate::store_common::temp_db();
    let mut names = Vec::new();
    for (file, opts) in [
        ("a.json", "--rooms 2 --corridor-length 16"),
        ("b.json", "--rooms 2 --corridor-length 16 --seed 3"),
        (
            "c.json",
            "--floors 2 --rooms 2 --corridor-length 16 --aps 6",
        ),
    ] {
        let path = dir.path().join(file);
        let path = path.to_str().expect("utf-8 path");
        let o = trailprint(&[&["generate", "--out", path][..], &words(opts)].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        // Every one imports beside the others: the name says what made it.
        let out = crate::store_common::run_ok(&db, &["import", path]);
        let name = format!("Synthetic building ({opts})");
        assert!(out.contains(&format!("{name:?}")), "{out}");
        names.push(name);
    }
    let listed = crate::store_common::run_ok(&db, &["buildings"]);
    for n in &names {
        assert!(listed.contains(n.as_str()), "{n} in {listed}");
    }
}
