//! SIGKILL in the middle of an import leaves the database as it was before the transaction.
//!
//! A child `trailprint import --replace` of a large generated building is killed many times
//! at seeded random moments. Most kills land inside the transaction: the hidden test hook
//! `TRAILPRINT_TEST_IMPORT_DELAY_US` (see `cmd_import.rs`) makes the importer print
//! `progress <rows>` every 100 rows and pause, and the test kills it once a random row count
//! is reached. Others land at a random time (before, during or after the transaction), and
//! some imports are let finish so that later kills hit a `--replace` of an existing copy.
//! After each kill: `integrity_check` and `foreign_key_check` are clean, Area One (imported
//! first) is intact, and the big building is absent or exactly one of its two versions.

#![allow(clippy::expect_used)] // tests and their helpers may expect

use crate::store_common;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::Duration;

use store_common::{BIN, Rng, assert_healthy, grid_building, run_ok, shared_instance};
use trailprint::building::BuildingFile;
use trailprint::store::{ImportOptions, Store};
use trailprint::{Building, Error};

const KILLS: usize = 30;
const BIG: &str = "Big generated";

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Absent,
    Version(u32),
}

#[test]
fn sigkill_during_import_leaves_the_previous_state() {
    let _serial = crate::serial();
    let dir = tempfile::tempdir().expect("tempdir");
    let db = dir.path().join("kill.db");
    let wal = dir.path().join("kill.db-wal");
    run_ok(
        &db,
        &[
            "import",
            shared_instance("area-one.json").to_str().expect("utf-8"),
        ],
    );
    let area_one = {
        let store = Store::open(&db).expect("open");
        store
            .export_building("Area One (synthetic)")
            .expect("export")
    };

    // Two versions of one large building: 1,600 vertices, 3,120 edges, 5,000 dense
    // fingerprints of 10 readings: about 60,000 rows, several MB of pages, more than
    // SQLite's page cache, so uncommitted pages do spill into the WAL before the commit.
    let mut files = Vec::new();
    let mut expected: Vec<BuildingFile> = Vec::new();
    let mut total_rows = 0;
    for v in 1..=2u32 {
        let text = grid_building(BIG, 40, 5_000, 10, v);
        let path = dir.path().join(format!("big-v{v}.json"));
        std::fs::write(&path, &text).expect("write");
        let b = Building::from_json(&text, "big").expect("valid");
        if v == 1 {
            let mem = Store::open_in_memory().expect("mem");
            total_rows = mem
                .import_building(&b, None, &ImportOptions::default())
                .expect("count rows")
                .rows;
        }
        expected.push(b.to_file());
        files.push(path);
    }
    assert!(total_rows > 50_000, "{total_rows} rows");

    let state_of = |label: &str| -> State {
        {
            // A plain connection first: opening runs WAL recovery, then check the file.
            let conn = rusqlite::Connection::open(&db).expect("open after kill");
            assert_healthy(&conn);
        }
        let store = Store::open(&db).expect("store after kill");
        assert_eq!(
            store
                .export_building("Area One (synthetic)")
                .expect("area one"),
            area_one,
            "{label}: earlier content changed"
        );
        match store.export_building(BIG) {
            Err(Error::NotFound(_)) => State::Absent,
            Err(e) => panic!("{label}: {e}"),
            Ok(file) => {
                let v = expected
                    .iter()
                    .position(|e| *e == file)
                    .unwrap_or_else(|| panic!("{label}: the building is half-written"));
                State::Version(v as u32 + 1)
            }
        }
    };

    // How long a whole slowed-down import takes (process start to exit), into a scratch
    // database: random-time kills are spread over 1.3 times that.
    let started = std::time::Instant::now();
    let out = Command::new(BIN)
        .arg("--db")
        .arg(dir.path().join("scratch.db"))
        .arg("import")
        .arg(&files[0])
        .env("TRAILPRINT_TEST_IMPORT_DELAY_US", "200")
        .output()
        .expect("timing run");
    assert!(out.status.success());
    let window_ms = (started.elapsed().as_millis() as u64 * 13 / 10).max(10);

    let mut rng = Rng(0x7EA1_F00D);
    let mut current = State::Absent;
    let (mut mid, mut timed, mut finished, mut spilled) = (0, 0, 0, 0);
    let mut timed_outcomes = (0, 0); // (rolled back, committed)
    for i in 0..KILLS {
        let variant = 1 + (i % 2) as u32;
        let mut child = Command::new(BIN)
            .arg("--db")
            .arg(&db)
            .args(["import", "--replace"])
            .arg(&files[variant as usize - 1])
            .env("TRAILPRINT_TEST_IMPORT_DELAY_US", "200")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn");
        let stderr = child.stderr.take().expect("stderr");
        let label;
        let kind = if i % 10 == 9 {
            2
        } else if i % 5 == 4 {
            1
        } else {
            0
        };
        match kind {
            0 => {
                // Inside the transaction: after a random number of rows.
                let target = rng.range(100, total_rows - 100);
                label = format!("kill {i} at row {target}");
                let mut reached = false;
                for line in BufReader::new(stderr).lines() {
                    let line = line.expect("stderr line");
                    if let Some(n) = line.strip_prefix("progress ") {
                        if n.parse::<u64>().expect("progress count") >= target {
                            child.kill().expect("SIGKILL");
                            reached = true;
                            break;
                        }
                    } else {
                        panic!("{label}: unexpected output {line:?}");
                    }
                }
                assert!(reached, "{label}: the import ended first");
                child.wait().expect("wait");
                mid += 1;
            }
            1 => {
                // At a random time: before, inside or after the transaction.
                let ms = rng.range(0, window_ms);
                label = format!("kill {i} after {ms} ms");
                let drain = std::thread::spawn(move || {
                    let _ = std::io::copy(&mut BufReader::new(stderr), &mut std::io::sink());
                });
                std::thread::sleep(Duration::from_millis(ms));
                let _ = child.kill(); // it may have finished already
                child.wait().expect("wait");
                drain.join().expect("drain");
                timed += 1;
            }
            _ => {
                label = format!("import {i} let finish");
                let drain = std::thread::spawn(move || {
                    let _ = std::io::copy(&mut BufReader::new(stderr), &mut std::io::sink());
                });
                assert!(child.wait().expect("wait").success(), "{label}");
                drain.join().expect("drain");
                finished += 1;
            }
        }
        // The previous check closed the database cleanly (removing the WAL), so frames in a
        // WAL now were written by the killed child: uncommitted pages that had spilled.
        if kind == 0 && std::fs::metadata(&wal).map(|m| m.len()).unwrap_or(0) > 0 {
            spilled += 1;
        }
        let now = state_of(&label);
        match kind {
            0 => assert_eq!(now, current, "{label}: a killed transaction left a trace"),
            1 => {
                assert!(
                    now == current || now == State::Version(variant),
                    "{label}: {now:?} is neither before ({current:?}) nor after"
                );
                if now == current && current != State::Version(variant) {
                    timed_outcomes.0 += 1;
                } else {
                    timed_outcomes.1 += 1;
                }
            }
            _ => assert_eq!(now, State::Version(variant), "{label}"),
        }
        current = now;
    }
    eprintln!(
        "{KILLS} runs of a {total_rows}-row import ({window_ms} ms window): {mid} killed mid-transaction, {timed} \
         killed at a random time ({} rolled back, {} committed), {finished} let finish; \
         {spilled} of the mid-transaction kills left uncommitted frames in the WAL; all consistent",
        timed_outcomes.0, timed_outcomes.1
    );
    assert!(mid >= 20);
    // The point of the small page cache: some kills must really catch uncommitted pages
    // in the WAL, or this test only ever kills before anything reached the disk.
    assert!(
        spilled >= 1,
        "no mid-transaction kill left frames in the WAL"
    );
}
