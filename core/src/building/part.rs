//! A part of a building ([`Building::part`]): some of its floors, or what lies within a
//! walking distance of one vertex, as a building of its own.
//!
//! Planning needs memory that grows with the square of the vertex count (the vertex
//! covariance and the shortest-path table), so a building of many thousands of vertices is
//! refused with the size it would need. A surveyor covers one floor or one wing at a time
//! anyway; this cuts that part out, and the part is planned like any building. Its utility
//! is SPEC 3's `f_D` over the part's vertices: the part *is* the building the plan knows.
//!
//! What the part keeps:
//! - the vertices on the floors asked for (all floors when none are), and of those, with
//!   `around`, the ones within the walking distance of a vertex named (of any of them, for
//!   the walks of a team), walking on the kept floors only; the edges between two kept
//!   vertices, with their lengths as written;
//! - the pilot data of the kept floors, all of it: it is what the kernel is fitted on and
//!   what the prior is conditioned on, and a pilot location outside the part only
//!   conditions the part's vertices as far as it is correlated with them;
//! - the test points and the dense survey (what the localization evaluation compares
//!   against) on the kept floors inside the bounding box of the part's vertices there,
//!   widened by [`EVALUATION_MARGIN_M`]: a point outside it would be judged on a radio map
//!   that nothing of the part observes;
//! - the floor-plan outlines of the kept floors, the kernel and the geographic origin.
//!
//! A part whose vertices are not all connected within it (a floor reached only by the
//! stairs of another) is refused with its pieces named, like any disconnected building.

use std::collections::BTreeSet;

use super::{Building, BuildingFile, FORMAT, FloorSpec};
use crate::building::Fingerprint;
use crate::gp::Extent;
use crate::{Error, Result};

/// How far outside the bounding box of a part's vertices (on their floor) a test point or
/// a dense-survey point may lie and still be kept, metres: about one room's depth.
pub const EVALUATION_MARGIN_M: f64 = 2.0;

/// Which part of a building [`Building::part`] keeps.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PartSpec {
    /// Floor ids to keep; empty: every floor.
    pub floors: Vec<i64>,
    /// Keep only the vertices within one of these walking distances (metres) of its
    /// vertex (id), walking on the kept floors; empty: no such limit. Several: the union
    /// (the walks of a team).
    pub around: Vec<(String, f64)>,
    /// The part's name; `None`: the building's, followed by what was kept
    /// (`"Office (floor 1)"`, `"Office (within 120 m of f0-c00)"`).
    pub name: Option<String>,
}

impl Building {
    /// The part of this building that `spec` names, validated like any building file.
    /// Errors name what is wrong (an unknown floor or vertex, a radius that is not a
    /// positive number, a vertex on a floor not kept, a part in pieces) and change nothing.
    pub fn part(&self, spec: &PartSpec) -> Result<Building> {
        let floors: BTreeSet<i64> = self.floors.iter().map(|f| f.id).collect();
        for f in &spec.floors {
            if !floors.contains(f) {
                return Err(Error::InvalidRequest(format!(
                    "building {:?} has no floor {f} (its floors: {})",
                    self.name,
                    join(floors.iter())
                )));
            }
        }
        let on_floor =
            |v: usize| spec.floors.is_empty() || spec.floors.contains(&self.vertices[v].pos.floor);
        let mut keep: Vec<bool> = (0..self.len())
            .map(|v| spec.around.is_empty() && on_floor(v))
            .collect();
        for (id, radius) in &spec.around {
            if !(radius.is_finite() && *radius > 0.0) {
                return Err(Error::InvalidRequest(format!(
                    "the radius of a part must be a positive number of metres, got {radius}"
                )));
            }
            let root = self.require_vertex(id)?;
            if !on_floor(root) {
                return Err(Error::InvalidRequest(format!(
                    "vertex {id:?} is on floor {}, which the part does not keep (floors {})",
                    self.vertices[root].pos.floor,
                    join(spec.floors.iter())
                )));
            }
            let (d, _) = crate::plan::metric::shortest_path_tree_within(self, root, &on_floor);
            for (k, d) in keep.iter_mut().zip(d) {
                *k |= d <= *radius;
            }
        }
        let kept_floors: BTreeSet<i64> = (0..self.len())
            .filter(|&v| keep[v])
            .map(|v| self.vertices[v].pos.floor)
            .collect();
        if kept_floors.is_empty() {
            return Err(Error::InvalidRequest(format!(
                "the part of building {:?} would have no vertex",
                self.name
            )));
        }
        let name = spec.name.clone().unwrap_or_else(|| self.part_name(spec));
        let whole = self.to_file();
        // The extent of the kept vertices on each kept floor, widened by the margin.
        let boxes: Vec<(i64, Extent)> = kept_floors
            .iter()
            .map(|&f| {
                let on_f = (0..self.len())
                    .filter(|&v| keep[v] && self.vertices[v].pos.floor == f)
                    .map(|v| (self.vertices[v].pos.x, self.vertices[v].pos.y));
                (f, Extent::of(on_f).widened(EVALUATION_MARGIN_M))
            })
            .collect();
        let inside = |fp: &&Fingerprint| {
            boxes
                .iter()
                .any(|(f, b)| fp.floor == *f && b.contains(fp.x, fp.y))
        };
        let kept_ids: BTreeSet<&str> = (0..self.len())
            .filter(|&v| keep[v])
            .map(|v| self.vertices[v].id.as_str())
            .collect();
        let file = BuildingFile {
            format: FORMAT.into(),
            name,
            floors: whole.floors.map(|list| {
                list.into_iter()
                    .filter(|f| kept_floors.contains(&f.id))
                    .collect::<Vec<FloorSpec>>()
            }),
            vertices: whole
                .vertices
                .into_iter()
                .filter(|v| kept_ids.contains(v.id.as_str()))
                .collect(),
            edges: whole
                .edges
                .into_iter()
                .filter(|e| kept_ids.contains(e.a.as_str()) && kept_ids.contains(e.b.as_str()))
                .collect(),
            pilot: whole
                .pilot
                .into_iter()
                .filter(|p| kept_floors.contains(&p.floor))
                .collect(),
            test_points: whole.test_points.iter().filter(inside).cloned().collect(),
            dense_survey: whole.dense_survey.iter().filter(inside).cloned().collect(),
            kernel: whole.kernel,
            geo: whole.geo,
            outlines: whole
                .outlines
                .into_iter()
                .filter(|o| kept_floors.contains(&o.floor))
                .collect(),
        };
        let origin = format!("the part of building {:?}", self.name);
        Building::from_file(file, &origin).map_err(|e| match e {
            Error::InvalidBuilding { .. } if spec.around.len() != 1 => {
                Error::InvalidRequest(format!(
                    "{e}; keep the piece around one vertex with a walking distance (on the \
                 command line: --around VERTEX --radius M)"
                ))
            }
            e => e,
        })
    }

    /// The default name of a part: the building's, followed by what was kept.
    fn part_name(&self, spec: &PartSpec) -> String {
        let mut what = Vec::new();
        match spec.floors.as_slice() {
            [] => {}
            [f] => what.push(format!("floor {f}")),
            fs => what.push(format!("floors {}", join(fs.iter()))),
        }
        for (id, r) in &spec.around {
            what.push(format!("within {r} m of {id}"));
        }
        if what.is_empty() {
            what.push("part".into());
        }
        format!("{} ({})", self.name, what.join(", "))
    }
}

fn join<'a>(xs: impl Iterator<Item = &'a i64>) -> String {
    xs.map(|x| x.to_string()).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two floors joined by stairs at one end: floor 0 a corridor a0-a1-a2-a3 (10 m
    /// edges) with a room r0 off a1; floor 1 a corridor b0-b1-b2 over it, the stairs a3-b2.
    fn two_floors() -> Building {
        let text = r#"{"format":"survey-building/1","name":"Two",
          "floors":[{"id":0,"name":"ground"},{"id":1}],
          "vertices":[
            {"id":"a0","x":0,"y":0},{"id":"a1","x":10,"y":0},{"id":"a2","x":20,"y":0},
            {"id":"a3","x":30,"y":0},{"id":"r0","x":10,"y":5},
            {"id":"b0","x":10,"y":0,"floor":1},{"id":"b1","x":20,"y":0,"floor":1},
            {"id":"b2","x":30,"y":0,"floor":1}],
          "edges":[{"a":"a0","b":"a1"},{"a":"a1","b":"a2"},{"a":"a2","b":"a3"},
            {"a":"a1","b":"r0","length":6},{"a":"b0","b":"b1"},{"a":"b1","b":"b2"},
            {"a":"a3","b":"b2","length":8}],
          "pilot":[{"x":0,"y":0,"rss":{"ap":-50}},{"x":30,"y":0,"rss":{"ap":-60}},
            {"x":20,"y":0,"floor":1,"rss":{"ap":-55}}],
          "test_points":[{"x":1,"y":1,"rss":{"ap":-50}},{"x":29,"y":0,"rss":{"ap":-58}},
            {"x":20,"y":1,"floor":1,"rss":{"ap":-55}}],
          "kernel":{"sf2":40,"ell":6,"sn2":9}}"#;
        Building::from_json(text, "two").expect("valid")
    }

    fn ids(b: &Building) -> Vec<&str> {
        b.vertices.iter().map(|v| v.id.as_str()).collect()
    }

    #[test]
    fn a_floor_keeps_its_vertices_edges_pilot_and_the_kernel() {
        let b = two_floors();
        let part = b
            .part(&PartSpec {
                floors: vec![1],
                ..PartSpec::default()
            })
            .expect("floor 1 is connected on its own");
        assert_eq!(ids(&part), ["b0", "b1", "b2"]);
        assert_eq!(part.edges.len(), 2);
        assert_eq!(part.name, "Two (floor 1)");
        assert_eq!(part.floors.len(), 1);
        assert_eq!(part.pilot.len(), 1);
        assert_eq!(part.test_points.len(), 1);
        assert_eq!(part.kernel, b.kernel);
    }

    #[test]
    fn around_a_vertex_keeps_what_is_within_the_walking_distance() {
        let b = two_floors();
        // From a0: a1 at 10, r0 at 16, a2 at 20, a3 at 30, b2 at 38, b1 at 48.
        let part = b
            .part(&PartSpec {
                around: vec![("a0".into(), 16.0)],
                ..PartSpec::default()
            })
            .expect("valid");
        assert_eq!(ids(&part), ["a0", "a1", "r0"]);
        // The explicit length of a1-r0 is kept as written.
        let e = part
            .edges
            .iter()
            .find(|e| e.explicit_length)
            .expect("a1-r0");
        assert_eq!(e.length, 6.0);
        assert_eq!(part.name, "Two (within 16 m of a0)");
        // Every pilot point of floor 0 (the fit's data); test points inside the box
        // (x 0..10 widened by 2 m) only.
        assert_eq!(part.pilot.len(), 2);
        assert_eq!(part.test_points.len(), 1);
        // The stairs count as walking: 40 m reach floor 1's b2 (38 m), not b1 (48 m).
        let part = b
            .part(&PartSpec {
                around: vec![("a0".into(), 40.0)],
                ..PartSpec::default()
            })
            .expect("valid");
        assert!(ids(&part).contains(&"b2") && !ids(&part).contains(&"b1"));
        // Walking on the kept floors only: from b0 on floor 1, nothing of floor 0.
        let part = b
            .part(&PartSpec {
                floors: vec![1],
                around: vec![("b0".into(), 100.0)],
                name: Some("Upstairs".into()),
            })
            .expect("valid");
        assert_eq!(ids(&part), ["b0", "b1", "b2"]);
        assert_eq!(part.name, "Upstairs");
    }

    #[test]
    fn around_several_vertices_keeps_the_union_and_a_union_in_pieces_is_refused() {
        let b = two_floors();
        // From a0 within 10: a0, a1; from a3 within 8: a3, b2 (the stairs); a2 is 10 from
        // both, so 10 and 8 leave it out and the part is in two pieces.
        let spec = |r: f64| PartSpec {
            around: vec![("a0".into(), 10.0), ("a3".into(), r)],
            ..PartSpec::default()
        };
        let e = b.part(&spec(8.0)).expect_err("two pieces").to_string();
        assert!(e.contains("disconnected"), "{e}");
        let part = b.part(&spec(10.0)).expect("a2 joins them");
        assert_eq!(ids(&part), ["a0", "a1", "a2", "a3", "b2"]);
        assert_eq!(part.name, "Two (within 10 m of a0, within 10 m of a3)");
    }

    #[test]
    fn around_a_vertex_keeps_exactly_the_vertices_within_reach_on_random_buildings() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for case in 0..40 {
            // A random connected graph on two floors: a spanning tree with random chords,
            // vertex i on floor i % 2 (stairs wherever an edge joins the two).
            let n = rng.random_range(2..40usize);
            let vertices: Vec<String> = (0..n)
                .map(|i| {
                    // Close together: every edge (0.5 m or more) is longer than the line.
                    let (x, y) = (rng.random_range(0.0..0.3), rng.random_range(0.0..0.3));
                    format!(r#"{{"id":"v{i}","x":{x},"y":{y},"floor":{}}}"#, i % 2)
                })
                .collect();
            // Every edge with a length (one that joins the floors needs one).
            let mut edge = |a: usize, c: usize| {
                let l: f64 = rng.random_range(0.5..20.0);
                format!(r#"{{"a":"v{a}","b":"v{c}","length":{l}}}"#)
            };
            let mut edges: Vec<String> = Vec::new();
            let mut pairs = std::collections::HashSet::new();
            for i in 1..n {
                let a = (i * 7 + case) % i;
                pairs.insert((a.min(i), a.max(i)));
                edges.push(edge(a, i));
            }
            for k in 0..n {
                let (a, c) = ((k * 13 + case) % n, (k * 5 + 3 * case + 1) % n);
                if a != c && pairs.insert((a.min(c), a.max(c))) {
                    edges.push(edge(a, c));
                }
            }
            let text = format!(
                r#"{{"format":"survey-building/1","name":"r","floors":[{{"id":0}},{{"id":1}}],"vertices":[{}],"edges":[{}]}}"#,
                vertices.join(","),
                edges.join(",")
            );
            let b = Building::from_json(&text, "r").expect("a valid random building");
            let root = rng.random_range(0..n);
            let radius = rng.random_range(0.5..60.0);
            let part = b
                .part(&PartSpec {
                    around: vec![(b.vertices[root].id.clone(), radius)],
                    ..PartSpec::default()
                })
                .expect("a part around a vertex is connected");
            let (d, _) = crate::plan::metric::shortest_path_tree(&b, root);
            let want: Vec<&str> = (0..n)
                .filter(|&v| d[v] <= radius)
                .map(|v| b.vertices[v].id.as_str())
                .collect();
            assert_eq!(ids(&part), want, "case {case}");
            let inside = |id: &str| want.contains(&id);
            let edges_within = b
                .edges
                .iter()
                .filter(|e| inside(&b.vertices[e.a].id) && inside(&b.vertices[e.b].id))
                .count();
            assert_eq!(part.edges.len(), edges_within, "case {case}");
            // Walking distances inside the part are the building's (a shortest way to a
            // kept vertex only passes kept vertices).
            let proot = part
                .require_vertex(&b.vertices[root].id)
                .expect("root kept");
            let (pd, _) = crate::plan::metric::shortest_path_tree(&part, proot);
            for (v, pv) in part.vertices.iter().zip(&pd) {
                let w = b.require_vertex(&v.id).expect("same ids");
                assert!((d[w] - pv).abs() < 1e-9, "case {case}, {}", v.id);
            }
        }
    }

    #[test]
    fn a_bad_part_is_refused_with_what_is_wrong() {
        let b = two_floors();
        let err = |spec: PartSpec| b.part(&spec).expect_err("refused").to_string();
        let e = err(PartSpec {
            floors: vec![7],
            ..PartSpec::default()
        });
        assert!(e.contains("no floor 7") && e.contains("0, 1"), "{e}");
        let e = err(PartSpec {
            around: vec![("zz".into(), 10.0)],
            ..PartSpec::default()
        });
        assert!(e.contains("unknown vertex \"zz\""), "{e}");
        for r in [0.0, -3.0, f64::NAN, f64::INFINITY] {
            let e = err(PartSpec {
                around: vec![("a0".into(), r)],
                ..PartSpec::default()
            });
            assert!(e.contains("positive number of metres"), "{r}: {e}");
        }
        let e = err(PartSpec {
            floors: vec![1],
            around: vec![("a0".into(), 10.0)],
            ..PartSpec::default()
        });
        assert!(e.contains("\"a0\" is on floor 0"), "{e}");
    }

    #[test]
    fn a_part_in_pieces_is_refused_with_the_pieces_named() {
        // Floor 1 of this building is two corridors joined only through floor 0.
        let text = r#"{"format":"survey-building/1","name":"Split",
          "floors":[{"id":0},{"id":1}],
          "vertices":[{"id":"a0","x":0,"y":0},{"id":"a1","x":10,"y":0},
            {"id":"b0","x":0,"y":0,"floor":1},{"id":"b1","x":10,"y":0,"floor":1}],
          "edges":[{"a":"a0","b":"a1"},{"a":"a0","b":"b0","length":5},
            {"a":"a1","b":"b1","length":5}]}"#;
        let b = Building::from_json(text, "split").expect("valid");
        let e = b
            .part(&PartSpec {
                floors: vec![1],
                ..PartSpec::default()
            })
            .expect_err("floor 1 alone is in two pieces")
            .to_string();
        assert!(e.contains("disconnected") && e.contains("--around"), "{e}");
        // Around one vertex, the piece it is in (b1 is 10 m away, but through floor 0).
        let part = b
            .part(&PartSpec {
                floors: vec![1],
                around: vec![("b0".into(), 50.0)],
                ..PartSpec::default()
            })
            .expect("the piece of b0");
        assert_eq!(ids(&part), ["b0"]);
    }
}
