//! `trailprint fit` and `plan` on a floor too long for SPEC 2's access-point rule: every
//! access point is heard on a stretch of the corridor only, so none is heard at half the
//! pilot locations (decision record 0007).

#![allow(clippy::expect_used)] // tests and their helpers may expect

use std::path::Path;

use crate::store_common::{run, run_ok, temp_db, words};
use trailprint::gp::fit::ApRule;

/// A 120 m corridor (61 vertices) with 25 pilot locations 5 m apart and 8 access points,
/// each heard within `range_m` of it (path loss plus a fixed ripple, no randomness).
fn long_corridor(dir: &Path, range_m: f64) -> std::path::PathBuf {
    let vertices: Vec<serde_json::Value> = (0..=60)
        .map(|i| serde_json::json!({"id": format!("c{i:02}"), "x": 2.0 * i as f64, "y": 0.0}))
        .collect();
    let edges: Vec<serde_json::Value> = (0..60)
        .map(|i| serde_json::json!({"a": format!("c{i:02}"), "b": format!("c{:02}", i + 1)}))
        .collect();
    let pilot: Vec<serde_json::Value> = (0..25)
        .map(|k| {
            let x = 5.0 * k as f64;
            let mut rss = serde_json::Map::new();
            for a in 0..8 {
                let ap_x = 7.5 + 15.0 * a as f64;
                let d = (x - ap_x).abs();
                if d <= range_m {
                    let ripple = 3.0 * ((k * 7 + a * 3) as f64).sin();
                    let v = -40.0 - 25.0 * (1.0 + d).log10() + ripple;
                    rss.insert(
                        format!("ap-{a}"),
                        serde_json::json!((v * 100.0).round() / 100.0),
                    );
                }
            }
            serde_json::json!({"x": x, "y": 0.0, "rss": rss})
        })
        .collect();
    let doc = serde_json::json!({
        "format": "survey-building/1",
        "name": format!("Long corridor, heard within {range_m} m"),
        "vertices": vertices,
        "edges": edges,
        "pilot": pilot,
    });
    let path = dir.join(format!("corridor-{range_m}.json"));
    std::fs::write(&path, doc.to_string()).expect("write building");
    path
}

#[test]
fn a_floor_where_no_access_point_is_heard_at_half_the_pilot_locations_is_fitted_and_planned() {
    let (dir, db) = temp_db();
    let file = long_corridor(dir.path(), 25.0);
    let file = file.to_str().expect("utf-8");
    run_ok(&db, &["import", file]);
    let name = "Long corridor, heard within 25 m";
    let out = run_ok(&db, &["fit", "--building", name, "--json"]);
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("one JSON object");
    assert_eq!(v["ap_rule"], "heard_only", "{v}");
    assert_eq!(v["aps_used"].as_array().map(Vec::len), Some(8), "{v}");
    assert!(
        v["fit_id"].as_i64().is_some(),
        "recorded in the database: {v}"
    );
    for key in ["sf2", "ell", "sn2"] {
        assert!(v[key].as_f64().is_some_and(|x| x > 0.0), "{key} in {v}");
    }
    // The rule is kept with the fit, and the next plan uses that fit.
    let store = trailprint::Store::open(&db).expect("open");
    let fit = store.latest_fit(name).expect("read").expect("a fit");
    assert_eq!(fit.record.ap_rule, ApRule::HeardOnly);
    drop(store);
    let out = run_ok(
        &db,
        &[
            "plan",
            "--building",
            name,
            "--start",
            "c00",
            "--end",
            "c00",
            "--budget",
            "80",
            "--time-limit",
            "1",
            "--json",
        ],
    );
    let p: serde_json::Value = serde_json::from_str(out.trim()).expect("one JSON object");
    assert_eq!(
        p["kernel"]["ell"], v["ell"],
        "the plan takes the recorded fit: {p}"
    );
    assert!(p["utility_nats"].as_f64().is_some_and(|u| u > 0.0), "{p}");
    assert!(
        p["length_m"].as_f64().is_some_and(|l| l > 0.95 * 80.0),
        "{p}"
    );
}

/// What the refusal of the 6 m corridor's pilot data says: the cause, the counts, and the
/// way around it.
const REFUSAL: [&str; 4] = [
    "no access point is heard at half or more of the 25 pilot locations",
    "nor at 4 or more of them (the most: 2)",
    "give the kernel",
    "--kernel SF2,ELL,SN2",
];

#[test]
fn pilot_data_too_sparse_for_either_rule_is_refused_with_what_to_do() {
    let (dir, db) = temp_db();
    // Heard within 6 m: at 2 locations each.
    let file = long_corridor(dir.path(), 6.0);
    let path = file.to_str().expect("utf-8");
    // `fit`, and `plan` on the file (it has no kernel of its own), both refuse with the
    // cause and the option that does without a fit.
    let plan = [
        &["plan", "--building", path][..],
        &words("--start c00 --budget 40"),
    ]
    .concat();
    for args in [&["fit", "--building", path][..], &plan] {
        let o = run(&db, args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        for want in REFUSAL {
            assert!(err.contains(want), "{args:?}: {want:?} in {err}");
        }
    }
}
