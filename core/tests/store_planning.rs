//! The one planning policy of the core (issue 15): which kernel a plan of a stored building
//! is made with (the file's, the latest stored fit, a new fit that is recorded), plan and
//! save, team plans saved whole, and the command line planning a stored building with the
//! kernel the phone recorded.

#![allow(clippy::expect_used)] // tests and their helpers may expect

use crate::store_common;
use crate::store_common::temp_db;

use trailprint::gp::{Kernel, fit_kernel};
use trailprint::plan::{Algorithm, Control, PlanSettings};
use trailprint::store::{
    FitRecord, ImportOptions, KernelSource, MAX_BUNDLE_BYTES, Store, StorePlanRequest,
    StoreTeamRequest, now_ms,
};
use trailprint::team::SurveyorTask;

/// Imports the demo building (no kernel in the file, 20 pilot locations) into `store`.
fn import_demo(store: &Store) -> i64 {
    store
        .import_json(
            trailprint::synth::DEMO_BUILDING_JSON,
            "demo.json",
            &ImportOptions::default(),
        )
        .expect("import")
        .id
}

/// The demo building in a fresh store.
fn demo_store() -> (Store, i64) {
    let store = Store::open_in_memory().expect("store");
    let id = import_demo(&store);
    (store, id)
}

/// The kernel of [`recorded_fit`], one that no refit of the demo gives.
const RECORDED: Kernel = Kernel {
    sf2: 55.0,
    ell: 4.5,
    sn2: 7.0,
};

/// A fit recorded elsewhere (a phone's "fit", a bundle), of kernel [`RECORDED`].
fn recorded_fit() -> FitRecord {
    FitRecord {
        kernel: RECORDED,
        log_likelihood: -10.0,
        aps_used: vec![],
        ap_rule: Default::default(),
        fitted_ms: now_ms(),
    }
}

fn route() -> SurveyorTask {
    SurveyorTask {
        start: "f0-c00".into(),
        end: "f0-r5-door".into(),
        budget: 30.0,
    }
}

fn settings() -> PlanSettings {
    PlanSettings {
        algorithm: Algorithm::Greedy,
        seed: 3,
        ..PlanSettings::default()
    }
}

fn fits(store: &Store, id: i64) -> u64 {
    store.building_info(id).expect("info").fits
}

#[test]
fn without_a_kernel_the_first_plan_fits_and_records_and_later_plans_reuse_that_fit() {
    let (store, id) = demo_store();
    assert_eq!(store.known_planning_kernel(id, None).expect("known"), None);
    let first = store.planning_kernel(id, None).expect("kernel");
    let KernelSource::NewFit { fit_id } = first.source else {
        panic!("expected a new fit, got {:?}", first.source)
    };
    let b = store.get_building(id).expect("building");
    assert_eq!(first.kernel, fit_kernel(&b.pilot).expect("fit").kernel);
    assert_eq!(fits(&store, id), 1);
    let again = store.planning_kernel(id, None).expect("kernel");
    assert_eq!(again.source, KernelSource::StoredFit { fit_id });
    assert_eq!(again.kernel, first.kernel);
    assert_eq!(fits(&store, id), 1, "a stored fit is reused, not refitted");
}

#[test]
fn the_latest_stored_fit_wins_over_a_refit_and_a_given_kernel_over_everything() {
    let (store, id) = demo_store();
    let fit_id = store.record_fit(id, &recorded_fit()).expect("record");
    let k = store.planning_kernel(id, None).expect("kernel");
    assert_eq!(
        (k.kernel, k.source),
        (RECORDED, KernelSource::StoredFit { fit_id })
    );
    let given = Kernel::new(40.0, 6.0, 9.0);
    let k = store.planning_kernel(id, Some(given)).expect("kernel");
    assert_eq!((k.kernel, k.source), (given, KernelSource::Given));
    let bad = store
        .planning_kernel(id, Some(Kernel::new(-1.0, 6.0, 9.0)))
        .expect_err("a negative sf2 is refused");
    assert!(bad.to_string().contains("kernel"), "{bad}");
}

#[test]
fn a_file_kernel_wins_over_stored_fits_and_nothing_is_fitted() {
    let mut doc: serde_json::Value =
        serde_json::from_str(trailprint::synth::DEMO_BUILDING_JSON).expect("json");
    doc["kernel"] = serde_json::json!({"sf2": 30.0, "ell": 5.0, "sn2": 8.0});
    let store = Store::open_in_memory().expect("store");
    let id = store
        .import_json(&doc.to_string(), "demo.json", &ImportOptions::default())
        .expect("import")
        .id;
    let saved = store
        .plan_and_save(
            id,
            &StorePlanRequest {
                route: route(),
                settings: settings(),
                kernel: None,
            },
            &Control::new(),
        )
        .expect("plan");
    assert_eq!(saved.kernel.source, KernelSource::File);
    assert_eq!(saved.stored.record.kernel, Kernel::new(30.0, 5.0, 8.0));
    assert_eq!(fits(&store, id), 0);
}

#[test]
fn plan_and_save_saves_the_walk_it_planned_with_the_policy_kernel() {
    let (store, id) = demo_store();
    let req = StorePlanRequest {
        route: route(),
        settings: settings(),
        kernel: None,
    };
    let saved = store
        .plan_and_save(id, &req, &Control::new())
        .expect("plan");
    let stored = store.load_plan(saved.stored.id).expect("load");
    assert_eq!(stored.record.walk, saved.result.walk);
    assert_eq!(stored.record.kernel, saved.kernel.kernel);
    assert_eq!(stored.record.algorithm, "greedy");
    assert!(matches!(saved.kernel.source, KernelSource::NewFit { .. }));
    // The second plan uses the fit the first recorded.
    let second = store
        .plan_and_save(id, &req, &Control::new())
        .expect("plan");
    assert!(matches!(
        second.kernel.source,
        KernelSource::StoredFit { .. }
    ));
    assert_eq!(second.result.walk, saved.result.walk);
    assert_eq!(store.list_plans(id).expect("plans").len(), 2);
}

#[test]
fn a_team_is_saved_whole_one_plan_per_member_or_not_at_all() {
    let (store, id) = demo_store();
    let mut req = StoreTeamRequest {
        members: vec![route(), route()],
        settings: settings(),
        kernel: None,
        independent: false,
        rounds: 0,
        condition_on_collected: true,
    };
    let saved = store
        .plan_team_and_save(id, &req, &Control::new())
        .expect("team");
    assert_eq!(saved.plan_ids.len(), 2);
    for (pid, p) in saved.plan_ids.iter().zip(&saved.team.plans) {
        assert_eq!(store.load_plan(*pid).expect("plan").record.walk, p.walk);
    }
    req.members[1].start = "nope".into();
    let e = store
        .plan_team_and_save(id, &req, &Control::new())
        .expect_err("unknown start");
    assert!(e.to_string().contains("nope"), "{e}");
    assert_eq!(store.list_plans(id).expect("plans").len(), 2);
}

#[test]
fn a_bundle_over_the_limit_is_refused_before_it_is_parsed() {
    let (store, _) = demo_store();
    let huge = " ".repeat(MAX_BUNDLE_BYTES as usize + 1);
    let e = store
        .import_bundle(&huge, "big.json")
        .expect_err("too big")
        .to_string();
    assert!(e.contains("big.json") && e.contains("256 MiB"), "{e}");
}

/// The command line plans a stored building with the fit the phone recorded (before
/// issue 15 it refitted and ignored stored fits, so the two planned with different kernels).
#[cfg(unix)]
#[test]
fn the_command_line_plans_a_stored_building_with_the_stored_fit() {
    let (_dir, db) = temp_db();
    let id = {
        let store = Store::open(&db).expect("open");
        let id = import_demo(&store);
        store.record_fit(id, &recorded_fit()).expect("fit");
        id
    };
    let id = id.to_string();
    let out = store_common::run_ok(
        &db,
        &[
            &["plan", "--building", &id][..],
            &store_common::demo_route("30"),
            &["--algorithm", "greedy", "--json"],
        ]
        .concat(),
    );
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("json");
    assert_eq!(v["kernel"]["sf2"], 55.0, "{v}");
    assert_eq!(v["kernel"]["ell"], 4.5, "{v}");
    let store = Store::open(&db).expect("open");
    let plan = store
        .load_plan(v["plan_id"].as_i64().expect("plan id"))
        .expect("plan");
    assert_eq!(plan.record.kernel, RECORDED);
}
