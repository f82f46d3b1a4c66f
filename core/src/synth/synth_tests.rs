//! Generator tests: the shipped demo is reproducible, buildings are valid and sensible.

use super::*;
use crate::building::Building;

fn small(seed: u64) -> SynthParams {
    SynthParams {
        name: "Small".into(),
        floors: 2,
        corridor_length_m: 16.0,
        rooms_per_side: 2,
        aps: 5,
        pilot: 8,
        test_points: 12,
        dense_spacing_m: 1.0,
        seed,
        ..SynthParams::default()
    }
}

#[test]
fn regenerating_the_demo_gives_exactly_the_committed_file() {
    // If this fails after an intended change, regenerate the file with the command in the
    // module docs and commit it.
    let synth = generate(&SynthParams::default()).expect("generate");
    let text = to_json_text(&synth.file);
    assert!(
        text == DEMO_BUILDING_JSON,
        "core/data/demo-building.json differs from the generator's output"
    );
}

#[test]
fn demo_is_a_valid_modest_building_without_a_kernel() {
    let b = Building::from_json(DEMO_BUILDING_JSON, "demo").expect("valid demo");
    assert!((60..=120).contains(&b.len()), "{} vertices", b.len());
    assert_eq!(b.floors.len(), 1);
    assert!(b.kernel.is_none(), "the demo's kernel is to be fitted");
    assert_eq!(b.pilot.len(), 20);
    assert_eq!(b.test_points.len(), 60);
    assert!(b.dense_survey.len() > 200);
    let aps: std::collections::BTreeSet<&String> =
        b.dense_survey.iter().flat_map(|f| f.rss.keys()).collect();
    assert_eq!(aps.len(), 10);
    // Everything heard is at or above the threshold, and something is heard everywhere.
    for fp in b.pilot.iter().chain(&b.test_points).chain(&b.dense_survey) {
        assert!(!fp.rss.is_empty());
        assert!(fp.rss.values().all(|&v| (-100.0..=0.0).contains(&v)));
    }
}

#[test]
fn same_seed_same_building_other_seed_other_building() {
    let a = generate(&small(5)).expect("a");
    let b = generate(&small(5)).expect("b");
    let c = generate(&small(6)).expect("c");
    assert_eq!(a.file, b.file);
    assert_ne!(a.file.dense_survey, c.file.dense_survey);
    assert_ne!(a.file.pilot, c.file.pilot);
}

#[test]
fn more_pilot_points_do_not_move_the_access_points_or_the_dense_survey() {
    let a = generate(&small(5)).expect("a");
    let b = generate(&SynthParams {
        pilot: 30,
        ..small(5)
    })
    .expect("b");
    assert_eq!(a.model, b.model);
    assert_eq!(a.file.dense_survey, b.file.dense_survey);
    assert_eq!(a.file.pilot[..], b.file.pilot[..8]);
}

#[test]
fn multi_floor_building_is_connected_with_explicit_stairs() {
    let s = generate(&small(2)).expect("generate");
    let b = Building::from_file(s.file.clone(), "small").expect("valid");
    let stairs: Vec<_> = b
        .edges
        .iter()
        .filter(|e| b.vertices[e.a].pos.floor != b.vertices[e.b].pos.floor)
        .collect();
    assert_eq!(stairs.len(), 1);
    assert!(stairs[0].explicit_length && stairs[0].length == 8.0);
    // Access points on both floors.
    let floors: std::collections::BTreeSet<i64> = s
        .model
        .access_points()
        .iter()
        .map(|a| a.pos.floor)
        .collect();
    assert_eq!(floors.len(), 2);
    // Both floors have fingerprints.
    assert!(b.dense_survey.iter().any(|f| f.floor == 1));
    assert!(b.pilot.iter().chain(&b.test_points).all(|f| f.floor <= 1));
}

#[test]
fn dense_survey_covers_every_edge_at_the_spacing() {
    let s = generate(&small(3)).expect("generate");
    let b = Building::from_file(s.file, "small").expect("valid");
    for e in &b.edges {
        let (pa, pb) = (b.vertices[e.a].pos, b.vertices[e.b].pos);
        if pa.floor != pb.floor {
            continue;
        }
        // Every point of the edge is within half a spacing (plus rounding) of a survey point.
        for k in 0..=20 {
            let t = k as f64 / 20.0;
            let q = Point::new(pa.x + t * (pb.x - pa.x), pa.y + t * (pb.y - pa.y), pa.floor);
            let near = b
                .dense_survey
                .iter()
                .filter(|f| f.floor == q.floor)
                .map(|f| f.point().planar_distance(&q))
                .fold(f64::INFINITY, f64::min);
            assert!(
                near <= 0.5 + 0.01,
                "edge point {q:?} is {near} m from the survey"
            );
        }
    }
}

#[test]
fn rss_falls_with_distance_on_average() {
    let s = generate(&SynthParams::default()).expect("generate");
    let ap = &s.model.access_points()[0];
    let mean_at = |d: f64| {
        let pts = (0..36).map(|i| {
            let a = i as f64 * std::f64::consts::PI / 18.0;
            Point::new(ap.pos.x + d * a.cos(), ap.pos.y + d * a.sin(), ap.pos.floor)
        });
        pts.map(|p| s.model.mean_rss(0, &p)).sum::<f64>() / 36.0
    };
    assert!(mean_at(2.0) > mean_at(8.0) + 5.0);
    assert!(mean_at(8.0) > mean_at(25.0) + 5.0);
}

#[test]
fn bad_parameters_are_named() {
    let e = generate(&SynthParams {
        floors: 0,
        ..SynthParams::default()
    })
    .expect_err("no floors");
    assert!(e.to_string().contains("floors = 0"), "{e}");
    let e = generate(&SynthParams {
        rooms_per_side: 40,
        ..SynthParams::default()
    })
    .expect_err("narrow rooms");
    assert!(e.to_string().contains("at least 2 m wide"), "{e}");
    let e = generate(&SynthParams {
        corridor_length_m: f64::NAN,
        ..SynthParams::default()
    })
    .expect_err("nan");
    assert!(e.to_string().contains("corridor length"), "{e}");
}

#[test]
fn bare_corridor_works() {
    let s = generate(&SynthParams {
        rooms_per_side: 0,
        ..small(1)
    })
    .expect("generate");
    let b = Building::from_file(s.file, "corridor").expect("valid");
    assert_eq!(b.len(), 2 * 9);
}
