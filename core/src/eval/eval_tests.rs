//! Evaluation tests: the reference grid, the summary, and localization on the paper's
//! areas and on generated buildings.

use super::*;
use crate::samples::{Surveyor, sample_walk};
use crate::synth::{DEMO_BUILDING_JSON, SynthParams, generate};

fn fixture(name: &str) -> Building {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    Building::load(&path).expect("fixture loads")
}

/// The authors' fitted hyperparameters (SPEC section 6).
const AREA_ONE: Kernel = Kernel {
    sf2: 168.40,
    ell: 23.86,
    sn2: 1.08,
};
const AREA_TWO: Kernel = Kernel {
    sf2: 103.22,
    ell: 32.17,
    sn2: 3.3,
};
/// A plausible kernel for the demo building until its fitted one is available.
const DEMO: Kernel = Kernel {
    sf2: 60.0,
    ell: 8.0,
    sn2: 4.0,
};

fn dense_points(b: &Building) -> Vec<Point> {
    b.dense_survey.iter().map(Fingerprint::point).collect()
}

#[test]
fn reference_grid_keeps_points_near_edges_of_their_floor() {
    let text = serde_json::json!({
        "format": "survey-building/1",
        "name": "L",
        "floors": [{"id": 0}, {"id": 3}],
        "vertices": [
            {"id": "a", "x": 0.0, "y": 0.0},
            {"id": "b", "x": 10.0, "y": 0.0},
            {"id": "c", "x": 10.0, "y": 10.0},
            {"id": "d", "x": 0.0, "y": 0.0, "floor": 3}
        ],
        "edges": [{"a": "a", "b": "b"}, {"a": "b", "b": "c"}, {"a": "a", "b": "d", "length": 5.0}]
    })
    .to_string();
    let b = Building::from_json(&text, "t").expect("valid");
    let g = reference_grid(&b, 1.0, 1.5);
    // Floor 0: an L of two 10 m edges on an 11 x 11 lattice; within 1.5 m of the edges are
    // the rows y = 0, 1 and the columns x = 9, 10 (overlapping in 4 points).
    let f0 = g.iter().filter(|p| p.floor == 0).count();
    assert_eq!(f0, 11 * 2 + 11 * 2 - 4);
    assert!(
        g.iter()
            .filter(|p| p.floor == 0)
            .all(|p| p.y <= 1.0 || p.x >= 9.0)
    );
    // Floor 3 has one vertex and no edge of its own: just that point.
    let f3: Vec<&Point> = g.iter().filter(|p| p.floor == 3).collect();
    assert_eq!(f3.len(), 1);
}

#[test]
fn summary_matches_hand_computed_percentiles() {
    let (mean, median, p90) = summary(&[4.0, 1.0, 3.0, 2.0]);
    assert_eq!(mean, 2.5);
    assert_eq!(median, 2.5);
    assert!((p90 - 3.7).abs() < 1e-12);
    let (_, median, p90) = summary(&[5.0]);
    assert_eq!((median, p90), (5.0, 5.0));
}

#[test]
fn all_dense_positions_localize_well_on_area_two() {
    // Paper: 2.06 m with all RSS on the real Area Two.
    let b = fixture("area-two.json");
    let t = std::time::Instant::now();
    let ev = Evaluator::new(&b, &AREA_TWO, EvalOptions::default()).expect("evaluator");
    let prepared = t.elapsed();
    let r = ev.evaluate(&dense_points(&b), 1).expect("evaluate");
    let elapsed = t.elapsed();
    eprintln!(
        "area-two, all {} dense positions: mean {:.2} m, median {:.2} m, p90 {:.2} m, \
         {} grid points, world model {prepared:?}, total {elapsed:?}",
        r.samples, r.mean_error_m, r.median_error_m, r.p90_error_m, r.grid_points
    );
    let pilot_only = ev.evaluate(&[], 1).expect("pilot only");
    eprintln!(
        "area-two, pilot only: mean {:.2} m",
        pilot_only.mean_error_m
    );
    let t = std::time::Instant::now();
    let every_other: Vec<Point> = dense_points(&b).into_iter().step_by(2).collect();
    let half = ev.evaluate(&every_other, 1).expect("half");
    eprintln!(
        "area-two, {} samples: mean {:.2} m in {:?} (world model cached)",
        half.samples,
        half.mean_error_m,
        t.elapsed()
    );
    assert!(pilot_only.mean_error_m > r.mean_error_m);
    assert_eq!(r.errors_m.len(), 131);
    assert_eq!(r.access_points, 18);
    // The synthetic instance is easier than the real area (about 3 dB of residual per
    // access point against 1.8 dB/m of gradient, 18 access points): 0.56 m with seed 1.
    // The evaluation is deterministic given the seed; the margin allows a few of the 131
    // test points to flip between near-tied grid points under other floating-point
    // rounding (each flip moves the mean by a few millimetres), not a worse map.
    assert!(r.mean_error_m < 0.65, "mean error {} m", r.mean_error_m);
    assert!(
        half.mean_error_m < 0.7,
        "half the positions: {} m",
        half.mean_error_m
    );
    assert!(r.median_error_m <= r.p90_error_m);
}

#[test]
fn all_dense_positions_localize_well_on_area_one() {
    // Paper: 3.8 m with all RSS on the real Area One.
    let b = fixture("area-one.json");
    let r =
        evaluate(&b, &AREA_ONE, &dense_points(&b), 1, &EvalOptions::default()).expect("evaluate");
    eprintln!(
        "area-one, all {} dense positions: mean {:.2} m, median {:.2} m, p90 {:.2} m",
        r.samples, r.mean_error_m, r.median_error_m, r.p90_error_m
    );
    assert_eq!(r.errors_m.len(), 58);
    // 0.71 m with seed 1 on the synthetic instance (58 test points; margin as on Area Two).
    assert!(r.mean_error_m < 0.8, "mean error {} m", r.mean_error_m);
}

/// A walk that visits every vertex: a depth-first tour from vertex 0, walking back along
/// the tree edges.
fn dfs_tour(b: &Building) -> Vec<usize> {
    fn visit(b: &Building, v: usize, seen: &mut [bool], walk: &mut Vec<usize>) {
        seen[v] = true;
        walk.push(v);
        for &(w, _) in b.neighbours(v) {
            if !seen[w] {
                visit(b, w, seen, walk);
                walk.push(v);
            }
        }
    }
    let mut seen = vec![false; b.len()];
    let mut walk = Vec::new();
    visit(b, 0, &mut seen, &mut walk);
    walk
}

#[test]
fn a_dense_walk_beats_the_pilot_data_alone_on_a_generated_building() {
    let b = Building::from_json(DEMO_BUILDING_JSON, "demo").expect("demo");
    let ev = Evaluator::new(&b, &DEMO, EvalOptions::default()).expect("evaluator");
    let walk = dfs_tour(&b);
    b.check_walk(&walk).expect("a walk");
    let samples = sample_walk(&b, &walk, &Surveyor::robot(), &DEMO).expect("samples");
    let mut pilot_only = 0.0;
    let mut dense = 0.0;
    for seed in 0..3 {
        pilot_only += ev.evaluate(&[], seed).expect("pilot only").mean_error_m;
        dense += ev
            .evaluate_samples(&samples, seed)
            .expect("dense")
            .mean_error_m;
    }
    eprintln!(
        "demo: pilot only {:.2} m, {} samples along {:.0} m {:.2} m",
        pilot_only / 3.0,
        samples.len(),
        b.walk_length(&walk),
        dense / 3.0
    );
    assert!(
        pilot_only > dense + 0.3,
        "pilot only {pilot_only} vs dense {dense} (sums over 3 seeds)"
    );
}

#[test]
fn human_label_noise_enters_the_map_and_is_deterministic() {
    let b = Building::from_json(DEMO_BUILDING_JSON, "demo").expect("demo");
    let ev = Evaluator::new(&b, &DEMO, EvalOptions::default()).expect("evaluator");
    let walk = dfs_tour(&b);
    let human = sample_walk(&b, &walk, &Surveyor::human(), &DEMO).expect("samples");
    assert!(human.iter().any(|s| s.extra_noise > 0.0));
    let a = ev.evaluate_samples(&human, 3).expect("a");
    assert_eq!(a, ev.evaluate_samples(&human, 3).expect("again"));
    // Without the label noise the same positions give another map.
    let points: Vec<Point> = human.iter().map(|s| s.pos).collect();
    let plain = ev.evaluate(&points, 3).expect("plain");
    assert_eq!(plain.samples, a.samples);
    assert_ne!(plain.errors_m, a.errors_m);
}

#[test]
fn evaluation_is_deterministic_by_seed() {
    let b = Building::from_json(DEMO_BUILDING_JSON, "demo").expect("demo");
    // Half the test points without rss, so that test fingerprints are drawn too.
    let mut file = b.to_file();
    for t in file.test_points.iter_mut().step_by(2) {
        t.rss.clear();
    }
    let b = Building::from_file(file, "demo").expect("valid");
    let samples: Vec<Point> = dense_points(&b).into_iter().step_by(3).collect();
    let ev = Evaluator::new(&b, &DEMO, EvalOptions::default()).expect("evaluator");
    let a = ev.evaluate(&samples, 7).expect("a");
    let again = evaluate(&b, &DEMO, &samples, 7, &EvalOptions::default()).expect("again");
    assert_eq!(a, again);
    let other = ev.evaluate(&samples, 8).expect("other");
    assert_ne!(a.errors_m, other.errors_m);
}

#[test]
fn synthetic_world_model_works_without_a_dense_survey() {
    let s = generate(&SynthParams {
        pilot: 10,
        test_points: 30,
        ..SynthParams::default()
    })
    .expect("generate");
    let mut file = s.file.clone();
    file.dense_survey.clear();
    let b = Building::from_file(file, "synthetic").expect("valid");
    let e = Evaluator::new(&b, &DEMO, EvalOptions::default()).expect_err("no dense survey");
    assert!(e.to_string().contains("no dense_survey"), "{e}");
    let ev = Evaluator::with_world(
        &b,
        &DEMO,
        WorldModel::Synthetic(s.model.clone()),
        EvalOptions::default(),
    )
    .expect("evaluator");
    assert_eq!(ev.access_points().len(), 10);
    let samples: Vec<Point> = s.file.dense_survey.iter().map(Fingerprint::point).collect();
    let r = ev.evaluate(&samples, 1).expect("evaluate");
    // Recorded 0.61 m (2026-12-02); the evaluation is a function of the seed, so a change
    // beyond rounding means the synthetic world model or the localizer changed.
    assert!(
        (r.mean_error_m - 0.61).abs() < 0.02,
        "mean error {} m, recorded 0.61 m",
        r.mean_error_m
    );
}

#[test]
fn missing_test_points_or_data_are_errors() {
    let b = Building::from_json(DEMO_BUILDING_JSON, "demo").expect("demo");
    let mut file = b.to_file();
    file.test_points.clear();
    let nt = Building::from_file(file, "no tests").expect("valid");
    let e = Evaluator::new(&nt, &DEMO, EvalOptions::default()).expect_err("no tests");
    assert!(e.to_string().contains("no test_points"), "{e}");
    let mut file = b.to_file();
    file.pilot.clear();
    let np = Building::from_file(file, "no pilot").expect("valid");
    let ev = Evaluator::new(&np, &DEMO, EvalOptions::default()).expect("evaluator");
    assert!(ev.evaluate(&[], 1).is_err());
}

#[test]
fn weighted_knn_matches_a_hand_computation() {
    // One access point. A (0,0) -40, B (10,0) -60, C (0,10) -80 on floor 0; D (20,0) -50 on
    // floor 1.
    let points = [
        Point::new(0.0, 0.0, 0),
        Point::new(10.0, 0.0, 0),
        Point::new(0.0, 10.0, 0),
        Point::new(20.0, 0.0, 1),
    ];
    let values = DMatrix::from_column_slice(4, 1, &[-40.0, -60.0, -80.0, -50.0]);
    // z = -45: distances A 5, D 5, B 15 (C 35 is out); weights 1/6, 1/6, 1/16. Floor 0
    // weighs 1/6 + 1/16 > 1/6, so floor 0, at x = (0/6 + 10/16) / (1/6 + 1/16) = 30/11.
    let p = knn_locate(&[-45.0], &points, &values, 3);
    assert_eq!(p.floor, 0);
    assert!((p.x - 30.0 / 11.0).abs() < 1e-12, "{p:?}");
    assert!(p.y.abs() < 1e-12);
    // z = -50: D at distance 0 weighs 1, A and B 1/11 each: floor 1, exactly at D.
    let p = knn_locate(&[-50.0], &points, &values, 3);
    assert_eq!(p, Point::new(20.0, 0.0, 1));
    // k = 1 is nearest neighbour; k larger than the map uses all of it.
    assert_eq!(knn_locate(&[-79.0], &points, &values, 1), points[2]);
    let all = knn_locate(&[-60.0], &points[..3], &values.rows(0, 3).into_owned(), 10);
    // Weights 1/21, 1/1, 1/21: x = 10 / (1 + 2/21) * 1, y = (10/21) / (1 + 2/21).
    let wsum = 1.0 + 2.0 / 21.0;
    assert!((all.x - 10.0 / wsum).abs() < 1e-12 && (all.y - (10.0 / 21.0) / wsum).abs() < 1e-12);
}

#[test]
fn localizer_names_parse_and_bad_ones_are_refused() {
    assert_eq!(Localizer::parse("gp").expect("gp"), Localizer::Gp);
    assert_eq!(
        Localizer::parse("knn").expect("knn"),
        Localizer::Knn { k: 3 }
    );
    assert_eq!(
        Localizer::parse("knn:5").expect("knn:5"),
        Localizer::Knn { k: 5 }
    );
    for bad in ["knn:0", "knn:x", "nearest", ""] {
        let e = Localizer::parse(bad).expect_err(bad).to_string();
        assert!(e.contains("localizer") && e.contains(bad), "{e}");
    }
}

#[test]
fn both_localizers_locate_a_dense_walk_on_area_two() {
    let b = fixture("area-two.json");
    let ev = Evaluator::new(&b, &AREA_TWO, EvalOptions::default()).expect("evaluator");
    let pts = dense_points(&b);
    let gp = ev.evaluate_with(&pts, 1, Localizer::Gp).expect("gp");
    let knn = ev
        .evaluate_with(&pts, 1, Localizer::Knn { k: 3 })
        .expect("knn");
    assert_eq!(gp, ev.evaluate(&pts, 1).expect("default"));
    assert_eq!(knn.errors_m.len(), b.test_points.len());
    // Recorded (2026-12-02): gp 0.56 m, knn 0.64 m (docs/results.md: 0.57 m and 0.63 m
    // over five seeds). A function of the seed: a change beyond rounding means a changed
    // localizer or world model.
    for (what, got, recorded) in [
        ("gp", gp.mean_error_m, 0.56),
        ("knn", knn.mean_error_m, 0.64),
    ] {
        assert!(
            (got - recorded).abs() < 0.02,
            "{what}: mean error {got} m, recorded {recorded} m"
        );
    }
    assert_ne!(gp.errors_m, knn.errors_m);
}

#[test]
fn collected_fingerprints_are_judged_on_their_own_readings() {
    let b = fixture("area-two.json");
    // The dense survey's own measured fingerprints, taken as if a session collected them.
    let collected: Vec<LabelledFingerprint> = b
        .dense_survey
        .iter()
        .map(|f| LabelledFingerprint {
            pos: f.point(),
            extra_noise: 0.0,
            rss: f.rss.clone(),
        })
        .collect();
    let opts = EvalOptions::default();
    let full =
        evaluate_collected(&b, &AREA_TWO, &collected, &opts, Localizer::Gp, 1).expect("eval");
    let loc = full
        .localization
        .as_ref()
        .expect("test points are measured");
    assert_eq!(loc.errors_m.len(), b.test_points.len());
    assert_eq!(full.collected, collected.len());
    let none = evaluate_collected(&b, &AREA_TWO, &[], &opts, Localizer::Gp, 1).expect("pilot only");
    // More fingerprints: a better map and less uncertainty everywhere.
    let none_loc = none.localization.as_ref().expect("pilot map");
    assert!(
        loc.mean_error_m < none_loc.mean_error_m,
        "{loc:?} vs {none_loc:?}"
    );
    assert!(full.std_mean_db < none.std_mean_db && full.std_max_db <= none.std_max_db);
    let knn = evaluate_collected(&b, &AREA_TWO, &collected, &opts, Localizer::Knn { k: 3 }, 1)
        .expect("knn");
    assert!(knn.localization.expect("knn").mean_error_m.is_finite());
}
