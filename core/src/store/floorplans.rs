//! What a floor-plan import adds to a building (SPEC 7 `geo` and `outlines`), and pilot
//! fingerprints added to a stored building afterwards (`trailprint pilot add`).

use rusqlite::{Connection, OptionalExtension, TransactionBehavior, params};

use super::{BuildingRef, UPSERT_ACCESS_POINT, building_id};
use crate::building::{Fingerprint, GeoOrigin, Outline};
use crate::{Building, Error, Result};

/// Writes the building's `geo` and `outlines` (nothing when it has neither).
pub(super) fn save(tx: &Connection, id: i64, b: &Building) -> Result<()> {
    if b.geo.is_none() && b.outlines.is_empty() {
        return Ok(());
    }
    let outlines = serde_json::to_string(&b.outlines)
        .map_err(|e| Error::InvalidRequest(format!("outlines: {e}")))?;
    tx.execute(
        "INSERT INTO building_floorplans (building_id, geo_lat, geo_lon, outlines)
         VALUES (?1, ?2, ?3, ?4)",
        params![id, b.geo.map(|g| g.lat), b.geo.map(|g| g.lon), outlines],
    )?;
    Ok(())
}

/// Reads the building's `geo` and `outlines` (none when it came from a plain file).
pub(super) fn load(
    conn: &Connection,
    id: i64,
    db: &str,
) -> Result<(Option<GeoOrigin>, Vec<Outline>)> {
    let row: Option<(Option<f64>, Option<f64>, String)> = conn
        .query_row(
            "SELECT geo_lat, geo_lon, outlines FROM building_floorplans WHERE building_id = ?1",
            [id],
            |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)),
        )
        .optional()?;
    let Some((lat, lon, text)) = row else {
        return Ok((None, Vec::new()));
    };
    let outlines: Vec<Outline> = serde_json::from_str(&text).map_err(|e| Error::Database {
        path: db.to_string(),
        message: format!("building id {id}: stored outlines cannot be read: {e}"),
    })?;
    let geo = match (lat, lon) {
        (Some(lat), Some(lon)) => Some(GeoOrigin { lat, lon }),
        _ => None,
    };
    Ok((geo, outlines))
}

/// Appends pilot fingerprints to a stored building in one transaction, after checking the
/// building with them exactly as an import would (floors, coordinates, RSS range). Returns
/// the number of pilot fingerprints the building has now.
pub(super) fn add_pilot(
    conn: &mut Connection,
    building: BuildingRef<'_>,
    pilot: &[Fingerprint],
    origin: &str,
    db: &str,
) -> Result<usize> {
    let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
    let id = building_id(&tx, building)?;
    let current = super::buildings::get(&tx, BuildingRef::Id(id), db)?;
    let mut file = current.to_file();
    let before = file.pilot.len();
    file.pilot.extend(pilot.iter().cloned());
    // The same rules as a building file; errors name the added list's index.
    Building::from_file(file, origin).map_err(|e| match e {
        Error::InvalidBuilding {
            origin,
            path,
            message,
        } => Error::InvalidBuilding {
            origin,
            path: renumber(&path, before),
            message,
        },
        other => other,
    })?;
    {
        let mut st_fp = tx.prepare(
            "INSERT INTO fingerprints (building_id, kind, ord, x, y, floor)
             VALUES (?1, 'pilot', ?2, ?3, ?4, ?5)",
        )?;
        let mut st_ap = tx.prepare(UPSERT_ACCESS_POINT)?;
        let mut st_rd = tx.prepare(
            "INSERT INTO fingerprint_readings (fingerprint_id, ap_id, rss) VALUES (?1, ?2, ?3)",
        )?;
        for (i, fp) in pilot.iter().enumerate() {
            st_fp.execute(params![id, (before + i) as i64, fp.x, fp.y, fp.floor])?;
            let fid = tx.last_insert_rowid();
            for (ap, rss) in &fp.rss {
                let ap_id: i64 = st_ap.query_row(params![id, ap], |r| r.get(0))?;
                st_rd.execute(params![fid, ap_id, rss])?;
            }
        }
    }
    tx.commit()?;
    Ok(before + pilot.len())
}

/// `pilot[12].x` of the combined list back to the index in the added list.
fn renumber(path: &str, before: usize) -> String {
    if let Some(rest) = path.strip_prefix("pilot[")
        && let Some((n, tail)) = rest.split_once(']')
        && let Ok(n) = n.parse::<usize>()
        && n >= before
    {
        return format!("[{}]{tail}", n - before);
    }
    path.to_string()
}
