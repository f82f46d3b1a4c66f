use std::sync::Arc;

use super::sim::{SimOptions, SimReport, World, simulate};
use super::*;
use crate::store::BuildingRef;
use crate::synth::DEMO_BUILDING_JSON;

// a(0,0) - b(5,0) - c(10,0) - e(10,5) ; b - d(5,5) ; d - e ; c - f(15,0)
fn tee() -> Building {
    Building::from_json(
        r#"{"format":"survey-building/1","name":"T",
        "vertices":[{"id":"a","x":0,"y":0},{"id":"b","x":5,"y":0,"label":"Lobby"},
          {"id":"c","x":10,"y":0},{"id":"d","x":5,"y":5},{"id":"e","x":10,"y":5},
          {"id":"f","x":15,"y":0}],
        "edges":[{"a":"a","b":"b"},{"a":"b","b":"c"},{"a":"c","b":"e"},{"a":"b","b":"d"},
          {"a":"d","b":"e"},{"a":"c","b":"f"}],
        "pilot":[{"x":0,"y":0},{"x":10,"y":5}]}"#,
        "tee",
    )
    .expect("valid")
}

fn kernel() -> Kernel {
    Kernel::new(20.0, 5.0, 2.0)
}

/// The walk every tee session plans: a, b, c, then the left turn to e.
const WALK: [&str; 4] = ["a", "b", "c", "e"];

/// Adds the tee to `log` and saves the plan that walks [`WALK`] within `budget`.
fn save_tee_plan(log: &MemoryLog, budget: f64) -> i64 {
    let b = Arc::new(tee());
    let bid = log.add_building(b.clone());
    let ids = b.resolve_walk(&WALK).expect("walk");
    log.save_plan(&PlanData::for_walk(
        bid,
        &WALK,
        budget,
        kernel(),
        b.walk_length(&ids),
    ))
    .expect("plan")
}

/// A session on the tee that walks [`WALK`] within `budget`, with the default options.
fn setup(budget: f64, surveyor: Surveyor) -> (Arc<MemoryLog>, Session) {
    let log = Arc::new(MemoryLog::new());
    let plan = save_tee_plan(&log, budget);
    let s = Session::start(log.clone(), plan, surveyor, SessionOptions::default()).expect("start");
    (log, s)
}

fn steps(s: &mut Session, t0: i64, n: u32) -> i64 {
    for i in 0..n {
        s.record(Event::Step {
            t_ms: t0 + i64::from(i) * 500,
            steps: 1,
        })
        .expect("step");
    }
    t0 + i64::from(n) * 500
}

fn check_in(s: &mut Session, t_ms: i64, vertex: &str) -> Result<Ack> {
    s.record(Event::CheckIn {
        t_ms,
        vertex: vertex.into(),
    })
}

/// A scan event: one reading a `(bssid, rss_dbm)` pair.
fn scan(t_ms: i64, readings: &[(&str, f64)]) -> Event {
    Event::Scan {
        t_ms,
        readings: readings
            .iter()
            .map(|&(bssid, rss_dbm)| Reading {
                bssid: bssid.into(),
                rss_dbm,
            })
            .collect(),
    }
}

fn human_exact_step(l: f64) -> Surveyor {
    match Surveyor::human() {
        Surveyor::Human {
            speed_mps,
            scan_interval_s,
            step_error,
            turn_threshold_deg,
            ..
        } => Surveyor::Human {
            step_length_m: l,
            speed_mps,
            scan_interval_s,
            step_error,
            turn_threshold_deg,
        },
        r => r,
    }
}

#[test]
fn guidance_names_turns_and_check_ins() {
    let (_, mut s) = setup(30.0, human_exact_step(1.0));
    let g = s.guidance();
    // b is straight on (no check-in); the next check-in is c, where the walk turns left.
    assert_eq!(g.next_vertex.as_deref(), Some("b"));
    assert_eq!(g.next_label.as_deref(), Some("Lobby"));
    assert_eq!(g.turn, Turn::Straight);
    assert!(!g.check_in_at_next);
    assert_eq!(g.next_check_in.as_deref(), Some("c"));
    assert!((g.distance_to_check_in_m - 10.0).abs() < 1e-12);
    let t = steps(&mut s, 0, 7);
    let g = s.guidance();
    assert_eq!(g.next_vertex.as_deref(), Some("c"));
    assert_eq!(g.turn, Turn::Left);
    assert!(g.check_in_at_next);
    assert!((g.distance_m - 3.0).abs() < 1e-12);
    // Walking more than due holds the estimate at c.
    let t = steps(&mut s, t, 4);
    let g = s.guidance();
    assert_eq!(g.next_vertex.as_deref(), Some("c"));
    assert_eq!(g.distance_m, 0.0);
    let ack = check_in(&mut s, t, "c").expect("check in");
    assert!(!ack.off_route);
    assert_eq!(ack.position.x, 10.0);
    let g = s.guidance();
    assert_eq!(g.next_vertex.as_deref(), Some("e"));
    assert_eq!(g.turn, Turn::Arrive);
    // 11 steps for 10 m: (20 * 1.0 + 10) / (20 + 10.5).
    assert!((s.tracker().step_length_m() - 30.0 / 30.5).abs() < 1e-12);
}

#[test]
fn scans_get_dead_reckoned_positions_and_label_noise() {
    let (_, mut s) = setup(30.0, human_exact_step(0.5));
    let t = steps(&mut s, 0, 13);
    let ack = s.record(scan(t, &[("ap", -60.0)])).expect("scan");
    let smp = ack.sample.expect("sample");
    assert!((smp.position.x - 6.5).abs() < 1e-12 && smp.position.y == 0.0);
    assert_eq!(smp.since_checkin_m, Some(6.5));
    assert!((smp.sigma_m - 0.05 * 6.5).abs() < 1e-12);
    assert!((smp.extra_noise - kernel().label_noise(0.05 * 6.5)).abs() < 1e-15);
}

#[test]
fn wrong_turn_is_off_route_and_replans_from_there_within_budget() {
    let (_, mut s) = setup(30.0, human_exact_step(1.0));
    let t = steps(&mut s, 0, 5);
    // At b the walk goes straight to c; the surveyor turns to d and checks in there.
    let t = steps(&mut s, t, 5);
    let walked_before = s.tracker().walked_m();
    let ack = check_in(&mut s, t, "d").expect("check in");
    assert!(ack.went_off_route);
    let replan = ack.replan_seq.expect("replanned");
    assert_eq!(replan, ack.seq + 1);
    assert!(!ack.off_route, "the replan put the surveyor back on a walk");
    assert_eq!(s.tracker().off_route_events(), 1);
    let route = s.tracker().route();
    let b = s.building().clone();
    assert_eq!(b.vertices[route[0]].id, "d");
    assert_eq!(b.vertices[*route.last().expect("end")].id, "e");
    assert!(b.walk_length(route) <= 30.0 - walked_before + 1e-9);
    assert_eq!(walked_before, 10.0);
}

#[test]
fn manual_replan_starts_at_the_vertex_ahead_and_fits_the_budget_left() {
    let (_, mut s) = setup(40.0, human_exact_step(1.0));
    // 3 m along a-b: the replan starts at b, 2 m ahead.
    let t = steps(&mut s, 0, 3);
    s.record(scan(t, &[])).expect("scan");
    let (origin, left) = s.tracker().replan_origin(s.building()).expect("origin");
    assert_eq!(s.building().vertices[origin].id, "b");
    assert!((left - (40.0 - 3.0 - 2.0)).abs() < 1e-12);
    let out = s.replan().expect("replan");
    assert_eq!(out.from_vertex, "b");
    assert_eq!(out.walk.last().map(String::as_str), Some("e"));
    assert!(out.length_m <= 35.0 + 1e-9);
    assert!(!out.over_budget);
    // The walked part stays: the route now starts at the last check-in, a.
    assert_eq!(s.building().vertices[s.tracker().route()[0]].id, "a");
    assert_eq!(s.samples().len(), 1);
    assert_eq!(s.tracker().walked_m(), 3.0);
    assert_eq!(s.guidance().next_vertex.as_deref(), Some("b"));
}

#[test]
fn walking_far_past_the_due_check_in_is_off_route() {
    let (_, mut s) = setup(30.0, human_exact_step(1.0));
    // Due at c after 10 m; slack 3 m + 25% of 10 m.
    let t = steps(&mut s, 0, 15);
    assert!(!s.tracker().off_route());
    s.record(Event::Step { t_ms: t, steps: 1 }).expect("step");
    assert!(s.tracker().off_route());
    assert!(s.guidance().message.contains("check in"));
    assert!(s.replan().is_err(), "position unknown");
    // Checking in back on the walk puts the surveyor on-route again.
    let ack = check_in(&mut s, t + 10, "c").expect("check in");
    assert!(!ack.off_route);
    assert_eq!(s.tracker().off_route_events(), 1);
}

#[test]
fn bad_events_are_rejected_and_write_nothing() {
    let (log, mut s) = setup(30.0, Surveyor::human());
    s.record(Event::Step {
        t_ms: 1000,
        steps: 1,
    })
    .expect("step");
    let id = s.id();
    let before = (log.events(id).expect("events").len(), s.digest());
    let scan_rss = |rss: f64| scan(2000, &[("aa:bb", rss)]);
    let cases: Vec<(Event, &str)> = vec![
        (
            Event::Step {
                t_ms: 999,
                steps: 1,
            },
            "goes back in time",
        ),
        (
            Event::CheckIn {
                t_ms: 2000,
                vertex: "zz".into(),
            },
            "unknown vertex \"zz\"",
        ),
        (scan_rss(f64::NAN), "NaN"),
        (scan_rss(3.0), "got 3"),
        (scan_rss(-121.0), "got -121"),
        (scan_rss(f64::INFINITY), "finite"),
        (
            Event::Step {
                t_ms: 2000,
                steps: 0,
            },
            "1 to",
        ),
        (
            Event::Pose {
                t_ms: 2000,
                x: 0.0,
                y: 0.0,
                floor: 0,
            },
            "pose events are for robots",
        ),
        (Event::Resume { t_ms: 2000 }, "not paused"),
    ];
    for (ev, want) in cases {
        let e = s.record(ev.clone()).expect_err("must be rejected");
        let msg = e.to_string();
        assert!(msg.contains(want), "{ev:?}: {msg}");
        assert!(msg.starts_with(&format!("session {id}:")), "{msg}");
        assert_eq!(
            (log.events(id).expect("events").len(), s.digest()),
            before,
            "{ev:?} changed something"
        );
    }
    s.record(Event::Pause { t_ms: 3000 }).expect("pause");
    let e = s
        .record(Event::Step {
            t_ms: 3500,
            steps: 1,
        })
        .expect_err("paused");
    assert!(e.to_string().contains("paused"));
    s.record(Event::Resume { t_ms: 5000 }).expect("resume");
    s.finish(6000).expect("finish");
    let n = log.events(id).expect("events").len();
    for ev in [
        Event::Step {
            t_ms: 7000,
            steps: 1,
        },
        Event::Finish { t_ms: 7000 },
        Event::Abort {
            t_ms: 7000,
            reason: None,
        },
    ] {
        let e = s.record(ev).expect_err("after finish");
        assert!(e.to_string().contains("finished"), "{e}");
    }
    assert_eq!(log.events(id).expect("events").len(), n);
    // Pauses do not count as active time: 1 s..3 s and 5 s..6 s.
    assert_eq!(s.tracker().elapsed_ms(), 3000);
}

fn demo_session(surveyor: Surveyor, budget: f64) -> (Arc<MemoryLog>, Session) {
    demo_session_with(surveyor, budget, SessionOptions::default())
}

fn demo_session_with(
    surveyor: Surveyor,
    budget: f64,
    options: SessionOptions,
) -> (Arc<MemoryLog>, Session) {
    let b = Arc::new(Building::from_json(DEMO_BUILDING_JSON, "demo").expect("demo"));
    let k = crate::gp::fit_kernel(&b.pilot).expect("fit").kernel;
    let log = Arc::new(MemoryLog::new());
    let bid = log.add_building(b.clone());
    let start = 0;
    let end = b.len() - 1;
    let walk = GreedyReplanner
        .replan(&ReplanRequest {
            building: &b,
            kernel: k,
            model: surveyor,
            prior: &[],
            start,
            end,
            budget_m: budget,
            seed: 1,
            memory_budget: SessionOptions::default().memory_budget_mb << 20,
        })
        .expect("plan");
    let ids = b.walk_ids(&walk);
    let idr: Vec<&str> = ids.iter().map(String::as_str).collect();
    let plan = log
        .save_plan(&PlanData::for_walk(
            bid,
            &idr,
            budget,
            k,
            b.walk_length(&walk),
        ))
        .expect("save");
    let s = Session::start(log.clone(), plan, surveyor, options).expect("start");
    (log, s)
}

/// Simulator options that take a wrong turn with probability `deviate`, seed 5.
fn deviating(deviate: f64) -> SimOptions {
    SimOptions {
        deviate,
        seed: 5,
        ..SimOptions::default()
    }
}

/// Simulates `surveyor` walking the demo plan within `budget` (world seed 3) to the end,
/// with `on_ack` called after every acknowledged event.
fn simulate_demo<F>(
    surveyor: Surveyor,
    budget: f64,
    opts: &SimOptions,
    on_ack: F,
) -> (Arc<MemoryLog>, Session, Summary, SimReport)
where
    F: FnMut(&Session, &Event, &Ack) -> Result<()>,
{
    let (log, mut s) = demo_session(surveyor, budget);
    let world = World::for_building(s.building(), &kernel(), 3).expect("world");
    let (sum, rep) = simulate(&mut s, &world, opts, on_ack).expect("sim");
    (log, s, sum, rep)
}

/// A robot that walks the demo plan within `budget` exactly, to the end.
fn robot_walks_demo_plan(budget: f64) -> (Session, Summary, SimReport) {
    let (_, s, sum, rep) = simulate_demo(
        Surveyor::robot(),
        budget,
        &SimOptions::default(),
        |_, _, _| Ok(()),
    );
    (s, sum, rep)
}

/// How far the collected utility is from the planned, relative to the planned.
fn utility_gap(sum: &Summary) -> f64 {
    (sum.collected_utility_nats - sum.planned_utility_nats).abs() / sum.planned_utility_nats
}

#[test]
fn a_robot_walking_the_plan_exactly_collects_the_planned_utility() {
    let (s, sum, rep) = robot_walks_demo_plan(60.0);
    assert_eq!(rep.wrong_turns, 0);
    assert_eq!(sum.off_route_events, 0);
    assert_eq!(sum.replans, 0);
    assert!(utility_gap(&sum) < 1e-6, "{sum:?}");
    assert!(sum.planned_utility_nats > 1.0);
    // Progress follows the walk: every metre of it, corners included.
    let len = s.building().walk_length(s.tracker().route());
    assert!(
        (sum.walked_m - len).abs() < 1e-6,
        "{} vs {len}",
        sum.walked_m
    );
}

#[test]
fn replay_reproduces_the_live_state_event_by_event() {
    for (surveyor, deviate) in [(Surveyor::human(), 0.3), (Surveyor::robot(), 0.2)] {
        let mut digests = std::collections::BTreeMap::new();
        let (log, s, sum, rep) =
            simulate_demo(surveyor, 80.0, &deviating(deviate), |sess, _, ack| {
                digests.insert(ack.last_seq(), sess.digest());
                Ok(())
            });
        assert!(rep.wrong_turns > 0, "{rep:?}");
        assert!(sum.off_route_events > 0 && sum.replans > 0, "{sum:?}");
        let r = Session::resume(log.clone(), s.id()).expect("resume");
        assert_eq!(r.digest(), s.digest());
        assert_eq!(r.summary().expect("summary"), sum);
        // Every acknowledged state is what replaying the log up to there gives.
        for (&seq, d) in &digests {
            let r = Session::replay_to(log.clone(), s.id(), seq).expect("replay");
            assert_eq!(&r.digest(), d, "state after event {seq}");
        }
    }
}

#[test]
fn on_the_store_events_persist_resume_and_export() {
    use crate::store::{ImportOptions, PlanRecord, Store, collected_csv};
    let store = Arc::new(Store::open_in_memory().expect("store"));
    let b = tee();
    let rep = store
        .import_building(&b, Some("tee"), &ImportOptions::default())
        .expect("import");
    let _ = rep;
    let ids = b.resolve_walk(&WALK).expect("walk");
    let plan = store
        .save_plan(
            BuildingRef::Name("T"),
            &PlanRecord {
                start: "a".into(),
                end: "e".into(),
                budget_m: 30.0,
                surveyor: None,
                kernel: kernel(),
                algorithm: crate::plan::PlanOrigin::Given,
                seed: None,
                walk: WALK.iter().map(|s| s.to_string()).collect(),
                length_m: b.walk_length(&ids),
                samples: 0,
                utility_nats: 0.0,
                elapsed_ms: 0,
                created_ms: 0,
            },
        )
        .expect("plan");
    let log: Arc<dyn SessionLog> = store.clone();
    let mut s = Session::start(
        log.clone(),
        plan,
        human_exact_step(1.0),
        SessionOptions::default(),
    )
    .expect("start");
    let t = steps(&mut s, 0, 4);
    s.record(scan(t, &[("aa:01", -61.5), ("aa:02", -80.0)]))
        .expect("scan");
    let t = steps(&mut s, t, 6);
    // A wrong turn at b: off-route at d, replanned from d.
    let ack = check_in(&mut s, t, "d").expect("check in");
    assert!(ack.replan_seq.is_some());
    let n = store.list_events(s.id(), 0).expect("events").len();
    assert!(s.record(scan(t, &[("x", f64::NAN)])).is_err());
    assert_eq!(store.list_events(s.id(), 0).expect("events").len(), n);
    let r = Session::resume(log.clone(), s.id()).expect("resume");
    assert_eq!(r.digest(), s.digest());
    let csv = collected_csv(
        &store
            .list_collected(BuildingRef::Name("T"), Some(s.id()))
            .expect("collected"),
    );
    assert!(
        csv.lines().nth(1).expect("row").contains(",4.0,0.0,0,"),
        "{csv}"
    );
    assert!(csv.contains("-61.5"));
}

/// Fails every replan append, as if the process died between an off-route check-in and
/// its replan.
struct DiesBeforeReplan(Arc<MemoryLog>);

impl SessionLog for DiesBeforeReplan {
    fn building(&self, id: i64) -> Result<Arc<Building>> {
        self.0.building(id)
    }
    fn load_plan(&self, id: i64) -> Result<PlanData> {
        self.0.load_plan(id)
    }
    fn save_plan(&self, plan: &PlanData) -> Result<i64> {
        self.0.save_plan(plan)
    }
    fn create_session(
        &self,
        b: i64,
        p: i64,
        settings: &serde_json::Value,
        created_ms: i64,
    ) -> Result<i64> {
        self.0.create_session(b, p, settings, created_ms)
    }
    fn session(&self, id: i64) -> Result<SessionRow> {
        self.0.session(id)
    }
    fn append(&self, id: i64, t_ms: i64, event: &SessionEvent) -> Result<i64> {
        if matches!(event, SessionEvent::Replan { .. }) {
            return Err(Error::Database {
                path: "test".into(),
                message: "killed".into(),
            });
        }
        self.0.append(id, t_ms, event)
    }
    fn events(&self, id: i64) -> Result<Vec<LogEntry>> {
        self.0.events(id)
    }
}

#[test]
fn resume_finishes_a_replan_that_a_kill_interrupted() {
    let run = |log: Arc<dyn SessionLog>, mem: &Arc<MemoryLog>| {
        let pid = save_tee_plan(mem, 30.0);
        let mut s = Session::start(log, pid, human_exact_step(1.0), SessionOptions::default())
            .expect("start");
        let t = steps(&mut s, 0, 10);
        let ack = check_in(&mut s, t, "d");
        (s, ack)
    };
    let whole = Arc::new(MemoryLog::new());
    let (live, ack) = run(whole.clone(), &whole);
    assert!(ack.expect("ack").replan_seq.is_some());
    let broken = Arc::new(MemoryLog::new());
    let (s, ack) = run(Arc::new(DiesBeforeReplan(broken.clone())), &broken);
    let ack = ack.expect("the check-in itself is recorded");
    assert!(ack.replan_seq.is_none() && ack.off_route);
    assert!(ack.replan_error.expect("why").contains("killed"));
    assert!(s.tracker().replan_due());
    let resumed = Session::resume(broken.clone(), s.id()).expect("resume");
    assert_eq!(resumed.last_seq(), live.last_seq());
    assert_eq!(resumed.digest(), live.digest());
}

/// The coverage map as the session computed it before the running posterior: a GP fitted
/// from scratch on pilot data plus samples.
fn uncertainty_from_scratch(s: &Session) -> Vec<f64> {
    use crate::gp::predict::GpModel;
    let b = s.building();
    let k = s.kernel;
    let mut train = b.pilot_points();
    let mut noise = vec![k.sn2; train.len()];
    for o in s.tracker().observations() {
        train.push(o.pos);
        noise.push(k.sn2 + o.extra_noise);
    }
    let values = nalgebra::DMatrix::zeros(train.len(), 1);
    let gp = GpModel::fit_with_noise(&k, &train, &noise, &values).expect("fit");
    gp.variance(&b.vertex_points())
        .into_iter()
        .map(|v| v.max(0.0).sqrt())
        .collect()
}

#[test]
fn incremental_progress_equals_a_from_scratch_computation() {
    for (surveyor, deviate) in [(Surveyor::human(), 0.3), (Surveyor::robot(), 0.0)] {
        let mut checked = 0;
        let mut worst: f64 = 0.0;
        let (_, s, _, _) = simulate_demo(surveyor, 80.0, &deviating(deviate), |sess, ev, _| {
            if !matches!(ev, Event::Scan { .. }) || sess.samples().len() % 3 != 1 {
                return Ok(());
            }
            let p = sess.progress()?;
            let scratch = sess.collected_utility_from_scratch()?;
            let reference = crate::utility::reference_utility(
                &sess.kernel,
                &sess.building().vertex_points(),
                &crate::utility::reference::pilot_observations(&sess.building().pilot_points())
                    .into_iter()
                    .chain(sess.tracker().observations())
                    .collect::<Vec<_>>(),
            )?;
            let rel = (p.collected_utility_nats - scratch).abs() / scratch.max(1e-300);
            assert!(
                rel < 1e-9,
                "{} vs {scratch} (rel {rel:e})",
                p.collected_utility_nats
            );
            let rel_ref = (p.collected_utility_nats - reference).abs() / reference;
            assert!(
                rel_ref < 1e-9,
                "{} vs reference {reference}",
                p.collected_utility_nats
            );
            for (u, want) in p.uncertainty.iter().zip(uncertainty_from_scratch(sess)) {
                let err = (u.std_db - want).abs();
                worst = worst.max(err);
                assert!(
                    err < 1e-7 * (1.0 + want),
                    "vertex {}: {} vs {want}",
                    u.vertex,
                    u.std_db
                );
            }
            checked += 1;
            Ok(())
        });
        assert!(checked >= 5, "checked {checked}");
        assert!(s.samples().len() > 15, "{}", s.samples().len());
        eprintln!("{checked} checks, worst std difference {worst:e} dB");
    }
}

#[test]
fn a_robot_that_follows_the_plan_gets_no_reserve_and_exactly_the_planned_utility() {
    let (s, sum, _) = robot_walks_demo_plan(80.0);
    assert_eq!(sum.replans, 0);
    assert_eq!(s.reserve_m(), 0.0);
    assert!(!s.guidance().message.contains("reserve"));
    assert!(utility_gap(&sum) < 1e-12, "{sum:?}");
}

/// A generated two-floor campus of 290 vertices (more than
/// [`replan::LARGE_REPLAN_VERTICES`]).
fn campus() -> Arc<Building> {
    use crate::synth::{SynthParams, generate};
    let params = SynthParams {
        name: "campus".into(),
        floors: 2,
        rooms_per_side: 6,
        corridor_length_m: 48.0,
        room_depth_m: 8.0,
        ..SynthParams::default()
    };
    Arc::new(
        Building::from_file(generate(&params).expect("generate").file, "campus").expect("valid"),
    )
}

/// A session replans with `auto` on a building of more than
/// [`replan::LARGE_REPLAN_VERTICES`] vertices (the session greedy takes seconds there and
/// plans short-sighted walks) and with the session greedy on a small one; either way the
/// new walk starts where the surveyor is and fits what is left.
#[test]
fn a_large_building_replans_with_auto_and_a_small_one_with_the_session_greedy() {
    use crate::plan::{Algorithm, PlanOrigin};

    let (log, mut small) = setup(40.0, Surveyor::human());
    let r = small.replan().expect("replan");
    let origin = log.load_plan(r.plan_id).expect("plan").record.algorithm;
    assert_eq!(origin, PlanOrigin::SessionGreedy);

    let b = campus();
    assert!(
        b.len() > replan::LARGE_REPLAN_VERTICES,
        "{} vertices",
        b.len()
    );
    let k = crate::gp::fit_kernel(&b.pilot).expect("fit").kernel;
    let log = Arc::new(MemoryLog::new());
    let bid = log.add_building(b.clone());
    let start = b.vertices[0].id.clone();
    let mut req = crate::plan::PlanRequest::new(&start, &start, 200.0, k);
    req.settings.algorithm = Algorithm::Coverage;
    req.settings.model = Surveyor::human();
    let planned = crate::plan::plan(b.clone(), &req, &crate::plan::Control::new()).expect("plan");
    let ids: Vec<&str> = planned.walk.iter().map(String::as_str).collect();
    let plan = log
        .save_plan(&PlanData::for_walk(bid, &ids, 200.0, k, planned.length_m))
        .expect("save");
    let mut large = Session::start(
        log.clone(),
        plan,
        Surveyor::human(),
        SessionOptions::default(),
    )
    .expect("start");
    let r = large.replan().expect("replan");
    let record = log.load_plan(r.plan_id).expect("plan").record;
    assert_eq!(record.algorithm, PlanOrigin::Planner(Algorithm::Auto));
    assert_eq!(r.from_vertex, start);
    assert!(r.length_m <= r.budget_left_m - r.reserve_m + 1e-9, "{r:?}");
    // What auto plans from the start with the whole budget is worth more than the
    // systematic walk it replaced.
    assert!(
        r.utility_nats > planned.utility_nats,
        "{r:?} against {}",
        planned.utility_nats
    );
}

#[test]
fn replans_on_one_building_share_its_metric_closure_and_plan_as_without() {
    // The replanner keeps the session's building's closure between replans; a replan
    // must give the walk a plan without it gives (same seed, a deterministic algorithm),
    // from the first replan, which builds the closure, and from those that reuse it.
    let b = Arc::new(Building::from_json(DEMO_BUILDING_JSON, "demo").expect("demo"));
    let k = crate::gp::fit_kernel(&b.pilot).expect("fit").kernel;
    let request = |start: usize, budget_m: f64| ReplanRequest {
        building: &b,
        kernel: k,
        model: Surveyor::human(),
        prior: &[],
        start,
        end: 0,
        budget_m,
        seed: 3,
        memory_budget: SessionOptions::default().memory_budget_mb << 20,
    };
    let replanner = PlannerReplanner::new(crate::plan::Algorithm::Greedy);
    for (start, budget) in [(0, 40.0), (5, 35.0), (0, 60.0)] {
        let fresh = PlannerReplanner::new(crate::plan::Algorithm::Greedy)
            .replan(&request(start, budget))
            .expect("fresh");
        let kept = replanner.replan(&request(start, budget)).expect("kept");
        assert_eq!(kept, fresh, "start {start}, budget {budget}");
    }
}

#[test]
fn a_replan_keeps_to_the_sessions_memory_budget() {
    let b = Arc::new(Building::from_json(DEMO_BUILDING_JSON, "demo").expect("demo"));
    let k = crate::gp::fit_kernel(&b.pilot).expect("fit").kernel;
    let request = |memory_budget_mb: u64| ReplanRequest {
        building: &b,
        kernel: k,
        model: Surveyor::robot(),
        prior: &[],
        start: 0,
        end: 0,
        budget_m: 20.0,
        seed: 1,
        memory_budget: memory_budget_mb << 20,
    };
    let replanner = PlannerReplanner::new(crate::plan::Algorithm::Coverage);
    let e = replanner
        .replan(&request(1))
        .expect_err("1 MiB is too little");
    assert!(
        e.to_string()
            .contains("more than the memory budget of 1 MiB"),
        "{e}"
    );
    let walk = replanner
        .replan(&request(SessionOptions::default().memory_budget_mb))
        .expect("the default holds the demo");
    assert!(b.walk_length(&walk) <= 20.0 + 1e-9);
    let zero = SessionOptions {
        memory_budget_mb: 0,
        ..SessionOptions::default()
    };
    assert!(
        zero.validate()
            .expect_err("0 MiB")
            .to_string()
            .contains("memory_budget_mb")
    );
}

/// A robot session past its memory budget (1 MiB: half of it, 512 KiB, for the running
/// posterior, about 280 observations on the demo building) keeps one sample of several,
/// says so in its progress, collects a lower bound of its samples' utility, and resumes
/// to the same figures.
#[test]
fn a_long_robot_session_keeps_to_its_memory_budget_and_says_its_figures_are_a_lower_bound() {
    let options = SessionOptions {
        memory_budget_mb: 1,
        ..SessionOptions::default()
    };
    let (log, mut s) = demo_session_with(Surveyor::robot(), 300.0, options);
    let world = World::for_building(s.building(), &kernel(), 3).expect("world");
    let mut blocks = Vec::new();
    let (sum, _) = simulate(&mut s, &world, &SimOptions::default(), |sess, _, _| {
        assert!(sess.posterior.memory_bytes() <= 1 << 19);
        let p = sess.progress()?;
        assert!(p.samples_in_figures <= p.samples);
        assert!(p.samples - p.samples_in_figures < p.sample_block.max(1));
        if blocks.last() != Some(&p.sample_block) {
            blocks.push(p.sample_block);
        }
        Ok(())
    })
    .expect("simulate");
    assert!(sum.samples > 500, "{} samples", sum.samples);
    assert_eq!(blocks.first(), Some(&1));
    assert!(
        blocks.len() >= 2 && blocks.windows(2).all(|w| w[1] == 2 * w[0]),
        "{blocks:?}"
    );
    let p = s.progress().expect("progress");
    assert_eq!(
        p.samples_in_figures, p.samples,
        "finished: every sample accounted for"
    );
    let all = s.collected_utility_from_scratch().expect("from scratch");
    eprintln!(
        "{} samples, one kept of {:?}: {:.2} of {all:.2} nats",
        p.samples, blocks, p.collected_utility_nats
    );
    assert!(p.collected_utility_nats < all);
    assert!(
        p.collected_utility_nats > 0.85 * all,
        "{} of {all}",
        p.collected_utility_nats
    );
    // What a replan conditions on: at most the samples the figures keep.
    let (k, kept) = s.posterior.kept_samples(usize::MAX);
    assert_eq!(k as u64, p.sample_block);
    assert_eq!(kept.len() as u64, p.samples.div_ceil(p.sample_block));
    // Resuming replays to the same figures, bit for bit.
    let resumed = Session::resume(log.clone(), s.id()).expect("resume");
    let q = resumed.progress().expect("progress");
    assert_eq!(q.sample_block, p.sample_block);
    assert_eq!(q.samples_in_figures, p.samples_in_figures);
    assert_eq!(
        q.collected_utility_nats.to_bits(),
        p.collected_utility_nats.to_bits()
    );
}

/// A planner's replan brings its own exact utility given the samples (the session does
/// not evaluate the walk again), and it is the utility of SPEC 3 given pilot data, the
/// samples and the new walk.
#[test]
fn a_planner_replan_reports_the_exact_utility_given_the_samples() {
    use crate::plan::Algorithm;
    let (log, mut s) = setup(40.0, human_exact_step(1.0));
    s.set_replanner(Arc::new(PlannerReplanner::new(Algorithm::Greedy)));
    let mut t = 0;
    for _ in 0..3 {
        t = steps(&mut s, t, 2);
        s.record(scan(t, &[])).expect("scan");
    }
    let out = s.replan().expect("replan");
    let walk = s.building().resolve_walk(&out.walk).expect("walk");
    let exact = UtilityEngine::with_prior(
        s.building().clone(),
        s.kernel,
        human_exact_step(1.0),
        &s.tracker().observations(),
    )
    .expect("engine")
    .utility(&walk)
    .expect("utility");
    assert_eq!(s.samples().len(), 3);
    assert!(
        (out.utility_nats - exact).abs() < 1e-9 * exact,
        "{} vs {exact}",
        out.utility_nats
    );
    let saved = log
        .load_plan(out.plan_id)
        .expect("plan")
        .record
        .utility_nats;
    assert_eq!(saved.to_bits(), out.utility_nats.to_bits());
}

/// Resuming a session of more than [`posterior::DENSE_FROM`] samples takes them in one
/// blocked factorisation: the figures agree with the live session's to rounding, and the
/// session goes on from there the same way.
#[test]
fn resuming_a_long_session_factors_its_samples_at_once_and_agrees_with_the_live_one() {
    let (log, s, sum, _) = simulate_demo(
        Surveyor::robot(),
        300.0,
        &SimOptions::default(),
        |_, _, _| Ok(()),
    );
    assert!(
        sum.samples as usize >= posterior::DENSE_FROM,
        "{} samples",
        sum.samples
    );
    let live = s.progress().expect("progress");
    let resumed = Session::resume(log.clone(), s.id()).expect("resume");
    let back = resumed.progress().expect("progress");
    assert_eq!(resumed.digest(), s.digest());
    assert_eq!(
        (back.samples, back.samples_in_figures, back.sample_block),
        (live.samples, live.samples_in_figures, 1)
    );
    let (a, b) = (live.collected_utility_nats, back.collected_utility_nats);
    assert!((a - b).abs() < 1e-9 * a, "{a} vs {b}");
    for (x, y) in live.uncertainty.iter().zip(&back.uncertainty) {
        assert!(
            (x.std_db - y.std_db).abs() < 1e-7 * (1.0 + x.std_db),
            "{x:?} vs {y:?}"
        );
    }
    let scratch = resumed.collected_utility_from_scratch().expect("scratch");
    assert!((b - scratch).abs() < 1e-9 * scratch, "{b} vs {scratch}");
}

/// A new session whose memory budget cannot hold the building's running figures (half of
/// 1 MiB, on a two-floor campus of 290 vertices) is refused with the size it needs, and
/// writes nothing: the next session started gets the first id.
#[test]
fn a_session_whose_memory_budget_cannot_hold_the_building_is_refused_and_writes_nothing() {
    let b = campus();
    let k = crate::gp::fit_kernel(&b.pilot).expect("fit").kernel;
    let log = Arc::new(MemoryLog::new());
    let bid = log.add_building(b.clone());
    let (v0, v1) = (
        b.vertices[0].id.clone(),
        b.vertices[b.neighbours(0)[0].0].id.clone(),
    );
    let walk = [v0.as_str(), v1.as_str(), v0.as_str()];
    let plan = log
        .save_plan(&PlanData::for_walk(
            bid,
            &walk,
            100.0,
            k,
            b.walk_length(&[0, b.neighbours(0)[0].0, 0]),
        ))
        .expect("save");
    let tiny = SessionOptions {
        memory_budget_mb: 1,
        ..SessionOptions::default()
    };
    let e = Session::start(log.clone(), plan, Surveyor::human(), tiny).expect_err("1 MiB");
    let need = posterior::IncrementalPosterior::least_memory(&b).div_ceil(1 << 20);
    let text = e.to_string();
    assert!(text.contains(&format!("{need} MiB")), "{text}");
    assert!(text.contains("memory_budget_mb"), "{text}");
    let s = Session::start(
        log.clone(),
        plan,
        Surveyor::human(),
        SessionOptions::default(),
    )
    .expect("the default holds it");
    assert_eq!(s.id(), 1, "the refused session took no id");
}

/// A replanner that stops on a clock is asked once a replan, so that the surveyor waits no
/// longer than its limit. One that runs to completion may be asked twice, and then the
/// reserve the session keeps covers the way home from the farthest point of the walk it
/// planned (with the wrong-turn rate of that moment).
#[test]
fn a_time_limited_replan_plans_once_and_an_untimed_one_keeps_a_reserve_for_its_walk() {
    use std::sync::atomic::{AtomicU32, Ordering};
    use std::time::Duration;

    struct Counting {
        limit: Option<Duration>,
        asked: AtomicU32,
    }
    impl Replanner for Counting {
        fn replan(&self, r: &ReplanRequest<'_>) -> Result<Vec<usize>> {
            self.asked.fetch_add(1, Ordering::SeqCst);
            GreedyReplanner.replan(r)
        }
        fn origin(&self) -> crate::plan::PlanOrigin {
            crate::plan::PlanOrigin::SessionGreedy
        }
        fn time_limit(&self) -> Option<Duration> {
            self.limit
        }
    }

    for limit in [Some(Duration::from_secs(1)), None] {
        let counting = Arc::new(Counting {
            limit,
            asked: AtomicU32::new(0),
        });
        let (_, mut s) = demo_session(Surveyor::human(), 200.0);
        s.set_replanner(counting.clone());
        let world = World::for_building(s.building(), &kernel(), 3).expect("world");
        let (mut covered, mut twice) = (0, 0);
        let (sum, _) = simulate(&mut s, &world, &deviating(0.3), |s, _, ack| {
            let asked = counting.asked.swap(0, Ordering::SeqCst);
            twice += usize::from(asked == 2);
            if limit.is_some() {
                assert!(asked <= 1, "asked {asked} times in one event");
                return Ok(());
            }
            assert!(asked <= 2, "asked {asked} times in one event");
            if ack.replan_seq.is_some() && s.reserve_m() > 0.0 {
                let b = s.building();
                let to_end = replan::distances_from(b, s.tracker().end());
                let ahead: Vec<usize> = s
                    .route_ahead()
                    .iter()
                    .filter_map(|w| b.vertex_index(&w.vertex))
                    .collect();
                let (origin, left) = s.tracker().replan_origin(b).expect("origin");
                let home = to_end[origin];
                let farthest = ahead.iter().map(|&v| to_end[v]).fold(home, f64::max);
                // At most what is left beyond the way home.
                let need = s.deviation_reserve(farthest, &to_end).min(left - home);
                assert!(need <= s.reserve_m() + 1e-9, "{need} > {}", s.reserve_m());
                covered += 1;
            }
            Ok(())
        })
        .expect("sim");
        assert!(sum.replans >= 2, "{sum:?}");
        if limit.is_none() {
            assert!(covered >= 1, "no replan kept a reserve: {sum:?}");
            assert!(twice >= 1, "no replan planned twice: {sum:?}");
        }
    }
}
