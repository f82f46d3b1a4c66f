//! Shared helpers of the planner tests.
#![allow(dead_code)]

use std::sync::Arc;

use trailprint::Building;
use trailprint::gp::Kernel;
use trailprint::plan::{Algorithm, PlanRequest, PlanResult, Problem};
use trailprint::surveyor::Surveyor;
use trailprint::utility::UtilityEngine;

/// One of the paper-shaped instances, from the repository's copies in `core/tests/fixtures`
/// (byte for byte the files of `shared/instances/`), so a checkout anywhere can run them.
pub fn instance(name: &str) -> Arc<Building> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    Arc::new(Building::load(&path).expect("instance fixture"))
}

/// The `survey-building/1` text of a building `name`: `vertices` and `edges` are the JSON
/// objects of its vertices and edges, `pilot` the JSON array of its pilot fingerprints.
pub fn building_json(name: &str, vertices: &[String], edges: &[String], pilot: &str) -> String {
    format!(
        r#"{{"format":"survey-building/1","name":"{name}","vertices":[{}],"edges":[{}],"pilot":{pilot}}}"#,
        vertices.join(","),
        edges.join(",")
    )
}

/// A line named "line" of `n` vertices 1 m apart (`v0`, `v1`, ...) with the pilot data
/// `pilot` (a JSON array), as a `survey-building/1` file's text.
pub fn line_json(n: usize, pilot: &str) -> String {
    let v: Vec<String> = (0..n)
        .map(|i| format!(r#"{{"id":"v{i}","x":{i},"y":0}}"#))
        .collect();
    let e: Vec<String> = (1..n)
        .map(|i| format!(r#"{{"a":"v{}","b":"v{i}"}}"#, i - 1))
        .collect();
    building_json("line", &v, &e, pilot)
}

/// A `w x h` grid with `step` m edges, minus the edges in `drop` (by index in row-major
/// edge order, skipped if that would disconnect the grid), with a few pilot points.
pub fn grid(w: usize, h: usize, step: f64, drop: &[usize]) -> Arc<Building> {
    let mut vs = Vec::new();
    for y in 0..h {
        for x in 0..w {
            vs.push(format!(
                r#"{{"id":"v{x}_{y}","x":{},"y":{}}}"#,
                x as f64 * step,
                y as f64 * step
            ));
        }
    }
    let mut es: Vec<(String, String)> = Vec::new();
    for y in 0..h {
        for x in 0..w {
            if x + 1 < w {
                es.push((format!("v{x}_{y}"), format!("v{}_{y}", x + 1)));
            }
            if y + 1 < h {
                es.push((format!("v{x}_{y}"), format!("v{x}_{}", y + 1)));
            }
        }
    }
    let build = |es: &[(String, String)]| {
        let edges: Vec<String> = es
            .iter()
            .map(|(a, b)| format!(r#"{{"a":"{a}","b":"{b}"}}"#))
            .collect();
        let pilot = format!(
            r#"[{{"x":0.3,"y":0.1,"rss":{{"a":-50}}}},{{"x":{},"y":{},"rss":{{"a":-60}}}}]"#,
            (w - 1) as f64 * step * 0.6,
            (h - 1) as f64 * step * 0.7
        );
        Building::from_json(&building_json("grid", &vs, &edges, &pilot), "grid")
    };
    let mut kept = es.clone();
    for &d in drop {
        if kept.len() <= 1 {
            break;
        }
        let i = d % kept.len();
        let mut trial = kept.clone();
        trial.remove(i);
        if build(&trial).is_ok() {
            kept = trial;
        }
    }
    Arc::new(build(&kept).expect("grid"))
}

/// A budget of `extra` metres over the shortest distance from `s` to `t`.
pub fn p_budget(b: &Building, s: usize, t: usize, extra: f64) -> f64 {
    trailprint::plan::Metric::new(b).dist(s, t) + extra
}

/// A random case of the planner property tests: the grid [`grid`] makes of `w`, `h` and
/// `drop`, end points `s` and `t` taken modulo its size, and a budget of `extra` metres
/// over the shortest distance between them.
pub fn random_grid_case(
    (w, h, drop): (usize, usize, &[usize]),
    (s, t): (usize, usize),
    extra: f64,
) -> (Arc<Building>, (usize, usize), f64) {
    let b = grid(w, h, 2.0, drop);
    let n = b.len();
    let (s, t) = (s % n, t % n);
    let budget = p_budget(&b, s, t, extra);
    (b, (s, t), budget)
}

pub fn kernel() -> Kernel {
    Kernel::new(60.0, 6.0, 4.0)
}

pub fn request(b: &Building, s: usize, t: usize, budget: f64, alg: Algorithm) -> PlanRequest {
    let mut r = PlanRequest::new(&b.vertices[s].id, &b.vertices[t].id, budget, kernel());
    r.settings.algorithm = alg;
    r.settings.seed = 7;
    r.settings.params.population = 30;
    r.settings.params.generations = 3;
    r.settings.params.iterations = 150;
    r.settings.time_limit = Some(std::time::Duration::from_secs(if alg == Algorithm::Auto {
        1
    } else {
        20
    }));
    r
}

pub fn problem(b: &Arc<Building>, s: usize, t: usize, budget: f64) -> Problem {
    Problem::new(b.clone(), kernel(), Surveyor::robot(), s, t, budget).expect("problem")
}

/// Plain enumeration: the best utility over every walk from `s` to `t` within budget.
pub fn brute_force(p: &Problem) -> (f64, Vec<usize>) {
    fn rec(p: &Problem, walk: &mut Vec<usize>, len: f64, best: &mut (f64, Vec<usize>)) {
        let v = *walk.last().expect("non-empty");
        if v == p.end {
            let u = p.utility(walk).expect("utility");
            if u > best.0 {
                *best = (u, walk.clone());
            }
        }
        for &(w, e) in p.building.neighbours(v) {
            let l = len + p.building.edges[e].length;
            if l <= p.budget + 1e-9 {
                walk.push(w);
                rec(p, walk, l, best);
                walk.pop();
            }
        }
    }
    let mut best = (f64::NEG_INFINITY, Vec::new());
    rec(p, &mut vec![p.start], 0.0, &mut best);
    best
}

/// Checks what every plan promises: a real walk from the start to the end within the
/// budget, whose reported length, ids and utility are the walk's (utility evaluated by a
/// fresh engine).
pub fn assert_sound(b: &Arc<Building>, req: &PlanRequest, r: &PlanResult, what: &str) {
    let w = &r.walk_indices;
    assert_eq!(
        w.first(),
        b.vertex_index(&req.start).as_ref(),
        "{what}: start"
    );
    assert_eq!(w.last(), b.vertex_index(&req.end).as_ref(), "{what}: end");
    b.check_walk(w).unwrap_or_else(|e| panic!("{what}: {e}"));
    let len = b.walk_length(w);
    assert!(
        len <= req.budget + 1e-9,
        "{what}: {len} m > {} m",
        req.budget
    );
    assert!((r.length_m - len).abs() < 1e-9, "{what}: reported length");
    assert_eq!(r.walk, b.walk_ids(w), "{what}: ids");
    let e = UtilityEngine::new(b.clone(), req.kernel, req.settings.model).expect("engine");
    let u = e.utility(w).expect("utility");
    assert!(
        (u - r.utility_nats).abs() <= 1e-9 * u.abs().max(1.0),
        "{what}: reported {} vs evaluated {u}",
        r.utility_nats
    );
}

/// Plans `s` to `t` within `budget` with every algorithm (seed `seed`, time limit
/// `limit(algorithm)`) and checks each result with [`assert_sound`].
pub fn every_algorithm_is_sound(
    b: &Arc<Building>,
    (s, t): (usize, usize),
    budget: f64,
    seed: u64,
    limit: impl Fn(Algorithm) -> Option<std::time::Duration>,
) {
    for alg in Algorithm::ALL {
        let mut req = request(b, s, t, budget, alg);
        req.settings.seed = seed;
        req.settings.time_limit = limit(alg).or(req.settings.time_limit);
        let r = trailprint::plan::plan(b.clone(), &req, &trailprint::plan::Control::new())
            .expect("plan");
        assert_sound(b, &req, &r, alg.name());
    }
}
