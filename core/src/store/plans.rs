//! Planning results: request, walk and figures, as the planner fills them in.

use rusqlite::{Connection, OptionalExtension, params};
use serde::{Deserialize, Serialize};

use super::{BuildingRef, building_id, query_all, read_tx, write_tx};
use crate::gp::Kernel;
use crate::plan::PlanOrigin;
use crate::surveyor::Surveyor;
use crate::{Error, Result};

/// A planning request and its result (the fields of SPEC section 7's planning result plus
/// the request that produced it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanRecord {
    /// Start vertex id.
    pub start: String,
    /// End vertex id.
    pub end: String,
    /// Budget `B`, metres.
    pub budget_m: f64,
    /// Who the plan was made for (robot or human, speeds, scan interval, step error...);
    /// `None` for a walk handed to a session rather than planned (SQL `null`), and for a
    /// stored value of a shape this version cannot read (only early development versions
    /// wrote one).
    pub surveyor: Option<Surveyor>,
    /// The kernel the utility was computed with.
    pub kernel: Kernel,
    /// Where the walk came from: a planner (`greedy`, `genetic`, ...), the session's
    /// replanner (`session-greedy`) or a caller (`given`); stored as that name.
    pub algorithm: PlanOrigin,
    /// Random seed, if the algorithm uses one.
    pub seed: Option<u64>,
    /// The walk, as vertex ids from `start` to `end`.
    pub walk: Vec<String>,
    /// `C(P)`, metres.
    pub length_m: f64,
    /// Number of sample positions `|R(P)|`.
    pub samples: u64,
    /// `f_D(P)`, nats.
    pub utility_nats: f64,
    /// Planner run time, ms.
    pub elapsed_ms: u64,
    /// When it was planned, ms since the Unix epoch.
    pub created_ms: i64,
}

/// A plan as stored.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StoredPlan {
    pub id: i64,
    pub building_id: i64,
    #[serde(flatten)]
    pub record: PlanRecord,
}

fn check(plan: &PlanRecord) -> Result<()> {
    let bad = |m: String| Err(Error::InvalidRequest(format!("plan: {m}")));
    plan.kernel.validate("plan kernel")?;
    for (name, v) in [
        ("budget_m", plan.budget_m),
        ("length_m", plan.length_m),
        ("utility_nats", plan.utility_nats),
    ] {
        if !v.is_finite() {
            return bad(format!("{name} must be finite, got {v}"));
        }
    }
    if plan.budget_m < 0.0 || plan.length_m < 0.0 {
        return bad("budget and length must not be negative".into());
    }
    match (plan.walk.first(), plan.walk.last()) {
        (Some(first), Some(last)) if *first == plan.start && *last == plan.end => Ok(()),
        (None, _) | (_, None) => bad("the walk is empty".into()),
        _ => bad(format!(
            "the walk must go from start {:?} to end {:?}",
            plan.start, plan.end
        )),
    }
}

pub(super) fn save(
    conn: &mut Connection,
    building: BuildingRef<'_>,
    plan: &PlanRecord,
) -> Result<i64> {
    write_tx(conn, |tx| save_in(tx, building, plan))
}

/// Saves several plans of one building in one transaction (a team's): all or none.
pub(super) fn save_all(
    conn: &mut Connection,
    building: BuildingRef<'_>,
    plans: &[PlanRecord],
) -> Result<Vec<i64>> {
    write_tx(conn, |tx| {
        plans.iter().map(|p| save_in(tx, building, p)).collect()
    })
}

/// [`save`] inside a transaction the caller owns (bundle import writes many
/// sessions in one).
pub(super) fn save_in(
    tx: &Connection,
    building: BuildingRef<'_>,
    plan: &PlanRecord,
) -> Result<i64> {
    check(plan)?;
    let as_i64 = |v: u64, what: &str| {
        i64::try_from(v)
            .map_err(|_| Error::InvalidRequest(format!("plan: {what} {v} is too large")))
    };
    let samples = as_i64(plan.samples, "samples")?;
    let elapsed = as_i64(plan.elapsed_ms, "elapsed_ms")?;
    let bid = building_id(tx, building)?;
    // Every step must be a vertex of this building and every hop an edge of it.
    {
        let mut vertex =
            tx.prepare("SELECT 1 FROM vertices WHERE building_id = ?1 AND vid = ?2")?;
        let mut edge = tx.prepare(
            "SELECT 1 FROM edges WHERE building_id = ?1
             AND ((a = ?2 AND b = ?3) OR (a = ?3 AND b = ?2))",
        )?;
        for (step, v) in plan.walk.iter().enumerate() {
            if !vertex.exists(params![bid, v])? {
                return Err(Error::InvalidWalk {
                    step,
                    message: format!("unknown vertex {v:?} in {building}"),
                });
            }
            if step > 0 {
                let prev = &plan.walk[step - 1];
                if !edge.exists(params![bid, prev, v])? {
                    return Err(Error::InvalidWalk {
                        step,
                        message: format!("no edge between {prev:?} and {v:?}"),
                    });
                }
            }
        }
    }
    tx.execute(
        "INSERT INTO plans (building_id, created_ms, start_vid, end_vid, budget_m, surveyor,
                            sf2, ell, sn2, algorithm, seed, length_m, samples, utility_nats,
                            elapsed_ms)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15)",
        params![
            bid,
            plan.created_ms,
            plan.start,
            plan.end,
            plan.budget_m,
            serde_json::to_string(&plan.surveyor)
                .map_err(|e| Error::InvalidRequest(format!("plan surveyor: {e}")))?,
            plan.kernel.sf2,
            plan.kernel.ell,
            plan.kernel.sn2,
            plan.algorithm.name(),
            // A u64 seed is kept bit for bit in SQLite's signed 64-bit integer.
            plan.seed.map(|s| s as i64),
            plan.length_m,
            samples,
            plan.utility_nats,
            elapsed,
        ],
    )?;
    let id = tx.last_insert_rowid();
    {
        let mut st = tx.prepare(
            "INSERT INTO plan_steps (plan_id, step, building_id, vid) VALUES (?1, ?2, ?3, ?4)",
        )?;
        for (step, v) in plan.walk.iter().enumerate() {
            st.execute(params![id, step as i64, bid, v])?;
        }
    }
    Ok(id)
}

const PLAN_SQL: &str = "SELECT id, building_id, created_ms, start_vid, end_vid, budget_m,
    surveyor, sf2, ell, sn2, algorithm, seed, length_m, samples, utility_nats, elapsed_ms
    FROM plans";

fn plan_row(conn: &Connection, r: &rusqlite::Row<'_>) -> Result<StoredPlan> {
    let id: i64 = r.get(0)?;
    let surveyor_text: String = r.get(6)?;
    // Early development versions stored other shapes here (the column only requires JSON);
    // such a plan reads as one without a recorded surveyor rather than failing every list
    // of the building's plans. The row itself is never rewritten.
    let surveyor = serde_json::from_str::<Option<Surveyor>>(&surveyor_text)
        .ok()
        .flatten();
    let walk = query_all(
        conn,
        "SELECT vid FROM plan_steps WHERE plan_id = ?1 ORDER BY step",
        [id],
        |r| r.get(0),
    )?;
    Ok(StoredPlan {
        id,
        building_id: r.get(1)?,
        record: PlanRecord {
            created_ms: r.get(2)?,
            start: r.get(3)?,
            end: r.get(4)?,
            budget_m: r.get(5)?,
            surveyor,
            kernel: Kernel::new(r.get(7)?, r.get(8)?, r.get(9)?),
            algorithm: PlanOrigin::from_name(&r.get::<_, String>(10)?)
                .map_err(|e| Error::InvalidRequest(format!("plan {id}: stored algorithm: {e}")))?,
            seed: r.get::<_, Option<i64>>(11)?.map(|s| s as u64),
            length_m: r.get(12)?,
            samples: r.get::<_, i64>(13)?.max(0) as u64,
            utility_nats: r.get(14)?,
            elapsed_ms: r.get::<_, i64>(15)?.max(0) as u64,
            walk,
        },
    })
}

pub(super) fn load(conn: &Connection, id: i64) -> Result<StoredPlan> {
    read_tx(conn, |conn| {
        let mut st = conn.prepare(&format!("{PLAN_SQL} WHERE id = ?1"))?;
        let mut rows = st.query([id])?;
        match rows.next()? {
            Some(r) => plan_row(conn, r),
            None => Err(Error::NotFound(format!("plan {id} is not in the database"))),
        }
    })
}

pub(super) fn list(conn: &Connection, building: BuildingRef<'_>) -> Result<Vec<StoredPlan>> {
    read_tx(conn, |conn| {
        let bid = building_id(conn, building)?;
        let mut st = conn.prepare(&format!(
            "{PLAN_SQL} WHERE building_id = ?1 ORDER BY created_ms, id"
        ))?;
        let mut rows = st.query([bid])?;
        let mut out = Vec::new();
        while let Some(r) = rows.next()? {
            out.push(plan_row(conn, r)?);
        }
        Ok(out)
    })
}

/// Whether a plan exists and belongs to the building (sessions refer to plans).
pub(super) fn belongs(conn: &Connection, plan_id: i64, building_id: i64) -> Result<bool> {
    Ok(conn
        .query_row(
            "SELECT building_id FROM plans WHERE id = ?1",
            [plan_id],
            |r| r.get::<_, i64>(0),
        )
        .optional()?
        == Some(building_id))
}

impl PlanRecord {
    /// The record of a plan as the planner returned it.
    pub fn from_plan(
        req: &crate::plan::PlanRequest,
        res: &crate::plan::PlanResult,
        created_ms: i64,
    ) -> Self {
        PlanRecord {
            start: req.start.clone(),
            end: req.end.clone(),
            budget_m: req.budget,
            surveyor: Some(req.settings.model),
            kernel: res.kernel,
            algorithm: res.algorithm.into(),
            seed: Some(res.seed),
            walk: res.walk.clone(),
            length_m: res.length_m,
            samples: res.samples as u64,
            utility_nats: res.utility_nats,
            elapsed_ms: res.elapsed_ms,
            created_ms,
        }
    }
}
