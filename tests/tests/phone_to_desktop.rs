//! End to end across the crates: a phone (the bindings layer, as the Kotlin app drives it)
//! plans and walks a survey on a file database, the app is "killed" and resumed from a
//! fresh store object, the session is exported as a bundle, and a desktop database (the
//! core store, as the command line uses it) merges it and plans the next surveyor's walk
//! conditioned on what was collected.

use std::sync::Arc;

use trailprint::plan::{PlanRequest, plan, plan_with_prior};
use trailprint::store::{BuildingRef, Store};
use trailprint_ffi::{
    PlanAlgorithm, PlanRequest as FfiPlanRequest, TrailprintStore, WifiReading,
    default_robot_profile,
};

fn demo_json() -> String {
    trailprint::synth::DEMO_BUILDING_JSON.to_string()
}

/// A phone's database: the file `phone.db` in `dir` (its path), opened through the
/// bindings, with the demo building imported (its id).
fn phone_with_demo(dir: &tempfile::TempDir) -> (String, Arc<TrailprintStore>, i64) {
    let db = dir.path().join("phone.db").display().to_string();
    let phone = TrailprintStore::open(db.clone()).expect("open");
    let id = phone
        .import_building_json(demo_json(), "demo".into(), false)
        .expect("import")
        .id;
    (db, phone, id)
}

/// A robot's plan request through the bindings: seed 3, no time or memory limit.
fn robot_request(
    building_id: i64,
    (start, end): (&str, &str),
    budget_m: f64,
    algorithm: PlanAlgorithm,
) -> FfiPlanRequest {
    FfiPlanRequest {
        building_id,
        start: start.into(),
        end: end.into(),
        budget_m,
        surveyor: default_robot_profile(),
        algorithm,
        seed: 3,
        time_limit_s: None,
        memory_budget_mb: None,
    }
}

#[test]
fn a_survey_walked_on_a_phone_reaches_the_desktop_and_steers_the_next_plan() {
    let dir = tempfile::tempdir().expect("tempdir");
    // The phone imports the demo building and plans through the bindings.
    let (phone_db, phone, bid) = phone_with_demo(&dir);
    let building = trailprint::Building::from_json(&demo_json(), "demo").expect("demo");
    let (start, end) = (
        building.vertices[0].id.clone(),
        building.vertices[5].id.clone(),
    );
    let job = phone.clone().new_plan(robot_request(
        bid,
        (&start, &end),
        25.0,
        PlanAlgorithm::Genetic,
    ));
    let planned = job.run(None).expect("plan");
    assert_eq!(planned.walk.first(), Some(&start));
    assert!(planned.length_m <= 25.0 + 1e-9);

    // The robot walks the first part of the plan, scanning as it goes.
    let session = phone
        .clone()
        .start_session(planned.id, default_robot_profile(), None)
        .expect("session");
    let sid = session.id();
    let mut t = 1_700_000_000_000i64;
    for (i, v) in planned.walk.iter().take(4).enumerate() {
        let vid = building.vertex_index(v).expect("vertex");
        let p = building.vertices[vid].pos;
        t += 1_000;
        session.robot_pose(t, p.x, p.y, p.floor).expect("pose");
        session
            .scan(
                t + 10,
                vec![WifiReading {
                    bssid: "ap-01".into(),
                    rss_dbm: -50.0 - i as f64,
                }],
            )
            .expect("scan");
    }
    let collected_before_kill = session.samples().len();
    assert!(collected_before_kill >= 4);
    drop(session);
    drop(job);
    drop(phone);

    // The app was killed; a fresh store object resumes exactly where it was.
    let phone = TrailprintStore::open(phone_db.clone()).expect("reopen");
    let session = phone.clone().resume_session(sid).expect("resume");
    assert_eq!(session.samples().len(), collected_before_kill);
    session.finish(t + 5_000).expect("finish");

    // Export from the phone (core store on the same file), merge on the desktop.
    let phone_core = Store::open(&phone_db).expect("core store");
    let bundle = phone_core
        .export_bundle(
            BuildingRef::Id(bid),
            &trailprint::store::ExportOptions::default(),
        )
        .expect("bundle");
    let desk = Store::open(dir.path().join("desk.db")).expect("desk");
    let r = desk.import_bundle(&bundle, "phone.json").expect("import");
    assert!(r.building_created);
    assert_eq!(r.sessions_added, 1);
    let collected = desk
        .list_collected(BuildingRef::Name(&building.name), None)
        .expect("collected");
    assert_eq!(collected.len(), collected_before_kill);

    // The desktop plans the next walk conditioned on what was collected: the same request
    // is now worth less (the data is no longer thin where the phone walked).
    let kernel = trailprint::gp::fit_kernel(&building.pilot)
        .expect("fit")
        .kernel;
    let bld = Arc::new(
        desk.get_building(BuildingRef::Name(&building.name))
            .expect("building"),
    );
    let mut req = PlanRequest::new(&start, &end, 25.0, kernel);
    req.settings.algorithm = trailprint::plan::Algorithm::Genetic;
    req.settings.seed = 3;
    let prior = desk
        .collected_observations(BuildingRef::Name(&building.name), &kernel)
        .expect("prior");
    assert_eq!(prior.len(), collected_before_kill);
    let fresh = plan(bld.clone(), &req, &trailprint::plan::Control::new()).expect("plan");
    let informed =
        plan_with_prior(bld, &req, &prior, &trailprint::plan::Control::new()).expect("plan");
    let engine = trailprint::utility::UtilityEngine::new(
        Arc::new(building.clone()),
        kernel,
        trailprint::surveyor::Surveyor::robot(),
    )
    .expect("engine");
    let with_prior = trailprint::utility::UtilityEngine::with_prior(
        Arc::new(building),
        kernel,
        trailprint::surveyor::Surveyor::robot(),
        &prior,
    )
    .expect("engine");
    let gain =
        |w: &[usize]| with_prior.utility(w).expect("u") - with_prior.prior_utility().expect("u");
    // The walk planned with the prior adds at least as much on top of the collected data
    // as the walk planned without it.
    assert!(gain(&informed.walk_indices) >= gain(&fresh.walk_indices) - 1e-9);
    let fresh_worth = engine.utility(&fresh.walk_indices).expect("u");
    assert!(fresh_worth > 0.0);
    // The next plan is worth less: what the informed walk adds on top of the collected
    // data is less than the fresh walk was worth without it.
    let informed_worth = gain(&informed.walk_indices);
    assert!(
        informed_worth < fresh_worth,
        "informed walk adds {informed_worth} nats, fresh walk was worth {fresh_worth}"
    );
    // The planners report exact values: the fresh plan its f_D, the informed plan
    // f_{D + collected} of its walk (the collected data counts; subtracting the collected
    // data's own value leaves what the walk adds).
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1.0);
    assert!(
        close(fresh.utility_nats, fresh_worth),
        "fresh report {}",
        fresh.utility_nats
    );
    let informed_total = with_prior.utility(&informed.walk_indices).expect("u");
    assert!(
        close(informed.utility_nats, informed_total),
        "informed report {} vs exact {informed_total}",
        informed.utility_nats
    );
    assert!(informed.utility_nats - with_prior.prior_utility().expect("u") < fresh.utility_nats);
}

/// The phone and the command line plan a stored building with one kernel (issue 15): the
/// phone's first plan fits and records the kernel, and the core call the command line
/// makes (`Store::plan_and_save`) on the same database takes that stored fit.
#[test]
fn the_phone_and_the_command_line_plan_one_building_with_one_kernel() {
    use trailprint::store::{KernelSource, StorePlanRequest};
    let dir = tempfile::tempdir().expect("tempdir");
    let (db, phone, bid) = phone_with_demo(&dir);
    let request = robot_request(bid, ("f0-c00", "f0-r5-door"), 30.0, PlanAlgorithm::Greedy);
    let on_phone = phone.clone().new_plan(request).run(None).expect("plan");
    let desk = Store::open(&db).expect("core store");
    let on_desk = desk
        .plan_and_save(
            bid,
            &StorePlanRequest {
                route: trailprint::team::SurveyorTask {
                    start: "f0-c00".into(),
                    end: "f0-r5-door".into(),
                    budget: 30.0,
                },
                settings: trailprint::plan::PlanSettings {
                    algorithm: trailprint::plan::Algorithm::Greedy,
                    seed: 3,
                    ..Default::default()
                },
                kernel: None,
            },
            &trailprint::plan::Control::new(),
        )
        .expect("plan");
    assert!(matches!(
        on_desk.kernel.source,
        KernelSource::StoredFit { .. }
    ));
    let k = on_desk.kernel.kernel;
    assert_eq!(
        (
            on_phone.kernel.sf2,
            on_phone.kernel.ell,
            on_phone.kernel.sn2
        ),
        (k.sf2, k.ell, k.sn2)
    );
    assert_eq!(on_phone.walk, on_desk.result.walk);
    assert_eq!(desk.building_info(bid).expect("info").fits, 1);
}
