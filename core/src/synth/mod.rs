//! Synthetic buildings: corridors with rooms on both sides, access points, and survey data
//! from a propagation model, all determined by one seed.
//!
//! Layout of every floor (all floors are alike, stacked `floor_height_m` apart):
//!
//! ```text
//!  y ^   +---------+---------+---------+      rooms_per_side rooms of width
//!    |   | . . . . | . . . . | . . . . |      corridor_length / rooms_per_side and depth
//!    |   | . . . . | . . . . | . . . . |      room_depth, each a grid graph (grid_spacing)
//!    |   +----d----+--d------+------d--+      reached through a door vertex d on the wall
//!  0 |   c---c---c---c---c---c---c---c--c     corridor vertices every ~corridor_spacing
//!    |   +--d------+----d----+-d-------+      (corridor_width wide, centre line y = 0)
//!    |   | . . . . | . . . . | . . . . |
//!    +------------------------------------> x
//! ```
//!
//! Floors are joined by a staircase edge (explicit `stair_length_m`) between the first
//! corridor vertices of consecutive floors. Walls (for the wall loss) are the corridor
//! walls, the back walls of the rooms and the walls between rooms.
//!
//! The survey data follow SPEC section 7: pilot points on the walkable graph (uniform by
//! edge length), test points near it (up to 0.75 m off an edge) with measured RSS, and a
//! dense survey every `dense_spacing_m` along every edge of a floor. Every random choice
//! uses its own ChaCha stream of `seed`, and the numbers are platform-independent, so a
//! generated file is reproducible byte for byte.
//!
//! The shipped demo building ([`DEMO_BUILDING_JSON`]) is regenerated with
//!
//! ```text
//! cargo run -p trailprint-core --bin trailprint -- generate --out core/data/demo-building.json \
//!     --floors 1 --rooms 3 --corridor-length 30 --aps 10 --seed 8
//! ```
//!
//! (these are the defaults of [`SynthParams`]); a test checks that this gives exactly the
//! committed file.

mod propagation;
pub(crate) mod random;

use std::collections::HashSet;

use crate::building::{BuildingFile, EdgeSpec, FORMAT, Fingerprint, FloorSpec, VertexSpec};
use crate::gp::Point;
use crate::{Error, Result};

pub use propagation::{AccessPoint, PropagationModel, PropagationParams, Wall};
use random::{index, stream_rng, uniform};

/// The demo building shipped with the library (see the module docs for how it is made).
pub const DEMO_BUILDING_JSON: &str = include_str!("../../data/demo-building.json");

// ChaCha streams of the seed, one per concern.
const STREAM_DOORS: u64 = 1;
const STREAM_APS: u64 = 2;
pub(crate) const STREAM_SHADOW: u64 = 3;
const STREAM_PILOT: u64 = 4;
const STREAM_TEST: u64 = 5;
const STREAM_DENSE: u64 = 6;

/// Parameters of a synthetic building. The defaults make the demo building.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthParams {
    /// Building name written to the file.
    pub name: String,
    /// Number of floors (ids 0, 1, ...).
    pub floors: usize,
    /// Corridor length, metres.
    pub corridor_length_m: f64,
    /// Corridor width, metres (the graph runs along its centre line).
    pub corridor_width_m: f64,
    /// Spacing of corridor vertices, metres (rounded so that they split the corridor evenly).
    pub corridor_spacing_m: f64,
    /// Rooms on each side of the corridor (0 for a bare corridor).
    pub rooms_per_side: usize,
    /// Depth of a room, metres.
    pub room_depth_m: f64,
    /// Spacing of a room's grid graph, metres.
    pub grid_spacing_m: f64,
    /// Length of a staircase edge between floors, metres.
    pub stair_length_m: f64,
    /// Number of access points (spread over the floors).
    pub aps: usize,
    /// Number of pilot points.
    pub pilot: usize,
    /// Number of test points.
    pub test_points: usize,
    /// Spacing of the dense survey along edges, metres.
    pub dense_spacing_m: f64,
    /// The radio model.
    pub propagation: PropagationParams,
    /// Seed of every random choice.
    pub seed: u64,
}

impl Default for SynthParams {
    fn default() -> Self {
        SynthParams {
            name: "Demo building (synthetic)".into(),
            floors: 1,
            corridor_length_m: 30.0,
            corridor_width_m: 2.5,
            corridor_spacing_m: 2.0,
            rooms_per_side: 3,
            room_depth_m: 6.0,
            grid_spacing_m: 2.5,
            stair_length_m: 8.0,
            aps: 10,
            pilot: 20,
            test_points: 60,
            dense_spacing_m: 0.5,
            propagation: PropagationParams::default(),
            seed: 8,
        }
    }
}

impl SynthParams {
    /// Checks every parameter; errors name it and say what would be right.
    pub fn validate(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::InvalidRequest(msg));
        if self.name.trim().is_empty() {
            return bad("synthetic building: name must not be empty".into());
        }
        if self.floors == 0 || self.floors > 100 {
            return bad(format!(
                "synthetic building: floors = {}, expected 1 to 100",
                self.floors
            ));
        }
        for (name, v, min) in [
            ("corridor length", self.corridor_length_m, 2.0),
            ("corridor width", self.corridor_width_m, 0.5),
            ("corridor spacing", self.corridor_spacing_m, 0.1),
            ("room depth", self.room_depth_m, 1.0),
            ("grid spacing", self.grid_spacing_m, 0.1),
            ("stair length", self.stair_length_m, 0.5),
            ("dense survey spacing", self.dense_spacing_m, 0.05),
        ] {
            if !v.is_finite() || v < min || v > 10_000.0 {
                return bad(format!(
                    "synthetic building: {name} = {v} m, expected {min} to 10000 m"
                ));
            }
        }
        if self.rooms_per_side > 0 {
            let width = self.corridor_length_m / self.rooms_per_side as f64;
            if width < 2.0 {
                return bad(format!(
                    "synthetic building: {} rooms per side make rooms {width:.2} m wide \
                     along a {} m corridor; rooms must be at least 2 m wide",
                    self.rooms_per_side, self.corridor_length_m
                ));
            }
        }
        if self.aps == 0 || self.aps > 999 {
            return bad(format!(
                "synthetic building: aps = {}, expected 1 to 999",
                self.aps
            ));
        }
        if self.pilot > 100_000 || self.test_points > 100_000 {
            return bad("synthetic building: at most 100000 pilot or test points".into());
        }
        self.propagation.validate()
    }
}

/// A generated building and the world it was measured in.
#[derive(Debug, Clone)]
pub struct SyntheticBuilding {
    /// The `survey-building/1` document (no `kernel`: it is fitted on the pilot data).
    pub file: BuildingFile,
    /// The propagation model that produced the fingerprints.
    pub model: PropagationModel,
}

/// Plan-view geometry of one floor plus the graph of all floors.
struct Layout {
    vertices: Vec<VertexSpec>,
    edges: Vec<EdgeSpec>,
    walls: Vec<Wall>,
    /// Rectangles (x0, y0, x1, y1) that are inside the building (corridor and rooms).
    areas: Vec<(f64, f64, f64, f64)>,
}

/// Rounds to a millimetre, so that coordinates print short and compare exactly.
fn mm(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0 + 0.0
}

/// `count` evenly spaced positions centred in `[lo, hi]`, `spacing` apart when they fit.
fn centred_line(lo: f64, hi: f64, spacing: f64) -> Vec<f64> {
    let span = hi - lo;
    if span <= 0.0 {
        return vec![(lo + hi) / 2.0];
    }
    let count = (span / spacing + 1e-9).floor() as usize + 1;
    let start = (lo + hi) / 2.0 - (count - 1) as f64 * spacing / 2.0;
    (0..count).map(|i| start + i as f64 * spacing).collect()
}

fn layout(p: &SynthParams) -> Layout {
    let mut rng = stream_rng(p.seed, STREAM_DOORS);
    let len = p.corridor_length_m;
    let half = p.corridor_width_m / 2.0;
    let depth = p.room_depth_m;
    let rps = p.rooms_per_side;
    let n_corr = ((len / p.corridor_spacing_m).round() as usize).max(1) + 1;
    let corr_x: Vec<f64> = (0..n_corr)
        .map(|i| mm(i as f64 * len / (n_corr - 1) as f64))
        .collect();

    let mut vertices = Vec::new();
    let mut edges = Vec::new();
    let edge = |a: &str, b: &str| EdgeSpec {
        a: a.to_string(),
        b: b.to_string(),
        length: None,
    };
    for f in 0..p.floors as i64 {
        let cid = |i: usize| format!("f{f}-c{i:02}");
        for (i, &x) in corr_x.iter().enumerate() {
            vertices.push(VertexSpec {
                id: cid(i),
                x,
                y: 0.0,
                floor: f,
                label: (i == 0 && p.floors > 1).then(|| "Stairs".to_string()),
            });
            if i > 0 {
                edges.push(edge(&cid(i - 1), &cid(i)));
            }
        }
        if rps > 0 {
            let width = len / rps as f64;
            for r in 0..2 * rps {
                let north = r < rps;
                let slot = r % rps;
                let (x0, x1) = (slot as f64 * width, (slot + 1) as f64 * width);
                let sign = if north { 1.0 } else { -1.0 };
                let inset = (width / 2.0).min(depth / 2.0).min(1.0);
                let xs = centred_line(x0 + inset, x1 - inset, p.grid_spacing_m);
                // Rows from the corridor wall outwards.
                let ys: Vec<f64> =
                    centred_line(half + inset, half + depth - inset, p.grid_spacing_m)
                        .into_iter()
                        .map(|y| sign * y)
                        .collect();
                let rid = |row: usize, col: usize| format!("f{f}-r{r}-{row}{col:02}");
                for (row, &y) in ys.iter().enumerate() {
                    for (col, &x) in xs.iter().enumerate() {
                        vertices.push(VertexSpec {
                            id: rid(row, col),
                            x: mm(x),
                            y: mm(y),
                            floor: f,
                            label: None,
                        });
                        if col > 0 {
                            edges.push(edge(&rid(row, col - 1), &rid(row, col)));
                        }
                        if row > 0 {
                            edges.push(edge(&rid(row - 1, col), &rid(row, col)));
                        }
                    }
                }
                // The door: on the corridor wall in front of a corridor vertex that lies
                // within the room (0.5 m from its side walls), chosen at random.
                let inside: Vec<usize> = (0..n_corr)
                    .filter(|&i| corr_x[i] > x0 + 0.5 && corr_x[i] < x1 - 0.5)
                    .collect();
                let (door_x, corr) = if inside.is_empty() {
                    let centre = (x0 + x1) / 2.0;
                    let nearest = (0..n_corr)
                        .min_by(|&a, &b| {
                            (corr_x[a] - centre)
                                .abs()
                                .total_cmp(&(corr_x[b] - centre).abs())
                        })
                        .unwrap_or(0);
                    (mm(centre), nearest)
                } else {
                    let c = inside[index(&mut rng, inside.len())];
                    (corr_x[c], c)
                };
                let did = format!("f{f}-r{r}-door");
                vertices.push(VertexSpec {
                    id: did.clone(),
                    x: door_x,
                    y: mm(sign * half),
                    floor: f,
                    // Rooms 1, 2, ... on the ground floor, 101, 102, ... on floor 1.
                    label: Some(format!("Room {}", f * 100 + r as i64 + 1)),
                });
                edges.push(edge(&cid(corr), &did));
                // The room vertex nearest the door (first row), ties to the left.
                let col = (0..xs.len())
                    .min_by(|&a, &b| (xs[a] - door_x).abs().total_cmp(&(xs[b] - door_x).abs()))
                    .unwrap_or(0);
                edges.push(edge(&did, &rid(0, col)));
            }
        }
        if f > 0 {
            edges.push(EdgeSpec {
                a: format!("f{}-c00", f - 1),
                b: cid(0),
                length: Some(p.stair_length_m),
            });
        }
    }

    let mut walls = vec![
        Wall {
            a: (0.0, half),
            b: (len, half),
        },
        Wall {
            a: (0.0, -half),
            b: (len, -half),
        },
    ];
    let mut areas = vec![(0.0, -half, len, half)];
    if rps > 0 {
        let width = len / rps as f64;
        for sign in [1.0, -1.0] {
            walls.push(Wall {
                a: (0.0, sign * (half + depth)),
                b: (len, sign * (half + depth)),
            });
            for slot in 0..=rps {
                let x = slot as f64 * width;
                walls.push(Wall {
                    a: (x, sign * half),
                    b: (x, sign * (half + depth)),
                });
            }
            let (y0, y1) = if sign > 0.0 {
                (half, half + depth)
            } else {
                (-half - depth, -half)
            };
            areas.push((0.0, y0, len, y1));
        }
    }
    Layout {
        vertices,
        edges,
        walls,
        areas,
    }
}

/// Walkable segments of one floor: (from, to, floor) for every edge within a floor.
fn floor_segments(lay: &Layout) -> Vec<(Point, Point)> {
    let pos = |id: &str| {
        lay.vertices
            .iter()
            .find(|v| v.id == id)
            .map(|v| Point::new(v.x, v.y, v.floor))
    };
    lay.edges
        .iter()
        .filter_map(|e| {
            let (a, b) = (pos(&e.a)?, pos(&e.b)?);
            (a.floor == b.floor).then_some((a, b))
        })
        .collect()
}

/// A point uniform by length on the segments (`total`: their summed length).
fn point_on_segments<R: rand::Rng>(segs: &[(Point, Point)], total: f64, rng: &mut R) -> Point {
    let mut target = uniform(rng, 0.0, total);
    for (i, (a, b)) in segs.iter().enumerate() {
        let l = a.planar_distance(b);
        if target <= l || i + 1 == segs.len() {
            let t = if l > 0.0 {
                (target / l).clamp(0.0, 1.0)
            } else {
                0.0
            };
            return Point::new(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.floor);
        }
        target -= l;
    }
    Point::new(0.0, 0.0, 0)
}

/// Generates a building. Deterministic in `params` (including the seed).
pub fn generate(params: &SynthParams) -> Result<SyntheticBuilding> {
    params.validate()?;
    let lay = layout(params);
    let floors: Vec<i64> = (0..params.floors as i64).collect();

    // Access points: floors in turn; along the building in strata so that they spread out;
    // anywhere across the corridor and the rooms.
    let mut rng = stream_rng(params.seed, STREAM_APS);
    let prm = &params.propagation;
    let len = params.corridor_length_m;
    let y_extent = params.corridor_width_m / 2.0
        + if params.rooms_per_side > 0 {
            params.room_depth_m
        } else {
            0.0
        };
    let mut aps = Vec::with_capacity(params.aps);
    for i in 0..params.aps {
        let floor = (i % params.floors) as i64;
        let on_floor = (params.aps - 1 - (i % params.floors)) / params.floors + 1;
        let k = i / params.floors;
        let stratum = len / on_floor as f64;
        let x = uniform(&mut rng, k as f64 * stratum, (k + 1) as f64 * stratum);
        let y = uniform(&mut rng, -y_extent, y_extent);
        let p0 = uniform(&mut rng, prm.p0_dbm.0, prm.p0_dbm.1);
        let n = uniform(&mut rng, prm.exponent.0, prm.exponent.1);
        aps.push(AccessPoint {
            id: format!("ap-{:02}", i + 1),
            pos: Point::new(mm(x), mm(y), floor),
            p0_dbm: (p0 * 100.0).round() / 100.0,
            exponent: (n * 1000.0).round() / 1000.0,
        });
    }
    let model = PropagationModel::new(aps, lay.walls.clone(), &floors, prm.clone(), params.seed)?;

    let segs = floor_segments(&lay);
    let total: f64 = segs.iter().map(|(a, b)| a.planar_distance(b)).sum();
    let measure = |p: Point, rng: &mut rand_chacha::ChaCha8Rng| Fingerprint {
        x: p.x,
        y: p.y,
        floor: p.floor,
        rss: model.measure(&p, rng),
    };

    let mut rng = stream_rng(params.seed, STREAM_PILOT);
    let pilot: Vec<Fingerprint> = (0..params.pilot)
        .map(|_| {
            let p = point_on_segments(&segs, total, &mut rng);
            measure(Point::new(mm(p.x), mm(p.y), p.floor), &mut rng)
        })
        .collect();

    let mut rng = stream_rng(params.seed, STREAM_TEST);
    let inside = |x: f64, y: f64| {
        lay.areas
            .iter()
            .any(|&(x0, y0, x1, y1)| x >= x0 && x <= x1 && y >= y0 && y <= y1)
    };
    let test_points: Vec<Fingerprint> = (0..params.test_points)
        .map(|_| {
            let p = point_on_segments(&segs, total, &mut rng);
            let mut x = mm(p.x + uniform(&mut rng, -0.75, 0.75));
            let mut y = mm(p.y + uniform(&mut rng, -0.75, 0.75));
            if !inside(x, y) {
                (x, y) = (mm(p.x), mm(p.y));
            }
            measure(Point::new(x, y, p.floor), &mut rng)
        })
        .collect();

    // Dense survey: every vertex once, then points spaced evenly inside every edge.
    let mut rng = stream_rng(params.seed, STREAM_DENSE);
    let mut dense = Vec::new();
    let mut seen: HashSet<(i64, u64, u64)> = HashSet::new();
    let mut push = |p: Point, rng: &mut rand_chacha::ChaCha8Rng| {
        let key = (p.floor, p.x.to_bits(), p.y.to_bits());
        if seen.insert(key) {
            dense.push(measure(p, rng));
        }
    };
    for v in &lay.vertices {
        push(Point::new(v.x, v.y, v.floor), &mut rng);
    }
    for (a, b) in &segs {
        let l = a.planar_distance(b);
        let pieces = (l / params.dense_spacing_m - 1e-9).ceil().max(1.0) as usize;
        for k in 1..pieces {
            let t = k as f64 / pieces as f64;
            let p = Point::new(
                mm(a.x + t * (b.x - a.x)),
                mm(a.y + t * (b.y - a.y)),
                a.floor,
            );
            push(p, &mut rng);
        }
    }

    let file = BuildingFile {
        format: FORMAT.into(),
        name: params.name.clone(),
        floors: Some(
            floors
                .iter()
                .map(|&id| FloorSpec {
                    id,
                    name: Some(if id == 0 {
                        "Ground".to_string()
                    } else {
                        format!("Floor {id}")
                    }),
                })
                .collect(),
        ),
        vertices: lay.vertices,
        edges: lay.edges,
        pilot,
        test_points,
        dense_survey: dense,
        kernel: None,
        geo: None,
        outlines: Vec::new(),
    };
    Ok(SyntheticBuilding { file, model })
}

/// The JSON text of a generated building as the `generate` command writes it (pretty,
/// with a final newline).
pub fn to_json_text(file: &BuildingFile) -> String {
    let mut s = file.to_json();
    s.push('\n');
    s
}

#[cfg(test)]
#[path = "synth_tests.rs"]
mod tests;
