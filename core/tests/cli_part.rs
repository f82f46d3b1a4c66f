//! End-to-end: a building too large to plan on the device is cut into a part that is not
//! (`trailprint export --floor` / `--around --radius`), as the refusal says.

use std::path::{Path, PathBuf};

use crate::plan_common::line_json;
use crate::store_common::{run, run_ok, trailprint, words};

/// A scratch folder with the path of its database and of a 3,000-vertex [`corridor`]
/// written there.
fn corridor_3000() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().expect("tempdir");
    let (db, file) = (dir.path().join("t.db"), dir.path().join("corridor.json"));
    corridor(&file, 3000);
    (dir, db, file)
}

/// A straight corridor of `n` vertices 1 m apart (`v0`, `v1`, ...) named "Long
/// corridor", a pilot point every 50 m, and the kernel in the file.
fn corridor(path: &Path, n: usize) {
    let pilot: Vec<String> = (0..n)
        .step_by(50)
        .map(|i| {
            format!(
                r#"{{"x":{i},"y":0,"rss":{{"ap1":{},"ap2":-70}}}}"#,
                -40.0 - 0.01 * i as f64
            )
        })
        .collect();
    let mut b: serde_json::Value =
        serde_json::from_str(&line_json(n, &format!("[{}]", pilot.join(",")))).expect("json");
    b["name"] = "Long corridor".into();
    b["kernel"] = serde_json::json!({"sf2": 40, "ell": 6, "sn2": 9});
    std::fs::write(path, b.to_string()).expect("write the building");
}

#[test]
fn a_building_refused_for_its_size_is_planned_on_the_part_the_refusal_names() {
    let (dir, db, file) = corridor_3000();
    run_ok(&db, &["import", file.to_str().expect("utf-8")]);
    let plan = words("--start v0 --budget 60 --memory-budget 64");
    let o = run(
        &db,
        &[&["plan", "--building", "Long corridor"][..], &plan].concat(),
    );
    assert!(!o.status.success(), "3,000 vertices fit 64 MiB?");
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        err.contains("more than the memory budget of 64 MiB"),
        "{err}"
    );
    // The message names the part to cut out: every vertex the walk can reach.
    let hint = err
        .split('`')
        .find(|s| s.starts_with("--around"))
        .unwrap_or_else(|| panic!("no --around hint in: {err}"));
    // A round trip of 60 m reaches 30 m from v0; two length scales (6 m) more.
    assert_eq!(hint, "--around v0 --radius 42");
    let part = dir.path().join("part.json");
    let part_s = part.to_str().expect("utf-8");
    let export = [&["export", "Long corridor", "-o", part_s][..], &words(hint)].concat();
    let o = run(&db, &export);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(summary.contains("43 of 3000 vertices"), "{summary}");
    let b = trailprint::Building::load(&part).expect("the part is a valid building");
    assert_eq!(b.name, "Long corridor (within 42 m of v0)");
    assert_eq!(b.len(), 43);
    // Every pilot point of the floor is kept (the kernel's data), the kernel too.
    assert_eq!(b.pilot.len(), 60);
    assert!(b.kernel.is_some());

    let out = run_ok(
        &db,
        &[&["plan", "--building", part_s, "--json"][..], &plan].concat(),
    );
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("one JSON object");
    let length = v["length_m"].as_f64().expect("length");
    assert!(length > 0.95 * 60.0 && length <= 60.0 + 1e-9, "{v}");
    assert!(v["utility_nats"].as_f64().is_some_and(|u| u > 0.0), "{v}");
    // Refused on the part too (16 MiB), the message names no part: it would be the same.
    let o = run(
        &db,
        &[
            &["plan", "--building", part_s, "--memory-budget", "16"][..],
            &plan[..4],
        ]
        .concat(),
    );
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        err.contains("more than the memory budget of 16 MiB"),
        "{err}"
    );
    assert!(
        err.contains("this walk can reach every vertex of this one") && !err.contains("--around"),
        "{err}"
    );

    // From v0 to v20 within 60 m: nothing beyond (60 + 20) / 2 = 40 m is reachable.
    let to_v20 = words("--start v0 --end v20 --budget 60 --memory-budget 64");
    let o = run(
        &db,
        &[&["plan", "--building", "Long corridor"][..], &to_v20].concat(),
    );
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(err.contains("`--around v0 --radius 52`"), "{err}");
}

#[test]
fn one_floor_is_exported_as_a_building_and_bad_parts_write_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = dir.path().join("t.db");
    let whole = dir.path().join("b.json");
    let whole_s = whole.to_str().expect("utf-8");
    let sizes = words("--floors 2 --rooms 2 --corridor-length 16 --aps 6 --seed 4");
    let o = trailprint(&[&["generate", "--out", whole_s][..], &sizes].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let b = trailprint::Building::load(&whole).expect("valid");

    let part = dir.path().join("f1.json");
    let part_s = part.to_str().expect("utf-8");
    run_ok(&db, &["export", whole_s, "--floor", "1", "-o", part_s]);
    let p = trailprint::Building::load(&part).expect("valid");
    let on_1 = b.vertices.iter().filter(|v| v.pos.floor == 1).count();
    assert_eq!(p.len(), on_1);
    assert!(p.vertices.iter().all(|v| v.pos.floor == 1));
    assert!(p.pilot.iter().all(|f| f.floor == 1) && !p.pilot.is_empty());
    assert!(p.test_points.iter().all(|f| f.floor == 1));
    // A part is a building like another: it imports under its own name beside the whole.
    run_ok(&db, &["import", whole_s]);
    run_ok(&db, &["import", part_s]);
    let list = run_ok(&db, &["buildings"]);
    assert!(list.contains(&format!("{} (floor 1)", b.name)), "{list}");

    let bad = dir.path().join("bad.json");
    let bad_s = bad.to_str().expect("utf-8");
    for (args, says) in [
        (vec!["--floor", "5"], "has no floor 5"),
        (
            words("--around nowhere --radius 10"),
            "unknown vertex \"nowhere\"",
        ),
        (
            words("--around f0-c00 --radius 0"),
            "positive number of metres",
        ),
        (
            words("--floor 1 --around f0-c00 --radius 10"),
            "is on floor 0",
        ),
    ] {
        let o = run(
            &db,
            &[&["export", whole_s, "-o", bad_s][..], &args].concat(),
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{args:?}: {err}");
        assert!(!bad.exists(), "{args:?} wrote a file");
    }
}

#[test]
fn every_command_that_plans_takes_the_memory_budget_its_refusal_names() {
    let (_dir, db, file) = corridor_3000();
    let b = file.to_str().expect("utf-8");
    let team = [
        "team-plan",
        "--building",
        b,
        "--surveyor",
        "v0:60",
        "--surveyor",
        "v100:60",
    ];
    let simulate = [
        "simulate",
        "--building",
        b,
        "--start",
        "v0",
        "--budget",
        "60",
        "--surveyor",
        "human",
    ];
    let plan = ["plan", "--building", b, "--start", "v0", "--budget", "60"];
    let utility = ["utility", "--building", b, "--walk", "v0,v1,v2"];
    for command in [&team[..], &simulate, &plan, &utility] {
        let o = run(&db, &[command, &["--memory-budget", "16"]].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("more than the memory budget of 16 MiB"),
            "{command:?}: {err}"
        );
    }
    // The default (512 MiB) holds this building.
    let out = run_ok(
        &db,
        &[&team[..], &["--algorithm", "coverage", "--json"]].concat(),
    );
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("one JSON object");
    assert!(
        v["team_utility_nats"].as_f64().is_some_and(|u| u > 0.0),
        "{v}"
    );
}

#[test]
fn a_team_refused_for_its_size_is_planned_on_the_one_part_its_refusal_names() {
    let (dir, db, file) = corridor_3000();
    let b = file.to_str().expect("utf-8");
    let team = words("--surveyor v0:60 --surveyor v100:60 --memory-budget 64 --algorithm coverage");
    let o = run(&db, &[&["team-plan", "--building", b][..], &team].concat());
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "{err}");
    // v100's reach (30 m and two length scales) is 100 m away from v0: 142 m around v0.
    let hint = err
        .split("for the whole team, one part that holds every surveyor's walk: `")
        .nth(1)
        .and_then(|rest| rest.split('`').next())
        .unwrap_or_else(|| panic!("no team part in: {err}"));
    assert_eq!(hint, "--around v0 --radius 142");
    let part = dir.path().join("team.json");
    let part_s = part.to_str().expect("utf-8");
    run_ok(
        &db,
        &[&["export", b, "-o", part_s][..], &words(hint)].concat(),
    );
    let out = run_ok(
        &db,
        &[&["team-plan", "--building", part_s, "--json"][..], &team].concat(),
    );
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("one JSON object");
    assert_eq!(v["walks"].as_array().map(Vec::len), Some(2), "{v}");

    // Several --around, each with its --radius: their union, in one piece or refused.
    let two = dir.path().join("two.json");
    let two_s = two.to_str().expect("utf-8");
    let union = words("--around v0 --radius 10 --around v15 --radius 5");
    run_ok(&db, &[&["export", b, "-o", two_s][..], &union].concat());
    let p = trailprint::Building::load(&two).expect("valid");
    assert_eq!(p.len(), 21); // v0..v20
    let apart = words("--around v0 --radius 10 --around v50 --radius 5");
    let o = run(&db, &[&["export", b, "-o", two_s][..], &apart].concat());
    assert!(String::from_utf8_lossy(&o.stderr).contains("disconnected"));
    let unpaired = words("--around v0 --around v5 --radius 5");
    let o = run(&db, &[&["export", b, "-o", two_s][..], &unpaired].concat());
    assert!(String::from_utf8_lossy(&o.stderr).contains("each --around takes one --radius"));
}
