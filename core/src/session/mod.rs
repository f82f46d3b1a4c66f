//! Survey sessions: a surveyor walking a saved plan with a phone (or a robot), turned into
//! positions, fingerprints, guidance, progress and replans.
//!
//! # Design
//! * The state of a session is a pure function of its plan and its event log
//!   ([`tracker::Tracker`]); resuming is replaying the log, which touches no numerics
//!   beyond a label per scan, so it is fast. A replan is logged as an event naming the
//!   saved plan it switched to, so replay never plans again.
//! * [`Session::record`] checks an event against the state, writes it to the log and only
//!   then applies it and acknowledges it ([`Ack`]): a rejected event writes nothing, and an
//!   acknowledged one survives a kill.
//! * Storage is behind the small [`SessionLog`] trait ([`MemoryLog`] in memory, the SQLite
//!   store for the app); replanning is behind [`Replanner`] ([`default_replanner`]: the
//!   built-in [`GreedyReplanner`] on small buildings, `auto` on large ones).
//! * Threading: a `Session` is `Send` but used from one thread at a time; the bindings wrap
//!   it in a mutex.
//!
//! # Example
//! ```
//! use std::sync::Arc;
//! use trailprint::session::{Event, MemoryLog, PlanData, Session, SessionOptions, SessionLog, Surveyor};
//! use trailprint::{Building, gp::Kernel};
//!
//! let b = Building::from_json(r#"{"format":"survey-building/1","name":"L",
//!   "vertices":[{"id":"a","x":0,"y":0},{"id":"b","x":4,"y":0},{"id":"c","x":4,"y":4}],
//!   "edges":[{"a":"a","b":"b"},{"a":"b","b":"c"}]}"#, "doc")?;
//! let log = Arc::new(MemoryLog::new());
//! let bid = log.add_building(Arc::new(b));
//! let plan = log.save_plan(&PlanData::for_walk(bid, &["a", "b", "c"], 10.0, Kernel::new(20.0, 5.0, 2.0), 8.0))?;
//! let mut s = Session::start(log, plan, Surveyor::human(), SessionOptions::default())?;
//! assert_eq!(s.guidance().next_vertex.as_deref(), Some("b"));
//! for t in 0..6 {
//!     s.record(Event::Step { t_ms: 1000 * t, steps: 1 })?;
//! }
//! let ack = s.record(Event::CheckIn { t_ms: 7000, vertex: "b".into() })?;
//! assert!(!ack.off_route);
//! assert!((s.progress()?.step_length_m - (20.0 * 0.7 + 4.0) / 25.5).abs() < 1e-12);
//! # Ok::<(), trailprint::Error>(())
//! ```

pub mod log;
pub mod posterior;
pub mod replan;
#[cfg(feature = "research")]
pub mod sim;
mod store_log;
pub mod tracker;
pub mod types;

// The session tests drive the simulator and the demo building (feature `research`).
#[cfg(all(test, feature = "research"))]
mod tests;

use std::sync::Arc;
use std::time::Instant;

use serde::{Deserialize, Serialize};

pub use log::{LogEntry, MemoryLog, PlanData, SessionLog, SessionRow};
pub use posterior::IncrementalPosterior;
pub use replan::{GreedyReplanner, PlannerReplanner, ReplanRequest, Replanner, default_replanner};
pub use tracker::Tracker;
pub use types::*;

use crate::building::Building;
use crate::gp::{Kernel, Point};
use crate::plan::PlanOrigin;
use crate::samples::sample_walk;
use crate::store::{PlanRecord, SessionEvent};
use crate::utility::UtilityEngine;
use crate::{Error, Result};

/// What the session row keeps besides the plan: who walks and how the session reacts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SessionSettings {
    pub surveyor: Surveyor,
    #[serde(default)]
    pub options: SessionOptions,
}

use crate::store::now_ms;

impl PlanData {
    /// A plan record for a walk given by ids (for tests and tools; figures left at zero
    /// except the ones given).
    pub fn for_walk(
        building_id: i64,
        walk: &[&str],
        budget_m: f64,
        kernel: Kernel,
        length_m: f64,
    ) -> Self {
        PlanData {
            building_id,
            record: PlanRecord {
                start: walk.first().map(|s| s.to_string()).unwrap_or_default(),
                end: walk.last().map(|s| s.to_string()).unwrap_or_default(),
                budget_m,
                surveyor: None,
                kernel,
                algorithm: PlanOrigin::Given,
                seed: None,
                walk: walk.iter().map(|s| s.to_string()).collect(),
                length_m,
                samples: 0,
                utility_nats: 0.0,
                elapsed_ms: 0,
                created_ms: 0,
            },
        }
    }
}

/// A survey session (see the module documentation).
pub struct Session {
    log: Arc<dyn SessionLog>,
    replanner: Arc<dyn Replanner>,
    id: i64,
    building_id: i64,
    plan_id: i64,
    building: Arc<Building>,
    kernel: Kernel,
    tracker: Tracker,
    /// The session's surveyor model (the utility engine of the plan's value is built
    /// when needed, not kept: on a building of thousands of vertices it holds the
    /// factor of `K_VV`, 80 MB on 3,161 vertices, which the running posterior has its
    /// own copy of).
    surveyor: Surveyor,
    planned_utility: f64,
    last_replan_error: Option<String>,
    /// Pilot data plus every sample so far, updated as scans arrive.
    posterior: IncrementalPosterior,
    /// Why the running posterior could not take a sample (numerically), if it could not.
    posterior_error: Option<String>,
    /// Metres the last replan kept back for wrong turns (0 before any replan).
    reserve_m: f64,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("id", &self.id)
            .field("plan_id", &self.plan_id)
            .field("status", &self.tracker.status())
            .field("last_seq", &self.tracker.last_seq())
            .finish()
    }
}

impl Session {
    /// Starts a new session on the saved plan `plan_id`.
    pub fn start(
        log: Arc<dyn SessionLog>,
        plan_id: i64,
        surveyor: Surveyor,
        options: SessionOptions,
    ) -> Result<Session> {
        surveyor.validate()?;
        options.validate()?;
        let plan = log.load_plan(plan_id)?;
        let settings = SessionSettings { surveyor, options };
        let value = serde_json::to_value(settings)
            .map_err(|e| Error::InvalidRequest(format!("session settings: {e}")))?;
        // Open first so that a plan the session cannot walk creates no row.
        let mut s = Self::open(log.clone(), 0, plan_id, &plan, settings)?;
        let id = log.create_session(plan.building_id, plan_id, &value, now_ms())?;
        s.id = id;
        s.tracker = Tracker::new(
            id,
            &s.building,
            surveyor,
            options,
            s.kernel,
            plan.record.budget_m,
            s.tracker.route().to_vec(),
        )?;
        Ok(s)
    }

    /// Resumes a session from its log: replays every event, then finishes an automatic
    /// replan that a kill interrupted.
    pub fn resume(log: Arc<dyn SessionLog>, session_id: i64) -> Result<Session> {
        let mut s = Self::replay_to(log, session_id, i64::MAX)?;
        s.finish_due_replan();
        Ok(s)
    }

    /// The session as it was right after event `seq` (replayed; an automatic replan that a
    /// kill interrupted is not finished, so nothing is written).
    pub fn replay_to(log: Arc<dyn SessionLog>, session_id: i64, seq: i64) -> Result<Session> {
        let row = log.session(session_id)?;
        let settings: SessionSettings =
            serde_json::from_value(row.settings.clone()).map_err(|e| Error::Session {
                session: session_id,
                message: format!("stored settings cannot be read: {e}"),
            })?;
        let plan = log.load_plan(row.plan_id)?;
        let mut s = Self::open(log.clone(), session_id, row.plan_id, &plan, settings)?;
        for entry in log.events(session_id)?.iter().take_while(|e| e.seq <= seq) {
            s.replay(entry)?;
        }
        // The samples all at once: one blocked factorisation, not one row per sample.
        let samples: Vec<(Point, f64)> = s
            .tracker
            .samples()
            .iter()
            .map(|c| {
                let p = Point::new(c.position.x, c.position.y, c.position.floor);
                (p, c.extra_noise)
            })
            .collect();
        if let Err(e) = s.posterior.add_all(&samples) {
            s.posterior_error = Some(format!("the samples of the log: {e}"));
        }
        s.absorb_samples();
        Ok(s)
    }

    fn open(
        log: Arc<dyn SessionLog>,
        id: i64,
        plan_id: i64,
        plan: &PlanData,
        settings: SessionSettings,
    ) -> Result<Session> {
        let building = log.building(plan.building_id)?;
        let walk = building.resolve_walk(&plan.record.walk)?;
        let kernel = plan.record.kernel;
        let planned_utility =
            UtilityEngine::new(building.clone(), kernel, settings.surveyor)?.utility(&walk)?;
        let mut posterior_bytes = usize::try_from(settings.options.memory_budget_mb)
            .unwrap_or(usize::MAX)
            .saturating_mul(1 << 20);
        // A new session with a budget too small for the building is refused (nothing is
        // written); a stored one opens anyway, with the least that holds the building, so
        // that what was walked can always be read back.
        if id != 0 {
            posterior_bytes = posterior_bytes.max(IncrementalPosterior::least_memory(&building));
        }
        let posterior = IncrementalPosterior::new(&building, kernel, posterior_bytes)?;
        let tracker = Tracker::new(
            id,
            &building,
            settings.surveyor,
            settings.options,
            kernel,
            plan.record.budget_m,
            walk,
        )?;
        Ok(Session {
            log,
            replanner: replan::default_replanner(&building),
            id,
            building_id: plan.building_id,
            plan_id,
            building,
            kernel,
            tracker,
            surveyor: settings.surveyor,
            planned_utility,
            last_replan_error: None,
            posterior,
            posterior_error: None,
            reserve_m: 0.0,
        })
    }

    /// Uses another planner for replans.
    pub fn set_replanner(&mut self, replanner: Arc<dyn Replanner>) {
        self.replanner = replanner;
    }

    fn replay(&mut self, entry: &LogEntry) -> Result<()> {
        let b = self.building.clone();
        let expect = self.tracker.last_seq() + 1;
        if entry.seq != expect {
            return Err(Error::Session {
                session: self.id,
                message: format!("log gap: expected event {expect}, found {}", entry.seq),
            });
        }
        let bad = |e: Error| Error::Session {
            session: self.id,
            message: format!("event {} of the log cannot be replayed: {e}", entry.seq),
        };
        let t_ms = entry.t_ms;
        let ev = match &entry.event {
            SessionEvent::Replan { plan_id } => {
                let plan = self.log.load_plan(*plan_id)?;
                let walk = b.resolve_walk(&plan.record.walk).map_err(bad)?;
                // The reserve is what the budget left exceeded the plan's budget by (see
                // `replan`), so replay recovers it without planning.
                let (_, left) = self.tracker.replan_origin(&b).map_err(bad)?;
                let reserve = (left.max(0.0) - plan.record.budget_m).max(0.0);
                self.tracker
                    .apply_replan(&b, &walk, entry.seq)
                    .map_err(bad)?;
                self.reserve_m = reserve;
                return Ok(());
            }
            SessionEvent::Step { steps, .. } => Event::Step {
                t_ms,
                steps: *steps,
            },
            SessionEvent::Scan(fp) => Event::Scan {
                t_ms,
                readings: fp
                    .rss
                    .iter()
                    .map(|(k, &v)| Reading {
                        bssid: k.clone(),
                        rss_dbm: v,
                    })
                    .collect(),
            },
            SessionEvent::CheckIn { vertex } => Event::CheckIn {
                t_ms,
                vertex: vertex.clone(),
            },
            SessionEvent::Pose { x, y, floor, .. } => Event::Pose {
                t_ms,
                x: *x,
                y: *y,
                floor: *floor,
            },
            SessionEvent::Pause => Event::Pause { t_ms },
            SessionEvent::Resume => Event::Resume { t_ms },
            SessionEvent::Finish => Event::Finish { t_ms },
            SessionEvent::Abort { reason } => Event::Abort {
                t_ms,
                reason: reason.clone(),
            },
        };
        self.tracker.check(&b, &ev).map_err(bad)?;
        self.tracker.apply(&b, &ev, entry.seq);
        Ok(())
    }

    /// Feeds the samples the tracker collected since the last call to the running
    /// posterior. A numerical failure is kept and reported by the utility and progress.
    fn absorb_samples(&mut self) {
        if self.posterior_error.is_some() {
            return;
        }
        let done = self.posterior.samples();
        for s in &self.tracker.samples()[done.min(self.tracker.samples().len())..] {
            let p = Point::new(s.position.x, s.position.y, s.position.floor);
            if let Err(e) = self.posterior.add(p, s.extra_noise) {
                self.posterior_error = Some(format!("sample of event {}: {e}", s.seq));
                return;
            }
        }
        // At the end, the samples of a row not yet complete go into the figures too.
        if matches!(
            self.tracker.status(),
            SessionStatus::Finished | SessionStatus::Aborted
        ) && let Err(e) = self.posterior.flush()
        {
            self.posterior_error = Some(format!("the last samples: {e}"));
        }
    }

    fn finish_due_replan(&mut self) -> Option<i64> {
        if !self.tracker.replan_due() {
            return None;
        }
        match self.replan() {
            Ok(o) => {
                self.last_replan_error = None;
                Some(o.seq)
            }
            Err(e) => {
                self.last_replan_error = Some(e.to_string());
                None
            }
        }
    }

    /// Records an event: checks it, writes it to the log, applies it, and replans if it took
    /// the surveyor off-route and automatic replanning is on. A rejected event writes
    /// nothing and changes nothing.
    pub fn record(&mut self, event: Event) -> Result<Ack> {
        let event = event.without_negative_zeros();
        let b = self.building.clone();
        self.tracker.check(&b, &event)?;
        let entry = self.tracker.log_event(&b, &event);
        let seq = self.log.append(self.id, event.t_ms(), &entry)?;
        let expect = self.tracker.last_seq() + 1;
        let applied = self.tracker.apply(&b, &event, seq);
        self.absorb_samples();
        if seq != expect {
            return Err(Error::Session {
                session: self.id,
                message: format!(
                    "the log was written by someone else (event {seq} where {expect} was \
                     expected): resume the session"
                ),
            });
        }
        let mut replan_seq = self.finish_due_replan();
        if replan_seq.is_none() && matches!(event, Event::CheckIn { .. }) && !applied.went_off_route
        {
            replan_seq = self.release_surplus_reserve();
        }
        Ok(Ack {
            seq,
            status: self.tracker.status(),
            off_route: self.tracker.off_route(),
            went_off_route: applied.went_off_route,
            replan_seq,
            replan_error: if replan_seq.is_none() {
                self.last_replan_error.take()
            } else {
                None
            },
            sample: applied.sample,
            position: self.tracker.position_plain(&b),
        })
    }

    /// Replans from the vertex the surveyor is at or walking to, with the budget left, to
    /// the same end, conditioning on the pilot data and every sample collected so far
    /// (past the running posterior's memory budget, the samples it keeps). The
    /// walked part stays recorded. When the budget left cannot reach the end, the new walk
    /// is the shortest way there (`over_budget`).
    pub fn replan(&mut self) -> Result<ReplanOutcome> {
        let started = Instant::now();
        let b = self.building.clone();
        let (origin, left) = self.tracker.replan_origin(&b)?;
        let budget = left.max(0.0);
        let end = self.tracker.end();
        let model = *self.tracker.surveyor();
        // Every sample, or past REPLAN_PRIOR_MAX of them (or the running posterior's
        // memory budget) one of several: a replan then fits its time and memory.
        let prior = match self.posterior_ok() {
            Ok(p) => p.kept_samples(posterior::REPLAN_PRIOR_MAX).1,
            Err(_) => self.tracker.observations(),
        };
        let seed = self
            .tracker
            .options()
            .seed
            .wrapping_add(u64::from(self.tracker.replans()) + 1);
        let to_end = replan::distances_from(&b, end);
        let home = to_end[origin];
        let over_budget = home > budget + replan::BUDGET_EPS;
        let keep = !over_budget && self.tracker.options().deviation_reserve;
        let left_for_plan = budget;
        let plan_within = |this: &Self, budget: f64| -> Result<(Vec<usize>, Option<f64>)> {
            if over_budget || budget <= home + 1e-6 {
                Ok((replan::shortest_path(&b, origin, end)?, None))
            } else {
                this.replanner.replan_scored(&ReplanRequest {
                    building: &b,
                    kernel: this.kernel,
                    model,
                    prior: &prior,
                    start: origin,
                    end,
                    budget_m: budget,
                    seed,
                    memory_budget: this
                        .tracker
                        .options()
                        .memory_budget_mb
                        .saturating_mul(1 << 20),
                })
            }
        };
        // The reserve covers the way home from the farthest point of the walk: the walk
        // this replan replaces goes so far, and replans of one session mostly reach as far
        // as the plan before them. When the new walk goes farther, a replanner without a
        // time limit (the session greedy, milliseconds) plans once more with the reserve
        // for the farthest vertex any walk within the rest can reach, which covers
        // whatever that walk does; a time-limited one is asked once, so that the surveyor
        // waits no longer than its limit, and its walk keeps the reserve it was planned
        // with. Measured on 45 robot replans (six generated buildings, `--deviate 0.05`,
        // seeds 1-3): 8 walks went farther, short of their own need by 0.55 to 2.13 m of
        // reserve and once by 16 m.
        let farthest = |walk: &[usize]| walk.iter().map(|&v| to_end[v]).fold(home, f64::max);
        let reserve_for = |this: &Self, h: f64| {
            if keep {
                this.deviation_reserve(h, &to_end)
                    .clamp(0.0, left_for_plan - home)
            } else {
                0.0
            }
        };
        let mut reserve = reserve_for(self, farthest(self.tracker.route_remaining()));
        let (mut walk, mut scored) = plan_within(self, budget - reserve)?;
        if self.replanner.time_limit().is_none()
            && reserve_for(self, farthest(&walk)) > reserve + 1e-6
        {
            reserve = self.reserve_within(origin, budget, &to_end);
            (walk, scored) = plan_within(self, budget - reserve)?;
        }
        let budget = budget - reserve;
        b.check_walk(&walk)?;
        let length = b.walk_length(&walk);
        if walk.first() != Some(&origin) || walk.last() != Some(&end) {
            return Err(Error::Session {
                session: self.id,
                message: format!(
                    "replanner {} returned a walk that does not go from {:?} to {:?}",
                    self.replanner.origin(),
                    b.vertices[origin].id,
                    b.vertices[end].id
                ),
            });
        }
        if !over_budget && length > budget + replan::BUDGET_EPS {
            return Err(Error::Session {
                session: self.id,
                message: format!(
                    "replanner {} returned a walk of {length:.3} m over the {budget:.3} m left",
                    self.replanner.origin()
                ),
            });
        }
        let utility = match scored {
            Some(u) => u,
            None => {
                UtilityEngine::with_prior(b.clone(), self.kernel, model, &prior)?.utility(&walk)?
            }
        };
        let samples = sample_walk(&b, &walk, &model, &self.kernel)?.len() as u64;
        let ids = b.walk_ids(&walk);
        let plan = PlanData {
            building_id: self.building_id,
            record: PlanRecord {
                start: ids[0].clone(),
                end: b.vertices[end].id.clone(),
                budget_m: budget,
                surveyor: Some(model),
                kernel: self.kernel,
                algorithm: self.replanner.origin(),
                seed: Some(seed),
                walk: ids.clone(),
                length_m: length,
                samples,
                utility_nats: utility,
                elapsed_ms: started.elapsed().as_millis() as u64,
                created_ms: now_ms(),
            },
        };
        let plan_id = self.log.save_plan(&plan)?;
        let t = self.tracker.last_t_ms().unwrap_or_else(now_ms);
        let seq = self
            .log
            .append(self.id, t, &SessionEvent::Replan { plan_id })?;
        self.tracker.apply_replan(&b, &walk, seq)?;
        self.reserve_m = (left_for_plan - budget).max(0.0);
        Ok(ReplanOutcome {
            seq,
            plan_id,
            from_vertex: ids[0].clone(),
            walk: ids,
            length_m: length,
            budget_left_m: left,
            over_budget,
            reserve_m: self.reserve_m,
            utility_nats: utility,
        })
    }

    /// The reserve a replan from `origin` with `left` metres keeps back: the least `r`
    /// that covers the way home ([`Self::deviation_reserve`]) from the farthest vertex a
    /// walk of `left - r` metres from `origin` to the end can reach, at most what is left
    /// beyond the shortest way home. A walk planned within the rest cannot go farther, so
    /// a replan's second plan needs no third. It is an upper bound: as the reserve of
    /// every replan it kept robots' walks 1.7% below the reserve from the walk a replan
    /// replaces (36 simulated sessions on six generated buildings), hence only for a
    /// second plan. The bound shrinks as the walk nears its end (or goes without wrong
    /// turns), and [`Self::release_surplus_reserve`] hands back what it no longer needs;
    /// judged against the walk's own farthest point instead, a walk planned under the
    /// bound would release at once and plan under the bound again, check-in after
    /// check-in.
    fn reserve_within(&self, origin: usize, left: f64, to_end: &[f64]) -> f64 {
        let home = to_end[origin];
        if left <= home {
            return 0.0;
        }
        let from = replan::distances_from(&self.building, origin);
        // The farthest from the end that a walk of `within` metres can reach.
        let reach = |within: f64| {
            from.iter()
                .zip(to_end)
                .filter(|&(f, t)| f + t <= within + replan::BUDGET_EPS)
                .map(|(_, &t)| t)
                .fold(home, f64::max)
        };
        let need = |r: f64| {
            self.deviation_reserve(reach(left - r), to_end)
                .min(left - home)
        };
        // `need` falls as `r` grows: bisect for the least `r >= need(r)`.
        let hi = need(0.0);
        if hi <= 0.0 {
            return 0.0;
        }
        let (mut lo, mut hi) = (0.0, hi);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if mid >= need(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
            if hi - lo < 1e-3 {
                break;
            }
        }
        hi
    }

    /// Metres to keep back, when replanning at `home` metres from the end (`to_end`: every
    /// vertex's distance to the end), for the wrong turns still to come.
    ///
    /// Wrong turns in the middle of the walk cost nothing against the budget, since the
    /// replan that follows fits the budget left; what overruns it are the wrong turns on
    /// the way back to the end, when the budget left is just the way back. So:
    /// * the rate is the session's own, off-route events per metre walked (over at least
    ///   ten mean edge lengths, so that one early wrong turn does not read as a storm);
    /// * a wrong turn from `u` onto the edge to `w` costs `len + to_end(w) - to_end(u)`
    ///   against the way home (up to twice the edge); `cost` is its mean over the edges
    ///   leaving junctions (vertices of degree 3 or more, where a wrong turn is possible)
    ///   that do not lead home (those are the planned steps on the way home);
    /// * on the `home` metres still to walk at least, `rate * home` wrong turns are
    ///   expected, plus those on their own detours (a geometric series,
    ///   `1 / (1 - rate * cost)`, capped at 4);
    /// * the reserve is `cost` times that expectation plus one standard deviation of a
    ///   Poisson count.
    ///
    /// With no wrong turn yet it is zero: a surveyor (or a robot) that follows the plan
    /// never gets a shorter one.
    fn deviation_reserve(&self, home: f64, to_end: &[f64]) -> f64 {
        let t = &self.tracker;
        let events = f64::from(t.off_route_events());
        let b = &self.building;
        if events == 0.0 || b.edges.is_empty() {
            return 0.0;
        }
        let edge = b.total_edge_length() / b.edges.len() as f64;
        let (mut sum, mut n) = (0.0, 0usize);
        for junctions_only in [true, false] {
            for u in 0..b.len() {
                let nb = b.neighbours(u);
                if (junctions_only && nb.len() < 3) || !to_end[u].is_finite() {
                    continue;
                }
                for &(w, e) in nb {
                    // A step that leads home is the planned one, not a wrong turn.
                    if to_end[w].is_finite() && to_end[w] >= to_end[u] {
                        sum += b.edges[e].length + to_end[w] - to_end[u];
                        n += 1;
                    }
                }
            }
            if n > 0 {
                break;
            }
        }
        let cost = if n > 0 { sum / n as f64 } else { 2.0 * edge };
        let rate = events / t.walked_m().max(10.0 * edge);
        let compound = 1.0 / (1.0 - (rate * cost).min(0.75));
        let expected = rate * home * compound;
        cost * (expected + expected.sqrt())
    }

    /// After an on-route check-in: when the walk ahead leaves clearly more in reserve
    /// than the wrong turns still to come need (the way home got shorter and no wrong turn
    /// used the reserve), replans so that the walk ahead uses the surplus. Only once a
    /// replan has kept a reserve.
    fn release_surplus_reserve(&mut self) -> Option<i64> {
        let t = &self.tracker;
        if self.reserve_m <= 0.0
            || !t.options().auto_replan
            || !t.options().deviation_reserve
            || t.off_route()
            || t.status() != SessionStatus::Active
        {
            return None;
        }
        let b = self.building.clone();
        let (origin, left) = t.replan_origin(&b).ok()?;
        let end = t.end();
        if origin == end {
            return None;
        }
        let to_end = replan::distances_from(&b, end);
        let need = self.reserve_within(origin, left.max(0.0), &to_end);
        let edge = b.total_edge_length() / b.edges.len().max(1) as f64;
        let surplus = self.slack_m() - need;
        if surplus <= (4.0 * edge).max(0.03 * t.budget_m()) {
            return None;
        }
        match self.replan() {
            Ok(o) => Some(o.seq),
            Err(e) => {
                self.last_replan_error = Some(e.to_string());
                None
            }
        }
    }

    /// Metres the last replan kept back for wrong turns (0 before any replan).
    pub fn reserve_m(&self) -> f64 {
        self.reserve_m
    }

    /// What to do next.
    pub fn guidance(&self) -> Guidance {
        let mut g = self.tracker.guidance(&self.building);
        let slack = self.slack_m();
        if self.reserve_m > 0.0 && slack >= 0.5 && g.next_vertex.is_some() && !g.off_route {
            g.message.push_str(&format!(
                " Plan shortened to keep {slack:.0} m in reserve for wrong turns."
            ));
        }
        g
    }

    /// Budget left beyond the walk ahead, metres (what is in reserve).
    fn slack_m(&self) -> f64 {
        let t = &self.tracker;
        t.budget_m() - t.walked_m() - t.remaining_m(&self.building)
    }

    /// The vertices still ahead on the walk (empty when off-route or at the end).
    pub fn route_ahead(&self) -> Vec<Waypoint> {
        self.tracker.route_ahead(&self.building)
    }

    fn posterior_ok(&self) -> Result<&IncrementalPosterior> {
        match &self.posterior_error {
            Some(m) => Err(Error::Numerical(format!(
                "session {}: the running posterior failed: {m}",
                self.id
            ))),
            None => Ok(&self.posterior),
        }
    }

    /// Posterior standard deviation of the latent RSS at every vertex given the pilot
    /// data and the samples, read off the running posterior in `O(|V|)` (the coverage
    /// map).
    pub fn uncertainty(&self) -> Result<Vec<VertexUncertainty>> {
        let var = self.posterior_ok()?.vertex_variance();
        Ok(self
            .building
            .vertices
            .iter()
            .zip(var)
            .map(|(v, var)| VertexUncertainty {
                vertex: v.id.clone(),
                x: v.pos.x,
                y: v.pos.y,
                floor: v.pos.floor,
                std_db: var.sqrt(),
            })
            .collect())
    }

    /// Utility of the samples actually recorded, with their real label noise, nats: kept
    /// up to date as scans arrive ([`IncrementalPosterior`]), so this is `O(1)`.
    pub fn collected_utility(&self) -> Result<f64> {
        Ok(self.posterior_ok()?.utility())
    }

    /// The same utility evaluated from scratch (one factorisation of everything; for
    /// checks, `O((n + |V|)^3)`).
    pub fn collected_utility_from_scratch(&self) -> Result<f64> {
        UtilityEngine::new(self.building.clone(), self.kernel, self.surveyor)?
            .utility_of_observations(&self.tracker.observations())
    }

    /// A snapshot: distance, time, samples, utilities and the coverage map.
    pub fn progress(&self) -> Result<Progress> {
        let b = &self.building;
        let t = &self.tracker;
        let walked = t.walked_m();
        let remaining = t.remaining_m(b);
        let elapsed_s = t.elapsed_ms() as f64 / 1000.0;
        let observed = if elapsed_s > 10.0 && walked > 5.0 {
            walked / elapsed_s
        } else {
            t.surveyor().speed_mps()
        };
        let total = walked + remaining;
        Ok(Progress {
            status: t.status(),
            off_route: t.off_route(),
            fraction_done: if total > 0.0 {
                (walked / total).clamp(0.0, 1.0)
            } else {
                1.0
            },
            walked_m: walked,
            budget_m: t.budget_m(),
            budget_left_m: t.budget_m() - walked,
            remaining_m: remaining,
            elapsed_s,
            remaining_s: remaining / observed,
            samples: t.samples().len() as u64,
            samples_in_figures: self.posterior_ok()?.samples_in_figures() as u64,
            sample_block: self.posterior_ok()?.block() as u64,
            planned_utility_nats: self.planned_utility,
            collected_utility_nats: self.collected_utility()?,
            step_length_m: t.step_length_m(),
            replans: t.replans(),
            off_route_events: t.off_route_events(),
            reserve_m: if self.reserve_m > 0.0 {
                self.slack_m().max(0.0)
            } else {
                0.0
            },
            uncertainty: self.uncertainty()?,
        })
    }

    /// Records the end of the walk and returns the summary.
    pub fn finish(&mut self, t_ms: i64) -> Result<Summary> {
        self.record(Event::Finish { t_ms })?;
        self.summary()
    }

    /// The summary of the session so far (final once finished).
    pub fn summary(&self) -> Result<Summary> {
        let p = self.progress()?;
        let n = p.uncertainty.len().max(1) as f64;
        Ok(Summary {
            session_id: self.id,
            status: p.status,
            walked_m: p.walked_m,
            budget_m: p.budget_m,
            elapsed_s: p.elapsed_s,
            samples: p.samples,
            check_ins: self.tracker.check_ins(),
            steps: self.tracker.steps_total(),
            planned_utility_nats: p.planned_utility_nats,
            collected_utility_nats: p.collected_utility_nats,
            sample_block: p.sample_block,
            step_length_m: p.step_length_m,
            replans: p.replans,
            off_route_events: p.off_route_events,
            mean_std_db: p.uncertainty.iter().map(|u| u.std_db).sum::<f64>() / n,
            max_std_db: p.uncertainty.iter().map(|u| u.std_db).fold(0.0, f64::max),
        })
    }

    /// The session's store id.
    pub fn id(&self) -> i64 {
        self.id
    }

    /// The plan the session started from.
    pub fn plan_id(&self) -> i64 {
        self.plan_id
    }

    /// Store id of the building.
    pub fn building_id(&self) -> i64 {
        self.building_id
    }

    /// The building.
    pub fn building(&self) -> &Arc<Building> {
        &self.building
    }

    pub fn status(&self) -> SessionStatus {
        self.tracker.status()
    }

    /// Utility of the plan as first planned, nats.
    pub fn planned_utility(&self) -> f64 {
        self.planned_utility
    }

    /// The samples collected so far.
    pub fn samples(&self) -> &[CollectedSample] {
        self.tracker.samples()
    }

    /// The state machine (read-only), for inspection and tests.
    pub fn tracker(&self) -> &Tracker {
        &self.tracker
    }

    /// The whole state as JSON: equal digests mean equal states.
    pub fn digest(&self) -> String {
        serde_json::to_string(&self.tracker).unwrap_or_default()
    }

    /// Seq of the last event applied.
    pub fn last_seq(&self) -> i64 {
        self.tracker.last_seq()
    }
}
