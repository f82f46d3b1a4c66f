//! The store's API on in-memory and file databases: round trips, fits, plans, session
//! helpers, deletes and errors.

#![allow(clippy::expect_used)] // tests and their helpers may expect

use crate::store_common;

use std::collections::BTreeMap;

use store_common::{assert_healthy, fixtures, shared_instance, tables, temp_db};
use trailprint::building::BuildingFile;
use trailprint::gp::Kernel;
use trailprint::store::{
    BuildingRef, CollectedFingerprint, FitRecord, ImportOptions, PlanRecord, SessionEvent,
    SessionStatus, Store, collected_csv, collected_json,
};
use trailprint::{Building, Error};

fn read(path: &std::path::Path) -> String {
    std::fs::read_to_string(path).expect("read fixture")
}

fn import(store: &Store, path: &std::path::Path) -> i64 {
    store
        .import_json(
            &read(path),
            &path.display().to_string(),
            &ImportOptions::default(),
        )
        .expect("import")
        .id
}

fn round_trip_files() -> Vec<std::path::PathBuf> {
    vec![
        shared_instance("area-one.json"),
        shared_instance("area-two.json"),
        fixtures().join("good/two_floors.json"),
        fixtures().join("good/minimal.json"),
    ]
}

#[test]
fn import_export_import_gives_the_same_building() {
    for path in round_trip_files() {
        let text = read(&path);
        let original = Building::from_json(&text, "original")
            .expect("valid")
            .to_file();

        let store = Store::open_in_memory().expect("store");
        let id = import(&store, &path);
        let exported = store.export_building(id).expect("export");
        assert_eq!(exported, original, "{}: first export", path.display());

        // Through JSON text and into a second database: still the same, bit for bit.
        let json = exported.to_json();
        let again = Store::open_in_memory().expect("store");
        let id2 = again
            .import_json(&json, "exported", &ImportOptions::default())
            .expect("re-import")
            .id;
        let exported2 = again.export_building(id2).expect("export again");
        assert_eq!(exported2, original, "{}: second export", path.display());
        assert_eq!(exported2.to_json(), json);
        // The file's own JSON, as a value, is what we export (shared instances are canonical).
        if path.to_string_lossy().contains("instances") {
            let a: serde_json::Value = serde_json::from_str(&text).expect("json");
            let b: serde_json::Value = serde_json::from_str(&json).expect("json");
            assert_eq!(a, b, "{}: export differs from the file", path.display());
        }
        store
            .with_connection(|c| {
                assert_healthy(c);
                Ok(())
            })
            .expect("healthy");
    }
}

#[test]
fn get_building_rebuilds_the_graph_by_stable_ids() {
    let store = Store::open_in_memory().expect("store");
    let path = shared_instance("area-two.json");
    import(&store, &path);
    let b = store
        .get_building(BuildingRef::Name("Area Two (synthetic)"))
        .expect("get by name");
    let original = Building::load(&path).expect("load");
    assert_eq!(b.len(), original.len());
    assert_eq!(b.graph.edge_count(), original.graph.edge_count());
    for v in &original.vertices {
        let i = b.vertex_index(&v.id).expect("same ids");
        let j = original.vertex_index(&v.id).expect("id");
        let mut n1: Vec<&str> = b
            .neighbours(i)
            .iter()
            .map(|&(n, _)| b.vertices[n].id.as_str())
            .collect();
        let mut n2: Vec<&str> = original
            .neighbours(j)
            .iter()
            .map(|&(n, _)| original.vertices[n].id.as_str())
            .collect();
        n1.sort();
        n2.sort();
        assert_eq!(n1, n2, "neighbours of {}", v.id);
    }
    assert!((b.total_edge_length() - original.total_edge_length()).abs() < 1e-12);
}

#[test]
fn negative_zero_reads_back_as_zero() {
    // Documented in schema/README.md: the one value SQLite does not keep.
    let store = Store::open_in_memory().expect("store");
    let text = r#"{"format":"survey-building/1","name":"z","vertices":[{"id":"a","x":-0.0,"y":0.5},{"id":"b","x":1.0,"y":0.5}],"edges":[{"a":"a","b":"b"}]}"#;
    let id = store
        .import_json(text, "z", &ImportOptions::default())
        .expect("import")
        .id;
    let x = store.export_building(id).expect("export").vertices[0].x;
    assert_eq!(x, 0.0);
}

#[test]
fn duplicate_names_are_refused_unless_replace() {
    let store = Store::open_in_memory().expect("store");
    let path = shared_instance("area-one.json");
    let first = import(&store, &path);
    let err = store
        .import_json(&read(&path), "again", &ImportOptions::default())
        .expect_err("duplicate");
    assert!(matches!(err, Error::AlreadyExists(_)), "{err}");
    assert!(err.to_string().contains("Area One (synthetic)"), "{err}");
    assert_eq!(store.list_buildings().expect("list").len(), 1);

    store
        .record_fit(first, &fit(1_000, 10.0))
        .expect("fit of the old building");
    let report = store
        .import_json(
            &read(&path),
            "again",
            &ImportOptions {
                replace: true,
                ..Default::default()
            },
        )
        .expect("replace");
    assert_eq!(report.replaced, Some(first));
    assert_ne!(report.id, first, "ids are never reused");
    let list = store.list_buildings().expect("list");
    assert_eq!(list.len(), 1);
    assert_eq!(list[0].fits, 0, "the old building's fits went with it");

    // A building with survey sessions is not replaced: its collected data would be lost.
    store
        .create_session(report.id, None, None, 5)
        .expect("session");
    let err = store
        .import_json(
            &read(&path),
            "third",
            &ImportOptions {
                replace: true,
                ..Default::default()
            },
        )
        .expect_err("sessions block replace");
    assert!(err.to_string().contains("survey session"), "{err}");
    assert_eq!(store.list_buildings().expect("list")[0].id, report.id);
}

#[test]
fn list_counts_and_progress_hook() {
    let store = Store::open_in_memory().expect("store");
    let path = shared_instance("area-one.json");
    let calls = std::cell::Cell::new(0u64);
    let hook = |n: u64| calls.set(n);
    let report = store
        .import_json(
            &read(&path),
            "a1",
            &ImportOptions {
                replace: false,
                progress: Some(&hook),
            },
        )
        .expect("import");
    assert_eq!(calls.get(), report.rows);
    let b = Building::load(&path).expect("load");
    let readings: usize = [&b.pilot, &b.test_points, &b.dense_survey]
        .iter()
        .flat_map(|l| l.iter())
        .map(|f| f.rss.len())
        .sum();
    let info = store.building_info("Area One (synthetic)").expect("info");
    assert_eq!(info.vertices, 27);
    assert_eq!(info.edges, 37);
    assert_eq!(
        (info.pilot, info.test_points, info.dense_survey),
        (20, 58, 212)
    );
    assert_eq!(info.access_points, 11);
    assert_eq!(info.floors, 1);
    assert!(!info.has_kernel);
    assert_eq!(
        report.rows as usize,
        1 + 1 + 27 + 37 + 11 + 20 + 58 + 212 + readings
    );
}

#[test]
fn delete_removes_every_row_of_the_building() {
    let store = Store::open_in_memory().expect("store");
    let keep = import(&store, &fixtures().join("good/minimal.json"));
    let before = store
        .with_connection(|c| Ok(store_common::dump(c)))
        .expect("dump");
    let id = import(&store, &fixtures().join("good/two_floors.json"));
    let plan = store.save_plan(id, &plan_record()).expect("plan");
    store.record_fit(id, &fit(1, -3.0)).expect("fit");
    let session = store
        .create_session(
            id,
            Some(plan),
            Some(&serde_json::json!({"kind": "human"})),
            7,
        )
        .expect("session");
    store
        .append_event(session, 8, &SessionEvent::Scan(scan(0.5, -60.0)))
        .expect("scan");
    let info = store
        .delete_building("Two floors, with stairs")
        .expect("delete");
    assert_eq!(
        (info.plans, info.fits, info.sessions, info.collected),
        (1, 1, 1, 1)
    );
    let after = store
        .with_connection(|c| {
            assert_healthy(c);
            Ok(store_common::dump(c))
        })
        .expect("dump");
    // Everything but the AUTOINCREMENT counters is as before the import.
    let strip = |d: &str| {
        d.lines()
            .filter(|l| !l.starts_with("sqlite_sequence"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(strip(&before), strip(&after));
    assert!(matches!(store.get_building(id), Err(Error::NotFound(_))));
    assert!(store.get_building(keep).is_ok());
    assert!(matches!(store.delete_building(id), Err(Error::NotFound(_))));
}

fn fit(at: i64, ll: f64) -> FitRecord {
    FitRecord {
        kernel: Kernel::new(168.4, 23.86, 1.08),
        log_likelihood: ll,
        aps_used: vec!["ap-07".into(), "ap-01".into(), "new-ap".into()],
        ap_rule: Default::default(),
        fitted_ms: at,
    }
}

#[test]
fn fits_are_recorded_and_the_latest_is_returned() {
    let store = Store::open_in_memory().expect("store");
    let id = import(&store, &shared_instance("area-one.json"));
    assert_eq!(store.latest_fit(id).expect("none yet"), None);
    let a = store.record_fit(id, &fit(2_000, -10.0)).expect("fit a");
    let b = store
        .record_fit(id, &fit(1_000, -20.0))
        .expect("fit b (older)");
    let latest = store.latest_fit(id).expect("latest").expect("some");
    assert_eq!(latest.id, a);
    assert_ne!(a, b);
    assert_eq!(latest.record, fit(2_000, -10.0));

    let mut dup = fit(3_000, 1.0);
    dup.aps_used.push("ap-01".into());
    let err = store.record_fit(id, &dup).expect_err("listed twice");
    assert!(err.to_string().contains("ap-01"), "{err}");
    let mut bad = fit(3_000, 1.0);
    bad.kernel.ell = f64::NAN;
    assert!(store.record_fit(id, &bad).is_err());
    assert_eq!(store.latest_fit(id).expect("latest").expect("some").id, a);
    assert!(matches!(
        store.record_fit(BuildingRef::Name("nope"), &fit(1, 1.0)),
        Err(Error::NotFound(_))
    ));

    // What the fitter returns goes in as it is.
    let result = trailprint::gp::fit::FitResult {
        kernel: Kernel::new(103.22, 32.17, 3.3),
        log_likelihood: -812.5,
        aps_used: vec!["ap-01".into(), "ap-02".into()],
        ap_rule: trailprint::gp::fit::ApRule::HalfOfLocations,
        locations: 30,
    };
    store
        .record_fit(id, &FitRecord::from_fit(&result, 4_000))
        .expect("fit result");
    let latest = store.latest_fit(id).expect("latest").expect("some");
    assert_eq!(latest.record.kernel, result.kernel);
    assert_eq!(latest.record.aps_used, result.aps_used);
    assert_eq!(latest.record.ap_rule, result.ap_rule);
    // A fit on a large floor keeps its rule (migration 0004), and drops it with the fit.
    let heard_only = trailprint::gp::fit::FitResult {
        ap_rule: trailprint::gp::fit::ApRule::HeardOnly,
        ..result
    };
    let h = store
        .record_fit(id, &FitRecord::from_fit(&heard_only, 5_000))
        .expect("heard-only fit");
    let latest = store.latest_fit(id).expect("latest").expect("some");
    assert_eq!((latest.id, latest.record.ap_rule), (h, heard_only.ap_rule));
    store
        .with_connection(|c| {
            let n: i64 = c.query_row(
                "SELECT count(*) FROM fit_rules WHERE fit_id = ?1",
                [h],
                |r| r.get(0),
            )?;
            assert_eq!(n, 1);
            Ok(())
        })
        .expect("count");
}

fn plan_record() -> PlanRecord {
    PlanRecord {
        start: "g0".into(),
        end: "f1".into(),
        budget_m: 20.0,
        surveyor: Some(trailprint::surveyor::Surveyor::human()),
        kernel: Kernel::new(40.0, 6.0, 9.0),
        algorithm: trailprint::plan::Algorithm::Genetic.into(),
        seed: Some(u64::MAX - 1),
        walk: ["g0", "g1", "g2", "f2", "f1"].map(String::from).to_vec(),
        length_m: 4.5 + 3.5 + 6.0 + 5.0,
        samples: 4,
        utility_nats: 12.25,
        elapsed_ms: 812,
        created_ms: 1_700_000_000_000,
    }
}

/// Plans saved before the surveyor types were merged hold the planner's older JSON form
/// (`{"model": ...}`); they read back as the same surveyor, and a shape no version of the
/// planner wrote reads as a plan without a recorded surveyor instead of failing the list.
#[test]
fn plans_stored_with_older_surveyor_forms_are_read() {
    use trailprint::surveyor::Surveyor;
    let store = Store::open_in_memory().expect("store");
    let id = import(&store, &fixtures().join("good/two_floors.json"));
    let pid = store.save_plan(id, &plan_record()).expect("save");
    let set = |text: &str| {
        store
            .with_connection(|c| {
                c.execute(
                    "UPDATE plans SET surveyor = ?1 WHERE id = ?2",
                    rusqlite::params![text, pid],
                )?;
                Ok(())
            })
            .expect("update");
        store.load_plan(pid).expect("load").record.surveyor
    };
    let human = Surveyor::Human {
        step_length_m: trailprint::surveyor::DEFAULT_STEP_LENGTH_M,
        speed_mps: 1.1,
        scan_interval_s: 3.0,
        step_error: 0.1,
        turn_threshold_deg: 40.0,
    };
    assert_eq!(
        set(
            r#"{"model":"human","speed":1.1,"scan_interval":3.0,"step_error":0.1,"turn_threshold_deg":40.0}"#
        ),
        Some(human)
    );
    assert_eq!(
        set(r#"{"model":"robot","interval":0.8}"#),
        Some(Surveyor::robot_every(0.8))
    );
    assert_eq!(set("null"), None);
    assert_eq!(set(r#"{"robot":{"speed":0.5,"interval_s":1.0}}"#), None);
    assert_eq!(store.list_plans(id).expect("list").len(), 1);
    // Saved again, a plan is written in the current form.
    let mut p = plan_record();
    p.surveyor = Some(human);
    let again = store.save_plan(id, &p).expect("save");
    let text: String = store
        .with_connection(|c| {
            Ok(
                c.query_row("SELECT surveyor FROM plans WHERE id = ?1", [again], |r| {
                    r.get(0)
                })?,
            )
        })
        .expect("read");
    assert!(text.contains(r#""kind":"human""#), "{text}");
    assert_eq!(store.load_plan(again).expect("load").record, p);
}

#[test]
fn plans_round_trip_and_walks_are_checked() {
    let store = Store::open_in_memory().expect("store");
    let id = import(&store, &fixtures().join("good/two_floors.json"));
    let p = plan_record();
    let pid = store.save_plan(id, &p).expect("save");
    let loaded = store.load_plan(pid).expect("load");
    assert_eq!(loaded.record, p);
    assert_eq!(loaded.building_id, id);
    let mut greedy = p.clone();
    greedy.seed = None;
    greedy.algorithm = trailprint::plan::Algorithm::Greedy.into();
    greedy.created_ms += 1;
    store.save_plan(id, &greedy).expect("save");
    let list = store.list_plans(id).expect("list");
    assert_eq!(list.len(), 2);
    assert_eq!(list[1].record, greedy);

    let mut hop = p.clone();
    hop.walk = ["g0", "g2", "f2", "f1"].map(String::from).to_vec();
    let err = store.save_plan(id, &hop).expect_err("g0-g2 is no edge");
    assert!(matches!(err, Error::InvalidWalk { step: 1, .. }), "{err}");
    let mut unknown = p.clone();
    unknown.walk[2] = "zz".into();
    assert!(matches!(
        store.save_plan(id, &unknown),
        Err(Error::InvalidWalk { step: 2, .. })
    ));
    let mut ends = p.clone();
    ends.end = "g0".into();
    assert!(store.save_plan(id, &ends).is_err());
    assert!(matches!(store.load_plan(9999), Err(Error::NotFound(_))));
    assert_eq!(store.list_plans(id).expect("list").len(), 2);
}

fn scan(x: f64, rss: f64) -> CollectedFingerprint {
    CollectedFingerprint {
        x,
        y: 0.0,
        floor: 0,
        sigma_m: 0.25,
        since_checkin_m: Some(x),
        rss: BTreeMap::from([
            ("aa:bb:cc:dd:ee:01".to_string(), rss),
            ("new, \"quoted\" ap".to_string(), -90.5),
        ]),
    }
}

#[test]
fn session_events_append_in_order_and_read_back() {
    let store = Store::open_in_memory().expect("store");
    let id = import(&store, &fixtures().join("good/two_floors.json"));
    let plan = store.save_plan(id, &plan_record()).expect("plan");
    let plan2 = store.save_plan(id, &plan_record()).expect("plan");
    let s = store
        .create_session(id, Some(plan), None, 100)
        .expect("session");
    let events = vec![
        SessionEvent::CheckIn {
            vertex: "g0".into(),
        },
        SessionEvent::Step {
            steps: 3,
            distance_m: 2.1,
        },
        SessionEvent::Scan(scan(2.1, -55.0)),
        SessionEvent::Pose {
            x: 2.0,
            y: 0.1,
            floor: 0,
            sigma_m: 0.3,
        },
        SessionEvent::Pause,
        SessionEvent::Resume,
        SessionEvent::Replan { plan_id: plan2 },
        SessionEvent::Scan(CollectedFingerprint {
            since_checkin_m: None,
            rss: BTreeMap::new(),
            ..scan(3.0, -50.0)
        }),
        SessionEvent::Finish,
    ];
    for (i, e) in events.iter().enumerate() {
        let seq = store.append_event(s, 1000 + i as i64, e).expect("append");
        assert_eq!(seq, i as i64 + 1);
    }
    let stored = store.list_events(s, 0).expect("events");
    assert_eq!(stored.len(), events.len());
    for (i, (st, e)) in stored.iter().zip(&events).enumerate() {
        assert_eq!(&st.event, e, "event {i}");
        assert_eq!(st.seq, i as i64 + 1);
        assert_eq!(st.at_ms, 1000 + i as i64);
    }
    assert_eq!(store.list_events(s, 7).expect("tail").len(), 2);

    // Refused: unknown vertex, unknown floor, other building's plan, NaN, unknown session.
    let bad = [
        SessionEvent::CheckIn {
            vertex: "nowhere".into(),
        },
        SessionEvent::Pose {
            x: 0.0,
            y: 0.0,
            floor: 7,
            sigma_m: 1.0,
        },
        SessionEvent::Replan { plan_id: 999 },
        SessionEvent::Step {
            steps: 1,
            distance_m: f64::NAN,
        },
        SessionEvent::Scan(scan(1.0, 99.0)),
    ];
    for e in &bad {
        assert!(store.append_event(s, 5, e).is_err(), "{e:?} accepted");
    }
    assert!(matches!(
        store.append_event(4242, 5, &SessionEvent::Pause),
        Err(Error::NotFound(_))
    ));
    assert_eq!(store.list_events(s, 0).expect("events").len(), events.len());

    let sessions = store.list_sessions(id).expect("sessions");
    assert_eq!(sessions.len(), 1);
    assert_eq!(sessions[0].status, SessionStatus::Finished);
    assert_eq!(sessions[0].last_seq, events.len() as i64);
    assert_eq!(sessions[0].collected, 2);

    // The schema itself keeps the log append-only and gap-free.
    store
        .with_connection(|c| {
            let gap = c.execute(
                "INSERT INTO session_events (session_id, seq, kind, at_ms, payload)
                 VALUES (?1, 99, 'pause', 0, '{}')",
                [s],
            );
            assert!(gap.is_err(), "a gap in seq was accepted");
            let upd = c.execute(
                "UPDATE session_events SET at_ms = 0 WHERE session_id = ?1",
                [s],
            );
            assert!(upd.is_err(), "an event was updated");
            let bad_kind = c.execute(
                "INSERT INTO session_events (session_id, seq, kind, at_ms, payload)
                 VALUES (?1, 10, 'teleport', 0, '{}')",
                [s],
            );
            assert!(bad_kind.is_err(), "an unknown kind was accepted");
            Ok(())
        })
        .expect("raw sql");
}

#[test]
fn collected_fingerprints_export_as_csv_and_json() {
    let store = Store::open_in_memory().expect("store");
    let id = import(&store, &fixtures().join("good/two_floors.json"));
    let s1 = store.create_session(id, None, None, 1).expect("s1");
    let s2 = store.create_session(id, None, None, 2).expect("s2");
    store
        .append_event(s1, 10, &SessionEvent::Scan(scan(0.1, -70.0)))
        .expect("scan");
    store
        .append_event(s2, 20, &SessionEvent::Pause)
        .expect("pause");
    store
        .append_event(s2, 21, &SessionEvent::Scan(scan(0.2, -71.0)))
        .expect("scan");
    let all = store.list_collected(id, None).expect("all");
    assert_eq!(all.len(), 2);
    assert_eq!((all[1].session_id, all[1].seq, all[1].at_ms), (s2, 2, 21));
    assert_eq!(all[0].fingerprint, scan(0.1, -70.0));
    assert_eq!(store.list_collected(id, Some(s2)).expect("s2").len(), 1);

    let csv = collected_csv(&all);
    let lines: Vec<&str> = csv.split("\r\n").collect();
    assert_eq!(
        lines[0],
        "session,seq,at_ms,x,y,floor,sigma_m,since_checkin_m,aa:bb:cc:dd:ee:01,\"new, \"\"quoted\"\" ap\""
    );
    assert_eq!(
        lines[1],
        format!("{s1},1,10,0.1,0.0,0,0.25,0.1,-70.0,-90.5")
    );
    assert_eq!(lines.len(), 4, "header, two rows, final line break");

    let json: serde_json::Value =
        serde_json::from_str(&collected_json("Two floors, with stairs", &all)).expect("json");
    assert_eq!(json["format"], "survey-collected/1");
    assert_eq!(json["fingerprints"][1]["rss"]["aa:bb:cc:dd:ee:01"], -71.0);
    assert_eq!(json["fingerprints"][1]["session_id"], s2);
}

#[test]
fn file_store_readers_and_in_memory_limits() {
    let (_dir, db) = temp_db();
    let store = Store::open(&db).expect("open");
    let id = import(&store, &shared_instance("area-one.json"));
    let reader = store.reader().expect("reader");
    assert_eq!(reader.list_buildings().expect("list").len(), 1);
    assert_eq!(reader.get_building(id).expect("get").len(), 27);
    assert!(reader.latest_fit(id).expect("fit").is_none());
    // A reader cannot write.
    let err = reader
        .connection()
        .execute("DELETE FROM buildings", [])
        .expect_err("read-only");
    assert!(err.to_string().contains("readonly"), "{err}");
    drop(store);
    // Reopening keeps everything.
    let store = Store::open(&db).expect("reopen");
    assert_eq!(store.get_building(id).expect("get").len(), 27);
    let mem = Store::open_in_memory().expect("mem");
    assert!(mem.reader().is_err());
    // The pragmas are in force.
    store
        .with_connection(|c| {
            let fk: i64 = c.pragma_query_value(None, "foreign_keys", |r| r.get(0))?;
            let sync: i64 = c.pragma_query_value(None, "synchronous", |r| r.get(0))?;
            let mode: String = c.pragma_query_value(None, "journal_mode", |r| r.get(0))?;
            let temp: i64 = c.pragma_query_value(None, "temp_store", |r| r.get(0))?;
            assert_eq!((fk, sync, mode.as_str(), temp), (1, 2, "wal", 2));
            Ok(())
        })
        .expect("pragmas");
}

#[test]
fn every_table_is_documented_in_the_schema_readme() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../schema/README.md"))
            .expect("schema/README.md");
    let store = Store::open_in_memory().expect("store");
    let names = store.with_connection(|c| Ok(tables(c))).expect("tables");
    for t in names {
        assert!(
            readme.contains(&format!("`{t}`")),
            "table {t} is not in schema/README.md"
        );
    }
}

#[test]
fn exported_file_parses_as_a_building_file() {
    let store = Store::open_in_memory().expect("store");
    let id = import(&store, &fixtures().join("good/two_floors.json"));
    let json = store.export_building(id).expect("export").to_json();
    let file = BuildingFile::parse(&json, "export").expect("parse");
    assert_eq!(file.format, "survey-building/1");
}

#[test]
fn every_foreign_key_lookup_uses_an_index_on_all_its_columns() {
    // A cascade looks children up by the foreign key's columns; without an index on all of
    // them (or when the planner prefers a shorter primary-key prefix) it scans.
    let store = Store::open_in_memory().expect("store");
    import(&store, &fixtures().join("good/two_floors.json"));
    store
        .with_connection(|c| {
            for t in tables(c) {
                let mut st = c.prepare(&format!("PRAGMA foreign_key_list(\"{t}\")"))?;
                let mut keys: BTreeMap<i64, Vec<String>> = BTreeMap::new();
                for row in
                    st.query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, String>(3)?)))?
                {
                    let (id, col) = row?;
                    keys.entry(id).or_default().push(col);
                }
                for cols in keys.values() {
                    let cond = cols
                        .iter()
                        .map(|c| format!("{c}=?"))
                        .collect::<Vec<_>>()
                        .join(" AND ");
                    // As the cascade does it: delete whole rows (a covering index can hide the problem).
                    let sql = format!("EXPLAIN QUERY PLAN DELETE FROM \"{t}\" WHERE {cond}");
                    let plan: Vec<String> = c
                        .prepare(&sql)?
                        .query_map(rusqlite::params_from_iter(cols.iter().map(|_| 0)), |r| {
                            r.get::<_, String>(3)
                        })?
                        .collect::<Result<_, _>>()?;
                    // The first line is the lookup itself; the others are further cascades.
                    let first = plan.first().map_or("", String::as_str);
                    assert!(
                        first.starts_with("SEARCH")
                            && cols.iter().all(|c| first.contains(&format!("{c}=?"))),
                        "{t}({}): {}",
                        cols.join(", "),
                        plan.join("; ")
                    );
                }
            }
            Ok(())
        })
        .expect("plans");
}

#[test]
fn store_is_shareable_across_threads() {
    // The bindings hand one Store to many threads; readers move to their thread.
    fn send_sync<T: Send + Sync>() {}
    fn send<T: Send>() {}
    send_sync::<Store>();
    send::<trailprint::store::Reader>();
}

#[test]
fn the_same_part_asked_for_twice_is_one_building() {
    use trailprint::building::PartSpec;
    let store = Store::open_in_memory().expect("open");
    let whole = import(&store, &shared_instance("area-two.json"));
    let first_vertex = store.get_building(whole).expect("get").vertices[0]
        .id
        .clone();
    let spec = PartSpec {
        around: vec![(first_vertex, 12.0)],
        ..PartSpec::default()
    };
    let opts = ImportOptions::default();
    let a = store.import_part(whole, &spec, &opts).expect("part");
    assert!(a.rows > 0);
    let info = store.building_info(a.id).expect("info");
    assert_eq!(
        info.source.as_deref(),
        Some("part of \"Area Two (synthetic)\"")
    );
    // Again: the same building, nothing written.
    let b = store
        .import_part(whole, &spec, &opts)
        .expect("the same part");
    assert_eq!((b.id, b.rows), (a.id, 0));
    assert_eq!(store.list_buildings().expect("list").len(), 2);
    // Another part under that name is refused as any import of a taken name is.
    let wider = PartSpec {
        name: Some(a.name.clone()),
        around: spec
            .around
            .iter()
            .map(|(v, r)| (v.clone(), 2.0 * r))
            .collect(),
        ..PartSpec::default()
    };
    let e = store
        .import_part(whole, &wider, &opts)
        .expect_err("name taken");
    assert!(matches!(e, Error::AlreadyExists(_)), "{e}");
    assert_eq!(store.list_buildings().expect("list").len(), 2);
}
