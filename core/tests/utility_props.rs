//! Properties of the utility (SPEC section 3) and agreement of the fast engine with the
//! reference evaluator, on the shared instances and on random walks.

use std::sync::Arc;

use proptest::prelude::*;
use trailprint::building::Building;
use trailprint::gp::{Kernel, Point};
use trailprint::samples::{Surveyor, sample_walk};
use trailprint::utility::reference::{Observation, pilot_observations};
use trailprint::utility::{UtilityEngine, reference_utility};

fn instance(name: &str) -> Arc<Building> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    Arc::new(Building::load(&path).expect("shared instance"))
}

fn reference(b: &Building, k: &Kernel, model: &Surveyor, walk: &[usize]) -> f64 {
    let mut obs = pilot_observations(&b.pilot_points());
    for s in sample_walk(b, walk, model, k).expect("samples") {
        obs.push(Observation::from(&s));
    }
    reference_utility(k, &b.vertex_points(), &obs).expect("reference")
}

/// A random walk of `steps` steps from `start`, driven by `choices`.
fn random_walk(b: &Building, start: usize, choices: &[usize]) -> Vec<usize> {
    let mut walk = vec![start];
    for &c in choices {
        let nb = b.neighbours(*walk.last().expect("nonempty"));
        walk.push(nb[c % nb.len()].0);
    }
    walk
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// Checks that the engine's (batch) utility of `walk`, `what` it is, is the reference's to
/// 1e-9; returns it.
fn assert_engine_matches_reference(
    b: &Arc<Building>,
    k: Kernel,
    model: Surveyor,
    walk: &[usize],
    what: &str,
) -> f64 {
    let e = UtilityEngine::new(b.clone(), k, model).expect("engine");
    let fast = e.utility(walk).expect("fast");
    let slow = reference(b, &k, &model, walk);
    assert!(
        rel(fast, slow) < 1e-9,
        "{model:?}: {what} {fast} vs reference {slow}"
    );
    fast
}

const K2: Kernel = Kernel {
    sf2: 103.22,
    ell: 32.17,
    sn2: 3.3,
};

#[test]
fn one_vertex_one_sample_in_closed_form() {
    let text = r#"{"format":"survey-building/1","name":"one","vertices":[{"id":"v","x":1,"y":2},{"id":"w","x":1000,"y":2}],
        "edges":[{"a":"v","b":"w"}]}"#;
    let b = Arc::new(Building::from_json(text, "one").expect("valid"));
    let k = Kernel::new(40.0, 6.0, 9.0);
    // Two vertices 999 m apart are nearly independent; compute the exact 2x2 case.
    let e = UtilityEngine::new(b.clone(), k, Surveyor::robot()).expect("engine");
    let got = e.utility(&[0]).expect("utility");
    // One sample at v: Sigma = A - b b^T / (sf2 + sn2), b = (sf2, k(v,w)).
    let (sf2, sn2) = (k.sf2, k.sn2);
    let kvw = sf2 * (-999.0f64 / 6.0).exp();
    let a = [[sf2 + sn2, kvw], [kvw, sf2 + sn2]];
    let bb = [sf2, kvw];
    let c = sf2 + sn2;
    let s = [
        [a[0][0] - bb[0] * bb[0] / c, a[0][1] - bb[0] * bb[1] / c],
        [a[1][0] - bb[1] * bb[0] / c, a[1][1] - bb[1] * bb[1] / c],
    ];
    let det = |m: [[f64; 2]; 2]| m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let expect = 0.5 * (det(a) / det(s)).ln();
    assert!(rel(got, expect) < 1e-12, "{got} vs {expect}");
    // And the textbook single-variable value: 1/2 ln(1 + sf2^2 / (sn2 (2 sf2 + sn2))) when
    // the second vertex is independent.
    let single = 0.5 * ((sf2 + sn2) / (sf2 + sn2 - sf2 * sf2 / (sf2 + sn2))).ln();
    assert!(rel(got, single) < 1e-9);
}

#[test]
fn engine_matches_reference_on_a_140m_walk_of_area_two() {
    let b = instance("area-two.json");
    let start = b.vertex_index("b00").expect("b00");
    let choices: Vec<usize> = (0..200).map(|i| (i * 7 + 3) % 11).collect();
    let mut walk = vec![start];
    for w in random_walk(&b, start, &choices).into_iter().skip(1) {
        if b.walk_length(&[*walk.last().expect("x"), w]) + b.walk_length(&walk) > 140.0 {
            break;
        }
        walk.push(w);
    }
    for model in [Surveyor::robot(), Surveyor::human()] {
        let fast = assert_engine_matches_reference(&b, K2, model, &walk, "fast");
        assert!(fast > 0.0);
    }
}

/// A walk that goes back and forth along the same edges puts samples exactly where
/// earlier ones were; the batch path merges those into one observation each
/// (`merge_coincident`), which must leave the value the reference computes from every
/// sample: to 1e-9 for robot and person, on one floor and across the stair.
#[test]
fn back_and_forth_walks_merge_coincident_samples_exactly() {
    use trailprint::utility::merge_coincident;
    let b = two_floors();
    let id = |s: &str| b.vertex_index(s).expect(s);
    // Along a row and back, up the stair and back, twice: on 2 m and 6 m edges the
    // robot's 0.5 m samples of every return land on the first pass's points.
    let mut walk = vec![id("a0_0")];
    for _ in 0..2 {
        walk.extend(
            [
                "a1_0", "a2_0", "a3_0", "a2_0", "a1_0", "a0_0", "b0_0", "b1_0", "b0_0", "a0_0",
            ]
            .map(id),
        );
    }
    let k = Kernel::new(60.0, 8.0, 2.0);
    for model in [Surveyor::robot(), Surveyor::human()] {
        let samples = sample_walk(&b, &walk, &model, &k).expect("samples");
        let obs: Vec<(Point, f64)> = samples.iter().map(|s| (s.pos, s.extra_noise)).collect();
        let merged = merge_coincident(&obs, k.sn2);
        if matches!(model, Surveyor::Robot { .. }) {
            // 56 m of walk over 14 m of distinct track: 113 samples on 29 places.
            assert!(
                merged.len() * 3 < obs.len(),
                "robot: {} of {} kept",
                merged.len(),
                obs.len()
            );
        }
        assert_engine_matches_reference(&b, k, model, &walk, "merged");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, .. ProptestConfig::default() })]

    /// Incremental = batch = reference, the utility is never negative and never decreases
    /// as the walk grows (mutual information is monotone in the observed set).
    #[test]
    fn incremental_batch_reference_agree_and_utility_is_monotone(
        start in 0usize..27,
        choices in proptest::collection::vec(0usize..8, 0..25),
        human in any::<bool>(),
        sf2 in 5.0f64..200.0, ell in 1.0f64..40.0, sn2 in 1.0f64..10.0,
    ) {
        let b = instance("area-one.json");
        let k = Kernel::new(sf2, ell, sn2);
        let model = if human {
            Surveyor::Human { step_length_m: 0.7, speed_mps: 1.0, scan_interval_s: 1.3, step_error: 0.1, turn_threshold_deg: 30.0 }
        } else {
            Surveyor::robot_every(0.7)
        };
        let walk = random_walk(&b, start, &choices);
        let e = UtilityEngine::new(b.clone(), k, model).expect("engine");
        let mut st = e.start(walk[0]).expect("start");
        let mut last = st.utility().expect("u");
        // The engine clamps at 0, so `last >= 0` could not fail: check the one-vertex walk
        // against the reference evaluator instead.
        let first = reference(&b, &k, &model, &walk[..1]);
        prop_assert!(rel(last, first) < 1e-9, "start {last} vs reference {first}");
        let prior = e.prior_utility().expect("prior");
        prop_assert!(last >= prior - 1e-9 * prior.abs());
        for (i, &v) in walk.iter().enumerate().skip(1) {
            st.push(v).expect("push");
            let u = st.utility().expect("u");
            prop_assert!(u >= last - 1e-9 * last.abs(), "decreased at step {i}: {last} -> {u}");
            last = u;
        }
        let batch = e.utility(&walk).expect("batch");
        let refv = reference(&b, &k, &model, &walk);
        prop_assert!(rel(last, batch) < 1e-12, "incremental {last} vs batch {batch}");
        prop_assert!(rel(batch, refv) < 1e-9, "batch {batch} vs reference {refv}");
        prop_assert_eq!(st.samples(), sample_walk(&b, &walk, &model, &k).expect("s").len());
    }

    /// Mark and rewind give exactly the utility of the shorter walk, and branching from a
    /// mark gives the utility of the other branch.
    #[test]
    fn rewind_restores_and_branches(start in 0usize..61, a in proptest::collection::vec(0usize..6, 1..12), c in proptest::collection::vec(0usize..6, 1..12)) {
        let b = instance("area-two.json");
        let e = UtilityEngine::new(b.clone(), K2, Surveyor::human()).expect("engine");
        let prefix = random_walk(&b, start, &a);
        let mut st = e.start(prefix[0]).expect("start");
        for &v in &prefix[1..] { st.push(v).expect("push"); }
        let mark = st.mark();
        let u_prefix = st.utility().expect("u");
        let branch = random_walk(&b, *prefix.last().expect("x"), &c);
        for &v in &branch[1..] { st.push(v).expect("push"); }
        st.rewind(&mark);
        prop_assert!(rel(st.utility().expect("u"), u_prefix) < 1e-13);
        let other = random_walk(&b, *prefix.last().expect("x"), &c.iter().map(|x| x + 1).collect::<Vec<_>>());
        for &v in &other[1..] { st.push(v).expect("push"); }
        let mut full = prefix.clone();
        full.extend_from_slice(&other[1..]);
        prop_assert!(rel(st.utility().expect("u"), e.utility(&full).expect("u")) < 1e-12);
    }

    /// Human label noise is 0 at a check-in and grows with the distance walked since.
    #[test]
    fn human_noise_is_zero_at_checkins_and_grows(start in 0usize..27, choices in proptest::collection::vec(0usize..8, 1..20)) {
        let b = instance("area-one.json");
        let k = Kernel::new(168.4, 23.86, 1.08);
        let w = random_walk(&b, start, &choices);
        let s = sample_walk(&b, &w, &Surveyor::human(), &k).expect("samples");
        prop_assert_eq!(s[0].extra_noise, 0.0);
        for pair in s.windows(2) {
            let (p, q) = (pair[0], pair[1]);
            if q.since_checkin == 0.0 {
                prop_assert_eq!(q.extra_noise, 0.0);
            } else if q.since_checkin > p.since_checkin {
                prop_assert!(q.extra_noise > p.extra_noise);
            }
            prop_assert!((q.extra_noise - k.label_noise(0.05 * q.since_checkin)).abs() < 1e-12);
        }
    }
}

#[test]
fn parallel_evaluation_matches_sequential() {
    let b = instance("area-two.json");
    let e = UtilityEngine::new(b.clone(), K2, Surveyor::robot()).expect("engine");
    let walks: Vec<Vec<usize>> = (0..16)
        .map(|s| random_walk(&b, s, &(0..30).map(|i| (i * s + 1) % 5).collect::<Vec<_>>()))
        .collect();
    let par = e.utilities(&walks);
    for (w, u) in walks.iter().zip(par) {
        assert_eq!(u.expect("u"), e.utility(w).expect("u"));
    }
}

#[test]
fn observations_api_agrees_with_walks() {
    let b = instance("area-one.json");
    let k = Kernel::new(168.4, 23.86, 1.08);
    let e = UtilityEngine::new(b.clone(), k, Surveyor::human()).expect("engine");
    let walk = random_walk(&b, 0, &[1, 2, 3, 1, 0, 2]);
    let obs: Vec<Observation> = sample_walk(&b, &walk, &Surveyor::human(), &k)
        .expect("s")
        .iter()
        .map(Observation::from)
        .collect();
    let a = e.utility_of_observations(&obs).expect("u");
    assert!(rel(a, e.utility(&walk).expect("u")) < 1e-12);
    // Conditioning the engine on those observations leaves nothing for the same walk to add.
    let e2 = UtilityEngine::with_prior(b.clone(), k, Surveyor::human(), &obs).expect("engine");
    assert!(rel(e2.prior_utility().expect("u"), a) < 1e-12);
    let _ = Point::new(0.0, 0.0, 0);
}

/// Two 4 x 3 floors of 2 m lattices joined by a 6 m stair between `a0_0` and `b0_0`, with
/// pilot points on both floors: exercises the zero covariance across floors in every
/// evaluator (the dense path's masked kernel rows among them).
fn two_floors() -> Arc<Building> {
    let mut vertices = Vec::new();
    let mut edges = Vec::new();
    for (f, name) in [(0, "a"), (1, "b")] {
        for x in 0..4 {
            for y in 0..3 {
                vertices.push(serde_json::json!({"id": format!("{name}{x}_{y}"), "x": x as f64 * 2.0, "y": y as f64 * 2.0, "floor": f}));
                if x + 1 < 4 {
                    edges.push(serde_json::json!({"a": format!("{name}{x}_{y}"), "b": format!("{name}{}_{y}", x + 1)}));
                }
                if y + 1 < 3 {
                    edges.push(serde_json::json!({"a": format!("{name}{x}_{y}"), "b": format!("{name}{x}_{}", y + 1)}));
                }
            }
        }
    }
    edges.push(serde_json::json!({"a": "a0_0", "b": "b0_0", "length": 6.0}));
    let pilot: Vec<_> = [(0.0, 0.0, 0), (5.0, 3.0, 0), (2.0, 4.0, 1), (6.0, 1.0, 1)]
        .iter()
        .map(|&(x, y, f)| serde_json::json!({"x": x, "y": y, "floor": f, "rss": {"ap": -60.0}}))
        .collect();
    let doc = serde_json::json!({"format": "survey-building/1", "name": "two floors",
        "floors": [{"id": 0}, {"id": 1}], "vertices": vertices, "edges": edges, "pilot": pilot});
    Arc::new(Building::from_json(&doc.to_string(), "two floors").expect("two floors"))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, .. ProptestConfig::default() })]

    /// On a building with two floors the whole-walk (dense) path, the incremental path and
    /// the reference agree, for robot and human surveyors.
    #[test]
    fn every_evaluator_agrees_across_floors(
        choices in proptest::collection::vec(0usize..5, 1..40),
        human in any::<bool>(),
        sf2 in 5.0f64..200.0, ell in 1.0f64..40.0, sn2 in 1.0f64..10.0,
    ) {
        let b = two_floors();
        let k = Kernel::new(sf2, ell, sn2);
        let model = if human { Surveyor::human() } else { Surveyor::robot() };
        // Start at the stair foot so that many walks change floor.
        let start = b.vertex_index("a0_0").expect("a0_0");
        let walk = random_walk(&b, start, &choices);
        let e = UtilityEngine::new(b.clone(), k, model).expect("engine");
        let mut st = e.start(walk[0]).expect("start");
        for &v in &walk[1..] {
            st.push(v).expect("push");
        }
        let inc = st.utility().expect("incremental");
        let dense = e.utility(&walk).expect("dense");
        let refv = reference(&b, &k, &model, &walk);
        prop_assert!(rel(dense, refv) < 1e-9, "dense {dense} vs reference {refv}");
        prop_assert!(rel(inc, dense) < 1e-12, "incremental {inc} vs dense {dense}");
    }
}
