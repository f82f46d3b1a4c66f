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

use nalgebra::DMatrix;
use rayon::prelude::*;

use super::{Kernel, Point};
use crate::utility::dense::{self, Layout};
use crate::utility::simd::Isa;
use crate::{Error, Result};

/// Query points handled per parallel task in [`GpModel::predict`].
const CHUNK: usize = 256;

/// Most memory a fit may take, bytes: the factorisation's buffer, about `8 n^2` bytes
/// ([`fit_bytes`]), which then holds the model's factor `L` ([`GpModel::l`]), so at most
/// 8,176 training points. Beyond that a fit is refused before it allocates: the generated
/// 3,161-vertex floor's dense survey (23,121 points) took 4.3 GB and did not finish its
/// factorisation in 15 minutes as the world model of `simulate`. The same default as a
/// plan's memory budget ([`crate::plan::DEFAULT_MEMORY_BUDGET`]).
pub const FIT_MEMORY_BUDGET: u64 = crate::plan::DEFAULT_MEMORY_BUDGET;

/// Bytes a fit of `n` training points allocates for its factorisation.
pub fn fit_bytes(n: usize) -> u64 {
    8 * Layout::new(n).len() as u64
}

/// A fitted posterior: one Cholesky factor for all outputs.
#[derive(Debug, Clone)]
pub struct GpModel {
    kernel: Kernel,
    train: Vec<Point>,
    /// `ln det(K + N)` (0 without training points).
    ln_det: f64,
    /// Lower Cholesky factor `L` of `K + N` (zeros above the diagonal), for the solves.
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
        let need = fit_bytes(n);
        if need > FIT_MEMORY_BUDGET {
            return Err(Error::InvalidRequest(format!(
                "GP fit: {n} training points need about {} MiB (an {n} x {n} factor), more \
                 than the {} MiB a fit may take; use at most {} points (a part of the \
                 building, or fewer samples)",
                need.div_ceil(1 << 20),
                FIT_MEMORY_BUDGET >> 20,
                max_fit_points()
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
                ln_det: 0.0,
                l: DMatrix::zeros(0, 0),
                alpha: DMatrix::zeros(0, m),
                means,
            });
        }
        if let Some((i, s)) = noise
            .iter()
            .enumerate()
            .find(|(_, s)| !s.is_finite() || **s < 0.0)
        {
            return Err(Error::InvalidRequest(format!(
                "GP fit: noise variance {s} at training point {i} must be finite and >= 0"
            )));
        }
        let (l, ln_det) = factor(kernel, train, noise).ok_or_else(|| {
            Error::Numerical(format!(
                "GP fit: covariance of {n} training points is not positive definite \
                 (kernel sf2={}, ell={}, sn2={})",
                kernel.sf2, kernel.ell, kernel.sn2
            ))
        })?;
        let mut alpha = values.clone();
        for (a, &mu) in means.iter().enumerate() {
            alpha.column_mut(a).add_scalar_mut(-mu);
        }
        // (K + N)^-1 (Y - m) = L^-T L^-1 (Y - m); L has a positive diagonal.
        l.solve_lower_triangular_unchecked_mut(&mut alpha);
        l.tr_solve_lower_triangular_unchecked_mut(&mut alpha);
        Ok(GpModel {
            kernel: *kernel,
            train: train.to_vec(),
            ln_det,
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
        self.ln_det
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

/// Most training points a fit takes within [`FIT_MEMORY_BUDGET`].
pub fn max_fit_points() -> usize {
    let (mut lo, mut hi) = (0usize, 1usize << 20);
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        if fit_bytes(mid) <= FIT_MEMORY_BUDGET {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    lo
}

/// The lower Cholesky factor `L` of `K + N` (`n x n`, zeros above the diagonal) and
/// `ln det(K + N)`, or `None` when it is not positive definite.
///
/// By the engine's blocked factorisation ([`dense::factor`]) rather than nalgebra's
/// `Cholesky`: a `simulate` world model is a fit on a building's whole dense survey
/// (3,817 points on the generated mall), where nalgebra took 4.2 s of a 6.7 s run and
/// held the factor twice (see `docs/decisions/0008-gp-fit-factorisation.md`). Its upper
/// factor `U` (row-major, `U^T U = K + N`) read column-major is `L`: each row of `U`
/// becomes a column of `L` in place, so the fit holds one `n x n` matrix.
fn factor(kernel: &Kernel, train: &[Point], noise: &[f64]) -> Option<(DMatrix<f64>, f64)> {
    let n = train.len();
    let layout = Layout::new(n);
    let ld = layout.ld;
    let mut a = vec![0.0; layout.len()];
    // Row i of the upper triangle: k(x_i, x_j) for j >= i, noise on the diagonal.
    a.par_chunks_mut(ld)
        .take(n)
        .enumerate()
        .for_each(|(i, row)| {
            for j in i..n {
                row[j] = kernel.k(&train[i], &train[j]);
            }
            row[i] += noise[i];
        });
    let ln_det = dense::factor(Isa::detect(), &mut a, layout, 0)?;
    // Row i of U, read column-major, is column i of L (rows i..n); what lies before the
    // diagonal in it is not part of the factor. Columns move down to stride n in order,
    // each to an offset at most its own.
    for c in 0..n {
        a.copy_within(c * ld..c * ld + n, c * n);
        a[c * n..c * n + c].fill(0.0);
    }
    a.truncate(n * n);
    a.shrink_to_fit();
    Some((DMatrix::from_vec(n, n, a), ln_det))
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
    /// before its matrix is allocated; the largest that fits is named.
    #[test]
    fn a_fit_beyond_the_memory_budget_is_refused_with_its_size() {
        let k = Kernel::new(20.0, 4.0, 2.0);
        let most = max_fit_points();
        assert!(fit_bytes(most) <= FIT_MEMORY_BUDGET && fit_bytes(most + 1) > FIT_MEMORY_BUDGET);
        let n = most + 1;
        let train: Vec<Point> = (0..n).map(|i| Point::new(i as f64, 0.0, 0)).collect();
        let e = GpModel::fit(&k, &train, &DMatrix::zeros(n, 1)).expect_err("too large");
        let msg = e.to_string();
        let mib = fit_bytes(n).div_ceil(1 << 20);
        assert!(
            msg.contains(&format!("{n} training points need about {mib} MiB"))
                && msg.contains(&format!("use at most {most} points")),
            "{msg}"
        );
    }

    /// The factor, the solves and the log-determinant agree with nalgebra's Cholesky on a
    /// fit large enough for the factorisation's chunked path (more than 1,024 points).
    #[test]
    fn the_fit_agrees_with_nalgebras_cholesky() {
        let k = Kernel::new(180.0, 9.0, 2.5);
        let n = 1_100;
        let train: Vec<Point> = (0..n)
            .map(|i| {
                Point::new(
                    (i % 40) as f64 * 1.3,
                    (i / 40) as f64 * 1.7,
                    (i % 3 == 0) as i64,
                )
            })
            .collect();
        let noise: Vec<f64> = (0..n).map(|i| 2.5 + (i % 7) as f64 * 0.3).collect();
        let values = DMatrix::from_fn(n, 3, |i, a| -55.0 - ((i * 31 + a * 17) % 41) as f64);
        let gp = GpModel::fit_with_noise(&k, &train, &noise, &values).expect("fit");
        let mut km = DMatrix::from_fn(n, n, |i, j| k.k(&train[i], &train[j]));
        for i in 0..n {
            km[(i, i)] += noise[i];
        }
        let chol = nalgebra::Cholesky::new(km).expect("pd");
        let rel = |a: f64, b: f64| (a - b).abs() / (1.0 + a.abs().max(b.abs()));
        assert!(rel(gp.ln_det(), chol.ln_determinant()) < 1e-11);
        assert!((&gp.l - chol.l()).amax() < 1e-10);
        let queries: Vec<Point> = (0..50)
            .map(|i| Point::new(i as f64 * 1.1, 7.3, i % 2))
            .collect();
        let p = gp.predict(&queries);
        // The reference: means from (K + N)^-1 (Y - m), variances from L^-1 k.
        let mut centred = values.clone();
        for a in 0..3 {
            let mu = centred.column(a).mean();
            centred.column_mut(a).add_scalar_mut(-mu);
        }
        let alpha = chol.solve(&centred);
        for (q, x) in queries.iter().enumerate() {
            let kq = DMatrix::from_fn(n, 1, |i, _| k.k(&train[i], x));
            for a in 0..3 {
                let mean = values.column(a).mean() + kq.column(0).dot(&alpha.column(a));
                assert!(
                    rel(p.mean[(q, a)], mean) < 1e-9,
                    "{} vs {mean}",
                    p.mean[(q, a)]
                );
            }
            let v = chol.l().solve_lower_triangular(&kq).expect("solve");
            let var = (k.sf2 - v.norm_squared()).max(0.0);
            assert!(
                (p.variance[q] - var).abs() < 1e-8 * k.sf2,
                "{} vs {var}",
                p.variance[q]
            );
        }
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
