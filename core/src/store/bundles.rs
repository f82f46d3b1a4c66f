//! Survey bundles: what one phone collected, as one file another phone or a desktop can
//! merge (issue 9).
//!
//! A bundle is JSON: `{"format": "trailprint-bundle/1", "sha256": "...", "body": {...}}`.
//! The body carries the building (so a database that has never seen it can take the
//! sessions), provenance (device, surveyor, time) and, per session, its global `uid`, the
//! plans it used and its whole event log. `sha256` is the SHA-256 of the body as compact
//! JSON with sorted keys; a bundle whose checksum does not match, or that does not parse
//! (a truncated file), is rejected before anything is written.
//!
//! Import is one transaction and matches sessions by `uid`: a session already present gets
//! only the events it lacks (a phone may export the same session again after walking on),
//! so importing the same bundle twice changes nothing and bundles can be imported in any
//! order. Refused whole, with nothing imported:
//! * two logs that disagree on an event they share (its kind, time or any field: a scan's
//!   readings, a replan's plan), naming the session and the event;
//! * a log with an event after its `finish` or `abort`;
//! * a bundle whose building has the name of a local building with other geometry (floors,
//!   vertex positions, edges and lengths): its sessions' positions would not mean the same.

use std::collections::BTreeMap;

use rusqlite::{Connection, OptionalExtension, TransactionBehavior, params};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::plans::PlanRecord;
use super::sessions::SessionEvent;
use super::{BuildingRef, ImportOptions, Store, now_ms};
use crate::building::{Building, BuildingFile};
use crate::{Error, Result};

/// The only bundle format version this code reads and writes.
pub const BUNDLE_FORMAT: &str = "trailprint-bundle/1";

/// One event of a session log in a bundle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BundleEvent {
    pub seq: i64,
    pub at_ms: i64,
    pub event: SessionEvent,
}

/// A plan a session used, under the id it had on the exporting device.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BundlePlan {
    pub source_id: i64,
    pub plan: PlanRecord,
}

/// A session in a bundle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BundleSession {
    pub uid: String,
    pub created_ms: i64,
    pub device: Option<String>,
    pub surveyor_name: Option<String>,
    pub surveyor: Option<serde_json::Value>,
    /// Source id (in `plans`) of the plan the session started with.
    pub plan: Option<i64>,
    pub plans: Vec<BundlePlan>,
    pub events: Vec<BundleEvent>,
}

/// The checksummed part of a bundle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BundleBody {
    pub created_ms: i64,
    pub device: Option<String>,
    pub surveyor_name: Option<String>,
    #[serde(deserialize_with = "crate::building::shape::object")]
    pub building: BuildingFile,
    pub sessions: Vec<BundleSession>,
}

/// What an import did.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct BundleImportReport {
    pub bundle_id: String,
    pub building: String,
    pub building_created: bool,
    pub sessions_added: u64,
    pub sessions_extended: u64,
    pub sessions_unchanged: u64,
    pub events_added: u64,
}

/// Who and what exports a bundle.
#[derive(Debug, Clone, Default)]
pub struct ExportOptions {
    pub device: Option<String>,
    pub surveyor_name: Option<String>,
    /// Only these session ids (local); all of the building's sessions when empty.
    pub sessions: Vec<i64>,
}

fn sha256_hex(text: &str) -> String {
    let digest = Sha256::digest(text.as_bytes());
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// Compact JSON of a value with sorted keys (serde_json's map is ordered): the text the
/// checksum is computed on.
fn canonical(v: &serde_json::Value) -> String {
    v.to_string()
}

fn random_uid() -> String {
    use rand::RngExt;
    // An identifier, not a modelling choice: it must differ between devices, so it comes
    // from the operating system's entropy rather than a seed.
    let mut rng = rand::rng();
    let hi: u64 = rng.random();
    let lo: u64 = rng.random();
    format!("{hi:016x}{lo:016x}")
}

impl Store {
    /// Writes a bundle of a building's sessions (all, or those in `options.sessions`) and
    /// returns its JSON text. Sessions without a global id get one (stored), so exporting
    /// again names them the same.
    pub fn export_bundle<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        options: &ExportOptions,
    ) -> Result<String> {
        let building = building.into();
        let file = self.export_building(building)?;
        let info = self.building_info(building)?;
        let mut sessions = Vec::new();
        for s in self.list_sessions(BuildingRef::Id(info.id))? {
            if !options.sessions.is_empty() && !options.sessions.contains(&s.id) {
                continue;
            }
            let uid = self.with_connection(|c| {
                let uid: Option<String> = c.query_row(
                    "SELECT uid FROM survey_sessions WHERE id = ?1",
                    [s.id],
                    |r| r.get(0),
                )?;
                match uid {
                    Some(u) => Ok(u),
                    None => {
                        let u = random_uid();
                        c.execute(
                            "UPDATE survey_sessions SET uid = ?1 WHERE id = ?2 AND uid IS NULL",
                            params![u, s.id],
                        )?;
                        Ok(u)
                    }
                }
            })?;
            let (device, surveyor_name): (Option<String>, Option<String>) =
                self.with_connection(|c| {
                    Ok(c.query_row(
                        "SELECT device, surveyor_name FROM survey_sessions WHERE id = ?1",
                        [s.id],
                        |r| Ok((r.get(0)?, r.get(1)?)),
                    )?)
                })?;
            let events: Vec<BundleEvent> = self
                .list_events(s.id, 0)?
                .into_iter()
                .map(|e| BundleEvent {
                    seq: e.seq,
                    at_ms: e.at_ms,
                    event: e.event,
                })
                .collect();
            let mut plan_ids: Vec<i64> = s.plan_id.into_iter().collect();
            for e in &events {
                if let SessionEvent::Replan { plan_id } = e.event
                    && !plan_ids.contains(&plan_id)
                {
                    plan_ids.push(plan_id);
                }
            }
            let mut plans = Vec::new();
            for id in plan_ids {
                plans.push(BundlePlan {
                    source_id: id,
                    plan: self.load_plan(id)?.record,
                });
            }
            sessions.push(BundleSession {
                uid,
                created_ms: s.created_ms,
                // A session recorded here carries this device's provenance.
                device: device.or_else(|| options.device.clone()),
                surveyor_name: surveyor_name.or_else(|| options.surveyor_name.clone()),
                surveyor: s.surveyor,
                plan: s.plan_id,
                plans,
                events,
            });
        }
        let body = BundleBody {
            created_ms: now_ms(),
            device: options.device.clone(),
            surveyor_name: options.surveyor_name.clone(),
            building: file,
            sessions,
        };
        let body_value = serde_json::to_value(&body)
            .map_err(|e| Error::InvalidRequest(format!("bundle: {e}")))?;
        let sha = sha256_hex(&canonical(&body_value));
        let doc = serde_json::json!({"format": BUNDLE_FORMAT, "sha256": sha, "body": body_value});
        Ok(doc.to_string())
    }

    /// Imports a bundle (JSON text; `origin` names it in errors) in one transaction. A text
    /// over [`MAX_BUNDLE_BYTES`] is refused before it is parsed.
    pub fn import_bundle(&self, text: &str, origin: &str) -> Result<BundleImportReport> {
        if text.len() as u64 > MAX_BUNDLE_BYTES {
            return Err(Error::invalid(
                origin,
                "$",
                format!(
                    "the bundle is {:.1} MiB, over the bundle limit of {} MiB",
                    text.len() as f64 / 1048576.0,
                    MAX_BUNDLE_BYTES / (1024 * 1024)
                ),
            ));
        }
        let (bundle_id, body) = parse_bundle(text, origin)?;
        let building =
            Building::from_file(body.building.clone(), &format!("{origin}: body.building"))?;
        self.with_connection(|conn| import_in_tx(conn, &bundle_id, &body, &building, origin))
    }
}

/// Largest bundle [`Store::import_bundle`] accepts: 256 MiB, room for a few hundred
/// thousand fingerprints, and a bound on the memory a corrupt or hostile file can make the
/// phone spend parsing it.
pub const MAX_BUNDLE_BYTES: u64 = 256 * 1024 * 1024;

/// Reads a bundle file for [`Store::import_bundle`] (`-` reads standard input), refusing
/// anything over [`MAX_BUNDLE_BYTES`] before reading it whole.
pub fn read_bundle_text(path: &std::path::Path) -> Result<String> {
    super::buildings::read_limited(path, MAX_BUNDLE_BYTES, "the bundle limit", "a bundle")
}

/// Parses and verifies a bundle; nothing is written.
pub fn parse_bundle(text: &str, origin: &str) -> Result<(String, BundleBody)> {
    let bad = |path: &str, message: String| Error::Parse {
        origin: origin.to_string(),
        path: path.to_string(),
        message,
    };
    let doc: serde_json::Value = serde_json::from_str(text).map_err(|e| {
        bad(
            "$",
            format!("not a complete bundle (truncated or not JSON): {e}"),
        )
    })?;
    let format = doc.get("format").and_then(|f| f.as_str()).unwrap_or("");
    if format != BUNDLE_FORMAT {
        return Err(bad(
            "format",
            format!("unknown bundle format {format:?}, expected {BUNDLE_FORMAT:?}"),
        ));
    }
    let sha = doc
        .get("sha256")
        .and_then(|s| s.as_str())
        .ok_or_else(|| bad("sha256", "missing checksum".into()))?;
    let body_value = doc
        .get("body")
        .ok_or_else(|| bad("body", "missing".into()))?;
    let actual = sha256_hex(&canonical(body_value));
    if actual != sha {
        return Err(bad(
            "sha256",
            format!(
                "checksum mismatch: the bundle is corrupt (expected {sha}, content hashes to {actual})"
            ),
        ));
    }
    let body: BundleBody = serde_path_to_error::deserialize(body_value.clone()).map_err(|e| {
        let path = format!("body.{}", e.path());
        bad(&path, e.into_inner().to_string())
    })?;
    for (i, s) in body.sessions.iter().enumerate() {
        if s.uid.trim().is_empty() {
            return Err(bad(
                &format!("body.sessions[{i}].uid"),
                "must not be empty".into(),
            ));
        }
        let mut ended: Option<(i64, &str)> = None;
        for (j, e) in s.events.iter().enumerate() {
            if e.seq != j as i64 + 1 {
                return Err(bad(
                    &format!("body.sessions[{i}].events[{j}].seq"),
                    format!("expected seq {}, got {}", j + 1, e.seq),
                ));
            }
            if let Some((end_seq, end_kind)) = ended {
                return Err(bad(
                    &format!("body.sessions[{i}].events[{j}]"),
                    format!(
                        "session {}: event {} ({}) comes after the session ended with {end_kind} \
                         at event {end_seq}",
                        s.uid,
                        e.seq,
                        e.event.kind()
                    ),
                ));
            }
            if matches!(e.event, SessionEvent::Finish | SessionEvent::Abort { .. }) {
                ended = Some((e.seq, e.event.kind()));
            }
        }
    }
    Ok((sha.to_string(), body))
}

fn import_in_tx(
    conn: &mut Connection,
    bundle_id: &str,
    body: &BundleBody,
    building: &Building,
    origin: &str,
) -> Result<BundleImportReport> {
    let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
    let existing: Option<i64> = tx
        .query_row(
            "SELECT id FROM buildings WHERE name = ?1",
            [&building.name],
            |r| r.get(0),
        )
        .optional()?;
    let (bid, building_created) = match existing {
        Some(id) => {
            let local = super::buildings::get(&tx, BuildingRef::Id(id), origin)?;
            if let Some(diff) = geometry_difference(&local, building) {
                return Err(Error::InvalidRequest(format!(
                    "{origin}: body.building: building {:?} (id {id}) is already in the \
                     database with other geometry ({diff}); its sessions cannot be attached \
                     to it: import the bundle into another database, or rename one building",
                    building.name
                )));
            }
            (id, false)
        }
        None => {
            let report = super::buildings::import_in(
                &tx,
                building,
                Some(origin),
                &ImportOptions::default(),
            )?;
            (report.id, true)
        }
    };
    let mut report = BundleImportReport {
        bundle_id: bundle_id.to_string(),
        building: building.name.clone(),
        building_created,
        sessions_added: 0,
        sessions_extended: 0,
        sessions_unchanged: 0,
        events_added: 0,
    };
    for (si, s) in body.sessions.iter().enumerate() {
        let ctx = |m: String| {
            Error::InvalidRequest(format!(
                "{origin}: body.sessions[{si}] (session {}): {m}",
                s.uid
            ))
        };
        // Plans: saved once per session import, under new local ids.
        let local: Option<(i64, i64)> = tx
            .query_row(
                "SELECT id, building_id FROM survey_sessions WHERE uid = ?1",
                [&s.uid],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .optional()?;
        let mut plan_map: BTreeMap<i64, i64> = BTreeMap::new();
        let session_id = match local {
            Some((id, b)) => {
                if b != bid {
                    return Err(ctx(format!(
                        "already in the database for another building (id {b})"
                    )));
                }
                id
            }
            None => {
                for p in &s.plans {
                    let new_id = super::plans::save_in(&tx, BuildingRef::Id(bid), &p.plan)?;
                    plan_map.insert(p.source_id, new_id);
                }
                let plan_id = match s.plan {
                    Some(src) => Some(*plan_map.get(&src).ok_or_else(|| {
                        ctx(format!("its plan {src} is not among the bundle's plans"))
                    })?),
                    None => None,
                };
                let id = super::sessions::create_in(
                    &tx,
                    BuildingRef::Id(bid),
                    plan_id,
                    s.surveyor.as_ref(),
                    s.created_ms,
                )?;
                tx.execute(
                    "UPDATE survey_sessions SET uid = ?1, device = ?2, surveyor_name = ?3, imported_ms = ?4 WHERE id = ?5",
                    params![s.uid, s.device, s.surveyor_name, now_ms(), id],
                )?;
                report.sessions_added += 1;
                id
            }
        };
        let have: Vec<super::sessions::StoredEvent> = super::sessions::events(&tx, session_id, 0)?;
        // The shared prefix must agree event for event: kind, time and every field (a
        // replan's plan is compared by its content, since local plan ids differ).
        for (e, h) in s.events.iter().zip(&have) {
            let conflict = |what: String| {
                ctx(format!(
                    "conflicting histories at event {}: {what}; nothing was imported",
                    e.seq
                ))
            };
            if e.event.kind() != h.event.kind() || e.at_ms != h.at_ms {
                return Err(conflict(format!(
                    "the bundle has {} at {} ms, the database {} at {} ms",
                    e.event.kind(),
                    e.at_ms,
                    h.event.kind(),
                    h.at_ms
                )));
            }
            match (&e.event, &h.event) {
                (
                    SessionEvent::Replan { plan_id: theirs },
                    SessionEvent::Replan { plan_id: ours },
                ) => {
                    let bundled = s.plans.iter().find(|p| p.source_id == *theirs);
                    let local = super::plans::load(&tx, *ours)?;
                    if bundled.map(|p| &p.plan) != Some(&local.record) {
                        return Err(conflict(format!(
                            "the bundle's replan (to its plan {theirs}) and the database's (to \
                             plan {ours}) name different plans"
                        )));
                    }
                }
                (theirs, ours) if theirs != ours => {
                    let text = |ev: &SessionEvent| serde_json::to_string(ev).unwrap_or_default();
                    return Err(conflict(format!(
                        "the bundle has {}, the database {}",
                        text(theirs),
                        text(ours)
                    )));
                }
                _ => {}
            }
        }
        let new_events = &s.events[have.len().min(s.events.len())..];
        if local.is_some() {
            if new_events.is_empty() {
                report.sessions_unchanged += 1;
            } else {
                report.sessions_extended += 1;
                // Plans referenced by the new replans must be brought in too.
                for p in &s.plans {
                    let referenced = new_events
                        .iter()
                        .any(|e| matches!(e.event, SessionEvent::Replan { plan_id } if plan_id == p.source_id));
                    if referenced {
                        let new_id = super::plans::save_in(&tx, BuildingRef::Id(bid), &p.plan)?;
                        plan_map.insert(p.source_id, new_id);
                    }
                }
            }
        }
        for e in new_events {
            let event = match &e.event {
                SessionEvent::Replan { plan_id } => SessionEvent::Replan {
                    plan_id: *plan_map.get(plan_id).ok_or_else(|| {
                        ctx(format!(
                            "event {} replans to plan {plan_id}, which the bundle does not carry",
                            e.seq
                        ))
                    })?,
                },
                other => other.clone(),
            };
            let seq = super::sessions::append_in(&tx, session_id, e.at_ms, &event)
                .map_err(|err| ctx(format!("event {}: {err}", e.seq)))?;
            if seq != e.seq {
                return Err(ctx(format!("event {} would be stored as {seq}", e.seq)));
            }
            report.events_added += 1;
        }
    }
    tx.execute(
        "INSERT INTO bundle_imports (bundle_id, device, surveyor_name, created_ms, imported_ms, sessions_added, events_added)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7) ON CONFLICT (bundle_id) DO NOTHING",
        params![
            bundle_id,
            body.device,
            body.surveyor_name,
            body.created_ms,
            now_ms(),
            report.sessions_added as i64,
            report.events_added as i64
        ],
    )?;
    tx.commit()?;
    Ok(report)
}

/// The first difference between the geometry of two buildings of the same name (floors,
/// vertex ids and positions, edges and their lengths), or `None` if they agree. Labels and
/// survey data may differ: they do not move a session's positions.
fn geometry_difference(local: &Building, theirs: &Building) -> Option<String> {
    let floors = |b: &Building| b.floors.iter().map(|f| f.id).collect::<Vec<_>>();
    if floors(local) != floors(theirs) {
        return Some(format!(
            "floors {:?} here, {:?} in the bundle",
            floors(local),
            floors(theirs)
        ));
    }
    let count = |what: &str, here: usize, there: usize| {
        (here != there).then(|| format!("{here} {what} here, {there} in the bundle"))
    };
    if let Some(d) = count("vertices", local.vertices.len(), theirs.vertices.len()) {
        return Some(d);
    }
    for v in &theirs.vertices {
        let Some(i) = local.vertex_index(&v.id) else {
            return Some(format!("vertex {:?} is not here", v.id));
        };
        let (p, q) = (local.vertices[i].pos, v.pos);
        if (p.x, p.y, p.floor) != (q.x, q.y, q.floor) {
            return Some(format!(
                "vertex {:?} is at ({}, {}) on floor {} here, at ({}, {}) on floor {} in the bundle",
                v.id, p.x, p.y, p.floor, q.x, q.y, q.floor
            ));
        }
    }
    if let Some(d) = count("edges", local.edges.len(), theirs.edges.len()) {
        return Some(d);
    }
    for e in &theirs.edges {
        let (a, b) = (&theirs.vertices[e.a].id, &theirs.vertices[e.b].id);
        let here = local
            .vertex_index(a)
            .zip(local.vertex_index(b))
            .and_then(|(i, j)| local.edge_between(i, j));
        match here {
            None => return Some(format!("no edge {a:?}-{b:?} here")),
            Some(h) if h.length != e.length => {
                return Some(format!(
                    "edge {a:?}-{b:?} is {} m here, {} m in the bundle",
                    h.length, e.length
                ));
            }
            Some(_) => {}
        }
    }
    None
}

impl Store {
    /// Everything collected so far in a building, as observations to condition a plan on
    /// (a new surveyor's walk then goes where the data is thinnest). The label uncertainty
    /// `sigma_m` of each fingerprint becomes its extra noise under `kernel` (SPEC 4).
    pub fn collected_observations<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        kernel: &crate::gp::Kernel,
    ) -> Result<Vec<crate::utility::Observation>> {
        Ok(self
            .list_collected(building, None)?
            .iter()
            .map(|c| crate::utility::Observation {
                pos: crate::gp::Point::new(c.fingerprint.x, c.fingerprint.y, c.fingerprint.floor),
                extra_noise: kernel.label_noise(c.fingerprint.sigma_m),
            })
            .collect())
    }
}
