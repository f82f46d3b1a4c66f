//! Floor plans in (issue 17, part 1): the OSM indoor and IMDF test maps of
//! `fixtures/floorplans/` import into buildings whose graph is what a surveyor can walk.
//!
//! Checked on every map: vertices inside walkable outlines; every edge inside walkable
//! space or within 0.1 m of a door or opening vertex; no edge across a wall but at a door;
//! rooms joined through their door, or through the middle of the boundary they share with
//! the corridor; floors joined at stairs and elevators with the documented lengths; messy
//! input gives counted warnings and a building; nothing walkable is refused.

#![allow(clippy::expect_used, clippy::unwrap_used)]

use std::path::{Path, PathBuf};

use geo::{Contains, Coord, Distance, Euclidean, LineString, Point, Polygon};
use trailprint::Building;
use trailprint::building::{BuildingFile, GeoOrigin, OutlineKind};
use trailprint::floorplan::{
    ELEVATOR_BASE_M, ELEVATOR_M_PER_LEVEL, FloorplanImport, Format, ImportOptions, LocalFrame,
    STAIRS_M_PER_LEVEL, import_osm_text, import_path,
};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/floorplans")
}

fn import(name: &str) -> (FloorplanImport, Building) {
    let r = import_path(&fixtures().join(name), &ImportOptions::default()).expect(name);
    let b = Building::from_file(r.file.clone(), name).expect("valid building");
    (r, b)
}

/// Where a point drawn at fixture metres `(x, y)` lands in the imported building: the
/// fixture generator's frame to WGS84 (rounded to 1e-7 degree, as it writes), then the
/// building's frame.
fn at(b: &Building, x: f64, y: f64) -> Coord<f64> {
    let fixture = LocalFrame::new(GeoOrigin {
        lat: 48.8763,
        lon: 2.3591,
    });
    let (lon, lat) = fixture.to_wgs84(x, y);
    let (lon, lat) = ((lon * 1e7).round() / 1e7, (lat * 1e7).round() / 1e7);
    let (x, y) = LocalFrame::new(b.geo.expect("geo")).to_local(lon, lat);
    Coord { x, y }
}

/// The rectangle from `(x0, y0)` to `(x1, y1)` in fixture metres, in the building's frame
/// (see [`at`]).
fn rect_at(b: &Building, (x0, y0): (f64, f64), (x1, y1): (f64, f64)) -> Polygon<f64> {
    Polygon::new(
        LineString::from(vec![
            at(b, x0, y0),
            at(b, x1, y0),
            at(b, x1, y1),
            at(b, x0, y1),
        ]),
        vec![],
    )
}

fn walkable(b: &Building, floor: i64) -> Vec<Polygon<f64>> {
    b.outlines
        .iter()
        .filter(|o| o.floor == floor && o.kind.is_walkable())
        .map(|o| {
            Polygon::new(
                LineString::from(o.points.iter().map(|p| (p[0], p[1])).collect::<Vec<_>>()),
                vec![],
            )
        })
        .collect()
}

fn walls(b: &Building, floor: i64) -> Vec<LineString<f64>> {
    b.outlines
        .iter()
        .filter(|o| o.floor == floor && o.kind == OutlineKind::Wall)
        .map(|o| LineString::from(o.points.iter().map(|p| (p[0], p[1])).collect::<Vec<_>>()))
        .collect()
}

fn pos(b: &Building, v: usize) -> Coord<f64> {
    Coord {
        x: b.vertices[v].pos.x,
        y: b.vertices[v].pos.y,
    }
}

fn is_portal(b: &Building, v: usize) -> bool {
    matches!(
        b.vertices[v].label.as_deref(),
        Some("door") | Some("opening")
    )
}

/// The walkable-space properties every imported map must have.
fn check_walkable(b: &Building) {
    for (v, vx) in b.vertices.iter().enumerate() {
        let polys = walkable(b, vx.pos.floor);
        let p = Point(pos(b, v));
        let d = polys
            .iter()
            .map(|poly| Euclidean.distance(&p, poly))
            .fold(f64::INFINITY, f64::min);
        assert!(
            d <= 0.01,
            "vertex {} is {d} m outside walkable space",
            vx.id
        );
    }
    for e in &b.edges {
        let (fa, fb) = (b.vertices[e.a].pos.floor, b.vertices[e.b].pos.floor);
        if fa != fb {
            assert!(e.explicit_length, "edge between floors without a length");
            continue;
        }
        let polys = walkable(b, fa);
        let (a, c) = (pos(b, e.a), pos(b, e.b));
        let len = Euclidean.distance(&Point(a), &Point(c));
        let n = (len / 0.05).ceil().max(1.0) as usize;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let q = a + (c - a) * t;
            let inside = polys
                .iter()
                .any(|poly| Euclidean.distance(&Point(q), poly) <= 1e-6);
            let near_portal = [e.a, e.b].iter().any(|&v| {
                is_portal(b, v) && Euclidean.distance(&Point(q), &Point(pos(b, v))) <= 0.1
            });
            assert!(
                inside || near_portal,
                "edge {}-{} leaves walkable space at ({:.2}, {:.2})",
                b.vertices[e.a].id,
                b.vertices[e.b].id,
                q.x,
                q.y
            );
        }
        // Across a wall only at a door.
        let seg = geo::Line::new(a, c);
        for w in walls(b, fa) {
            for l in w.lines() {
                if let Some(x) = geo::line_intersection::line_intersection(seg, l) {
                    let p = match x {
                        geo::LineIntersection::SinglePoint { intersection, .. } => intersection,
                        geo::LineIntersection::Collinear { intersection } => intersection.start,
                    };
                    let ok = [e.a, e.b].iter().any(|&v| {
                        is_portal(b, v) && Euclidean.distance(&Point(p), &Point(pos(b, v))) <= 0.1
                    });
                    assert!(
                        ok,
                        "edge {}-{} crosses a wall away from a door",
                        b.vertices[e.a].id, b.vertices[e.b].id
                    );
                }
            }
        }
    }
}

/// The vertex at `c` on `floor` with this label: within 2 cm for a door (at the door
/// node), within 0.1 m for an opening (the middle of a shared boundary, sampled every 0.1 m).
fn vertex_at(b: &Building, floor: i64, c: Coord<f64>, label: &str) -> usize {
    let tol = if label == "opening" { 0.1 } else { 0.02 };
    (0..b.len())
        .find(|&v| {
            b.vertices[v].pos.floor == floor
                && b.vertices[v].label.as_deref() == Some(label)
                && Euclidean.distance(&Point(pos(b, v)), &Point(c)) <= tol
        })
        .unwrap_or_else(|| {
            panic!(
                "no {label} vertex at ({:.2}, {:.2}) on floor {floor}",
                c.x, c.y
            )
        })
}

/// Whether `v` has a neighbour labelled `label`.
fn joined_to(b: &Building, v: usize, label: &str) -> bool {
    b.neighbours(v)
        .iter()
        .any(|&(w, _)| b.vertices[w].label.as_deref() == Some(label))
}

fn vertical_lengths(b: &Building) -> Vec<(String, String, f64)> {
    b.edges
        .iter()
        .filter(|e| b.vertices[e.a].pos.floor != b.vertices[e.b].pos.floor)
        .map(|e| {
            (
                b.vertices[e.a].label.clone().unwrap_or_default(),
                b.vertices[e.b].label.clone().unwrap_or_default(),
                e.length,
            )
        })
        .collect()
}

/// [`import`] of a clean test map: the format detected, the building's name and floor ids
/// are `format`, `name` and `floors`, nothing is warned of or dropped, and the building is
/// walkable ([`check_walkable`]).
fn import_clean(
    fixture: &str,
    format: Format,
    name: &str,
    floors: &[i64],
) -> (FloorplanImport, Building) {
    let (r, b) = import(fixture);
    assert_eq!(r.format, format, "{fixture}");
    assert_eq!(b.name, name);
    assert_eq!(b.floors.iter().map(|f| f.id).collect::<Vec<_>>(), floors);
    assert!(r.warnings.is_empty(), "{fixture}: {:?}", r.warnings);
    assert!(r.dropped.is_empty(), "{fixture}: {:?}", r.dropped);
    check_walkable(&b);
    (r, b)
}

#[test]
fn office_on_two_levels_is_walkable_and_joined() {
    let (r, b) = import_clean(
        "office-l.geojson",
        Format::OsmIndoor,
        "Rue des Bureaux 12",
        &[0, 1],
    );

    // Rooms with a door: a door vertex at the door, joined to the room and the corridor.
    for (room, x, y, floor) in [
        ("Office 101", 5.2, 2.4, 0),
        ("Office 103", 17.0, 2.4, 0),
        ("Office 105", 2.4, 10.4, 0),
        ("Meeting room", 5.0, 0.0, 0),
        ("Lab", 15.0, 0.0, 0),
        ("Kitchen", 20.0, 2.4, 1),
    ] {
        let corridor = format!("Corridor {floor}");
        let d = vertex_at(&b, floor, at(&b, x, y), "door");
        assert!(joined_to(&b, d, room), "door of {room} not joined to it");
        assert!(
            joined_to(&b, d, &corridor),
            "door of {room} not joined to the corridor"
        );
    }
    // Office 104 has no door: it is joined in the middle of the 6 m it shares with the corridor.
    let j = vertex_at(&b, 0, at(&b, 23.0, 2.4), "opening");
    assert!(joined_to(&b, j, "Office 104") && joined_to(&b, j, "Corridor 0"));
    // Every office has vertices inside (a grid, not only a door).
    for room in ["Office 101", "Office 102", "Office 106", "Office 201"] {
        let n = b
            .vertices
            .iter()
            .filter(|v| v.label.as_deref() == Some(room))
            .count();
        assert!(n >= 4, "{room}: {n} vertices");
    }
    // The 2.4 m arm of the corridor gets one row of grid vertices along it (where the
    // L's grid puts it, at least 0.3 m from both walls), 2 m apart.
    let (lo, hi) = (at(&b, 15.0, 0.0).y, at(&b, 15.0, 2.4).y);
    let mut ys: Vec<f64> = b
        .vertices
        .iter()
        .filter(|v| v.label.as_deref() == Some("Corridor 0") && v.pos.x > at(&b, 3.0, 0.0).x)
        .map(|v| v.pos.y)
        .collect();
    assert!(ys.len() >= 13, "{ys:?}");
    ys.sort_by(f64::total_cmp);
    assert!(ys[ys.len() - 1] - ys[0] < 1e-3, "one row: {ys:?}");
    assert!(
        ys[0] - lo >= 0.3 && hi - ys[0] >= 0.3,
        "{ys:?} in [{lo}, {hi}]"
    );

    // Floors: the stairwell (8 m per storey) and the elevator (15 m + 3 m per storey).
    let mut v = vertical_lengths(&b);
    v.sort_by(|a, c| a.2.total_cmp(&c.2));
    assert_eq!(v.len(), 2, "{v:?}");
    assert_eq!(v[0].0, "stairs");
    assert_eq!(v[0].2, STAIRS_M_PER_LEVEL);
    assert_eq!(v[1].0, "elevator");
    assert_eq!(v[1].2, ELEVATOR_BASE_M + ELEVATOR_M_PER_LEVEL);
    assert_eq!(r.stats.connectors, 2);
}

#[test]
fn mall_imdf_folder_and_zip() {
    let (r, b) = import_clean("mall-imdf", Format::Imdf, "Galerie Test", &[0, 1]);
    let floor_names: Vec<_> = b.floors.iter().map(|f| f.name.as_deref()).collect();
    assert_eq!(floor_names, [Some("0"), Some("1")]);
    // Nothing stands in, or walks through, the hall's pillar.
    let pillar = rect_at(&b, (19.0, 8.0), (21.0, 10.0));
    for e in b
        .edges
        .iter()
        .filter(|e| b.vertices[e.a].pos.floor == 0 && b.vertices[e.b].pos.floor == 0)
    {
        let line = geo::Line::new(pos(&b, e.a), pos(&b, e.b));
        assert!(
            !geo::Intersects::intersects(&line, &pillar),
            "edge through the pillar"
        );
    }
    // Shops: through their opening; the kiosk, which has none, through its shared boundary.
    let d = vertex_at(&b, 0, at(&b, 5.0, 12.0), "door");
    assert!(joined_to(&b, d, "Bakery") && joined_to(&b, d, "Hall"));
    let j = vertex_at(&b, 0, at(&b, 24.0, 6.0), "opening");
    assert!(joined_to(&b, j, "Kiosk") && joined_to(&b, j, "Hall"));
    // The structure unit is left out.
    let structure = rect_at(&b, (28.2, 0.2), (30.8, 2.8));
    assert!(
        !b.vertices
            .iter()
            .any(|v| v.pos.floor == 0 && structure.contains(&Point::new(v.pos.x, v.pos.y)))
    );
    let mut v = vertical_lengths(&b);
    v.sort_by(|a, c| a.2.total_cmp(&c.2));
    assert_eq!(
        v.iter().map(|x| (x.0.as_str(), x.2)).collect::<Vec<_>>(),
        vec![
            ("stairs", STAIRS_M_PER_LEVEL),
            ("elevator", ELEVATOR_BASE_M + ELEVATOR_M_PER_LEVEL)
        ]
    );

    // The same data set zipped (as IMDF archives are delivered) gives the same building.
    let dir = tempfile::tempdir().unwrap();
    let zip_path = dir.path().join("mall.zip");
    {
        let f = std::fs::File::create(&zip_path).unwrap();
        let mut z = zip::ZipWriter::new(f);
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        let mut names: Vec<_> = std::fs::read_dir(fixtures().join("mall-imdf"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        names.sort();
        for p in names {
            z.start_file(
                format!("mall/{}", p.file_name().unwrap().to_string_lossy()),
                opts,
            )
            .unwrap();
            std::io::Write::write_all(&mut z, &std::fs::read(&p).unwrap()).unwrap();
        }
        z.finish().unwrap();
    }
    let zipped = import_path(&zip_path, &ImportOptions::default()).unwrap();
    assert_eq!(zipped.file, r.file);
}

#[test]
fn messy_export_gives_counted_warnings_and_a_building() {
    let (r, b) = import("messy.geojson");
    let count = |what: &str| {
        r.warnings
            .iter()
            .find(|w| w.what.contains(what))
            .map_or(0, |w| w.count)
    };
    assert_eq!(count("unclosed rings"), 2, "{:?}", r.warnings);
    assert_eq!(count("overlapping walkable polygons"), 1);
    assert_eq!(count("without a level (assumed level 0)"), 1);
    assert_eq!(count("untagged features"), 1);
    assert_eq!(count("without indoor tagging"), 1);
    assert_eq!(count("fewer than 3 distinct points"), 1);
    assert_eq!(count("doors on the outline of no walkable space"), 1);
    assert_eq!(r.warnings.iter().map(|w| w.count).sum::<usize>(), 8);
    // The island room cannot be reached: dropped, and said.
    assert_eq!(r.dropped.len(), 1, "{:?}", r.dropped);
    assert!(
        r.dropped[0].spaces.iter().any(|s| s.contains("Island")),
        "{:?}",
        r.dropped
    );
    assert!(
        !b.vertices
            .iter()
            .any(|v| v.label.as_deref() == Some("Island"))
    );
    // The overlapping room, the room without a level and the open way are all in.
    for room in ["Overlapping", "No level", "Open way"] {
        assert!(
            b.vertices.iter().any(|v| v.label.as_deref() == Some(room)),
            "{room}"
        );
    }
    check_walkable(&b);
}

#[test]
fn nothing_walkable_is_refused_with_a_reason() {
    let err = import_path(
        &fixtures().join("nothing-walkable.geojson"),
        &ImportOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("nothing-walkable.geojson") && err.contains("nothing walkable"),
        "{err}"
    );
    // Projected coordinates are not GeoJSON.
    let text = r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"indoor":"room","level":"0"},
        "geometry":{"type":"Polygon","coordinates":[[[500000,5400000],[500010,5400000],[500010,5400010],[500000,5400000]]]}}]}"#;
    let err = import_osm_text(text, "utm.geojson", &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("not WGS84 longitude/latitude"), "{err}");
    let err = import_osm_text("[1, 2]", "array.geojson", &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("FeatureCollection"), "{err}");
}

#[test]
fn spacing_changes_the_grid() {
    let fine = import_path(
        &fixtures().join("mall-imdf"),
        &ImportOptions {
            spacing_m: 1.0,
            ..ImportOptions::default()
        },
    )
    .unwrap();
    let (coarse, _) = import("mall-imdf");
    assert!(fine.stats.vertices > 3 * coarse.stats.vertices);
    let bad = import_path(
        &fixtures().join("mall-imdf"),
        &ImportOptions {
            spacing_m: 0.0,
            ..ImportOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(bad.contains("--spacing"), "{bad}");
}

/// A lowered `max_grid_cells` refuses a plan that needs more cells than it, naming the
/// limit and a space, and a limit the plan fits in imports it as the default does.
#[test]
fn a_lowered_grid_cell_limit_refuses_a_larger_plan() {
    let (whole, _) = import("mall-imdf");
    let with_limit = |cells: usize| {
        import_path(
            &fixtures().join("mall-imdf"),
            &ImportOptions {
                max_grid_cells: cells,
                ..ImportOptions::default()
            },
        )
    };
    // The grid lays at most one vertex a cell, so the plan needs more cells than a tenth
    // of its vertices.
    let small = whole.stats.vertices / 10;
    let err = with_limit(small).unwrap_err().to_string();
    assert!(
        err.contains("grid cells") && err.contains(&format!("limit of {small}")),
        "{err}"
    );
    assert!(err.contains("on floor"), "{err}");
    let roomy = with_limit(100 * whole.stats.vertices).unwrap();
    assert_eq!(roomy.file, whole.file);
}

/// The building file's `geo` and `outlines` keys (SPEC 7): checked with a clear error.
#[test]
fn geo_and_outlines_are_validated() {
    let base = |extra: &str| {
        format!(
            r#"{{"format": "survey-building/1", "name": "b", "vertices": [{{"id": "a", "x": 0, "y": 0}}],
                "edges": [], {extra}}}"#
        )
    };
    let ok = base(
        r#""geo": {"lat": 48.8, "lon": 2.3}, "outlines": [{"kind": "room", "name": "R", "points": [[0,0],[1,0],[1,1]]},
            {"kind": "wall", "points": [[0,0],[1,0]]}]"#,
    );
    let b = Building::from_json(&ok, "ok.json").unwrap();
    assert_eq!(b.outlines.len(), 2);
    assert_eq!(
        BuildingFile::parse(&b.to_file().to_json(), "again").unwrap(),
        b.to_file()
    );
    for (extra, needle) in [
        (r#""geo": {"lat": 91, "lon": 2}"#, "geo.lat"),
        (r#""geo": {"lat": 1, "lon": -181}"#, "geo.lon"),
        (
            r#""outlines": [{"kind": "door", "points": [[0,0],[1,0],[1,1]]}]"#,
            "outlines[0].kind",
        ),
        (
            r#""outlines": [{"kind": "room", "points": [[0,0],[1,0]]}]"#,
            "at least 3 distinct points",
        ),
        (
            r#""outlines": [{"kind": "area", "points": [[0,0],[1,0],[1,1],[0,0]]}]"#,
            "repeats the first",
        ),
        // The limit named as a vertex's is (one constant, SPEC 7).
        (
            r#""outlines": [{"kind": "corridor", "points": [[0,0],[2e6,0],[1,1]]}]"#,
            "outlines[0].points[1][0]: corridor outline: x must be a finite number of metres \
             with |x| <= 1e6, got 2e6",
        ),
        (
            r#""outlines": [{"kind": "wall", "points": [[0,0]]}]"#,
            "at least 2 points",
        ),
        (
            r#""outlines": [{"floor": 3, "kind": "room", "points": [[0,0],[1,0],[1,1]]}]"#,
            "outlines[0].floor",
        ),
    ] {
        let err = Building::from_json(&base(extra), "bad.json")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.json") && err.contains(needle),
            "{extra}: {err}"
        );
    }
}

/// A generated office floor, drawn the way `make_fixtures.py` draws the test maps and
/// written as an Overpass export: a corridor `length` by `width` metres with rooms
/// north and south of it, each with a door at `door` (fraction along the side it shares
/// with the corridor) or none (joined through the shared boundary); with `wall`, a wall
/// along the corridor's south side (the southern rooms then all have doors); with two
/// levels, the same corridor upstairs, joined by a stairwell room at the east end and an
/// elevator node in the corridor's west end.
#[derive(Debug, Clone)]
struct GeneratedOffice {
    length: f64,
    width: f64,
    north: Vec<(f64, f64, Option<f64>)>,
    south: Vec<(f64, f64, Option<f64>)>,
    wall: bool,
    levels: u8,
}

impl GeneratedOffice {
    fn geojson(&self) -> String {
        let frame = LocalFrame::new(GeoOrigin {
            lat: 48.8763,
            lon: 2.3591,
        });
        let ll = |x: f64, y: f64| {
            let (lon, lat) = frame.to_wgs84(x, y);
            serde_json::json!([(lon * 1e7).round() / 1e7, (lat * 1e7).round() / 1e7])
        };
        let ring = |pts: &[(f64, f64)]| {
            let mut r: Vec<_> = pts.iter().map(|&(x, y)| ll(x, y)).collect();
            r.push(r[0].clone());
            serde_json::json!({"type": "Polygon", "coordinates": [r]})
        };
        let rect =
            |x0: f64, y0: f64, x1: f64, y1: f64| ring(&[(x0, y0), (x1, y0), (x1, y1), (x0, y1)]);
        let mut features = Vec::new();
        let mut feature = |props: serde_json::Value, geometry: serde_json::Value| {
            let id = format!("way/{}", 1000 + features.len());
            features.push(serde_json::json!({"type": "Feature", "id": id, "properties": props, "geometry": geometry}));
        };
        let (l, w) = (self.length, self.width);
        let levels: Vec<String> = (0..self.levels).map(|i| i.to_string()).collect();
        for lvl in &levels {
            feature(
                serde_json::json!({"indoor": "corridor", "level": lvl, "name": format!("Corridor {lvl}")}),
                rect(0.0, 0.0, l, w),
            );
            for (side, rooms) in [("N", &self.north), ("S", &self.south)] {
                let mut x = 0.0;
                for (i, &(width, depth, door)) in rooms.iter().enumerate() {
                    let (y0, y1, yd) = if side == "N" {
                        (w, w + depth, w)
                    } else {
                        (-depth, 0.0, 0.0)
                    };
                    feature(
                        serde_json::json!({"indoor": "room", "level": lvl, "name": format!("Room {side}{i} level {lvl}")}),
                        rect(x, y0, x + width, y1),
                    );
                    if let Some(t) = door {
                        feature(
                            serde_json::json!({"door": "hinged", "level": lvl}),
                            serde_json::json!({"type": "Point", "coordinates": ll(x + t * width, yd)}),
                        );
                    }
                    x += width;
                }
            }
            if self.wall {
                feature(
                    serde_json::json!({"indoor": "wall", "level": lvl}),
                    serde_json::json!({"type": "LineString", "coordinates": [ll(0.0, 0.0), ll(l, 0.0)]}),
                );
            }
        }
        if self.levels > 1 {
            let all = levels.join(";");
            feature(
                serde_json::json!({"indoor": "room", "stairs": "yes", "level": all, "name": "Stairs"}),
                rect(l, 0.0, l + 3.0, w),
            );
            feature(
                serde_json::json!({"door": "hinged", "level": all}),
                serde_json::json!({"type": "Point", "coordinates": ll(l, w / 2.0)}),
            );
            feature(
                serde_json::json!({"highway": "elevator", "level": all}),
                serde_json::json!({"type": "Point", "coordinates": ll(0.6, w / 2.0)}),
            );
        }
        serde_json::json!({"type": "FeatureCollection", "generator": "overpass-turbo", "features": features})
            .to_string()
    }
}

/// Rooms along one side of the corridor: widths that fill at most `length`, depths, and a
/// door (a fraction along the room's corridor side, away from its corners) or none.
fn rooms(
    length: f64,
    doors_always: bool,
) -> impl proptest::strategy::Strategy<Value = Vec<(f64, f64, Option<f64>)>> {
    use proptest::prelude::*;
    proptest::collection::vec(
        (
            1.5f64..8.0,
            2.0f64..7.0,
            (any::<bool>(), 0.2f64..0.8).prop_map(move |(d, t)| (d || doors_always).then_some(t)),
        ),
        1..6,
    )
    .prop_map(move |mut v| {
        let mut x = 0.0;
        v.retain(|r| {
            x += r.0;
            x <= length
        });
        v
    })
}

fn generated_office() -> impl proptest::strategy::Strategy<Value = GeneratedOffice> {
    use proptest::prelude::*;
    (8.0f64..30.0, 1.5f64..4.0, any::<bool>(), 1u8..=2).prop_flat_map(
        |(length, width, wall, levels)| {
            (rooms(length, false), rooms(length, wall)).prop_map(move |(north, south)| {
                GeneratedOffice {
                    length,
                    width,
                    north,
                    south,
                    wall,
                    levels,
                }
            })
        },
    )
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 32, .. proptest::prelude::ProptestConfig::default() })]

    /// On generated office floors (any corridor, rooms of any size with or without doors,
    /// a wall or none, one or two levels) the import's properties hold: every vertex in
    /// walkable space, every edge inside it or through a door (never across a wall
    /// elsewhere), every room reached from the corridor (nothing dropped, one connected
    /// part), levels joined at the stairs and the elevator with the documented lengths.
    #[test]
    fn generated_offices_import_walkable_connected_and_joined(
        office in generated_office(),
        spacing in proptest::sample::select(vec![1.0, 2.0, 3.0]),
    ) {
        let text = office.geojson();
        let opts = ImportOptions { spacing_m: spacing, ..ImportOptions::default() };
        let r = import_osm_text(&text, "generated.geojson", &opts).expect("imports");
        let b = Building::from_file(r.file.clone(), "generated").expect("valid building");
        proptest::prop_assert!(r.dropped.is_empty(), "{:?}", r.dropped);
        proptest::prop_assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        check_walkable(&b);
        // Every room has a vertex, and the building is one connected part.
        for lvl in 0..office.levels {
            for (side, rooms) in [("N", &office.north), ("S", &office.south)] {
                for i in 0..rooms.len() {
                    let name = format!("Room {side}{i} level {lvl}");
                    proptest::prop_assert!(
                        b.vertices.iter().any(|v| v.label.as_deref() == Some(name.as_str())),
                        "{name} has no vertex"
                    );
                }
            }
        }
        let mut seen = vec![false; b.len()];
        let mut stack = vec![0];
        seen[0] = true;
        while let Some(v) = stack.pop() {
            for &(w, _) in b.neighbours(v) {
                if !seen[w] {
                    seen[w] = true;
                    stack.push(w);
                }
            }
        }
        proptest::prop_assert!(seen.iter().all(|&s| s), "not one connected part");
        let mut vertical: Vec<(String, f64)> =
            vertical_lengths(&b).into_iter().map(|(a, _, l)| (a, l)).collect();
        vertical.sort_by(|a, c| a.1.total_cmp(&c.1));
        if office.levels == 2 {
            proptest::prop_assert_eq!(
                vertical,
                vec![
                    ("stairs".to_string(), STAIRS_M_PER_LEVEL),
                    ("elevator".to_string(), ELEVATOR_BASE_M + ELEVATOR_M_PER_LEVEL)
                ]
            );
        } else {
            proptest::prop_assert!(vertical.is_empty());
        }
    }
}
