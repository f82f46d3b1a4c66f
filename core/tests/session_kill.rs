//! SIGKILL in mid-session: `trailprint simulate --db` is killed at seeded random moments;
//! this process then checks that every event the child acknowledged is in the log, that
//! the log replays to the state an uninterrupted run had at that event, and that the
//! session resumes (finishing an interrupted replan) and accepts new events.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Arc;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use trailprint::session::sim::{SimOptions, World, simulate};
use trailprint::session::{
    Event, MemoryLog, Session, SessionLog, SessionSettings, SessionStatus, Surveyor,
};
use trailprint::store::{SessionEvent, Store};

use crate::store_common::{BIN, DEMO_BUILDING, demo_route};

struct Child {
    session: i64,
    acked: Vec<(i64, i64)>,
    finished: bool,
}

/// Runs the simulation in a child and kills it after `kill_after` acknowledgements.
fn run_child(db: &Path, surveyor: &str, seed: u64, kill_after: usize) -> Child {
    let mut child = Command::new(BIN)
        .arg("--db")
        .arg(db)
        .args(["simulate", "--building", DEMO_BUILDING])
        .args(demo_route("60"))
        .args([
            "--surveyor",
            surveyor,
            "--deviate",
            "0.25",
            "--seed",
            &seed.to_string(),
            // greedy, not auto under a time limit: the walk, and so how many events
            // the session has before its kill, must not depend on the machine's load.
            "--algorithm",
            "greedy",
            "--print-acks",
            "--json",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn trailprint simulate");
    let out = child.stdout.take().expect("stdout");
    let mut session = 0;
    let mut acked = Vec::new();
    let mut finished = false;
    for line in BufReader::new(out).lines() {
        let line = line.expect("line");
        let parts: Vec<&str> = line.split_whitespace().collect();
        match parts.as_slice() {
            ["session", id, "plan", _] => session = id.parse().expect("id"),
            ["ack", seq, last] => {
                acked.push((seq.parse().expect("seq"), last.parse().expect("last")));
                if acked.len() >= kill_after {
                    child.kill().expect("SIGKILL");
                    break;
                }
            }
            _ if line.starts_with('{') => finished = true,
            _ => panic!("unexpected output {line:?}"),
        }
    }
    child.wait().expect("wait");
    Child {
        session,
        acked,
        finished,
    }
}

/// The same session run to the end without interruption, in memory: the digest after
/// every acknowledgement, keyed by the last seq it covers, and the log.
fn reference(
    store: &Store,
    session: i64,
) -> (BTreeMap<i64, String>, Vec<trailprint::session::LogEntry>) {
    let row = SessionLog::session(store, session).expect("row");
    let settings: SessionSettings = serde_json::from_value(row.settings).expect("settings");
    let mut plan = SessionLog::load_plan(store, row.plan_id).expect("plan");
    let building = SessionLog::building(store, row.building_id).expect("building");
    let log = Arc::new(MemoryLog::new());
    plan.building_id = log.add_building(building.clone());
    let pid = log.save_plan(&plan).expect("save");
    let mut s =
        Session::start(log.clone(), pid, settings.surveyor, settings.options).expect("start");
    assert_eq!(
        s.id(),
        session,
        "fresh database and fresh log both start at 1"
    );
    let world =
        World::for_building(&building, &plan.record.kernel, settings.options.seed).expect("world");
    let opts = SimOptions {
        deviate: 0.25,
        seed: settings.options.seed,
        ..SimOptions::default()
    };
    let mut digests = BTreeMap::new();
    simulate(&mut s, &world, &opts, |s, _, ack| {
        digests.insert(ack.last_seq(), s.digest());
        Ok(())
    })
    .expect("reference run");
    (digests, log.events(session).expect("events"))
}

fn mask_plan(e: &SessionEvent) -> SessionEvent {
    match e {
        SessionEvent::Replan { .. } => SessionEvent::Replan { plan_id: 0 },
        other => other.clone(),
    }
}

#[test]
fn sigkill_loses_no_acknowledged_event_and_the_session_resumes_elsewhere() {
    let _serial = crate::serial();
    use rand::RngExt;
    let dir = tempfile::tempdir().expect("tempdir");
    let mut rng = ChaCha8Rng::seed_from_u64(0x5e55_10f1);
    let mut kills = 0;
    let mut verified = 0;
    let mut resumed_replans = 0;
    for round in 0..8u64 {
        let surveyor = if round % 2 == 0 { "human" } else { "robot" };
        let db = dir.path().join(format!("kill-{round}.db"));
        let kill_after = rng.random_range(3..150usize);
        let child = run_child(&db, surveyor, round + 1, kill_after);
        kills += usize::from(!child.finished);
        let store = Arc::new(Store::open(&db).expect("open after kill"));
        let log = store.list_events(child.session, 0).expect("events");
        let n = log.len() as i64;
        // Every acknowledged event is there, and the log has no gap.
        for (i, e) in log.iter().enumerate() {
            assert_eq!(e.seq, i as i64 + 1);
        }
        let max_acked = child.acked.iter().map(|a| a.1).max().unwrap_or(0);
        assert!(
            max_acked <= n,
            "round {round}: event {max_acked} was acknowledged but the log ends at {n}"
        );
        verified += child.acked.len();

        // The log is the uninterrupted run's log, event for event.
        let (digests, ref_log) = reference(&store, child.session);
        let ours = SessionLog::events(&*store, child.session).expect("log");
        for (a, b) in ours.iter().zip(&ref_log) {
            assert_eq!(
                (a.seq, a.t_ms, mask_plan(&a.event)),
                (b.seq, b.t_ms, mask_plan(&b.event)),
                "round {round}"
            );
        }
        // Replaying up to the last event gives the uninterrupted state there. (A kill
        // between an off-route check-in and its replan leaves a state no acknowledgement
        // showed; resuming finishes the replan.)
        let dyn_log: Arc<dyn SessionLog> = store.clone();
        let replayed = Session::replay_to(dyn_log.clone(), child.session, n).expect("replay");
        if let Some(d) = digests.get(&n) {
            assert_eq!(
                &replayed.digest(),
                d,
                "round {round}: state after event {n}"
            );
        }
        let mut resumed = Session::resume(dyn_log, child.session).expect("resume");
        let last = resumed.last_seq();
        if last > n {
            resumed_replans += 1;
        }
        assert_eq!(
            &resumed.digest(),
            digests.get(&last).expect("an acknowledged state"),
            "round {round}: resumed state at event {last}"
        );
        // The resumed session goes on from where it was.
        if resumed.status() == SessionStatus::Active {
            let t = resumed.tracker().last_t_ms().unwrap_or(0) + 500;
            let ev = match resumed.tracker().surveyor() {
                Surveyor::Human { .. } => Event::Step { t_ms: t, steps: 1 },
                Surveyor::Robot { .. } => {
                    let p = resumed.tracker().position(resumed.building());
                    Event::Pose {
                        t_ms: t,
                        x: p.x,
                        y: p.y,
                        floor: p.floor,
                    }
                }
            };
            let ack = resumed.record(ev).expect("record after resume");
            assert_eq!(ack.seq, last + 1);
            let sum = resumed.finish(t + 1000).expect("finish");
            assert_eq!(sum.status, SessionStatus::Finished);
        }
    }
    eprintln!(
        "{kills} kills, {verified} acknowledged events verified, {resumed_replans} replans finished on resume"
    );
    assert!(kills >= 4, "most rounds must be killed mid-session");
}
