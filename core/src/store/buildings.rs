//! Buildings in the store: import (all or nothing), list, load, delete.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::io::Read;
use std::path::Path;

use rusqlite::{Connection, OptionalExtension, TransactionBehavior, params};
use serde::Serialize;

use super::{BuildingRef, building_id, group_readings, now_ms, query_all, read_tx, write_tx};
use crate::building::{BuildingFile, EdgeSpec, FORMAT, Fingerprint, FloorSpec, VertexSpec};
use crate::gp::Kernel;
use crate::{Building, Error, Result};

/// Largest building file the importer reads: 64 MiB. Area Two with its dense survey is about
/// 0.1 MiB; a file a thousand times larger is a mistake (a log, a video, a database), and
/// refusing it before reading keeps a phone from running out of memory on it.
pub const MAX_IMPORT_BYTES: u64 = 64 * 1024 * 1024;

/// Options of an import.
#[derive(Default)]
pub struct ImportOptions<'a> {
    /// Replace a building of the same name (in the same transaction) instead of failing.
    pub replace: bool,
    /// Called inside the import transaction after each row written, with the number of rows
    /// so far: a progress bar for the app. Nothing is committed until the import returns.
    pub progress: Option<&'a dyn Fn(u64)>,
}

/// What an import did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImportReport {
    /// Store id of the new building.
    pub id: i64,
    pub name: String,
    /// Id of the building it replaced, if any.
    pub replaced: Option<i64>,
    /// Rows written in the transaction.
    pub rows: u64,
}

/// A building's summary: ids and counts, as `trailprint buildings` lists them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BuildingInfo {
    pub id: i64,
    pub name: String,
    /// Where it was imported from.
    pub source: Option<String>,
    pub imported_ms: i64,
    pub floors: u64,
    pub vertices: u64,
    pub edges: u64,
    pub access_points: u64,
    pub pilot: u64,
    pub test_points: u64,
    pub dense_survey: u64,
    /// Whether the file gave a kernel.
    pub has_kernel: bool,
    pub fits: u64,
    pub plans: u64,
    pub sessions: u64,
    pub collected: u64,
}

/// Reads a building file for import (`-` reads standard input), refusing anything over
/// [`MAX_IMPORT_BYTES`]: a regular file by its size before reading a byte, a stream after
/// reading one byte more than the limit.
pub fn read_import_text(path: &Path) -> Result<String> {
    read_limited(
        path,
        MAX_IMPORT_BYTES,
        "the import limit",
        "a building file",
    )
}

/// Reads `path` (`-`: standard input) as text of at most `limit` bytes; a larger input is
/// refused naming `limit_name` and saying it is not `what`.
pub(super) fn read_limited(
    path: &Path,
    limit: u64,
    limit_name: &str,
    what: &str,
) -> Result<String> {
    let stdin = path == Path::new("-");
    let origin = if stdin {
        "<stdin>".to_string()
    } else {
        path.display().to_string()
    };
    let too_big = |size: String| {
        Error::invalid(
            &origin,
            "$",
            format!(
                "{size} over {limit_name} of {} MiB; it is not {what}",
                limit / (1024 * 1024)
            ),
        )
    };
    let mut text = String::new();
    if stdin {
        std::io::stdin()
            .lock()
            .take(limit + 1)
            .read_to_string(&mut text)
            .map_err(|e| Error::io(&origin, e))?;
    } else {
        let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
        if len > limit {
            return Err(too_big(format!(
                "the file is {:.1} MiB,",
                len as f64 / 1048576.0
            )));
        }
        // The size can grow after the check (a file being written): cap the read as well.
        file.take(limit + 1)
            .read_to_string(&mut text)
            .map_err(|e| Error::io(path, e))?;
    }
    if text.len() as u64 > limit {
        return Err(too_big("the input is".into()));
    }
    Ok(text)
}

/// Imports a validated building in one IMMEDIATE transaction.
pub(super) fn import(
    conn: &mut Connection,
    b: &Building,
    source: Option<&str>,
    options: &ImportOptions<'_>,
) -> Result<ImportReport> {
    write_tx(conn, |tx| import_in(tx, b, source, options))
}

/// [`import`] inside a transaction the caller owns.
pub(super) fn import_in(
    tx: &Connection,
    b: &Building,
    source: Option<&str>,
    options: &ImportOptions<'_>,
) -> Result<ImportReport> {
    let mut rows = 0u64;
    let mut row = || {
        rows += 1;
        if let Some(p) = options.progress {
            p(rows);
        }
    };

    let existing: Option<i64> = tx
        .query_row("SELECT id FROM buildings WHERE name = ?1", [&b.name], |r| {
            r.get(0)
        })
        .optional()?;
    if let Some(old) = existing {
        if !options.replace {
            return Err(Error::AlreadyExists(format!(
                "building {:?} is already in the database (id {old}); replace it (--replace) \
                 or rename the new one",
                b.name
            )));
        }
        let sessions: i64 = tx.query_row(
            "SELECT count(*) FROM survey_sessions WHERE building_id = ?1",
            [old],
            |r| r.get(0),
        )?;
        if sessions > 0 {
            return Err(Error::InvalidRequest(format!(
                "building {:?} (id {old}) has {sessions} survey session(s); replacing it would \
                 delete their collected fingerprints: export them, then delete the building",
                b.name
            )));
        }
        tx.execute("DELETE FROM buildings WHERE id = ?1", [old])?;
    }

    let kernel = b.kernel;
    tx.execute(
        "INSERT INTO buildings (name, source, imported_ms, vertex_count, edge_count,
                                kernel_sf2, kernel_ell, kernel_sn2)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)",
        params![
            b.name,
            source,
            now_ms(),
            b.vertices.len() as i64,
            b.edges.len() as i64,
            kernel.map(|k| k.sf2),
            kernel.map(|k| k.ell),
            kernel.map(|k| k.sn2),
        ],
    )?;
    let id = tx.last_insert_rowid();
    row();
    super::floorplans::save(tx, id, b)?;

    {
        let mut st = tx.prepare(
            "INSERT INTO floors (building_id, floor, ord, name) VALUES (?1, ?2, ?3, ?4)",
        )?;
        for (ord, f) in b.floors.iter().enumerate() {
            st.execute(params![id, f.id, ord as i64, f.name])?;
            row();
        }
        let mut st = tx.prepare(
            "INSERT INTO vertices (building_id, vid, ord, x, y, floor, label)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
        )?;
        for (ord, v) in b.vertices.iter().enumerate() {
            st.execute(params![
                id,
                v.id,
                ord as i64,
                v.pos.x,
                v.pos.y,
                v.pos.floor,
                v.label
            ])?;
            row();
        }
        let mut st = tx.prepare(
            "INSERT INTO edges (building_id, ord, a, b, length) VALUES (?1, ?2, ?3, ?4, ?5)",
        )?;
        for (ord, e) in b.edges.iter().enumerate() {
            st.execute(params![
                id,
                ord as i64,
                b.vertices[e.a].id,
                b.vertices[e.b].id,
                e.explicit_length.then_some(e.length),
            ])?;
            row();
        }

        let lists: [(&str, &[Fingerprint]); 3] = [
            ("pilot", &b.pilot),
            ("test_points", &b.test_points),
            ("dense_survey", &b.dense_survey),
        ];
        let names: BTreeSet<&str> = lists
            .iter()
            .flat_map(|(_, list)| list.iter())
            .flat_map(|fp| fp.rss.keys().map(String::as_str))
            .collect();
        let mut aps: HashMap<&str, i64> = HashMap::with_capacity(names.len());
        let mut st = tx.prepare("INSERT INTO access_points (building_id, name) VALUES (?1, ?2)")?;
        for name in names {
            st.execute(params![id, name])?;
            aps.insert(name, tx.last_insert_rowid());
            row();
        }
        let mut st_fp = tx.prepare(
            "INSERT INTO fingerprints (building_id, kind, ord, x, y, floor)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
        )?;
        let mut st_rd = tx.prepare(
            "INSERT INTO fingerprint_readings (fingerprint_id, ap_id, rss) VALUES (?1, ?2, ?3)",
        )?;
        for (kind, list) in lists {
            for (ord, fp) in list.iter().enumerate() {
                st_fp.execute(params![id, kind, ord as i64, fp.x, fp.y, fp.floor])?;
                let fid = tx.last_insert_rowid();
                row();
                for (ap, rss) in &fp.rss {
                    // Every name was inserted above.
                    let ap_id = aps.get(ap.as_str()).copied().unwrap_or_default();
                    st_rd.execute(params![fid, ap_id, rss])?;
                    row();
                }
            }
        }
    }
    Ok(ImportReport {
        id,
        name: b.name.clone(),
        replaced: existing,
        rows,
    })
}

const INFO_SQL: &str = "
SELECT b.id, b.name, b.source, b.imported_ms, b.vertex_count, b.edge_count,
       (SELECT count(*) FROM floors WHERE building_id = b.id),
       (SELECT count(*) FROM access_points WHERE building_id = b.id),
       (SELECT count(*) FROM fingerprints WHERE building_id = b.id AND kind = 'pilot'),
       (SELECT count(*) FROM fingerprints WHERE building_id = b.id AND kind = 'test_points'),
       (SELECT count(*) FROM fingerprints WHERE building_id = b.id AND kind = 'dense_survey'),
       b.kernel_sf2 IS NOT NULL,
       (SELECT count(*) FROM fits WHERE building_id = b.id),
       (SELECT count(*) FROM plans WHERE building_id = b.id),
       (SELECT count(*) FROM survey_sessions WHERE building_id = b.id),
       (SELECT count(*) FROM collected_fingerprints c
          JOIN survey_sessions s ON s.id = c.session_id WHERE s.building_id = b.id)
FROM buildings b";

fn info_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<BuildingInfo> {
    let n = |i: usize| -> rusqlite::Result<u64> { Ok(r.get::<_, i64>(i)?.max(0) as u64) };
    Ok(BuildingInfo {
        id: r.get(0)?,
        name: r.get(1)?,
        source: r.get(2)?,
        imported_ms: r.get(3)?,
        vertices: n(4)?,
        edges: n(5)?,
        floors: n(6)?,
        access_points: n(7)?,
        pilot: n(8)?,
        test_points: n(9)?,
        dense_survey: n(10)?,
        has_kernel: r.get(11)?,
        fits: n(12)?,
        plans: n(13)?,
        sessions: n(14)?,
        collected: n(15)?,
    })
}

/// All buildings (or the one with id `only`), by name; one statement, one snapshot.
pub(super) fn list(conn: &Connection, only: Option<i64>) -> Result<Vec<BuildingInfo>> {
    let sql = format!("{INFO_SQL} WHERE ?1 IS NULL OR b.id = ?1 ORDER BY b.name");
    query_all(conn, &sql, [only], info_row)
}

pub(super) fn info(conn: &Connection, building: BuildingRef<'_>) -> Result<BuildingInfo> {
    read_tx(conn, |conn| {
        let id = building_id(conn, building)?;
        list(conn, Some(id))?
            .pop()
            .ok_or_else(|| Error::NotFound(format!("{building} is not in the database")))
    })
}

/// Loads a building in one read transaction and validates it again.
pub(super) fn get(conn: &Connection, building: BuildingRef<'_>, db: &str) -> Result<Building> {
    read_tx(conn, |conn| {
        let id = building_id(conn, building)?;
        let (name, vertex_count, edge_count, sf2, ell, sn2): (
            String,
            i64,
            i64,
            Option<f64>,
            Option<f64>,
            Option<f64>,
        ) = conn.query_row(
            "SELECT name, vertex_count, edge_count, kernel_sf2, kernel_ell, kernel_sn2
             FROM buildings WHERE id = ?1",
            [id],
            |r| r.try_into(),
        )?;
        let floors = query_all(
            conn,
            "SELECT floor, name FROM floors WHERE building_id = ?1 ORDER BY ord",
            [id],
            |r| {
                Ok(FloorSpec {
                    id: r.get(0)?,
                    name: r.get(1)?,
                })
            },
        )?;
        let vertices = query_all(
            conn,
            "SELECT vid, x, y, floor, label FROM vertices WHERE building_id = ?1 ORDER BY ord",
            [id],
            |r| {
                Ok(VertexSpec {
                    id: r.get(0)?,
                    x: r.get(1)?,
                    y: r.get(2)?,
                    floor: r.get(3)?,
                    label: r.get(4)?,
                })
            },
        )?;
        let edges = query_all(
            conn,
            "SELECT a, b, length FROM edges WHERE building_id = ?1 ORDER BY ord",
            [id],
            |r| {
                Ok(EdgeSpec {
                    a: r.get(0)?,
                    b: r.get(1)?,
                    length: r.get(2)?,
                })
            },
        )?;
        if vertices.len() as i64 != vertex_count || edges.len() as i64 != edge_count {
            return Err(Error::Database {
                path: db.to_string(),
                message: format!(
                    "building {name:?} (id {id}) records {vertex_count} vertices and {edge_count} \
                     edges but has {} and {}: the database is inconsistent",
                    vertices.len(),
                    edges.len()
                ),
            });
        }

        let mut lists: BTreeMap<String, Vec<Fingerprint>> = BTreeMap::new();
        let mut st = conn.prepare(
            "SELECT f.kind, f.id, f.x, f.y, f.floor, a.name, r.rss
             FROM fingerprints f
             LEFT JOIN fingerprint_readings r ON r.fingerprint_id = f.id
             LEFT JOIN access_points a ON a.id = r.ap_id
             WHERE f.building_id = ?1
             ORDER BY f.kind, f.ord",
        )?;
        let all = group_readings(
            st.query([id])?,
            1,
            5,
            |r| {
                let kind: String = r.get(0)?;
                let f = Fingerprint {
                    x: r.get(2)?,
                    y: r.get(3)?,
                    floor: r.get(4)?,
                    rss: BTreeMap::new(),
                };
                Ok((kind, f))
            },
            |(_, f)| &mut f.rss,
        )?;
        for (kind, f) in all {
            lists.entry(kind).or_default().push(f);
        }
        let kernel = match (sf2, ell, sn2) {
            (Some(sf2), Some(ell), Some(sn2)) => Some(Kernel::new(sf2, ell, sn2)),
            _ => None,
        };
        let (geo, outlines) = super::floorplans::load(conn, id, db)?;
        let file = BuildingFile {
            format: FORMAT.to_string(),
            name: name.clone(),
            floors: Some(floors),
            vertices,
            edges,
            pilot: lists.remove("pilot").unwrap_or_default(),
            test_points: lists.remove("test_points").unwrap_or_default(),
            dense_survey: lists.remove("dense_survey").unwrap_or_default(),
            kernel,
            geo,
            outlines,
        };
        Building::from_file(file, &format!("{db}: building {name:?}"))
    })
}

/// Deletes a building; the schema's cascades remove everything that belongs to it.
/// `check` sees what would go and may refuse (inside the transaction).
pub(super) fn delete(
    conn: &mut Connection,
    building: BuildingRef<'_>,
    check: impl FnOnce(&BuildingInfo) -> Result<()>,
) -> Result<BuildingInfo> {
    let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
    let id = building_id(&tx, building)?;
    let info = list(&tx, Some(id))?
        .pop()
        .ok_or_else(|| Error::NotFound(format!("{building} is not in the database")))?;
    check(&info)?;
    tx.execute("DELETE FROM buildings WHERE id = ?1", [id])?;
    tx.commit()?;
    Ok(info)
}
