//! Session event ingestion: a sequence of events decoded from the input, recorded into a
//! session on the small fuzz building, with its log in memory or in the SQLite store.
//!
//! Invariants: a refused event (`Err`) changes neither the session's state (its digest) nor
//! its log (with the log in the store: the store row for row); an accepted one has a time
//! from 0 to `MAX_EVENT_T_MS`,  is acknowledged with the next seq, is on the log, and leaves the
//! session's figures sane (finite, non-negative distances, a fraction in [0, 1], samples with
//! finite labels and RSS in range, nothing accepted after finish or abort); replaying the log
//! gives back the same state; memory and time stay bounded (libFuzzer's `-rss_limit_mb`,
//! `-malloc_limit_mb` and `-timeout`).
#![no_main]

use std::sync::Arc;

use libfuzzer_sys::fuzz_target;
use trailprint::gp::Kernel;
use trailprint::session::{
    Event, MAX_EVENT_T_MS, MemoryLog, PlanData, Reading, Session, SessionLog, SessionOptions,
    SessionStatus, Surveyor,
};
use trailprint::store::{ImportOptions, Store};
use trailprint_fuzz::{Bytes, small_building, snapshot};

const VERTICES: [&str; 8] = ["a", "b", "c", "d", "e", "f", "g", " a"];
const BSSIDS: [&str; 5] = ["ap1", "ap2", "ap3", " ", "ap1 "];

/// The session's log (in memory, or in an in-memory store, which is also returned so that
/// its rows can be compared) and the fuzz building's id in it.
fn log_for(kind: u8) -> (Arc<dyn SessionLog>, i64, Option<Arc<Store>>) {
    let b = small_building();
    if kind % 2 == 0 {
        let log = Arc::new(MemoryLog::new());
        let id = log.add_building(Arc::new(b));
        (log as Arc<dyn SessionLog>, id, None)
    } else {
        let store = match Store::open_in_memory() {
            Ok(s) => s,
            Err(e) => panic!("store: {e}"),
        };
        let id = match store.import_building(&b, None, &ImportOptions::default()) {
            Ok(r) => r.id,
            Err(e) => panic!("import: {e}"),
        };
        let store = Arc::new(store);
        (store.clone() as Arc<dyn SessionLog>, id, Some(store))
    }
}

fn event(r: &mut Bytes<'_>, t: &mut i64) -> Event {
    // Mostly forward in time, sometimes back, sometimes to the ends of the range (of `i64`
    // and of event times: 0 and `MAX_EVENT_T_MS`, and one past).
    *t = match r.u8() % 16 {
        0 => t.wrapping_sub(i64::from(r.u8())),
        1 => i64::MAX,
        2 => i64::MIN,
        3 => MAX_EVENT_T_MS + i64::from(r.u8() % 3) - 1,
        4 => i64::from(r.u8() % 3) - 1,
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

/// The input bytes that decode (by [`event`] and the target's loop) to `ops` (`None`: an
/// explicit replan) on the setup byte `setup`, or `None` if some event cannot be spelled
/// (a time step the decoder cannot make, a string of 16 bytes or more, over 3 readings).
fn encode(setup: u8, ops: &[Option<Event>]) -> Option<Vec<u8>> {
    fn string(out: &mut Vec<u8>, known: &[&str], s: &str) -> Option<()> {
        if let Some(i) = known.iter().position(|k| *k == s) {
            out.push(i as u8);
        } else {
            if s.len() >= 16 {
                return None;
            }
            out.extend([200, s.len() as u8]);
            out.extend(s.as_bytes());
        }
        Some(())
    }
    fn bits(out: &mut Vec<u8>, v: f64) {
        out.push(1);
        out.extend(v.to_bits().to_le_bytes());
    }
    // A small whole number in `lo..lo+n` (not -0) as one byte after selector 0, else bits.
    fn small(out: &mut Vec<u8>, v: f64, lo: f64, n: f64) {
        if v.fract() == 0.0 && v >= lo && v < lo + n && !(v == 0.0 && v.is_sign_negative()) {
            out.extend([0, (v - lo) as u8]);
        } else {
            out.push(1);
            bits(out, v);
        }
    }
    let mut out = vec![setup];
    let mut t = 1_700_000_000_000i64;
    for op in ops {
        let Some(ev) = op else {
            out.push(0);
            continue;
        };
        out.push(1);
        let to = ev.t_ms();
        let d = to.wrapping_sub(t);
        if (0..=25_500).contains(&d) && d % 100 == 0 {
            out.extend([5, (d / 100) as u8]);
        } else if (0..=255).contains(&t.wrapping_sub(to)) {
            out.extend([0, t.wrapping_sub(to) as u8]);
        } else if to == i64::MAX {
            out.push(1);
        } else if to == i64::MIN {
            out.push(2);
        } else if (-1..=1).contains(&(to - MAX_EVENT_T_MS)) {
            out.extend([3, (to - MAX_EVENT_T_MS + 1) as u8]);
        } else if (-1..=1).contains(&to) {
            out.extend([4, (to + 1) as u8]);
        } else {
            return None;
        }
        t = to;
        match ev {
            Event::Step { steps, .. } => {
                out.push(0);
                if *steps < 8 {
                    out.extend([1, *steps as u8]);
                } else {
                    out.push(0);
                    out.extend(steps.to_le_bytes());
                }
            }
            Event::Scan { readings, .. } => {
                if readings.len() > 3 {
                    return None;
                }
                out.extend([2, readings.len() as u8]);
                for rd in readings {
                    string(&mut out, &BSSIDS, &rd.bssid)?;
                    let v = rd.rss_dbm;
                    if v.fract() == 0.0
                        && (-120.0..=0.0).contains(&v)
                        && (v != 0.0 || v.is_sign_negative())
                    {
                        out.extend([0, (-v) as u8]);
                    } else {
                        out.push(1);
                        bits(&mut out, v);
                    }
                }
            }
            Event::CheckIn { vertex, .. } => {
                out.push(3);
                string(&mut out, &VERTICES, vertex)?;
            }
            Event::Pose { x, y, floor, .. } => {
                out.push(4);
                small(&mut out, *x, 0.0, 10.0);
                small(&mut out, *y, -4.0, 10.0);
                match floor {
                    0 => out.extend([0, 0]),
                    1 => out.extend([1, 0]),
                    2 => out.extend([2, 0]),
                    -1 => out.extend([0, 1]),
                    _ => return None,
                }
            }
            Event::Pause { .. } => out.push(5),
            Event::Resume { .. } => out.push(6),
            Event::Finish { .. } => out.push(7),
            Event::Abort { reason, .. } => {
                out.push(8);
                match reason {
                    Some(why) => {
                        out.push(0);
                        string(&mut out, &["battery"], why)?;
                    }
                    None => out.push(1),
                }
            }
        }
    }
    Some(out)
}

/// The ops the target's loop decodes from `data` (`None`: an explicit replan), as it reads
/// them (without the cap on replans).
fn decode(data: &[u8]) -> Vec<Option<Event>> {
    let mut r = Bytes::new(data);
    r.u8();
    let mut t = 1_700_000_000_000i64;
    let mut ops = Vec::new();
    while !r.is_empty() && ops.len() < 64 {
        if r.u8() % 16 == 0 {
            ops.push(None);
        } else {
            ops.push(Some(event(&mut r, &mut t)));
        }
    }
    ops
}

/// Seeds from the session fixtures of the core's tests (`core/tests/fixtures/fuzz/session-*.json`:
/// the walks, the regression inputs) as input bytes, written to `dir`; each is checked to
/// decode back to the fixture's events.
fn write_seeds(dir: &std::path::Path) {
    let fixtures =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../core/tests/fixtures/fuzz");
    let mut names: Vec<_> = match std::fs::read_dir(&fixtures) {
        Ok(d) => d.filter_map(|e| e.ok()).map(|e| e.path()).collect(),
        Err(e) => panic!("{}: {e}", fixtures.display()),
    };
    names.sort();
    for path in names {
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if !name.starts_with("session-") || name == "session-building" {
            continue;
        }
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let doc: serde_json::Value =
            serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let parse = |v: &serde_json::Value| -> Vec<Option<Event>> {
            let Some(list) = v.as_array() else {
                panic!("{}: no event list", path.display())
            };
            list.iter()
                .map(|op| {
                    if op.is_string() {
                        None
                    } else {
                        Some(
                            serde_json::from_value(op.clone())
                                .unwrap_or_else(|e| panic!("{}: {e}", path.display())),
                        )
                    }
                })
                .collect()
        };
        // (seed name, setup byte, ops)
        let mut seeds = Vec::new();
        if let Some(ops) = doc.get("ops") {
            let flag = |k: &str| doc.get(k).and_then(|v| v.as_bool()).unwrap_or(false);
            let mut setup = 0u8;
            if doc.get("log").and_then(|v| v.as_str()) == Some("store") {
                setup |= 1;
            }
            if doc.get("surveyor").and_then(|v| v.as_str()) == Some("robot") {
                setup |= 2;
            }
            if flag("auto_replan") {
                setup |= 4;
            }
            if flag("deviation_reserve") {
                setup |= 8;
            }
            if doc
                .get("walk")
                .and_then(|v| v.as_array())
                .is_some_and(|w| w.len() == 5)
            {
                setup |= 16;
            }
            seeds.push((name.clone(), setup, parse(ops)));
        } else {
            // `{"human": [...], "robot": [...]}`: each with the log in memory and in the store.
            for (who, bit) in [("human", 0u8), ("robot", 2)] {
                if let Some(evs) = doc.get(who) {
                    for log in [0u8, 1] {
                        seeds.push((format!("{name}-{who}-{log}"), bit | log, parse(evs)));
                    }
                }
            }
        }
        for (seed, setup, ops) in seeds {
            let Some(bytes) = encode(setup, &ops) else {
                // A fuzz input kept as JSON whose bytes were lossy (raw strings): its own
                // bytes are in the corpus already.
                eprintln!("{seed}: an event the input bytes cannot spell; skipped");
                continue;
            };
            let back = decode(&bytes);
            assert_eq!(
                format!("{back:?}"),
                format!("{ops:?}"),
                "{seed}: does not decode back"
            );
            if let Err(e) = std::fs::write(dir.join(&seed), bytes) {
                panic!("{}: {e}", dir.display());
            }
        }
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

fuzz_target!(
    init: {
        // `TRAILPRINT_FUZZ_SEEDS=DIR` writes the seeds made from the test fixtures to DIR and
        // exits (how `fuzz/corpus/session` was made).
        if let Some(dir) = std::env::var_os("TRAILPRINT_FUZZ_SEEDS") {
            write_seeds(std::path::Path::new(&dir));
            std::process::exit(0);
        }
    },
    |data: &[u8]| {
        let mut r = Bytes::new(data);
        let setup = r.u8();
        let (log, bid, store) = log_for(setup);
        let rows = |store: &Option<Arc<Store>>| store.as_deref().map(snapshot);
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
                let before_rows = rows(&store);
                if s.replan().is_err() {
                    assert_eq!(before, s.digest(), "a failed replan changed the session");
                    assert_eq!(before_rows, rows(&store), "a failed replan changed the store");
                    assert_eq!(
                        before_len,
                        log_len(&log),
                        "a failed replan wrote to the log"
                    );
                }
                continue;
            }
            let ev = event(&mut r, &mut t);
            let before_rows = rows(&store);
            match s.record(ev.clone()) {
                Err(e) => {
                    assert!(!e.to_string().is_empty());
                    assert_eq!(
                        before,
                        s.digest(),
                        "refused {ev:?} ({e}) changed the session"
                    );
                    assert_eq!(before_len, log_len(&log), "refused {ev:?} ({e}) was logged");
                    assert_eq!(
                        before_rows,
                        rows(&store),
                        "refused {ev:?} ({e}) changed the store"
                    );
                }
                Ok(ack) => {
                    assert!(!ended, "{ev:?} accepted after the session ended");
                    assert!(
                        (0..=MAX_EVENT_T_MS).contains(&ev.t_ms()),
                        "{ev:?} accepted at a time out of range"
                    );
                    let active = s.tracker().elapsed_ms();
                    assert!(
                        (0..=MAX_EVENT_T_MS).contains(&active),
                        "active time {active} ms"
                    );
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
    }
);
