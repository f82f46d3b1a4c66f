//! Survey sessions: a surveyor (or robot) walking a saved plan. Every event is checked,
//! written to the database and only then acknowledged; a session resumes from the database
//! in a fresh store object. The logic is the core's `trailprint::session`; this file only
//! mirrors its types.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use trailprint::session::{self as core, Event, Session};
use trailprint::store;

use crate::Result;
use crate::model::SurveyorProfile;
use crate::store::TrailprintStore;

/// How a session judges and reacts to the surveyor leaving the plan.
#[derive(Debug, Clone, Copy, uniffi::Record)]
pub struct SessionOptions {
    /// A human is off-route this many metres past a check-in that was due...
    pub off_route_slack_m: f64,
    /// ...plus this fraction of the leg to it.
    pub off_route_slack_fraction: f64,
    /// A robot pose farther than this from the walk is off-route, metres.
    pub robot_tolerance_m: f64,
    /// Replan automatically when the surveyor goes off-route.
    pub auto_replan: bool,
    /// Weight of the initial step length in its re-estimation, in steps.
    pub calibration_weight_steps: f64,
    /// Seed of the replanner.
    pub seed: u64,
}

impl From<SessionOptions> for core::SessionOptions {
    fn from(o: SessionOptions) -> Self {
        core::SessionOptions {
            off_route_slack_m: o.off_route_slack_m,
            off_route_slack_fraction: o.off_route_slack_fraction,
            robot_tolerance_m: o.robot_tolerance_m,
            auto_replan: o.auto_replan,
            calibration_weight_steps: o.calibration_weight_steps,
            seed: o.seed,
            ..core::SessionOptions::default()
        }
    }
}

impl From<core::SessionOptions> for SessionOptions {
    fn from(o: core::SessionOptions) -> Self {
        SessionOptions {
            off_route_slack_m: o.off_route_slack_m,
            off_route_slack_fraction: o.off_route_slack_fraction,
            robot_tolerance_m: o.robot_tolerance_m,
            auto_replan: o.auto_replan,
            calibration_weight_steps: o.calibration_weight_steps,
            seed: o.seed,
        }
    }
}

/// The core's default session options.
#[uniffi::export]
pub fn default_session_options() -> SessionOptions {
    core::SessionOptions::default().into()
}

/// One access point heard in a Wi-Fi scan.
#[derive(Debug, Clone, uniffi::Record)]
pub struct WifiReading {
    pub bssid: String,
    /// dBm, in [-120, 0].
    pub rss_dbm: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, uniffi::Enum)]
pub enum SessionStatus {
    Active,
    Paused,
    Finished,
    Aborted,
}

impl From<core::SessionStatus> for SessionStatus {
    fn from(s: core::SessionStatus) -> Self {
        match s {
            core::SessionStatus::Active => SessionStatus::Active,
            core::SessionStatus::Paused => SessionStatus::Paused,
            core::SessionStatus::Finished => SessionStatus::Finished,
            core::SessionStatus::Aborted => SessionStatus::Aborted,
        }
    }
}

/// A position estimate, metres on a floor.
#[derive(Debug, Clone, Copy, uniffi::Record)]
pub struct Position {
    pub x: f64,
    pub y: f64,
    pub floor: i64,
}

impl From<core::Position> for Position {
    fn from(p: core::Position) -> Self {
        Position {
            x: p.x,
            y: p.y,
            floor: p.floor,
        }
    }
}

/// A fingerprint the session collected: a scan and the position it is labelled with.
#[derive(Debug, Clone, uniffi::Record)]
pub struct CollectedSample {
    pub seq: i64,
    pub t_ms: i64,
    pub position: Position,
    /// Distance walked since the last check-in (null for a robot), m.
    pub since_checkin_m: Option<f64>,
    /// Standard deviation of the position label, m.
    pub sigma_m: f64,
    /// Extra observation noise of the label, dB².
    pub extra_noise: f64,
    /// dBm per access point.
    pub rss: HashMap<String, f64>,
}

impl From<core::CollectedSample> for CollectedSample {
    fn from(c: core::CollectedSample) -> Self {
        CollectedSample {
            seq: c.seq,
            t_ms: c.t_ms,
            position: c.position.into(),
            since_checkin_m: c.since_checkin_m,
            sigma_m: c.sigma_m,
            extra_noise: c.extra_noise,
            rss: c.rss.into_iter().collect(),
        }
    }
}

/// The answer to an accepted event: it is on disk.
#[derive(Debug, Clone, uniffi::Record)]
pub struct EventAck {
    pub seq: i64,
    pub status: SessionStatus,
    /// The surveyor is off the planned walk after this event.
    pub off_route: bool,
    /// This event took the surveyor off-route.
    pub went_off_route: bool,
    /// Seq of the automatic replan this event caused, if any.
    pub replan_seq: Option<i64>,
    /// Why an automatic replan failed (the event itself is recorded).
    pub replan_error: Option<String>,
    /// The sample a scan produced.
    pub sample: Option<CollectedSample>,
    /// Position estimate after the event.
    pub position: Position,
}

impl From<core::Ack> for EventAck {
    fn from(a: core::Ack) -> Self {
        EventAck {
            seq: a.seq,
            status: a.status.into(),
            off_route: a.off_route,
            went_off_route: a.went_off_route,
            replan_seq: a.replan_seq,
            replan_error: a.replan_error,
            sample: a.sample.map(Into::into),
            position: a.position.into(),
        }
    }
}

/// What to do at the next waypoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, uniffi::Enum)]
pub enum Turn {
    Straight,
    Left,
    Right,
    TurnBack,
    ChangeFloor,
    Arrive,
}

impl From<core::Turn> for Turn {
    fn from(t: core::Turn) -> Self {
        match t {
            core::Turn::Straight => Turn::Straight,
            core::Turn::Left => Turn::Left,
            core::Turn::Right => Turn::Right,
            core::Turn::TurnBack => Turn::TurnBack,
            core::Turn::ChangeFloor => Turn::ChangeFloor,
            core::Turn::Arrive => Turn::Arrive,
        }
    }
}

/// A vertex of the walk still ahead.
#[derive(Debug, Clone, uniffi::Record)]
pub struct Waypoint {
    pub vertex: String,
    pub label: Option<String>,
    /// A check-in is expected there.
    pub check_in: bool,
    /// Distance along the walk, m.
    pub distance_m: f64,
}

impl From<core::Waypoint> for Waypoint {
    fn from(w: core::Waypoint) -> Self {
        Waypoint {
            vertex: w.vertex,
            label: w.label,
            check_in: w.check_in,
            distance_m: w.distance_m,
        }
    }
}

/// What the surveyor should do next.
#[derive(Debug, Clone, uniffi::Record)]
pub struct Guidance {
    pub status: SessionStatus,
    pub off_route: bool,
    /// Next vertex of the walk (null at the end or once the session is over).
    pub next_vertex: Option<String>,
    pub next_label: Option<String>,
    /// Distance to it along the walk, m.
    pub distance_m: f64,
    pub turn: Turn,
    pub check_in_at_next: bool,
    pub next_check_in: Option<String>,
    pub distance_to_check_in_m: f64,
    /// One sentence for the screen.
    pub message: String,
}

impl From<core::Guidance> for Guidance {
    fn from(g: core::Guidance) -> Self {
        Guidance {
            status: g.status.into(),
            off_route: g.off_route,
            next_vertex: g.next_vertex,
            next_label: g.next_label,
            distance_m: g.distance_m,
            turn: g.turn.into(),
            check_in_at_next: g.check_in_at_next,
            next_check_in: g.next_check_in,
            distance_to_check_in_m: g.distance_to_check_in_m,
            message: g.message,
        }
    }
}

/// Posterior uncertainty at a vertex (coverage map).
#[derive(Debug, Clone, uniffi::Record)]
pub struct VertexUncertainty {
    pub vertex: String,
    pub x: f64,
    pub y: f64,
    pub floor: i64,
    /// Posterior standard deviation of the fingerprint, dB.
    pub std_db: f64,
}

/// A snapshot of a session.
#[derive(Debug, Clone, uniffi::Record)]
pub struct SessionProgress {
    pub status: SessionStatus,
    pub off_route: bool,
    /// Walked / (walked + remaining), 0 to 1.
    pub fraction_done: f64,
    pub walked_m: f64,
    pub budget_m: f64,
    pub budget_left_m: f64,
    pub remaining_m: f64,
    pub elapsed_s: f64,
    pub remaining_s: f64,
    pub samples: u64,
    pub planned_utility_nats: f64,
    pub collected_utility_nats: f64,
    pub step_length_m: f64,
    pub replans: u32,
    pub off_route_events: u32,
    pub uncertainty: Vec<VertexUncertainty>,
}

impl From<core::Progress> for SessionProgress {
    fn from(p: core::Progress) -> Self {
        SessionProgress {
            status: p.status.into(),
            off_route: p.off_route,
            fraction_done: p.fraction_done,
            walked_m: p.walked_m,
            budget_m: p.budget_m,
            budget_left_m: p.budget_left_m,
            remaining_m: p.remaining_m,
            elapsed_s: p.elapsed_s,
            remaining_s: p.remaining_s,
            samples: p.samples,
            planned_utility_nats: p.planned_utility_nats,
            collected_utility_nats: p.collected_utility_nats,
            step_length_m: p.step_length_m,
            replans: p.replans,
            off_route_events: p.off_route_events,
            uncertainty: p
                .uncertainty
                .into_iter()
                .map(|u| VertexUncertainty {
                    vertex: u.vertex,
                    x: u.x,
                    y: u.y,
                    floor: u.floor,
                    std_db: u.std_db,
                })
                .collect(),
        }
    }
}

/// The end of a session.
#[derive(Debug, Clone, uniffi::Record)]
pub struct SessionSummary {
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
    pub step_length_m: f64,
    pub replans: u32,
    pub off_route_events: u32,
    pub mean_std_db: f64,
    pub max_std_db: f64,
}

impl From<core::Summary> for SessionSummary {
    fn from(s: core::Summary) -> Self {
        SessionSummary {
            session_id: s.session_id,
            status: s.status.into(),
            walked_m: s.walked_m,
            budget_m: s.budget_m,
            elapsed_s: s.elapsed_s,
            samples: s.samples,
            check_ins: s.check_ins,
            steps: s.steps,
            planned_utility_nats: s.planned_utility_nats,
            collected_utility_nats: s.collected_utility_nats,
            step_length_m: s.step_length_m,
            replans: s.replans,
            off_route_events: s.off_route_events,
            mean_std_db: s.mean_std_db,
            max_std_db: s.max_std_db,
        }
    }
}

/// The result of a replan.
#[derive(Debug, Clone, uniffi::Record)]
pub struct ReplanOutcome {
    pub seq: i64,
    /// Store id of the new plan.
    pub plan_id: i64,
    /// Where the new walk starts.
    pub from_vertex: String,
    pub walk: Vec<String>,
    pub length_m: f64,
    pub budget_left_m: f64,
    /// The budget left cannot reach the end: the walk is the shortest way there.
    pub over_budget: bool,
    /// Metres of the budget left kept back for wrong turns still to come.
    pub reserve_m: f64,
    pub utility_nats: f64,
}

impl From<core::ReplanOutcome> for ReplanOutcome {
    fn from(r: core::ReplanOutcome) -> Self {
        ReplanOutcome {
            seq: r.seq,
            plan_id: r.plan_id,
            from_vertex: r.from_vertex,
            walk: r.walk,
            length_m: r.length_m,
            budget_left_m: r.budget_left_m,
            over_budget: r.over_budget,
            reserve_m: r.reserve_m,
            utility_nats: r.utility_nats,
        }
    }
}

/// A stored session, as listed.
#[derive(Debug, Clone, uniffi::Record)]
pub struct SessionInfo {
    pub id: i64,
    pub building_id: i64,
    pub plan_id: Option<i64>,
    pub created_ms: i64,
    pub last_seq: i64,
    pub status: SessionStatus,
    pub collected: u64,
}

impl From<store::SessionInfo> for SessionInfo {
    fn from(s: store::SessionInfo) -> Self {
        SessionInfo {
            id: s.id,
            building_id: s.building_id,
            plan_id: s.plan_id,
            created_ms: s.created_ms,
            last_seq: s.last_seq,
            status: s.status.into(),
            collected: s.collected,
        }
    }
}

/// A survey session. Every method may be called from any thread; calls are serialised by
/// the mutex inside, so events are recorded in the order the calls take the lock.
#[derive(uniffi::Object)]
pub struct SurveySession {
    store: Arc<TrailprintStore>,
    inner: Mutex<Session>,
}

impl SurveySession {
    fn lock(&self) -> MutexGuard<'_, Session> {
        // A panic inside the core left the session as it was before the event (the
        // tracker applies an event only after it is written).
        self.inner.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn record(&self, event: Event) -> Result<EventAck> {
        Ok(self.lock().record(event)?.into())
    }
}

#[uniffi::export]
impl SurveySession {
    pub fn id(&self) -> i64 {
        self.lock().id()
    }

    pub fn plan_id(&self) -> i64 {
        self.lock().plan_id()
    }

    pub fn building_id(&self) -> i64 {
        self.lock().building_id()
    }

    pub fn status(&self) -> SessionStatus {
        self.lock().status().into()
    }

    /// The step counter counted `steps` more steps (usually 1) at `t_ms` (ms since epoch).
    pub fn step(&self, t_ms: i64, steps: u32) -> Result<EventAck> {
        self.record(Event::Step { t_ms, steps })
    }

    /// A completed Wi-Fi scan.
    pub fn scan(&self, t_ms: i64, readings: Vec<WifiReading>) -> Result<EventAck> {
        self.record(Event::Scan {
            t_ms,
            readings: readings
                .into_iter()
                .map(|r| core::Reading {
                    bssid: r.bssid,
                    rss_dbm: r.rss_dbm,
                })
                .collect(),
        })
    }

    /// The surveyor confirms being at vertex `vertex`.
    pub fn check_in(&self, t_ms: i64, vertex: String) -> Result<EventAck> {
        self.record(Event::CheckIn { t_ms, vertex })
    }

    /// A robot's own pose (SLAM), metres on `floor`.
    pub fn robot_pose(&self, t_ms: i64, x: f64, y: f64, floor: i64) -> Result<EventAck> {
        self.record(Event::Pose { t_ms, x, y, floor })
    }

    pub fn pause(&self, t_ms: i64) -> Result<EventAck> {
        self.record(Event::Pause { t_ms })
    }

    pub fn resume(&self, t_ms: i64) -> Result<EventAck> {
        self.record(Event::Resume { t_ms })
    }

    /// Abandons the walk.
    pub fn abort(&self, t_ms: i64, reason: Option<String>) -> Result<EventAck> {
        self.record(Event::Abort { t_ms, reason })
    }

    /// Records the end of the walk; returns the summary.
    pub fn finish(&self, t_ms: i64) -> Result<SessionSummary> {
        Ok(self.lock().finish(t_ms)?.into())
    }

    /// Distance, time, samples, utilities and the coverage map.
    pub fn progress(&self) -> Result<SessionProgress> {
        Ok(self.lock().progress()?.into())
    }

    /// What to do next.
    pub fn guidance(&self) -> Guidance {
        self.lock().guidance().into()
    }

    /// The vertices still ahead.
    pub fn route_ahead(&self) -> Vec<Waypoint> {
        self.lock()
            .route_ahead()
            .into_iter()
            .map(Into::into)
            .collect()
    }

    /// The fingerprints collected so far.
    pub fn samples(&self) -> Vec<CollectedSample> {
        self.lock()
            .samples()
            .iter()
            .cloned()
            .map(Into::into)
            .collect()
    }

    /// Plans the rest of the walk again from where the surveyor is, with the budget left,
    /// given everything collected so far.
    pub fn replan(&self) -> Result<ReplanOutcome> {
        Ok(self.lock().replan()?.into())
    }

    /// The summary so far (final once finished).
    pub fn summary(&self) -> Result<SessionSummary> {
        Ok(self.lock().summary()?.into())
    }

    /// The collected fingerprints as the `trailprint export --collected` JSON document.
    pub fn export_json(&self) -> Result<String> {
        let (bid, sid) = {
            let s = self.lock();
            (s.building_id(), s.id())
        };
        let info = self.store.inner.building_info(bid)?;
        let list = self.store.inner.list_collected(bid, Some(sid))?;
        Ok(store::collected_json(&info.name, &list))
    }

    /// The collected fingerprints as CSV (one column per access point).
    pub fn export_csv(&self) -> Result<String> {
        let (bid, sid) = {
            let s = self.lock();
            (s.building_id(), s.id())
        };
        let list = self.store.inner.list_collected(bid, Some(sid))?;
        Ok(store::collected_csv(&list))
    }
}

#[uniffi::export]
impl TrailprintStore {
    /// Starts a session on a saved plan (`options`: null for the defaults).
    pub fn start_session(
        self: Arc<Self>,
        plan_id: i64,
        surveyor: SurveyorProfile,
        options: Option<SessionOptions>,
    ) -> Result<Arc<SurveySession>> {
        let options = options.map_or_else(core::SessionOptions::default, Into::into);
        let log: Arc<dyn core::SessionLog> = self.inner.clone();
        let session = Session::start(log, plan_id, surveyor.into(), options)?;
        Ok(Arc::new(SurveySession {
            store: self,
            inner: Mutex::new(session),
        }))
    }

    /// Reopens a stored session where its log ends (after a kill, or in another process).
    pub fn resume_session(self: Arc<Self>, session_id: i64) -> Result<Arc<SurveySession>> {
        let log: Arc<dyn core::SessionLog> = self.inner.clone();
        let session = Session::resume(log, session_id)?;
        Ok(Arc::new(SurveySession {
            store: self,
            inner: Mutex::new(session),
        }))
    }

    /// The sessions of a building, oldest first.
    pub fn list_sessions(&self, building_id: i64) -> Result<Vec<SessionInfo>> {
        Ok(self
            .inner
            .list_sessions(building_id)?
            .into_iter()
            .map(Into::into)
            .collect())
    }
}
