//! A simulated surveyor walking a session's plan: synthetic steps with stride noise (or
//! robot poses), Wi-Fi scans drawn from a world model, and wrong turns at vertices with a
//! given probability. Deterministic for a seed: the clock is simulated too.
//!
//! The surveyor follows the session's guidance: it walks the planned vertices, checks in
//! where a check-in is due, and, after a wrong turn, checks in at the vertex it reached
//! (it can read the vertex's label) and follows the replanned walk, or walks back when the
//! session did not replan.

use std::collections::VecDeque;
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::types::{Ack, Event, MAX_RSS_DBM, MIN_RSS_DBM, Reading, Surveyor};
use super::{Session, SessionStatus, Summary};
use crate::building::Building;
use crate::eval::{MISSING_DBM, WorldModel};
use crate::gp::{Kernel, Point};
use crate::samples::{ARC_EPS, point_on_edge};
use crate::synth::random::{normal, unit};
use crate::synth::{AccessPoint, PropagationModel, PropagationParams};
use crate::{Error, Result};

/// How the simulated surveyor behaves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimOptions {
    /// Probability of taking a wrong turn at a vertex.
    pub deviate: f64,
    pub seed: u64,
    /// The human's real mean step length, metres (the session starts from its own guess).
    pub true_step_m: f64,
    /// Relative standard deviation of one stride.
    pub stride_noise: f64,
    /// Simulated clock at the start, ms since the Unix epoch.
    pub t0_ms: i64,
    /// Time a check-in takes, ms.
    pub check_in_ms: i64,
    /// Give up (abort) after walking this many times the budget.
    pub max_walk_factor: f64,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            deviate: 0.0,
            seed: 1,
            true_step_m: 0.75,
            stride_noise: 0.05,
            t0_ms: 1_767_225_600_000,
            check_in_ms: 2_000,
            max_walk_factor: 3.0,
        }
    }
}

impl SimOptions {
    pub fn validate(&self) -> Result<()> {
        if !(0.0..=1.0).contains(&self.deviate) {
            return Err(Error::InvalidRequest(format!(
                "--deviate must be a probability in [0, 1], got {}",
                self.deviate
            )));
        }
        if !self.true_step_m.is_finite() || self.true_step_m <= 0.05 {
            return Err(Error::InvalidRequest(format!(
                "true step length must be above 0.05 m, got {}",
                self.true_step_m
            )));
        }
        if !(0..=3_600_000).contains(&self.check_in_ms) {
            return Err(Error::InvalidRequest(format!(
                "the check-in pause must be between 0 and 3600 s, got {} ms",
                self.check_in_ms
            )));
        }
        if !self.stride_noise.is_finite() || !(0.0..0.5).contains(&self.stride_noise) {
            return Err(Error::InvalidRequest(format!(
                "stride noise must be in [0, 0.5), got {}",
                self.stride_noise
            )));
        }
        Ok(())
    }
}

/// Where simulated scans come from (SPEC section 5).
#[derive(Debug, Clone)]
pub enum World {
    /// GP posterior mean of the building's dense survey plus N(0, sn2) noise.
    Survey {
        aps: Vec<String>,
        model: WorldModel,
        noise_sd: f64,
    },
    /// A propagation model with access points placed at random vertices.
    Synthetic(PropagationModel),
}

impl World {
    /// The dense-survey world when the building has one, else a propagation model drawn
    /// from `seed`.
    pub fn for_building(b: &Building, kernel: &Kernel, seed: u64) -> Result<World> {
        if !b.dense_survey.is_empty() {
            let model = WorldModel::from_dense_survey(b, kernel)?;
            return Ok(World::Survey {
                aps: model.ap_ids(),
                model,
                noise_sd: kernel.sn2.sqrt(),
            });
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0005_eed0_fa11);
        let params = PropagationParams::default();
        let n_ap = (b.len() / 6).clamp(4, 20);
        let aps = (0..n_ap)
            .map(|i| {
                let v = &b.vertices[(rng.next_u64() % b.len() as u64) as usize];
                AccessPoint {
                    id: format!("sim-ap-{i:02}"),
                    pos: Point::new(v.pos.x + 0.5, v.pos.y + 0.5, v.pos.floor),
                    p0_dbm: params.p0_dbm.0 + (params.p0_dbm.1 - params.p0_dbm.0) * unit(&mut rng),
                    exponent: params.exponent.0
                        + (params.exponent.1 - params.exponent.0) * unit(&mut rng),
                }
            })
            .collect();
        let floors: Vec<i64> = b.floors.iter().map(|f| f.id).collect();
        Ok(World::Synthetic(PropagationModel::new(
            aps,
            Vec::new(),
            &floors,
            params,
            seed,
        )?))
    }

    /// One scan at `p`: access points heard, RSS in the range a session accepts.
    pub fn scan<R: Rng>(&self, p: &Point, rng: &mut R) -> Vec<Reading> {
        let clamp = |v: f64| v.clamp(MIN_RSS_DBM, MAX_RSS_DBM);
        match self {
            World::Survey {
                aps,
                model,
                noise_sd,
            } => {
                let mean = model.mean(std::slice::from_ref(p));
                aps.iter()
                    .enumerate()
                    .filter_map(|(a, id)| {
                        let v = mean[(0, a)] + noise_sd * normal(rng);
                        let v = (v * 100.0).round() / 100.0;
                        (v >= MISSING_DBM).then(|| Reading {
                            bssid: id.clone(),
                            rss_dbm: clamp(v),
                        })
                    })
                    .collect()
            }
            World::Synthetic(m) => m
                .measure(p, rng)
                .into_iter()
                .map(|(bssid, v)| Reading {
                    bssid,
                    rss_dbm: clamp(v),
                })
                .collect(),
        }
    }
}

/// What the simulation did besides the session's own figures.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SimReport {
    /// Events in the session's log: those the surveyor sent and the replans.
    pub events: u64,
    pub wrong_turns: u32,
    /// Metres the simulated surveyor really walked.
    pub true_walked_m: f64,
    /// Simulated time, seconds.
    pub sim_time_s: f64,
}

struct Walker<'a, F> {
    session: &'a mut Session,
    building: Arc<Building>,
    world: &'a World,
    opts: SimOptions,
    rng: ChaCha8Rng,
    on_ack: F,
    report: SimReport,
    /// Simulated clock, ms (fractional).
    t: f64,
}

/// The edge the simulated surveyor walks next.
struct Leg {
    /// The vertex it leads to.
    to: usize,
    /// Whether it leaves the planned walk (a wrong turn).
    wrong: bool,
    /// Its length, metres (0 where no edge joins the two vertices).
    len: f64,
    /// Its two ends: where the surveyor stands and `to`.
    pa: Point,
    pb: Point,
}

impl<F: FnMut(&Session, &Event, &Ack) -> Result<()>> Walker<'_, F> {
    fn emit(&mut self, ev: Event) -> Result<Ack> {
        let ack = self.session.record(ev.clone())?;
        self.report.events += 1;
        (self.on_ack)(self.session, &ev, &ack)?;
        Ok(ack)
    }

    fn t_ms(&self) -> i64 {
        self.t.round() as i64
    }

    /// The planned vertices ahead: (index, check-in due).
    fn plan_ahead(&self) -> VecDeque<(usize, bool)> {
        self.session
            .route_ahead()
            .iter()
            .filter_map(|w| {
                self.building
                    .vertex_index(&w.vertex)
                    .map(|i| (i, w.check_in))
            })
            .collect()
    }

    /// The next vertex to walk to: the planned one, or with probability `deviate` another
    /// neighbour (not where the surveyor came from). Returns it and whether it is wrong.
    fn choose(&mut self, at: usize, prev: Option<usize>, planned: usize) -> (usize, bool) {
        let Some(prev) = prev else {
            return (planned, false);
        };
        if self.opts.deviate <= 0.0 || unit(&mut self.rng) >= self.opts.deviate {
            return (planned, false);
        }
        let others: Vec<usize> = self
            .building
            .neighbours(at)
            .iter()
            .map(|&(n, _)| n)
            .filter(|&n| n != planned && n != prev)
            .collect();
        if others.is_empty() {
            return (planned, false);
        }
        let pick = others[(self.rng.next_u64() % others.len() as u64) as usize];
        self.report.wrong_turns += 1;
        (pick, true)
    }

    /// The edge walked next from `at` (reached from `prev`) toward `planned`, a wrong turn
    /// drawn as [`Self::choose`] draws it.
    fn next_leg(&mut self, at: usize, prev: Option<usize>, planned: usize) -> Leg {
        let (to, wrong) = self.choose(at, prev, planned);
        let b = &self.building;
        Leg {
            to,
            wrong,
            len: b.edge_between(at, to).map_or(0.0, |e| e.length),
            pa: b.vertices[at].pos,
            pb: b.vertices[to].pos,
        }
    }

    /// Checks in at `at`. Still off the route (no replan): the walk ahead starts by going
    /// back to `prev`, where the surveyor left it (`due`: a check-in is expected there);
    /// else the walk ahead is the session's, replanned or not.
    fn check_in(
        &mut self,
        at: usize,
        prev: Option<usize>,
        plan: &mut VecDeque<(usize, bool)>,
        due: bool,
    ) -> Result<()> {
        let ack = self.emit(Event::CheckIn {
            t_ms: self.t_ms(),
            vertex: self.building.vertices[at].id.clone(),
        })?;
        if ack.off_route {
            plan.push_front((prev.unwrap_or(at), due));
        } else {
            *plan = self.plan_ahead();
        }
        Ok(())
    }

    fn over_limit(&self) -> bool {
        self.report.true_walked_m
            > self.opts.max_walk_factor * self.session.tracker().budget_m() + 50.0
    }

    fn human(&mut self, speed: f64, scan_ms: f64) -> Result<()> {
        let mut at = self.session.tracker().route()[0];
        let mut prev: Option<usize> = None;
        let mut plan = self.plan_ahead();
        let mut next_scan = self.t;
        let mut carry = 0.0;
        while let Some(&(planned, due)) = plan.front() {
            if self.over_limit() {
                return Ok(());
            }
            let leg = self.next_leg(at, prev, planned);
            // The surveyor stops at a check-in (after a wrong turn, at the vertex reached):
            // the last step there is a short one.
            let stop = leg.wrong || due || (plan.len() == 1);
            let mut s = carry;
            while s < leg.len {
                let mut stride = (self.opts.true_step_m
                    * (1.0 + self.opts.stride_noise * normal(&mut self.rng)))
                .max(0.1);
                if stop {
                    stride = stride.min(leg.len - s);
                }
                let dt = stride / speed * 1000.0;
                while next_scan <= self.t + dt {
                    let frac = ((s + stride * (next_scan - self.t) / dt) / leg.len).clamp(0.0, 1.0);
                    let p = point_on_edge(&leg.pa, &leg.pb, frac);
                    let readings = self.world.scan(&p, &mut self.rng);
                    self.emit(Event::Scan {
                        t_ms: (next_scan.round() as i64).max(self.t_ms()),
                        readings,
                    })?;
                    next_scan += scan_ms;
                }
                s += stride;
                self.t += dt;
                self.report.true_walked_m += stride;
                self.emit(Event::Step {
                    t_ms: self.t_ms(),
                    steps: 1,
                })?;
            }
            prev = Some(at);
            at = leg.to;
            if stop {
                carry = 0.0;
                self.t += self.opts.check_in_ms as f64;
                self.check_in(at, prev, &mut plan, true)?;
            } else {
                carry = s - leg.len;
                plan.pop_front();
            }
        }
        Ok(())
    }

    fn robot(&mut self, interval: f64, speed: f64) -> Result<()> {
        let b = self.building.clone();
        let mut at = self.session.tracker().route()[0];
        let mut prev: Option<usize> = None;
        let mut plan = self.plan_ahead();
        let dt = interval / speed * 1000.0;
        let start = b.vertices[at].pos;
        self.pose_and_scan(&start)?;
        let mut arc = 0.0;
        let mut next_k: u64 = 1;
        while let Some(&(planned, _)) = plan.front() {
            if self.over_limit() {
                return Ok(());
            }
            let leg = self.next_leg(at, prev, planned);
            let start_arc = arc;
            let end_arc = start_arc + leg.len;
            loop {
                // The sample placement of `WalkSampler`, arithmetic for arithmetic.
                let s = next_k as f64 * interval;
                if s > end_arc + ARC_EPS {
                    break;
                }
                let frac = ((s - start_arc) / leg.len).clamp(0.0, 1.0);
                let p = point_on_edge(&leg.pa, &leg.pb, frac);
                self.t += dt;
                self.pose_and_scan(&p)?;
                next_k += 1;
            }
            arc = end_arc;
            self.report.true_walked_m += leg.len;
            prev = Some(at);
            at = leg.to;
            if leg.wrong || self.session.tracker().off_route() {
                self.check_in(at, prev, &mut plan, false)?;
            } else {
                plan.pop_front();
            }
        }
        // The robot reports its pose on arrival at the end.
        let end = b.vertices[at].pos;
        if self.session.tracker().position(&b) != end {
            self.t += dt * 0.5;
            self.emit(Event::Pose {
                t_ms: self.t_ms(),
                x: end.x,
                y: end.y,
                floor: end.floor,
            })?;
        }
        Ok(())
    }

    fn pose_and_scan(&mut self, p: &Point) -> Result<()> {
        self.emit(Event::Pose {
            t_ms: self.t_ms(),
            x: p.x,
            y: p.y,
            floor: p.floor,
        })?;
        let readings = self.world.scan(p, &mut self.rng);
        self.emit(Event::Scan {
            t_ms: self.t_ms(),
            readings,
        })?;
        Ok(())
    }
}

/// Walks the session's plan to the end and finishes the session (aborts it when the
/// surveyor wandered more than `max_walk_factor` budgets). `on_ack` sees every
/// acknowledged event. Continues a session that already has events only if it has none:
/// the simulated surveyor starts at the start vertex.
pub fn simulate<F>(
    session: &mut Session,
    world: &World,
    opts: &SimOptions,
    on_ack: F,
) -> Result<(Summary, SimReport)>
where
    F: FnMut(&Session, &Event, &Ack) -> Result<()>,
{
    opts.validate()?;
    if session.last_seq() != 0 || session.status() != SessionStatus::Active {
        return Err(Error::Session {
            session: session.id(),
            message: "the simulator starts only fresh sessions".into(),
        });
    }
    let surveyor = *session.tracker().surveyor();
    let building = session.building().clone();
    let mut w = Walker {
        session,
        building,
        world,
        opts: *opts,
        rng: ChaCha8Rng::seed_from_u64(opts.seed),
        on_ack,
        report: SimReport::default(),
        t: opts.t0_ms as f64,
    };
    match surveyor {
        Surveyor::Human {
            speed_mps,
            scan_interval_s,
            ..
        } => w.human(speed_mps, scan_interval_s * 1000.0)?,
        Surveyor::Robot {
            interval_m,
            speed_mps,
        } => w.robot(interval_m, speed_mps)?,
    }
    let t = w.t_ms() + 1000;
    let ev = if w.over_limit() {
        Event::Abort {
            t_ms: t,
            reason: Some("the simulated surveyor wandered too far".into()),
        }
    } else {
        Event::Finish { t_ms: t }
    };
    w.emit(ev)?;
    w.report.sim_time_s = (w.t - opts.t0_ms as f64) / 1000.0;
    // Every event of the log, the replans the session wrote too.
    w.report.events = u64::try_from(w.session.last_seq()).unwrap_or(0);
    let report = w.report;
    Ok((w.session.summary()?, report))
}
