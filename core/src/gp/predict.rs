//! GP posterior mean and variance for many outputs (access points) that share one kernel
//! and one set of training positions.
//!
//! Every access point is modelled as an independent GP with the same kernel (SPEC section
//! 2); its training values are centred on their own sample mean, which is added back to
//! the prediction. Because the training positions and the noise are shared, one Cholesky
//! factor `L Lᵀ = K + N` serves every access point, and the posterior variance is the same
//! for all of them:
//!
//! ```text
//! mean_a(q) = m_a + k_qᵀ (K + N)⁻¹ (y_a - m_a)
//! var(q)    = sf2 - k_qᵀ (K + N)⁻¹ k_q          (latent f, without observation noise)
//! ```
//!
//! # Examples
//!
//! ```
//! use nalgebra::DMatrix;
//! use trailprint::gp::{predict::GpModel, Kernel, Point};
//!
//! let kernel = Kernel::new(10.0, 5.0, 1.0);
//! let train = [Point::new(0.0, 0.0, 0), Point::new(4.0, 0.0, 0)];
//! // Two access points (columns), two training positions (rows).
//! let values = DMatrix::from_row_slice(2, 2, &[-60.0, -80.0, -70.0, -75.0]);
//! let gp = GpModel::fit(&kernel, &train, &values)?;
//! let p = gp.predict(&[Point::new(2.0, 0.0, 0)]);
//! assert!((p.mean[(0, 0)] - -65.0).abs() < 1e-9); // the midpoint, by symmetry
//! assert!(p.variance[0] < kernel.sf2);
//! # Ok::<(), trailprint::Error>(())
//! ```

use nalgebra::{Cholesky, DMatrix, Dyn};
use rayon::prelude::*;

use super::{Kernel, Point};
use crate::{Error, Result};

/// Query points handled per parallel task in [`GpModel::predict`].
const CHUNK: usize = 256;

/// Most memory a fitted model may take, bytes: a fit holds two `n x n` matrices (the
/// Cholesky factor and its lower triangle, [`GpModel::l`]), 16 `n^2` bytes, so at most
/// 5,792 training points. Beyond that a fit is refused before it allocates: the
/// generated 3,161-vertex floor's dense survey (23,121 points) took 4.3 GB and did not
/// finish its factorisation in 15 minutes as the world model of `simulate`. The same
/// default as a plan's memory budget ([`crate::plan::DEFAULT_MEMORY_BUDGET`]).
pub const FIT_MEMORY_BUDGET: u64 = crate::plan::DEFAULT_MEMORY_BUDGET;

/// A fitted posterior: one Cholesky factor for all outputs.
#[derive(Debug, Clone)]
pub struct GpModel {
    kernel: Kernel,
    train: Vec<Point>,
    /// `None` when there are no training points (the posterior is the prior).
    chol: Option<Cholesky<f64, Dyn>>,
    /// Lower factor `L` (zeros above the diagonal), kept for the variance solves.
    l: DMatrix<f64>,
    /// `(K + N)⁻¹ (Y - m)`, one column per output.
    alpha: DMatrix<f64>,
    /// Per-output mean of the training values.
    means: Vec<f64>,
}

/// Posterior at a set of query points.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// `mean[(q, a)]`: posterior mean of output `a` at query point `q`.
    pub mean: DMatrix<f64>,
    /// `variance[q]`: posterior variance of the latent function at query point `q`
    /// (the same for every output; add `sn2` for the variance of an observation).
    pub variance: Vec<f64>,
}

impl GpModel {
    /// Fits the posterior with observation noise `kernel.sn2` at every training point.
    ///
    /// `values` has one row per training point and one column per output (access point).
    pub fn fit(kernel: &Kernel, train: &[Point], values: &DMatrix<f64>) -> Result<Self> {
        let noise = vec![kernel.sn2; train.len()];
        Self::fit_with_noise(kernel, train, &noise, values)
    }

    /// Fits the posterior with a noise variance per training point (for example `sn2` plus
    /// the label noise of a human sample, SPEC section 4).
    ///
    /// Errors when the shapes disagree, a value is not finite, or the covariance matrix is
    /// not positive definite.
    pub fn fit_with_noise(
        kernel: &Kernel,
        train: &[Point],
        noise: &[f64],
        values: &DMatrix<f64>,
    ) -> Result<Self> {
        kernel.validate("GP kernel")?;
        let n = train.len();
        if noise.len() != n || values.nrows() != n {
            return Err(Error::InvalidRequest(format!(
                "GP fit: {n} training points but {} noise values and {} value rows",
                noise.len(),
                values.nrows()
            )));
        }
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(Error::Numerical(format!(
                "GP fit: training value {v} is not finite"
            )));
        }
        let need = 16.0 * (n as f64).powi(2);
        if need > FIT_MEMORY_BUDGET as f64 {
            return Err(Error::InvalidRequest(format!(
                "GP fit: {n} training points need about {} MiB (two {n} x {n} matrices), more \
                 than the {} MiB a fit may take; use at most 5,792 points (a part of the \
                 building, or fewer samples)",
                (need / (1u64 << 20) as f64).ceil(),
                FIT_MEMORY_BUDGET >> 20
            )));
        }
        let m = values.ncols();
        let means: Vec<f64> = (0..m)
            .map(|a| {
                if n == 0 {
                    0.0
                } else {
                    values.column(a).sum() / n as f64
                }
            })
            .collect();
        if n == 0 {
            return Ok(GpModel {
                kernel: *kernel,
                train: Vec::new(),
                chol: None,
                l: DMatrix::zeros(0, 0),
                alpha: DMatrix::zeros(0, m),
                means,
            });
        }
        let mut k = DMatrix::from_fn(n, n, |i, j| kernel.k(&train[i], &train[j]));
        for (i, &s) in noise.iter().enumerate() {
            if !s.is_finite() || s < 0.0 {
                return Err(Error::InvalidRequest(format!(
                    "GP fit: noise variance {s} at training point {i} must be finite and >= 0"
                )));
            }
            k[(i, i)] += s;
        }
        let chol = Cholesky::new(k).ok_or_else(|| {
            Error::Numerical(format!(
                "GP fit: covariance of {n} training points is not positive definite \
                 (kernel sf2={}, ell={}, sn2={})",
                kernel.sf2, kernel.ell, kernel.sn2
            ))
        })?;
        let mut centred = values.clone();
        for (a, &mu) in means.iter().enumerate() {
            centred.column_mut(a).add_scalar_mut(-mu);
        }
        let alpha = chol.solve(&centred);
        let l = chol.l();
        Ok(GpModel {
            kernel: *kernel,
            train: train.to_vec(),
            chol: Some(chol),
            l,
            alpha,
            means,
        })
    }

    /// The kernel the model was fitted with.
    pub fn kernel(&self) -> &Kernel {
        &self.kernel
    }

    /// Training positions.
    pub fn train(&self) -> &[Point] {
        &self.train
    }

    /// Number of outputs (access points).
    pub fn n_outputs(&self) -> usize {
        self.means.len()
    }

    /// Per-output mean of the training values (the prior mean of each output).
    pub fn output_means(&self) -> &[f64] {
        &self.means
    }

    /// `ln det(K + N)` of the training covariance (0 without training points).
    pub fn ln_det(&self) -> f64 {
        self.chol.as_ref().map_or(0.0, |c| c.ln_determinant())
    }

    /// Cross-covariance `K(query, train)`, one row per query point.
    fn cross(&self, query: &[Point]) -> DMatrix<f64> {
        DMatrix::from_fn(query.len(), self.train.len(), |i, j| {
            self.kernel.k(&query[i], &self.train[j])
        })
    }

    /// Posterior means only, `q x m`. Cheaper than [`GpModel::predict`].
    ///
    /// Complexity: `O(q n (m + 1))` for `q` queries, `n` training points, `m` outputs.
    pub fn mean(&self, query: &[Point]) -> DMatrix<f64> {
        let m = self.n_outputs();
        let chunks: Vec<DMatrix<f64>> = query
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut out = self.cross(chunk) * &self.alpha;
                for (a, &mu) in self.means.iter().enumerate() {
                    out.column_mut(a).add_scalar_mut(mu);
                }
                out
            })
            .collect();
        stack_rows(&chunks, query.len(), m)
    }

    /// Posterior variances of the latent function only.
    ///
    /// Complexity: `O(q n²)`; parallel over chunks of query points.
    pub fn variance(&self, query: &[Point]) -> Vec<f64> {
        query
            .par_chunks(CHUNK)
            .flat_map_iter(|chunk| self.variance_chunk(chunk, None))
            .collect()
    }

    fn variance_chunk(&self, chunk: &[Point], kqn: Option<&DMatrix<f64>>) -> Vec<f64> {
        let prior: Vec<f64> = chunk.iter().map(|p| self.kernel.k(p, p)).collect();
        if self.train.is_empty() {
            return prior;
        }
        // V = L⁻¹ K(train, chunk); var = k(q, q) - |V_q|².
        let mut v = match kqn {
            Some(k) => k.transpose(),
            None => DMatrix::from_fn(self.train.len(), chunk.len(), |i, j| {
                self.kernel.k(&self.train[i], &chunk[j])
            }),
        };
        // L has a positive diagonal (it is a Cholesky factor), so the solve succeeds.
        self.l.solve_lower_triangular_unchecked_mut(&mut v);
        prior
            .iter()
            .enumerate()
            .map(|(j, &p)| (p - v.column(j).norm_squared()).max(0.0))
            .collect()
    }

    /// Posterior means (`q x m`) and latent variances (`q`) at the query points.
    pub fn predict(&self, query: &[Point]) -> Prediction {
        let m = self.n_outputs();
        let parts: Vec<(DMatrix<f64>, Vec<f64>)> = query
            .par_chunks(CHUNK)
            .map(|chunk| {
                let kqn = self.cross(chunk);
                let mut mean = &kqn * &self.alpha;
                for (a, &mu) in self.means.iter().enumerate() {
                    mean.column_mut(a).add_scalar_mut(mu);
                }
                let var = self.variance_chunk(chunk, Some(&kqn));
                (mean, var)
            })
            .collect();
        let (means, variances): (Vec<DMatrix<f64>>, Vec<Vec<f64>>) = parts.into_iter().unzip();
        Prediction {
            mean: stack_rows(&means, query.len(), m),
            variance: variances.into_iter().flatten().collect(),
        }
    }
}

/// Stacks row blocks (all with `m` columns) into one `rows x m` matrix.
fn stack_rows(blocks: &[DMatrix<f64>], rows: usize, m: usize) -> DMatrix<f64> {
    let mut out = DMatrix::zeros(rows, m);
    let mut r = 0;
    for b in blocks {
        out.rows_mut(r, b.nrows()).copy_from(b);
        r += b.nrows();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
    }

    /// A fit too large for [`FIT_MEMORY_BUDGET`] is refused with the count and the size,
    /// before its matrices are allocated (5,793 points would take 512 MiB and more).
    #[test]
    fn a_fit_beyond_the_memory_budget_is_refused_with_its_size() {
        let k = Kernel::new(20.0, 4.0, 2.0);
        let n = 5_793;
        let train: Vec<Point> = (0..n).map(|i| Point::new(i as f64, 0.0, 0)).collect();
        let e = GpModel::fit(&k, &train, &DMatrix::zeros(n, 1)).expect_err("too large");
        let msg = e.to_string();
        assert!(
            msg.contains("5793 training points need about 513 MiB"),
            "{msg}"
        );
        // One point fewer fits the budget (checked on the estimate, not by fitting).
        assert!(16.0 * (5_792f64).powi(2) <= FIT_MEMORY_BUDGET as f64);
    }

    #[test]
    fn one_training_point_closed_form() {
        let k = Kernel::new(20.0, 4.0, 2.0);
        let x0 = Point::new(1.0, 1.0, 0);
        let values = DMatrix::from_row_slice(1, 2, &[-55.0, -70.0]);
        let gp = GpModel::fit(&k, &[x0], &values).expect("fit");
        let q = [
            Point::new(1.0, 1.0, 0),
            Point::new(4.0, 5.0, 0),
            Point::new(1.0, 1.0, 1),
        ];
        let p = gp.predict(&q);
        for (i, qi) in q.iter().enumerate() {
            // Centring on one value leaves nothing to explain: the mean is the value.
            assert!(close(p.mean[(i, 0)], -55.0));
            assert!(close(p.mean[(i, 1)], -70.0));
            let kq = k.k(qi, &x0);
            let expect = 20.0 - kq * kq / (20.0 + 2.0);
            assert!(
                close(p.variance[i], expect),
                "{} vs {expect}",
                p.variance[i]
            );
        }
        // Across floors the point is independent: the prior variance.
        assert!(close(p.variance[2], 20.0));
    }

    #[test]
    fn two_training_points_closed_form() {
        let (sf2, ell, sn2) = (30.0, 5.0, 3.0);
        let k = Kernel::new(sf2, ell, sn2);
        let x1 = Point::new(0.0, 0.0, 0);
        let x2 = Point::new(3.0, 4.0, 0); // 5 m apart
        let (y1, y2) = (-50.0, -80.0);
        let values = DMatrix::from_row_slice(2, 1, &[y1, y2]);
        let gp = GpModel::fit(&k, &[x1, x2], &values).expect("fit");
        let c = sf2 * (-5.0f64 / ell).exp();
        let s = sf2 + sn2;
        let mu = (y1 + y2) / 2.0;
        let d = (y1 - y2) / 2.0;
        let queries = [
            Point::new(0.0, 0.0, 0),
            Point::new(1.0, 2.0, 0),
            Point::new(-3.0, 7.5, 0),
            Point::new(10.0, 0.0, 2),
        ];
        let p = gp.predict(&queries);
        let means = gp.mean(&queries);
        let vars = gp.variance(&queries);
        for (i, q) in queries.iter().enumerate() {
            let (k1, k2) = (k.k(q, &x1), k.k(q, &x2));
            let mean = mu + d * (k1 - k2) / (s - c);
            let var = sf2 - (s * (k1 * k1 + k2 * k2) - 2.0 * c * k1 * k2) / (s * s - c * c);
            assert!(close(p.mean[(i, 0)], mean), "{} vs {mean}", p.mean[(i, 0)]);
            assert!(close(p.variance[i], var), "{} vs {var}", p.variance[i]);
            assert!(close(means[(i, 0)], mean));
            assert!(close(vars[i], var));
        }
        assert!(close(gp.ln_det(), (s * s - c * c).ln()));
    }

    #[test]
    fn without_training_points_the_prior_is_returned() {
        let k = Kernel::new(7.0, 2.0, 1.0);
        let gp = GpModel::fit(&k, &[], &DMatrix::zeros(0, 3)).expect("fit");
        let p = gp.predict(&[Point::new(0.0, 0.0, 0)]);
        assert_eq!(p.variance, vec![7.0]);
        assert_eq!(p.mean.shape(), (1, 3));
    }

    #[test]
    fn many_queries_match_one_by_one_across_chunks() {
        let k = Kernel::new(25.0, 6.0, 2.0);
        let train: Vec<Point> = (0..40)
            .map(|i| Point::new(i as f64 * 0.7, (i % 5) as f64, (i % 2) as i64))
            .collect();
        let values = DMatrix::from_fn(40, 3, |i, a| -60.0 - (i * (a + 1)) as f64 % 17.0);
        let gp = GpModel::fit(&k, &train, &values).expect("fit");
        let queries: Vec<Point> = (0..(CHUNK * 2 + 17))
            .map(|i| Point::new(i as f64 * 0.05, 1.3, (i % 2) as i64))
            .collect();
        let all = gp.predict(&queries);
        for i in [0, 1, CHUNK - 1, CHUNK, CHUNK * 2 + 16] {
            let one = gp.predict(&queries[i..=i]);
            assert!(close(one.variance[0], all.variance[i]));
            for a in 0..3 {
                assert!(close(one.mean[(0, a)], all.mean[(i, a)]));
            }
        }
    }

    #[test]
    fn shape_mismatch_is_an_error() {
        let k = Kernel::new(7.0, 2.0, 1.0);
        let e = GpModel::fit(&k, &[Point::new(0.0, 0.0, 0)], &DMatrix::zeros(2, 1));
        assert!(e.is_err());
    }
}
