//! The migrator: databases of every earlier schema version upgrade to exactly the schema of
//! a fresh database, with their rows; newer databases are refused untouched.
//!
//! Adding `0002_*.sql` extends these tests by itself: `every_earlier_version_upgrades`
//! builds a database at each version `0..SCHEMA_VERSION` by applying the first k steps, and
//! `committed_dumps_upgrade_with_their_rows` replays every `fixtures/store/migrations/v*.sql`
//! (write the dump of the version being superseded with `cargo test --test store_migrations
//! -- --ignored write_dump_fixture` before adding the step).

#![allow(clippy::expect_used)] // tests and their helpers may expect

use crate::store_common;

use std::path::{Path, PathBuf};

use rusqlite::Connection;
use store_common::{assert_healthy, rows, schema, tables};
use trailprint::Error;
use trailprint::gp::Kernel;
use trailprint::store::migrations::{MIGRATIONS, migrate_to, user_version};
use trailprint::store::{
    CollectedFingerprint, FitRecord, ImportOptions, PlanRecord, SCHEMA_VERSION, SessionEvent, Store,
};

fn fresh_schema(dir: &Path) -> Vec<String> {
    let path = dir.join("fresh.db");
    let store = Store::open(&path).expect("fresh");
    store.with_connection(|c| Ok(schema(c))).expect("schema")
}

#[test]
fn migrations_are_numbered_from_one_without_gaps() {
    for (i, m) in MIGRATIONS.iter().enumerate() {
        assert_eq!(m.version as usize, i + 1, "{}", m.name);
        assert!(
            m.name.starts_with(&format!("{:04}_", m.version)),
            "{} must be named {:04}_<what>",
            m.name,
            m.version
        );
        let upper = m.sql.to_uppercase();
        assert!(
            !upper.contains("BEGIN;") && !upper.contains("COMMIT;"),
            "{}: the migrator owns the transaction",
            m.name
        );
    }
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../schema/migrations"));
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .expect("schema/migrations")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".sql"))
        .collect();
    files.sort();
    let names: Vec<String> = MIGRATIONS
        .iter()
        .map(|m| format!("{}.sql", m.name))
        .collect();
    assert_eq!(
        files, names,
        "every file in schema/migrations is in MIGRATIONS, in order"
    );
}

#[test]
fn every_earlier_version_upgrades_to_the_fresh_schema() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fresh = fresh_schema(dir.path());
    for k in 0..SCHEMA_VERSION {
        let path = dir.path().join(format!("v{k}.db"));
        if k == 0 {
            // Version 0: the empty file a first launch finds (or creates).
            std::fs::File::create(&path).expect("empty file");
        } else {
            let mut conn = Connection::open(&path).expect("open");
            migrate_to(&mut conn, &path.display().to_string(), k).expect("first k steps");
            assert_eq!(user_version(&conn).expect("version"), k);
        }
        let store = Store::open(&path).expect("upgrade");
        store
            .with_connection(|c| {
                assert_eq!(user_version(c)?, SCHEMA_VERSION);
                assert_eq!(schema(c), fresh, "schema after upgrading from version {k}");
                assert_healthy(c);
                Ok(())
            })
            .expect("check");
        drop(store);
        // Opening again is a no-op.
        Store::open(&path).expect("reopen");
    }
}

#[test]
fn newer_databases_are_refused_untouched() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("future.db");
    {
        let store = Store::open(&path).expect("create");
        store
            .import_json(
                r#"{"format":"survey-building/1","name":"x","vertices":[{"id":"a","x":0,"y":0}],"edges":[]}"#,
                "x",
                &ImportOptions::default(),
            )
            .expect("import");
        store
            .with_connection(|c| {
                c.pragma_update(None, "user_version", SCHEMA_VERSION + 41)?;
                Ok(())
            })
            .expect("bump");
    }
    let before = std::fs::read(&path).expect("bytes");
    let err = Store::open(&path).expect_err("newer");
    let msg = err.to_string();
    assert!(matches!(err, Error::Database { .. }), "{msg}");
    assert!(msg.contains(&path.display().to_string()), "{msg}");
    assert!(
        msg.contains(&format!("version {}", SCHEMA_VERSION + 41)),
        "{msg}"
    );
    assert!(msg.contains(&format!("up to {SCHEMA_VERSION}")), "{msg}");
    assert_eq!(std::fs::read(&path).expect("bytes"), before);
    assert!(trailprint::store::Reader::open(&path).is_err());
}

#[test]
fn a_failing_step_leaves_the_previous_version() {
    // A database whose tables clash with step 1 (someone else's file): the step fails, the
    // version stays 0 and the foreign table is untouched.
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("clash.db");
    {
        let conn = Connection::open(&path).expect("open");
        conn.execute_batch("CREATE TABLE buildings (x); INSERT INTO buildings VALUES (42);")
            .expect("clash");
    }
    // The store refuses it before migrating (issue 14: not ours), byte for byte untouched.
    let before = std::fs::read(&path).expect("bytes");
    let err = Store::open(&path).expect_err("clash");
    assert!(
        err.to_string().contains("not a trailprint database"),
        "{err}"
    );
    assert_eq!(std::fs::read(&path).expect("bytes"), before);
    // The migrator run on it anyway fails at step 1 and leaves version 0.
    let mut conn = Connection::open(&path).expect("open");
    let err = trailprint::store::migrations::migrate(&mut conn, "clash.db").expect_err("clash");
    assert!(err.to_string().contains("migration 0001_init"), "{err}");
    drop(conn);
    let conn = Connection::open(&path).expect("open");
    assert_eq!(user_version(&conn).expect("version"), 0);
    assert_eq!(rows(&conn, "buildings"), vec!["42".to_string()]);
    assert_eq!(tables(&conn), vec!["buildings".to_string()]);
}

fn dumps_dir() -> PathBuf {
    store_common::fixtures().join("migrations")
}

#[test]
fn committed_dumps_upgrade_with_their_rows() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fresh = fresh_schema(dir.path());
    let mut seen = 0;
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dumps_dir())
        .expect("fixtures/store/migrations")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "sql"))
        .collect();
    entries.sort();
    for dump in entries {
        // `v1.sql` holds a database at version 1.
        let version: u32 = dump
            .file_stem()
            .and_then(|s| s.to_str())
            .and_then(|s| s.strip_prefix('v'))
            .and_then(|s| s.parse().ok())
            .expect("dump files are named v<version>.sql");
        let sql = std::fs::read_to_string(&dump).expect("dump");
        let path = dir.path().join("from-dump.db");
        let _ = std::fs::remove_file(&path);
        let before: Vec<(String, Vec<String>)> = {
            let conn = Connection::open(&path).expect("open");
            conn.execute_batch(&sql).expect("load dump");
            tables(&conn)
                .into_iter()
                .filter(|t| t != "sqlite_sequence")
                .map(|t| {
                    let r = rows(&conn, &t);
                    (t, r)
                })
                .collect()
        };
        let store = Store::open(&path).expect("upgrade dump");
        store
            .with_connection(|c| {
                assert_eq!(
                    schema(c),
                    fresh,
                    "{}: the upgraded schema differs from a fresh one (was a released \
                     migration edited?)",
                    dump.display()
                );
                assert_healthy(c);
                // Rows of tables no later step rewrites are kept verbatim (a step that
                // reshapes a table must extend this check for it).
                for (t, r) in &before {
                    // 0002 adds four provenance columns (uid, device, surveyor_name,
                    // imported_ms) to survey_sessions, NULL for sessions recorded before it.
                    let expect: Vec<String> = if t == "survey_sessions" && version < 2 {
                        r.iter()
                            .map(|row| format!("{row}, NULL, NULL, NULL, NULL"))
                            .collect()
                    } else {
                        r.clone()
                    };
                    assert_eq!(rows(c, t), expect, "{}: rows of {t}", dump.display());
                }
                Ok(())
            })
            .expect("check");
        // And the data is usable through the API.
        for b in store.list_buildings().expect("list") {
            store.get_building(b.id).expect("building from an old dump");
            store.latest_fit(b.id).expect("fit");
            store.list_plans(b.id).expect("plans");
            for s in store.list_sessions(b.id).expect("sessions") {
                store.list_events(s.id, 0).expect("events");
            }
        }
        seen += 1;
    }
    assert!(seen >= 1, "no dump fixtures in {}", dumps_dir().display());
}

/// Writes `fixtures/store/migrations/v{SCHEMA_VERSION}.sql`: a small database at the current
/// version with a row in every table. Run it (it is ignored otherwise) before adding the next
/// migration, and commit the file.
#[test]
#[ignore]
fn write_dump_fixture() {
    let store = Store::open_in_memory().expect("store");
    let fixture = store_common::fixtures().join("good/two_floors.json");
    let text = std::fs::read_to_string(&fixture).expect("fixture");
    let id = store
        .import_json(&text, "two_floors.json", &ImportOptions::default())
        .expect("import")
        .id;
    store
        .record_fit(
            id,
            &FitRecord {
                kernel: Kernel::new(40.0, 6.0, 9.0),
                log_likelihood: -123.5,
                aps_used: vec!["aa:bb:cc:dd:ee:01".into()],
                ap_rule: Default::default(),
                fitted_ms: 1_700_000_000_000,
            },
        )
        .expect("fit");
    let plan = store
        .save_plan(
            id,
            &PlanRecord {
                start: "g0".into(),
                end: "g2".into(),
                budget_m: 10.0,
                surveyor: Some(trailprint::surveyor::Surveyor::robot_every(0.5)),
                kernel: Kernel::new(40.0, 6.0, 9.0),
                algorithm: trailprint::plan::Algorithm::Greedy.into(),
                seed: Some(7),
                walk: vec!["g0".into(), "g1".into(), "g2".into()],
                length_m: 8.0,
                samples: 17,
                utility_nats: 3.5,
                elapsed_ms: 12,
                created_ms: 1_700_000_000_001,
            },
        )
        .expect("plan");
    let s = store
        .create_session(id, Some(plan), None, 1_700_000_000_002)
        .expect("session");
    for e in [
        SessionEvent::CheckIn {
            vertex: "g0".into(),
        },
        SessionEvent::Step {
            steps: 2,
            distance_m: 1.4,
        },
        SessionEvent::Scan(CollectedFingerprint {
            x: 1.4,
            y: 0.0,
            floor: 0,
            sigma_m: 0.07,
            since_checkin_m: Some(1.4),
            rss: [("aa:bb:cc:dd:ee:01".to_string(), -63.0)].into(),
        }),
        SessionEvent::Pause,
    ] {
        store.append_event(s, 1_700_000_000_100, &e).expect("event");
    }
    let sql = store.with_connection(|c| Ok(sql_dump(c))).expect("dump");
    let out = dumps_dir().join(format!("v{SCHEMA_VERSION}.sql"));
    std::fs::create_dir_all(dumps_dir()).expect("dir");
    std::fs::write(&out, sql).expect("write");
    eprintln!("wrote {}", out.display());
}

/// A replayable SQL dump: the schema in creation order, then the rows, then user_version.
fn sql_dump(conn: &Connection) -> String {
    use rusqlite::types::ValueRef;
    let mut out = format!(
        "-- A database at schema version {SCHEMA_VERSION}, written by\n-- `cargo test --test \
         store_migrations -- --ignored write_dump_fixture`. Do not edit.\n"
    );
    let mut st = conn
        .prepare(
            "SELECT type, name, sql FROM sqlite_master
             WHERE sql IS NOT NULL AND name <> 'sqlite_sequence' ORDER BY rowid",
        )
        .expect("master");
    let objects: Vec<(String, String, String)> = st
        .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
        .expect("query")
        .collect::<Result<_, _>>()
        .expect("rows");
    for (_, _, sql) in &objects {
        out.push_str(sql);
        out.push_str(";\n");
    }
    let mut names: Vec<&str> = objects
        .iter()
        .filter(|(t, _, _)| t == "table")
        .map(|(_, n, _)| n.as_str())
        .collect();
    names.push("sqlite_sequence");
    for t in names {
        if t == "sqlite_sequence" {
            // SQLite filled it while the rows went in; set it as it was.
            out.push_str("DELETE FROM sqlite_sequence;\n");
        }
        let mut st = conn
            .prepare(&format!("SELECT * FROM \"{t}\""))
            .expect("select");
        let n = st.column_count();
        let lines: Vec<String> = st
            .query_map([], |r| {
                let vals = (0..n)
                    .map(|i| {
                        r.get_ref(i).map(|v| match v {
                            ValueRef::Null => "NULL".to_string(),
                            ValueRef::Integer(i) => i.to_string(),
                            ValueRef::Real(f) => format!("{f:?}"),
                            ValueRef::Text(s) => {
                                format!("'{}'", String::from_utf8_lossy(s).replace('\'', "''"))
                            }
                            ValueRef::Blob(b) => format!(
                                "X'{}'",
                                b.iter().map(|x| format!("{x:02X}")).collect::<String>()
                            ),
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                Ok(format!("INSERT INTO \"{t}\" VALUES ({});", vals.join(", ")))
            })
            .expect("rows")
            .collect::<Result<_, _>>()
            .expect("rows");
        for l in lines {
            out.push_str(&l);
            out.push('\n');
        }
    }
    out.push_str(&format!("PRAGMA user_version = {SCHEMA_VERSION};\n"));
    out
}
