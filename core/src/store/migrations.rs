//! The schema migrator: numbered SQL steps replayed on `PRAGMA user_version`.
//!
//! Modelled on application-services' `sql-support`: the schema version lives in the
//! database header (`user_version`), each step runs in its own transaction together with the
//! version bump (so a kill between steps leaves a database at a whole version), and a
//! database written by a newer build is refused rather than guessed at.
//!
//! Adding a step: write `schema/migrations/000N_<name>.sql` and append it to [`MIGRATIONS`].
//! Never edit a released step; `core/tests/store_migrations.rs` upgrades databases of every
//! earlier version (and committed dumps of them) and compares the result with a fresh one.

use rusqlite::{Connection, TransactionBehavior};

use crate::{Error, Result};

/// One numbered schema step.
#[derive(Debug, Clone, Copy)]
pub struct Migration {
    /// The `user_version` the database has after this step.
    pub version: u32,
    /// File name stem, for messages (`0001_init`).
    pub name: &'static str,
    /// The SQL, without BEGIN/COMMIT: the migrator owns the transaction.
    pub sql: &'static str,
}

/// All steps, in order; step `i` takes the database from version `i` to `i + 1`.
pub const MIGRATIONS: &[Migration] = &[
    Migration {
        version: 1,
        name: "0001_init",
        sql: include_str!("../../../schema/migrations/0001_init.sql"),
    },
    Migration {
        version: 2,
        name: "0002_bundles",
        sql: include_str!("../../../schema/migrations/0002_bundles.sql"),
    },
    Migration {
        version: 3,
        name: "0003_floorplans",
        sql: include_str!("../../../schema/migrations/0003_floorplans.sql"),
    },
    Migration {
        version: 4,
        name: "0004_fit_rules",
        sql: include_str!("../../../schema/migrations/0004_fit_rules.sql"),
    },
];

/// The schema version this build writes: the number of the last migration.
pub const SCHEMA_VERSION: u32 = MIGRATIONS.len() as u32;

/// Reads `PRAGMA user_version`.
pub fn user_version(conn: &Connection) -> rusqlite::Result<u32> {
    conn.pragma_query_value(None, "user_version", |row| row.get::<_, i64>(0))
        .map(|v| u32::try_from(v).unwrap_or(u32::MAX))
}

/// Brings the database up to [`SCHEMA_VERSION`]; `path` names it in errors. Returns the
/// version it found.
pub fn migrate(conn: &mut Connection, path: &str) -> Result<u32> {
    migrate_to(conn, path, SCHEMA_VERSION)
}

/// Applies the steps up to `target` (tests build databases of older versions with it).
///
/// Refuses, without writing anything, a database whose version is above [`SCHEMA_VERSION`].
/// Each step re-reads the version inside its `BEGIN IMMEDIATE` transaction, so two
/// processes opening one new database at once apply every step exactly once.
pub fn migrate_to(conn: &mut Connection, path: &str, target: u32) -> Result<u32> {
    let found = check_version(conn, path)?;
    let target = target.min(SCHEMA_VERSION);
    // Up to date: no write lock is taken, so opening a store never waits for another
    // process's long write.
    for m in MIGRATIONS
        .iter()
        .filter(|m| m.version <= target && m.version > found)
    {
        let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
        let current = user_version(&tx)?;
        if current >= m.version {
            continue; // applied already (perhaps by another process meanwhile)
        }
        tx.execute_batch(m.sql).map_err(|e| Error::Database {
            path: path.to_string(),
            message: format!(
                "migration {} (to version {}) failed: {e}",
                m.name, m.version
            ),
        })?;
        tx.pragma_update(None, "user_version", m.version)?;
        tx.commit()?;
    }
    Ok(found)
}

/// Reads the version and refuses one newer than this build.
pub fn check_version(conn: &Connection, path: &str) -> Result<u32> {
    let found = user_version(conn).map_err(|e| open_error(path, e))?;
    if found > SCHEMA_VERSION {
        return Err(Error::Database {
            path: path.to_string(),
            message: format!(
                "schema version {found} was written by a newer trailprint; this build \
                 reads versions up to {SCHEMA_VERSION} (upgrade trailprint, or use another database)"
            ),
        });
    }
    Ok(found)
}

/// One schema object as `sqlite_master` lists it.
#[derive(Debug, Clone, PartialEq, Eq)]
struct SchemaObject {
    kind: String,
    name: String,
    sql: Option<String>,
}

fn schema_objects(conn: &Connection) -> rusqlite::Result<Vec<SchemaObject>> {
    let mut st = conn.prepare("SELECT type, name, sql FROM sqlite_master ORDER BY type, name")?;
    st.query_map([], |r| {
        Ok(SchemaObject {
            kind: r.get(0)?,
            name: r.get(1)?,
            sql: r.get(2)?,
        })
    })?
    .collect()
}

/// `sqlite_master` of a database built by the migrations, at every version from 0 to
/// [`SCHEMA_VERSION`] (built once, in memory).
fn expected_schemas() -> Result<&'static [Vec<SchemaObject>]> {
    use std::sync::OnceLock;
    static SCHEMAS: OnceLock<Vec<Vec<SchemaObject>>> = OnceLock::new();
    if let Some(s) = SCHEMAS.get() {
        return Ok(s);
    }
    let mut conn = Connection::open_in_memory()?;
    let mut out = vec![schema_objects(&conn)?];
    for m in MIGRATIONS {
        migrate_to(&mut conn, ":memory:", m.version)?;
        out.push(schema_objects(&conn)?);
    }
    Ok(SCHEMAS.get_or_init(|| out))
}

/// Decides, reading only, whether a database is one this build may use, and returns its
/// schema version. A database is ours when it is empty (version 0, no schema objects) or
/// carries every table, index and trigger our migrations create at its version, exactly as
/// they create them; anything else (another program's file, a dropped table, a newer
/// version) is refused with the reason, and nothing
/// has been written to it: call this before any pragma that writes (`journal_mode`).
/// Everything is read in one read transaction, so a concurrent migration is seen whole.
/// `PRAGMA quick_check`, which reads every page, is [`quick_check`], run before the first
/// write.
pub(crate) fn inspect(conn: &Connection, path: &str) -> Result<u32> {
    let refuse = |message: String| Error::Database {
        path: path.to_string(),
        message,
    };
    let tx = conn
        .unchecked_transaction()
        .map_err(|e| open_error(path, e))?;
    let found = check_version(&tx, path)?;
    let actual = schema_objects(&tx).map_err(|e| open_error(path, e))?;
    let expected = expected_schemas()?
        .get(found as usize)
        .map_or(&[][..], Vec::as_slice);
    if found == 0 && !actual.is_empty() {
        let mut names: Vec<String> = actual
            .iter()
            .filter(|o| o.kind == "table")
            .map(|o| format!("{:?}", o.name))
            .collect();
        if names.is_empty() {
            names = actual.iter().map(|o| format!("{:?}", o.name)).collect();
        }
        let shown: Vec<&str> = names.iter().take(5).map(String::as_str).collect();
        return Err(refuse(format!(
            "not a trailprint database: it has no trailprint schema version but holds {} \
             schema object(s) ({}{}); it was left untouched (use another --db)",
            actual.len(),
            shown.join(", "),
            if names.len() > shown.len() {
                ", ..."
            } else {
                ""
            }
        )));
    }
    for want in expected {
        match actual
            .iter()
            .find(|o| o.kind == want.kind && o.name == want.name)
        {
            None => {
                return Err(refuse(format!(
                    "schema version {found} needs {} {:?}, which is missing: the database is \
                     damaged or not trailprint's; it was left untouched",
                    want.kind, want.name
                )));
            }
            Some(have) if have.sql != want.sql => {
                return Err(refuse(format!(
                    "{} {:?} is not the one trailprint's schema version {found} creates: the \
                     database is damaged or not trailprint's; it was left untouched",
                    want.kind, want.name
                )));
            }
            Some(_) => {}
        }
    }
    // A read transaction: ending it writes nothing.
    tx.rollback().map_err(|e| open_error(path, e))?;
    Ok(found)
}

/// Runs `PRAGMA quick_check` (every page's b-tree structure, NOT NULL and CHECK
/// constraints) and refuses a database that fails it, naming the first problems. Reads only.
pub(crate) fn quick_check(conn: &Connection, path: &str) -> Result<()> {
    // A page too broken to walk makes the pragma fail instead of reporting it.
    let problems = conn
        .prepare("PRAGMA quick_check(5)")
        .and_then(|mut st| {
            st.query_map([], |r| r.get::<_, String>(0))?
                .collect::<rusqlite::Result<Vec<String>>>()
        })
        .or_else(|e| match e.sqlite_error_code() {
            Some(rusqlite::ErrorCode::DatabaseCorrupt | rusqlite::ErrorCode::NotADatabase) => {
                Ok(vec![e.to_string()])
            }
            _ => Err(open_error(path, e)),
        })?;
    if problems != ["ok"] {
        return Err(Error::Database {
            path: path.to_string(),
            message: format!(
                "the database is corrupt (PRAGMA quick_check: {}); nothing was written to it \
                 (restore a backup, or export what still reads with another tool)",
                problems.join("; ")
            ),
        });
    }
    Ok(())
}

/// Turns an SQLite error met while opening a database into a message that names the file
/// and the likely cause.
pub(crate) fn open_error(path: &str, e: rusqlite::Error) -> Error {
    use rusqlite::ErrorCode;
    let cause = match e.sqlite_error_code() {
        Some(ErrorCode::NotADatabase) => "not an SQLite database (or it is corrupt)",
        Some(ErrorCode::CannotOpen) => "cannot open or create the file (is the location writable?)",
        Some(ErrorCode::ReadOnly) => "the database is read-only",
        Some(ErrorCode::PermissionDenied) => "permission denied",
        Some(ErrorCode::DatabaseBusy) | Some(ErrorCode::DatabaseLocked) => {
            "the database is locked by another process"
        }
        Some(ErrorCode::DatabaseCorrupt) => "the database is corrupt",
        _ => "cannot use the database",
    };
    Error::Database {
        path: path.to_string(),
        message: format!("{cause}: {e}"),
    }
}
