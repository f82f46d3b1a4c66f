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

//!
//! # Layout
//! - this file: the state, its read-only views, [`Tracker::apply`] and replanning;
//! - `events`: [`Tracker::check`] (event validation) and [`Tracker::log_event`];
//! - `reckoning`: dead reckoning of a human surveyor (position along the walk, check-ins,
//!   step-length calibration);
//! - `robot`: projecting robot poses onto the walk;
//! - `guidance`: the next waypoint, the turn there and the sentence the surveyor reads.

mod events;
mod guidance;
mod reckoning;
mod robot;

use std::collections::BTreeMap;

use serde::Serialize;

use super::replan::distances_from;
use super::types::{CollectedSample, Event, Position, SessionOptions, SessionStatus, Surveyor};
use crate::building::Building;
use crate::gp::{Kernel, Point};
use crate::samples::check_in_flags;
use crate::utility::Observation;
use crate::{Error, Result};

pub use guidance::{classify_turn, guidance_sentence};

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

/// The route's check-in flags (see [`check_in_flags`]).
fn checkins(b: &Building, route: &[usize], surveyor: &Surveyor) -> Vec<bool> {
    check_in_flags(b, route, surveyor.turn_threshold_deg())
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
                out.went_off_route = self.human_steps(*steps);
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

    /// Marks the surveyor off-route at `at`; returns whether it was on-route before.
    fn go_off(&mut self, at: OffRoute) -> bool {
        let was_on = self.off.is_none();
        self.off = Some(at);
        if was_on {
            self.off_route_events += 1;
        }
        self.replan_due = self.options.auto_replan && matches!(at, OffRoute::At(_));
        was_on
    }

    // ---- replanning ----

    /// Route index of the vertex the surveyor is at or heading to (on-route).
    fn heading(&self) -> usize {
        let a = self.pos_arc();
        (self.anchor..self.route.len())
            .find(|&k| self.arc[k] >= a - ARC_TOL)
            .unwrap_or(self.route.len() - 1)
    }

    /// The planned route from the vertex the surveyor was last heading to on it (after a
    /// wrong turn too: where they left it) to the end.
    pub fn route_remaining(&self) -> &[usize] {
        &self.route[self.heading()..]
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

    /// Position as the bindings see it.
    pub fn position_plain(&self, b: &Building) -> Position {
        point_pos(&self.position(b))
    }
}
