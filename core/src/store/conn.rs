//! Opening connections: the pragmas every connection gets, and the writer/reader split.
//!
//! Threading rule: a [`Store`](super::Store) owns the one writer connection behind a mutex;
//! readers open their own read-only connections ([`Reader`](super::Reader)), which WAL lets
//! run while the writer works, each reading one committed snapshot per transaction.

use std::path::Path;
use std::time::Duration;

use rusqlite::{Connection, OpenFlags};

use super::migrations::{inspect, open_error};
use crate::{Error, Result};

/// How long a statement waits for a lock held by another connection before failing. Long
/// enough for the longest write trailprint makes: an import of a 64 MiB file (the largest
/// accepted) is one transaction of about 7 s on a desktop and several times that on a
/// phone, and a second command started meanwhile must wait for it, not fail with
/// "database is locked" (issue 14). A lock held longer than this is not a trailprint write.
pub const BUSY_TIMEOUT: Duration = Duration::from_secs(120);

/// Pragmas that only make sense on a connection that writes. Each with its reason.
fn writer_pragmas(conn: &Connection) -> rusqlite::Result<()> {
    // WAL: readers never block the writer nor see its uncommitted pages, and a kill at any
    // moment leaves the database at its last commit (uncommitted WAL frames are ignored).
    // (An in-memory database answers "memory"; either is fine.)
    let _mode: String = conn.pragma_update_and_check(None, "journal_mode", "WAL", |r| r.get(0))?;
    // FULL, not NORMAL: in WAL mode NORMAL skips the fsync at commit, so a power loss can
    // drop the last committed transactions; a scan acknowledged to the surveyor must survive.
    // The cost, one fsync per commit, is small at one scan every few seconds.
    conn.pragma_update(None, "synchronous", "FULL")?;
    Ok(())
}

/// Pragmas every connection gets, reader or writer.
fn common_pragmas(conn: &Connection) -> rusqlite::Result<()> {
    // SQLite leaves foreign keys off by default; the schema relies on them and on cascades.
    conn.pragma_update(None, "foreign_keys", true)?;
    // Another connection briefly holding the lock (a checkpoint, a second process) makes us
    // wait instead of failing at once with SQLITE_BUSY.
    conn.busy_timeout(BUSY_TIMEOUT)?;
    // Sorts and temporary indices stay in memory: Android offers SQLite no temp directory.
    conn.pragma_update(None, "temp_store", "MEMORY")?;
    Ok(())
}

/// Opens (creating if needed) the writer connection of a database file, checks that it is
/// ours (empty, or our schema at a version this build knows), configures it and migrates
/// it. Nothing is written to a file that turns out not to be a database, another program's
/// database, a damaged one (a table missing), or one from a newer version: every check
/// reads only, and runs before the first pragma that writes. A database that must be
/// migrated also passes `PRAGMA quick_check` first; the second value says whether it did
/// (otherwise the store runs it before its first write).
pub(crate) fn open_writer(path: &Path) -> Result<(Connection, bool)> {
    let name = path.display().to_string();
    // No SQLITE_OPEN_URI: a file called `file:x` is a file, not a URI.
    let flags = OpenFlags::SQLITE_OPEN_READ_WRITE
        | OpenFlags::SQLITE_OPEN_CREATE
        | OpenFlags::SQLITE_OPEN_NO_MUTEX;
    let mut conn = Connection::open_with_flags(path, flags).map_err(|e| open_error(&name, e))?;
    // The checks below read; a writer busy committing makes them wait, not fail.
    conn.busy_timeout(BUSY_TIMEOUT)
        .map_err(|e| open_error(&name, e))?;
    // The header is read here first: a file that is not SQLite fails now, untouched. A
    // database that is behind (or new) is written to by the migration below: check it whole.
    let version = inspect(&conn, &name)?;
    let checked = version < super::migrations::SCHEMA_VERSION;
    if checked {
        super::migrations::quick_check(&conn, &name)?;
    }
    if conn.is_readonly("main").map_err(|e| open_error(&name, e))? {
        return Err(Error::Database {
            path: name,
            message: "the file is read-only; trailprint needs to write to it".into(),
        });
    }
    common_pragmas(&conn).map_err(|e| open_error(&name, e))?;
    writer_pragmas(&conn).map_err(|e| open_error(&name, e))?;
    if version < super::migrations::SCHEMA_VERSION {
        super::migrations::migrate(&mut conn, &name)?;
    }
    Ok((conn, checked))
}

/// Opens an in-memory database at the current schema (tests, throw-away plans).
pub(crate) fn open_memory() -> Result<Connection> {
    let mut conn = Connection::open_in_memory()?;
    common_pragmas(&conn)?;
    writer_pragmas(&conn)?;
    super::migrations::migrate(&mut conn, ":memory:")?;
    Ok(conn)
}

/// Opens a read-only connection to an existing database at the current schema version.
pub(crate) fn open_reader(path: &Path) -> Result<Connection> {
    let name = path.display().to_string();
    let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
    let conn = Connection::open_with_flags(path, flags).map_err(|e| open_error(&name, e))?;
    common_pragmas(&conn).map_err(|e| open_error(&name, e))?;
    let version = inspect(&conn, &name)?;
    if version < super::migrations::SCHEMA_VERSION {
        return Err(Error::Database {
            path: name,
            message: format!(
                "schema version {version} is older than {}; open it once for writing to upgrade it",
                super::migrations::SCHEMA_VERSION
            ),
        });
    }
    Ok(conn)
}
