//! Rendering tests: the SVG is well formed and holds what was asked for.

use super::*;
use crate::eval::reference_grid;
use crate::samples::{Surveyor, sample_walk};
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

/// The value of the first `attr="..."` in `svg`, a number.
fn first_number(svg: &str, attr: &str) -> f64 {
    svg.split(&format!("{attr}=\""))
        .nth(1)
        .and_then(|w| w.split('"').next())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no number {attr}"))
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
    // One element per edge, vertex and pilot location, plus the legend's swatch of each.
    assert_eq!(count(&svg, "class=\"edge\""), b.edges.len() + 1);
    assert_eq!(count(&svg, "class=\"vertex\""), b.len() + 1);
    assert_eq!(count(&svg, "class=\"pilot\""), b.pilot.len() + 1);
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
    let samples = sample_walk(&b, &walk, &Surveyor::robot(), &kernel).expect("samples");
    let scene = Scene {
        samples: samples.clone(),
        kernel: Some(kernel),
        ..Scene::one_walk(walk, "planned walk")
    };
    let options = RenderOptions {
        labels: true,
        ..RenderOptions::default()
    };
    let svg = render_svg(&b, &scene, &options).expect("svg");
    assert_balanced(&svg);
    assert_eq!(
        count(&svg, "class=\"walk walk-0"),
        ids.len() - 1,
        "one segment per step"
    );
    // c02 -> c03 -> c02: that edge is walked there and back, drawn as two lanes.
    assert_eq!(count(&svg, "walk-0 repeat\""), 2);
    assert_eq!(
        count(&svg, "class=\"arrow\""),
        ids.len() - 1 + 1,
        "one per step and the legend's"
    );
    assert!(svg.contains("edge walked twice (there and back)"));
    assert_eq!(
        count(&svg, "class=\"sample\""),
        samples.len() + 1,
        "and the legend's"
    );
    let grid = reference_grid(&b, 0.5, 1.5);
    assert_eq!(count(&svg, "class=\"heat\""), grid.len());
    let labels = count(&svg, "class=\"label\"") - 1; // the legend's
    assert!(
        labels > b.len() / 2 && labels <= b.len(),
        "{labels} vertex ids placed"
    );
    // One marker each on the map, plus the legend's swatches.
    assert_eq!(count(&svg, "class=\"start\""), 2);
    assert_eq!(count(&svg, "class=\"end\""), 2);
    // Step numbers: f0-c02 is reached at steps 3 and 5.
    assert!(svg.contains(">3,5</text>"), "{svg}");
    // The colour scale spans the values drawn.
    assert!(svg.contains("posterior std. dev. of the RSS"));
    assert!(svg.contains("class=\"scale-bar\""));
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
    let scene = Scene::one_walk(walk, "planned walk");
    let svg = render_svg(&b, &scene, &RenderOptions::default()).expect("svg");
    assert_balanced(&svg);
    assert_eq!(count(&svg, "class=\"floor\""), 3);
    assert_eq!(
        count(&svg, "class=\"walk walk-0"),
        3,
        "one segment on floor 0, two on floor 1; stairs are not drawn as segments"
    );
    assert_eq!(
        count(&svg, "class=\"stairs\""),
        4 + 1,
        "two staircases, two ends each, and the legend's swatch"
    );
    // Floors are named once and the order of the walk is said.
    assert!(svg.contains("walked 1st: steps 1-2"), "{svg}");
    assert!(svg.contains("walked 2nd: steps 3-5"), "{svg}");
    assert!(svg.contains("stairs to Floor 1"), "{svg}");
}

#[test]
fn names_are_escaped_and_bad_walks_rejected() {
    let mut file = demo().to_file();
    file.name = "A & B <C>".into();
    let b = Building::from_file(file, "x").expect("valid");
    let svg = render_svg(&b, &Scene::default(), &RenderOptions::default()).expect("svg");
    assert!(svg.contains("A &amp; B &lt;C&gt;"));
    assert_balanced(&svg);
    let scene = Scene::one_walk(vec![0, 40], "bad");
    assert!(render_svg(&b, &scene, &RenderOptions::default()).is_err());
}

#[test]
fn start_equal_to_end_has_both_markers_and_a_long_strip_is_cut_into_rows() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/area-two.json"
    ))
    .expect("area-two");
    let b = Building::from_json(&text, "area-two").expect("valid");
    let walk = b
        .resolve_walk(&["b00", "b01", "b02", "b01", "b00"])
        .expect("walk");
    let svg = render_svg(&b, &Scene::one_walk(walk, "w"), &RenderOptions::default()).expect("svg");
    assert_balanced(&svg);
    assert!(svg.contains("<title>start: b00</title>") && svg.contains("<title>end: b00</title>"));
    assert!(svg.contains("start = end"));
    // 63 m by 2.5 m: two rows of one floor drawing, not a 1460 x 250 strip.
    assert_eq!(count(&svg, "<use "), 2);
    assert!(svg.contains("part 2 of 2"));
    let (width, height) = (first_number(&svg, "width"), first_number(&svg, "height"));
    assert!(width / height < 3.0, "{width} x {height}");
}

#[test]
fn team_walks_get_one_colour_each() {
    let b = demo();
    let w1 = b
        .resolve_walk(&["f0-c00", "f0-c01", "f0-c02"])
        .expect("walk");
    let w2 = b.resolve_walk(&["f0-c02", "f0-c01"]).expect("walk");
    let scene = Scene {
        walks: vec![
            WalkLayer {
                walk: w1,
                name: "surveyor 1".into(),
            },
            WalkLayer {
                walk: w2,
                name: "surveyor 2".into(),
            },
        ],
        ..Scene::default()
    };
    let svg = render_svg(&b, &scene, &RenderOptions::default()).expect("svg");
    assert_balanced(&svg);
    assert_eq!(count(&svg, "class=\"walk walk-0"), 2);
    assert_eq!(count(&svg, "class=\"walk walk-1"), 1);
    assert_ne!(style::walk_colour(0), style::walk_colour(1));
    assert!(svg.contains(&format!(
        "walk-1 repeat\" stroke=\"{}\"",
        style::walk_colour(1)
    )));
    assert!(svg.contains(">S1</text>") && svg.contains(">E2</text>"));
    // f0-c01 - f0-c02 is walked by both: two lanes, and the legend says so.
    assert_eq!(
        count(&svg, "walk-0 repeat\"") + count(&svg, "walk-1 repeat\""),
        2
    );
    assert!(svg.contains("edge walked twice (there and back, or by two surveyors)"));
}

/// An imported floor plan's heat map covers its rooms, corridors and stairwells whole,
/// not only within 1.5 m of an edge and the vertices' bounding box (which left holes of
/// room colour in the middle of rooms and a strip along the walls).
#[test]
fn heat_map_covers_the_walkable_outlines() {
    use geo::{Contains, Coord, LineString, Polygon};
    let office = crate::floorplan::import_path(
        std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/fixtures/floorplans/office-l.geojson"
        )),
        &crate::floorplan::ImportOptions::default(),
    )
    .expect("office imports");
    let b = Building::from_file(office.file, "office").expect("valid");
    let options = RenderOptions::default();
    let step = options.grid_step_m;
    let grid = heat::heat_grid(&b, step, options.grid_margin_m);
    let mut checked = 0;
    for o in b.outlines.iter().filter(|o| {
        matches!(
            o.kind,
            crate::building::OutlineKind::Room
                | crate::building::OutlineKind::Corridor
                | crate::building::OutlineKind::Area
        )
    }) {
        let ring: Vec<Coord<f64>> = o
            .points
            .iter()
            .map(|p| Coord { x: p[0], y: p[1] })
            .collect();
        let poly = Polygon::new(LineString::from(ring), vec![]);
        let (x0, x1, y0, y1) = o.points.iter().fold(
            (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ),
            |(a, b, c, d), p| (a.min(p[0]), b.max(p[0]), c.min(p[1]), d.max(p[1])),
        );
        // Every point of a fine lattice inside the outline is within a heat cell.
        let mut y = y0 + 0.1;
        while y < y1 {
            let mut x = x0 + 0.1;
            while x < x1 {
                if poly.contains(&Coord { x, y }) {
                    checked += 1;
                    assert!(
                        grid.iter().any(|g| g.floor == o.floor
                            && (g.x - x).abs() <= step / 2.0 + 1e-9
                            && (g.y - y).abs() <= step / 2.0 + 1e-9),
                        "{:?} at ({x:.1}, {y:.1}) floor {}: no heat cell",
                        o.name,
                        o.floor
                    );
                }
                x += 0.3;
            }
            y += 0.3;
        }
    }
    assert!(checked > 1000, "{checked} points checked");
    // And the picture draws one cell per grid point.
    let scene = Scene {
        kernel: Some(Kernel::new(40.0, 6.0, 9.0)),
        ..Scene::default()
    };
    let svg = render_svg(&b, &scene, &options).expect("svg");
    assert_eq!(count(&svg, "class=\"heat\""), grid.len());
    assert!(svg.contains("0.5 m grid, over the rooms and corridors"));
}
