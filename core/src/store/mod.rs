//! Storage: everything the phone keeps, in one SQLite file that survives being killed.
//!
//! * [`Store`] owns the one writer connection (behind a mutex) and offers every operation;
//!   each operation that writes is one transaction, so a kill leaves the database as it was
//!   before it or after it, never in between.
//! * [`Reader`] is a read-only connection of its own for another thread or process; WAL lets
//!   it read while the writer works, and every read operation runs in one read transaction,
//!   so it sees one committed snapshot.
//! * The schema is `schema/migrations/*.sql`, applied by [`migrations`] on
//!   `PRAGMA user_version`; `schema/README.md` describes every table.
//!
//! Buildings are stored by their stable vertex ids and rebuilt through
//! [`Building::from_file`] on the way out, so a stored building passes the same validation as
//! a file. Survey sessions only have their tables and typed append/list helpers here; the
//! session logic lives elsewhere.

mod buildings;
mod bundles;
mod conn;
mod export;
mod fits;
mod floorplans;
pub mod migrations;
mod planning;
mod plans;
mod sessions;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

use rusqlite::Connection;

pub use buildings::{
    BuildingInfo, ImportOptions, ImportReport, MAX_IMPORT_BYTES, read_import_text,
};
pub use bundles::{
    BUNDLE_FORMAT, BundleBody, BundleEvent, BundleImportReport, BundlePlan, BundleSession,
    ExportOptions, MAX_BUNDLE_BYTES, parse_bundle, read_bundle_text,
};
// The CSV quoting rule of the research side's files too (radio maps, experiment tables).
#[cfg(feature = "research")]
pub(crate) use export::csv_field;
pub use export::{collected_csv, collected_json};
pub use fits::{FitRecord, StoredFit};
pub use migrations::SCHEMA_VERSION;
pub use planning::{
    KernelSource, PlanningKernel, SavedPlan, SavedTeamPlan, StorePlanRequest, StoreTeamRequest,
    unstored_planning_kernel,
};
pub use plans::{PlanRecord, StoredPlan};
pub use sessions::{
    CollectedFingerprint, SessionEvent, SessionHeader, SessionInfo, SessionProvenance,
    SessionStatus, StoredCollected, StoredEvent,
};

use crate::building::BuildingFile;
use crate::{Building, Result};

/// Which building: by its store id or by its (unique) name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BuildingRef<'a> {
    Id(i64),
    Name(&'a str),
}

impl From<i64> for BuildingRef<'_> {
    fn from(id: i64) -> Self {
        BuildingRef::Id(id)
    }
}

impl<'a> From<&'a str> for BuildingRef<'a> {
    fn from(name: &'a str) -> Self {
        BuildingRef::Name(name)
    }
}

impl<'a> From<&'a String> for BuildingRef<'a> {
    fn from(name: &'a String) -> Self {
        BuildingRef::Name(name)
    }
}

impl std::fmt::Display for BuildingRef<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BuildingRef::Id(id) => write!(f, "building id {id}"),
            BuildingRef::Name(name) => write!(f, "building {name:?}"),
        }
    }
}

/// Milliseconds since the Unix epoch now (0 if the clock is before 1970).
pub fn now_ms() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_millis()).unwrap_or(i64::MAX))
}

/// The store: one database file (or an in-memory database) and its writer connection.
pub struct Store {
    /// The file, or `None` in memory.
    path: Option<PathBuf>,
    writer: Mutex<Connection>,
    /// Whether `PRAGMA quick_check` has passed on this store's database (see
    /// [`Store::lock_write`]).
    checked: AtomicBool,
}

impl std::fmt::Debug for Store {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Store").field("path", &self.path).finish()
    }
}

impl Store {
    /// Opens the database at `path`, creating the file (not its directory) if needed and
    /// upgrading its schema. Fails with [`Error::Database`](crate::Error::Database) naming
    /// the path for a file that is not SQLite, is read-only, or was written by a newer
    /// version (which is left untouched).
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let (writer, checked) = conn::open_writer(path)?;
        Ok(Store {
            writer: Mutex::new(writer),
            path: Some(path.to_path_buf()),
            checked: AtomicBool::new(checked),
        })
    }

    /// A fresh database in memory, at the current schema.
    pub fn open_in_memory() -> Result<Self> {
        Ok(Store {
            writer: Mutex::new(conn::open_memory()?),
            path: None,
            checked: AtomicBool::new(true),
        })
    }

    /// The database file, `None` in memory.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// A new read-only connection to the same file, for another thread.
    pub fn reader(&self) -> Result<Reader> {
        match &self.path {
            Some(p) => Reader::open(p),
            None => Err(crate::Error::InvalidRequest(
                "an in-memory store has no readers besides itself".into(),
            )),
        }
    }

    /// The writer connection. A panic while it was held rolled its transaction back (the
    /// transaction guard's drop), so the connection is usable despite the poison.
    fn lock(&self) -> MutexGuard<'_, Connection> {
        self.writer.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The writer connection, for an operation that writes. The first write of this store
    /// runs `PRAGMA quick_check` and refuses a corrupt database before anything is written
    /// to it; later writes reuse the answer. The check reads every page (about 2 s for an
    /// 86 MB database holding 113,000 fingerprints), so it is paid once, and only by a store
    /// that writes: listing and exporting do not wait for it. (Opening checks the header
    /// and the schema of every database, and runs the check at once on one it must migrate.)
    fn lock_write(&self) -> Result<MutexGuard<'_, Connection>> {
        let conn = self.lock();
        if !self.checked.load(Ordering::Acquire) {
            migrations::quick_check(&conn, &self.name())?;
            self.checked.store(true, Ordering::Release);
        }
        Ok(conn)
    }

    /// Runs `f` on the writer connection (for tests and tools that need raw SQL, such as
    /// integrity checks). Keep writes inside one transaction. Counts as a write for the
    /// integrity check of [`Store::lock_write`].
    pub fn with_connection<T>(&self, f: impl FnOnce(&mut Connection) -> Result<T>) -> Result<T> {
        f(&mut *self.lock_write()?)
    }

    fn name(&self) -> String {
        self.path
            .as_ref()
            .map_or_else(|| ":memory:".to_string(), |p| p.display().to_string())
    }

    // ---- buildings ----

    /// Imports a validated building, all or nothing. A building of the same name is an
    /// [`Error::AlreadyExists`](crate::Error::AlreadyExists) unless `options.replace`, which
    /// replaces it in the same transaction (refused if it has survey sessions, whose
    /// collected fingerprints could not be rebuilt).
    pub fn import_building(
        &self,
        building: &Building,
        source: Option<&str>,
        options: &ImportOptions<'_>,
    ) -> Result<ImportReport> {
        buildings::import(&mut *self.lock_write()?, building, source, options)
    }

    /// Parses, validates and imports `survey-building/1` JSON text; `origin` names it in
    /// errors and is kept as the building's source.
    pub fn import_json(
        &self,
        text: &str,
        origin: &str,
        options: &ImportOptions<'_>,
    ) -> Result<ImportReport> {
        let building = Building::from_json(text, origin)?;
        self.import_building(&building, Some(origin), options)
    }

    /// Imports a part of a stored building (some floors, or what lies within a walking
    /// distance of a vertex: [`Building::part`]) as a building of its own, for a building
    /// too large to plan on the device. Its source names the building it was cut from.
    /// The same part asked for again is the building already imported (`rows` 0), unless
    /// `options.replace`; another building of its name is an error, as for any import.
    pub fn import_part<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        spec: &crate::building::PartSpec,
        options: &ImportOptions<'_>,
    ) -> Result<ImportReport> {
        let whole = self.get_building(building)?;
        let part = whole.part(spec)?;
        let source = format!("part of {:?}", whole.name);
        match self.import_building(&part, Some(&source), options) {
            Err(crate::Error::AlreadyExists(m)) => match self.get_building(part.name.as_str()) {
                Ok(there) if there.to_file() == part.to_file() => Ok(ImportReport {
                    id: self.building_info(part.name.as_str())?.id,
                    name: part.name,
                    replaced: None,
                    rows: 0,
                }),
                _ => Err(crate::Error::AlreadyExists(m)),
            },
            other => other,
        }
    }

    /// Every building with its counts, by name.
    pub fn list_buildings(&self) -> Result<Vec<BuildingInfo>> {
        buildings::list(&self.lock(), None)
    }

    /// One building's summary.
    pub fn building_info<'a>(&self, building: impl Into<BuildingRef<'a>>) -> Result<BuildingInfo> {
        buildings::info(&self.lock(), building.into())
    }

    /// Loads a building, validated again through [`Building::from_file`].
    pub fn get_building<'a>(&self, building: impl Into<BuildingRef<'a>>) -> Result<Building> {
        buildings::get(&self.lock(), building.into(), &self.name())
    }

    /// The building as a `survey-building/1` document (what `trailprint export` writes).
    pub fn export_building<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
    ) -> Result<BuildingFile> {
        Ok(self.get_building(building)?.to_file())
    }

    /// Deletes a building and everything that belongs to it (fits, plans, sessions,
    /// collected fingerprints). Returns what it was.
    pub fn delete_building<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
    ) -> Result<BuildingInfo> {
        buildings::delete(&mut *self.lock_write()?, building.into(), |_| Ok(()))
    }

    /// Like [`Store::delete_building`], but `check` first sees what would go, inside the
    /// delete's transaction, and an error from it refuses the delete with nothing changed
    /// (the command line refuses to delete survey data without `--force`). No other writer
    /// can add a session between the check and the delete.
    pub fn delete_building_checked<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        check: impl FnOnce(&BuildingInfo) -> Result<()>,
    ) -> Result<BuildingInfo> {
        buildings::delete(&mut *self.lock_write()?, building.into(), check)
    }

    /// Appends pilot fingerprints to a building (a floor-plan import has none), checked as
    /// an import checks them; all or nothing. `origin` names the pilot file in errors.
    /// Returns how many pilot fingerprints the building has now.
    ///
    /// The building's earlier fits describe pilot data it no longer has, so when the new
    /// pilot data can be fitted the fit is recorded: the planning kernel policy
    /// ([`Store::planning_kernel`]) takes the latest fit, which is then the current one.
    pub fn add_pilot<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        pilot: &[crate::building::Fingerprint],
        origin: &str,
    ) -> Result<usize> {
        let building = building.into();
        let db = self.name();
        let n = floorplans::add_pilot(&mut self.lock(), building, pilot, origin, &db)?;
        if n >= 3 {
            // A pilot set the fitter refuses (no access point heard widely enough) keeps
            // the pilot data; an earlier fit, if any, then stays the latest (known gap:
            // fits do not record which pilot data they were made on).
            let _ = self.fit_and_record(building);
        }
        Ok(n)
    }

    // ---- fits ----

    /// Records a kernel fit of a building; returns its id.
    pub fn record_fit<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        fit: &FitRecord,
    ) -> Result<i64> {
        fits::record(&mut *self.lock_write()?, building.into(), fit)
    }

    /// The most recent fit of a building (latest `fitted_ms`, then latest id), if any.
    pub fn latest_fit<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
    ) -> Result<Option<StoredFit>> {
        fits::latest(&self.lock(), building.into())
    }

    // ---- plans ----

    /// Saves a plan of a building; the walk must be a walk of the building from `start` to
    /// `end`. Returns its id.
    pub fn save_plan<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        plan: &PlanRecord,
    ) -> Result<i64> {
        plans::save(&mut *self.lock_write()?, building.into(), plan)
    }

    /// Saves several plans of a building in one transaction (all or none); returns their
    /// ids in order.
    pub fn save_plans<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        plans: &[PlanRecord],
    ) -> Result<Vec<i64>> {
        plans::save_all(&mut *self.lock_write()?, building.into(), plans)
    }

    /// A session's building, plan and surveyor settings, by id.
    pub fn session_header(&self, session_id: i64) -> Result<SessionHeader> {
        sessions::header(&self.lock(), session_id)
    }

    /// The surveyor name and device of each session of a building, by session id.
    pub fn session_provenance<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
    ) -> Result<Vec<SessionProvenance>> {
        sessions::provenance(&self.lock(), building.into())
    }

    /// One plan by id.
    pub fn load_plan(&self, id: i64) -> Result<StoredPlan> {
        plans::load(&self.lock(), id)
    }

    /// The plans of a building, oldest first.
    pub fn list_plans<'a>(&self, building: impl Into<BuildingRef<'a>>) -> Result<Vec<StoredPlan>> {
        plans::list(&self.lock(), building.into())
    }

    // ---- survey sessions (tables and typed helpers only) ----

    /// Creates a survey session of a building, optionally walking a saved plan; `surveyor`
    /// is the surveyor model as the session code defines it. Returns its id.
    pub fn create_session<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        plan_id: Option<i64>,
        surveyor: Option<&serde_json::Value>,
        created_ms: i64,
    ) -> Result<i64> {
        sessions::create(
            &mut *self.lock_write()?,
            building.into(),
            plan_id,
            surveyor,
            created_ms,
        )
    }

    /// Appends an event to a session's log in one transaction (a scan together with its
    /// collected fingerprint) and returns its `seq`: once this returns, the event is on
    /// disk and may be acknowledged.
    pub fn append_event(&self, session_id: i64, at_ms: i64, event: &SessionEvent) -> Result<i64> {
        sessions::append(&mut *self.lock_write()?, session_id, at_ms, event)
    }

    /// A session's events with `seq > after_seq`, in order.
    pub fn list_events(&self, session_id: i64, after_seq: i64) -> Result<Vec<StoredEvent>> {
        sessions::events(&self.lock(), session_id, after_seq)
    }

    /// The sessions of a building, oldest first.
    pub fn list_sessions<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
    ) -> Result<Vec<SessionInfo>> {
        sessions::list(&self.lock(), building.into())
    }

    /// The fingerprints collected in a building (in one session if `session_id` is given),
    /// in session and seq order.
    pub fn list_collected<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        session_id: Option<i64>,
    ) -> Result<Vec<StoredCollected>> {
        sessions::collected(&self.lock(), building.into(), session_id)
    }
}

/// A read-only connection of its own (another thread, another process). Every method reads
/// one committed snapshot, whatever the writer is doing meanwhile.
pub struct Reader {
    path: PathBuf,
    conn: Connection,
}

impl std::fmt::Debug for Reader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Reader").field("path", &self.path).finish()
    }
}

impl Reader {
    /// Opens an existing database, read-only. It must be at the current schema version
    /// (open it once with [`Store::open`] to upgrade it).
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        Ok(Reader {
            conn: conn::open_reader(path)?,
            path: path.to_path_buf(),
        })
    }

    /// The raw connection (read-only).
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// See [`Store::list_buildings`].
    pub fn list_buildings(&self) -> Result<Vec<BuildingInfo>> {
        buildings::list(&self.conn, None)
    }

    /// See [`Store::building_info`].
    pub fn building_info<'a>(&self, building: impl Into<BuildingRef<'a>>) -> Result<BuildingInfo> {
        buildings::info(&self.conn, building.into())
    }

    /// See [`Store::get_building`].
    pub fn get_building<'a>(&self, building: impl Into<BuildingRef<'a>>) -> Result<Building> {
        buildings::get(
            &self.conn,
            building.into(),
            &self.path.display().to_string(),
        )
    }

    /// See [`Store::latest_fit`].
    pub fn latest_fit<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
    ) -> Result<Option<StoredFit>> {
        fits::latest(&self.conn, building.into())
    }

    /// See [`Store::load_plan`].
    pub fn load_plan(&self, id: i64) -> Result<StoredPlan> {
        plans::load(&self.conn, id)
    }

    /// See [`Store::list_events`].
    pub fn list_events(&self, session_id: i64, after_seq: i64) -> Result<Vec<StoredEvent>> {
        sessions::events(&self.conn, session_id, after_seq)
    }

    /// See [`Store::list_collected`].
    pub fn list_collected<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        session_id: Option<i64>,
    ) -> Result<Vec<StoredCollected>> {
        sessions::collected(&self.conn, building.into(), session_id)
    }
}

/// Runs `f` in one immediate write transaction: its writes commit together, or none of
/// them does when it fails (the transaction rolls back on drop). Immediate, so that two
/// writers queue on the lock instead of failing half-way with `SQLITE_BUSY`.
fn write_tx<T>(
    conn: &mut Connection,
    f: impl FnOnce(&rusqlite::Transaction<'_>) -> Result<T>,
) -> Result<T> {
    let tx = conn.transaction_with_behavior(rusqlite::TransactionBehavior::Immediate)?;
    let out = f(&tx)?;
    tx.commit()?;
    Ok(out)
}

/// Inserts an access point of a building if it is new, and returns its id either way
/// (parameters: building id, name). One statement for every writer that meets access
/// points (fits, pilot imports, collected scans), so they cannot disagree on the rule.
const UPSERT_ACCESS_POINT: &str = "INSERT INTO access_points (building_id, name) VALUES (?1, ?2)
             ON CONFLICT (building_id, name) DO UPDATE SET name = excluded.name
             RETURNING id";

/// Reads fingerprints joined with their readings: one row per reading (a fingerprint that
/// heard nothing has one row with a NULL access point), a fingerprint's rows consecutive.
/// Column `id_col` is the fingerprint's id, `ap_col` and the next one the access point's
/// name and the RSS; `first` makes a fingerprint from its first row and `rss` is where its
/// readings go. Pilot data and collected scans are both stored this way.
fn group_readings<T>(
    mut rows: rusqlite::Rows<'_>,
    id_col: usize,
    ap_col: usize,
    mut first: impl FnMut(&rusqlite::Row<'_>) -> rusqlite::Result<T>,
    rss: impl Fn(&mut T) -> &mut std::collections::BTreeMap<String, f64>,
) -> rusqlite::Result<Vec<T>> {
    let mut out: Vec<T> = Vec::new();
    let mut last = None;
    while let Some(r) = rows.next()? {
        let id: i64 = r.get(id_col)?;
        if last != Some(id) {
            out.push(first(r)?);
            last = Some(id);
        }
        let ap: Option<String> = r.get(ap_col)?;
        if let (Some(ap), Some(t)) = (ap, out.last_mut()) {
            rss(t).insert(ap, r.get(ap_col + 1)?);
        }
    }
    Ok(out)
}

/// Every row of one query, each made by `row`: the store's one way to read a list (the
/// statement is cached, as the same lists are read again and again).
fn query_all<T>(
    conn: &Connection,
    sql: &str,
    params: impl rusqlite::Params,
    row: impl FnMut(&rusqlite::Row<'_>) -> rusqlite::Result<T>,
) -> Result<Vec<T>> {
    let mut st = conn.prepare_cached(sql)?;
    let out = st
        .query_map(params, row)?
        .collect::<rusqlite::Result<Vec<T>>>()?;
    Ok(out)
}

/// Runs `f` in a read transaction: all its statements see one committed snapshot, even
/// while another connection writes (WAL). Without it, a delete landing between two SELECTs
/// could pair one building's row with another's vertices.
fn read_tx<T>(conn: &Connection, f: impl FnOnce(&Connection) -> Result<T>) -> Result<T> {
    // Inside a caller's transaction (a bundle import) the reads already see one snapshot.
    if !conn.is_autocommit() {
        return f(conn);
    }
    let tx = conn.unchecked_transaction()?;
    let out = f(&tx)?;
    tx.finish()?;
    Ok(out)
}

/// The id of a building, or [`Error::NotFound`](crate::Error::NotFound).
fn building_id(conn: &Connection, building: BuildingRef<'_>) -> Result<i64> {
    use rusqlite::OptionalExtension;
    let found = match building {
        BuildingRef::Id(id) => conn
            .query_row("SELECT id FROM buildings WHERE id = ?1", [id], |r| r.get(0))
            .optional()?,
        BuildingRef::Name(name) => conn
            .query_row("SELECT id FROM buildings WHERE name = ?1", [name], |r| {
                r.get(0)
            })
            .optional()?,
    };
    found.ok_or_else(|| crate::Error::NotFound(format!("{building} is not in the database")))
}
