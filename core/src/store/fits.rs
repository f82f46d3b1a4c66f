//! Kernel fits (SPEC section 2) recorded per building.

use rusqlite::{Connection, OptionalExtension, TransactionBehavior, params};
use serde::{Deserialize, Serialize};

use super::{BuildingRef, UPSERT_ACCESS_POINT, building_id, query_all, read_tx};
use crate::gp::Kernel;
use crate::gp::fit::ApRule;
use crate::{Error, Result};

/// A hyperparameter fit: the kernel, how well it fits, which access points it used, when.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitRecord {
    pub kernel: Kernel,
    /// Sum over the access points used of the GP log marginal likelihood, nats.
    pub log_likelihood: f64,
    /// Access points kept by the fit, in the fitter's order.
    pub aps_used: Vec<String>,
    /// How they were chosen: heard at half the pilot locations or more (SPEC 2), or, on a
    /// floor where none is, each on the locations that hear it.
    #[serde(default)]
    pub ap_rule: ApRule,
    /// When the fit was made, ms since the Unix epoch.
    pub fitted_ms: i64,
}

impl FitRecord {
    /// The record of a fit made by [`fit_kernel`](crate::gp::fit::fit_kernel) at `fitted_ms`.
    pub fn from_fit(fit: &crate::gp::fit::FitResult, fitted_ms: i64) -> Self {
        FitRecord {
            kernel: fit.kernel,
            log_likelihood: fit.log_likelihood,
            aps_used: fit.aps_used.clone(),
            ap_rule: fit.ap_rule,
            fitted_ms,
        }
    }
}

/// A fit as stored.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StoredFit {
    pub id: i64,
    pub building_id: i64,
    #[serde(flatten)]
    pub record: FitRecord,
}

pub(super) fn record(
    conn: &mut Connection,
    building: BuildingRef<'_>,
    fit: &FitRecord,
) -> Result<i64> {
    fit.kernel.validate("fit kernel")?;
    if !fit.log_likelihood.is_finite() {
        return Err(Error::InvalidRequest(format!(
            "fit: log likelihood must be finite, got {}",
            fit.log_likelihood
        )));
    }
    let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
    let bid = building_id(&tx, building)?;
    tx.execute(
        "INSERT INTO fits (building_id, fitted_ms, sf2, ell, sn2, log_likelihood)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
        params![
            bid,
            fit.fitted_ms,
            fit.kernel.sf2,
            fit.kernel.ell,
            fit.kernel.sn2,
            fit.log_likelihood
        ],
    )?;
    let fit_id = tx.last_insert_rowid();
    if fit.ap_rule == ApRule::HeardOnly {
        tx.execute(
            "INSERT INTO fit_rules (fit_id, ap_rule) VALUES (?1, 'heard_only')",
            [fit_id],
        )?;
    }
    {
        // An access point first met in a fit joins the building's list.
        let mut ap = tx.prepare(UPSERT_ACCESS_POINT)?;
        let mut link =
            tx.prepare("INSERT INTO fit_access_points (fit_id, ord, ap_id) VALUES (?1, ?2, ?3)")?;
        for (ord, name) in fit.aps_used.iter().enumerate() {
            let ap_id: i64 = ap.query_row(params![bid, name], |r| r.get(0))?;
            link.execute(params![fit_id, ord as i64, ap_id])
                .map_err(|e| match e.sqlite_error_code() {
                    Some(rusqlite::ErrorCode::ConstraintViolation) => Error::InvalidRequest(
                        format!("fit: access point {name:?} is listed twice in aps_used"),
                    ),
                    _ => e.into(),
                })?;
        }
    }
    tx.commit()?;
    Ok(fit_id)
}

pub(super) fn latest(conn: &Connection, building: BuildingRef<'_>) -> Result<Option<StoredFit>> {
    read_tx(conn, |conn| {
        let bid = building_id(conn, building)?;
        let row: Option<(i64, i64, f64, f64, f64, f64)> = conn
            .query_row(
                "SELECT id, fitted_ms, sf2, ell, sn2, log_likelihood FROM fits
                 WHERE building_id = ?1 ORDER BY fitted_ms DESC, id DESC LIMIT 1",
                [bid],
                |r| r.try_into(),
            )
            .optional()?;
        let Some((id, fitted_ms, sf2, ell, sn2, log_likelihood)) = row else {
            return Ok(None);
        };
        let aps_used = query_all(
            conn,
            "SELECT a.name FROM fit_access_points f JOIN access_points a ON a.id = f.ap_id
                 WHERE f.fit_id = ?1 ORDER BY f.ord",
            [id],
            |r| r.get(0),
        )?;
        let heard_only: Option<String> = conn
            .query_row(
                "SELECT ap_rule FROM fit_rules WHERE fit_id = ?1",
                [id],
                |r| r.get(0),
            )
            .optional()?;
        let ap_rule = match heard_only.as_deref() {
            None => ApRule::HalfOfLocations,
            Some("heard_only") => ApRule::HeardOnly,
            Some(other) => {
                return Err(Error::InvalidRequest(format!(
                    "fit {id}: unknown access-point rule {other:?} in fit_rules"
                )));
            }
        };
        Ok(Some(StoredFit {
            id,
            building_id: bid,
            record: FitRecord {
                kernel: Kernel::new(sf2, ell, sn2),
                log_likelihood,
                aps_used,
                ap_rule,
                fitted_ms,
            },
        }))
    })
}
