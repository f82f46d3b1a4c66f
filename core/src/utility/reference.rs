//! The reference evaluator: SPEC section 3 written straight from the formula.
//!
//! `f_D(P) = 1/2 ln det(K_VV + sn2 I) - 1/2 ln det(K_VV + sn2 I - K_VS (K_SS + N_S)^-1 K_SV)`
//!
//! It builds every matrix from scratch with nalgebra and is the yardstick the fast engine
//! is tested against; it is not meant to be fast.

use nalgebra::{DMatrix, DVector};

use crate::gp::{Kernel, Point};
use crate::{Error, Result};

/// A point observed with noise `sn2 + extra_noise` (a pilot location or a walk sample).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    pub pos: Point,
    pub extra_noise: f64,
}

impl From<&crate::samples::Sample> for Observation {
    /// A walk sample as the utility sees it: its position and its label noise.
    fn from(s: &crate::samples::Sample) -> Self {
        Observation {
            pos: s.pos,
            extra_noise: s.extra_noise,
        }
    }
}

/// `f_D(P)` in nats for vertex set `vertices`, observations `obs` (samples plus pilot).
pub fn reference_utility(kernel: &Kernel, vertices: &[Point], obs: &[Observation]) -> Result<f64> {
    let nv = vertices.len();
    let ns = obs.len();
    let a = DMatrix::from_fn(nv, nv, |i, j| {
        kernel.k(&vertices[i], &vertices[j]) + if i == j { kernel.sn2 } else { 0.0 }
    });
    if ns == 0 {
        return Ok(0.0);
    }
    let c = DMatrix::from_fn(ns, ns, |i, j| {
        kernel.k(&obs[i].pos, &obs[j].pos)
            + if i == j {
                kernel.sn2 + obs[i].extra_noise
            } else {
                0.0
            }
    });
    let b = DMatrix::from_fn(nv, ns, |i, j| kernel.k(&vertices[i], &obs[j].pos));
    let chol_c = c
        .cholesky()
        .ok_or_else(|| Error::Numerical("K_SS + N_S is not positive definite".into()))?;
    let cinv_bt = chol_c.solve(&b.transpose());
    let sigma = &a - &b * cinv_bt;
    let sigma = (sigma.clone() + sigma.transpose()) * 0.5;
    let la = a
        .cholesky()
        .ok_or_else(|| Error::Numerical("K_VV + sn2 I is not positive definite".into()))?;
    let ls = sigma
        .cholesky()
        .ok_or_else(|| Error::Numerical("posterior covariance is not positive definite".into()))?;
    Ok(0.5 * (la.ln_determinant() - ls.ln_determinant()))
}

/// Observations for pilot points (noise `sn2` only).
pub fn pilot_observations(points: &[Point]) -> Vec<Observation> {
    points
        .iter()
        .map(|&pos| Observation {
            pos,
            extra_noise: 0.0,
        })
        .collect()
}

/// Gaussian log marginal likelihood helpers shared with the fit: `y^T K^-1 y` and
/// `ln det K` for one kernel matrix and several right-hand sides.
pub(crate) fn quad_and_logdet(k: &DMatrix<f64>, ys: &[DVector<f64>]) -> Option<(f64, f64)> {
    let chol = k.clone().cholesky()?;
    let mut quad = 0.0;
    for y in ys {
        let z = chol.l().solve_lower_triangular(y)?;
        quad += z.norm_squared();
    }
    Some((quad, chol.ln_determinant()))
}
