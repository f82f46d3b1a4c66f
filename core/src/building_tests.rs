//! Validation tests: every rule of SPEC sections 1 and 7, each with its message checked.

use super::*;

fn base() -> serde_json::Value {
    serde_json::json!({
        "format": "survey-building/1",
        "name": "T",
        "vertices": [
            {"id": "a", "x": 0.0, "y": 0.0},
            {"id": "b", "x": 3.0, "y": 4.0},
            {"id": "c", "x": 3.0, "y": 0.0, "label": "Lobby"}
        ],
        "edges": [{"a": "a", "b": "b"}, {"a": "b", "b": "c", "length": 4.5}]
    })
}

/// [`base`], as `edit` changes it.
fn with(edit: impl FnOnce(&mut serde_json::Value)) -> serde_json::Value {
    let mut v = base();
    edit(&mut v);
    v
}

fn base_building() -> Building {
    Building::from_json(&base().to_string(), "t.json").expect("valid")
}

fn err_of(v: serde_json::Value) -> String {
    match Building::from_json(&v.to_string(), "t.json") {
        Ok(_) => panic!("expected an error for {v}"),
        Err(e) => e.to_string(),
    }
}

/// Checks that [`base`], as `edit` changes it, is refused with a message containing `want`.
fn assert_refused(edit: impl FnOnce(&mut serde_json::Value), want: &str) {
    let e = err_of(with(edit));
    assert!(e.contains(want), "expected {want:?} in: {e}");
}

#[test]
fn valid_building_loads_with_lengths_and_adjacency() {
    let b = base_building();
    assert_eq!(b.len(), 3);
    assert!((b.edges[0].length - 5.0).abs() < 1e-12, "Euclidean default");
    assert_eq!(b.edges[1].length, 4.5);
    assert_eq!(b.vertex_index("c"), Some(2));
    assert!(b.edge_between(0, 1).is_some() && b.edge_between(0, 2).is_none());
    assert_eq!(b.walk_length(&[0, 1, 2, 1]), 5.0 + 4.5 + 4.5);
    assert_eq!(b.graph.node_count(), 3);
    assert_eq!(b.graph.edge_count(), 2);
}

#[test]
fn export_then_import_gives_the_same_building() {
    let b = base_building();
    let text = b.to_file().to_json();
    let b2 = Building::from_json(&text, "again").expect("valid");
    assert_eq!(b.to_file(), b2.to_file());
}

#[test]
fn unknown_format_version() {
    assert_refused(
        |v| v["format"] = "survey-building/2".into(),
        "t.json: format: unknown format version \"survey-building/2\"",
    );
}

#[test]
fn unknown_vertex_in_edge() {
    assert_refused(
        |v| v["edges"][1]["b"] = "zz".into(),
        "edges[1].b: unknown vertex \"zz\"",
    );
}

#[test]
fn duplicate_vertex_id() {
    assert_refused(
        |v| v["vertices"][2]["id"] = "a".into(),
        "vertices[2].id: duplicate vertex id \"a\" (first at vertices[0])",
    );
}

#[test]
fn duplicate_position_on_a_floor() {
    assert_refused(
        |v| v["vertices"][2]["x"] = 0.0.into(),
        "duplicate position: vertex \"c\" and vertex \"a\" are both at (0, 0) on floor 0",
    );
}

#[test]
fn same_position_on_two_floors_is_fine_but_needs_explicit_length() {
    let mut v = base();
    v["floors"] = serde_json::json!([{"id": 0}, {"id": 1}]);
    v["vertices"][2] = serde_json::json!({"id": "c", "x": 0.0, "y": 0.0, "floor": 1});
    v["edges"][1] = serde_json::json!({"a": "a", "b": "c"});
    let e = err_of(v.clone());
    assert!(
        e.contains(
            "edges[1].length: edge \"a\"-\"c\" joins floors 0 and 1 and needs an explicit length"
        ),
        "{e}"
    );
    v["edges"][1]["length"] = 6.0.into();
    let b = Building::from_json(&v.to_string(), "t.json").expect("valid with length");
    assert_eq!(b.edges[1].length, 6.0);
}

#[test]
fn vertex_on_unknown_floor() {
    assert_refused(
        |v| v["vertices"][1]["floor"] = 3.into(),
        "vertices[1].floor: vertex \"b\" is on floor 3, which is not in `floors`",
    );
}

#[test]
fn negative_and_tiny_lengths() {
    assert_refused(
        |v| v["edges"][1]["length"] = (-1.0).into(),
        "edges[1].length: edge \"b\"-\"c\": length must be a finite non-negative number, got -1",
    );
    assert_refused(
        |v| v["edges"][1]["length"] = 1e-7.into(),
        "is shorter than 0.000001 m",
    );
}

#[test]
fn length_shorter_than_straight_line() {
    assert_refused(
        |v| v["edges"][1]["length"] = 3.9.into(),
        "edges[1].length: edge \"b\"-\"c\": length 3.9 m is shorter than the straight-line distance 4.000000 m",
    );
}

#[test]
fn self_loop() {
    assert_refused(
        |v| v["edges"][0]["b"] = "a".into(),
        "edges[0]: self-loop at vertex \"a\"",
    );
}

#[test]
fn same_pair_twice() {
    assert_refused(
        |v| {
            v["edges"]
                .as_array_mut()
                .expect("array")
                .push(serde_json::json!({"a": "b", "b": "a"}));
        },
        "edges[2]: vertices \"b\" and \"a\" are already joined by edges[0]",
    );
}

#[test]
fn disconnected_graph_names_components() {
    assert_refused(
        |v| {
            v["vertices"]
                .as_array_mut()
                .expect("array")
                .push(serde_json::json!({"id": "d", "x": 9.0, "y": 9.0}));
        },
        "the graph is disconnected: 2 components (3 vertices including \"a\"; 1 vertices including \"d\")",
    );
}

#[test]
fn non_finite_numbers_are_rejected() {
    // JSON has no NaN literal; an overflowing literal is how a non-finite number arrives.
    let text = base().to_string().replace("\"x\":3.0", "\"x\":1e999");
    let e = Building::from_json(&text, "t.json").expect_err("overflow");
    assert!(e.to_string().contains("t.json: vertices[1].x"), "{e}");
    assert_refused(
        |v| v["pilot"] = serde_json::json!([{"x": 0.0, "y": 1.0, "rss": {"ap": 5.0e3}}]),
        "pilot[0].rss.ap: RSS must be a finite dBm value in [-120, 0], got 5000",
    );
    assert_refused(
        |v| v["kernel"] = serde_json::json!({"sf2": 1.0, "ell": -2.0, "sn2": 1.0}),
        "kernel.ell: must be a finite positive number, got -2",
    );
}

#[test]
fn trailing_data_after_the_document_is_refused() {
    let text = base().to_string();
    for (tail, what) in [
        (" THIS IS NOT JSON", "stray text"),
        ("\n{\"format\": \"survey-building/1\"}", "a second document"),
        (&*base().to_string(), "the same document twice"),
        ("]", "a stray bracket"),
    ] {
        let e = Building::from_json(&format!("{text}{tail}"), "t.json")
            .expect_err(what)
            .to_string();
        assert!(
            e.starts_with(
                "t.json: unexpected data after the JSON document (trailing characters at line"
            ),
            "{what}: {e}"
        );
    }
    // Whitespace after the document is not data.
    Building::from_json(&format!("{text} \n\t\r\n"), "t.json").expect("trailing whitespace");
}

#[test]
fn positional_arrays_are_refused_naming_the_path() {
    let cases: Vec<(&str, serde_json::Value, &str)> = vec![
        (
            "vertices",
            serde_json::json!([["a", 0.0, 0.0, 0], {"id": "b", "x": 3.0, "y": 4.0}, {"id": "c", "x": 3.0, "y": 0.0}]),
            "vertices[0]",
        ),
        (
            "edges",
            serde_json::json!([{"a": "a", "b": "b"}, ["b", "c", 4.5]]),
            "edges[1]",
        ),
        ("floors", serde_json::json!([[0, "Ground"]]), "floors[0]"),
        (
            "pilot",
            serde_json::json!([[0.0, 1.0, 0, {"ap": -60.0}]]),
            "pilot[0]",
        ),
        (
            "test_points",
            serde_json::json!([[0.0, 1.0]]),
            "test_points[0]",
        ),
        (
            "dense_survey",
            serde_json::json!([{"x": 0.0, "y": 1.0}, [0.0, 2.0]]),
            "dense_survey[1]",
        ),
        ("kernel", serde_json::json!([40.0, 6.0, 9.0]), "kernel"),
    ];
    for (field, value, path) in cases {
        let e = err_of(with(|v| v[field] = value));
        assert!(
            e.starts_with(&format!(
                "t.json: {path}: invalid type: sequence, expected a JSON object"
            )),
            "{field}: {e}"
        );
    }
    // The whole document as an array.
    let e = Building::from_json(r#"["survey-building/1", "T", [], []]"#, "t.json")
        .expect_err("array document")
        .to_string();
    assert!(
        e.starts_with("t.json: invalid type: sequence, expected a JSON object"),
        "{e}"
    );
}

#[test]
fn nulls_are_refused_naming_the_path() {
    use serde_json::Value::Null;
    let cases = [
        (with(|v| v["floors"] = Null), "floors"),
        (
            with(|v| v["vertices"][2]["label"] = Null),
            "vertices[2].label",
        ),
        (with(|v| v["edges"][1]["length"] = Null), "edges[1].length"),
        (
            with(|v| v["floors"] = serde_json::json!([{"id": 0, "name": null}])),
            "floors[0].name",
        ),
        (with(|v| v["kernel"] = Null), "kernel"),
        (with(|v| v["pilot"] = Null), "pilot"),
        (
            with(|v| v["vertices"][0]["floor"] = Null),
            "vertices[0].floor",
        ),
        (
            with(|v| v["pilot"] = serde_json::json!([{"x": 0.0, "y": 1.0, "rss": null}])),
            "pilot[0].rss",
        ),
    ];
    for (v, path) in cases {
        let e = err_of(v);
        assert!(
            e.starts_with(&format!("t.json: {path}: invalid type: null, expected")),
            "{path}: {e}"
        );
    }
}

#[test]
fn coordinates_and_lengths_are_bounded() {
    // The bound itself is allowed, on both axes and both signs.
    let mut v = base();
    v["vertices"][0]["x"] = serde_json::json!(-1e6);
    v["vertices"][0]["y"] = serde_json::json!(1e6);
    v["pilot"] = serde_json::json!([{"x": 1e6, "y": -1e6, "rss": {"ap": -60.0}}]);
    let b = Building::from_json(&v.to_string(), "t.json").expect("on the bound");
    assert!(b.total_edge_length().is_finite());

    for (path, value) in [("vertices[1].x", 1e308), ("vertices[1].y", -1.000001e6)] {
        let axis = &path[path.len() - 1..];
        let e = err_of(with(|v| v["vertices"][1][axis] = serde_json::json!(value)));
        assert!(
            e.contains(&format!(
                "t.json: {path}: vertex \"b\": {axis} must be a finite number of metres with |{axis}| <= 1e6, got {value:e}"
            )),
            "{e}"
        );
    }
    assert_refused(
        |v| v["test_points"] = serde_json::json!([{"x": 0.0, "y": 2e6}]),
        "t.json: test_points[0].y: must be a finite number of metres with |y| <= 1e6, got 2e6",
    );
    // An explicit length may exceed the straight line, but not without bound.
    assert_refused(
        |v| v["edges"][1]["length"] = serde_json::json!(1e300),
        "t.json: edges[1].length: edge \"b\"-\"c\": length 1e300 m is longer than 1e7 m",
    );
}

#[test]
fn rss_is_between_minus_120_and_0_dbm() {
    for ok in [-120.0, -60.5, 0.0] {
        let v = with(|v| v["pilot"] = serde_json::json!([{"x": 0.0, "y": 1.0, "rss": {"ap": ok}}]));
        Building::from_json(&v.to_string(), "t.json").expect("in range");
    }
    for (field, bad) in [
        ("pilot", 25.0),
        ("test_points", -120.5),
        ("dense_survey", 0.01),
    ] {
        let e = err_of(with(|v| {
            v[field] = serde_json::json!([{"x": 0.0, "y": 1.0, "rss": {"ap-7": bad}}]);
        }));
        assert!(
            e.contains(&format!(
                "t.json: {field}[0].rss.ap-7: RSS must be a finite dBm value in [-120, 0], got {bad}"
            )),
            "{e}"
        );
    }
}

#[test]
fn wrong_types_name_the_json_path() {
    let mut v = base();
    v["vertices"][1]["x"] = "three".into();
    let e = Building::from_json(&v.to_string(), "t.json").expect_err("type");
    let s = e.to_string();
    assert!(
        s.starts_with("t.json: vertices[1].x: invalid type: string \"three\""),
        "{s}"
    );
    let e = Building::from_json("{not json", "t.json")
        .expect_err("syntax")
        .to_string();
    assert!(e.starts_with("t.json: "), "{e}");
}

#[test]
fn walks_are_resolved_and_checked() {
    let b = base_building();
    assert_eq!(
        b.resolve_walk(&["a", "b", "c"]).expect("walk"),
        vec![0, 1, 2]
    );
    let e = b
        .resolve_walk(&["a", "c"])
        .expect_err("no edge")
        .to_string();
    assert_eq!(e, "invalid walk at step 1: no edge between \"a\" and \"c\"");
    let e = b
        .resolve_walk(&["a", "q"])
        .expect_err("unknown")
        .to_string();
    // No id is a near miss of a one-letter id: the message says what the ids look like.
    assert!(
        e.starts_with("invalid walk at step 1: unknown vertex \"q\"; its ")
            && e.contains(" vertex ids run from \"a\" to "),
        "{e}"
    );
    let near = b.similar_vertex_ids("A");
    assert_eq!(near, vec!["a"], "case is ignored");
}

#[test]
fn shared_instances_load() {
    for name in ["area-one.json", "area-two.json"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures")
            .join(name);
        let b = Building::load(&path).expect("shared instance is valid");
        assert!(b.len() > 20 && !b.pilot.is_empty());
    }
}
