//! Session event ingestion: a sequence of events decoded from the input, recorded into a
//! session on the small fuzz building, with its log in memory or in the SQLite store.
//!
//! Invariants: a refused event (`Err`) changes neither the session's state (its digest) nor
//! its log; an accepted one is acknowledged with the next seq, is on the log, and leaves the
//! session's figures sane (finite, non-negative distances, a fraction in [0, 1], samples with
//! finite labels and RSS in range, nothing accepted after finish or abort); replaying the log
//! gives back the same state.
#![no_main]

use std::sync::Arc;

use libfuzzer_sys::fuzz_target;
use trailprint::gp::Kernel;
use trailprint::session::{
    Event, MemoryLog, PlanData, Reading, Session, SessionLog, SessionOptions, SessionStatus,
    Surveyor,
};
use trailprint::store::{ImportOptions, Store};
use trailprint_fuzz::{Bytes, small_building};

const VERTICES: [&str; 8] = ["a", "b", "c", "d", "e", "f", "g", " a"];
const BSSIDS: [&str; 5] = ["ap1", "ap2", "ap3", " ", "ap1 "];

fn log_for(kind: u8) -> (Arc<dyn SessionLog>, i64) {
    let b = small_building();
    if kind % 2 == 0 {
        let log = Arc::new(MemoryLog::new());
        let id = log.add_building(Arc::new(b));
        (log as Arc<dyn SessionLog>, id)
    } else {
        let store = match Store::open_in_memory() {
            Ok(s) => s,
            Err(e) => panic!("store: {e}"),
        };
        let id = match store.import_building(&b, None, &ImportOptions::default()) {
            Ok(r) => r.id,
            Err(e) => panic!("import: {e}"),
        };
        (Arc::new(store) as Arc<dyn SessionLog>, id)
    }
}

fn event(r: &mut Bytes<'_>, t: &mut i64) -> Event {
    // Mostly forward in time, sometimes back, sometimes to the ends of the range.
    *t = match r.u8() % 16 {
        0 => t.wrapping_sub(i64::from(r.u8())),
        1 => i64::MAX,
        2 => i64::MIN,
        _ => t.saturating_add(i64::from(r.u8()) * 100),
    };
    let t_ms = *t;
    match r.u8() % 9 {
        0 | 1 => Event::Step {
            t_ms,
            steps: match r.u8() % 4 {
                0 => r.u32(),
                _ => u32::from(r.u8() % 8),
            },
        },
        2 => {
            let n = usize::from(r.u8() % 4);
            Event::Scan {
                t_ms,
                readings: (0..n)
                    .map(|_| Reading {
                        bssid: r.string(&BSSIDS),
                        rss_dbm: if r.u8() % 2 == 0 {
                            -f64::from(r.u8() % 121)
                        } else {
                            r.f64()
                        },
                    })
                    .collect(),
            }
        }
        3 => Event::CheckIn {
            t_ms,
            vertex: r.string(&VERTICES),
        },
        4 => Event::Pose {
            t_ms,
            x: if r.u8() % 2 == 0 {
                f64::from(r.u8() % 10)
            } else {
                r.f64()
            },
            y: if r.u8() % 2 == 0 {
                f64::from(r.u8() % 10) - 4.0
            } else {
                r.f64()
            },
            floor: i64::from(r.u8() % 3) - (r.u8() % 2) as i64,
        },
        5 => Event::Pause { t_ms },
        6 => Event::Resume { t_ms },
        7 => Event::Finish { t_ms },
        _ => Event::Abort {
            t_ms,
            reason: (r.u8() % 2 == 0).then(|| r.string(&["battery"])),
        },
    }
}

fn check_sane(s: &Session) {
    let t = s.tracker();
    let walked = t.walked_m();
    assert!(walked.is_finite() && walked >= 0.0, "walked {walked}");
    let step = t.step_length_m();
    // A robot has no step length (0); a person's stays positive through re-estimation.
    if t.surveyor().is_human() {
        assert!(step.is_finite() && step > 0.0, "step length {step}");
    } else {
        assert!(step.is_finite() && step >= 0.0, "robot step length {step}");
    }
    for smp in s.samples() {
        let p = smp.position;
        assert!(p.x.is_finite() && p.y.is_finite(), "sample at {p:?}");
        assert!(
            s.building().floors.iter().any(|f| f.id == p.floor),
            "sample on floor {}",
            p.floor
        );
        assert!(
            smp.sigma_m.is_finite() && smp.sigma_m >= 0.0,
            "sigma {}",
            smp.sigma_m
        );
        assert!(smp.extra_noise.is_finite() && smp.extra_noise >= 0.0);
        for (ap, v) in &smp.rss {
            assert!(trailprint::building::rss_ok(*v), "{ap}: {v}");
        }
    }
    let g = s.guidance();
    assert!(
        g.distance_m.is_finite() && g.distance_m >= 0.0,
        "guidance {g:?}"
    );
    if let Ok(p) = s.progress() {
        assert!(
            (0.0..=1.0).contains(&p.fraction_done),
            "fraction {}",
            p.fraction_done
        );
        assert!(p.remaining_m.is_finite() && p.remaining_m >= 0.0, "{p:?}");
        assert!(
            p.elapsed_s.is_finite() && p.elapsed_s >= 0.0,
            "elapsed {}",
            p.elapsed_s
        );
        assert!(p.reserve_m.is_finite() && p.reserve_m >= 0.0);
    }
}

fuzz_target!(|data: &[u8]| {
    let mut r = Bytes::new(data);
    let setup = r.u8();
    let (log, bid) = log_for(setup);
    let surveyor = if setup & 2 == 0 {
        Surveyor::human()
    } else {
        Surveyor::robot()
    };
    let options = SessionOptions {
        auto_replan: setup & 4 != 0,
        deviation_reserve: setup & 8 != 0,
        ..SessionOptions::default()
    };
    let walk: &[&str] = if setup & 16 == 0 {
        &["a", "b", "c", "d"]
    } else {
        &["a", "b", "c", "d", "f"]
    };
    let plan = PlanData::for_walk(bid, walk, 40.0, Kernel::new(20.0, 5.0, 2.0), 12.0);
    let plan_id = match log.save_plan(&plan) {
        Ok(id) => id,
        Err(e) => panic!("plan: {e}"),
    };
    let mut s = match Session::start(log.clone(), plan_id, surveyor, options) {
        Ok(s) => s,
        Err(e) => panic!("start: {e}"),
    };
    let id = s.id();
    let log_len = |log: &Arc<dyn SessionLog>| match log.events(id) {
        Ok(e) => e.len(),
        Err(e) => panic!("events: {e}"),
    };
    let mut t = 1_700_000_000_000i64;
    let mut ops = 0;
    let mut replans = 0;
    while !r.is_empty() && ops < 64 {
        ops += 1;
        let before = s.digest();
        let before_len = log_len(&log);
        let before_seq = s.last_seq();
        let ended = matches!(s.status(), SessionStatus::Finished | SessionStatus::Aborted);
        if r.u8() % 16 == 0 {
            // An explicit replan (a few per input: each plans afresh, about 0.2 s under the
            // sanitizer, and sixty of them would read as a timeout).
            replans += 1;
            if replans > 4 {
                continue;
            }
            if s.replan().is_err() {
                assert_eq!(before, s.digest(), "a failed replan changed the session");
                assert_eq!(
                    before_len,
                    log_len(&log),
                    "a failed replan wrote to the log"
                );
            }
            continue;
        }
        let ev = event(&mut r, &mut t);
        match s.record(ev.clone()) {
            Err(e) => {
                assert!(!e.to_string().is_empty());
                assert_eq!(
                    before,
                    s.digest(),
                    "refused {ev:?} ({e}) changed the session"
                );
                assert_eq!(before_len, log_len(&log), "refused {ev:?} ({e}) was logged");
            }
            Ok(ack) => {
                assert!(!ended, "{ev:?} accepted after the session ended");
                assert_eq!(ack.seq, before_seq + 1, "{ev:?}: seq");
                assert_eq!(s.last_seq(), ack.last_seq(), "{ev:?}: last seq");
                let written = 1 + usize::from(ack.replan_seq.is_some());
                assert_eq!(log_len(&log), before_len + written, "{ev:?}: log length");
                assert!(ack.position.x.is_finite() && ack.position.y.is_finite());
                check_sane(&s);
            }
        }
    }
    // The log gives back the state.
    match Session::replay_to(log.clone(), id, i64::MAX) {
        Ok(again) => assert_eq!(again.digest(), s.digest(), "replay differs"),
        Err(e) => panic!("the session's own log cannot be replayed: {e}"),
    }
});
