//! The fast utility engine used by the planners.
//!
//! # What it computes
//! The same `f_D(P)` as [`reference_utility`](super::reference_utility), in the "V side"
//! form of SPEC section 3:
//!
//! `f = 1/2 ln det A - 1/2 ln det(A - W^T W)`, with `A = K_VV + sn2 I`,
//! `W = L^-1 K_SV` and `L L^T = K_SS + N_S` (S = pilot locations, then the walk's samples).
//!
//! # Why it is fast
//! * The pilot locations come first in `S`, so their rows of `L` and `W`, and
//!   `Sigma_D = A - W_D^T W_D`, are computed once per building ([`UtilityEngine::new`]).
//! * A walk's samples are appended one row at a time ([`Factor`]): a row of `L` costs
//!   one forward substitution against the rows before it, a row of `W` one pass over
//!   the earlier rows of `W`, and `Sigma` a rank-one downdate. A walk that extends
//!   another starts from the other's factor ([`WalkState::mark`] / [`WalkState::rewind`],
//!   or `Clone`), so extending by one edge costs only that edge's samples.
//! * Only `Sigma` (vertices x vertices, 61 x 61 on area-two) is factorised per
//!   evaluation; the big `|S| x |S|` factor is never refactorised.
//! * The inner loops are SIMD kernels dispatched at run time ([`super::simd`]).
//! * Many walks are evaluated in parallel with rayon ([`UtilityEngine::utilities`]).

use std::sync::Arc;

use rayon::prelude::*;

use super::reference::Observation;
use super::simd::{self, Isa, Points};
use crate::building::Building;
use crate::gp::{Kernel, Point};
use crate::samples::{Sample, SurveyorModel, WalkSampler};
use crate::{Error, Result};

/// Constants of one engine that the numeric kernels need.
#[derive(Debug, Clone)]
struct Ctx {
    sf2: f64,
    inv_ell: f64,
    sn2: f64,
    vertices: Points,
    nv: usize,
}

/// A growing factorisation: rows of `L` and `W` for the observations so far, and
/// `Sigma = A - W^T W` (lower triangle, row-major `nv x nv`).
#[derive(Debug, Clone)]
pub struct Factor {
    pts: Points,
    /// Packed lower-triangular rows: row `i` starts at `i (i + 1) / 2`, has `i + 1` entries.
    l: Vec<f64>,
    inv_diag: Vec<f64>,
    /// Row-major, `n x nv`.
    w: Vec<f64>,
    sigma: Vec<f64>,
}

impl Factor {
    /// Number of observations in the factor.
    pub fn len(&self) -> usize {
        self.pts.len()
    }

    /// Whether the factor holds no observation.
    pub fn is_empty(&self) -> bool {
        self.pts.is_empty()
    }

    fn truncate(&mut self, n: usize, nv: usize) {
        self.pts.truncate(n);
        self.l.truncate(n * (n + 1) / 2);
        self.inv_diag.truncate(n);
        self.w.truncate(n * nv);
    }
}

/// Appends one observation's rows of `L` and `W` (not `Sigma`). Returns `false` if the
/// new diagonal is not positive.
#[inline(always)]
fn push_rows<const FMA: bool>(f: &mut Factor, ctx: &Ctx, p: &Point, noise: f64) -> bool {
    let n = f.pts.len();
    let off = n * (n + 1) / 2;
    f.l.resize(off + n + 1, 0.0);
    let (prev, row) = f.l.split_at_mut(off);
    let pf = (p.x, p.y, p.floor as f64);
    simd::kernel_row::<FMA>(ctx.sf2, ctx.inv_ell, pf, &f.pts, &mut row[..n]);
    for j in 0..n {
        let oj = j * (j + 1) / 2;
        let s = row[j] - simd::dot::<FMA>(&prev[oj..oj + j], &row[..j]);
        row[j] = s * f.inv_diag[j];
    }
    let d2 = ctx.sf2 + ctx.sn2 + noise - simd::dot::<FMA>(&row[..n], &row[..n]);
    if d2.is_nan() || d2 <= 0.0 || !d2.is_finite() {
        f.l.truncate(off);
        return false;
    }
    let diag = d2.sqrt();
    row[n] = diag;
    let nv = ctx.nv;
    let woff = n * nv;
    f.w.resize(woff + nv, 0.0);
    let (wprev, wrow) = f.w.split_at_mut(woff);
    simd::kernel_row::<FMA>(ctx.sf2, ctx.inv_ell, pf, &ctx.vertices, wrow);
    for j in 0..n {
        simd::axpy::<FMA>(-row[j], &wprev[j * nv..(j + 1) * nv], wrow);
    }
    let inv = 1.0 / diag;
    for x in wrow.iter_mut() {
        *x *= inv;
    }
    f.inv_diag.push(inv);
    f.pts.push(p);
    true
}

/// `sigma -= w w^T` on the lower triangle.
#[inline(always)]
fn rank1_lower<const FMA: bool>(sigma: &mut [f64], w: &[f64], nv: usize) {
    for a in 0..nv {
        simd::axpy::<FMA>(-w[a], &w[..=a], &mut sigma[a * nv..a * nv + a + 1]);
    }
}

/// In-place Cholesky of the lower triangle of a row-major `n x n` matrix; returns
/// `ln det`, or `None` if the matrix is not positive definite.
#[inline(always)]
fn chol_logdet<const FMA: bool>(a: &mut [f64], n: usize) -> Option<f64> {
    let mut logdet = 0.0;
    for i in 0..n {
        let (done, rest) = a.split_at_mut(i * n);
        let row = &mut rest[..n];
        for j in 0..i {
            let rj = &done[j * n..j * n + n];
            let s = row[j] - simd::dot::<FMA>(&rj[..j], &row[..j]);
            row[j] = s / rj[j];
        }
        let d2 = row[i] - simd::dot::<FMA>(&row[..i], &row[..i]);
        if d2.is_nan() || d2 <= 0.0 || !d2.is_finite() {
            return None;
        }
        let d = d2.sqrt();
        row[i] = d;
        logdet += d2.ln();
    }
    Some(logdet)
}

/// Adds observations to a factor, downdating its `Sigma`.
#[inline(always)]
fn add_all<const FMA: bool>(f: &mut Factor, ctx: &Ctx, obs: &[(Point, f64)]) -> bool {
    for (p, noise) in obs {
        if !push_rows::<FMA>(f, ctx, p, *noise) {
            return false;
        }
        let n = f.pts.len();
        let nv = ctx.nv;
        let (w, sigma) = (&f.w[(n - 1) * nv..n * nv], &mut f.sigma);
        rank1_lower::<FMA>(sigma, w, nv);
    }
    true
}

/// `ln det Sigma`, with an optional extra observation applied to a copy only.
#[inline(always)]
fn logdet_sigma<const FMA: bool>(
    f: &mut Factor,
    ctx: &Ctx,
    extra: Option<(Point, f64)>,
    scratch: &mut Vec<f64>,
) -> Option<f64> {
    let nv = ctx.nv;
    scratch.clear();
    scratch.extend_from_slice(&f.sigma);
    if let Some((p, noise)) = extra {
        if !push_rows::<FMA>(f, ctx, &p, noise) {
            return None;
        }
        let n = f.pts.len();
        rank1_lower::<FMA>(scratch, &f.w[(n - 1) * nv..n * nv], nv);
        f.truncate(n - 1, nv);
    }
    chol_logdet::<FMA>(scratch, nv)
}

/// Arguments of the dispatched operations (one signature keeps the macro simple).
enum DispatchArg<'a> {
    Add(&'a [(Point, f64)]),
    LogDet(Option<(Point, f64)>, &'a mut Vec<f64>),
}

enum DispatchOut {
    Added(bool),
    LogDet(Option<f64>),
}

#[inline(always)]
fn run_op<const FMA: bool>(f: &mut Factor, ctx: &Ctx, a: DispatchArg<'_>) -> DispatchOut {
    match a {
        DispatchArg::Add(obs) => DispatchOut::Added(add_all::<FMA>(f, ctx, obs)),
        DispatchArg::LogDet(extra, scratch) => {
            DispatchOut::LogDet(logdet_sigma::<FMA>(f, ctx, extra, scratch))
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,fma")]
fn run_op_avx512(f: &mut Factor, ctx: &Ctx, a: DispatchArg<'_>) -> DispatchOut {
    run_op::<true>(f, ctx, a)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn run_op_avx2(f: &mut Factor, ctx: &Ctx, a: DispatchArg<'_>) -> DispatchOut {
    run_op::<true>(f, ctx, a)
}

/// Runs an operation with the kernels compiled for `isa`.
fn dispatch(isa: Isa, f: &mut Factor, ctx: &Ctx, a: DispatchArg<'_>) -> DispatchOut {
    match isa {
        // SAFETY: `Isa::detect` returns these variants only when the CPU has the features.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 => unsafe { run_op_avx512(f, ctx, a) },
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2Fma => unsafe { run_op_avx2(f, ctx, a) },
        _ => run_op::<false>(f, ctx, a),
    }
}

/// The fast evaluator for one building, kernel, surveyor model and set of prior
/// observations (the pilot data, plus anything already collected).
#[derive(Debug, Clone)]
pub struct UtilityEngine {
    building: Arc<Building>,
    kernel: Kernel,
    model: SurveyorModel,
    ctx: Ctx,
    isa: Isa,
    logdet_a: f64,
    base: Factor,
}

impl UtilityEngine {
    /// Conditions on the building's pilot locations.
    pub fn new(building: Arc<Building>, kernel: Kernel, model: SurveyorModel) -> Result<Self> {
        Self::with_prior(building, kernel, model, &[])
    }

    /// Conditions on the pilot locations plus `prior` (for example samples already
    /// collected, or other surveyors' walks).
    pub fn with_prior(
        building: Arc<Building>,
        kernel: Kernel,
        model: SurveyorModel,
        prior: &[Observation],
    ) -> Result<Self> {
        kernel.validate("kernel")?;
        model.validate()?;
        let mut vertices = Points::default();
        for v in &building.vertices {
            vertices.push(&v.pos);
        }
        let nv = vertices.len();
        let ctx = Ctx {
            sf2: kernel.sf2,
            inv_ell: 1.0 / kernel.ell,
            sn2: kernel.sn2,
            vertices,
            nv,
        };
        let isa = Isa::detect();
        // A = K_VV + sn2 I (lower triangle is what the kernels read).
        let vpts = building.vertex_points();
        let mut a = vec![0.0; nv * nv];
        for i in 0..nv {
            for j in 0..=i {
                a[i * nv + j] =
                    kernel.k(&vpts[i], &vpts[j]) + if i == j { kernel.sn2 } else { 0.0 };
            }
        }
        let mut base = Factor {
            pts: Points::default(),
            l: Vec::new(),
            inv_diag: Vec::new(),
            w: Vec::new(),
            sigma: a.clone(),
        };
        let mut scratch = Vec::new();
        let logdet_a = match dispatch(
            isa,
            &mut base,
            &ctx,
            DispatchArg::LogDet(None, &mut scratch),
        ) {
            DispatchOut::LogDet(Some(v)) => v,
            _ => {
                return Err(Error::Numerical(
                    "K_VV + sn2 I is not positive definite".into(),
                ));
            }
        };
        let mut obs: Vec<(Point, f64)> = building.pilot.iter().map(|f| (f.point(), 0.0)).collect();
        obs.extend(prior.iter().map(|o| (o.pos, o.extra_noise)));
        let mut engine = UtilityEngine {
            building,
            kernel,
            model,
            ctx,
            isa,
            logdet_a,
            base,
        };
        let mut base = std::mem::replace(
            &mut engine.base,
            Factor {
                pts: Points::default(),
                l: Vec::new(),
                inv_diag: Vec::new(),
                w: Vec::new(),
                sigma: Vec::new(),
            },
        );
        engine.add(&mut base, &obs)?;
        engine.base = base;
        Ok(engine)
    }

    fn add(&self, f: &mut Factor, obs: &[(Point, f64)]) -> Result<()> {
        match dispatch(self.isa, f, &self.ctx, DispatchArg::Add(obs)) {
            DispatchOut::Added(true) => Ok(()),
            _ => Err(Error::Numerical(
                "K_SS + N_S lost positive definiteness".into(),
            )),
        }
    }

    fn utility_of(
        &self,
        f: &mut Factor,
        extra: Option<(Point, f64)>,
        scratch: &mut Vec<f64>,
    ) -> Result<f64> {
        match dispatch(self.isa, f, &self.ctx, DispatchArg::LogDet(extra, scratch)) {
            DispatchOut::LogDet(Some(ld)) => Ok((0.5 * (self.logdet_a - ld)).max(0.0)),
            _ => Err(Error::Numerical(
                "posterior covariance is not positive definite".into(),
            )),
        }
    }

    /// The building.
    pub fn building(&self) -> &Arc<Building> {
        &self.building
    }

    /// The kernel.
    pub fn kernel(&self) -> &Kernel {
        &self.kernel
    }

    /// The surveyor model.
    pub fn model(&self) -> &SurveyorModel {
        &self.model
    }

    /// The instruction set the numeric kernels run on.
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// `f_D` of the prior observations alone (no walk).
    pub fn prior_utility(&self) -> Result<f64> {
        let mut f = self.base.clone();
        self.utility_of(&mut f, None, &mut Vec::new())
    }

    /// A walk that starts at `start` (its first sample is there).
    pub fn start(&self, start: usize) -> Result<WalkState<'_>> {
        if start >= self.building.len() {
            return Err(Error::InvalidWalk {
                step: 0,
                message: format!("vertex index {start} out of range"),
            });
        }
        Ok(WalkState {
            engine: self,
            sampler: WalkSampler::new(&self.building, start, self.model, self.kernel),
            factor: self.base.clone(),
            buf: Vec::new(),
            samples: 0,
        })
    }

    /// `f_D(P)` of a walk of vertex indices.
    pub fn utility(&self, walk: &[usize]) -> Result<f64> {
        let Some(&s) = walk.first() else {
            return Err(Error::InvalidWalk {
                step: 0,
                message: "the walk is empty".into(),
            });
        };
        let mut st = self.start(s)?;
        for &v in &walk[1..] {
            st.push(v)?;
        }
        st.utility()
    }

    /// `f_D` of many walks, in parallel.
    pub fn utilities(&self, walks: &[Vec<usize>]) -> Vec<Result<f64>> {
        walks.par_iter().map(|w| self.utility(w)).collect()
    }

    /// `f_D` of the prior plus arbitrary observations (for example samples actually
    /// collected, with their real label noise).
    pub fn utility_of_observations(&self, obs: &[Observation]) -> Result<f64> {
        let mut f = self.base.clone();
        let list: Vec<(Point, f64)> = obs.iter().map(|o| (o.pos, o.extra_noise)).collect();
        self.add(&mut f, &list)?;
        self.utility_of(&mut f, None, &mut Vec::new())
    }
}

/// A saved point of a [`WalkState`] to come back to.
#[derive(Debug, Clone)]
pub struct Mark {
    n: usize,
    sigma: Vec<f64>,
    sampler: WalkSampler,
    samples: usize,
}

/// A walk being built vertex by vertex, with its factorisation kept up to date.
#[derive(Debug, Clone)]
pub struct WalkState<'e> {
    engine: &'e UtilityEngine,
    sampler: WalkSampler,
    factor: Factor,
    buf: Vec<Sample>,
    samples: usize,
}

impl<'e> WalkState<'e> {
    /// Extends the walk to the neighbour `v`.
    pub fn push(&mut self, v: usize) -> Result<()> {
        self.buf.clear();
        self.sampler.push(&self.engine.building, v, &mut self.buf)?;
        let obs: Vec<(Point, f64)> = self.buf.iter().map(|s| (s.pos, s.extra_noise)).collect();
        self.samples += obs.len();
        self.engine.add(&mut self.factor, &obs)
    }

    /// `f_D` of the walk so far, in nats.
    pub fn utility(&mut self) -> Result<f64> {
        let extra = self.sampler.pending_final().map(|s| (s.pos, s.extra_noise));
        let mut scratch = Vec::with_capacity(self.factor.sigma.len());
        self.engine
            .utility_of(&mut self.factor, extra, &mut scratch)
    }

    /// The vertices so far.
    pub fn walk(&self) -> &[usize] {
        self.sampler.walk()
    }

    /// The vertex the walk ends at.
    pub fn last(&self) -> usize {
        *self.sampler.walk().last().unwrap_or(&0)
    }

    /// `C(P)` so far, metres.
    pub fn length(&self) -> f64 {
        self.sampler.length()
    }

    /// Number of samples of the walk so far (including one at the end vertex).
    pub fn samples(&self) -> usize {
        self.samples + usize::from(self.sampler.pending().is_some())
    }

    /// Saves the current state; [`rewind`](Self::rewind) returns to it cheaply.
    pub fn mark(&self) -> Mark {
        Mark {
            n: self.factor.len(),
            sigma: self.factor.sigma.clone(),
            sampler: self.sampler.clone(),
            samples: self.samples,
        }
    }

    /// Returns to a state saved by [`mark`](Self::mark) on this walk (it must be an
    /// ancestor of the current state).
    pub fn rewind(&mut self, mark: &Mark) {
        self.factor.truncate(mark.n, self.engine.ctx.nv);
        self.factor.sigma.clone_from(&mark.sigma);
        self.sampler = mark.sampler.clone();
        self.samples = mark.samples;
    }

    /// The engine this walk belongs to.
    pub fn engine(&self) -> &'e UtilityEngine {
        self.engine
    }
}
