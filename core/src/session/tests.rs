use std::sync::Arc;

use super::sim::{SimOptions, World, simulate};
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

fn setup(
    walk: &[&str],
    budget: f64,
    surveyor: Surveyor,
    options: SessionOptions,
) -> (Arc<MemoryLog>, Session) {
    let b = Arc::new(tee());
    let log = Arc::new(MemoryLog::new());
    let bid = log.add_building(b.clone());
    let ids = b.resolve_walk(walk).expect("walk");
    let plan = log
        .save_plan(&PlanData::for_walk(
            bid,
            walk,
            budget,
            kernel(),
            b.walk_length(&ids),
        ))
        .expect("plan");
    let s = Session::start(log.clone(), plan, surveyor, options).expect("start");
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
    let (_, mut s) = setup(
        &["a", "b", "c", "e"],
        30.0,
        human_exact_step(1.0),
        SessionOptions::default(),
    );
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
    let ack = s
        .record(Event::CheckIn {
            t_ms: t,
            vertex: "c".into(),
        })
        .expect("check in");
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
    let (_, mut s) = setup(
        &["a", "b", "c", "e"],
        30.0,
        human_exact_step(0.5),
        SessionOptions::default(),
    );
    let t = steps(&mut s, 0, 13);
    let ack = s
        .record(Event::Scan {
            t_ms: t,
            readings: vec![Reading {
                bssid: "ap".into(),
                rss_dbm: -60.0,
            }],
        })
        .expect("scan");
    let smp = ack.sample.expect("sample");
    assert!((smp.position.x - 6.5).abs() < 1e-12 && smp.position.y == 0.0);
    assert_eq!(smp.since_checkin_m, Some(6.5));
    assert!((smp.sigma_m - 0.05 * 6.5).abs() < 1e-12);
    assert!((smp.extra_noise - kernel().label_noise(0.05 * 6.5)).abs() < 1e-15);
}

#[test]
fn wrong_turn_is_off_route_and_replans_from_there_within_budget() {
    let (_, mut s) = setup(
        &["a", "b", "c", "e"],
        30.0,
        human_exact_step(1.0),
        SessionOptions::default(),
    );
    let t = steps(&mut s, 0, 5);
    // At b the walk goes straight to c; the surveyor turns to d and checks in there.
    let t = steps(&mut s, t, 5);
    let walked_before = s.tracker().walked_m();
    let ack = s
        .record(Event::CheckIn {
            t_ms: t,
            vertex: "d".into(),
        })
        .expect("check in");
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
    let (_, mut s) = setup(
        &["a", "b", "c", "e"],
        40.0,
        human_exact_step(1.0),
        SessionOptions::default(),
    );
    // 3 m along a-b: the replan starts at b, 2 m ahead.
    let t = steps(&mut s, 0, 3);
    s.record(Event::Scan {
        t_ms: t,
        readings: vec![],
    })
    .expect("scan");
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
    let (_, mut s) = setup(
        &["a", "b", "c", "e"],
        30.0,
        human_exact_step(1.0),
        SessionOptions::default(),
    );
    // Due at c after 10 m; slack 3 m + 25% of 10 m.
    let t = steps(&mut s, 0, 15);
    assert!(!s.tracker().off_route());
    s.record(Event::Step { t_ms: t, steps: 1 }).expect("step");
    assert!(s.tracker().off_route());
    assert!(s.guidance().message.contains("check in"));
    assert!(s.replan().is_err(), "position unknown");
    // Checking in back on the walk puts the surveyor on-route again.
    let ack = s
        .record(Event::CheckIn {
            t_ms: t + 10,
            vertex: "c".into(),
        })
        .expect("check in");
    assert!(!ack.off_route);
    assert_eq!(s.tracker().off_route_events(), 1);
}

#[test]
fn bad_events_are_rejected_and_write_nothing() {
    let (log, mut s) = setup(
        &["a", "b", "c", "e"],
        30.0,
        Surveyor::human(),
        SessionOptions::default(),
    );
    s.record(Event::Step {
        t_ms: 1000,
        steps: 1,
    })
    .expect("step");
    let id = s.id();
    let before = (log.events(id).expect("events").len(), s.digest());
    let scan = |rss: f64| Event::Scan {
        t_ms: 2000,
        readings: vec![Reading {
            bssid: "aa:bb".into(),
            rss_dbm: rss,
        }],
    };
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
        (scan(f64::NAN), "NaN"),
        (scan(3.0), "got 3"),
        (scan(-121.0), "got -121"),
        (scan(f64::INFINITY), "finite"),
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
    let s = Session::start(log.clone(), plan, surveyor, SessionOptions::default()).expect("start");
    (log, s)
}

#[test]
fn a_robot_walking_the_plan_exactly_collects_the_planned_utility() {
    let (_, mut s) = demo_session(Surveyor::robot(), 60.0);
    let world = World::for_building(s.building(), &kernel(), 3).expect("world");
    let (sum, rep) =
        simulate(&mut s, &world, &SimOptions::default(), |_, _, _| Ok(())).expect("sim");
    assert_eq!(rep.wrong_turns, 0);
    assert_eq!(sum.off_route_events, 0);
    assert_eq!(sum.replans, 0);
    let rel =
        (sum.collected_utility_nats - sum.planned_utility_nats).abs() / sum.planned_utility_nats;
    assert!(rel < 1e-6, "{sum:?}");
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
        let (log, mut s) = demo_session(surveyor, 80.0);
        let world = World::for_building(s.building(), &kernel(), 3).expect("world");
        let opts = SimOptions {
            deviate,
            seed: 5,
            ..SimOptions::default()
        };
        let mut digests = std::collections::BTreeMap::new();
        let (sum, rep) = simulate(&mut s, &world, &opts, |sess, _, ack| {
            digests.insert(ack.last_seq(), sess.digest());
            Ok(())
        })
        .expect("sim");
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
    let walk = ["a", "b", "c", "e"];
    let ids = b.resolve_walk(&walk).expect("walk");
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
                walk: walk.iter().map(|s| s.to_string()).collect(),
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
    s.record(Event::Scan {
        t_ms: t,
        readings: vec![
            Reading {
                bssid: "aa:01".into(),
                rss_dbm: -61.5,
            },
            Reading {
                bssid: "aa:02".into(),
                rss_dbm: -80.0,
            },
        ],
    })
    .expect("scan");
    let t = steps(&mut s, t, 6);
    // A wrong turn at b: off-route at d, replanned from d.
    let ack = s
        .record(Event::CheckIn {
            t_ms: t,
            vertex: "d".into(),
        })
        .expect("check in");
    assert!(ack.replan_seq.is_some());
    let n = store.list_events(s.id(), 0).expect("events").len();
    assert!(
        s.record(Event::Scan {
            t_ms: t,
            readings: vec![Reading {
                bssid: "x".into(),
                rss_dbm: f64::NAN
            }]
        })
        .is_err()
    );
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
        let b = Arc::new(tee());
        let bid = mem.add_building(b.clone());
        let ids = b.resolve_walk(&["a", "b", "c", "e"]).expect("walk");
        let pid = mem
            .save_plan(&PlanData::for_walk(
                bid,
                &["a", "b", "c", "e"],
                30.0,
                kernel(),
                b.walk_length(&ids),
            ))
            .expect("plan");
        let mut s = Session::start(log, pid, human_exact_step(1.0), SessionOptions::default())
            .expect("start");
        let t = steps(&mut s, 0, 10);
        let ack = s.record(Event::CheckIn {
            t_ms: t,
            vertex: "d".into(),
        });
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
        let (_, mut s) = demo_session(surveyor, 80.0);
        let world = World::for_building(s.building(), &kernel(), 3).expect("world");
        let opts = SimOptions {
            deviate,
            seed: 5,
            ..SimOptions::default()
        };
        let mut checked = 0;
        let mut worst: f64 = 0.0;
        simulate(&mut s, &world, &opts, |sess, ev, _| {
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
        })
        .expect("sim");
        assert!(checked >= 5, "checked {checked}");
        assert!(s.samples().len() > 15, "{}", s.samples().len());
        eprintln!("{checked} checks, worst std difference {worst:e} dB");
    }
}

#[test]
fn a_robot_that_follows_the_plan_gets_no_reserve_and_exactly_the_planned_utility() {
    let (_, mut s) = demo_session(Surveyor::robot(), 80.0);
    let world = World::for_building(s.building(), &kernel(), 3).expect("world");
    let (sum, _) = simulate(&mut s, &world, &SimOptions::default(), |_, _, _| Ok(())).expect("sim");
    assert_eq!(sum.replans, 0);
    assert_eq!(s.reserve_m(), 0.0);
    assert!(!s.guidance().message.contains("reserve"));
    let rel =
        (sum.collected_utility_nats - sum.planned_utility_nats).abs() / sum.planned_utility_nats;
    assert!(rel < 1e-12, "{sum:?}");
}
