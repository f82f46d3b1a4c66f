//! Planning at building scale (issue 13): the `coverage` baseline, `auto` on generated
//! buildings of hundreds of vertices, time limits, memory budgets, progress, reversals.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::plan_common::line_json as line_of;
use trailprint::Error;
use trailprint::building::Building;
use trailprint::gp::{Kernel, fit_kernel};
use trailprint::plan::coverage::reversals;
use trailprint::plan::{
    Algorithm, Control, Observer, PlanRequest, PlanResult, Problem, Progress, Termination, plan,
};
use trailprint::surveyor::Surveyor;
use trailprint::synth::{SynthParams, generate};
use trailprint::utility::UtilityEngine;

/// A generated office floor: 125 vertices, 402 m of edges.
fn office() -> (Arc<Building>, Kernel) {
    generated(SynthParams {
        name: "office".into(),
        rooms_per_side: 4,
        corridor_length_m: 40.0,
        room_depth_m: 8.0,
        ..SynthParams::default()
    })
}

/// The building `trailprint generate` makes with `params`, and the kernel fitted on its
/// pilot data (as the command line does for a file without a kernel).
fn generated(params: SynthParams) -> (Arc<Building>, Kernel) {
    let synth = generate(&params).expect("generate");
    let b = Arc::new(Building::from_file(synth.file, &params.name).expect("valid"));
    let k = fit_kernel(&b.pilot).expect("fit").kernel;
    (b, k)
}

/// A line of `n` vertices 1 m apart with one pilot point, as a file's text.
fn line_json(n: usize) -> String {
    line_of(n, r#"[{"x":0,"y":0,"rss":{"a":-50}}]"#)
}

fn line(n: usize) -> Arc<Building> {
    Arc::new(Building::from_json(&line_json(n), "line").expect("valid"))
}

/// A walk from the first vertex of `b` back to it within `budget` metres, kernel `k`.
fn round_trip(b: &Building, budget: f64, k: Kernel) -> PlanRequest {
    let start = &b.vertices[0].id;
    PlanRequest::new(start, start, budget, k)
}

/// The [`office`] and a [`round_trip`] on it with half its total edge length as budget.
fn office_half_round_trip() -> (Arc<Building>, PlanRequest) {
    let (b, k) = office();
    let req = round_trip(&b, 0.5 * b.total_edge_length(), k);
    (b, req)
}

/// The exact `f_D` of SPEC 3 of `walk`, by a fresh engine with the kernel and surveyor of
/// `req`.
fn exact_utility(b: &Arc<Building>, req: &PlanRequest, walk: &[usize]) -> f64 {
    UtilityEngine::new(b.clone(), req.kernel, req.settings.model)
        .expect("engine")
        .utility(walk)
        .expect("utility")
}

fn kernel() -> Kernel {
    Kernel {
        sf2: 40.0,
        ell: 6.0,
        sn2: 2.0,
    }
}

#[test]
fn coverage_walks_to_the_nearest_unwalked_edge_while_the_way_back_fits() {
    let _serial = crate::serial();
    // a line v0..v4, 1 m edges, closed walk from v0 with 6 m: v0-v1, v1-v2, v2-v3 fit with
    // the way back (6 m); v3-v4 would need 8 m.
    let b = line(5);
    let mut req = PlanRequest::new("v0", "v0", 6.0, kernel());
    req.settings.algorithm = Algorithm::Coverage;
    let r = plan(b.clone(), &req, &Control::new()).expect("plan");
    assert_eq!(r.walk, ["v0", "v1", "v2", "v3", "v2", "v1", "v0"]);
    assert_eq!(r.termination, Termination::Completed);
    let exact = exact_utility(&b, &req, &r.walk_indices);
    assert!((exact - r.utility_nats).abs() <= 1e-12 * exact);
}

#[test]
fn auto_on_a_large_building_uses_the_budget_and_beats_the_systematic_walk() {
    let _serial = crate::serial();
    let (b, mut req) = office_half_round_trip();
    let budget = req.budget;
    req.settings.algorithm = Algorithm::Coverage;
    let cov = plan(b.clone(), &req, &Control::new()).expect("coverage");
    req.settings.algorithm = Algorithm::Auto;
    let auto = plan(b.clone(), &req, &Control::new()).expect("auto");
    assert!(
        auto.length_m >= 0.95 * budget && auto.length_m <= budget + 1e-9,
        "auto walks {} m of {budget} m",
        auto.length_m
    );
    // What auto reports is the exact f_D of SPEC 3, not its search surrogate.
    assert_exact_and_at_least(&b, &req, &auto, cov.utility_nats, "auto");
}

/// A robot on a small tree-shaped floor (77 vertices, 76 edges, rooms off one corridor),
/// between two corridor vertices, with a budget of all 158 m of its edges: a building of
/// at most 100 vertices takes `auto`'s small-building portfolio, which alone reached only
/// 1.041x the systematic walk here (sweep 47 of `scripts/sweep_generated.py`).
#[test]
fn auto_on_a_small_floor_beats_the_systematic_walk_for_a_robot_too() {
    let _serial = crate::serial();
    let (b, k) = generated(SynthParams {
        name: "tree".into(),
        rooms_per_side: 8,
        corridor_length_m: 24.0,
        room_depth_m: 8.0,
        grid_spacing_m: 3.0,
        aps: 2,
        pilot: 20,
        seed: 642,
        ..SynthParams::default()
    });
    assert!(b.len() <= trailprint::plan::auto::LARGE_VERTICES);
    let mut req = PlanRequest::new("f0-c10", "f0-c09", 158.0, k);
    req.settings.model = Surveyor::robot();
    // Seed 1: the portfolio alone gave 59.82 nats for it, 1.05x is 60.33.
    req.settings.seed = 1;
    req.settings.algorithm = Algorithm::Coverage;
    let cov = plan(b.clone(), &req, &Control::new()).expect("coverage");
    req.settings.algorithm = Algorithm::Auto;
    let auto = plan(b.clone(), &req, &Control::new()).expect("auto");
    assert_exact_and_at_least(&b, &req, &auto, 1.05 * cov.utility_nats, "auto");
    assert!(
        auto.length_m >= 0.95 * 158.0,
        "auto walks {} m",
        auto.length_m
    );
}

/// `r` reports the exact `f_D` of its walk, and that is at least `floor` nats (the
/// systematic walk's).
fn assert_exact_and_at_least(
    b: &Arc<Building>,
    req: &PlanRequest,
    r: &PlanResult,
    floor: f64,
    what: &str,
) {
    assert!(
        r.utility_nats >= floor,
        "{what}: {} nats, the systematic walk {floor}",
        r.utility_nats
    );
    let exact = exact_utility(b, req, &r.walk_indices);
    assert!((exact - r.utility_nats).abs() <= 1e-9 * exact, "{what}");
}

#[test]
fn every_algorithm_honours_its_time_limit_on_a_large_building() {
    let _serial = crate::serial();
    let (b, k) = office();
    let limit = Duration::from_millis(800);
    for alg in Algorithm::ALL {
        let mut req = round_trip(&b, 200.0, k);
        req.settings.algorithm = alg;
        req.settings.time_limit = Some(limit);
        let t0 = Instant::now();
        let r = plan(b.clone(), &req, &Control::new()).expect("plan");
        let took = t0.elapsed();
        // The target is the limit + max(10%, 0.2 s) on an idle core (the benchmark's
        // figures); a test shares the machine, so it allows 0.6 s more.
        assert!(
            took <= limit + Duration::from_millis(800),
            "{alg} took {took:?} with a limit of {limit:?}"
        );
        assert!(r.length_m <= 200.0 + 1e-9);
    }
}

/// Every planner is anytime, not only auto (issue 13): a baseline stopped by its time limit
/// or a cancel returns at least the systematic walk it holds from its start, so greedy on
/// a building of hundreds of vertices no longer answers a short limit with the few metres
/// of its first rounds. One that completes returns its own walk, as the paper defines it.
#[test]
fn a_baseline_stopped_early_returns_at_least_the_systematic_walk() {
    let _serial = crate::serial();
    let (b, k) = office();
    let budget = 200.0;
    let mut req = round_trip(&b, budget, k);
    req.settings.algorithm = Algorithm::Coverage;
    let cov = plan(b.clone(), &req, &Control::new()).expect("coverage");
    let mut stopped = Vec::new();
    for alg in [
        Algorithm::Greedy,
        Algorithm::RecursiveGreedy,
        Algorithm::Genetic,
        Algorithm::Ero,
        Algorithm::Exact,
    ] {
        req.settings.algorithm = alg;
        req.settings.time_limit = Some(Duration::from_millis(150));
        let r = plan(b.clone(), &req, &Control::new()).expect("plan");
        if r.termination == Termination::TimeLimit {
            stopped.push(alg);
            assert_exact_and_at_least(&b, &req, &r, cov.utility_nats, &format!("{alg}"));
        }
    }
    // Branch and bound on 125 vertices never ends within 150 ms, and the other baselines
    // mostly do not either (greedy once finished inside it on an idle machine), so the
    // rule was exercised on branch and bound and at least two more.
    assert!(
        stopped.contains(&Algorithm::Exact) && stopped.len() >= 3,
        "{stopped:?}"
    );

    // Cancelled at its first progress report: greedy returns the held walk.
    req.settings.algorithm = Algorithm::Greedy;
    req.settings.time_limit = None;
    let token = Arc::new(AtomicBool::new(false));
    let control = Control::new()
        .with_cancel_token(token.clone())
        .with_observer(Arc::new(CancelOnReport(token)));
    let r = plan(b.clone(), &req, &control).expect("a cancelled plan returns its best walk");
    assert_eq!(r.termination, Termination::Cancelled);
    assert_exact_and_at_least(&b, &req, &r, cov.utility_nats, "cancelled greedy");
}

/// Cancels its plan at the first progress report.
struct CancelOnReport(Arc<AtomicBool>);

impl Observer for CancelOnReport {
    fn progress(&self, _: &Progress) {
        self.0.store(true, Ordering::Relaxed);
    }
}

/// A limit used up by set-up alone (here 1 ms: the metric closure and the engine take
/// longer) still gives a walk of the whole budget, on a large building (the scale search's
/// constructions) and on a small one (auto's stage 0), not the shortest walk.
#[test]
fn a_limit_used_up_by_set_up_still_gives_a_walk_of_the_whole_budget() {
    let _serial = crate::serial();
    let (office, k) = office();
    let area_two = Arc::new(
        Building::from_json(
            include_str!("fixtures/area-two.json"),
            "fixtures/area-two.json",
        )
        .expect("area two"),
    );
    let k2 = fit_kernel(&area_two.pilot).expect("fit").kernel;
    for (b, k, budget) in [(office, k, 200.0), (area_two, k2, 100.0)] {
        let mut req = round_trip(&b, budget, k);
        req.settings.time_limit = Some(Duration::from_millis(1));
        let r = plan(b.clone(), &req, &Control::new()).expect("plan");
        assert!(
            r.length_m >= 0.9 * budget && r.length_m <= budget + 1e-9,
            "{}: auto walked {} m of {budget} m under a 1 ms limit",
            b.name,
            r.length_m
        );
        assert_eq!(r.termination, Termination::TimeLimit, "{}", b.name);
        let exact = exact_utility(&b, &req, &r.walk_indices);
        assert!((exact - r.utility_nats).abs() <= 1e-9 * exact, "{}", b.name);
    }
}

/// The time limit counts from the caller's clock where it gives one: the command line
/// and the app start it before loading the building and fitting the kernel, which are
/// set-up too (a fit on 60 pilot locations took 0.2 s of a 2 s limit before the plan's
/// own clock started). A clock already past the limit gives the walk of the
/// constructions at once, not another full limit.
#[test]
fn the_limit_counts_from_the_callers_clock() {
    let _serial = crate::serial();
    let (office, k) = office();
    let mut req = round_trip(&office, 200.0, k);
    req.settings.time_limit = Some(Duration::from_secs(2));
    let began = Instant::now() - Duration::from_secs(3);
    let t0 = Instant::now();
    let r = plan(office.clone(), &req, &Control::new().with_clock_from(began)).expect("plan");
    let took = t0.elapsed();
    assert!(
        took < Duration::from_millis(1500),
        "{took:?} after a clock 3 s past its 2 s limit"
    );
    assert_eq!(r.termination, Termination::TimeLimit);
    assert!(r.length_m >= 0.9 * 200.0, "{} m", r.length_m);
}

/// Records the best walk's length and utility of every progress report that carries them.
#[derive(Default)]
struct Bests {
    lengths: Mutex<Vec<f64>>,
    utilities: Mutex<Vec<f64>>,
}

impl Observer for Bests {
    fn progress(&self, p: &Progress) {
        if let (Some(l), Ok(mut v)) = (p.best_length, self.lengths.lock()) {
            v.push(l);
        }
        if let (Some(u), Ok(mut v)) = (p.best_utility, self.utilities.lock()) {
            v.push(u);
        }
    }
}

#[test]
fn progress_carries_the_best_walks_length_and_cancel_returns_that_walk() {
    let _serial = crate::serial();
    let (b, mut req) = office_half_round_trip();
    let budget = req.budget;
    req.settings.time_limit = Some(Duration::from_secs(30));
    let obs = Arc::new(Bests::default());
    let token = Arc::new(AtomicBool::new(false));
    let control = Control::new()
        .with_observer(obs.clone())
        .with_cancel_token(token.clone());
    let t2 = token.clone();
    let h = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(700));
        t2.store(true, Ordering::Relaxed);
    });
    let t0 = Instant::now();
    let r = plan(b.clone(), &req, &control).expect("a cancelled plan returns its best walk");
    h.join().expect("thread");
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
    assert_eq!(r.termination, Termination::Cancelled);
    // Already spread over the building: most of the budget is used.
    assert!(r.length_m >= 0.9 * budget, "{} m of {budget}", r.length_m);
    let lengths = obs.lengths.lock().expect("lock").clone();
    assert!(!lengths.is_empty(), "no progress report carried a length");
    assert!(
        lengths.iter().all(|&l| l > 0.0 && l <= budget + 1e-9),
        "{lengths:?}"
    );
}

#[test]
fn a_request_beyond_the_memory_budget_is_refused_before_allocating() {
    let _serial = crate::serial();
    // 6,000 vertices: the dense vertex covariance alone would be 288 MB twice, the
    // shortest-path table 432 MB.
    let b = line(6000);
    let req = PlanRequest::new("v0", "v10", 20.0, kernel());
    let t0 = Instant::now();
    let e = plan(b, &req, &Control::new()).expect_err("refused");
    assert!(t0.elapsed() < Duration::from_secs(2), "{:?}", t0.elapsed());
    let msg = e.to_string();
    assert!(matches!(e, Error::InvalidRequest(_)), "{e:?}");
    assert!(
        msg.contains("6000 vertices") && msg.contains("MiB") && msg.contains("memory budget"),
        "{msg}"
    );
    // The same building plans once the budget allows it... on a small one: 1 MiB is too
    // little even for 20 vertices' planning threads, 512 MiB is plenty.
    let small = line(20);
    let mut req = PlanRequest::new("v0", "v10", 20.0, kernel());
    req.settings.memory_budget = 1 << 20;
    assert!(plan(small.clone(), &req, &Control::new()).is_err());
    req.settings.memory_budget = 512 << 20;
    plan(small, &req, &Control::new()).expect("fits");
}

/// Each planning thread may hold a walk's matrix, so the estimate grows with the threads;
/// a device with many cores plans with as many as the memory budget affords instead of
/// refusing what one core could plan (the 565-vertex mall, robot 2,036 m: refused at
/// 1,359 MiB on eight threads, 190 MiB on one). Only a request that one thread cannot
/// plan is refused, naming what one thread needs.
#[test]
fn many_threads_plan_with_fewer_where_the_memory_budget_needs_it() {
    let _serial = crate::serial();
    let (office, k) = office();
    let pool = |n: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("pool")
    };
    let mut req = round_trip(&office, 400.0, k);
    req.settings.algorithm = trailprint::plan::Algorithm::Coverage;
    let one = pool(1).install(|| trailprint::plan::estimate_memory(&office, &req, 0));
    let four = pool(4).install(|| trailprint::plan::estimate_memory(&office, &req, 0));
    assert!(four > one, "{four} against {one}");
    req.settings.memory_budget = (one + four) / 2;
    let r = pool(4)
        .install(|| plan(office.clone(), &req, &Control::new()))
        .expect("planned with fewer threads");
    assert!(r.length_m > 0.9 * 400.0, "{}", r.length_m);
    req.settings.memory_budget = one - 1;
    let e = pool(4)
        .install(|| plan(office.clone(), &req, &Control::new()))
        .expect_err("one thread does not fit");
    let mib = one.div_ceil(1 << 20);
    assert!(
        e.to_string().contains(&format!("needs about {mib} MiB")),
        "{e}"
    );
}

/// A refusal for memory names the longest budget that fits, which plans where 2 m more is
/// refused again; on a building whose tables alone exceed the memory budget it says that
/// no budget fits.
#[test]
fn a_refusal_for_memory_names_the_longest_budget_that_fits() {
    let _serial = crate::serial();
    let b = line(200);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let mut req = PlanRequest::new("v0", "v0", 150.0, kernel());
    req.settings.algorithm = Algorithm::Coverage;
    let need = |req: &PlanRequest, budget: f64| {
        let r = PlanRequest {
            budget,
            ..req.clone()
        };
        one.install(|| trailprint::plan::estimate_memory(&b, &r, 0))
    };
    req.settings.memory_budget = need(&req, 60.0);
    let run = |r: &PlanRequest| one.install(|| plan(b.clone(), r, &Control::new()));
    let msg = run(&req).expect_err("150 m does not fit").to_string();
    let named: f64 = msg
        .split("a budget of at most ")
        .nth(1)
        .and_then(|t| t.split(" m fits").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no budget named: {msg}"));
    assert!((59.0..=60.0).contains(&named), "{named}: {msg}");
    let fits = PlanRequest {
        budget: named,
        ..req.clone()
    };
    run(&fits).expect("the budget named fits");
    let over = PlanRequest {
        budget: named + 2.0,
        ..req.clone()
    };
    let e = run(&over).expect_err("2 m more does not").to_string();
    assert!(e.contains("more than the memory budget"), "{e}");
    req.settings.memory_budget = need(&req, 0.0) - 1;
    let e = run(&req).expect_err("nothing fits").to_string();
    assert!(
        e.contains("no budget fits: the building's tables alone need about"),
        "{e}"
    );
}

/// `trailprint utility` (and the bindings' `walk_utility`) evaluated any walk on any
/// building: on a line of 20,000 vertices a 2 m walk took 6.4 GB and 79 s, and aborted
/// under a 2 GB limit. Now a building whose vertex covariance alone exceeds the memory
/// budget is refused at once, naming the size; the same walk on a small building runs.
#[test]
fn utility_refuses_a_building_too_large_to_evaluate_before_allocating() {
    let _serial = crate::serial();
    let dir = tempfile::tempdir().expect("dir");
    let write = |n: usize| {
        let path = dir.path().join(format!("line{n}.json"));
        std::fs::write(&path, line_json(n)).expect("write");
        path
    };
    let utility = |path: &std::path::Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_trailprint"))
            .arg("utility")
            .arg("--building")
            .arg(path)
            .args(["--walk", "v0,v1,v2", "--kernel", "40,6,2"])
            .output()
            .expect("run trailprint utility")
    };
    let t0 = Instant::now();
    let out = utility(&write(6000));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(t0.elapsed() < Duration::from_secs(10), "{:?}", t0.elapsed());
    assert!(
        err.contains("\"line\" (6000 vertices) needs about")
            && err.contains("memory budget of 512 MiB"),
        "{err}"
    );
    let out = utility(&write(20));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_budget_far_beyond_the_building_is_refused_with_what_would_do() {
    let _serial = crate::serial();
    let b = line(5); // 4 m of edges
    let mut req = PlanRequest::new("v0", "v0", 100_000.0, kernel());
    req.settings.algorithm = Algorithm::Genetic;
    let e = plan(b, &req, &Control::new()).expect_err("refused");
    let msg = e.to_string();
    assert!(
        msg.contains("100000 m") && msg.contains("at most 16.0 m"),
        "{msg}"
    );
}

/// Reversals per 100 m of the walk `r` planned for `req` on `b`.
fn reversals_per_100m(b: &Arc<Building>, req: &PlanRequest, r: &PlanResult) -> f64 {
    let w = &r.walk_indices;
    let end = *w.last().expect("walk");
    let p = Problem::new(
        b.clone(),
        req.kernel,
        req.settings.model,
        w[0],
        end,
        req.budget,
    )
    .expect("problem");
    100.0 * reversals(&p, w) as f64 / r.length_m
}

#[test]
fn a_surveyors_walk_rarely_paces_back_along_the_edge_just_walked() {
    let _serial = crate::serial();
    let (b, mut req) = office_half_round_trip();
    req.settings.model = Surveyor::human();
    let r = plan(b.clone(), &req, &Control::new()).expect("plan");
    let per_100m = reversals_per_100m(&b, &req, &r);
    // Measured: 0 to 0.5 per 100 m whatever the time the search gets (0.1 s to 4 s).
    assert!(per_100m <= 1.0, "{per_100m} reversals per 100 m");
}

/// The small-building portfolio (the bundled demo building, 70 vertices) holds a person's
/// walks to the same rule: judged by utility alone its walks paced in and out of the
/// rooms' doors (seed 0: 15, 14 and 9 reversals per 100 m at 60, 120 and 200 m).
#[test]
fn a_surveyors_walk_on_a_small_building_does_not_pace_either() {
    let _serial = crate::serial();
    let b =
        Arc::new(Building::from_json(trailprint::synth::DEMO_BUILDING_JSON, "demo").expect("demo"));
    let k = fit_kernel(&b.pilot).expect("fit").kernel;
    for budget in [60.0, 120.0, 200.0] {
        let mut req = PlanRequest::new("f0-c00", "f0-c15", budget, k);
        req.settings.model = Surveyor::human();
        let r = plan(b.clone(), &req, &Control::new()).expect("plan");
        let per_100m = reversals_per_100m(&b, &req, &r);
        // Measured: 3.3, 1.7 and 3.5 per 100 m.
        assert!(
            per_100m <= 6.0,
            "{budget} m: {per_100m} reversals per 100 m"
        );
        assert!(
            r.length_m >= 0.95 * budget,
            "{budget} m: walks {} m",
            r.length_m
        );
    }
}

/// A progress bar's "best so far" is a promise: the plan never ends below a walk it has
/// shown. (The search once kept following its surrogate to a walk worse by `f_D` than one
/// it had already offered: office, robot, 402 m, 2 s gave 127.04 nats after showing 127.48.)
#[test]
fn auto_never_returns_less_than_a_walk_it_has_shown() {
    let _serial = crate::serial();
    let (b, k) = office();
    for (model, frac) in [(Surveyor::robot(), 1.0), (Surveyor::robot(), 0.5)] {
        let budget = frac * b.total_edge_length();
        let mut req = round_trip(&b, budget, k);
        req.settings.model = model;
        req.settings.time_limit = Some(Duration::from_secs(2));
        let obs = Arc::new(Bests::default());
        let r = plan(b.clone(), &req, &Control::new().with_observer(obs.clone())).expect("plan");
        let shown = obs.utilities.lock().expect("lock").clone();
        let best_shown = shown.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        assert!(!shown.is_empty(), "no report carried a utility");
        assert!(
            r.utility_nats >= best_shown - 1e-9 * best_shown.abs(),
            "{frac} of the edges: returned {} nats after showing {best_shown}",
            r.utility_nats
        );
        let exact = exact_utility(&b, &req, &r.walk_indices);
        assert!(
            (exact - r.utility_nats).abs() <= 1e-9 * exact.abs(),
            "{exact} vs {}",
            r.utility_nats
        );
    }
}
