//! The session's running posterior: the collected utility and the uncertainty at every
//! vertex, updated sample by sample instead of refitted per call.
//!
//! # What it keeps
//! With `S` the pilot locations then the samples in arrival order, `N_S` their noise
//! (`sn2`, plus the label noise of a human sample), `A = K_VV + sn2 I` over the vertices:
//! * `L`, the Cholesky factor of `K_SS + N_S` (lower triangular, rows packed);
//! * `W = L^-1 K_SV` (one row of `|V|` values per observation);
//! * `R`, the upper Cholesky factor of `Sigma = A - W^T W` (the covariance of the
//!   vertices' fingerprints given everything observed), and its diagonal;
//! * `ln det Sigma`.
//!
//! The utility of SPEC section 3 is `1/2 ln det A - 1/2 ln det Sigma` and the posterior
//! variance of the latent RSS at vertex `v` is `Sigma_vv - sn2`: both are read off in
//! `O(1)` and `O(|V|)`.
//!
//! # One sample, `x` with noise `r` (n observations so far)
//! * `l = L^-1 k_Sx` (a forward substitution, `O(n^2)`), `d^2 = k_xx + r - |l|^2`: the new
//!   row of `L` is `[l, d]`.
//! * `w = (k_Vx - W^T l) / d` (`O(n |V|)`): the new row of `W`; `Sigma' = Sigma - w w^T`.
//! * `q = R^-T w` (`O(|V|^2)`); by the matrix determinant lemma
//!   `ln det Sigma' = ln det Sigma + ln(1 - |q|^2)`, and `R` is downdated by the LINPACK
//!   `dchdd` rotations (`O(|V|^2)`).
//!
//! So a scan costs `O(n^2 + n |V| + |V|^2)` time and the state `n^2/2 + n |V| + |V|^2`
//! doubles, against `O((n + |V|)^3)` for the from-scratch evaluation. The forward
//! substitution reads all of `L` once: at 10,000 samples that is 400 MB read per scan, so a
//! scan is memory-bound there (see `examples/session_progress.rs` for measured times).
//! The values agree with a from-scratch evaluation to rounding (tested to 1e-9 relative).

use crate::building::Building;
use crate::gp::{Kernel, Point};
use crate::{Error, Result};

/// The running posterior of a session (see the module documentation).
#[derive(Debug, Clone)]
pub struct IncrementalPosterior {
    kernel: Kernel,
    vertices: Vec<Point>,
    /// Observation positions, in order (pilot locations first).
    pts: Vec<Point>,
    /// Rows of `L`, packed: row `i` holds `i + 1` values from offset `i (i + 1) / 2`.
    l: Vec<f64>,
    /// Rows of `W`, `nv` values each.
    w: Vec<f64>,
    /// Upper Cholesky factor of `Sigma`, row-major `nv x nv` (entries below the diagonal
    /// are zero).
    r: Vec<f64>,
    /// Diagonal of `Sigma`.
    sigma_diag: Vec<f64>,
    logdet_a: f64,
    logdet_sigma: f64,
    n_prior: usize,
    /// Scratch vectors (kept to avoid an allocation per sample).
    scratch_k: Vec<f64>,
    scratch_l: Vec<f64>,
    scratch_w: Vec<f64>,
    scratch_c: Vec<f64>,
    scratch_s: Vec<f64>,
}

/// `sum a_i b_i` with eight independent accumulators, so that the compiler vectorises it
/// (a single running sum is a dependency chain it may not reorder).
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 8];
    let ca = a.chunks_exact(8);
    let cb = b.chunks_exact(8);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += x * y;
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7])) + tail
}

/// `y += alpha x`.
#[inline]
fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += alpha * xi;
    }
}

impl IncrementalPosterior {
    /// The posterior given the building's pilot locations (noise `sn2` each).
    pub fn new(building: &Building, kernel: Kernel) -> Result<Self> {
        kernel.validate("kernel")?;
        let vertices = building.vertex_points();
        let nv = vertices.len();
        // R = chol(A), upper: A = R^T R.
        let mut r = vec![0.0; nv * nv];
        for i in 0..nv {
            for j in i..nv {
                r[i * nv + j] =
                    kernel.k(&vertices[i], &vertices[j]) + if i == j { kernel.sn2 } else { 0.0 };
            }
        }
        let sigma_diag: Vec<f64> = (0..nv).map(|i| r[i * nv + i]).collect();
        // Right-looking upper Cholesky in place.
        let mut logdet_a = 0.0;
        for k in 0..nv {
            let p = r[k * nv + k];
            if !(p.is_finite() && p > 0.0) {
                return Err(Error::Numerical(
                    "K_VV + sn2 I is not positive definite".into(),
                ));
            }
            let d = p.sqrt();
            logdet_a += 2.0 * d.ln();
            r[k * nv + k] = d;
            for j in k + 1..nv {
                r[k * nv + j] /= d;
            }
            for i in k + 1..nv {
                let rki = r[k * nv + i];
                if rki == 0.0 {
                    continue;
                }
                for j in i..nv {
                    r[i * nv + j] -= rki * r[k * nv + j];
                }
            }
        }
        let mut post = IncrementalPosterior {
            kernel,
            vertices,
            pts: Vec::new(),
            l: Vec::new(),
            w: Vec::new(),
            r,
            sigma_diag,
            logdet_a,
            logdet_sigma: logdet_a,
            n_prior: 0,
            scratch_k: Vec::new(),
            scratch_l: Vec::new(),
            scratch_w: vec![0.0; nv],
            scratch_c: vec![0.0; nv],
            scratch_s: vec![0.0; nv],
        };
        for p in building.pilot_points() {
            post.add(p, 0.0)?;
        }
        post.n_prior = post.pts.len();
        Ok(post)
    }

    /// Number of samples added (pilot locations not counted).
    pub fn samples(&self) -> usize {
        self.pts.len() - self.n_prior
    }

    /// Conditions on one more observation at `p` with noise `sn2 + extra_noise`. On error
    /// nothing changes.
    pub fn add(&mut self, p: Point, extra_noise: f64) -> Result<()> {
        let nv = self.vertices.len();
        let n = self.pts.len();
        let kern = self.kernel;
        // k_Sx and l = L^-1 k_Sx.
        self.scratch_k.clear();
        self.scratch_k
            .extend(self.pts.iter().map(|q| kern.k(q, &p)));
        self.scratch_l.clear();
        self.scratch_l.resize(n, 0.0);
        for i in 0..n {
            let row = &self.l[i * (i + 1) / 2..(i + 1) * (i + 2) / 2];
            let s = dot(&row[..i], &self.scratch_l[..i]);
            self.scratch_l[i] = (self.scratch_k[i] - s) / row[i];
        }
        let d2 = kern.sf2 + kern.sn2 + extra_noise - dot(&self.scratch_l, &self.scratch_l);
        if !(d2.is_finite() && d2 > 0.0) {
            return Err(Error::Numerical(format!(
                "K_SS + N_S lost positive definiteness at observation {} ({:.3}, {:.3}, floor {})",
                n + 1,
                p.x,
                p.y,
                p.floor
            )));
        }
        let d = d2.sqrt();
        // w = (k_Vx - W^T l) / d.
        let w = &mut self.scratch_w;
        for (wi, v) in w.iter_mut().zip(&self.vertices) {
            *wi = kern.k(v, &p);
        }
        for (j, &lj) in self.scratch_l.iter().enumerate() {
            if lj != 0.0 {
                axpy(-lj, &self.w[j * nv..(j + 1) * nv], w);
            }
        }
        for wi in w.iter_mut() {
            *wi /= d;
        }
        // q = R^-T w (forward substitution with R^T, lower triangular).
        let q = &mut self.scratch_c;
        q.copy_from_slice(w);
        for i in 0..nv {
            let qi = q[i] / self.r[i * nv + i];
            q[i] = qi;
            if qi != 0.0 {
                let row = &self.r[i * nv + i + 1..(i + 1) * nv];
                for (qj, rij) in q[i + 1..].iter_mut().zip(row) {
                    *qj -= qi * rij;
                }
            }
        }
        let qq = dot(q, q);
        let rho2 = 1.0 - qq;
        if !(rho2.is_finite() && rho2 > 0.0) {
            return Err(Error::Numerical(
                "posterior covariance of the vertices lost positive definiteness".into(),
            ));
        }
        // Downdate R (LINPACK dchdd): rotations from the last index up, then applied to
        // the columns of R.
        let (c, s) = (&mut self.scratch_s, &mut self.scratch_k);
        s.clear();
        s.resize(nv, 0.0);
        let mut alpha = rho2.sqrt();
        for i in (0..nv).rev() {
            let scale = alpha + q[i].abs();
            let a = alpha / scale;
            let b = q[i] / scale;
            let norm = a.hypot(b);
            c[i] = a / norm;
            s[i] = b / norm;
            alpha = scale * norm;
        }
        for j in 0..nv {
            let mut xx = 0.0;
            for i in (0..=j).rev() {
                let rij = self.r[i * nv + j];
                let t = c[i] * xx + s[i] * rij;
                self.r[i * nv + j] = c[i] * rij - s[i] * xx;
                xx = t;
            }
        }
        // Commit.
        for (sd, wi) in self.sigma_diag.iter_mut().zip(w.iter()) {
            *sd -= wi * wi;
        }
        self.logdet_sigma += rho2.ln();
        self.l.extend_from_slice(&self.scratch_l);
        self.l.push(d);
        self.w.extend_from_slice(w);
        self.pts.push(p);
        Ok(())
    }

    /// `f_D` of the pilot data plus the samples added, nats (SPEC section 3).
    pub fn utility(&self) -> f64 {
        (0.5 * (self.logdet_a - self.logdet_sigma)).max(0.0)
    }

    /// Posterior variance of the latent RSS at every vertex, in building order, dB².
    pub fn vertex_variance(&self) -> Vec<f64> {
        self.sigma_diag
            .iter()
            .map(|s| (s - self.kernel.sn2).max(0.0))
            .collect()
    }

    /// Bytes held by the factors (what grows with the samples).
    pub fn memory_bytes(&self) -> usize {
        8 * (self.l.capacity() + self.w.capacity() + self.r.capacity())
    }
}
