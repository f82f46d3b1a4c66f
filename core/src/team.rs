//! Several surveyors sharing one building: team planning.
//!
//! K surveyors each have a start, an end and a budget. Planned independently they all
//! chase the same informative places; planned as a team, each walk is conditioned on the
//! samples of the others, so the walks complement each other.
//!
//! The method ([`plan_team`]):
//! 1. *In turn*: surveyor `i` is planned conditioned on the pilot data, the `prior`
//!    (fingerprints already collected) and the samples of walks `0..i`.
//! 2. *Refinement* (coordinate ascent): each surveyor is replanned conditioned on all the
//!    other walks; the new walk is kept only if the team utility rises. Because each
//!    accepted step raises the team utility, the rounds stop (at the round limit or when
//!    no walk changes).
//!
//! The team utility is `f_D` of all the surveyors' samples together (SPEC section 3),
//! conditioned on the same prior.
//!
//! Every planner run reports its progress to the caller's observer, its message prefixed
//! with the run's place in the team plan (`surveyor 2/3, in turn: ...`). A cancel stops the
//! team plan as it stops one plan: the run under way returns its best walk so far, each
//! surveyor not yet planned gets the systematic walk ([`crate::plan::Algorithm::Coverage`],
//! milliseconds), no comparison or refinement run starts, and [`TeamPlan::cancelled`] says
//! so.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::building::Building;
use crate::gp::Kernel;
use crate::plan::{
    Algorithm, Control, Observer, PlanRequest, PlanResult, PlanSettings, Progress, SharedMetric,
    Termination, plan_with_prior_sharing,
};
use crate::samples::sample_walk;
use crate::utility::{Observation, UtilityEngine};
use crate::{Error, Result};

/// One surveyor's assignment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurveyorTask {
    pub start: String,
    pub end: String,
    pub budget: f64,
}

impl SurveyorTask {
    /// Parses `START:END:BUDGET`, or `START:BUDGET` for a walk back to its start (as
    /// `plan` without `--end`).
    pub fn parse(s: &str) -> Result<Self> {
        let parts: Vec<&str> = s.split(':').map(str::trim).collect();
        let bad = || {
            Error::InvalidRequest(format!(
                "surveyor {s:?}: expected START:END:BUDGET or START:BUDGET, for example \
                 b00:b10:120 or b00:120"
            ))
        };
        let (start, end, budget) = match parts[..] {
            [start, end, budget] => (start, end, budget),
            [start, budget] => (start, start, budget),
            _ => return Err(bad()),
        };
        if start.is_empty() || end.is_empty() {
            return Err(bad());
        }
        let budget: f64 = budget.parse().map_err(|_| bad())?;
        Ok(SurveyorTask {
            start: start.to_string(),
            end: end.to_string(),
            budget,
        })
    }
}

/// How a team is planned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TeamRequest {
    pub surveyors: Vec<SurveyorTask>,
    /// The kernel every walk is planned and valued with.
    pub kernel: Kernel,
    /// Planner settings shared by all surveyors (surveyor `i` uses the seed plus `i`).
    pub settings: PlanSettings,
    /// Plan each surveyor alone, ignoring the others (for comparison).
    pub independent: bool,
    /// Refinement rounds after planning in turn (0: in turn only).
    pub rounds: usize,
}

impl TeamRequest {
    /// The single-walk request of each surveyor, in order: its route, the shared settings
    /// and kernel, the seed offset by its index.
    pub fn requests(&self) -> Vec<PlanRequest> {
        self.surveyors
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let mut r = PlanRequest::with_settings(
                    &t.start,
                    &t.end,
                    t.budget,
                    self.kernel,
                    &self.settings,
                );
                r.settings.seed = self.settings.seed.wrapping_add(i as u64);
                r
            })
            .collect()
    }
}

/// The team's walks and what they are worth together.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TeamPlan {
    /// One plan per surveyor, in request order. Each `utility_nats` is the walk's own
    /// utility given the prior only (what it would be worth alone).
    pub plans: Vec<PlanResult>,
    /// `f_D` of all the surveyors' samples together, given the prior, nats.
    pub team_utility_nats: f64,
    /// Refinement rounds that changed at least one walk.
    pub rounds_used: usize,
    pub independent: bool,
    /// Whether the plan was cancelled: the walks are what it had then (see the module
    /// docs), each plan's `termination` says which were cut short.
    #[serde(default)]
    pub cancelled: bool,
}

/// Forwards a planner run's progress to the team plan's observer, the message prefixed
/// with the run's place in the team plan.
struct Labelled {
    inner: Arc<dyn Observer>,
    label: String,
}

impl Observer for Labelled {
    fn progress(&self, p: &Progress) {
        self.inner.progress(&Progress {
            message: format!("{}: {}", self.label, p.message),
            ..p.clone()
        });
    }
}

/// `control` with its progress reports labelled `label`.
fn labelled(control: &Control, label: String) -> Control {
    Control {
        observer: control.observer.as_ref().map(|o| {
            Arc::new(Labelled {
                inner: o.clone(),
                label,
            }) as Arc<dyn Observer>
        }),
        ..control.clone()
    }
}

fn observations(b: &Building, req: &PlanRequest, walk: &[usize]) -> Result<Vec<Observation>> {
    Ok(sample_walk(b, walk, &req.settings.model, &req.kernel)?
        .iter()
        .map(Observation::from)
        .collect())
}

/// `f_D` of all the walks' samples together, given the engine's prior.
fn team_utility_of(
    building: &Building,
    engine: &UtilityEngine,
    walks: &[Vec<usize>],
    request_for: &dyn Fn(usize) -> PlanRequest,
) -> Result<f64> {
    let mut all = Vec::new();
    for (i, w) in walks.iter().enumerate() {
        all.extend(observations(building, &request_for(i), w)?);
    }
    engine.utility_of_observations(&all)
}

/// Plans a team of surveyors.
///
/// # Arguments
/// * `building` - the building.
/// * `req` - the surveyors and the shared planner settings.
/// * `prior` - observations already collected (conditioning for every walk).
/// * `control` - cancel token and progress observer, shared by all the planner runs.
///
/// # Errors
/// An empty team, or any error of [`crate::plan::plan_with_prior`] for a surveyor (named by index).
/// The part of the building that holds every vertex any surveyor's walk can reach, for a
/// refusal for size: one walking distance around the first surveyor's start that holds
/// each surveyor's reach ([`crate::plan::reach_radius`] around their start, plus the way
/// to it), so the part is in one piece; empty when it would be every vertex.
fn team_part_hint(b: &Building, req: &TeamRequest) -> String {
    let Some(first) = req.surveyors.first().and_then(|t| b.vertex_index(&t.start)) else {
        return String::new();
    };
    let (from_first, _) = crate::plan::metric::shortest_path_tree(b, first);
    let mut radius = 0.0f64;
    for t in &req.surveyors {
        let (Some(s), Some(e)) = (b.vertex_index(&t.start), b.vertex_index(&t.end)) else {
            return String::new();
        };
        match crate::plan::reach_radius(b, s, e, t.budget, req.kernel.ell) {
            Some(r) => radius = radius.max((from_first[s] + r).ceil()),
            None => return String::new(),
        }
    }
    if from_first.iter().all(|&d| d <= radius) {
        return String::new();
    }
    format!(
        "; for the whole team, one part that holds every surveyor's walk: `--around {} --radius {radius}`",
        b.vertices[first].id
    )
}

pub fn plan_team(
    building: Arc<Building>,
    req: &TeamRequest,
    prior: &[Observation],
    control: &Control,
) -> Result<TeamPlan> {
    if req.surveyors.is_empty() {
        return Err(Error::InvalidRequest(
            "a team needs at least one surveyor".into(),
        ));
    }
    let requests = req.requests();
    let request_for = |i: usize| requests[i].clone();
    let name_err = |i: usize, e: Error| match e {
        Error::Cancelled => Error::Cancelled,
        // Kept as what it is, so that the app can offer the time it names.
        Error::TimeLimitTooShort { needed, message } => Error::TimeLimitTooShort {
            needed,
            message: format!("surveyor {} ({}): {message}", i + 1, req.surveyors[i].start),
        },
        other => {
            let mut message = format!("surveyor {} ({}): {other}", i + 1, req.surveyors[i].start);
            // A part that names one surveyor's reach would leave the others out.
            if message.contains("`--around ") {
                message.push_str(&team_part_hint(&building, req));
            }
            Error::InvalidRequest(message)
        }
    };
    // Every run gets the whole time limit of the shared settings: the clock starts
    // at each run, not at a start the caller may have set for one plan.
    let control = &Control {
        started: None,
        ..control.clone()
    };
    let k = req.surveyors.len();
    let engine =
        UtilityEngine::with_prior(building.clone(), req.kernel, req.settings.model, prior)?;
    // Every run plans on the same building: its metric closure is built once and kept.
    let shared = SharedMetric::default();
    let plan_with_prior = |b: Arc<Building>, r: &PlanRequest, cond: &[Observation], c: &Control| {
        plan_with_prior_sharing(b, r, cond, c, Some(&shared))
    };
    let mut walks: Vec<Vec<usize>> = Vec::with_capacity(k);
    let mut results: Vec<PlanResult> = Vec::with_capacity(k);
    for i in 0..k {
        let r = request_for(i);
        let mut cond = prior.to_vec();
        if !req.independent {
            for w in &walks {
                cond.extend(observations(&building, &r, w)?);
            }
        }
        let label = |what: &str| format!("surveyor {}/{k}, {what}", i + 1);
        if control.is_cancelled() {
            // Cancelled before this surveyor's turn: the systematic walk, on a control of
            // its own (the caller's is cancelled), so that every surveyor has a walk.
            let quick = Control {
                cancel: Arc::default(),
                ..labelled(control, label("cancelled: the systematic walk"))
            };
            let mut rq = r.clone();
            rq.settings.algorithm = Algorithm::Coverage;
            let mut res = plan_with_prior(building.clone(), &rq, &cond, &quick)
                .map_err(|e| name_err(i, e))?;
            res.termination = Termination::Cancelled;
            walks.push(res.walk_indices.clone());
            results.push(res);
            continue;
        }
        let what = if req.independent { "alone" } else { "in turn" };
        let res = plan_with_prior(building.clone(), &r, &cond, &labelled(control, label(what)))
            .map_err(|e| name_err(i, e))?;
        walks.push(res.walk_indices.clone());
        results.push(res);
        // A heuristic planner conditioned on the others can return a walk worth less to
        // the team than the walk it would plan alone (for example a shorter one); keep
        // whichever adds more, so that the team never does worse than in turn alone. The
        // first surveyor (nothing to condition on but the prior) was planned alone
        // already.
        if !req.independent && cond.len() > prior.len() && !control.is_cancelled() {
            let alone = plan_with_prior(
                building.clone(),
                &r,
                prior,
                &labelled(control, label("alone, for comparison")),
            )
            .map_err(|e| name_err(i, e))?;
            let mut trial = walks.clone();
            trial[i] = alone.walk_indices.clone();
            if team_utility_of(&building, &engine, &trial, &request_for)?
                > team_utility_of(&building, &engine, &walks, &request_for)?
            {
                walks[i] = alone.walk_indices.clone();
                results[i] = alone;
            }
        }
    }
    let team_utility =
        |walks: &[Vec<usize>]| team_utility_of(&building, &engine, walks, &request_for);
    let mut best = team_utility(&walks)?;
    let mut rounds_used = 0;
    if !req.independent {
        'rounds: for round in 0..req.rounds {
            let mut changed = false;
            for i in 0..k {
                if control.is_cancelled() {
                    break 'rounds;
                }
                let mut r = request_for(i);
                r.settings.seed = r.settings.seed.wrapping_add(1000 * (round as u64 + 1));
                let mut cond = prior.to_vec();
                for (j, w) in walks.iter().enumerate() {
                    if j != i {
                        cond.extend(observations(&building, &r, w)?);
                    }
                }
                let what = format!("surveyor {}/{k}, round {}", i + 1, round + 1);
                let res = plan_with_prior(building.clone(), &r, &cond, &labelled(control, what))
                    .map_err(|e| name_err(i, e))?;
                let mut trial = walks.clone();
                trial[i] = res.walk_indices.clone();
                let u = team_utility(&trial)?;
                if u > best + 1e-9 * best.abs() {
                    best = u;
                    walks = trial;
                    results[i] = res;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
            rounds_used += 1;
        }
    }
    // Report each walk's own utility given the prior only, so the numbers compare.
    for (res, walk) in results.iter_mut().zip(&walks) {
        res.utility_nats = engine.utility(walk)?;
    }
    Ok(TeamPlan {
        plans: results,
        team_utility_nats: best,
        rounds_used,
        independent: req.independent,
        cancelled: control.is_cancelled(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gp::Kernel;
    use crate::surveyor::Surveyor;

    fn area_two() -> Arc<Building> {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/area-two.json");
        Arc::new(Building::load(&path).expect("area-two"))
    }

    fn request(independent: bool) -> TeamRequest {
        // Genetic without a time limit: deterministic for a seed, whatever the machine.
        let mut settings = PlanSettings {
            algorithm: Algorithm::Genetic,
            model: Surveyor::robot_every(1.0),
            seed: 3,
            ..PlanSettings::default()
        };
        settings.params.population = 60;
        TeamRequest {
            surveyors: vec![
                SurveyorTask {
                    start: "b00".into(),
                    end: "b00".into(),
                    budget: 60.0,
                },
                SurveyorTask {
                    start: "b00".into(),
                    end: "b00".into(),
                    budget: 60.0,
                },
            ],
            kernel: Kernel::new(100.0, 10.0, 3.3),
            settings,
            independent,
            rounds: 1,
        }
    }

    #[test]
    fn a_team_collects_more_than_two_independent_plans() {
        let b = area_two();
        let team = plan_team(b.clone(), &request(false), &[], &Control::new()).expect("team");
        let alone = plan_team(b.clone(), &request(true), &[], &Control::new()).expect("alone");
        // Alone, both surveyors chase the same places near b00; as a team they split up.
        assert!(
            team.team_utility_nats > alone.team_utility_nats * 1.01,
            "team {} vs independent {}",
            team.team_utility_nats,
            alone.team_utility_nats
        );
        assert_ne!(team.plans[0].walk, team.plans[1].walk);
        for (p, t) in team.plans.iter().zip(&request(false).surveyors) {
            assert!(p.length_m <= t.budget + 1e-9);
            assert_eq!(p.walk.first(), Some(&t.start));
            assert_eq!(p.walk.last(), Some(&t.end));
        }
        // What holds (f_D is monotone but not submodular, so no upper bound by the sum of
        // the parts): the team is worth at least each member's walk alone, at least the
        // best single walk an independent plan found, and exactly the joint utility of all
        // its walks, as the reference evaluator computes it from the formula.
        for p in &team.plans {
            assert!(
                team.team_utility_nats >= p.utility_nats - 1e-9,
                "team {} below a member's {}",
                team.team_utility_nats,
                p.utility_nats
            );
        }
        let best_single = alone
            .plans
            .iter()
            .map(|p| p.utility_nats)
            .fold(0.0, f64::max);
        assert!(
            team.team_utility_nats >= best_single - 1e-9,
            "team {} below the best single plan {best_single}",
            team.team_utility_nats
        );
        let base = &request(false).requests()[0];
        let mut obs = crate::utility::reference::pilot_observations(&b.pilot_points());
        for p in &team.plans {
            let walk = b.resolve_walk(&p.walk).expect("walk");
            obs.extend(observations(&b, base, &walk).expect("samples"));
        }
        let joint =
            crate::utility::reference::reference_utility(&base.kernel, &b.vertex_points(), &obs)
                .expect("reference");
        assert!(
            (team.team_utility_nats - joint).abs() <= 1e-9 * joint.abs().max(1.0),
            "team {} vs joint reference {joint}",
            team.team_utility_nats
        );
    }

    /// Records every progress message of a team plan, and cancels it at the first whose
    /// message starts with `cancel_at`.
    struct Watch {
        seen: std::sync::Mutex<Vec<String>>,
        cancel_at: Option<&'static str>,
        token: Arc<std::sync::atomic::AtomicBool>,
    }

    impl Observer for Watch {
        fn progress(&self, p: &Progress) {
            if self.cancel_at.is_some_and(|c| p.message.starts_with(c)) {
                self.token.store(true, std::sync::atomic::Ordering::Relaxed);
            }
            self.seen.lock().expect("lock").push(p.message.clone());
        }
    }

    fn watched(cancel_at: Option<&'static str>) -> (Control, Arc<Watch>) {
        let control = Control::new();
        let watch = Arc::new(Watch {
            seen: std::sync::Mutex::new(Vec::new()),
            cancel_at,
            token: control.cancel_token(),
        });
        (control.with_observer(watch.clone()), watch)
    }

    /// What the caller's progress bar shows names the surveyor and the run; the first
    /// surveyor, conditioned on nothing but the prior, is not planned alone a second time.
    #[test]
    fn each_run_reports_which_surveyor_it_plans_and_the_first_is_planned_once() {
        let (control, watch) = watched(None);
        let team = plan_team(area_two(), &request(false), &[], &control).expect("team");
        assert!(!team.cancelled);
        let seen = watch.seen.lock().expect("lock");
        for run in [
            "surveyor 1/2, in turn: ",
            "surveyor 2/2, in turn: ",
            "surveyor 2/2, alone, for comparison: ",
            "surveyor 1/2, round 1: ",
        ] {
            assert!(
                seen.iter().any(|m| m.starts_with(run)),
                "no {run:?} in {seen:?}"
            );
        }
        assert!(
            !seen.iter().any(|m| m.starts_with("surveyor 1/2, alone")),
            "the first surveyor was planned alone again: {seen:?}"
        );
    }

    /// A cancel during the second surveyor's run: that run returns its best walk so far,
    /// the third surveyor gets the systematic walk, nothing else runs, and every surveyor
    /// has a walk of its route within its budget.
    #[test]
    fn a_cancelled_team_plan_returns_a_walk_for_every_surveyor() {
        let mut req = request(false);
        req.surveyors.push(SurveyorTask {
            start: "t29".into(),
            end: "t29".into(),
            budget: 60.0,
        });
        let (control, watch) = watched(Some("surveyor 2/3, in turn: "));
        let team = plan_team(area_two(), &req, &[], &control).expect("team");
        assert!(team.cancelled);
        assert_eq!(team.rounds_used, 0);
        assert_eq!(team.plans[0].termination, Termination::Completed);
        assert_eq!(team.plans[1].termination, Termination::Cancelled);
        assert_eq!(
            (team.plans[2].algorithm, team.plans[2].termination),
            (Algorithm::Coverage, Termination::Cancelled)
        );
        for (p, t) in team.plans.iter().zip(&req.surveyors) {
            assert!(p.length_m <= t.budget + 1e-9, "{} m", p.length_m);
            assert_eq!(p.walk.first(), Some(&t.start));
            assert_eq!(p.walk.last(), Some(&t.end));
            assert!(p.utility_nats > 0.0);
        }
        // The systematic walk is a walk, not the way from start to end: it uses the budget.
        assert!(
            team.plans[2].length_m > 0.9 * 60.0,
            "{} m",
            team.plans[2].length_m
        );
        let seen = watch.seen.lock().expect("lock");
        assert!(
            !seen
                .iter()
                .any(|m| m.contains("round") || m.starts_with("surveyor 2/3, alone")),
            "a run started after the cancel: {seen:?}"
        );
    }

    #[test]
    fn surveyor_specs_parse_with_clear_errors() {
        let t = SurveyorTask::parse("b00:b10:120").expect("ok");
        assert_eq!(
            (t.start.as_str(), t.end.as_str(), t.budget),
            ("b00", "b10", 120.0)
        );
        // Without an end, the walk returns to its start.
        let t = SurveyorTask::parse("b00:120").expect("ok");
        assert_eq!(
            (t.start.as_str(), t.end.as_str(), t.budget),
            ("b00", "b00", 120.0)
        );
        for bad in ["b00", "b00:b10:x", ":120", "b00::120", "a:b:c:120"] {
            let e = SurveyorTask::parse(bad).expect_err(bad).to_string();
            assert!(
                e.contains("expected START:END:BUDGET or START:BUDGET"),
                "{bad}: {e}"
            );
        }
        let mut req = request(false);
        req.surveyors[1].start = "nope".into();
        let e = plan_team(area_two(), &req, &[], &Control::new())
            .expect_err("unknown")
            .to_string();
        assert!(e.starts_with("surveyor 2 (nope): "), "{e}");
    }
}
