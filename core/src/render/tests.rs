//! Rendering tests: the SVG is well formed and holds what was asked for.

use super::*;
use crate::samples::{SurveyorModel, sample_walk};
use crate::synth::DEMO_BUILDING_JSON;

fn count(svg: &str, needle: &str) -> usize {
    svg.matches(needle).count()
}

/// A minimal XML well-formedness check: tags balance and nest.
fn assert_balanced(svg: &str) {
    let mut stack: Vec<String> = Vec::new();
    let mut rest = svg;
    while let Some(i) = rest.find('<') {
        rest = &rest[i + 1..];
        let end = rest.find('>').expect("tag closes");
        let tag = &rest[..end];
        rest = &rest[end + 1..];
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(
                stack.pop().as_deref(),
                Some(name.trim()),
                "mismatched </{name}>"
            );
        } else if !tag.ends_with('/') && !tag.starts_with('?') && !tag.starts_with('!') {
            let name = tag.split_whitespace().next().expect("tag name");
            stack.push(name.to_string());
        }
    }
    assert!(stack.is_empty(), "unclosed: {stack:?}");
}

fn demo() -> Building {
    Building::from_json(DEMO_BUILDING_JSON, "demo").expect("demo")
}

#[test]
fn building_alone_has_one_element_per_edge_vertex_and_pilot() {
    let b = demo();
    let svg = render_svg(&b, &Scene::default(), &RenderOptions::default()).expect("svg");
    assert_balanced(&svg);
    assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
    assert_eq!(count(&svg, "class=\"edge\""), b.edges.len());
    assert_eq!(count(&svg, "class=\"vertex\""), b.len());
    assert_eq!(count(&svg, "class=\"pilot\""), b.pilot.len());
    assert_eq!(count(&svg, "<polyline"), 0);
    assert_eq!(count(&svg, "class=\"heat\""), 0, "no kernel, no heat map");
    assert_eq!(count(&svg, "class=\"floor\""), 1);
}

#[test]
fn walk_samples_and_heat_map() {
    let b = demo();
    let ids = ["f0-c00", "f0-c01", "f0-c02", "f0-c03", "f0-c02"];
    let walk = b.resolve_walk(&ids).expect("walk");
    let kernel = Kernel::new(60.0, 8.0, 4.0);
    let samples = sample_walk(&b, &walk, &SurveyorModel::robot(), &kernel).expect("samples");
    let scene = Scene {
        walk,
        samples: samples.clone(),
        kernel: Some(kernel),
    };
    let options = RenderOptions {
        labels: true,
        ..RenderOptions::default()
    };
    let svg = render_svg(&b, &scene, &options).expect("svg");
    assert_balanced(&svg);
    assert_eq!(count(&svg, "<polyline"), 1, "one polyline per walk");
    assert_eq!(count(&svg, "class=\"arrow\""), ids.len() - 1);
    assert_eq!(count(&svg, "class=\"sample\""), samples.len());
    let grid = reference_grid(&b, 0.5, 1.5);
    assert_eq!(count(&svg, "class=\"heat\""), grid.len());
    assert_eq!(count(&svg, "class=\"label\""), b.len() + 3); // ids + 3 legend texts
    assert_eq!(count(&svg, "class=\"start\""), 1);
    assert_eq!(count(&svg, "class=\"end\""), 1);
}

#[test]
fn one_panel_per_floor_and_stairs_markers() {
    let s = crate::synth::generate(&crate::synth::SynthParams {
        floors: 3,
        rooms_per_side: 1,
        corridor_length_m: 10.0,
        aps: 3,
        pilot: 5,
        test_points: 5,
        dense_spacing_m: 2.0,
        ..crate::synth::SynthParams::default()
    })
    .expect("generate");
    let b = Building::from_file(s.file, "three").expect("valid");
    // A walk up the stairs: one polyline per floor run.
    let walk = b
        .resolve_walk(&["f0-c01", "f0-c00", "f1-c00", "f1-c01", "f1-c00", "f2-c00"])
        .expect("walk");
    let scene = Scene {
        walk,
        ..Scene::default()
    };
    let svg = render_svg(&b, &scene, &RenderOptions::default()).expect("svg");
    assert_balanced(&svg);
    assert_eq!(count(&svg, "class=\"floor\""), 3);
    assert_eq!(
        count(&svg, "<polyline"),
        2,
        "floor 0 and floor 1 runs; floor 2 is one vertex"
    );
    assert_eq!(
        count(&svg, "class=\"stairs\""),
        4,
        "two staircases, two ends each"
    );
}

#[test]
fn names_are_escaped_and_bad_walks_rejected() {
    let mut file = demo().to_file();
    file.name = "A & B <C>".into();
    let b = Building::from_file(file, "x").expect("valid");
    let svg = render_svg(&b, &Scene::default(), &RenderOptions::default()).expect("svg");
    assert!(svg.contains("A &amp; B &lt;C&gt;"));
    assert_balanced(&svg);
    let scene = Scene {
        walk: vec![0, 40],
        ..Scene::default()
    };
    assert!(render_svg(&b, &scene, &RenderOptions::default()).is_err());
}
