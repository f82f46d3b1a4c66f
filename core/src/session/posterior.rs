//! The session's running posterior: the collected utility and the uncertainty at every
//! vertex, updated sample by sample instead of refitted per call.
//!
//! # What it keeps
//! With `S` the observations (the pilot locations, then the samples in arrival order),
//! `N_S` their noise (`sn2`, plus the label noise of a human sample),
//! `A = K_VV + sn2 I` over the vertices:
//! * `L`, the Cholesky factor of `K_SS + N_S` (lower triangular, one row per observation);
//! * `W = L^-1 K_SV` (one row of `|V|` values per observation);
//! * `R`, the upper Cholesky factor of `Sigma = A - W^T W` (the covariance of the
//!   vertices' fingerprints given everything observed), and its diagonal;
//! * `ln det Sigma`.
//!
//! The utility of SPEC section 3 is `1/2 ln det A - 1/2 ln det Sigma` and the posterior
//! variance of the latent RSS at vertex `v` is `Sigma_vv - sn2`: both are read off in
//! `O(1)` and `O(|V|)`.
//!
//! # One observation, `x` with noise `r` (n observations so far)
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
//!
//! # Bounded memory: one sample of every `k`
//! The `n^2/2` of `L` grows without end in a long survey (a robot's 5 km at 0.5 m is
//! 10,000 samples, 400 MB), and a phone kills the app. So the posterior has a memory
//! budget ([`IncrementalPosterior::new`]), and the number of observations it can hold
//! follows from it. Until that many, every sample is conditioned on and the figures are
//! exact. When one more would not fit, the posterior is built again on one sample of
//! every `k = 2` consecutive ones (on one floor), then `k = 4`, and so on: of each run of
//! `k`, the sample nearest to a vertex.
//!
//! Conditioning on some of the samples can only tell less than on all of them: the
//! utility read off is then **at most** the samples' own, the uncertainty **at least**
//! theirs, and both are exact for the samples kept. Why the sample nearest to a vertex:
//! `f_D` and the coverage map are about the vertices, and with the kernels fitted here
//! (`sf2 / sn2` in the hundreds) a sample tells most about the points right around it.
//! On the demo building, 600 robot samples every 0.5 m tell 93.04 nats; one of every 4
//! kept, the nearest to a vertex, 87.73; the first of each run, 68.80 (and the mean of
//! each run, tried first, 65.69). Test
//! `tests::past_its_budget_the_posterior_keeps_one_sample_of_each_run_and_bounds_the_samples_own`
//! prints the first two.
//! The samples of a run not yet complete are not in the figures until it is (or
//! [`IncrementalPosterior::flush`]). [`IncrementalPosterior::block`] says which case
//! applies; the session's progress carries it, so that the app can say "at least".

use crate::building::Building;
use crate::gp::{Kernel, Point};
use crate::utility::dense::{self, Layout};
use crate::utility::simd::Isa;
use crate::{Error, Result};

/// Largest run of samples one kept sample may stand for (beyond, the budget is absurdly
/// small for the survey and the session says so).
const MAX_BLOCK: usize = 1 << 16;

/// From this many observations on, a rebuild (and [`IncrementalPosterior::add_all`], what
/// resuming a session uses) factors them at once with the engine's blocked
/// factorisation ([`dense::factor`]) instead of row by row: one pass at the core's FMA
/// rate instead of `n` memory-bound forward substitutions (on the office floor of
/// `examples/session_progress.rs`, building 10,000 rows row by row took 233 s).
pub const DENSE_FROM: usize = 512;

/// Most samples a replan conditions on: beyond, one of every `k` (the nearest to a
/// vertex, as the running posterior keeps them). A replan's exact evaluations cost
/// about `|S|^3 / 6` with `S` the prior and the walk's samples: on the generated mall
/// (565 vertices), one of a 500 m robot walk took 0.08 s given 1,000 prior samples,
/// 0.31 s given 2,000 and 1.33 s given 4,000, when the session gives a replan 1 s
/// (`examples/replan_prior.rs`); a phone is several times slower.
pub const REPLAN_PRIOR_MAX: usize = 1024;

/// The running posterior of a session (see the module documentation).
#[derive(Debug, Clone)]
pub struct IncrementalPosterior {
    kernel: Kernel,
    vertices: Vec<Point>,
    /// Observation positions, in order (pilot locations first), and their extra noise.
    pts: Vec<Point>,
    extra: Vec<f64>,
    /// The observations conditioned on (indices into `pts`, increasing).
    rows: Vec<usize>,
    /// `pts[..decided]` have been considered: kept in `rows` or not.
    decided: usize,
    /// Per row: its row of `L` (`i + 1` values) then its row of `W` (`|V|` values), so
    /// that memory grows row by row with no large reallocation.
    lw: Vec<Vec<f64>>,
    /// Upper Cholesky factor of `Sigma`, row-major `nv x nv` (entries below the diagonal
    /// are zero).
    r: Vec<f64>,
    /// Diagonal of `Sigma`.
    sigma_diag: Vec<f64>,
    logdet_a: f64,
    logdet_sigma: f64,
    n_prior: usize,
    /// One sample kept of every `block` (1: all, exact).
    block: usize,
    /// Most rows the memory budget allows.
    max_rows: usize,
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

/// Bytes the state holds with `rows` rows on `nv` vertices: `L`, `W`, `R` and the
/// vectors of `|V|` values.
pub fn posterior_bytes(rows: usize, nv: usize) -> usize {
    let rows_part = rows.saturating_mul(rows + 1) / 2 + rows.saturating_mul(nv);
    8usize.saturating_mul(
        rows_part
            .saturating_add(nv.saturating_mul(nv))
            .saturating_add(5 * nv),
    )
}

/// Bytes a blocked build of `rows` rows holds at its peak: the joint matrix of the rows
/// and the vertices, and the state taken out of it.
fn dense_build_bytes(rows: usize, nv: usize) -> usize {
    8usize
        .saturating_mul(Layout::new(rows.saturating_add(nv)).len())
        .saturating_add(posterior_bytes(rows, nv))
}

/// Upper Cholesky factor of `A = K_VV + sn2 I` (row-major, zeros below the diagonal),
/// its diagonal before factoring (`Sigma` with no observation), and `ln det A`. By the
/// engine's blocked factorisation ([`dense::factor`]): on 3,161 vertices the scalar loop
/// it replaces took 6.2 s of a session's start.
fn factor_a(kernel: &Kernel, vertices: &[Point]) -> Result<(Vec<f64>, Vec<f64>, f64)> {
    let nv = vertices.len();
    let layout = Layout::new(nv);
    let ld = layout.ld;
    let mut a = vec![0.0; layout.len()];
    for (i, v) in vertices.iter().enumerate() {
        let row = &mut a[i * ld..i * ld + nv];
        for (j, w) in vertices.iter().enumerate().skip(i) {
            row[j] = kernel.k(v, w);
        }
        row[i] += kernel.sn2;
    }
    let sigma_diag: Vec<f64> = (0..nv).map(|i| a[i * ld + i]).collect();
    let logdet_a = dense::factor(Isa::detect(), &mut a, layout, 0)
        .ok_or_else(|| Error::Numerical("K_VV + sn2 I is not positive definite".into()))?;
    let mut r = vec![0.0; nv * nv];
    for i in 0..nv {
        r[i * nv + i..(i + 1) * nv].copy_from_slice(&a[i * ld + i..i * ld + nv]);
    }
    Ok((r, sigma_diag, logdet_a))
}

impl IncrementalPosterior {
    /// The posterior given the building's pilot locations (noise `sn2` each), within the
    /// memory budget `memory_bytes` (see the module documentation): its state holds at
    /// most half of it, and a blocked rebuild at most all of it. A budget too small for
    /// the vertices' own factor and the pilot data is refused with the size needed.
    pub fn new(building: &Building, kernel: Kernel, memory_bytes: usize) -> Result<Self> {
        kernel.validate("kernel")?;
        let vertices = building.vertex_points();
        let nv = vertices.len();
        let pilot = building.pilot_points();
        let half = memory_bytes / 2;
        // Room for the pilot rows and at least two sample rows.
        let need = posterior_bytes(pilot.len() + 2, nv);
        if memory_bytes < Self::least_memory(building) {
            return Err(Error::InvalidRequest(format!(
                "the session's running posterior of {nv} vertices and {} pilot points \
                 needs at least {} MiB, half a memory budget of {} MiB: raise the \
                 session's memory_budget_mb",
                pilot.len(),
                need.div_ceil(1 << 20),
                (2 * need).div_ceil(1 << 20)
            )));
        }
        let fits = |m: usize| {
            posterior_bytes(m, nv) <= half
                && (m < DENSE_FROM || dense_build_bytes(m, nv) <= memory_bytes)
        };
        // Largest row count that fits (`fits` holds up to some count, then never).
        let (mut lo, mut hi) = (pilot.len() + 2, pilot.len() + 2);
        while hi < usize::MAX / 4 && fits(hi) {
            lo = hi;
            hi = hi.saturating_mul(2);
        }
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if fits(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let mut post = Self::empty(kernel, vertices, lo)?;
        for p in pilot {
            post.pts.push(p);
            post.extra.push(0.0);
            post.add_row(post.pts.len() - 1)?;
            post.decided = post.pts.len();
        }
        post.n_prior = post.pts.len();
        Ok(post)
    }

    /// The least memory budget [`Self::new`] takes for `building`: room for the
    /// vertices' factor, the pilot rows and two sample rows, in half of it.
    pub fn least_memory(building: &Building) -> usize {
        2 * posterior_bytes(building.pilot.len() + 2, building.len())
    }

    /// No observation yet.
    fn empty(kernel: Kernel, vertices: Vec<Point>, max_rows: usize) -> Result<Self> {
        let nv = vertices.len();
        let (r, sigma_diag, logdet_a) = factor_a(&kernel, &vertices)?;
        Ok(IncrementalPosterior {
            kernel,
            vertices,
            pts: Vec::new(),
            extra: Vec::new(),
            rows: Vec::new(),
            decided: 0,
            lw: Vec::new(),
            r,
            sigma_diag,
            logdet_a,
            logdet_sigma: logdet_a,
            n_prior: 0,
            block: 1,
            max_rows,
            scratch_k: Vec::new(),
            scratch_l: Vec::new(),
            scratch_w: vec![0.0; nv],
            scratch_c: vec![0.0; nv],
            scratch_s: vec![0.0; nv],
        })
    }

    /// Number of samples added (pilot locations not counted), in the figures or not yet.
    pub fn samples(&self) -> usize {
        self.pts.len() - self.n_prior
    }

    /// Number of samples the figures account for: all but those of a run not yet
    /// complete (one of every [`Self::block`] of them is conditioned on).
    pub fn samples_in_figures(&self) -> usize {
        self.decided - self.n_prior
    }

    /// 1 while the figures condition on every sample (exact); `k > 1` once the memory
    /// budget made them keep one sample of every `k` (the utility is then a lower bound,
    /// the uncertainty an upper bound, of the samples' own).
    pub fn block(&self) -> usize {
        self.block
    }

    /// At most `max` of the samples (every one if they are that few), as observations:
    /// of every run of `k` consecutive samples on one floor, the one nearest to a vertex,
    /// with `k` the smallest power of two (and at least [`Self::block`]) that keeps at
    /// most `max`. What a replan conditions on ([`REPLAN_PRIOR_MAX`]); returns `k` too.
    pub fn kept_samples(&self, max: usize) -> (usize, Vec<crate::utility::Observation>) {
        let end = self.pts.len();
        let mut block = self.block;
        let mut runs = self.sample_runs(block, end);
        while runs.len() > max.max(1) && block < MAX_BLOCK {
            block *= 2;
            runs = self.sample_runs(block, end);
        }
        let kept = runs
            .iter()
            .map(|&(a, b)| {
                let i = if b - a == 1 {
                    a
                } else {
                    self.nearest_to_a_vertex(a, b)
                };
                crate::utility::Observation {
                    pos: self.pts[i],
                    extra_noise: self.extra[i],
                }
            })
            .collect();
        (block, kept)
    }

    /// Most observations (pilot included) the memory budget allows.
    pub fn max_rows(&self) -> usize {
        self.max_rows
    }

    /// Conditions on one more sample at `p` with noise `sn2 + extra_noise` (once its run
    /// is complete, when samples are kept one of several). On error the sample is not
    /// added.
    pub fn add(&mut self, p: Point, extra_noise: f64) -> Result<()> {
        // A run does not span two floors: a pending run on another floor is complete.
        if self.decided < self.pts.len() && self.pts[self.decided].floor != p.floor {
            self.commit(true)?;
        }
        self.pts.push(p);
        self.extra.push(extra_noise);
        if self.pts.len() - self.decided >= self.block
            && let Err(e) = self.commit(false)
        {
            self.pts.pop();
            self.extra.pop();
            return Err(e);
        }
        Ok(())
    }

    /// Puts the samples of a run not yet complete into the figures (at the end of a
    /// session). On error nothing changes.
    pub fn flush(&mut self) -> Result<()> {
        if self.decided < self.pts.len() {
            self.commit(true)?;
        }
        Ok(())
    }

    /// [`Self::add`] of every sample in turn, to the same rows (resuming a session): many
    /// samples at once are factored in one blocked pass ([`DENSE_FROM`]), which agrees
    /// with adding them one by one to rounding, not bit for bit.
    pub fn add_all(&mut self, samples: &[(Point, f64)]) -> Result<()> {
        if samples.len() < DENSE_FROM {
            return samples.iter().try_for_each(|&(p, x)| self.add(p, x));
        }
        let (pts0, extra0) = (self.pts.len(), self.extra.len());
        for &(p, x) in samples {
            self.pts.push(p);
            self.extra.push(x);
        }
        // The rows `add` would have reached: the first block (from the current one, it
        // only grows) at which the complete runs fit.
        let end = self.pts.len();
        let mut block = self.block;
        let runs = loop {
            let mut runs = self.sample_runs(block, end);
            if runs.last().is_some_and(|r| r.1 - r.0 < block) {
                runs.pop();
            }
            if self.n_prior + runs.len() <= self.max_rows {
                break runs;
            }
            block *= 2;
            if block > MAX_BLOCK {
                self.pts.truncate(pts0);
                self.extra.truncate(extra0);
                return Err(Error::InvalidRequest(format!(
                    "the running posterior cannot account for {} samples in {} rows: raise \
                     the session's memory_budget_mb",
                    end - self.n_prior,
                    self.max_rows
                )));
            }
        };
        let built = self.rebuild(block, &runs);
        if built.is_err() {
            self.pts.truncate(pts0);
            self.extra.truncate(extra0);
        }
        built
    }

    /// Index in `pts[a..b]` of the point nearest to a vertex of its floor (the first of
    /// equals).
    fn nearest_to_a_vertex(&self, a: usize, b: usize) -> usize {
        let near = |p: &Point| {
            self.vertices
                .iter()
                .filter(|v| v.floor == p.floor)
                .map(|v| v.planar_distance(p))
                .fold(f64::INFINITY, f64::min)
        };
        let mut best = (a, f64::INFINITY);
        for i in a..b {
            let d = near(&self.pts[i]);
            if d < best.1 {
                best = (i, d);
            }
        }
        best.0
    }

    /// Decides the pending samples: keeps one (all, while every sample is kept), first
    /// building the posterior again keeping fewer when one more would exceed the budget.
    /// After such a rebuild, a last run shorter than the new length stays pending unless
    /// `tail` (it is complete: the floor changes, or the session ends). On error nothing
    /// changes.
    fn commit(&mut self, tail: bool) -> Result<()> {
        let end = self.pts.len();
        if self.rows.len() < self.max_rows {
            let keep = self.nearest_to_a_vertex(self.decided, end);
            self.add_row(keep)?;
            self.decided = end;
            return Ok(());
        }
        let mut block = self.block;
        loop {
            block *= 2;
            if block > MAX_BLOCK {
                return Err(Error::InvalidRequest(format!(
                    "the running posterior cannot account for {} samples in {} rows: raise \
                     the session's memory_budget_mb",
                    self.samples(),
                    self.max_rows
                )));
            }
            let mut runs = self.sample_runs(block, end);
            if !tail && runs.last().is_some_and(|r| r.1 == end && r.1 - r.0 < block) {
                runs.pop();
            }
            if self.n_prior + runs.len() <= self.max_rows {
                return self.rebuild(block, &runs);
            }
        }
    }

    /// The runs of the samples in `pts[n_prior..end]` with `block` samples each:
    /// consecutive samples on one floor, cut every `block`; the last may be shorter.
    fn sample_runs(&self, block: usize, end: usize) -> Vec<(usize, usize)> {
        let mut runs = Vec::new();
        let mut from = self.n_prior;
        for i in self.n_prior + 1..=end {
            if i == end || i - from == block || self.pts[i].floor != self.pts[from].floor {
                if i > from {
                    runs.push((from, i));
                }
                from = i;
            }
        }
        runs
    }

    /// The posterior again from the vertices' prior: the pilot rows, then one sample of
    /// each of `runs`.
    fn rebuild(&mut self, block: usize, runs: &[(usize, usize)]) -> Result<()> {
        let keep: Vec<usize> = runs
            .iter()
            .map(|&(a, b)| self.nearest_to_a_vertex(a, b))
            .collect();
        let mut fresh = Self::empty(self.kernel, self.vertices.clone(), self.max_rows)?;
        fresh.n_prior = self.n_prior;
        fresh.block = block;
        // Share the positions instead of copying them; put them back whatever happens.
        std::mem::swap(&mut fresh.pts, &mut self.pts);
        std::mem::swap(&mut fresh.extra, &mut self.extra);
        let rows: Vec<usize> = (0..self.n_prior).chain(keep).collect();
        let built = if rows.len() >= DENSE_FROM {
            fresh.build_dense(rows)
        } else {
            rows.into_iter().try_for_each(|i| fresh.add_row(i))
        };
        std::mem::swap(&mut fresh.pts, &mut self.pts);
        std::mem::swap(&mut fresh.extra, &mut self.extra);
        built?;
        fresh.decided = runs.last().map_or(self.n_prior, |r| r.1);
        // Drop the old factors before taking the new ones.
        self.lw = Vec::new();
        fresh.pts = std::mem::take(&mut self.pts);
        fresh.extra = std::mem::take(&mut self.extra);
        *self = fresh;
        Ok(())
    }

    /// Conditions an empty posterior on the observations `pts[rows]` at once: one
    /// blocked factorisation of their joint covariance with the vertices, ordered
    /// `[rows, V]`, whose upper factor `U` holds everything kept: `L` is the transpose of
    /// its leading block, `W` its off-diagonal block (`U_SV = L^-1 K_SV`), `R` its
    /// trailing block (the factor of the Schur complement `Sigma`).
    fn build_dense(&mut self, rows: Vec<usize>) -> Result<()> {
        debug_assert!(self.rows.is_empty());
        let (m, nv) = (rows.len(), self.vertices.len());
        let n = m + nv;
        let layout = Layout::new(n);
        let ld = layout.ld;
        let kern = self.kernel;
        let mut a = vec![0.0; layout.len()];
        for (i, &x) in rows.iter().enumerate() {
            let p = &self.pts[x];
            let row = &mut a[i * ld..i * ld + n];
            for (j, &y) in rows.iter().enumerate().skip(i) {
                row[j] = kern.k(p, &self.pts[y]);
            }
            row[i] += kern.sn2 + self.extra[x];
            for (j, v) in self.vertices.iter().enumerate() {
                row[m + j] = kern.k(p, v);
            }
        }
        for (i, v) in self.vertices.iter().enumerate() {
            let row = &mut a[(m + i) * ld..(m + i) * ld + n];
            for (j, w) in self.vertices.iter().enumerate().skip(i) {
                row[m + j] = kern.k(v, w);
            }
            row[m + i] += kern.sn2;
        }
        let logdet_sigma = dense::factor(Isa::detect(), &mut a, layout, m).ok_or_else(|| {
            Error::Numerical(
                "K_SS + N_S and the posterior covariance of the vertices are not positive \
                 definite"
                    .into(),
            )
        })?;
        let mut lw = Vec::with_capacity(m);
        for i in 0..m {
            let mut row = Vec::with_capacity(i + 1 + nv);
            row.extend((0..=i).map(|j| a[j * ld + i]));
            row.extend_from_slice(&a[i * ld + m..i * ld + n]);
            lw.push(row);
        }
        for i in 0..nv {
            for j in 0..nv {
                self.r[i * nv + j] = if j >= i { a[(m + i) * ld + m + j] } else { 0.0 };
            }
        }
        drop(a);
        // Sigma_jj = sum_i R_ij^2.
        for j in 0..nv {
            self.sigma_diag[j] = (0..=j).map(|i| self.r[i * nv + j].powi(2)).sum();
        }
        self.logdet_sigma = logdet_sigma;
        self.lw = lw;
        self.rows = rows;
        Ok(())
    }

    /// Conditions on the observation `pts[x]` (one more row). On error nothing changes.
    fn add_row(&mut self, x: usize) -> Result<()> {
        let nv = self.vertices.len();
        let n = self.rows.len();
        let kern = self.kernel;
        let p = self.pts[x];
        // k_Sx and l = L^-1 k_Sx.
        self.scratch_k.clear();
        self.scratch_k
            .extend(self.rows.iter().map(|&i| kern.k(&self.pts[i], &p)));
        self.scratch_l.clear();
        self.scratch_l.resize(n, 0.0);
        for i in 0..n {
            let row = &self.lw[i][..=i];
            let s = dot(&row[..i], &self.scratch_l[..i]);
            self.scratch_l[i] = (self.scratch_k[i] - s) / row[i];
        }
        let d2 = kern.sf2 + kern.sn2 + self.extra[x] - dot(&self.scratch_l, &self.scratch_l);
        if !(d2.is_finite() && d2 > 0.0) {
            return Err(Error::Numerical(format!(
                "K_SS + N_S lost positive definiteness at observation {} ({:.3}, {:.3}, floor {})",
                x + 1,
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
                axpy(-lj, &self.lw[j][j + 1..], w);
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
        let mut row = Vec::with_capacity(n + 1 + nv);
        row.extend_from_slice(&self.scratch_l);
        row.push(d);
        row.extend_from_slice(w);
        self.lw.push(row);
        self.rows.push(x);
        Ok(())
    }

    /// `f_D` of the pilot data plus the samples in the figures, nats (SPEC section 3; a
    /// lower bound of the samples' own once [`Self::block`] is above 1).
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
        8 * (self.lw.iter().map(Vec::capacity).sum::<usize>() + self.r.capacity())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    fn demo() -> (Building, Kernel) {
        // The shipped demo building (`synth::DEMO_BUILDING_JSON`, a `research` module:
        // these tests run in the phone's configuration too).
        let json = include_str!("../../data/demo-building.json");
        let b = Building::from_json(json, "demo").expect("demo");
        let k = crate::gp::fit_kernel(&b.pilot).expect("fit").kernel;
        (b, k)
    }

    /// A robot's samples every 0.5 m along the demo building's edges, one after another
    /// (edges in file order, each from its first vertex), with a little label noise on
    /// every third.
    fn robot_samples(b: &Building, n: usize) -> Vec<(Point, f64)> {
        let mut out = Vec::new();
        for e in b.edges.iter().cycle() {
            let (pa, pb) = (b.vertices[e.a].pos, b.vertices[e.b].pos);
            let mut s = 0.0;
            while s < e.length {
                let t = s / e.length;
                let floor = if t <= 0.5 { pa.floor } else { pb.floor };
                let p = Point::new(pa.x + t * (pb.x - pa.x), pa.y + t * (pb.y - pa.y), floor);
                out.push((p, if out.len() % 3 == 0 { 0.7 } else { 0.0 }));
                if out.len() == n {
                    return out;
                }
                s += 0.5;
            }
        }
        out
    }

    /// `(utility, vertex variances)` of conditioning on the observations `obs[rows]`, by
    /// one dense solve: the definition, not the recurrences.
    fn from_scratch(
        b: &Building,
        k: &Kernel,
        obs: &[(Point, f64)],
        rows: &[usize],
    ) -> (f64, Vec<f64>) {
        let v = b.vertex_points();
        let (nv, m) = (v.len(), rows.len());
        let c = DMatrix::from_fn(m, m, |i, j| {
            let (p, x) = obs[rows[i]];
            k.k(&p, &obs[rows[j]].0) + if i == j { k.sn2 + x } else { 0.0 }
        });
        let kv = DMatrix::from_fn(m, nv, |i, j| k.k(&obs[rows[i]].0, &v[j]));
        let a = DMatrix::from_fn(nv, nv, |i, j| {
            k.k(&v[i], &v[j]) + if i == j { k.sn2 } else { 0.0 }
        });
        let cc = c.cholesky().expect("observations positive definite");
        let sigma = &a - kv.transpose() * cc.solve(&kv);
        let ld = |m: DMatrix<f64>| {
            2.0 * m
                .cholesky()
                .expect("positive definite")
                .l()
                .diagonal()
                .iter()
                .map(|d| d.ln())
                .sum::<f64>()
        };
        let var = (0..nv).map(|i| (sigma[(i, i)] - k.sn2).max(0.0)).collect();
        (0.5 * (ld(a) - ld(sigma)), var)
    }

    /// The pilot locations then `samples`, as observations with their extra noise.
    fn observations(b: &Building, samples: &[(Point, f64)]) -> Vec<(Point, f64)> {
        let mut obs: Vec<(Point, f64)> = b.pilot_points().into_iter().map(|p| (p, 0.0)).collect();
        obs.extend(samples);
        obs
    }

    #[test]
    fn past_its_budget_the_posterior_keeps_one_sample_of_each_run_and_bounds_the_samples_own() {
        let (b, k) = demo();
        let samples = robot_samples(&b, 600);
        let np = b.pilot.len();
        let budget = posterior_bytes(np + 160, b.len());
        let mut post = IncrementalPosterior::new(&b, k, 2 * budget).expect("fits");
        let mut exact = IncrementalPosterior::new(&b, k, usize::MAX).expect("unbounded");
        assert_eq!(post.max_rows(), np + 160);
        for &(p, x) in &samples {
            post.add(p, x).expect("add");
            exact.add(p, x).expect("add");
            assert!(post.rows.len() <= post.max_rows());
            assert!(
                post.memory_bytes() <= budget,
                "{} > {budget}",
                post.memory_bytes()
            );
        }
        assert_eq!((exact.block(), exact.samples_in_figures()), (1, 600));
        // What a replan conditions on: all 600, or one of every 8 to keep at most 100.
        assert_eq!(exact.kept_samples(1000).1.len(), 600);
        let (k8, kept) = exact.kept_samples(100);
        assert_eq!((k8, kept.len()), (8, 75));
        // 600 samples in at most 160 rows: one of every 4 (all on one floor).
        assert_eq!(post.block(), 4);
        assert_eq!(post.samples_in_figures(), 600);
        let obs = observations(&b, &samples);
        // Of each run of 4, the sample nearest to a vertex.
        let dist = |i: usize| {
            let p = obs[i].0;
            b.vertex_points()
                .iter()
                .filter(|v| v.floor == p.floor)
                .map(|v| v.planar_distance(&p))
                .fold(f64::INFINITY, f64::min)
        };
        assert_eq!(post.rows.len(), np + 150);
        for (run, &kept) in post.rows[np..].iter().enumerate() {
            let from = np + 4 * run;
            assert!((from..from + 4).contains(&kept), "run {run} kept {kept}");
            assert!((from..from + 4).all(|i| dist(kept) <= dist(i)));
        }
        for p in [&post, &exact] {
            let (u, var) = from_scratch(&b, &k, &obs, &p.rows);
            assert!((p.utility() - u).abs() < 1e-9 * u, "{} vs {u}", p.utility());
            for (a, w) in p.vertex_variance().iter().zip(&var) {
                assert!((a - w).abs() < 1e-7 * (1.0 + w), "{a} vs {w}");
            }
        }
        // The samples kept tell at most what all do, and most of it.
        assert!(post.utility() < exact.utility());
        assert!(
            post.utility() > 0.9 * exact.utility(),
            "{} of {}",
            post.utility(),
            exact.utility()
        );
        for (a, e) in post.vertex_variance().iter().zip(exact.vertex_variance()) {
            assert!(*a >= e - 1e-9 * (1.0 + e), "{a} < {e}");
        }
        // Why the nearest to a vertex: keeping the first of each run tells much less.
        let first: Vec<usize> = (0..np).chain((np..obs.len()).step_by(4)).collect();
        let (u_first, _) = from_scratch(&b, &k, &obs, &first);
        eprintln!(
            "600 samples: all {:.2} nats; one of 4, nearest a vertex {:.2}, first {u_first:.2}",
            exact.utility(),
            post.utility()
        );
        assert!(post.utility() > u_first + 0.1 * exact.utility());
    }

    #[test]
    fn a_run_not_yet_complete_joins_the_figures_at_the_end() {
        let (b, k) = demo();
        let samples = robot_samples(&b, 250);
        let np = b.pilot.len();
        let mut post =
            IncrementalPosterior::new(&b, k, 2 * posterior_bytes(np + 100, b.len())).expect("fits");
        for &(p, x) in &samples {
            post.add(p, x).expect("add");
        }
        // 250 samples in 100 rows: one of every 4; the last 2 wait for their run.
        assert_eq!((post.block(), post.samples_in_figures()), (4, 248));
        let before = post.utility();
        post.flush().expect("flush");
        assert_eq!(post.samples_in_figures(), 250);
        assert!(post.utility() > before);
        let (u, _) = from_scratch(&b, &k, &observations(&b, &samples), &post.rows);
        assert!((post.utility() - u).abs() < 1e-9 * u);
    }

    /// Resuming: many samples at once, by one blocked factorisation, reach the rows and
    /// the figures of adding them one by one.
    #[test]
    fn adding_all_samples_at_once_agrees_with_adding_them_one_by_one() {
        let (b, k) = demo();
        let samples = robot_samples(&b, 1500);
        let np = b.pilot.len();
        let rows_800 =
            dense_build_bytes(np + 800, b.len()).max(2 * posterior_bytes(np + 800, b.len()));
        for budget in [usize::MAX, rows_800] {
            let mut one = IncrementalPosterior::new(&b, k, budget).expect("fits");
            for &(p, x) in &samples {
                one.add(p, x).expect("add");
            }
            let mut all = IncrementalPosterior::new(&b, k, budget).expect("fits");
            assert!(budget == usize::MAX || all.max_rows() == np + 800);
            all.add_all(&samples).expect("add all");
            // Blocked (more than DENSE_FROM rows): every sample, then one of every 2.
            assert!(all.rows.len() >= DENSE_FROM);
            assert_eq!(all.block(), if budget == usize::MAX { 1 } else { 2 });
            assert_eq!(all.rows, one.rows);
            assert_eq!(
                (all.block(), all.samples_in_figures(), all.samples()),
                (one.block(), one.samples_in_figures(), one.samples())
            );
            let (u1, ua) = (one.utility(), all.utility());
            assert!((u1 - ua).abs() < 1e-9 * u1, "{u1} vs {ua}");
            for (x, y) in one.vertex_variance().iter().zip(all.vertex_variance()) {
                assert!((x - y).abs() < 1e-7 * (1.0 + x), "{x} vs {y}");
            }
            // Both go on the same way.
            for &(p, x) in &robot_samples(&b, 1530)[1500..] {
                one.add(p, x).expect("add");
                all.add(p, x).expect("add");
            }
            assert_eq!(all.rows, one.rows);
            assert!((one.utility() - all.utility()).abs() < 1e-9 * one.utility());
        }
    }

    /// Runs end where the floor changes (a sample on another floor tells nothing about
    /// this one's vertices, and keeping one sample for both floors would drop one).
    #[test]
    fn runs_of_samples_end_where_the_floor_changes() {
        let (b, k) = demo();
        // Seven samples on the ground floor, then seven on a floor above (no vertices
        // there), and so on.
        let samples: Vec<(Point, f64)> = robot_samples(&b, 280)
            .into_iter()
            .enumerate()
            .map(|(i, (p, x))| (Point::new(p.x, p.y, ((i / 7) % 2) as i64), x))
            .collect();
        let np = b.pilot.len();
        let mut post =
            IncrementalPosterior::new(&b, k, 2 * posterior_bytes(np + 100, b.len())).expect("fits");
        for &(p, x) in &samples {
            post.add(p, x).expect("add");
        }
        // 280 samples in runs of 4 cut at every 7: 40 blocks of 7, each runs of 4 and 3;
        // the last run waits for the end.
        assert_eq!(post.block(), 4);
        assert_eq!((post.rows.len(), post.samples_in_figures()), (np + 79, 277));
        post.flush().expect("flush");
        assert_eq!(post.rows.len(), np + 80);
        for (i, &kept) in post.rows[np..].iter().enumerate() {
            let seg = np + 7 * (i / 2);
            let run = if i % 2 == 0 {
                seg..seg + 4
            } else {
                seg + 4..seg + 7
            };
            assert!(run.contains(&kept), "row {i}: {kept} not in {run:?}");
        }
        let (u, _) = from_scratch(&b, &k, &observations(&b, &samples), &post.rows);
        assert!(
            (post.utility() - u).abs() < 1e-9 * u,
            "{} vs {u}",
            post.utility()
        );
    }

    #[test]
    fn a_budget_too_small_for_the_vertices_is_refused_with_the_size_needed() {
        let (b, k) = demo();
        let e = IncrementalPosterior::new(&b, k, 20_000).expect_err("too small");
        let need = posterior_bytes(b.pilot.len() + 2, b.len()).div_ceil(1 << 20);
        assert!(
            e.to_string()
                .contains(&format!("needs at least {need} MiB")),
            "{e}"
        );
        assert!(e.to_string().contains("memory_budget_mb"), "{e}");
    }
}
