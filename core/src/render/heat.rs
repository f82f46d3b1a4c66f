//! The heat map: the GP posterior standard deviation on the reference grid, and, on a
//! building with floor-plan outlines, over the whole of its rooms, corridors and open
//! areas (a room's middle is as walkable as its edges: left blank it looked like a hole).

use nalgebra::DMatrix;

use super::{RenderOptions, Scene};
use crate::Result;
use crate::building::{Building, OutlineKind};
use crate::eval::reference_grid;
use crate::gp::predict::GpModel;
use crate::gp::{Extent, Point};

/// Standard deviation (dB) at each grid point, with the range the colours span.
pub(super) struct Heat {
    pub grid: Vec<Point>,
    pub sd: Vec<f64>,
    /// Smallest and largest value: the colour scale spans exactly this range, so that the
    /// whole of it is used (a survey rarely brings the uncertainty near 0 or leaves it at
    /// the prior `sqrt(sf2)`).
    pub lo: f64,
    pub hi: f64,
    /// The prior standard deviation `sqrt(sf2)`, for the legend.
    pub prior: f64,
    /// The grid covers walkable outlines too ([`heat_grid`]).
    pub outlines: bool,
}

impl Heat {
    /// `None` without a kernel or with the heat map turned off.
    pub fn compute(
        building: &Building,
        scene: &Scene,
        options: &RenderOptions,
    ) -> Result<Option<Heat>> {
        let (true, Some(kernel)) = (options.heatmap, scene.kernel) else {
            return Ok(None);
        };
        kernel.validate("render kernel")?;
        let grid = heat_grid(building, options.grid_step_m, options.grid_margin_m);
        let mut train = building.pilot_points();
        let mut noise = vec![kernel.sn2; train.len()];
        for smp in &scene.samples {
            train.push(smp.pos);
            noise.push(kernel.sn2 + smp.extra_noise);
        }
        let gp = GpModel::fit_with_noise(&kernel, &train, &noise, &DMatrix::zeros(train.len(), 0))?;
        let sd: Vec<f64> = gp
            .variance(&grid)
            .iter()
            .map(|v| v.max(0.0).sqrt())
            .collect();
        let lo = sd.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = sd.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = if lo.is_finite() && hi.is_finite() {
            (lo, hi)
        } else {
            (0.0, kernel.sf2.sqrt())
        };
        Ok(Some(Heat {
            grid,
            sd,
            lo,
            hi,
            prior: kernel.sf2.sqrt(),
            outlines: has_walkable_outlines(building),
        }))
    }

    /// Where `v` falls in the colour range, in `[0, 1]`.
    pub fn t(&self, v: f64) -> f64 {
        if self.hi - self.lo > 1e-9 {
            (v - self.lo) / (self.hi - self.lo)
        } else {
            0.5
        }
    }
}

/// Whether the building has outlines of walkable space (rooms, corridors, open areas).
pub(super) fn has_walkable_outlines(building: &Building) -> bool {
    building.outlines.iter().any(|o| is_walkable(o.kind))
}

fn is_walkable(kind: OutlineKind) -> bool {
    matches!(
        kind,
        OutlineKind::Room | OutlineKind::Corridor | OutlineKind::Area
    )
}

/// The points the heat map is drawn at: [`reference_grid`] (points within `margin` of an
/// edge, over the vertices' bounding box), plus, on the same lattice (`step` apart from the
/// floor's lowest vertex coordinates), every point inside a walkable outline of the floor
/// or less than half a step outside it (its cell reaches in).
pub(super) fn heat_grid(building: &Building, step: f64, margin: f64) -> Vec<Point> {
    use geo::{Contains, Coord, Distance, Euclidean, LineString, Polygon};
    let mut grid = reference_grid(building, step, margin);
    if !has_walkable_outlines(building) {
        return grid;
    }
    let key = |p: &Point, x0: f64, y0: f64| {
        (
            ((p.x - x0) / step).round() as i64,
            ((p.y - y0) / step).round() as i64,
        )
    };
    for floor in &building.floors {
        let on = |p: &&Point| p.floor == floor.id;
        let (mut x0, mut y0) = (f64::INFINITY, f64::INFINITY);
        for v in building.vertices.iter().map(|v| v.pos).filter(|p| on(&p)) {
            x0 = x0.min(v.x);
            y0 = y0.min(v.y);
        }
        let shapes: Vec<Polygon<f64>> = building
            .outlines
            .iter()
            .filter(|o| o.floor == floor.id && is_walkable(o.kind) && o.points.len() >= 3)
            .map(|o| {
                let ring: Vec<Coord<f64>> = o
                    .points
                    .iter()
                    .map(|p| Coord { x: p[0], y: p[1] })
                    .collect();
                Polygon::new(LineString::from(ring), vec![])
            })
            .collect();
        if shapes.is_empty() || !x0.is_finite() {
            continue;
        }
        let have: std::collections::HashSet<(i64, i64)> =
            grid.iter().filter(on).map(|p| key(p, x0, y0)).collect();
        let Extent {
            x0: bx0,
            y0: by0,
            x1: bx1,
            y1: by1,
        } = Extent::of(
            shapes
                .iter()
                .flat_map(|p| p.exterior().coords())
                .map(|c| (c.x, c.y)),
        );
        let (i0, i1) = (
            ((bx0 - x0) / step).floor() as i64,
            ((bx1 - x0) / step).ceil() as i64,
        );
        let (j0, j1) = (
            ((by0 - y0) / step).floor() as i64,
            ((by1 - y0) / step).ceil() as i64,
        );
        for j in j0..=j1 {
            for i in i0..=i1 {
                if have.contains(&(i, j)) {
                    continue;
                }
                let (x, y) = (x0 + i as f64 * step, y0 + j as f64 * step);
                // Inside, or its cell reaches in (so that the cells meet the walls).
                let c = Coord { x, y };
                if shapes
                    .iter()
                    .any(|s| s.contains(&c) || Euclidean.distance(&geo::Point(c), s) < step / 2.0)
                {
                    grid.push(Point::new(x, y, floor.id));
                }
            }
        }
    }
    grid
}
