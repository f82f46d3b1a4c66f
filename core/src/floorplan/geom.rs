//! Small geometric questions the network asks, answered with `geo`'s predicates:
//! is a point (or a whole segment) inside a polygon within a tolerance, where does a
//! polygon's boundary run along another's, which grid points fit inside a polygon.

use geo::{
    Closest, ClosestPoint, Contains, Coord, Distance, Euclidean, Line, LineIntersection,
    LineString, Point, Polygon, line_intersection::line_intersection,
};

/// Step of the samples along segments and boundaries, metres.
const SAMPLE_M: f64 = 0.05;

/// Most samples [`shared_runs`] takes along one outline (besides one per segment): 20,000,
/// every 0.1 m of a 2 km outline.
const MAX_RING_SAMPLES: usize = 20_000;

/// Distance from `c` to the nearest ring (outer or hole) of `poly`.
pub(crate) fn boundary_distance(poly: &Polygon<f64>, c: Coord<f64>) -> f64 {
    let p = Point(c);
    std::iter::once(poly.exterior())
        .chain(poly.interiors())
        .map(|r| Euclidean.distance(&p, r))
        .fold(f64::INFINITY, f64::min)
}

/// Whether `c` is inside `poly` or within `tol` of its boundary.
pub(crate) fn covers(poly: &Polygon<f64>, c: Coord<f64>, tol: f64) -> bool {
    poly.contains(&Point(c)) || boundary_distance(poly, c) <= tol
}

/// Whether the whole segment `a b` lies inside `poly` or within `tol` of its boundary
/// (checked every 5 cm).
pub(crate) fn segment_within(poly: &Polygon<f64>, a: Coord<f64>, b: Coord<f64>, tol: f64) -> bool {
    let len = (b - a).x.hypot((b - a).y);
    let n = (len / SAMPLE_M).ceil().max(1.0) as usize;
    (0..=n).all(|i| {
        let t = i as f64 / n as f64;
        covers(poly, a + (b - a) * t, tol)
    })
}

/// The nearest point of `poly`'s boundary to `c`.
pub(crate) fn nearest_boundary_point(poly: &Polygon<f64>, c: Coord<f64>) -> Coord<f64> {
    let p = Point(c);
    let mut best = (f64::INFINITY, c);
    for ring in std::iter::once(poly.exterior()).chain(poly.interiors()) {
        let q = match ring.closest_point(&p) {
            Closest::Intersection(q) | Closest::SinglePoint(q) => q,
            Closest::Indeterminate => continue,
        };
        let d = Euclidean.distance(&p, &q);
        if d < best.0 {
            best = (d, q.0);
        }
    }
    best.1
}

/// The wall direction of a polygon, radians in `[0, pi/2)`: the angle (modulo 90 degrees)
/// that the longest share of its boundary runs at, so that a grid laid at it follows the
/// walls of a rectilinear building whatever its bearing.
pub(crate) fn dominant_angle(poly: &Polygon<f64>) -> f64 {
    let quarter = std::f64::consts::FRAC_PI_2;
    // Each boundary edge of positive length: its angle modulo 90 degrees, its 1-degree
    // bin and its length.
    let edges = || {
        poly.exterior().lines().filter_map(move |line| {
            let d = line.delta();
            let len = d.x.hypot(d.y);
            let a = d.y.atan2(d.x).rem_euclid(quarter);
            (len > 0.0).then(|| (a, ((a / quarter * 90.0).round() as usize) % 90, len))
        })
    };
    let mut bins = [0.0f64; 90];
    for (_, bin, len) in edges() {
        bins[bin] += len;
    }
    let (best, _) = bins.iter().enumerate().fold(
        (0, -1.0),
        |acc, (i, &w)| if w > acc.1 { (i, w) } else { acc },
    );
    // Refine: the length-weighted mean angle of the edges in the winning bin.
    let (mut sum, mut weight) = (0.0, 0.0);
    for (a, bin, len) in edges() {
        if bin == best {
            // Unwrap angles near 90 degrees onto 0 so that the mean does not split them.
            let a = if best == 0 && a > quarter / 2.0 {
                a - quarter
            } else {
                a
            };
            sum += a * len;
            weight += len;
        }
    }
    if weight > 0.0 {
        (sum / weight).rem_euclid(quarter)
    } else {
        0.0
    }
}

/// A grid point of a space: its row and column in the grid and its position.
#[derive(Debug, Clone, Copy)]
pub(crate) struct GridPoint {
    pub row: usize,
    pub col: usize,
    pub pos: Coord<f64>,
}

/// The grid of a polygon: rows and columns along its wall direction, as many as fit at
/// about `spacing` over its extent (at least one), centred, so that a corridor narrower
/// than 1.5 spacings gets one row down its middle. Points inside the polygon and at least
/// `clearance` from its boundary are kept.
/// The frame of a polygon's grid: the angle of its walls and its extent `(u0, v0, u1, v1)`
/// along them.
fn grid_frame(poly: &Polygon<f64>) -> (f64, [f64; 4]) {
    let theta = dominant_angle(poly);
    let (c, s) = (theta.cos(), theta.sin());
    let (mut u0, mut v0, mut u1, mut v1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    for p in poly.exterior().coords() {
        let (u, v) = (p.x * c + p.y * s, -p.x * s + p.y * c);
        u0 = u0.min(u);
        v0 = v0.min(v);
        u1 = u1.max(u);
        v1 = v1.max(v);
    }
    (theta, [u0, v0, u1, v1])
}

/// How many cells [`grid_points`] tries for a polygon (in `f64`: a polygon in the wrong
/// units has more cells than a `usize` holds), and its extent `(width, height)` in metres.
pub(crate) fn grid_cells(poly: &Polygon<f64>, spacing: f64) -> (f64, f64, f64) {
    let (_, [u0, v0, u1, v1]) = grid_frame(poly);
    if !(u1 > u0 && v1 > v0) {
        return (0.0, 0.0, 0.0);
    }
    let (w, h) = (u1 - u0, v1 - v0);
    let cells = (w / spacing).round().max(1.0) * (h / spacing).round().max(1.0);
    (cells, w, h)
}

pub(crate) fn grid_points(poly: &Polygon<f64>, spacing: f64, clearance: f64) -> Vec<GridPoint> {
    let (theta, [u0, v0, u1, v1]) = grid_frame(poly);
    let (c, s) = (theta.cos(), theta.sin());
    let from_uv = |u: f64, v: f64| Coord {
        x: u * c - v * s,
        y: u * s + v * c,
    };
    if !(u1 > u0 && v1 > v0) {
        return Vec::new();
    }
    let nu = ((u1 - u0) / spacing).round().max(1.0) as usize;
    let nv = ((v1 - v0) / spacing).round().max(1.0) as usize;
    let (du, dv) = ((u1 - u0) / nu as f64, (v1 - v0) / nv as f64);
    let mut out = Vec::new();
    for row in 0..nv {
        for col in 0..nu {
            let pos = from_uv(u0 + (col as f64 + 0.5) * du, v0 + (row as f64 + 0.5) * dv);
            if poly.contains(&Point(pos)) && boundary_distance(poly, pos) >= clearance {
                out.push(GridPoint { row, col, pos });
            }
        }
    }
    out
}

/// A stretch of one polygon's boundary that runs along another polygon.
#[derive(Debug, Clone)]
pub(crate) struct Run {
    /// Length, metres.
    pub length: f64,
    /// Samples along the stretch with the length walked to each.
    pub points: Vec<(Coord<f64>, f64)>,
}

impl Run {
    /// The sample nearest to `t` metres along the stretch.
    pub(crate) fn at(&self, t: f64) -> Coord<f64> {
        let mut best = (f64::INFINITY, self.points[0].0);
        for &(p, s) in &self.points {
            if (s - t).abs() < best.0 {
                best = ((s - t).abs(), p);
            }
        }
        best.1
    }

    /// The middle of the stretch.
    pub(crate) fn middle(&self) -> Coord<f64> {
        self.at(self.length / 2.0)
    }
}

/// Stretches of `a`'s outer boundary that run along `b` (within `tol` of `b`'s boundary, or
/// inside `b` where the two overlap), longest first.
pub(crate) fn shared_runs(a: &Polygon<f64>, b: &Polygon<f64>, tol: f64) -> Vec<Run> {
    // Samples along the ring with the length each one stands for: every `2 SAMPLE_M`, or
    // coarser on an outline over 2 km long, so that there are at most about
    // MAX_RING_SAMPLES (plus one per segment). A unit outline thousands of kilometres long
    // (a mutated coordinate) asked for a gigabyte of samples (found by `floorplan_imdf`).
    let perimeter: f64 = a
        .exterior()
        .lines()
        .map(|l| l.delta().x.hypot(l.delta().y))
        .filter(|l| l.is_finite())
        .sum();
    let step = (2.0 * SAMPLE_M).max(perimeter / MAX_RING_SAMPLES as f64);
    let mut samples: Vec<(Coord<f64>, f64, bool)> = Vec::new();
    for line in a.exterior().lines() {
        let d = line.delta();
        let len = d.x.hypot(d.y);
        if !(len > 0.0 && len.is_finite()) {
            continue;
        }
        let n = (len / step).ceil().max(1.0) as usize;
        for i in 0..n {
            let p = line.start + d * ((i as f64 + 0.5) / n as f64);
            let on = covers(b, p, tol);
            samples.push((p, len / n as f64, on));
        }
    }
    let n = samples.len();
    if n == 0 || !samples.iter().any(|s| s.2) {
        return Vec::new();
    }
    // Start just after a sample that is off, so that runs do not wrap around.
    let start = (0..n).find(|&i| !samples[i].2).map_or(0, |i| i + 1);
    let mut runs: Vec<Vec<usize>> = Vec::new();
    let mut current: Vec<usize> = Vec::new();
    for k in 0..n {
        let i = (start + k) % n;
        if samples[i].2 {
            current.push(i);
        } else if !current.is_empty() {
            runs.push(std::mem::take(&mut current));
        }
    }
    if !current.is_empty() {
        runs.push(current);
    }
    let mut out: Vec<Run> = runs
        .into_iter()
        .map(|run| {
            let mut acc = 0.0;
            let points = run
                .iter()
                .map(|&i| {
                    let here = acc + samples[i].1 / 2.0;
                    acc += samples[i].1;
                    (samples[i].0, here)
                })
                .collect();
            Run {
                length: acc,
                points,
            }
        })
        .collect();
    out.sort_by(|x, y| y.length.total_cmp(&x.length));
    out
}

/// Points where the segment `a b` meets the wall lines (a touching or overlapping wall
/// counts too).
pub(crate) fn wall_crossings(
    a: Coord<f64>,
    b: Coord<f64>,
    walls: &[&LineString<f64>],
) -> Vec<Coord<f64>> {
    let seg = Line::new(a, b);
    let mut out = Vec::new();
    for w in walls {
        for l in w.lines() {
            match line_intersection(seg, l) {
                Some(LineIntersection::SinglePoint { intersection, .. }) => out.push(intersection),
                Some(LineIntersection::Collinear { intersection }) => {
                    out.push(intersection.start);
                    out.push(intersection.end);
                }
                None => {}
            }
        }
    }
    out
}

/// Distance between two points.
pub(crate) fn dist(a: Coord<f64>, b: Coord<f64>) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::polygon;

    /// A room inside a larger area shares its whole outline. A 10 m room keeps a sample
    /// every 0.1 m; an outline 4,000 km long (a mutated coordinate; `floorplan_imdf` found
    /// one that asked for a gigabyte of samples) gets at most MAX_RING_SAMPLES and one per
    /// segment, and still measures its full length.
    #[test]
    fn shared_runs_takes_bounded_samples_on_a_huge_outline() {
        let area =
            polygon![(x: -2e6, y: -2e6), (x: 2e6, y: -2e6), (x: 2e6, y: 2e6), (x: -2e6, y: 2e6)];
        let small =
            polygon![(x: 0.0, y: 0.0), (x: 10.0, y: 0.0), (x: 10.0, y: 10.0), (x: 0.0, y: 10.0)];
        let runs = shared_runs(&small, &area, 0.15);
        assert_eq!(runs.len(), 1);
        assert_eq!(runs[0].points.len(), 400);
        assert!((runs[0].length - 40.0).abs() < 1e-9);
        let huge = polygon![(x: 0.0, y: 0.0), (x: 1e6, y: 0.0), (x: 1e6, y: 1e6), (x: 0.0, y: 1e6)];
        let runs = shared_runs(&huge, &area, 0.15);
        assert_eq!(runs.len(), 1);
        assert!(
            runs[0].points.len() <= MAX_RING_SAMPLES + 4,
            "{}",
            runs[0].points.len()
        );
        assert!((runs[0].length - 4e6).abs() < 1e-3, "{}", runs[0].length);
    }

    #[test]
    fn narrow_corridor_gets_its_centre_line() {
        let p = polygon![(x: 0.0, y: 0.0), (x: 20.0, y: 0.0), (x: 20.0, y: 1.6), (x: 0.0, y: 1.6)];
        let g = grid_points(&p, 2.0, 0.3);
        assert_eq!(g.len(), 10);
        assert!(g.iter().all(|q| (q.pos.y - 0.8).abs() < 1e-9), "{g:?}");
    }

    #[test]
    fn rotated_room_grid_follows_its_walls() {
        // A 6 m x 4 m room rotated by 30 degrees: a 3 x 2 grid.
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let r = |x: f64, y: f64| (x * c - y * s, x * s + y * c);
        let pts = [r(0.0, 0.0), r(6.0, 0.0), r(6.0, 4.0), r(0.0, 4.0)];
        let p = Polygon::new(LineString::from(pts.to_vec()), vec![]);
        assert!((dominant_angle(&p) - 30f64.to_radians()).abs() < 1e-9);
        assert_eq!(grid_points(&p, 2.0, 0.3).len(), 6);
    }

    #[test]
    fn shared_boundary_middle() {
        let room = polygon![(x: 0.0, y: 2.0), (x: 4.0, y: 2.0), (x: 4.0, y: 6.0), (x: 0.0, y: 6.0)];
        let corridor =
            polygon![(x: -10.0, y: 0.0), (x: 10.0, y: 0.0), (x: 10.0, y: 2.0), (x: -10.0, y: 2.0)];
        let runs = shared_runs(&room, &corridor, 0.15);
        assert_eq!(runs.len(), 1);
        // 4 m along the corridor, plus the 0.15 m tolerance up each side wall.
        assert!((runs[0].length - 4.0).abs() < 0.45, "{runs:?}");
        assert!(
            dist(runs[0].middle(), Coord { x: 2.0, y: 2.0 }) < 0.1,
            "{runs:?}"
        );
    }
}
