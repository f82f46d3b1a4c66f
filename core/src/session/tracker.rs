//! The pure session state machine: a plan plus events in, positions, samples and flags out.
//! No I/O; [`Tracker::check`] decides whether an event is acceptable without changing
//! anything, [`Tracker::apply`] then applies it and cannot fail. The session state is
//! therefore a pure function of the plan and the event log, and replay is a loop over
//! `apply`.
//!
//! # Human position tracking
//! Dead reckoning along the planned walk from the last check-in: `u = steps x L` metres
//! past it, held at the next check-in that is due (the surveyor waits there to confirm).
//! The step length `L` is re-estimated at every on-route check-in from the planned length
//! of the leg and the steps it took (less half a step: the surveyor stops at the vertex). Walking more than the slack past the due check-in, or
//! checking in at a vertex that is not on the walk between the last check-in and the due
//! one, puts the surveyor off-route.
//!
//! # Robot position tracking
//! Poses are the robot's own; each is projected onto the walk (the first nearby segment
//! ahead, never going back by more than the tolerance); a pose farther than the tolerance
//! from the walk puts the robot off-route, at the nearest vertex.

use std::collections::BTreeMap;

use serde::Serialize;

use super::log::LogEvent;
use super::replan::distances_from;
use super::types::{
    CollectedSample, Event, Guidance, MAX_READINGS, MAX_RSS_DBM, MAX_STEPS_PER_EVENT, MIN_RSS_DBM,
    Position, SessionOptions, SessionStatus, Surveyor, Turn, Waypoint,
};
use crate::building::Building;
use crate::gp::{Kernel, Point};
use crate::samples::{is_turn_checkin, turn_angle_deg};
use crate::utility::Observation;
use crate::{Error, Result};

/// Arc-length tolerance for "at the same place".
const ARC_TOL: f64 = 1e-6;
/// How far ahead of the last projection a robot pose is searched for: this many scan
/// intervals, and at least 2 m (a pose is expected every interval).
const ROBOT_LOOKAHEAD_INTERVALS: f64 = 4.0;

/// Where an off-route surveyor is.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum OffRoute {
    /// At (or, for a robot, nearest to) this vertex.
    At(usize),
    /// Somewhere past the check-in that was due: position unknown until the next check-in.
    Lost,
}

/// What applying an event did.
#[derive(Debug, Clone, PartialEq)]
pub struct Applied {
    pub went_off_route: bool,
    pub sample: Option<CollectedSample>,
}

/// The state of a session (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tracker {
    session_id: i64,
    surveyor: Surveyor,
    options: SessionOptions,
    kernel: Kernel,
    budget_m: f64,
    end: usize,
    /// The walk being followed: vertex indices, cumulative arc lengths, check-in flags.
    route: Vec<usize>,
    arc: Vec<f64>,
    required: Vec<bool>,
    /// Human: route index of the last on-route check-in. Robot: route segment of the last
    /// projected pose.
    anchor: usize,
    off: Option<OffRoute>,
    steps_since: u64,
    steps_total: u64,
    step_len: f64,
    calib_m: f64,
    calib_steps: f64,
    /// Human: metres walked up to the last check-in.
    confirmed_m: f64,
    pose: Option<Point>,
    robot_arc: f64,
    robot_walked_m: f64,
    status: SessionStatus,
    off_route_events: u32,
    replans: u32,
    replan_due: bool,
    t_first: Option<i64>,
    t_last: Option<i64>,
    paused_ms: i64,
    paused_since: Option<i64>,
    samples: Vec<CollectedSample>,
    check_ins: u32,
    last_seq: i64,
}

fn point_pos(p: &Point) -> Position {
    Position {
        x: p.x,
        y: p.y,
        floor: p.floor,
    }
}

fn arcs(b: &Building, route: &[usize]) -> Vec<f64> {
    let mut out = Vec::with_capacity(route.len());
    let mut acc = 0.0;
    out.push(0.0);
    for w in route.windows(2) {
        acc += b.edge_between(w[0], w[1]).map_or(0.0, |e| e.length);
        out.push(acc);
    }
    out
}

fn checkins(b: &Building, route: &[usize], surveyor: &Surveyor) -> Vec<bool> {
    let n = route.len();
    let mut out = vec![false; n];
    out[0] = true;
    out[n - 1] = true;
    if let Surveyor::Human {
        turn_threshold_deg, ..
    } = *surveyor
    {
        for i in 1..n.saturating_sub(1) {
            out[i] = is_turn_checkin(b, route[i - 1], route[i], route[i + 1], turn_threshold_deg);
        }
    }
    out
}

/// The sentence a surveyor reads for the next waypoint: "In 12 m at c33 (corridor): turn
/// left; check in there." Shared by the live guidance of a session and the printed
/// turn-by-turn sheet of `trailprint plan --instructions`, so both say the same thing.
pub fn guidance_sentence(
    distance_m: f64,
    vertex: &str,
    label: Option<&str>,
    turn: Turn,
    check_in: bool,
) -> String {
    let name = match label {
        Some(l) => format!("{vertex} ({l})"),
        None => vertex.to_string(),
    };
    let what = match turn {
        Turn::Straight => "go straight on",
        Turn::Left => "turn left",
        Turn::Right => "turn right",
        Turn::TurnBack => "turn back",
        Turn::ChangeFloor => "change floor",
        Turn::Arrive => "that is the end of the walk",
    };
    format!(
        "In {distance_m:.0} m at {name}: {what}{}.",
        if check_in { "; check in there" } else { "" }
    )
}

/// The turn at `b` coming from `a`, going on to `c`.
pub fn classify_turn(a: &Point, b: &Point, c: &Point) -> Turn {
    if a.floor != b.floor || b.floor != c.floor {
        return Turn::ChangeFloor;
    }
    let angle = turn_angle_deg(a, b, c);
    if angle <= 30.0 {
        Turn::Straight
    } else if angle >= 150.0 {
        Turn::TurnBack
    } else {
        let cross = (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
        if cross > 0.0 { Turn::Left } else { Turn::Right }
    }
}

impl Tracker {
    /// A session at the start of `walk` (vertex indices, validated by the caller).
    pub fn new(
        session_id: i64,
        b: &Building,
        surveyor: Surveyor,
        options: SessionOptions,
        kernel: Kernel,
        budget_m: f64,
        walk: Vec<usize>,
    ) -> Result<Self> {
        let (Some(&start), Some(&end)) = (walk.first(), walk.last()) else {
            return Err(Error::Session {
                session: session_id,
                message: "the plan's walk is empty".into(),
            });
        };
        b.check_walk(&walk)?;
        let step_len = match surveyor {
            Surveyor::Human { step_length_m, .. } => step_length_m,
            Surveyor::Robot { .. } => 0.0,
        };
        let pose = (!surveyor.is_human()).then(|| b.vertices[start].pos);
        Ok(Tracker {
            session_id,
            surveyor,
            options,
            kernel,
            budget_m,
            end,
            arc: arcs(b, &walk),
            required: checkins(b, &walk, &surveyor),
            route: walk,
            anchor: 0,
            off: None,
            steps_since: 0,
            steps_total: 0,
            step_len,
            calib_m: 0.0,
            calib_steps: 0.0,
            confirmed_m: 0.0,
            pose,
            robot_arc: 0.0,
            robot_walked_m: 0.0,
            status: SessionStatus::Active,
            off_route_events: 0,
            replans: 0,
            replan_due: false,
            t_first: None,
            t_last: None,
            paused_ms: 0,
            paused_since: None,
            samples: Vec::new(),
            check_ins: 0,
            last_seq: 0,
        })
    }

    fn err(&self, message: impl Into<String>) -> Error {
        Error::Session {
            session: self.session_id,
            message: message.into(),
        }
    }

    // ---- read-only views ----

    pub fn status(&self) -> SessionStatus {
        self.status
    }
    pub fn surveyor(&self) -> &Surveyor {
        &self.surveyor
    }
    pub fn options(&self) -> &SessionOptions {
        &self.options
    }
    pub fn budget_m(&self) -> f64 {
        self.budget_m
    }
    pub fn end(&self) -> usize {
        self.end
    }
    pub fn route(&self) -> &[usize] {
        &self.route
    }
    pub fn off_route(&self) -> bool {
        self.off.is_some()
    }
    pub fn off(&self) -> Option<OffRoute> {
        self.off
    }
    pub fn replan_due(&self) -> bool {
        self.replan_due
    }
    pub fn replans(&self) -> u32 {
        self.replans
    }
    pub fn off_route_events(&self) -> u32 {
        self.off_route_events
    }
    pub fn samples(&self) -> &[CollectedSample] {
        &self.samples
    }
    pub fn check_ins(&self) -> u32 {
        self.check_ins
    }
    pub fn steps_total(&self) -> u64 {
        self.steps_total
    }
    pub fn step_length_m(&self) -> f64 {
        self.step_len
    }
    pub fn last_seq(&self) -> i64 {
        self.last_seq
    }
    pub fn last_t_ms(&self) -> Option<i64> {
        self.t_last
    }

    /// The collected samples as utility observations (position label and its noise).
    pub fn observations(&self) -> Vec<Observation> {
        self.samples
            .iter()
            .map(|s| Observation {
                pos: Point::new(s.position.x, s.position.y, s.position.floor),
                extra_noise: s.extra_noise,
            })
            .collect()
    }

    /// Dead-reckoned distance since the last check-in, metres.
    fn dr(&self) -> f64 {
        self.steps_since as f64 * self.step_len
    }

    /// Route index of the next check-in due after route index `from` (the end if none).
    fn next_required(&self, from: usize) -> usize {
        (from + 1..self.route.len())
            .find(|&k| self.required[k])
            .unwrap_or(self.route.len() - 1)
    }

    /// Arc length of the current position estimate along the route.
    fn pos_arc(&self) -> f64 {
        if self.surveyor.is_human() {
            let nr = self.next_required(self.anchor);
            (self.arc[self.anchor] + self.dr()).min(self.arc[nr])
        } else {
            self.robot_arc
        }
    }

    /// The point at arc length `a` of the route.
    fn point_at(&self, b: &Building, a: f64) -> Point {
        let n = self.route.len();
        let idx = self.arc.partition_point(|&x| x < a);
        if idx == 0 {
            return b.vertices[self.route[0]].pos;
        }
        if idx >= n {
            return b.vertices[self.route[n - 1]].pos;
        }
        if self.arc[idx] == a {
            return b.vertices[self.route[idx]].pos;
        }
        let (pa, pb) = (
            b.vertices[self.route[idx - 1]].pos,
            b.vertices[self.route[idx]].pos,
        );
        let start = self.arc[idx - 1];
        let len = self.arc[idx] - start;
        let frac = ((a - start) / len).clamp(0.0, 1.0);
        let floor = if pa.floor == pb.floor || frac < 0.5 {
            pa.floor
        } else if frac > 0.5 {
            pb.floor
        } else {
            pa.floor.min(pb.floor)
        };
        Point::new(
            pa.x + frac * (pb.x - pa.x),
            pa.y + frac * (pb.y - pa.y),
            floor,
        )
    }

    /// The current position estimate.
    pub fn position(&self, b: &Building) -> Point {
        match (self.surveyor.is_human(), self.off) {
            (false, _) => self.pose.unwrap_or(b.vertices[self.route[0]].pos),
            (true, Some(OffRoute::At(v))) => b.vertices[v].pos,
            (true, _) => self.point_at(b, self.pos_arc()),
        }
    }

    /// Metres walked so far.
    pub fn walked_m(&self) -> f64 {
        if self.surveyor.is_human() {
            self.confirmed_m + self.dr()
        } else {
            self.robot_walked_m
        }
    }

    /// Metres of walk still ahead (shortest way to the end when off-route at a vertex).
    pub fn remaining_m(&self, b: &Building) -> f64 {
        let last = self.arc[self.arc.len() - 1];
        match self.off {
            Some(OffRoute::At(v)) => {
                let d = distances_from(b, self.end)[v];
                let extra = self
                    .pose
                    .filter(|_| !self.surveyor.is_human())
                    .map_or(0.0, |p| p.planar_distance(&b.vertices[v].pos));
                d + extra
            }
            _ => (last - self.pos_arc()).max(0.0),
        }
    }

    /// Active time in milliseconds (pauses excluded).
    pub fn elapsed_ms(&self) -> i64 {
        let (Some(first), Some(last)) = (self.t_first, self.t_last) else {
            return 0;
        };
        let paused_now = self.paused_since.map_or(0, |p| last - p);
        (last - first - self.paused_ms - paused_now).max(0)
    }

    /// The label of a scan taken now: position, `u`, `s` and the extra noise.
    fn label(&self, b: &Building) -> (Point, Option<f64>, f64, f64) {
        let pos = self.position(b);
        match self.surveyor {
            Surveyor::Human { step_error, .. } => {
                let u = self.dr();
                let s = step_error * u;
                (pos, Some(u), s, self.kernel.label_noise(s))
            }
            Surveyor::Robot { .. } => (pos, None, 0.0, 0.0),
        }
    }

    // ---- events ----

    /// Whether `ev` can be accepted now; changes nothing. The error names what is wrong.
    pub fn check(&self, b: &Building, ev: &Event) -> Result<()> {
        match self.status {
            SessionStatus::Finished | SessionStatus::Aborted => {
                return Err(self.err(format!(
                    "the session is {}: no more events are accepted (got {})",
                    if self.status == SessionStatus::Finished {
                        "finished"
                    } else {
                        "aborted"
                    },
                    ev.kind()
                )));
            }
            SessionStatus::Paused
                if matches!(
                    ev,
                    Event::Step { .. }
                        | Event::Scan { .. }
                        | Event::CheckIn { .. }
                        | Event::Pose { .. }
                ) =>
            {
                return Err(self.err(format!(
                    "the session is paused: record a resume event before this {} event",
                    ev.kind()
                )));
            }
            _ => {}
        }
        let t = ev.t_ms();
        if let Some(last) = self.t_last
            && t < last
        {
            return Err(self.err(format!(
                "{} event at t_ms {t} goes back in time: the previous event was at t_ms {last}",
                ev.kind()
            )));
        }
        match ev {
            Event::Step { steps, .. } => {
                if !self.surveyor.is_human() {
                    return Err(self.err(
                        "step events are for human surveyors; a robot reports poses".to_string(),
                    ));
                }
                if *steps == 0 || *steps > MAX_STEPS_PER_EVENT {
                    return Err(self.err(format!(
                        "a step event counts 1 to {MAX_STEPS_PER_EVENT} steps, got {steps}"
                    )));
                }
            }
            Event::Scan { readings, .. } => {
                if readings.len() > MAX_READINGS {
                    return Err(self.err(format!(
                        "a scan holds at most {MAX_READINGS} readings, got {}",
                        readings.len()
                    )));
                }
                let mut seen = std::collections::HashSet::new();
                for (i, r) in readings.iter().enumerate() {
                    if r.bssid.trim().is_empty() {
                        return Err(self.err(format!("scan reading {i}: empty BSSID")));
                    }
                    if !r.rss_dbm.is_finite() || !(MIN_RSS_DBM..=MAX_RSS_DBM).contains(&r.rss_dbm) {
                        return Err(self.err(format!(
                            "scan reading {i} ({}): RSS must be a finite dBm value in \
                             [{MIN_RSS_DBM}, {MAX_RSS_DBM}], got {}",
                            r.bssid, r.rss_dbm
                        )));
                    }
                    if !seen.insert(r.bssid.as_str()) {
                        return Err(self.err(format!(
                            "scan reading {i}: BSSID {} appears twice in one scan",
                            r.bssid
                        )));
                    }
                }
            }
            Event::CheckIn { vertex, .. } => {
                if b.vertex_index(vertex).is_none() {
                    return Err(self.err(format!(
                        "check-in at unknown vertex {vertex:?}: building {:?} has no such vertex",
                        b.name
                    )));
                }
            }
            Event::Pose { x, y, floor, .. } => {
                if self.surveyor.is_human() {
                    return Err(self.err(
                        "pose events are for robots; a human surveyor reports steps and check-ins"
                            .to_string(),
                    ));
                }
                for (name, v) in [("x", *x), ("y", *y)] {
                    if !v.is_finite() || v.abs() > 1e7 {
                        return Err(self.err(format!(
                            "pose: {name} must be a finite number of metres, got {v}"
                        )));
                    }
                }
                if !b.floors.iter().any(|f| f.id == *floor) {
                    return Err(self.err(format!(
                        "pose on floor {floor}, which is not a floor of building {:?}",
                        b.name
                    )));
                }
            }
            Event::Pause { .. } => {
                if self.status != SessionStatus::Active {
                    return Err(self.err("pause: the session is already paused".to_string()));
                }
            }
            Event::Resume { .. } => {
                if self.status != SessionStatus::Paused {
                    return Err(self.err("resume: the session is not paused".to_string()));
                }
            }
            Event::Finish { .. } | Event::Abort { .. } => {}
        }
        Ok(())
    }

    /// The event as it goes to the log (a scan with the label it gets now).
    pub fn log_event(&self, b: &Building, ev: &Event) -> LogEvent {
        match ev {
            Event::Step { steps, .. } => LogEvent::Step {
                steps: *steps,
                distance_m: *steps as f64 * self.step_len,
            },
            Event::Scan { readings, .. } => {
                let (p, u, s, _) = self.label(b);
                LogEvent::Scan {
                    x: p.x,
                    y: p.y,
                    floor: p.floor,
                    sigma_m: s,
                    since_checkin_m: u,
                    rss: readings
                        .iter()
                        .map(|r| (r.bssid.clone(), r.rss_dbm))
                        .collect(),
                }
            }
            Event::CheckIn { vertex, .. } => LogEvent::CheckIn {
                vertex: vertex.clone(),
            },
            Event::Pose { x, y, floor, .. } => LogEvent::Pose {
                x: *x,
                y: *y,
                floor: *floor,
            },
            Event::Pause { .. } => LogEvent::Pause,
            Event::Resume { .. } => LogEvent::Resume,
            Event::Finish { .. } => LogEvent::Finish,
            Event::Abort { reason, .. } => LogEvent::Abort {
                reason: reason.clone(),
            },
        }
    }

    /// Applies an event that [`check`](Self::check) accepted.
    pub fn apply(&mut self, b: &Building, ev: &Event, seq: i64) -> Applied {
        let t = ev.t_ms();
        self.t_first.get_or_insert(t);
        self.t_last = Some(t);
        self.last_seq = seq;
        let mut out = Applied {
            went_off_route: false,
            sample: None,
        };
        match ev {
            Event::Step { steps, .. } => {
                self.steps_since += u64::from(*steps);
                self.steps_total += u64::from(*steps);
                if self.off.is_none() {
                    let nr = self.next_required(self.anchor);
                    let leg = self.arc[nr] - self.arc[self.anchor];
                    let slack = self.options.off_route_slack_m
                        + self.options.off_route_slack_fraction * leg;
                    if self.arc[self.anchor] + self.dr() > self.arc[nr] + slack {
                        self.off = Some(OffRoute::Lost);
                        self.off_route_events += 1;
                        out.went_off_route = true;
                        // Replanning needs a known vertex: it waits for the next check-in.
                        self.replan_due = false;
                    }
                }
            }
            Event::Scan { readings, .. } => {
                let (p, u, s, extra) = self.label(b);
                let rss: BTreeMap<String, f64> = readings
                    .iter()
                    .map(|r| (r.bssid.clone(), r.rss_dbm))
                    .collect();
                let sample = CollectedSample {
                    seq,
                    t_ms: t,
                    position: point_pos(&p),
                    since_checkin_m: u,
                    sigma_m: s,
                    extra_noise: extra,
                    rss,
                };
                self.samples.push(sample.clone());
                out.sample = Some(sample);
            }
            Event::CheckIn { vertex, .. } => {
                // `check` made sure the vertex exists.
                let v = b.vertex_index(vertex).unwrap_or(0);
                self.check_ins += 1;
                out.went_off_route = if self.surveyor.is_human() {
                    self.human_check_in(v)
                } else {
                    self.robot_check_in(b, v)
                };
            }
            Event::Pose { x, y, floor, .. } => {
                let p = Point::new(*x, *y, *floor);
                out.went_off_route = self.robot_pose(b, p);
            }
            Event::Pause { .. } => {
                self.status = SessionStatus::Paused;
                self.paused_since = Some(t);
            }
            Event::Resume { .. } => {
                if let Some(p) = self.paused_since.take() {
                    self.paused_ms += t - p;
                }
                self.status = SessionStatus::Active;
            }
            Event::Finish { .. } | Event::Abort { .. } => {
                if let Some(p) = self.paused_since.take() {
                    self.paused_ms += t - p;
                }
                self.replan_due = false;
                self.status = if matches!(ev, Event::Finish { .. }) {
                    SessionStatus::Finished
                } else {
                    SessionStatus::Aborted
                };
            }
        }
        out
    }

    fn go_off(&mut self, at: OffRoute) -> bool {
        let was_on = self.off.is_none();
        self.off = Some(at);
        if was_on {
            self.off_route_events += 1;
        }
        self.replan_due = self.options.auto_replan && matches!(at, OffRoute::At(_));
        was_on
    }

    /// A human check-in at vertex `v`; returns whether it took the surveyor off-route.
    fn human_check_in(&mut self, v: usize) -> bool {
        let walked = self.dr();
        let found = if self.off.is_none() {
            let nr = self.next_required(self.anchor);
            (self.anchor + 1..=nr).find(|&k| self.route[k] == v)
        } else {
            // Back on the walk anywhere ahead of the last on-route check-in.
            (self.anchor..self.route.len()).find(|&k| self.route[k] == v)
        };
        match found {
            Some(k) => {
                let leg = self.arc[k] - self.arc[self.anchor];
                if self.off.is_none() {
                    if self.steps_since > 0 && leg > 0.0 {
                        // The last step of a leg ends at the vertex, half a step short on
                        // average: a leg of n counted steps is n - 1/2 strides long.
                        self.calib_m += leg;
                        self.calib_steps += self.steps_since as f64 - 0.5;
                        if let Surveyor::Human { step_length_m, .. } = self.surveyor {
                            let w = self.options.calibration_weight_steps;
                            self.step_len =
                                (w * step_length_m + self.calib_m) / (w + self.calib_steps);
                        }
                    }
                    self.confirmed_m += leg;
                } else {
                    self.confirmed_m += walked;
                }
                self.anchor = k;
                self.steps_since = 0;
                self.off = None;
                self.replan_due = false;
                false
            }
            None if self.off.is_none() && self.route[self.anchor] == v => {
                // Checked in again where the last check-in was.
                self.confirmed_m += walked;
                self.steps_since = 0;
                false
            }
            None => {
                self.confirmed_m += walked;
                self.steps_since = 0;
                self.go_off(OffRoute::At(v))
            }
        }
    }

    fn move_pose(&mut self, p: Point) {
        if let Some(prev) = self.pose {
            self.robot_walked_m += prev.planar_distance(&p);
        }
        self.pose = Some(p);
    }

    /// A robot check-in at vertex `v`.
    fn robot_check_in(&mut self, b: &Building, v: usize) -> bool {
        self.move_pose(b.vertices[v].pos);
        let from = self.anchor;
        let found = if self.off.is_none() {
            // On-route: the vertex must be where the robot is along the walk, give or take
            // the tolerance and one scan interval (the last pose may lag behind).
            let reach = self.tol() + self.surveyor.model().spacing();
            (from..self.route.len()).find(|&k| {
                self.route[k] == v
                    && self.arc[k] >= self.robot_arc - self.tol()
                    && self.arc[k] <= self.robot_arc + reach
            })
        } else {
            (from..self.route.len()).find(|&k| self.route[k] == v)
        };
        match found {
            Some(k) => {
                self.anchor = k.min(self.route.len().saturating_sub(2));
                self.robot_arc = self.arc[k];
                self.off = None;
                self.replan_due = false;
                false
            }
            None => self.go_off(OffRoute::At(v)),
        }
    }

    fn tol(&self) -> f64 {
        self.options.robot_tolerance_m
    }

    /// Projects a pose onto the route ahead: `(segment, arc)`.
    fn project(&self, b: &Building, p: &Point) -> Option<(usize, f64)> {
        let n = self.route.len();
        let tol = self.tol();
        if n == 1 {
            let v = b.vertices[self.route[0]].pos;
            return (v.floor == p.floor && v.planar_distance(p) <= tol).then_some((0, 0.0));
        }
        // Ahead (or level): the nearest segment, the earliest on a tie (a U-turn retraces
        // the same line). Behind by less than the tolerance: the latest (pose noise).
        let mut forward: Option<(usize, f64, f64)> = None;
        let mut backward: Option<(usize, f64)> = None;
        let lookahead = (ROBOT_LOOKAHEAD_INTERVALS * self.surveyor.model().spacing()).max(2.0);
        for k in self.anchor..n - 1 {
            if self.arc[k] > self.robot_arc + lookahead + tol {
                break;
            }
            let (pa, pb) = (
                b.vertices[self.route[k]].pos,
                b.vertices[self.route[k + 1]].pos,
            );
            let (t, d) = if pa.floor == pb.floor {
                if p.floor != pa.floor {
                    continue;
                }
                let (dx, dy) = (pb.x - pa.x, pb.y - pa.y);
                let l2 = dx * dx + dy * dy;
                let t = if l2 > 0.0 {
                    (((p.x - pa.x) * dx + (p.y - pa.y) * dy) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (t, (p.x - (pa.x + t * dx)).hypot(p.y - (pa.y + t * dy)))
            } else if p.floor == pa.floor {
                (0.0, p.planar_distance(&pa))
            } else if p.floor == pb.floor {
                (1.0, p.planar_distance(&pb))
            } else {
                continue;
            };
            if d > tol {
                continue;
            }
            let a = self.arc[k] + t * (self.arc[k + 1] - self.arc[k]);
            if a >= self.robot_arc - ARC_TOL {
                if forward.is_none_or(|(_, fa, fd)| d < fd - 1e-9 || (d <= fd + 1e-9 && a < fa)) {
                    forward = Some((k, a, d));
                }
            } else if a >= self.robot_arc - tol && backward.is_none_or(|(_, ba)| a > ba) {
                backward = Some((k, a));
            }
        }
        forward.map(|(k, a, _)| (k, a)).or(backward)
    }

    fn nearest_vertex(b: &Building, p: &Point) -> usize {
        let mut best = (f64::INFINITY, 0);
        for (i, v) in b.vertices.iter().enumerate() {
            let d = v.pos.planar_distance(p) + if v.pos.floor == p.floor { 0.0 } else { 1e6 };
            if d < best.0 {
                best = (d, i);
            }
        }
        best.1
    }

    /// A robot pose; returns whether it took the robot off-route. The distance walked
    /// between two on-route poses is the longer of the distance along the walk (corners
    /// and turns are not cut) and the straight line (a detour within the tolerance
    /// counts); otherwise the straight line.
    fn robot_pose(&mut self, b: &Building, p: Point) -> bool {
        let projected = self.project(b, &p);
        match (self.off, self.pose, projected) {
            (None, Some(prev), Some((_, a))) => {
                self.robot_walked_m += (a - self.robot_arc).abs().max(prev.planar_distance(&p));
                self.pose = Some(p);
            }
            _ => self.move_pose(p),
        }
        match projected {
            Some((k, a)) => {
                self.anchor = k;
                self.robot_arc = a;
                self.off = None;
                self.replan_due = false;
                false
            }
            None => self.go_off(OffRoute::At(Self::nearest_vertex(b, &p))),
        }
    }

    // ---- replanning ----

    /// Route index of the vertex the surveyor is at or heading to (on-route).
    fn heading(&self) -> usize {
        let a = self.pos_arc();
        (self.anchor..self.route.len())
            .find(|&k| self.arc[k] >= a - ARC_TOL)
            .unwrap_or(self.route.len() - 1)
    }

    /// Where a replan starts and the budget left for it: the vertex the surveyor is at or
    /// walking to, and the budget minus what was walked and what it takes to get there.
    pub fn replan_origin(&self, b: &Building) -> Result<(usize, f64)> {
        if matches!(
            self.status,
            SessionStatus::Finished | SessionStatus::Aborted
        ) {
            return Err(self.err("replan: the session is over"));
        }
        match self.off {
            Some(OffRoute::Lost) => Err(self.err(
                "replan: the position is unknown (walked past the check-in that was due); \
                 check in at the nearest vertex first",
            )),
            Some(OffRoute::At(v)) => {
                let to_v = self
                    .pose
                    .filter(|_| !self.surveyor.is_human())
                    .map_or(0.0, |p| p.planar_distance(&b.vertices[v].pos));
                Ok((v, self.budget_m - self.walked_m() - to_v))
            }
            None => {
                let j = self.heading();
                let to_j = (self.arc[j] - self.pos_arc()).max(0.0);
                Ok((self.route[j], self.budget_m - self.walked_m() - to_j))
            }
        }
    }

    /// Switches to a new walk from [`replan_origin`](Self::replan_origin) to the end.
    /// Checks it first; on error nothing changes.
    pub fn apply_replan(&mut self, b: &Building, walk: &[usize], seq: i64) -> Result<()> {
        let (origin, _) = self.replan_origin(b)?;
        b.check_walk(walk)?;
        if walk.first() != Some(&origin) || walk.last() != Some(&self.end) {
            return Err(self.err(format!(
                "replan: the new walk must go from {:?} to {:?}",
                b.vertices[origin].id, b.vertices[self.end].id
            )));
        }
        let (route, shift) = match self.off {
            Some(_) => (walk.to_vec(), None),
            None => {
                let j = self.heading();
                let mut r = self.route[self.anchor..=j].to_vec();
                r.extend_from_slice(&walk[1..]);
                (r, Some(self.arc[self.anchor]))
            }
        };
        match shift {
            Some(s) => self.robot_arc = (self.robot_arc - s).max(0.0),
            None => self.robot_arc = 0.0,
        }
        self.arc = arcs(b, &route);
        self.required = checkins(b, &route, &self.surveyor);
        self.route = route;
        self.anchor = 0;
        self.off = None;
        self.replan_due = false;
        self.replans += 1;
        self.last_seq = seq;
        Ok(())
    }

    // ---- guidance ----

    /// Route index of the next waypoint (on-route), `None` at the end.
    fn next_index(&self) -> Option<usize> {
        let a = self.pos_arc();
        let n = self.route.len();
        if self.surveyor.is_human() {
            (self.anchor + 1..n).find(|&k| self.arc[k] >= a - ARC_TOL)
        } else {
            (self.anchor..n).find(|&k| self.arc[k] > a + ARC_TOL)
        }
    }

    /// The vertices still ahead on the walk, with their distances (empty off-route).
    pub fn route_ahead(&self, b: &Building) -> Vec<Waypoint> {
        if self.off.is_some() {
            return Vec::new();
        }
        let a = self.pos_arc();
        let Some(j) = self.next_index() else {
            return Vec::new();
        };
        (j..self.route.len())
            .map(|k| {
                let v = &b.vertices[self.route[k]];
                Waypoint {
                    vertex: v.id.clone(),
                    label: v.label.clone(),
                    check_in: self.surveyor.is_human() && self.required[k],
                    distance_m: (self.arc[k] - a).max(0.0),
                }
            })
            .collect()
    }

    /// What to do next.
    pub fn guidance(&self, b: &Building) -> Guidance {
        let mut g = Guidance {
            status: self.status,
            off_route: self.off.is_some(),
            next_vertex: None,
            next_label: None,
            distance_m: 0.0,
            turn: Turn::Arrive,
            check_in_at_next: false,
            next_check_in: None,
            distance_to_check_in_m: 0.0,
            message: String::new(),
        };
        match self.status {
            SessionStatus::Finished => {
                g.message = "The session is finished.".into();
                return g;
            }
            SessionStatus::Aborted => {
                g.message = "The session was aborted.".into();
                return g;
            }
            SessionStatus::Paused => {
                g.message = "Paused: resume to continue the walk.".into();
                return g;
            }
            SessionStatus::Active => {}
        }
        match self.off {
            Some(OffRoute::Lost) => {
                g.message = "Off route: check in at the nearest vertex.".into();
                return g;
            }
            Some(OffRoute::At(v)) => {
                g.message = format!(
                    "Off route at {}: replan, or walk back to the planned walk and check in.",
                    b.vertices[v].id
                );
                return g;
            }
            None => {}
        }
        let a = self.pos_arc();
        let Some(j) = self.next_index() else {
            g.message = format!(
                "You have arrived at {}: finish the session.",
                b.vertices[self.end].id
            );
            return g;
        };
        let n = self.route.len();
        let v = &b.vertices[self.route[j]];
        g.next_vertex = Some(v.id.clone());
        g.next_label = v.label.clone();
        g.distance_m = (self.arc[j] - a).max(0.0);
        g.turn = if j + 1 >= n {
            Turn::Arrive
        } else {
            classify_turn(
                &b.vertices[self.route[j - 1]].pos,
                &v.pos,
                &b.vertices[self.route[j + 1]].pos,
            )
        };
        let human = self.surveyor.is_human();
        g.check_in_at_next = human && self.required[j];
        if human && let Some(k) = (j..n).find(|&k| self.required[k]) {
            g.next_check_in = Some(b.vertices[self.route[k]].id.clone());
            g.distance_to_check_in_m = (self.arc[k] - a).max(0.0);
        }
        g.message = guidance_sentence(
            g.distance_m,
            &v.id,
            v.label.as_deref(),
            g.turn,
            g.check_in_at_next,
        );
        g
    }

    /// Position as the bindings see it.
    pub fn position_plain(&self, b: &Building) -> Position {
        point_pos(&self.position(b))
    }
}
