//! Survey sessions through the public API on a file-backed store, with plans from the
//! planners: exact robot walks, replans, off-route detection, rejected events, replay speed.

use std::sync::Arc;
use std::time::Instant;

use trailprint::building::Building;
use trailprint::gp::{Kernel, fit_kernel};
use trailprint::plan::{Algorithm, Control, PlanRequest, PlanSettings, plan};
use trailprint::session::replan::distances_from;
use trailprint::session::sim::{SimOptions, World, simulate};
use trailprint::session::{
    Event, GreedyReplanner, MemoryLog, PlanData, PlannerReplanner, Reading, Session, SessionLog,
    SessionOptions, Surveyor,
};
use trailprint::store::{
    BuildingRef, ImportOptions, PlanRecord, SessionEvent, Store, collected_csv, now_ms,
};
use trailprint::synth::DEMO_BUILDING_JSON;

fn demo() -> Building {
    Building::from_json(DEMO_BUILDING_JSON, "demo").expect("demo building")
}

/// A file store holding the demo building and a plan for `surveyor`.
fn planned(
    dir: &tempfile::TempDir,
    surveyor: Surveyor,
    budget: f64,
    algorithm: Algorithm,
) -> (Arc<Store>, i64, Kernel) {
    let store = Arc::new(Store::open(dir.path().join("t.db")).expect("store"));
    let b = demo();
    let bid = store
        .import_building(&b, Some("demo"), &ImportOptions::default())
        .expect("import")
        .id;
    let kernel = fit_kernel(&b.pilot).expect("fit").kernel;
    let settings = PlanSettings {
        model: surveyor,
        algorithm,
        seed: 7,
        time_limit: Some(std::time::Duration::from_millis(500)),
        ..PlanSettings::default()
    };
    let req = PlanRequest::with_settings("f0-c00", "f0-r5-door", budget, kernel, &settings);
    let res = plan(Arc::new(b), &req, &Control::new()).expect("plan");
    let pid = store
        .save_plan(
            BuildingRef::Id(bid),
            &PlanRecord::from_plan(&req, &res, now_ms()),
        )
        .expect("save plan");
    (store, pid, kernel)
}

fn count(store: &Store, table: &str) -> i64 {
    store
        .with_connection(|c| {
            Ok(c.query_row(&format!("SELECT count(*) FROM {table}"), [], |r| r.get(0))?)
        })
        .expect("count")
}

#[test]
fn a_robot_walking_the_plan_exactly_collects_the_planned_utility() {
    let dir = tempfile::tempdir().expect("dir");
    let (store, pid, kernel) = planned(&dir, Surveyor::robot(), 50.0, Algorithm::Auto);
    let plan = store.load_plan(pid).expect("plan");
    let log: Arc<dyn SessionLog> = store.clone();
    let mut s =
        Session::start(log, pid, Surveyor::robot(), SessionOptions::default()).expect("start");
    // The session's planned utility is the planner's.
    let rel = (s.planned_utility() - plan.record.utility_nats).abs() / plan.record.utility_nats;
    assert!(
        rel < 1e-9,
        "{} vs {}",
        s.planned_utility(),
        plan.record.utility_nats
    );
    let world = World::for_building(s.building(), &kernel, 1).expect("world");
    let (sum, rep) =
        simulate(&mut s, &world, &SimOptions::default(), |_, _, _| Ok(())).expect("simulate");
    assert_eq!(
        (rep.wrong_turns, sum.off_route_events, sum.replans),
        (0, 0, 0)
    );
    assert_eq!(sum.samples, plan.record.samples);
    let rel =
        (sum.collected_utility_nats - sum.planned_utility_nats).abs() / sum.planned_utility_nats;
    assert!(rel < 1e-6, "collected {sum:?}");
    assert!((sum.walked_m - plan.record.length_m).abs() < 1e-6);
    // Every scan is in the store with its position, ready for export.
    let list = store
        .list_collected(BuildingRef::Id(plan.building_id), Some(s.id()))
        .expect("collected");
    assert_eq!(list.len() as u64, sum.samples);
    assert_eq!(collected_csv(&list).lines().count() as u64, sum.samples + 1);
}

#[test]
fn replanned_walks_start_at_the_current_vertex_and_fit_the_budget_left() {
    let dir = tempfile::tempdir().expect("dir");
    let (store, pid, kernel) = planned(&dir, Surveyor::human(), 90.0, Algorithm::Auto);
    let mut replans = 0;
    for (seed, replanner) in [
        (3u64, None),
        (4, None),
        (5, Some(PlannerReplanner::new(Algorithm::Greedy))),
    ] {
        let log: Arc<dyn SessionLog> = store.clone();
        let mut s =
            Session::start(log, pid, Surveyor::human(), SessionOptions::default()).expect("start");
        if let Some(r) = replanner {
            s.set_replanner(Arc::new(r));
        }
        let world = World::for_building(s.building(), &kernel, seed).expect("world");
        let opts = SimOptions {
            deviate: 0.3,
            seed,
            ..SimOptions::default()
        };
        // Before each automatic replan: where it must start and the budget it has.
        let mut expected = Vec::new();
        simulate(&mut s, &world, &opts, |sess, ev, ack| {
            if let (Some(_), Event::CheckIn { vertex, .. }) = (ack.replan_seq, ev) {
                expected.push((ack.replan_seq, vertex.clone()));
            }
            let _ = sess;
            Ok(())
        })
        .expect("simulate");
        let events = SessionLog::events(&*store, s.id()).expect("events");
        for (seq, vertex) in expected {
            let e = events
                .iter()
                .find(|e| Some(e.seq) == seq)
                .expect("replan event");
            let SessionEvent::Replan { plan_id } = e.event else {
                panic!("event {seq:?} is not a replan");
            };
            let p = store.load_plan(plan_id).expect("replan plan").record;
            assert_eq!(
                p.start, vertex,
                "the replan starts where the surveyor checked in"
            );
            assert_eq!(p.walk.first(), Some(&vertex));
            assert_eq!(p.end, "f0-r5-door");
            let b = s.building();
            let walk = b.resolve_walk(&p.walk).expect("a walk of the building");
            let len = b.walk_length(&walk);
            // Replay the log up to the check-in: the budget left then.
            let before = Session::replay_to(store.clone(), s.id(), e.seq - 1).expect("replay");
            let (origin, left) = before
                .tracker()
                .replan_origin(b)
                .expect("origin before the replan");
            assert_eq!(b.vertices[origin].id, vertex);
            // The plan's budget is what was left less the reserve kept for wrong turns.
            let after = Session::replay_to(store.clone(), s.id(), e.seq).expect("replay");
            assert!(after.reserve_m() >= 0.0);
            assert!((p.budget_m + after.reserve_m() - left.max(0.0)).abs() < 1e-9);
            let shortest = distances_from(b, walk[walk.len() - 1])[walk[0]];
            assert!(
                len <= left + 1e-9 || (shortest > left && (len - shortest).abs() < 1e-9),
                "a {len} m walk for {left} m left (shortest {shortest} m)"
            );
            if len <= left + 1e-9 {
                replans += 1;
            }
        }
    }
    assert!(replans >= 3, "only {replans} replans fitted their budget");
}

#[test]
fn a_robot_taking_a_wrong_turn_is_off_route() {
    let b = Arc::new(
        Building::from_json(
            r#"{"format":"survey-building/1","name":"T",
            "vertices":[{"id":"a","x":0,"y":0},{"id":"b","x":5,"y":0},{"id":"c","x":10,"y":0},
              {"id":"d","x":5,"y":6},{"id":"e","x":10,"y":6}],
            "edges":[{"a":"a","b":"b"},{"a":"b","b":"c"},{"a":"c","b":"e"},{"a":"b","b":"d"},
              {"a":"d","b":"e"}]}"#,
            "t",
        )
        .expect("building"),
    );
    let log = Arc::new(MemoryLog::new());
    let bid = log.add_building(b.clone());
    let k = Kernel::new(20.0, 5.0, 2.0);
    let pid = log
        .save_plan(&PlanData::for_walk(
            bid,
            &["a", "b", "c", "e"],
            40.0,
            k,
            15.0,
        ))
        .expect("plan");
    let options = SessionOptions {
        auto_replan: false,
        ..SessionOptions::default()
    };
    let mut s = Session::start(log.clone(), pid, Surveyor::robot(), options).expect("start");
    let mut t = 0;
    let mut pose = |s: &mut Session, x: f64, y: f64| {
        t += 1000;
        s.record(Event::Pose {
            t_ms: t,
            x,
            y,
            floor: 0,
        })
        .expect("pose")
    };
    for i in 0..=10 {
        assert!(!pose(&mut s, 0.5 * f64::from(i), 0.0).off_route);
    }
    // At b the plan goes on east; the robot turns north towards d.
    assert!(!pose(&mut s, 5.0, 1.0).off_route, "within the tolerance");
    let ack = pose(&mut s, 5.0, 2.0);
    assert!(ack.off_route && ack.went_off_route);
    assert!(s.guidance().message.starts_with("Off route at b"));
    // Back on the walk, it is on-route again; the off-route event stays counted.
    assert!(!pose(&mut s, 5.0, 0.0).off_route);
    assert!(!pose(&mut s, 7.0, 0.0).off_route);
    assert_eq!(s.tracker().off_route_events(), 1);
    let g = s.guidance();
    assert_eq!(g.next_vertex.as_deref(), Some("c"));
    assert!((g.distance_m - 3.0).abs() < 1e-12);
}

#[test]
fn rejected_events_write_nothing_to_the_store() {
    let dir = tempfile::tempdir().expect("dir");
    let (store, pid, _) = planned(&dir, Surveyor::human(), 40.0, Algorithm::Auto);
    let log: Arc<dyn SessionLog> = store.clone();
    let mut s =
        Session::start(log, pid, Surveyor::human(), SessionOptions::default()).expect("start");
    s.record(Event::Step {
        t_ms: 10_000,
        steps: 1,
    })
    .expect("step");
    let scan = |rss: f64| Event::Scan {
        t_ms: 10_500,
        readings: vec![
            Reading {
                bssid: "02:00:00:00:00:01".into(),
                rss_dbm: -70.0,
            },
            Reading {
                bssid: "02:00:00:00:00:02".into(),
                rss_dbm: rss,
            },
        ],
    };
    let tables = [
        "session_events",
        "collected_fingerprints",
        "collected_readings",
    ];
    let snapshot = |s: &Session| (tables.map(|t| count(&store, t)), s.digest());
    let before = snapshot(&s);
    for (ev, want) in [
        (
            Event::Step {
                t_ms: 9_999,
                steps: 1,
            },
            "goes back in time",
        ),
        (
            Event::CheckIn {
                t_ms: 10_500,
                vertex: "nowhere".into(),
            },
            "unknown vertex \"nowhere\"",
        ),
        (scan(f64::NAN), "got NaN"),
        (scan(1.0), "[-120, 0], got 1"),
        (scan(-130.0), "got -130"),
    ] {
        let e = s.record(ev).expect_err("rejected");
        assert!(e.to_string().contains(want), "{e}");
        assert_eq!(snapshot(&s), before);
    }
    let sum = s.finish(11_000).expect("finish");
    assert_eq!(sum.steps, 1);
    let after_finish = snapshot(&s);
    let e = s.record(scan(-60.0)).expect_err("after finish");
    assert!(e.to_string().contains("finished"), "{e}");
    assert_eq!(snapshot(&s), after_finish);
}

#[test]
fn sessions_are_send_and_replay_is_fast() {
    fn send<T: Send>() {}
    send::<Session>();
    let b = Arc::new(demo());
    let kernel = fit_kernel(&b.pilot).expect("fit").kernel;
    let log = Arc::new(MemoryLog::new());
    let bid = log.add_building(b.clone());
    let walk = trailprint::session::Replanner::replan(
        &GreedyReplanner,
        &trailprint::session::ReplanRequest {
            building: &b,
            kernel,
            model: Surveyor::robot(),
            prior: &[],
            start: 0,
            end: b.len() - 1,
            budget_m: 150.0,
            seed: 1,
            memory_budget: trailprint::plan::PlanSettings::default().memory_budget,
        },
    )
    .expect("plan");
    let ids = b.walk_ids(&walk);
    let ids: Vec<&str> = ids.iter().map(String::as_str).collect();
    let pid = log
        .save_plan(&PlanData::for_walk(
            bid,
            &ids,
            150.0,
            kernel,
            b.walk_length(&walk),
        ))
        .expect("plan");
    let mut s = Session::start(
        log.clone(),
        pid,
        Surveyor::robot(),
        SessionOptions::default(),
    )
    .expect("start");
    let world = World::for_building(&b, &kernel, 1).expect("world");
    let opts = SimOptions {
        deviate: 0.1,
        ..SimOptions::default()
    };
    simulate(&mut s, &world, &opts, |_, _, _| Ok(())).expect("simulate");
    let n = s.last_seq();
    let started = Instant::now();
    let r = Session::resume(log, s.id()).expect("resume");
    let replay = started.elapsed();
    assert_eq!(r.digest(), s.digest());
    let started = Instant::now();
    let p = r.progress().expect("progress");
    let progress = started.elapsed();
    eprintln!(
        "replay of {n} events ({} samples): {:.1} ms; progress(): {:.1} ms",
        p.samples,
        replay.as_secs_f64() * 1e3,
        progress.as_secs_f64() * 1e3
    );
    assert!(n > 400);
    assert!(replay.as_secs_f64() < 2.0);
    assert_eq!(p.uncertainty.len(), b.len());
}
