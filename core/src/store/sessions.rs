//! Survey sessions: tables and typed helpers only (append and list events, list collected
//! fingerprints). The session logic (which event is allowed when, replanning, resuming) is
//! built on these by the sessions code.

use std::collections::BTreeMap;

use rusqlite::{Connection, OptionalExtension, params};
use serde::{Deserialize, Serialize};

use super::{
    BuildingRef, UPSERT_ACCESS_POINT, building_id, group_readings, query_all, read_tx, write_tx,
};
use crate::{Error, Result};

/// A fingerprint collected during a session: the RSS heard and where the surveyor was
/// estimated to be.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollectedFingerprint {
    /// Estimated position (metres, floor id of the building).
    pub x: f64,
    pub y: f64,
    #[serde(default)]
    pub floor: i64,
    /// Standard deviation of the position estimate, metres (`s = eps * u`, SPEC 4).
    pub sigma_m: f64,
    /// Distance walked since the last check-in, `u` of SPEC 4, if known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub since_checkin_m: Option<f64>,
    /// dBm per access point heard.
    pub rss: BTreeMap<String, f64>,
}

/// One event of a session's log. Serialised with a `kind` tag; the store keeps `kind` in
/// its own column and the other fields as JSON (a scan's fingerprint goes to
/// `collected_fingerprints`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SessionEvent {
    /// Steps counted by the step counter since the previous step event.
    Step {
        steps: u32,
        distance_m: f64,
    },
    /// A completed Wi-Fi scan and the position estimate it is labelled with.
    Scan(CollectedFingerprint),
    /// The surveyor confirmed being at a vertex.
    CheckIn {
        vertex: String,
    },
    /// A position estimate (for example after a turn or from a map tap).
    Pose {
        x: f64,
        y: f64,
        floor: i64,
        sigma_m: f64,
    },
    /// The session switched to another saved plan.
    Replan {
        plan_id: i64,
    },
    Pause,
    Resume,
    Finish,
    Abort {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        reason: Option<String>,
    },
}

impl SessionEvent {
    /// The `kind` column value.
    pub fn kind(&self) -> &'static str {
        match self {
            SessionEvent::Step { .. } => "step",
            SessionEvent::Scan(_) => "scan",
            SessionEvent::CheckIn { .. } => "check_in",
            SessionEvent::Pose { .. } => "pose",
            SessionEvent::Replan { .. } => "replan",
            SessionEvent::Pause => "pause",
            SessionEvent::Resume => "resume",
            SessionEvent::Finish => "finish",
            SessionEvent::Abort { .. } => "abort",
        }
    }
}

/// An event as stored.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StoredEvent {
    pub seq: i64,
    pub at_ms: i64,
    pub event: SessionEvent,
}

/// Where a session stands, read off its last lifecycle event (no event: active); the live
/// session ([`crate::session::Session`]) tracks the same status as events arrive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SessionStatus {
    Active,
    Paused,
    Finished,
    Aborted,
}

/// A session's summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SessionInfo {
    pub id: i64,
    pub building_id: i64,
    pub plan_id: Option<i64>,
    pub created_ms: i64,
    pub surveyor: Option<serde_json::Value>,
    /// Seq of the last event, 0 if none.
    pub last_seq: i64,
    pub status: SessionStatus,
    pub collected: u64,
}

/// A collected fingerprint as stored, with the session and event it came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StoredCollected {
    pub session_id: i64,
    pub seq: i64,
    pub at_ms: i64,
    #[serde(flatten)]
    pub fingerprint: CollectedFingerprint,
}

pub(super) fn create(
    conn: &mut Connection,
    building: BuildingRef<'_>,
    plan_id: Option<i64>,
    surveyor: Option<&serde_json::Value>,
    created_ms: i64,
) -> Result<i64> {
    write_tx(conn, |tx| {
        create_in(tx, building, plan_id, surveyor, created_ms)
    })
}

/// [`create`] inside a transaction the caller owns (bundle import writes many
/// sessions in one).
pub(super) fn create_in(
    tx: &Connection,
    building: BuildingRef<'_>,
    plan_id: Option<i64>,
    surveyor: Option<&serde_json::Value>,
    created_ms: i64,
) -> Result<i64> {
    let bid = building_id(tx, building)?;
    if let Some(p) = plan_id
        && !super::plans::belongs(tx, p, bid)?
    {
        return Err(Error::NotFound(format!(
            "plan {p} of {building} is not in the database"
        )));
    }
    tx.execute(
        "INSERT INTO survey_sessions (building_id, plan_id, created_ms, surveyor)
         VALUES (?1, ?2, ?3, ?4)",
        params![bid, plan_id, created_ms, surveyor.map(|s| s.to_string())],
    )?;
    let id = tx.last_insert_rowid();
    Ok(id)
}

fn finite(what: &str, values: &[(&str, f64)]) -> Result<()> {
    for (name, v) in values {
        if !v.is_finite() {
            return Err(Error::InvalidRequest(format!(
                "{what}: {name} must be finite, got {v}"
            )));
        }
    }
    Ok(())
}

fn check_fingerprint(fp: &CollectedFingerprint) -> Result<()> {
    finite("scan", &[("x", fp.x), ("y", fp.y), ("sigma_m", fp.sigma_m)])?;
    if fp.sigma_m < 0.0
        || fp
            .since_checkin_m
            .is_some_and(|u| !(u >= 0.0 && u.is_finite()))
    {
        return Err(Error::InvalidRequest(
            "scan: sigma_m and since_checkin_m must be finite and not negative".into(),
        ));
    }
    for (ap, &rss) in &fp.rss {
        if !crate::building::rss_ok(rss) {
            return Err(Error::InvalidRequest(format!(
                "scan: RSS of {ap:?} must be a finite dBm value in [{}, {}], got {rss}",
                crate::building::MIN_RSS_DBM,
                crate::building::MAX_RSS_DBM
            )));
        }
    }
    Ok(())
}

pub(super) fn append(
    conn: &mut Connection,
    session_id: i64,
    at_ms: i64,
    event: &SessionEvent,
) -> Result<i64> {
    write_tx(conn, |tx| append_in(tx, session_id, at_ms, event))
}

/// [`append`] inside a transaction the caller owns (bundle import writes many
/// sessions in one).
pub(super) fn append_in(
    tx: &Connection,
    session_id: i64,
    at_ms: i64,
    event: &SessionEvent,
) -> Result<i64> {
    // The session's bound on event times: a bundle or log holding a time past it could be
    // stored but never replayed into a session.
    if !(0..=crate::session::MAX_EVENT_T_MS).contains(&at_ms) {
        return Err(Error::Session {
            session: session_id,
            message: format!(
                "{} event: at_ms must be from 0 to {} ms since the Unix epoch \
                 (MAX_EVENT_T_MS), got {at_ms}",
                event.kind(),
                crate::session::MAX_EVENT_T_MS
            ),
        });
    }
    match event {
        SessionEvent::Step { distance_m, .. } => {
            finite("step", &[("distance_m", *distance_m)])?;
        }
        SessionEvent::Scan(fp) => check_fingerprint(fp)?,
        SessionEvent::Pose { x, y, sigma_m, .. } => {
            finite("pose", &[("x", *x), ("y", *y), ("sigma_m", *sigma_m)])?;
        }
        _ => {}
    }
    let bid: i64 = tx
        .query_row(
            "SELECT building_id FROM survey_sessions WHERE id = ?1",
            [session_id],
            |r| r.get(0),
        )
        .optional()?
        .ok_or_else(|| Error::NotFound(format!("session {session_id} is not in the database")))?;
    let floor_ok = |floor: i64| -> Result<()> {
        let ok = tx
            .prepare_cached("SELECT 1 FROM floors WHERE building_id = ?1 AND floor = ?2")?
            .exists(params![bid, floor])?;
        if ok {
            Ok(())
        } else {
            Err(Error::Session {
                session: session_id,
                message: format!("floor {floor} is not a floor of the session's building"),
            })
        }
    };
    match event {
        SessionEvent::CheckIn { vertex } => {
            let ok = tx
                .prepare_cached("SELECT 1 FROM vertices WHERE building_id = ?1 AND vid = ?2")?
                .exists(params![bid, vertex])?;
            if !ok {
                return Err(Error::Session {
                    session: session_id,
                    message: format!("check-in at unknown vertex {vertex:?}"),
                });
            }
        }
        SessionEvent::Replan { plan_id } if !super::plans::belongs(tx, *plan_id, bid)? => {
            return Err(Error::Session {
                session: session_id,
                message: format!("replan to plan {plan_id}, which is not a plan of its building"),
            });
        }
        SessionEvent::Pose { floor, .. } => floor_ok(*floor)?,
        SessionEvent::Scan(fp) => floor_ok(fp.floor)?,
        _ => {}
    }

    // The log ends at `finish` or `abort`: nothing may follow (a bundle carrying events
    // after its finish is refused here too). Only the last event needs looking at, since
    // this rule keeps every earlier one from following an end.
    let last: Option<(i64, String)> = tx
        .prepare_cached(
            "SELECT seq, kind FROM session_events WHERE session_id = ?1 ORDER BY seq DESC LIMIT 1",
        )?
        .query_row([session_id], |r| Ok((r.get(0)?, r.get(1)?)))
        .optional()?;
    if let Some((last_seq, kind)) = &last
        && (kind == "finish" || kind == "abort")
    {
        return Err(Error::Session {
            session: session_id,
            message: format!(
                "the session ended with {kind} at event {last_seq}: no more events are accepted \
                 (got {})",
                event.kind()
            ),
        });
    }
    let seq = last.map_or(0, |(s, _)| s) + 1;
    let payload = match event {
        SessionEvent::Scan(_) => "{}".to_string(),
        other => {
            let mut v = serde_json::to_value(other)
                .map_err(|e| Error::InvalidRequest(format!("event: {e}")))?;
            if let Some(map) = v.as_object_mut() {
                map.remove("kind");
            }
            v.to_string()
        }
    };
    tx.execute(
        "INSERT INTO session_events (session_id, seq, kind, at_ms, payload)
         VALUES (?1, ?2, ?3, ?4, ?5)",
        params![session_id, seq, event.kind(), at_ms, payload],
    )?;
    if let SessionEvent::Scan(fp) = event {
        tx.execute(
            "INSERT INTO collected_fingerprints (session_id, seq, x, y, floor, sigma_m, since_checkin_m)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
            params![session_id, seq, fp.x, fp.y, fp.floor, fp.sigma_m, fp.since_checkin_m],
        )?;
        let fid = tx.last_insert_rowid();
        let mut ap = tx.prepare_cached(UPSERT_ACCESS_POINT)?;
        let mut rd = tx.prepare_cached(
            "INSERT INTO collected_readings (fingerprint_id, ap_id, rss) VALUES (?1, ?2, ?3)",
        )?;
        for (name, rss) in &fp.rss {
            let ap_id: i64 = ap.query_row(params![bid, name], |r| r.get(0))?;
            rd.execute(params![fid, ap_id, rss])?;
        }
    }
    Ok(seq)
}

/// Loads the fingerprint of a scan event.
fn scan_fingerprint(conn: &Connection, session_id: i64, seq: i64) -> Result<CollectedFingerprint> {
    let (fid, x, y, floor, sigma_m, since_checkin_m): (i64, f64, f64, i64, f64, Option<f64>) = conn
        .prepare_cached(
            "SELECT id, x, y, floor, sigma_m, since_checkin_m FROM collected_fingerprints
             WHERE session_id = ?1 AND seq = ?2",
        )?
        .query_row(params![session_id, seq], |r| r.try_into())?;
    let rss = conn
        .prepare_cached(
            "SELECT a.name, r.rss FROM collected_readings r JOIN access_points a ON a.id = r.ap_id
             WHERE r.fingerprint_id = ?1",
        )?
        .query_map([fid], |r| Ok((r.get(0)?, r.get(1)?)))?
        .collect::<rusqlite::Result<BTreeMap<String, f64>>>()?;
    Ok(CollectedFingerprint {
        x,
        y,
        floor,
        sigma_m,
        since_checkin_m,
        rss,
    })
}

pub(super) fn events(
    conn: &Connection,
    session_id: i64,
    after_seq: i64,
) -> Result<Vec<StoredEvent>> {
    read_tx(conn, |conn| {
        let exists = conn
            .prepare_cached("SELECT 1 FROM survey_sessions WHERE id = ?1")?
            .exists([session_id])?;
        if !exists {
            return Err(Error::NotFound(format!(
                "session {session_id} is not in the database"
            )));
        }
        let rows = query_all(
            conn,
            "SELECT seq, kind, at_ms, payload FROM session_events
             WHERE session_id = ?1 AND seq > ?2 ORDER BY seq",
            params![session_id, after_seq],
            |r| <(i64, String, i64, String)>::try_from(r),
        )?;
        let mut out = Vec::with_capacity(rows.len());
        for (seq, kind, at_ms, payload) in rows {
            let event = if kind == "scan" {
                SessionEvent::Scan(scan_fingerprint(conn, session_id, seq)?)
            } else {
                let mut v: serde_json::Value =
                    serde_json::from_str(&payload).map_err(|e| Error::Session {
                        session: session_id,
                        message: format!("event {seq}: stored payload is not JSON: {e}"),
                    })?;
                if let Some(map) = v.as_object_mut() {
                    map.insert("kind".into(), serde_json::Value::String(kind.clone()));
                }
                serde_json::from_value(v).map_err(|e| Error::Session {
                    session: session_id,
                    message: format!(
                        "event {seq} of kind {kind:?} cannot be read by this version: {e}"
                    ),
                })?
            };
            out.push(StoredEvent { seq, at_ms, event });
        }
        Ok(out)
    })
}

pub(super) fn list(conn: &Connection, building: BuildingRef<'_>) -> Result<Vec<SessionInfo>> {
    read_tx(conn, |conn| {
        let bid = building_id(conn, building)?;
        let rows = query_all(
            conn,
            "SELECT s.id, s.plan_id, s.created_ms, s.surveyor,
                    (SELECT coalesce(max(seq), 0) FROM session_events e WHERE e.session_id = s.id),
                    (SELECT kind FROM session_events e WHERE e.session_id = s.id
                       AND kind IN ('pause', 'resume', 'finish', 'abort')
                     ORDER BY seq DESC LIMIT 1),
                    (SELECT count(*) FROM collected_fingerprints c WHERE c.session_id = s.id)
             FROM survey_sessions s WHERE s.building_id = ?1 ORDER BY s.created_ms, s.id",
            [bid],
            |r| {
                <(
                    i64,
                    Option<i64>,
                    i64,
                    Option<String>,
                    i64,
                    Option<String>,
                    i64,
                )>::try_from(r)
            },
        )?;
        rows.into_iter()
            .map(
                |(id, plan_id, created_ms, surveyor, last_seq, last_kind, collected)| {
                    let surveyor = surveyor
                        .map(|s| serde_json::from_str(&s))
                        .transpose()
                        .map_err(|e| Error::Session {
                            session: id,
                            message: format!("stored surveyor model is not JSON: {e}"),
                        })?;
                    let status = match last_kind.as_deref() {
                        Some("pause") => SessionStatus::Paused,
                        Some("finish") => SessionStatus::Finished,
                        Some("abort") => SessionStatus::Aborted,
                        _ => SessionStatus::Active,
                    };
                    Ok(SessionInfo {
                        id,
                        building_id: bid,
                        plan_id,
                        created_ms,
                        surveyor,
                        last_seq,
                        status,
                        collected: collected.max(0) as u64,
                    })
                },
            )
            .collect()
    })
}

pub(super) fn collected(
    conn: &Connection,
    building: BuildingRef<'_>,
    session_id: Option<i64>,
) -> Result<Vec<StoredCollected>> {
    read_tx(conn, |conn| {
        let bid = building_id(conn, building)?;
        let mut st = conn.prepare(
            "SELECT c.id, c.session_id, c.seq, e.at_ms, c.x, c.y, c.floor, c.sigma_m,
                    c.since_checkin_m, a.name, r.rss
             FROM collected_fingerprints c
             JOIN survey_sessions s ON s.id = c.session_id
             JOIN session_events e ON e.session_id = c.session_id AND e.seq = c.seq
             LEFT JOIN collected_readings r ON r.fingerprint_id = c.id
             LEFT JOIN access_points a ON a.id = r.ap_id
             WHERE s.building_id = ?1 AND (?2 IS NULL OR c.session_id = ?2)
             ORDER BY c.session_id, c.seq",
        )?;
        let out = group_readings(
            st.query(params![bid, session_id])?,
            0,
            9,
            |r| {
                Ok(StoredCollected {
                    session_id: r.get(1)?,
                    seq: r.get(2)?,
                    at_ms: r.get(3)?,
                    fingerprint: CollectedFingerprint {
                        x: r.get(4)?,
                        y: r.get(5)?,
                        floor: r.get(6)?,
                        sigma_m: r.get(7)?,
                        since_checkin_m: r.get(8)?,
                        rss: BTreeMap::new(),
                    },
                })
            },
            |c| &mut c.fingerprint.rss,
        )?;
        Ok(out)
    })
}

/// Who walked a session and on which device (bundle provenance), by session id.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SessionProvenance {
    pub session_id: i64,
    pub surveyor_name: Option<String>,
    pub device: Option<String>,
}

/// A session's own row: its building, plan and surveyor settings (JSON text as stored).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SessionHeader {
    pub building_id: i64,
    pub plan_id: Option<i64>,
    pub surveyor: Option<String>,
}

pub(super) fn header(conn: &Connection, session_id: i64) -> Result<SessionHeader> {
    conn.query_row(
        "SELECT building_id, plan_id, surveyor FROM survey_sessions WHERE id = ?1",
        [session_id],
        |r| {
            Ok(SessionHeader {
                building_id: r.get(0)?,
                plan_id: r.get(1)?,
                surveyor: r.get(2)?,
            })
        },
    )
    .optional()?
    .ok_or_else(|| Error::NotFound(format!("session {session_id} is not in the database")))
}

pub(super) fn provenance(
    conn: &Connection,
    building: BuildingRef<'_>,
) -> Result<Vec<SessionProvenance>> {
    read_tx(conn, |conn| {
        let bid = building_id(conn, building)?;
        query_all(
            conn,
            "SELECT id, surveyor_name, device FROM survey_sessions WHERE building_id = ?1
             ORDER BY id",
            [bid],
            |r| {
                Ok(SessionProvenance {
                    session_id: r.get(0)?,
                    surveyor_name: r.get(1)?,
                    device: r.get(2)?,
                })
            },
        )
    })
}
