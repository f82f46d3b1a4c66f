//! Readers never see half-written data while a writer works.
//!
//! A writer thread imports, replaces and deletes generated buildings in a loop through the
//! `Store`; reader threads, each with its own read-only connection (`Reader`), check over
//! and over that every building they see has as many vertex and edge rows as its row in
//! `buildings` records, both through the API (which loads and validates the whole building
//! in one read transaction) and with bare SQL in one read transaction.

#![allow(clippy::expect_used)] // tests and their helpers may expect

use crate::store_common;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use store_common::grid_building;
use trailprint::Error;
use trailprint::store::{ImportOptions, Reader, Store};

#[test]
fn readers_see_whole_buildings_or_none() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = dir.path().join("readers.db");
    let store = Store::open(&db).expect("open");
    // Two names, each in two sizes, so that a replace changes the counts.
    let texts: Vec<(String, String)> = [("North", 12), ("North", 16), ("South", 10), ("South", 14)]
        .iter()
        .map(|&(name, side)| {
            (
                name.to_string(),
                grid_building(name, side, 300, 6, side as u32),
            )
        })
        .collect();
    store
        .import_json(&texts[0].1, "north", &ImportOptions::default())
        .expect("first import");

    let stop = Arc::new(AtomicBool::new(false));
    let checks = Arc::new(AtomicU64::new(0));
    let seen_buildings = Arc::new(AtomicU64::new(0));
    let readers: Vec<_> = (0..2)
        .map(|r| {
            let (db, stop, checks, seen) = (
                db.clone(),
                stop.clone(),
                checks.clone(),
                seen_buildings.clone(),
            );
            std::thread::spawn(move || {
                let reader = Reader::open(&db).expect("reader");
                while !stop.load(Ordering::Relaxed) {
                    if r == 0 {
                        // Through the API: list, then load each (it may be gone by then).
                        for info in reader.list_buildings().expect("list") {
                            match reader.get_building(info.id) {
                                Ok(b) => {
                                    assert_eq!(b.name, info.name);
                                    seen.fetch_add(1, Ordering::Relaxed);
                                }
                                Err(Error::NotFound(_)) => {}
                                Err(e) => panic!("reader saw a broken building: {e}"),
                            }
                        }
                    } else {
                        // Bare SQL, separate statements in one read transaction.
                        let conn = reader.connection();
                        let tx = conn.unchecked_transaction().expect("read tx");
                        let rows: Vec<(i64, i64, i64)> = tx
                            .prepare("SELECT id, vertex_count, edge_count FROM buildings")
                            .expect("prepare")
                            .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
                            .expect("query")
                            .collect::<Result<_, _>>()
                            .expect("rows");
                        // The rows of `table` that belong to building `id`.
                        let count = |table: &str, id: i64| -> i64 {
                            tx.query_row(
                                &format!("SELECT count(*) FROM {table} WHERE building_id = ?1"),
                                [id],
                                |r| r.get(0),
                            )
                            .expect("count")
                        };
                        for (id, vertices, edges) in rows {
                            let (v, e) = (count("vertices", id), count("edges", id));
                            assert_eq!((v, e), (vertices, edges), "building {id} half-written");
                            seen.fetch_add(1, Ordering::Relaxed);
                        }
                        tx.finish().expect("end read tx");
                    }
                    checks.fetch_add(1, Ordering::Relaxed);
                }
            })
        })
        .collect();

    // The writer: replace, import, delete, for a bounded number of rounds and time.
    let started = Instant::now();
    let mut writes = 0;
    for round in 0..200 {
        if started.elapsed() > Duration::from_secs(3) && round >= 8 {
            break;
        }
        let (name, text) = &texts[round % texts.len()];
        let replace = ImportOptions {
            replace: true,
            ..Default::default()
        };
        store.import_json(text, name, &replace).expect("import");
        writes += 1;
        if round % 3 == 2 {
            store.delete_building(name.as_str()).expect("delete");
            writes += 1;
        }
    }
    stop.store(true, Ordering::Relaxed);
    for r in readers {
        r.join().expect("a reader failed");
    }
    let (checks, seen) = (
        checks.load(Ordering::Relaxed),
        seen_buildings.load(Ordering::Relaxed),
    );
    eprintln!("{writes} writes; {checks} reader passes looked at {seen} buildings, all whole");
    assert!(
        checks >= 10 && seen >= 10,
        "readers barely ran: {checks} passes, {seen} buildings"
    );
}
