//! Survey sessions end to end through the command line: the budget holds for a surveyor
//! who takes wrong turns, a robot collects exactly what was planned, `simulate` counts every
//! event of the log, `sessions` lists what the database holds and `evaluate --session`
//! judges what a session really collected.

use std::path::Path;

use crate::store_common::run_ok as run;

fn fixture(name: &str) -> String {
    format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn last_json(text: &str) -> serde_json::Value {
    serde_json::from_str(text.lines().last().expect("a line")).expect("JSON")
}

/// `simulate --json` on a fixture with start = end and the given seed.
fn simulate(
    db: &Path,
    building: &str,
    start: &str,
    budget: &str,
    seed: &str,
    extra: &[&str],
) -> serde_json::Value {
    let file = fixture(building);
    let mut args = vec![
        "simulate",
        "--building",
        &file,
        "--start",
        start,
        "--end",
        start,
        "--budget",
        budget,
        "--seed",
        seed,
        "--json",
    ];
    args.extend_from_slice(extra);
    last_json(&run(db, &args))
}

/// The surveys of the first two tests: `(building, start = end, budget, algorithm)`. Area One
/// with the auto planner (it proves its plan optimal well within the limit, so the plan
/// does not depend on the machine's speed); Area Two with greedy (deterministic).
const SURVEYS: [(&str, &str, &str, &str); 2] = [
    ("area-one.json", "r0c0", "45", "auto"),
    ("area-two.json", "b00", "140", "greedy"),
];

/// `simulate`'s options for a person who takes a wrong turn at 30% of the vertices, planned
/// by `algo`.
fn wrong_turns(algo: &str) -> [&str; 6] {
    [
        "--surveyor",
        "human",
        "--deviate",
        "0.3",
        "--algorithm",
        algo,
    ]
}

fn f(v: &serde_json::Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("{key} in {v}"))
}

#[test]
fn thirty_percent_wrong_turns_end_within_budget_plus_five_percent() {
    // Area Two with greedy (deterministic), seed 2: the walk ends within budget + 5%, and
    // without the reserve it overruns by far more (the failure).
    let dir = tempfile::tempdir().expect("dir");
    let db = dir.path().join("b.db");
    let (building, start, budget, algo) = SURVEYS[1];
    let human = wrong_turns(algo);
    let v = simulate(&db, building, start, budget, "2", &human);
    let b: f64 = budget.parse().expect("budget");
    assert_eq!(v["status"], "finished", "{v}");
    assert!(f(&v, "wrong_turns") >= 3.0, "{v}");
    assert!(f(&v, "walked_m") <= 1.05 * b, "{building}: {v}");
    assert!(f(&v, "true_walked_m") <= 1.05 * b, "{building}: {v}");
    let mut no_reserve = human.to_vec();
    no_reserve.push("--no-reserve");
    let w = simulate(&db, building, start, budget, "2", &no_reserve);
    assert!(
        f(&w, "walked_m") > 1.1 * b,
        "{building} without reserve: {w}"
    );
    assert_eq!(w["reserve_m"], 0.0);
}

/// On Area One (3 m edges) one wrong turn on the way home costs 6 m, 13% of a 45 m budget,
/// and the reserve is kept only once the session has seen a wrong turn (a surveyor who
/// follows the plan gets the whole of it): a surveyor whose first wrong turn comes late
/// and far from home overruns whatever the plan. What the reserve holds is the budget on
/// average. Measured over seeds 1-30 with auto: walked / budget 0.957 on average with the
/// reserve, 1.254 without; beyond budget + 5% on 9 seeds with it, 22 without.
#[test]
fn thirty_percent_wrong_turns_keep_the_budget_on_average() {
    let dir = tempfile::tempdir().expect("dir");
    let db = dir.path().join("a.db");
    let (building, start, budget, algo) = SURVEYS[0];
    let b: f64 = budget.parse().expect("budget");
    let human = wrong_turns(algo);
    let mut no_reserve = human.to_vec();
    no_reserve.push("--no-reserve");
    let seeds = 1..=10;
    let n = seeds.clone().count() as f64;
    let (mut with, mut without) = (0.0, 0.0);
    for seed in seeds {
        let seed = seed.to_string();
        let v = simulate(&db, building, start, budget, &seed, &human);
        assert_eq!(v["status"], "finished", "{v}");
        with += f(&v, "walked_m") / b / n;
        let w = simulate(&db, building, start, budget, &seed, &no_reserve);
        assert_eq!(w["reserve_m"], 0.0);
        without += f(&w, "walked_m") / b / n;
    }
    // Measured: 0.973 and 1.210.
    assert!(with <= 1.0, "walked / budget with the reserve: {with}");
    assert!(
        without > 1.1,
        "walked / budget without the reserve: {without}"
    );
}

#[test]
fn a_robot_that_follows_the_plan_collects_exactly_the_planned_utility() {
    let dir = tempfile::tempdir().expect("dir");
    let db = dir.path().join("r.db");
    for (building, start, budget, algo) in SURVEYS {
        let v = simulate(
            &db,
            building,
            start,
            budget,
            "2",
            &["--surveyor", "robot", "--algorithm", algo],
        );
        assert!(f(&v, "plan_length_m") > 0.5 * f(&v, "budget_m"), "{v}");
        assert_eq!(f(&v, "replans"), 0.0, "{v}");
        assert_eq!(f(&v, "reserve_m"), 0.0, "{v}");
        let (p, c) = (
            f(&v, "planned_utility_nats"),
            f(&v, "collected_utility_nats"),
        );
        assert!(
            (p - c).abs() <= 1e-9 * p,
            "{building}: planned {p}, collected {c}"
        );
        assert!(
            (f(&v, "walked_m") - f(&v, "plan_length_m")).abs() < 1e-6,
            "{v}"
        );
    }
}

#[test]
fn sessions_lists_and_evaluate_judges_what_was_collected() {
    let dir = tempfile::tempdir().expect("dir");
    let db = dir.path().join("s.db");
    let human = simulate(
        &db,
        "area-one.json",
        "r0c0",
        "45",
        "2",
        &["--surveyor", "human", "--deviate", "0.3"],
    );
    let robot = simulate(
        &db,
        "area-one.json",
        "r0c0",
        "40",
        "2",
        &["--surveyor", "robot"],
    );
    assert!(f(&human, "replans") >= 1.0, "{human}");

    // `events` counts every event of the log, the replans too.
    let rows = db_events(&db);
    for v in [&human, &robot] {
        let id = v["session_id"].as_i64().expect("id");
        let n = rows.iter().find(|r| r.0 == id).map_or(0, |r| r.1);
        assert_eq!(v["events"].as_i64(), Some(n), "{v}");
    }

    let list: serde_json::Value =
        serde_json::from_str(run(&db, &["sessions", "--json"]).trim()).expect("JSON array");
    let list = list.as_array().expect("array");
    assert_eq!(list.len(), 2);
    for (row, v, kind) in [(&list[0], &human, "human"), (&list[1], &robot, "robot")] {
        assert_eq!(row["id"], v["session_id"]);
        assert_eq!(row["building"], "Area One (synthetic)");
        assert_eq!(row["surveyor"], kind);
        assert_eq!(row["status"], "finished");
        assert_eq!(row["samples"], v["samples"]);
        assert_eq!(row["events"], v["events"]);
        assert_eq!(row["replans"], v["replans"]);
        assert!(
            (f(row, "walked_m") - f(v, "walked_m")).abs() < 1e-9,
            "{row} vs {v}"
        );
        let (a, b) = (
            f(row, "collected_utility_nats"),
            f(v, "collected_utility_nats"),
        );
        assert!((a - b).abs() <= 1e-12 * b, "{row} vs {v}");
    }
    let table = run(&db, &["sessions"]);
    assert!(
        table.contains("human") && table.contains("robot") && table.contains("finished"),
        "{table}"
    );

    // evaluate --session: the session's own fingerprints, against the measured test points.
    let hid = human["session_id"].to_string();
    let rid = robot["session_id"].to_string();
    let eh = last_json(&run(&db, &["evaluate", "--session", &hid, "--json"]));
    let er = last_json(&run(&db, &["evaluate", "--session", &rid, "--json"]));
    for (e, v) in [(&eh, &human), (&er, &robot)] {
        assert_eq!(e["collected"], v["samples"], "{e}");
        assert_eq!(e["test_points"], 58, "{e}");
        assert_eq!(e["localizer"], "gp");
        assert_eq!(e["kernel_source"], "plan");
        let m = f(e, "mean_error_m");
        assert!(m > 0.0 && m < 10.0, "{e}");
        assert!(f(e, "std_max_db") >= f(e, "std_mean_db"), "{e}");
    }
    // The robot scanned every 0.5 m: a denser map than the human's, less uncertain.
    assert!(f(&er, "collected") > f(&eh, "collected"));
    assert!(
        f(&er, "std_mean_db") < f(&eh, "std_mean_db"),
        "{er} vs {eh}"
    );
    let k = last_json(&run(
        &db,
        &[
            "evaluate",
            "--session",
            &rid,
            "--localizer",
            "knn",
            "--json",
        ],
    ));
    assert_eq!(k["localizer"], "knn:3");
    assert!(f(&k, "mean_error_m").is_finite());
    let text = run(&db, &["evaluate", "--session", &hid]);
    assert!(
        text.contains("localization error (gp)") && text.contains("posterior std"),
        "{text}"
    );

    // Unknown sessions and bad localizers are refused with a message.
    let out = crate::store_common::run(&db, &["evaluate", "--session", "99"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("session 99"));
    let out = crate::store_common::trailprint(&[
        "evaluate",
        "--building",
        &fixture("area-one.json"),
        "--localizer",
        "knn:0",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("knn:K"));
}

/// `(session id, number of events)` as the database holds them.
fn db_events(db: &Path) -> Vec<(i64, i64)> {
    let conn = rusqlite::Connection::open(db).expect("open");
    let mut st = conn
        .prepare("SELECT session_id, count(*) FROM session_events GROUP BY session_id")
        .expect("prepare");
    st.query_map([], |r| Ok((r.get(0)?, r.get(1)?)))
        .expect("query")
        .collect::<rusqlite::Result<Vec<_>>>()
        .expect("rows")
}
