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
    for m in MIGRATIONS.iter().filter(|m| m.version <= target) {
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
