//! Records and enums shared by the store, the planner and the sessions: surveyor models
//! and kernel fits, converted to and from the core's types.

use std::sync::Arc;

use trailprint::Building;
use trailprint::surveyor::Surveyor;

use crate::building::KernelParams;
use crate::{Result, TrailprintError};

/// Who walks the survey: the core's [`Surveyor`] (SPEC section 4), field for field, so the
/// two conversions below copy and invent nothing.
#[derive(Debug, Clone, Copy, PartialEq, uniffi::Enum)]
pub enum SurveyorProfile {
    /// A robot labelled by SLAM: one scan every `interval_m` metres (paper: 0.5).
    Robot {
        /// Metres between scans (default 0.5).
        interval_m: f64,
        /// Driving speed, m/s (time estimates; default 0.5).
        speed_mps: f64,
    },
    /// A person with a step counter.
    Human {
        /// Step length before the session re-estimates it at check-ins, m (default 0.7).
        step_length_m: f64,
        /// Walking speed, m/s (default 1.2).
        speed_mps: f64,
        /// Time between completed Wi-Fi scans, s (default 4; measure it on the phone).
        scan_interval_s: f64,
        /// Relative step-length error (default 0.05).
        step_error: f64,
        /// A turn sharper than this is a check-in, degrees (default 30).
        turn_threshold_deg: f64,
    },
}

impl From<Surveyor> for SurveyorProfile {
    fn from(s: Surveyor) -> Self {
        match s {
            Surveyor::Robot {
                interval_m,
                speed_mps,
            } => SurveyorProfile::Robot {
                interval_m,
                speed_mps,
            },
            Surveyor::Human {
                step_length_m,
                speed_mps,
                scan_interval_s,
                step_error,
                turn_threshold_deg,
            } => SurveyorProfile::Human {
                step_length_m,
                speed_mps,
                scan_interval_s,
                step_error,
                turn_threshold_deg,
            },
        }
    }
}

impl From<SurveyorProfile> for Surveyor {
    fn from(p: SurveyorProfile) -> Self {
        match p {
            SurveyorProfile::Robot {
                interval_m,
                speed_mps,
            } => Surveyor::Robot {
                interval_m,
                speed_mps,
            },
            SurveyorProfile::Human {
                step_length_m,
                speed_mps,
                scan_interval_s,
                step_error,
                turn_threshold_deg,
            } => Surveyor::Human {
                step_length_m,
                speed_mps,
                scan_interval_s,
                step_error,
                turn_threshold_deg,
            },
        }
    }
}

/// The human surveyor with the defaults of SPEC section 4 and a 0.7 m step.
#[uniffi::export]
pub fn default_human_profile() -> SurveyorProfile {
    Surveyor::human().into()
}

/// The paper's robot (a scan every 0.5 m, at 0.5 m/s).
#[uniffi::export]
pub fn default_robot_profile() -> SurveyorProfile {
    Surveyor::robot().into()
}

/// A kernel fitted on pilot data.
#[derive(Debug, Clone, uniffi::Record)]
pub struct FitSummary {
    /// The fitted kernel.
    pub kernel: KernelParams,
    /// Summed log marginal likelihood, nats.
    pub log_likelihood: f64,
    /// Access points used by the fit, sorted by name.
    pub aps_used: Vec<String>,
    /// Whether each access point was fitted only on the locations that hear it: the
    /// rule on a large floor, where none is heard at half the pilot locations (SPEC 2's
    /// rule, `false`).
    pub heard_only: bool,
    /// Number of pilot locations.
    pub locations: u32,
}

impl From<trailprint::gp::FitResult> for FitSummary {
    fn from(f: trailprint::gp::FitResult) -> Self {
        FitSummary {
            kernel: f.kernel.into(),
            log_likelihood: f.log_likelihood,
            aps_used: f.aps_used,
            heard_only: f.ap_rule == trailprint::gp::fit::ApRule::HeardOnly,
            locations: u32::try_from(f.locations).unwrap_or(u32::MAX),
        }
    }
}

/// Fits the kernel `(sf2, ell, sn2)` on a building's pilot data (SPEC section 2).
#[uniffi::export]
pub fn fit_building_kernel(building_json: String, origin: String) -> Result<FitSummary> {
    let b = Building::from_json(&building_json, &origin)?;
    Ok(trailprint::gp::fit_kernel(&b.pilot)?.into())
}

/// The mutual information `f_D(P)` (nats) of a walk given by vertex ids, with the given
/// kernel, or the building's own kernel when `kernel` is null. A walk whose evaluation
/// would need more than 512 MiB (a building of thousands of vertices) is refused with
/// the size, before anything is allocated.
#[uniffi::export]
pub fn walk_utility(
    building_json: String,
    origin: String,
    walk: Vec<String>,
    surveyor: SurveyorProfile,
    kernel: Option<KernelParams>,
) -> Result<f64> {
    let b = Building::from_json(&building_json, &origin)?;
    let kernel = kernel.map(Into::into).or(b.kernel).ok_or_else(|| {
        TrailprintError::Fit(format!(
            "building {:?} has no kernel: fit one first or pass it",
            b.name
        ))
    })?;
    let indices = b.resolve_walk(&walk)?;
    let model = surveyor.into();
    let samples = trailprint::samples::sample_walk(&b, &indices, &model, &kernel)?.len();
    trailprint::utility::check_evaluation_memory(
        &b,
        samples,
        1,
        trailprint::plan::DEFAULT_MEMORY_BUDGET,
    )?;
    let engine = trailprint::utility::UtilityEngine::new(Arc::new(b), kernel, model)?;
    Ok(engine.utility(&indices)?)
}
