//! Planners: walks from `v_s` to `v_t` within a budget that maximise the utility `f_D(P)`
//! of SPEC section 3.
//!
//! # Layout (argmin style)
//! This file holds the dispatch: [`validate`], [`plan`] / [`plan_with_prior`], the memory
//! estimate and [`solver_for`]. What a caller sends and gets back is in `request.rs`
//! ([`PlanRequest`], [`PlanSettings`], [`Algorithm`], [`PlanResult`]), the run state in
//! `run.rs` ([`Run`], [`Control`], [`Progress`]), the instance in `problem.rs`.
//! * The **problem** ([`Problem`]) holds the building, the fast [`UtilityEngine`], the
//!   metric closure ([`metric::Metric`]) and the request's start, end and budget.
//! * Each **solver** is a type implementing [`Solver`] in its own file: [`greedy`] (the
//!   paper's Algorithm 1), [`genetic`] (paper IV-B), [`recursive_greedy`] (Chekuri and Pal),
//!   [`ero`] (edge-based random orienteering), [`exact`] (branch and bound) and [`auto`]
//!   (ours, the default).
//! * The **run state** ([`Run`]) carries the caller's [`Control`] (cancel token, progress
//!   observer), the deadline from the time limit and the seeded random generator is
//!   created by each solver from [`PlanSettings::seed`] (`ChaCha8Rng::seed_from_u64`).
//! * **Termination** is an enum ([`Termination`]): completed, proved optimal, time limit,
//!   cancelled. Solvers [`offer`](Run::offer) their best walk as they go, so a plan that
//!   is cancelled (or a solver that runs out of time deep inside a step) returns the best
//!   walk so far, `termination: cancelled`, never nothing.
//!
//! Every returned walk follows real edges, starts at `v_s`, ends at `v_t` and satisfies
//! `C(P) <= B + BUDGET_EPS` (1e-9 m); [`plan`] checks this before returning.

pub mod auto;
#[cfg(feature = "research")]
pub mod bench;
pub mod coverage;
pub mod ero;
pub mod exact;
pub mod genetic;
pub mod greedy;
pub mod local_search;
pub mod metric;
mod problem;
pub mod recursive_greedy;
mod request;
mod run;
pub mod scale;
pub mod steiner;
pub mod surrogate;

use std::sync::Arc;

use crate::building::Building;
use crate::samples::sample_walk;
use crate::utility::UtilityEngine;
use crate::{Error, Result};

pub use metric::{Metric, SharedMetric};
pub use problem::{Outcome, Problem};
pub use request::*;
pub use run::{Control, NoObserver, Observer, Progress, Run};

/// Feasibility tolerance of SPEC section 3: a walk fits when `C(P) <= B + BUDGET_EPS`.
pub const BUDGET_EPS: f64 = 1e-9;

/// A planning algorithm.
pub trait Solver {
    /// Which algorithm this is.
    fn algorithm(&self) -> Algorithm;

    /// Plans on `problem`. Returns the best walk found; [`Error::Cancelled`] if `run` was
    /// cancelled.
    fn solve(&self, problem: &Problem, run: &Run) -> Result<Outcome>;
}

/// The solver for a request's algorithm, seed and parameters.
pub fn solver_for(
    algorithm: Algorithm,
    seed: u64,
    params: &Params,
) -> Box<dyn Solver + Send + Sync> {
    match algorithm {
        Algorithm::Greedy => Box::new(greedy::Greedy::paper()),
        Algorithm::Genetic => Box::new(genetic::Genetic::new(*params, seed)),
        Algorithm::RecursiveGreedy => Box::new(recursive_greedy::RecursiveGreedy::new(
            params.depth,
            params.budget_step,
        )),
        Algorithm::Ero => Box::new(ero::Ero::new(params.iterations, seed)),
        Algorithm::Exact => Box::new(exact::Exact::new()),
        Algorithm::Auto => Box::new(auto::Auto::new(*params, seed)),
        Algorithm::Coverage => Box::new(coverage::Coverage),
    }
}

/// A number of metres as a person typed it: `100000`, `-5`, and `1e308` rather than its
/// 309 digits (`{}` writes every digit of a large float, `{:?}` adds `.0` to whole ones).
fn metres_as_typed(x: f64) -> String {
    if x.abs() < 1e15 {
        x.to_string()
    } else {
        format!("{x:e}")
    }
}

/// Checks a request against a building and resolves its end points.
///
/// # Errors
/// One clear [`Error`] per problem: an unknown vertex ([`Error::InvalidRequest`] naming
/// it), a budget that is not a positive finite number, invalid kernel or model or
/// parameters, or an end that cannot be reached within the budget ([`Error::Unreachable`]
/// with the shortest distance).
pub fn validate(building: &Building, req: &PlanRequest) -> Result<(usize, usize)> {
    let start = building
        .require_vertex(&req.start)
        .map_err(|e| Error::InvalidRequest(format!("start: {e}")))?;
    let end = building
        .require_vertex(&req.end)
        .map_err(|e| Error::InvalidRequest(format!("end: {e}")))?;
    if !req.budget.is_finite() || req.budget <= 0.0 {
        return Err(Error::InvalidRequest(format!(
            "budget must be a positive finite number of metres, got {}",
            metres_as_typed(req.budget)
        )));
    }
    let total = building.total_edge_length();
    if req.budget > MAX_BUDGET_FACTOR * total + BUDGET_EPS {
        return Err(Error::InvalidRequest(format!(
            "budget {} m is more than {MAX_BUDGET_FACTOR} times the {total:.1} m of edges of \
             {:?}: a walk that long only repeats what it has walked; ask for at most {:.1} m \
             (a budget of {total:.1} m or more lets a planner walk every edge)",
            metres_as_typed(req.budget),
            building.name,
            MAX_BUDGET_FACTOR * total
        )));
    }
    if req.settings.memory_budget == 0 {
        return Err(Error::InvalidRequest(
            "memory budget must be a positive number of bytes".into(),
        ));
    }
    req.kernel.validate("kernel")?;
    req.settings.model.validate()?;
    let p = &req.settings.params;
    let bad = |m: String| Err(Error::InvalidRequest(m));
    if p.population < 2 {
        return bad(format!(
            "population must be at least 2, got {}",
            p.population
        ));
    }
    if p.tournament < 1 {
        return bad(format!(
            "tournament must be at least 1, got {}",
            p.tournament
        ));
    }
    if !(0.0..=1.0).contains(&p.mutation) {
        return bad(format!(
            "mutation must be a probability in [0, 1], got {}",
            p.mutation
        ));
    }
    if p.population > MAX_POPULATION {
        return bad(format!(
            "population must be at most {MAX_POPULATION}, got {}",
            p.population
        ));
    }
    if p.generations > MAX_GENERATIONS {
        return bad(format!(
            "generations must be at most {MAX_GENERATIONS}, got {}",
            p.generations
        ));
    }
    if p.depth > 5 {
        return bad(format!("depth must be at most 5, got {}", p.depth));
    }
    if !p.budget_step.is_finite() || p.budget_step < 0.0 {
        return bad(format!(
            "budget step must be a non-negative number of metres, got {}",
            p.budget_step
        ));
    }
    Ok((start, end))
}

/// Plans a walk.
///
/// # Arguments
/// * `building` - the building (shared with the engine).
/// * `req` - start, end, budget, model, kernel, algorithm, seed, time limit, parameters.
/// * `control` - cancel token and progress observer.
///
/// # Returns
/// The walk and its figures. With a time limit the best walk found so far is returned
/// when the limit is reached (`termination: time_limit`).
///
/// # Errors
/// See [`validate`]; [`Error::Cancelled`] when cancelled through `control`.
pub fn plan(building: Arc<Building>, req: &PlanRequest, control: &Control) -> Result<PlanResult> {
    plan_with_prior(building, req, &[], control)
}

/// Plans a walk whose utility is conditioned on the pilot data plus `prior`
/// observations: samples already collected (replanning a survey in progress) or the walks
/// of other surveyors (team planning). The utility reported is then `f_{D + prior}(P)`:
/// SPEC section 3 with `S = R(P) ∪ D ∪ prior`, so it counts what the prior already knows;
/// what the walk adds on top is that minus [`UtilityEngine::prior_utility`] of an engine
/// built with the same prior.
pub fn plan_with_prior(
    building: Arc<Building>,
    req: &PlanRequest,
    prior: &[crate::utility::Observation],
    control: &Control,
) -> Result<PlanResult> {
    plan_with_prior_sharing(building, req, prior, control, None)
}

/// [`plan_with_prior`], taking the building's metric closure from `shared` when it holds
/// that building's (and leaving it there for the next plan): what a session's replanner
/// does between its replans.
pub fn plan_with_prior_sharing(
    building: Arc<Building>,
    req: &PlanRequest,
    prior: &[crate::utility::Observation],
    control: &Control,
    shared: Option<&SharedMetric>,
) -> Result<PlanResult> {
    // The clock starts now, or earlier where the caller says so (loading the building,
    // fitting the kernel): set-up (shortest paths, the engine) counts against the limit.
    let started = control.clock_start();
    let (start, end) = validate(&building, req)?;
    let threads = check_memory(&building, req, (start, end), prior.len())?;
    if threads < rayon::current_num_threads() {
        // Fewer threads evaluate fewer walks at once: a device with many cores plans
        // what one core could within the memory budget, rather than refusing it.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| Error::InvalidRequest(format!("{threads} planning threads: {e}")))?;
        return pool.install(|| {
            plan_validated(building, req, prior, control, started, (start, end), shared)
        });
    }
    plan_validated(building, req, prior, control, started, (start, end), shared)
}

/// [`plan_with_prior`] once the request is valid and its memory affordable.
fn plan_validated(
    building: Arc<Building>,
    req: &PlanRequest,
    prior: &[crate::utility::Observation],
    control: &Control,
    started: std::time::Instant,
    (start, end): (usize, usize),
    shared: Option<&SharedMetric>,
) -> Result<PlanResult> {
    let run = Run::starting_at(control.clone(), req.effective_time_limit(), started)
        .for_algorithm(req.settings.algorithm);
    let metric = match shared {
        Some(s) => s.for_building(&building),
        None => Arc::new(Metric::new(&building)),
    };
    let shortest = metric.dist(start, end);
    if !shortest.is_finite() || shortest > req.budget + BUDGET_EPS {
        return Err(Error::Unreachable {
            start: req.start.clone(),
            end: req.end.clone(),
            budget: req.budget,
            shortest,
        });
    }
    let engine =
        UtilityEngine::with_prior(building.clone(), req.kernel, req.settings.model, prior)?;
    let headroom =
        req.settings
            .memory_budget
            .saturating_sub(estimate_memory(&building, req, prior.len()))
            / 8;
    let problem = Problem {
        building: building.clone(),
        engine,
        metric,
        start,
        end,
        budget: req.budget,
        near: Arc::default(),
        order: Arc::default(),
        exact_cost: Arc::default(),
        near_base_max: usize::try_from(headroom)
            .unwrap_or(usize::MAX)
            .min(crate::utility::engine::NEAR_BASE_MAX),
    };
    let solver = solver_for(
        req.settings.algorithm,
        req.settings.seed,
        &req.settings.params,
    );
    let held = held_walk(&problem, &run, req.settings.algorithm)?;
    let out = match solver.solve(&problem, &run) {
        Ok(mut out) => {
            if run.control.is_cancelled() {
                out.termination = Termination::Cancelled;
            }
            out
        }
        Err(Error::Cancelled) => best_so_far(&problem, &run, Termination::Cancelled)?,
        Err(e) => return Err(e),
    };
    // A baseline stopped early returns the better of its own walk and the one it held.
    let out = match held {
        Some(h)
            if matches!(
                out.termination,
                Termination::TimeLimit | Termination::Cancelled
            ) && h.utility > out.utility =>
        {
            Outcome {
                walk: h.walk,
                utility: h.utility,
                ..out
            }
        }
        _ => out,
    };
    finish(&problem, req, out, &run)
}

/// Largest share of the time limit that evaluating the held walk of [`held_walk`] may
/// take; where it would take more (a walk of thousands of robot samples on a slow
/// device), the baseline runs without one.
const HELD_SHARE: f64 = 0.5;

/// The walk a baseline planner (greedy, genetic, recursive greedy, ERO, branch and bound)
/// holds from its start, so that it is anytime like `auto` (issue 13): the systematic
/// walk of [`coverage`], evaluated exactly before the solver starts. A plan stopped by its
/// time limit or a cancel returns it when it is worth more than the solver's own best
/// walk; a solver that completes returns its own walk, as the paper defines it, even where
/// the systematic walk is worth more (greedy on large buildings, ERO on Area One at 30 m).
/// So the held walk is not offered to `run`: progress reports the solver's own best walk,
/// which a completed plan returns, and never more than a stopped one returns.
/// `auto` and `coverage` hold their own walks (`None`), and so does a run whose limit
/// the evaluation would take more than [`HELD_SHARE`] of (timed as `auto` times its
/// deferred evaluation), or whose set-up has left less time than it takes: huge-3k's
/// person on 3,116 m with a 1 s limit spends 0.8 s on the metric closure and the
/// engine, and the held walk's 0.3 s evaluation after them brought greedy, genetic and
/// ERO back after 1.45 to 1.49 s.
fn held_walk(problem: &Problem, run: &Run, algorithm: Algorithm) -> Result<Option<Outcome>> {
    if matches!(algorithm, Algorithm::Auto | Algorithm::Coverage) {
        return Ok(None);
    }
    let walk = coverage::systematic_walk(problem, run);
    if let Some(limit) = run.time_limit()
        && let Some((time, _)) = scale::exact_time_estimate(problem, &walk, limit)?
        && (time.as_secs_f64() > HELD_SHARE * limit.as_secs_f64()
            || run
                .deadline()
                .is_some_and(|d| std::time::Instant::now() + time > d))
    {
        return Ok(None);
    }
    let utility = problem.utility(&walk)?;
    Ok(Some(Outcome::new(walk, utility, Termination::Completed)))
}

/// The run's best offered walk, else the shortest walk from the start to the end (the
/// answer of a plan stopped before any solver offered one).
fn best_so_far(problem: &Problem, run: &Run, termination: Termination) -> Result<Outcome> {
    if let Some((walk, utility)) = run.incumbent() {
        return Ok(Outcome::new(walk, utility, termination));
    }
    let walk = problem.shortest_walk();
    let utility = problem.utility(&walk)?;
    Ok(Outcome::new(walk, utility, termination))
}

/// Estimated peak working set of planning `req` on `building` with `prior` extra
/// observations, in bytes: the shortest-path table (12 bytes per vertex pair), the engine's
/// vertex covariance and its factor (two `|V| x |V|` matrices, the covariance not kept on
/// floors of more than 1,024 vertices; a third, the posterior of the pilot data, for the
/// planners that grow walks incrementally), the pilot rows, and
/// per planning thread one dense matrix of `[pilot + prior, samples of a full-budget walk,
/// vertices]` plus the incremental rows of such a walk (and, for recursive greedy, the
/// posterior covariances of the partial walks it holds).
pub fn estimate_memory(building: &Building, req: &PlanRequest, prior: usize) -> u64 {
    estimate_memory_with(building, req, prior, rayon::current_num_threads())
}

/// [`estimate_memory`] with `threads` planning threads.
fn estimate_memory_with(
    building: &Building,
    req: &PlanRequest,
    prior: usize,
    threads: usize,
) -> u64 {
    let nv = building.len() as f64;
    let nd = (building.pilot.len() + prior) as f64;
    let budget = if req.budget.is_finite() {
        req.budget
    } else {
        0.0
    };
    let ns = budget / req.settings.model.spacing().max(1e-3) + 2.0;
    let metric = 12.0 * nv * nv;
    let n = nd + ns + nv + 16.0;
    let threads = threads.max(1) as f64;
    // The large-building search (auto and coverage beyond `auto::LARGE_VERTICES`) only
    // evaluates whole walks; the other planners also grow walks incrementally (rows of
    // `L` and `W` per sample, from the engine's posterior of the pilot data).
    let whole_walks = matches!(
        req.settings.algorithm,
        Algorithm::Auto | Algorithm::Coverage
    ) && building.len() > auto::LARGE_VERTICES;
    let vertex_matrices = if whole_walks { 2.0 } else { 3.0 };
    let engine = 8.0
        * (vertex_matrices * nv * nv - crate::utility::unkept_covariance(building)
            + nd * nd
            + 2.0 * nd * nv);
    let incremental = if whole_walks {
        0.0
    } else {
        2.0 * ns * (nd + ns + nv)
    };
    // Branch and bound keeps a saved posterior (`|V| x |V|`) per level of its depth-first
    // search, one level per edge of the deepest walk.
    let min_edge = building
        .edges
        .iter()
        .map(|e| e.length)
        .fold(f64::INFINITY, f64::min)
        .max(1e-3);
    let marks = if req.settings.algorithm == Algorithm::Exact {
        (budget / min_edge).min(1e6) * nv * nv
    } else {
        0.0
    };
    // Recursive greedy holds engine states of partial walks ([`crate::utility::WalkState`]),
    // each with a posterior covariance of the vertices: per thread one for each level of
    // its recursion, one being scored and the scratch copy its score factorises, besides
    // the root state they are cloned from (measured: 620 MiB on the generated 3,161-vertex
    // floor, person, 3,116 m, where the estimate without them was 508 MiB).
    let walk_states = if req.settings.algorithm == Algorithm::RecursiveGreedy {
        (req.settings.params.depth + 2) as f64 * nv * nv
    } else {
        0.0
    };
    let per_thread = 8.0 * (n * n + incremental + marks + walk_states);
    // The large-building search's exact phase keeps its walk's factorisation, at most
    // NEAR_BASE_MAX doubles ([`crate::utility::NearBase`]).
    let near_base = if whole_walks {
        8.0 * (n * n).min(crate::utility::engine::NEAR_BASE_MAX as f64)
    } else {
        0.0
    };
    // A fixed allowance for the process, the building and the search's own tables.
    let fixed = 16.0 * 1024.0 * 1024.0;
    let root_state = if walk_states > 0.0 {
        8.0 * nv * nv
    } else {
        0.0
    };
    (metric + engine + root_state + near_base + threads * per_thread + fixed).min(u64::MAX as f64)
        as u64
}

/// The number of planning threads whose estimated working set fits the request's memory
/// budget (each thread may hold a walk's matrix, so the estimate grows with them): all of
/// the current pool's where they fit, else fewer. Refuses the request when even one
/// thread does not fit. (On eight threads the 565-vertex mall, robot 2,036 m, was
/// refused at 1,359 MiB; one thread plans it in 190 MiB.)
fn check_memory(
    building: &Building,
    req: &PlanRequest,
    (start, end): (usize, usize),
    prior: usize,
) -> Result<usize> {
    let threads = rayon::current_num_threads().max(1);
    if let Some(k) = (1..=threads)
        .rev()
        .find(|&k| estimate_memory_with(building, req, prior, k) <= req.settings.memory_budget)
    {
        return Ok(k);
    }
    let need = estimate_memory_with(building, req, prior, 1);
    let mib = |b: u64| b.div_ceil(1 << 20);
    let shorter = match budget_that_fits(building, req, prior) {
        Some(b) if b >= metric::shortest_path_tree(building, end).0[start] => {
            format!("a budget of at most {b:.0} m fits")
        }
        Some(_) => "no walk from the start to the end fits".into(),
        None => format!(
            "no budget fits: the building's tables alone need about {} MiB",
            mib(estimate_memory_with(
                building,
                &PlanRequest {
                    budget: 0.0,
                    ..req.clone()
                },
                prior,
                1
            ))
        ),
    };
    Err(Error::InvalidRequest(format!(
        "planning on {:?} ({} vertices, budget {} m) needs about {} MiB, more than the memory \
         budget of {} MiB: the vertex covariance and the shortest-path table grow with the \
         square of the vertex count and a walk's matrix with its samples; plan one floor or \
         part of the building ({}), use a shorter budget ({shorter}) or a sparser sample \
         interval, or raise the memory budget (--memory-budget MIB, \
         PlanRequest.memory_budget) if the device has {} MiB to spare",
        building.name,
        building.len(),
        req.budget,
        mib(need),
        mib(req.settings.memory_budget),
        part_hint(building, start, end, req.budget, req.kernel.ell),
        mib(need)
    )))
}

/// The longest budget, to the metre below, whose plan of `req` fits its memory budget on
/// one thread ([`estimate_memory_with`] grows with the budget); `None` when not even a
/// walk of no length does (the vertex tables alone are too large).
fn budget_that_fits(building: &Building, req: &PlanRequest, prior: usize) -> Option<f64> {
    let fits = |budget: f64| {
        let r = PlanRequest {
            budget,
            ..req.clone()
        };
        estimate_memory_with(building, &r, prior, 1) <= req.settings.memory_budget
    };
    if !fits(0.0) {
        return None;
    }
    let (mut lo, mut hi) = (0.0, req.budget);
    while hi - lo > 0.5 {
        let mid = 0.5 * (lo + hi);
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo.floor())
}

/// The walking distance from `start` that holds every vertex a walk from `start` to `end`
/// within `budget` metres can reach, and two length scales `ell` more; `None` when that
/// is every vertex of `b`. Such a vertex `v` has `d(start, v) + d(v, end) <= budget`, and
/// since `d(start, end) <= d(start, v) + d(v, end)`, it lies within `(budget + d(start,
/// end)) / 2` of `start`; two length scales more keep the vertices its samples still tell
/// about (correlation `e^-2` there), so that a part's plan is the whole building's but
/// for what lies further away.
pub(crate) fn reach_radius(
    b: &Building,
    start: usize,
    end: usize,
    budget: f64,
    ell: f64,
) -> Option<f64> {
    let (d, _) = metric::shortest_path_tree(b, start);
    let radius = ((budget + d[end]) / 2.0 + 2.0 * ell).ceil();
    (!d.iter().all(|&x| x <= radius)).then_some(radius)
}

/// How to cut out a part of a building to plan instead (`Building::part`), for the
/// messages of a request refused for its size ([`reach_radius`]).
pub(crate) fn part_hint(b: &Building, start: usize, end: usize, budget: f64, ell: f64) -> String {
    let floor = "`trailprint export BUILDING --floor ID -o part.json` writes one floor";
    match reach_radius(b, start, end, budget, ell) {
        // The part around the start would be the whole building (or the part this is).
        None => format!("{floor}; this walk can reach every vertex of this one"),
        Some(radius) => format!(
            "{floor}; `--around {} --radius {radius}` keeps every vertex this walk can reach \
             and two length scales around them",
            b.vertices[start].id
        ),
    }
}

/// Checks an outcome and dresses it as a result.
fn finish(problem: &Problem, req: &PlanRequest, out: Outcome, run: &Run) -> Result<PlanResult> {
    problem.check(&out.walk).map_err(|e| {
        Error::Numerical(format!(
            "internal error: {} returned an infeasible walk: {e}",
            req.settings.algorithm
        ))
    })?;
    let b = &problem.building;
    let samples = sample_walk(b, &out.walk, &req.settings.model, &req.kernel)?.len();
    // The last report is the result itself, so that "best so far" ends at what is returned.
    problem.offer(run, &out.walk, out.utility);
    run.report(
        req.settings.algorithm,
        1.0,
        Some(out.utility),
        "done".into(),
    );
    Ok(PlanResult {
        algorithm: req.settings.algorithm,
        walk: b.walk_ids(&out.walk),
        length_m: problem.length(&out.walk),
        budget_m: req.budget,
        samples,
        utility_nats: out.utility,
        elapsed_ms: run.elapsed().as_millis() as u64,
        seed: req.settings.seed,
        kernel: req.kernel,
        optimal: out.optimal,
        nodes: out.nodes,
        termination: out.termination,
        walk_indices: out.walk,
    })
}

/// Keeps the better of two (walk, utility) pairs; ties go to the shorter, then the
/// lexicographically smaller walk, so that parallel searches stay deterministic.
pub(crate) fn better(a: (&[usize], f64), b: (&[usize], f64)) -> bool {
    // true if a is better than b
    if a.1 != b.1 {
        return a.1 > b.1;
    }
    if a.0.len() != b.0.len() {
        return a.0.len() < b.0.len();
    }
    a.0 < b.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::scale::tests::grid_problem;
    use std::time::{Duration, Instant};

    /// A baseline holds the systematic walk when its evaluation fits in the time left,
    /// and not when the set-up has used the limit up (the evaluation would end past the
    /// deadline and the plan with it).
    #[test]
    fn the_held_walk_is_evaluated_only_when_it_ends_before_the_deadline() {
        let p = grid_problem(300.0);
        let limit = Some(Duration::from_millis(100));
        let fresh = Run::new(Control::new(), limit);
        let held = held_walk(&p, &fresh, Algorithm::Greedy).expect("held");
        let h = held.expect("a walk is held when there is time");
        assert_eq!(h.walk, coverage::systematic_walk(&p, &fresh));
        assert_eq!(h.utility, p.utility(&h.walk).expect("utility"));
        let late = Instant::now()
            .checked_sub(Duration::from_secs(1))
            .expect("a second ago");
        let spent = Run::starting_at(Control::new(), limit, late);
        assert!(
            held_walk(&p, &spent, Algorithm::Greedy)
                .expect("held")
                .is_none()
        );
        // Without a limit the walk is always held; auto never holds one.
        let free = Run::new(Control::new(), None);
        assert!(
            held_walk(&p, &free, Algorithm::Greedy)
                .expect("held")
                .is_some()
        );
        assert!(
            held_walk(&p, &free, Algorithm::Auto)
                .expect("held")
                .is_none()
        );
    }
}
