//! The plain data of a survey session: events in, acknowledgements, guidance, progress and
//! the summary out. Every type here is a plain struct or enum (no references, no generics)
//! so that the bindings can mirror it one to one.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

pub use crate::surveyor::{DEFAULT_STEP_LENGTH_M, Surveyor};
use crate::{Error, Result};

/// Strongest RSS a scan may report, dBm (a reading above it is a driver bug).
pub const MAX_RSS_DBM: f64 = 0.0;
/// Weakest RSS a scan may report, dBm.
pub const MIN_RSS_DBM: f64 = -120.0;
/// Most readings one scan may carry.
pub const MAX_READINGS: usize = 4096;
/// Most steps one step event may carry.
pub const MAX_STEPS_PER_EVENT: u32 = 10_000;
/// Latest event time a session accepts, milliseconds since the Unix epoch: 100 Julian years
/// (early 2070). Event times run from 0 to this; a device clock outside is broken, and the
/// bound keeps every difference and sum of event times (active time, pauses) far inside
/// `i64` (the fuzzer sent times at `i64::MIN` and `i64::MAX`).
pub const MAX_EVENT_T_MS: i64 = 100 * 36_525 * 864_000;

/// How the session judges and reacts to the surveyor leaving the plan.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SessionOptions {
    /// A human is off-route when the step counter puts them this many metres past the
    /// next check-in that was due ...
    pub off_route_slack_m: f64,
    /// ... plus this fraction of the length of the leg to that check-in.
    pub off_route_slack_fraction: f64,
    /// A robot pose farther than this from the planned walk is off-route, metres.
    pub robot_tolerance_m: f64,
    /// Replan automatically when the surveyor goes off-route.
    pub auto_replan: bool,
    /// Weight of the initial step length in its re-estimation, in steps: the estimate is
    /// `(w L0 + sum of leg lengths) / (w + sum of (steps - 1/2))` over the legs between
    /// consecutive on-route check-ins (the last step of a leg stops at the vertex, half a
    /// stride short on average).
    pub calibration_weight_steps: f64,
    /// Seed of the replanner (replan `k` uses `seed + k`).
    pub seed: u64,
    /// Replans keep part of the budget left in reserve for wrong turns, following the
    /// rate of wrong turns observed so far (see `Session::replan`).
    pub deviation_reserve: bool,
    /// Memory budget of the session, MiB: on a phone, what the app allows. Half of it is
    /// the running posterior's (past that, its rows average consecutive samples, see
    /// `session::posterior`); a replan may use all of it (the plan's own
    /// `memory_budget`) and one that would need more is refused with the size.
    pub memory_budget_mb: u64,
}

impl Default for SessionOptions {
    fn default() -> Self {
        SessionOptions {
            off_route_slack_m: 3.0,
            off_route_slack_fraction: 0.25,
            robot_tolerance_m: 1.5,
            auto_replan: true,
            calibration_weight_steps: 20.0,
            seed: 1,
            deviation_reserve: true,
            memory_budget_mb: crate::plan::PlanSettings::default().memory_budget >> 20,
        }
    }
}

impl SessionOptions {
    /// Checks every option; the message names the bad one.
    pub fn validate(&self) -> Result<()> {
        if let Some((name, v)) = crate::error::first_negative([
            ("off_route_slack_m", self.off_route_slack_m),
            ("off_route_slack_fraction", self.off_route_slack_fraction),
            ("robot_tolerance_m", self.robot_tolerance_m),
            ("calibration_weight_steps", self.calibration_weight_steps),
        ]) {
            return Err(Error::InvalidRequest(format!(
                "session options: {name} must be a finite number >= 0, got {v}"
            )));
        }
        if self.memory_budget_mb == 0 {
            return Err(Error::InvalidRequest(
                "session options: memory_budget_mb must be at least 1 MiB, got 0".into(),
            ));
        }
        Ok(())
    }
}

/// One access point heard in a scan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reading {
    /// BSSID (or any stable access-point name).
    pub bssid: String,
    /// Received signal strength, dBm, in [-120, 0].
    pub rss_dbm: f64,
}

/// What the app reports. Every event carries the device time in milliseconds since the Unix
/// epoch, from 0 to [`MAX_EVENT_T_MS`]; times never go backwards within a session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Event {
    /// The step counter counted `steps` more steps (usually 1).
    Step {
        t_ms: i64,
        steps: u32,
    },
    /// A completed Wi-Fi scan.
    Scan {
        t_ms: i64,
        readings: Vec<Reading>,
    },
    /// The surveyor confirms being at a vertex (by its id).
    CheckIn {
        t_ms: i64,
        vertex: String,
    },
    /// A robot's own position estimate (metres, floor id).
    Pose {
        t_ms: i64,
        x: f64,
        y: f64,
        floor: i64,
    },
    Pause {
        t_ms: i64,
    },
    Resume {
        t_ms: i64,
    },
    /// The walk is done.
    Finish {
        t_ms: i64,
    },
    /// The walk is abandoned.
    Abort {
        t_ms: i64,
        reason: Option<String>,
    },
}

impl Event {
    /// The device time of the event.
    pub fn t_ms(&self) -> i64 {
        match *self {
            Event::Step { t_ms, .. }
            | Event::Scan { t_ms, .. }
            | Event::CheckIn { t_ms, .. }
            | Event::Pose { t_ms, .. }
            | Event::Pause { t_ms }
            | Event::Resume { t_ms }
            | Event::Finish { t_ms }
            | Event::Abort { t_ms, .. } => t_ms,
        }
    }

    /// The event with every negative zero (an RSS of -0 dBm, a pose at x = -0) made +0:
    /// both spell one value, and the SQLite log stores both as 0, so a session that kept the
    /// sign would differ from the same session resumed from its log.
    pub fn without_negative_zeros(mut self) -> Event {
        match &mut self {
            Event::Scan { readings, .. } => {
                for r in readings {
                    r.rss_dbm += 0.0;
                }
            }
            Event::Pose { x, y, .. } => {
                *x += 0.0;
                *y += 0.0;
            }
            _ => {}
        }
        self
    }

    /// Short name of the kind (`step`, `scan`, ...).
    pub fn kind(&self) -> &'static str {
        match self {
            Event::Step { .. } => "step",
            Event::Scan { .. } => "scan",
            Event::CheckIn { .. } => "check_in",
            Event::Pose { .. } => "pose",
            Event::Pause { .. } => "pause",
            Event::Resume { .. } => "resume",
            Event::Finish { .. } => "finish",
            Event::Abort { .. } => "abort",
        }
    }
}

/// Where a session stands: one type for the live session and the store, which reads it
/// off the last lifecycle event.
pub use crate::store::SessionStatus;

/// A position estimate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Position {
    pub x: f64,
    pub y: f64,
    pub floor: i64,
}

/// A fingerprint collected by the session: a scan and the position it is labelled with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CollectedSample {
    /// Seq of the scan event in the session's log.
    pub seq: i64,
    pub t_ms: i64,
    /// Estimated position.
    pub position: Position,
    /// Distance walked since the last check-in (`u` of SPEC section 4); `None` for a robot.
    pub since_checkin_m: Option<f64>,
    /// Standard deviation of the position label, metres (`s = eps * u`).
    pub sigma_m: f64,
    /// Extra observation noise of the label, dB² (`Kernel::label_noise(s)`).
    pub extra_noise: f64,
    /// dBm per access point.
    pub rss: BTreeMap<String, f64>,
}

/// The answer to an accepted event: it is on disk.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ack {
    /// Seq of the event in the session's log.
    pub seq: i64,
    pub status: SessionStatus,
    /// Whether the surveyor is off the planned walk after this event.
    pub off_route: bool,
    /// This event took the surveyor off-route.
    pub went_off_route: bool,
    /// Seq of the replan event written because of this event, if the session replanned.
    pub replan_seq: Option<i64>,
    /// Why an automatic replan failed, if it did (the event itself is still recorded).
    pub replan_error: Option<String>,
    /// The sample a scan produced.
    pub sample: Option<CollectedSample>,
    /// Position estimate after the event.
    pub position: Position,
}

impl Ack {
    /// The highest seq this acknowledgement covers (the replan's, if there was one).
    pub fn last_seq(&self) -> i64 {
        self.replan_seq.unwrap_or(self.seq)
    }
}

/// What to do at the next waypoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Turn {
    /// Keep going (the walk bends by at most 30 degrees there).
    Straight,
    Left,
    Right,
    /// Turn round (more than 150 degrees).
    TurnBack,
    /// Take the stairs or the lift to another floor.
    ChangeFloor,
    /// The waypoint is the end of the walk.
    Arrive,
}

/// One vertex of the walk still ahead.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Waypoint {
    pub vertex: String,
    pub label: Option<String>,
    /// The surveyor is expected to check in there.
    pub check_in: bool,
    /// Distance from the current position along the walk, metres.
    pub distance_m: f64,
}

/// What the surveyor should do next.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Guidance {
    pub status: SessionStatus,
    pub off_route: bool,
    /// Next vertex of the walk (`None` once the end is reached or the session is over).
    pub next_vertex: Option<String>,
    pub next_label: Option<String>,
    /// Distance to it along the walk, metres.
    pub distance_m: f64,
    /// The turn to make there.
    pub turn: Turn,
    /// Whether to check in at the next vertex.
    pub check_in_at_next: bool,
    /// The next vertex where a check-in is due, and how far it is.
    pub next_check_in: Option<String>,
    pub distance_to_check_in_m: f64,
    /// One sentence for the screen.
    pub message: String,
}

/// Posterior uncertainty at one vertex (for the coverage map).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VertexUncertainty {
    pub vertex: String,
    pub x: f64,
    pub y: f64,
    pub floor: i64,
    /// Posterior standard deviation of the fingerprint (latent RSS), dB.
    pub std_db: f64,
}

/// A snapshot of a session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Progress {
    pub status: SessionStatus,
    pub off_route: bool,
    /// Fraction of the walk done: walked / (walked + remaining), in [0, 1].
    pub fraction_done: f64,
    pub walked_m: f64,
    pub budget_m: f64,
    /// Budget minus metres walked (may be negative after a detour).
    pub budget_left_m: f64,
    /// Metres of planned walk still ahead.
    pub remaining_m: f64,
    /// Active time (pauses excluded), seconds.
    pub elapsed_s: f64,
    /// Estimated time to walk the rest, seconds.
    pub remaining_s: f64,
    pub samples: u64,
    /// Samples the utility and uncertainty below include: all of them, except, once rows
    /// average several samples (`sample_block` above 1), those of a row not yet complete.
    pub samples_in_figures: u64,
    /// Samples per row of the running posterior: 1 while the figures are exact; above 1
    /// once the session's memory budget made each row the mean of that many consecutive
    /// samples, and then the collected utility is a lower bound and the uncertainty an
    /// upper bound of the samples' own (`session::posterior`).
    pub sample_block: u64,
    /// Utility of the plan as first planned (SPEC section 3), nats.
    pub planned_utility_nats: f64,
    /// Utility of the samples actually recorded, with their real label noise, nats.
    pub collected_utility_nats: f64,
    pub step_length_m: f64,
    pub replans: u32,
    pub off_route_events: u32,
    /// Budget beyond the walk ahead kept in reserve for wrong turns, metres (0 until a
    /// replan keeps one).
    pub reserve_m: f64,
    /// Posterior standard deviation at every vertex given pilot data and collected samples.
    pub uncertainty: Vec<VertexUncertainty>,
}

/// The end of a session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub session_id: i64,
    pub status: SessionStatus,
    pub walked_m: f64,
    pub budget_m: f64,
    pub elapsed_s: f64,
    pub samples: u64,
    pub check_ins: u32,
    pub steps: u64,
    pub planned_utility_nats: f64,
    pub collected_utility_nats: f64,
    /// As in [`Progress::sample_block`]: 1 when the figures count every sample.
    pub sample_block: u64,
    pub step_length_m: f64,
    pub replans: u32,
    pub off_route_events: u32,
    /// Mean and largest posterior standard deviation over the vertices, dB.
    pub mean_std_db: f64,
    pub max_std_db: f64,
}

/// The result of a replan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReplanOutcome {
    /// Seq of the replan event.
    pub seq: i64,
    /// Store id of the new plan.
    pub plan_id: i64,
    /// The vertex the new walk starts at (where the surveyor is, or is about to be).
    pub from_vertex: String,
    /// The new walk, vertex ids from `from_vertex` to the end.
    pub walk: Vec<String>,
    pub length_m: f64,
    /// Budget that was left for it.
    pub budget_left_m: f64,
    /// The budget could not reach the end: the walk is the shortest way there.
    pub over_budget: bool,
    /// Metres of the budget left that the new walk keeps back for wrong turns still to
    /// come (it was planned with `budget_left_m - reserve_m`).
    pub reserve_m: f64,
    /// Utility of the pilot data, the samples collected and the new walk, nats: of every
    /// sample up to [`crate::session::posterior::REPLAN_PRIOR_MAX`] of them, beyond of
    /// those the replan conditioned on (one in `k`, the nearest to a vertex), and then a
    /// lower bound.
    pub utility_nats: f64,
}
