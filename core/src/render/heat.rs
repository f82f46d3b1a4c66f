//! The heat map: the GP posterior standard deviation on the reference grid.

use nalgebra::DMatrix;

use super::{RenderOptions, Scene};
use crate::Result;
use crate::building::Building;
use crate::eval::reference_grid;
use crate::gp::Point;
use crate::gp::predict::GpModel;

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
        let grid = reference_grid(building, options.grid_step_m, options.grid_margin_m);
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
