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
    /// A human is off-route once the step count puts them this many metres past a
    /// check-in that was due (default 3)...
    pub off_route_slack_m: f64,
    /// ...plus this fraction of the leg to it (default 0.25).
    pub off_route_slack_fraction: f64,
    /// A robot pose farther than this from the walk is off-route, metres (default 1.5).
    pub robot_tolerance_m: f64,
    /// Replan automatically when the surveyor goes off-route at a known vertex (default
    /// true).
    pub auto_replan: bool,
    /// Weight of the profile's step length in its re-estimation at check-ins, counted as
    /// that many steps already measured (default 20).
    pub calibration_weight_steps: f64,
    /// Seed of the replanner: replan k of the session uses seed + k (default 1).
    pub seed: u64,
    /// Memory budget of the session, MiB (null: 512): what the phone allows. A replan may
    /// use all of it (as `PlanRequest.memoryBudgetMb`); the running figures half (see
    /// `SessionProgress.sampleBlock`).
    #[uniffi(default)]
    pub memory_budget_mb: Option<u64>,
}

impl From<SessionOptions> for core::SessionOptions {
    fn from(o: SessionOptions) -> Self {
        let defaults = core::SessionOptions::default();
        core::SessionOptions {
            off_route_slack_m: o.off_route_slack_m,
            off_route_slack_fraction: o.off_route_slack_fraction,
            robot_tolerance_m: o.robot_tolerance_m,
            auto_replan: o.auto_replan,
            calibration_weight_steps: o.calibration_weight_steps,
            seed: o.seed,
            memory_budget_mb: o.memory_budget_mb.unwrap_or(defaults.memory_budget_mb),
            ..defaults
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
            memory_budget_mb: Some(o.memory_budget_mb),
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
    /// The access point's BSSID (or any name that stays the same for it); not empty, and
    /// at most once per scan.
    pub bssid: String,
    /// dBm, in [-120, 0].
    pub rss_dbm: f64,
}

/// Where a session stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, uniffi::Enum)]
pub enum SessionStatus {
    /// Accepting every event.
    Active,
    /// After `pause`: only resume, finish or abort are accepted.
    Paused,
    /// After `finish`: no more events are accepted.
    Finished,
    /// After `abort`: no more events are accepted.
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
    /// Metres, in the building's own frame (the frame of its vertices).
    pub x: f64,
    /// Metres, in the building's own frame.
    pub y: f64,
    /// Floor id (a `FloorInfo.id` of the building).
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
    /// Seq of the scan event in the session's log.
    pub seq: i64,
    /// Device time of the scan, ms since the Unix epoch.
    pub t_ms: i64,
    /// The position the scan is labelled with: the session's estimate when it arrived.
    pub position: Position,
    /// Distance walked since the last check-in by the step count (steps times the
    /// current step length), m; null for a robot.
    pub since_checkin_m: Option<f64>,
    /// Standard deviation of the position label, m: the profile's step error times
    /// `sinceCheckinM` (0 for a robot).
    pub sigma_m: f64,
    /// Extra observation noise the label's uncertainty adds to this sample in the
    /// utilities and the coverage map, dB² (0 for a robot).
    pub extra_noise: f64,
    /// RSS per BSSID, dBm, as the scan reported them.
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
    /// Seq of this event in the session's log (1 for the first; a replan takes a seq too).
    pub seq: i64,
    /// The session's status after the event.
    pub status: SessionStatus,
    /// The surveyor is off the planned walk after this event.
    pub off_route: bool,
    /// This event took the surveyor off-route.
    pub went_off_route: bool,
    /// Seq of the automatic replan this event caused, if any.
    pub replan_seq: Option<i64>,
    /// Why an automatic replan failed (the event itself is recorded).
    pub replan_error: Option<String>,
    /// The sample a scan produced (null for every other event).
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
    /// Keep going: the walk bends by at most 30 degrees there.
    Straight,
    /// Turn left (by more than 30 and less than 150 degrees).
    Left,
    /// Turn right (by more than 30 and less than 150 degrees).
    Right,
    /// Turn round: 150 degrees or more.
    TurnBack,
    /// Take the stairs or the lift to another floor.
    ChangeFloor,
    /// The waypoint is the end of the walk.
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
    /// Vertex id.
    pub vertex: String,
    /// The vertex's label in the building file, if it has one.
    pub label: Option<String>,
    /// A check-in is expected there (always false for a robot).
    pub check_in: bool,
    /// Distance from the current position along the walk, m.
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
    /// The session's status; only an active, on-route session gets a next vertex.
    pub status: SessionStatus,
    /// The surveyor is off the planned walk (the message says how to get back).
    pub off_route: bool,
    /// Next vertex of the walk (null at the end, off-route, paused, or once the session
    /// is over).
    pub next_vertex: Option<String>,
    /// Label of the next vertex in the building file, if it has one.
    pub next_label: Option<String>,
    /// Distance to it along the walk, m (0 when there is no next vertex).
    pub distance_m: f64,
    /// What to do at the next vertex (`ARRIVE` there at the end, and when there is no
    /// next vertex).
    pub turn: Turn,
    /// Check in at the next vertex (always false for a robot).
    pub check_in_at_next: bool,
    /// The first vertex from the next one on where a check-in is due (null for a robot
    /// and when there is no next vertex).
    pub next_check_in: Option<String>,
    /// Distance to `nextCheckIn` along the walk, m (0 when it is null).
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
    /// Vertex id.
    pub vertex: String,
    /// The vertex's position, metres, in the building's own frame.
    pub x: f64,
    /// Metres, in the building's own frame.
    pub y: f64,
    /// Floor id of the vertex.
    pub floor: i64,
    /// Posterior standard deviation of the fingerprint, dB.
    pub std_db: f64,
}

/// A snapshot of a session.
#[derive(Debug, Clone, uniffi::Record)]
pub struct SessionProgress {
    /// The session's status.
    pub status: SessionStatus,
    /// The surveyor is off the planned walk.
    pub off_route: bool,
    /// Walked / (walked + remaining), 0 to 1 (1 when both are 0).
    pub fraction_done: f64,
    /// Metres walked: for a human, the planned length of each leg ended by an on-route
    /// check-in, and the step count for the rest; for a robot, the straight distances
    /// between its successive poses.
    pub walked_m: f64,
    /// The distance budget of the plan the session started with, m (replans keep it).
    pub budget_m: f64,
    /// `budgetM - walkedM`, m; negative once the surveyor has walked more than the budget.
    pub budget_left_m: f64,
    /// Metres of planned walk still ahead; off-route at a vertex, the shortest way from
    /// there to the end.
    pub remaining_m: f64,
    /// Active time from the first event to the last, pauses left out, s.
    pub elapsed_s: f64,
    /// Estimated time to walk `remainingM`, s: at the speed observed so far once more
    /// than 10 s and 5 m are behind, else at the surveyor profile's speed.
    pub remaining_s: f64,
    /// Scans recorded so far (fingerprints collected).
    pub samples: u64,
    /// Scans the utility and the coverage map account for: all of them, except, while
    /// `sampleBlock` is above 1, the last few of a run not yet complete.
    pub samples_in_figures: u64,
    /// 1 while the figures condition on every scan (exact). Above 1 once the session's
    /// memory budget (`SessionOptions.memoryBudgetMb`, half of it for these figures) was
    /// reached: they then keep one scan of every `sampleBlock` (the one nearest a
    /// vertex), so `collectedUtilityNats` is a lower bound ("at least") and the coverage
    /// map's uncertainty an upper bound. Every scan is still stored.
    pub sample_block: u64,
    /// Utility of the walk the session started with, valued for this session's surveyor
    /// profile, nats.
    pub planned_utility_nats: f64,
    /// Utility of the scans actually recorded, at their labelled positions and with
    /// their label noise, nats: compare with `plannedUtilityNats`.
    pub collected_utility_nats: f64,
    /// The current step-length estimate, m (re-estimated at on-route check-ins; 0 for a
    /// robot).
    pub step_length_m: f64,
    /// Replans applied so far, automatic or asked for with `replan()`.
    pub replans: u32,
    /// How many times the surveyor went off the walk.
    pub off_route_events: u32,
    /// The coverage map: one entry per vertex of the building, in the building's order.
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
            samples_in_figures: p.samples_in_figures,
            sample_block: p.sample_block,
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
    /// Store id of the session.
    pub session_id: i64,
    /// The session's status (`FINISHED` once `finish` was recorded).
    pub status: SessionStatus,
    /// Metres walked, as in `SessionProgress.walkedM`.
    pub walked_m: f64,
    /// The plan's distance budget, m.
    pub budget_m: f64,
    /// Active time, pauses left out, s.
    pub elapsed_s: f64,
    /// Scans recorded (fingerprints collected).
    pub samples: u64,
    /// Check-in events recorded.
    pub check_ins: u32,
    /// Steps counted by all the step events (0 for a robot).
    pub steps: u64,
    /// As in `SessionProgress.plannedUtilityNats`, nats.
    pub planned_utility_nats: f64,
    /// As in `SessionProgress.collectedUtilityNats`, nats (a lower bound when
    /// `sampleBlock` is above 1).
    pub collected_utility_nats: f64,
    /// As in `SessionProgress.sampleBlock`: 1 when the figures count every scan.
    pub sample_block: u64,
    /// The final step-length estimate, m (0 for a robot).
    pub step_length_m: f64,
    /// Replans applied, automatic or asked for.
    pub replans: u32,
    /// How many times the surveyor went off the walk.
    pub off_route_events: u32,
    /// Posterior standard deviation of the fingerprint averaged over the building's
    /// vertices, dB: lower is a better-surveyed building.
    pub mean_std_db: f64,
    /// The largest posterior standard deviation at any vertex, dB: the worst-covered spot.
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
            sample_block: s.sample_block,
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
    /// Seq of the replan event in the session's log.
    pub seq: i64,
    /// Store id of the new plan.
    pub plan_id: i64,
    /// Where the new walk starts: the vertex the surveyor is at or walking to.
    pub from_vertex: String,
    /// The new walk, vertex ids from `fromVertex` to the end.
    pub walk: Vec<String>,
    /// Length of the new walk, m.
    pub length_m: f64,
    /// Budget that was left for it: the plan's budget less the metres walked and the way
    /// to `fromVertex`, m.
    pub budget_left_m: f64,
    /// The budget left cannot reach the end: the walk is the shortest way there.
    pub over_budget: bool,
    /// Metres of the budget left kept back for wrong turns still to come.
    pub reserve_m: f64,
    /// Utility of the new walk given the pilot data and everything collected so far, nats.
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
    /// Store id of the session (what `resumeSession` takes).
    pub id: i64,
    /// Store id of its building.
    pub building_id: i64,
    /// The plan it started from; null for a session stored without one (a bundle may
    /// bring such sessions in).
    pub plan_id: Option<i64>,
    /// When it was started, ms since the Unix epoch (for a session imported from a
    /// bundle, when it was started on the other device).
    pub created_ms: i64,
    /// Seq of its last logged event, 0 if it has none.
    pub last_seq: i64,
    /// Read off its last pause, resume, finish or abort event (`ACTIVE` if none).
    pub status: SessionStatus,
    /// Fingerprints collected in it.
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
