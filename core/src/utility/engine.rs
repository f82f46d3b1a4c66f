//! The fast utility engine used by the planners.
//!
//! # What it computes
//! The same `f_D(P)` as [`reference_utility`](super::reference_utility), in the "V side"
//! form of SPEC section 3:
//!
//! `f = 1/2 ln det A - 1/2 ln det(A - W^T W)`, with `A = K_VV + sn2 I`,
//! `W = L^-1 K_SV` and `L L^T = K_SS + N_S` (S = pilot locations, then the walk's samples).
//!
//! # Two paths
//! * A whole walk evaluated from scratch ([`UtilityEngine::utility`],
//!   [`UtilityEngine::utilities`], [`UtilityEngine::utility_of_observations`]) takes the
//!   dense path of [`super::dense`]: one factorisation of the joint covariance of
//!   `[prior, samples, vertices]`, whose last rows give `ln det Sigma`. It runs at about
//!   90% of the FMA peak of an AVX-512 core and is the genetic planner's workhorse.
//! * A walk grown vertex by vertex ([`WalkState`]) keeps a factor that later steps
//!   extend, as below; the greedy planners and branch and bound use it.
//!
//! # Why the incremental path is fast
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

#[path = "near.rs"]
mod near;
pub use near::{BASE_MAX as NEAR_BASE_MAX, NearBase};

use super::blocked;
use super::dense;
use super::reference::Observation;
use super::simd::{self, Isa, Points};
use crate::building::Building;
use crate::gp::{Kernel, Point};
use crate::samples::{Sample, Surveyor, WalkSampler};
use crate::{Error, Result};

/// Constants of one engine that the numeric kernels need.
#[derive(Debug, Clone)]
struct Ctx {
    sf2: f64,
    inv_ell: f64,
    sn2: f64,
    vertices: Points,
    nv: usize,
    isa: Isa,
}

impl Ctx {
    /// Kernel values between `p` and points `from..` of `q`, into `out` (see
    /// [`simd::kernel_row_isa`]).
    #[inline(always)]
    fn kernel_row<const FMA: bool>(
        &self,
        p: (f64, f64, f64),
        q: &Points,
        from: usize,
        out: &mut [f64],
    ) {
        simd::kernel_row_isa::<FMA>(self.isa, self.sf2, self.inv_ell, p, q, from, out);
    }
}

/// What the dense whole-walk path ([`super::dense`]) copies instead of recomputing: the
/// prior observations' kernel blocks and `A`, all raw (not factored).
#[derive(Debug, Clone)]
struct Prior {
    pts: Points,
    /// `K_DD + N_D`, row-major `nd x nd` (upper triangle used).
    dd: Vec<f64>,
    /// `K_DV`, row-major `nd x nv`.
    dv: Vec<f64>,
    /// `A = K_VV + sn2 I`, row-major `nv x nv` (upper triangle used), on parts of at
    /// most [`DENSE_A_FROM`] vertices; empty on larger ones, which keep only `a_tail`
    /// and compute other entries again when asked ([`Prior::a_row`]).
    a: Vec<f64>,
    /// On parts beyond [`DENSE_A_FROM`] vertices: `A`'s columns `known..nv` of every row,
    /// row-major `nv x (nv - known)`: all the S-side form reads of `A`.
    a_tail: Vec<f64>,
    /// The kernel and the part's vertices, to compute `A`'s entries that are not kept.
    kernel: Kernel,
    vpts: Vec<Point>,
    /// The same vertices in structure-of-arrays form, and the instruction set, for
    /// [`a_entries_large`].
    vsoa: Points,
    isa: Isa,
    /// The upper Cholesky factor of `A` (`U^T U = A`), row-major `nv x nv`: the leading
    /// block of the joint factor in the "S side" form (see [`dense_gain`]).
    ua: Vec<f64>,
    /// Row stride of `ua`.
    ua_ld: usize,
    /// Rows of `ua` the S-side form reuses: `nv` rounded down to [`dense::KNOWN_STEP`].
    known: usize,
    /// `ln det A`.
    logdet_a: f64,
}

/// Largest dense matrix (in doubles) a thread keeps between evaluations: 32 MiB, about
/// 2,000 rows. Bigger problems (buildings of thousands of vertices) allocate per
/// evaluation, where the allocation is small beside the factorisation, so that a phone
/// does not hold that much memory per planning thread once planning is over.
const DENSE_KEEP_MAX: usize = 4 << 20;

thread_local! {
    /// The dense path's matrix, kept per thread: allocating (and page-faulting) a fresh
    /// megabyte per evaluation would cost a sizeable share of the evaluation itself.
    static DENSE: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
    /// Largest matrix (doubles) this thread keeps in [`DENSE`]: [`DENSE_KEEP_MAX`], or
    /// any size while a [`KeepScratch`] of the thread is alive.
    static KEEP: std::cell::Cell<usize> = const { std::cell::Cell::new(DENSE_KEEP_MAX) };
}

/// Keeps the dense matrix of the calling thread's exact evaluations between them, however
/// large, until it is dropped (then a matrix beyond [`DENSE_KEEP_MAX`] is freed): for a
/// plan on a building of thousands of vertices, whose few evaluations on that thread
/// (the timing of two prefixes, the final walk's) would each allocate and page-fault a
/// fresh matrix of a hundred megabytes. Measured on the generated 3,161-vertex floor,
/// person 3,116 m, one core: 261 ms per evaluation without, 202 ms with (a fifth of
/// each). The matrix is one the evaluation allocates anyway, so the plan's peak memory
/// is what it was; it is only held between evaluations, and never after the plan.
#[must_use = "the matrix is kept only while the guard is alive"]
pub struct KeepScratch {
    before: usize,
}

impl KeepScratch {
    pub fn new() -> KeepScratch {
        KeepScratch {
            before: KEEP.replace(usize::MAX),
        }
    }
}

impl Default for KeepScratch {
    fn default() -> Self {
        Self::new()
    }
}

impl Drop for KeepScratch {
    fn drop(&mut self) {
        KEEP.set(self.before);
        DENSE.with_borrow_mut(|a| {
            if a.capacity() > self.before {
                *a = Vec::new();
            }
        });
    }
}

/// Puts `a` back as the thread's dense matrix when the thread keeps one of its size.
fn keep_dense(a: Vec<f64>) {
    if a.capacity() <= KEEP.get() {
        DENSE.set(a);
    }
}

/// Twice the utility, `ln det A - ln det Sigma`, of the prior plus `obs`, by dense
/// factorisation ([`super::dense`]), in whichever of SPEC 3's two equivalent forms costs
/// less:
/// * **V side** (`|V| <= |S|`): one factorisation of the joint covariance ordered
///   `[D, obs, V]`, whose last rows give `ln det Sigma`: `N^3 / 6` multiply-adds for
///   `N = |S| + |V|`.
/// * **S side** (`|V|` well above `|S|`, e.g. a person's walk on a building of thousands of
///   vertices): `ln det (K_SS + N_S) - ln det (K_SS + N_S - K_SV A^-1 K_VS)`, the second
///   from the joint covariance ordered `[V, D, obs]`, whose leading block is `A` and
///   whose factor is the engine's (`Prior::ua`) for every walk, so only the rest is
///   computed. That saves `|V|^3 / 6` and costs `|S|^3 / 6` more: on 3,161 vertices and a
///   650-sample walk, 4.3 instead of 9.4 billion.
///
/// Both agree to rounding (the determinant identity of the Schur complement); the choice
/// depends only on the sizes, so a given walk always takes the same path.
#[inline(always)]
fn dense_gain<const FMA: bool>(ctx: &Ctx, prior: &Prior, obs: &[(Point, f64)]) -> Option<f64> {
    let ns = prior.pts.len() + obs.len();
    let mut rp = Points::default();
    for (p, _) in obs {
        rp.push(p);
    }
    let known = prior.known as f64;
    let s_side = prior.known > 0 && known.powi(3) > 1.5 * (ns as f64).powi(3);
    // Taken out of the thread-local rather than filled in a closure: a closure would not
    // inherit the caller's target features, and the kernel rows would lose FMA and SIMD.
    let mut a = DENSE.take();
    let out = if s_side {
        dense_gain_s_side::<FMA>(ctx, prior, obs, &rp, &mut a)
    } else {
        dense_gain_v_side::<FMA>(ctx, prior, obs, &rp, &mut a)
    };
    keep_dense(a);
    out
}

/// The S-side form of [`dense_gain`], in the thread's dense buffer: the observations'
/// own matrix first, then the joint one over it.
#[inline(always)]
fn dense_gain_s_side<const FMA: bool>(
    ctx: &Ctx,
    prior: &Prior,
    obs: &[(Point, f64)],
    rp: &Points,
    a: &mut Vec<f64>,
) -> Option<f64> {
    let (alone, joint) = s_side_layouts(ctx, prior, obs);
    let need = alone.len().max(joint.len());
    if a.len() < need {
        a.resize(need, 0.0);
    }
    let e = Entries {
        ctx,
        prior,
        obs,
        rp,
    };
    let ld_s = s_side_logdet::<FMA>(e, a, alone, 0, false)?;
    let ld_post = s_side_logdet::<FMA>(e, a, joint, prior.known, true)?;
    Some(ld_s - ld_post)
}

/// What the raw entries of one floor's dense matrices are made of: the floor's kernel
/// and vertices, its prior observations and a walk's observations on it (with their
/// positions packed for the kernel rows).
#[derive(Clone, Copy)]
struct Entries<'a> {
    ctx: &'a Ctx,
    prior: &'a Prior,
    obs: &'a [(Point, f64)],
    rp: &'a Points,
}

/// The layouts of the S-side form's two matrices: `K_SS + N_S` (`S = [D, obs]`) and the
/// joint `[V, D, obs]`.
fn s_side_layouts(
    ctx: &Ctx,
    prior: &Prior,
    obs: &[(Point, f64)],
) -> (dense::Layout, dense::Layout) {
    let ns = prior.pts.len() + obs.len();
    (dense::Layout::new(ns), dense::Layout::new(ctx.nv + ns))
}

/// Of the S-side form's two matrices in `a` (see [`s_side_layouts`]), whose rows and
/// columns `..known` hold its factor already (a multiple of [`dense::KNOWN_STEP`]):
/// * `joint == false`: `ln det (K_SS + N_S)`, `S = [D, obs]`;
/// * `joint == true`: `ln det (K_SS + N_S - K_SV A^-1 K_VS)`, the Schur complement in the
///   joint matrix `[V, D, obs]`, `known` from `prior.known` (the rows of `A`'s factor the
///   prior keeps, copied in here) up to the whole matrix less its last rows (a walk's
///   that shares its first observations with another's, [`near`]).
#[inline(always)]
fn s_side_logdet<const FMA: bool>(
    e: Entries<'_>,
    a: &mut [f64],
    layout: dense::Layout,
    known: usize,
    joint: bool,
) -> Option<f64> {
    let Entries { ctx, prior, .. } = e;
    let ld = layout.ld;
    if joint && known == prior.known {
        for v in 0..known {
            let u = v * prior.ua_ld;
            a[v * ld + v..v * ld + known].copy_from_slice(&prior.ua[u + v..u + known]);
        }
    }
    fill_raw::<FMA>(e, a, ld, joint, known);
    dense::factor_after(ctx.isa, a, layout, known, if joint { ctx.nv } else { 0 })
}

/// Writes the raw entries (upper triangle) of the matrix ordered `[V, D, obs]` (or `[D,
/// obs]` without `with_v`) into `a` of row stride `ld`: of each row `i`, the columns
/// from `known` (rows above `known`) or from `i` (the others) to the end, and zeros from
/// there to `ld`. The block `..known` is left as it is (a factor already).
#[inline(always)]
fn fill_raw<const FMA: bool>(e: Entries<'_>, a: &mut [f64], ld: usize, with_v: bool, known: usize) {
    let Entries {
        ctx,
        prior,
        obs,
        rp,
    } = e;
    let nv = if with_v { ctx.nv } else { 0 };
    let nd = prior.pts.len();
    let o = nv + nd;
    let n = o + obs.len();
    for i in 0..n {
        let from = i.max(known);
        let row = &mut a[i * ld..(i + 1) * ld];
        if i < nv {
            if from < nv {
                prior.a_row(i, from, &mut row[from..nv]);
            }
            let lo = from.max(nv).min(o);
            for (c, x) in (lo..o).zip(&mut row[lo..o]) {
                *x = prior.dv[(c - nv) * ctx.nv + i];
            }
            let c0 = from.max(o);
            ctx.kernel_row::<FMA>(ctx.vertices.at(i), rp, c0 - o, &mut row[c0..n]);
        } else if i < o {
            let d = i - nv;
            if from < o {
                row[from..o].copy_from_slice(&prior.dd[d * nd + from - nv..d * nd + o - nv]);
            }
            let c0 = from.max(o);
            ctx.kernel_row::<FMA>(prior.pts.at(d), rp, c0 - o, &mut row[c0..n]);
        } else {
            let r = i - o;
            ctx.kernel_row::<FMA>(rp.at(r), rp, from - o, &mut row[from..n]);
            if from == i {
                row[i] += ctx.sn2 + obs[r].1;
            }
        }
        row[n..].fill(0.0);
    }
}

/// The V-side form of [`dense_gain`].
#[inline(always)]
fn dense_gain_v_side<const FMA: bool>(
    ctx: &Ctx,
    prior: &Prior,
    obs: &[(Point, f64)],
    rp: &Points,
    a: &mut Vec<f64>,
) -> Option<f64> {
    let nd = prior.pts.len();
    let nr = obs.len();
    let nv = ctx.nv;
    let n = nd + nr + nv;
    let layout = dense::Layout::new(n);
    let ld = layout.ld;
    if a.len() < layout.len() {
        a.resize(layout.len(), 0.0);
    }
    let e = Entries {
        ctx,
        prior,
        obs,
        rp,
    };
    fill_raw::<FMA>(e, a, ld, false, 0);
    for i in 0..nd {
        let row = &mut a[i * ld..(i + 1) * ld];
        row[nd + nr..n].copy_from_slice(&prior.dv[i * nv..(i + 1) * nv]);
    }
    for r in 0..nr {
        let i = nd + r;
        let row = &mut a[i * ld..(i + 1) * ld];
        ctx.kernel_row::<FMA>(rp.at(r), &ctx.vertices, 0, &mut row[nd + nr..n]);
    }
    for v in 0..nv {
        let i = nd + nr + v;
        let row = &mut a[i * ld..(i + 1) * ld];
        prior.a_row(v, v, &mut row[i..n]);
        row[n..].fill(0.0);
    }
    let ld_post = dense::factor(ctx.isa, a, layout, nd + nr)?;
    Some(prior.logdet_a - ld_post)
}

/// Vertices (of one floor) beyond which `A` is factored by the dense factor (see
/// [`Part::new`]).
pub(crate) const DENSE_A_FROM: usize = 1024;

/// One floor's share of the dense path: its vertices and the prior observations on it.
#[derive(Debug, Clone)]
struct Part {
    floor: i64,
    /// Positions of the part's vertices in the engine's `V`, increasing.
    index: Vec<usize>,
    ctx: Ctx,
    prior: Prior,
}

/// `A`'s entries `(i, from..)` of the vertices `vpts` (`A = K_VV + sn2 I`) into `out`
/// (`out.len()` of them). The one formula for them: entries computed again later
/// ([`Prior::a_row`]) are the same bits as those first factored.
/// `A`'s entries `(i, from..from + out.len())` on a part of more than [`DENSE_A_FROM`]
/// vertices, by the vectorised kernel row ([`simd::kernel_row_isa`]) instead of
/// [`a_entries`]' scalar `hypot` and `exp`: the engine's set-up on the generated
/// 3,161-vertex floor (5 million entries) went from 348 to about 290 ms on one core
/// (`examples/phase_timing.rs`), the rest being mostly `A`'s factorisation. The
/// same function computes an entry again ([`Prior::a_row`]), so it has the same bits as
/// the one factored. Smaller parts keep [`a_entries`], whose figures every earlier
/// release gave.
fn a_entries_large(
    isa: Isa,
    kernel: &Kernel,
    pts: &Points,
    i: usize,
    from: usize,
    out: &mut [f64],
) {
    let p = (pts.x[i], pts.y[i], pts.floor[i]);
    let inv_ell = 1.0 / kernel.ell;
    if isa.fma() {
        simd::kernel_row_isa::<true>(isa, kernel.sf2, inv_ell, p, pts, from, out);
    } else {
        simd::kernel_row_isa::<false>(isa, kernel.sf2, inv_ell, p, pts, from, out);
    }
    if let Some(x) = i.checked_sub(from).and_then(|k| out.get_mut(k)) {
        *x += kernel.sn2;
    }
}

fn a_entries(kernel: &Kernel, vpts: &[Point], i: usize, from: usize, out: &mut [f64]) {
    for (k, x) in out.iter_mut().enumerate() {
        let j = from + k;
        *x = kernel.k(&vpts[i], &vpts[j]) + if i == j { kernel.sn2 } else { 0.0 };
    }
}

impl Prior {
    /// `A`'s entries `(v, from..from + out.len())` (`from >= v`: the upper triangle), from
    /// what the part keeps or computed again.
    fn a_row(&self, v: usize, from: usize, out: &mut [f64]) {
        let nv = self.vpts.len();
        if !self.a.is_empty() {
            out.copy_from_slice(&self.a[v * nv + from..v * nv + from + out.len()]);
        } else if from >= self.known {
            let w = nv - self.known;
            let at = v * w + from - self.known;
            out.copy_from_slice(&self.a_tail[at..at + out.len()]);
        } else {
            a_entries_large(self.isa, &self.kernel, &self.vsoa, v, from, out);
        }
    }
}

impl Part {
    /// `vpts`: the part's vertices; `obs`: the prior observations with their extra noise.
    fn new(
        kernel: &Kernel,
        isa: Isa,
        vpts: &[Point],
        obs: &[(Point, f64)],
        index: Vec<usize>,
    ) -> Result<Part> {
        let nv = vpts.len();
        let mut vertices = Points::default();
        for p in vpts {
            vertices.push(p);
        }
        let ctx = Ctx {
            sf2: kernel.sf2,
            inv_ell: 1.0 / kernel.ell,
            sn2: kernel.sn2,
            vertices,
            nv,
            isa,
        };
        let known = nv / dense::KNOWN_STEP * dense::KNOWN_STEP;
        // ln det A, and the factor itself, kept for the S-side form. Up to DENSE_A_FROM
        // vertices by the blocked factor (the figures of every earlier release, bit for
        // bit); beyond, by the dense one in its own layout, at about twice the rate (0.45
        // against 0.2 s on 3,161 vertices, a quarter of the set-up there). Beyond, `A`
        // itself is not kept either, only its last columns (`a_tail`): 80 MB less on
        // 3,161 vertices, and its entries computed again are the same bits.
        let not_pd = || Error::Numerical("K_VV + sn2 I is not positive definite".into());
        let (a, a_tail, ua, ua_ld, logdet_a) = if nv > DENSE_A_FROM {
            let layout = dense::Layout::new(nv);
            let mut ua = vec![0.0; layout.len()];
            let w = nv - known;
            let mut a_tail = vec![0.0; nv * w];
            // Row by row, in parallel where there are threads (a phone's other cores).
            let (ld, vs) = (layout.ld, &ctx.vertices);
            ua[..nv * ld]
                .par_chunks_mut(ld)
                .enumerate()
                .for_each(|(i, row)| a_entries_large(isa, kernel, vs, i, i, &mut row[i..nv]));
            if w > 0 {
                let ua = &ua;
                a_tail.par_chunks_mut(w).enumerate().for_each(|(i, tail)| {
                    let from = i.max(known);
                    tail[from - known..].copy_from_slice(&ua[i * ld + from..i * ld + nv]);
                });
            }
            let logdet_a = dense::factor(isa, &mut ua, layout, 0).ok_or_else(not_pd)?;
            (Vec::new(), a_tail, ua, layout.ld, logdet_a)
        } else {
            // A = K_VV + sn2 I (the upper triangle is what the kernels read).
            let mut a = vec![0.0; nv * nv];
            for i in 0..nv {
                a_entries(kernel, vpts, i, i, &mut a[i * nv + i..(i + 1) * nv]);
            }
            let mut tmp = Factor {
                sigma: a,
                ..Factor::default()
            };
            let mut ua = Vec::new();
            let logdet_a = match dispatch(isa, &mut tmp, &ctx, DispatchArg::LogDet(None, &mut ua)) {
                DispatchOut::LogDet(Some(v)) => v,
                _ => return Err(not_pd()),
            };
            (tmp.sigma, Vec::new(), ua, nv, logdet_a)
        };
        let nd = obs.len();
        let mut prior = Prior {
            pts: Points::default(),
            dd: vec![0.0; nd * nd],
            dv: vec![0.0; nd * nv],
            a,
            a_tail,
            kernel: *kernel,
            vpts: vpts.to_vec(),
            vsoa: ctx.vertices.clone(),
            isa,
            ua,
            ua_ld,
            known,
            logdet_a,
        };
        for (i, (p, noise)) in obs.iter().enumerate() {
            prior.pts.push(p);
            for (j, (q, _)) in obs.iter().enumerate() {
                prior.dd[i * nd + j] =
                    kernel.k(p, q) + if i == j { kernel.sn2 + noise } else { 0.0 };
            }
            for (j, v) in vpts.iter().enumerate() {
                prior.dv[i * nv + j] = kernel.k(p, v);
            }
        }
        Ok(Part {
            floor: vpts.first().map_or(0, |p| p.floor),
            index,
            ctx,
            prior,
        })
    }
}

/// A growing factorisation: rows of `L` and `W` for the observations so far, and
/// `Sigma = A - W^T W` (upper triangle, row-major `nv x nv`).
#[derive(Debug, Clone, Default)]
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
        let s = row[j] - simd::dot_isa::<FMA>(ctx.isa, &prev[oj..oj + j], &row[..j]);
        row[j] = s * f.inv_diag[j];
    }
    let d2 = ctx.sf2 + ctx.sn2 + noise - simd::dot_isa::<FMA>(ctx.isa, &row[..n], &row[..n]);
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
    simd::gemv_sub_isa::<FMA>(ctx.isa, &row[..n], wprev, nv, wrow);
    let inv = 1.0 / diag;
    for x in wrow.iter_mut() {
        *x *= inv;
    }
    f.inv_diag.push(inv);
    f.pts.push(p);
    true
}

/// `sigma -= w w^T` on the upper triangle.
#[inline(always)]
fn rank1_upper<const FMA: bool>(sigma: &mut [f64], w: &[f64], nv: usize) {
    for a in 0..nv {
        simd::axpy::<FMA>(-w[a], &w[a..nv], &mut sigma[a * nv + a..a * nv + nv]);
    }
}

/// Appends many observations at once with the blocked kernels: the cross block against
/// the factor so far, the Schur complement of the new block and its Cholesky, then the
/// new rows of `L` and `W`, and the downdate of `Sigma`.
#[inline(always)]
fn add_batch<const FMA: bool>(f: &mut Factor, ctx: &Ctx, obs: &[(Point, f64)]) -> bool {
    let n0 = f.pts.len();
    let m = obs.len();
    let nv = ctx.nv;
    let mut newp = Points::default();
    for (p, _) in obs {
        newp.push(p);
    }
    // Xt (n0 x m): row j holds L^-1-transformed cross covariances, X = L^-1 K_{old,new}.
    let mut xt = vec![0.0; n0 * m];
    for j in 0..n0 {
        let pj = f.pts.at(j);
        let (done, rest) = xt.split_at_mut(j * m);
        let row = &mut rest[..m];
        simd::kernel_row::<FMA>(ctx.sf2, ctx.inv_ell, pj, &newp, row);
        let lj = &f.l[j * (j + 1) / 2..j * (j + 1) / 2 + j];
        let mut k0 = 0;
        while k0 < j {
            let kb = blocked::BLOCK.min(j - k0);
            let mut srcs: [&[f64]; blocked::BLOCK] = [&[]; blocked::BLOCK];
            for t in 0..kb {
                srcs[t] = &done[(k0 + t) * m..(k0 + t) * m + m];
            }
            blocked::update_block::<FMA>(row, &lj[k0..k0 + kb], &srcs[..kb]);
            k0 += kb;
        }
        let inv = f.inv_diag[j];
        for x in row.iter_mut() {
            *x *= inv;
        }
    }
    // Schur complement S = K_nn + N - X^T X (upper), then S = U^T U.
    let mut s = vec![0.0; m * m];
    for a in 0..m {
        let pa = newp.at(a);
        simd::kernel_row_from::<FMA>(
            ctx.sf2,
            ctx.inv_ell,
            pa,
            &newp,
            a,
            &mut s[a * m + a..a * m + m],
        );
        s[a * m + a] += ctx.sn2 + obs[a].1;
    }
    blocked::syrk_upper_sub::<FMA>(&mut s, m, &xt, n0);
    if blocked::cholesky_upper::<FMA>(&mut s, m).is_none() {
        return false;
    }
    // W rows of the new observations: (K_{new,V} - X^T W_old) solved with U^T.
    let mut wn = vec![0.0; m * nv];
    for i in 0..m {
        let pi = newp.at(i);
        let row = &mut wn[i * nv..i * nv + nv];
        simd::kernel_row::<FMA>(ctx.sf2, ctx.inv_ell, pi, &ctx.vertices, row);
        let mut j0 = 0;
        while j0 < n0 {
            let jb = blocked::BLOCK.min(n0 - j0);
            let mut coeffs = [0.0; blocked::BLOCK];
            let mut srcs: [&[f64]; blocked::BLOCK] = [&[]; blocked::BLOCK];
            for t in 0..jb {
                coeffs[t] = xt[(j0 + t) * m + i];
                srcs[t] = &f.w[(j0 + t) * nv..(j0 + t) * nv + nv];
            }
            blocked::update_block::<FMA>(row, &coeffs[..jb], &srcs[..jb]);
            j0 += jb;
        }
    }
    blocked::solve_upper_transposed::<FMA>(&s, m, &mut wn, nv);
    blocked::syrk_upper_sub::<FMA>(&mut f.sigma, nv, &wn, m);
    // Append the rows of L: [X^T row i, U column i].
    f.l.reserve(m * n0 + m * (m + 1) / 2);
    for i in 0..m {
        for j in 0..n0 {
            f.l.push(xt[j * m + i]);
        }
        for k in 0..=i {
            f.l.push(s[k * m + i]);
        }
        f.inv_diag.push(1.0 / s[i * m + i]);
        f.pts.push(&obs[i].0);
    }
    f.w.extend_from_slice(&wn);
    true
}

/// Adds observations to a factor, downdating its `Sigma`.
#[inline(always)]
fn add_all<const FMA: bool>(f: &mut Factor, ctx: &Ctx, obs: &[(Point, f64)]) -> bool {
    if obs.len() >= blocked::BLOCK {
        return add_batch::<FMA>(f, ctx, obs);
    }
    for (p, noise) in obs {
        if !push_rows::<FMA>(f, ctx, p, *noise) {
            return false;
        }
        let n = f.pts.len();
        let nv = ctx.nv;
        let (w, sigma) = (&f.w[(n - 1) * nv..n * nv], &mut f.sigma);
        rank1_upper::<FMA>(sigma, w, nv);
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
        rank1_upper::<FMA>(scratch, &f.w[(n - 1) * nv..n * nv], nv);
        f.truncate(n - 1, nv);
    }
    blocked::cholesky_upper::<FMA>(scratch, nv)
}

/// Arguments of the dispatched operations (one signature keeps the macro simple).
enum DispatchArg<'a> {
    /// Observations to append to the factor (rows of `L` and `W`, downdate of `Sigma`).
    Add(&'a [(Point, f64)]),
    LogDet(Option<(Point, f64)>, &'a mut Vec<f64>),
    /// Twice the utility of the prior plus these observations, by the dense path.
    Dense(&'a Prior, &'a [(Point, f64)]),
    /// The same, keeping the factorisation as a base for walks near it ([`near`]).
    NearBase(&'a Prior, &'a [(Point, f64)], usize),
    /// The same, from a base's factorisation ([`near`]).
    Near(&'a Prior, &'a [(Point, f64)], &'a near::BasePart),
}

enum DispatchOut {
    Added(bool),
    LogDet(Option<f64>),
    Base(Option<near::BasePart>),
}

#[inline(always)]
fn run_op<const FMA: bool>(f: &mut Factor, ctx: &Ctx, a: DispatchArg<'_>) -> DispatchOut {
    match a {
        DispatchArg::Add(obs) => DispatchOut::Added(add_all::<FMA>(f, ctx, obs)),
        DispatchArg::LogDet(extra, scratch) => {
            DispatchOut::LogDet(logdet_sigma::<FMA>(f, ctx, extra, scratch))
        }
        DispatchArg::Dense(prior, obs) => DispatchOut::LogDet(dense_gain::<FMA>(ctx, prior, obs)),
        DispatchArg::NearBase(prior, obs, max) => {
            DispatchOut::Base(near::base_part::<FMA>(ctx, prior, obs, max))
        }
        DispatchArg::Near(prior, obs, base) => {
            DispatchOut::LogDet(near::near_part::<FMA>(ctx, prior, obs, base))
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
/// The portable build fuses multiply-adds where the base instruction set has them
/// (aarch64, [`simd::GENERIC_FMA`]).
fn dispatch(isa: Isa, f: &mut Factor, ctx: &Ctx, a: DispatchArg<'_>) -> DispatchOut {
    match isa.kind() {
        // SAFETY: an `Isa` of this kind exists only on a CPU with the features
        // (`Isa::detect`, `Isa::supported`).
        #[cfg(target_arch = "x86_64")]
        simd::IsaKind::Avx512 => unsafe { run_op_avx512(f, ctx, a) },
        // SAFETY: as above.
        #[cfg(target_arch = "x86_64")]
        simd::IsaKind::Avx2Fma => unsafe { run_op_avx2(f, ctx, a) },
        _ => run_op::<{ simd::GENERIC_FMA }>(f, ctx, a),
    }
}

/// The fast evaluator for one building, kernel, surveyor model and set of prior
/// observations (the pilot data, plus anything already collected).
#[derive(Debug, Clone)]
pub struct UtilityEngine {
    building: Arc<Building>,
    kernel: Kernel,
    model: Surveyor,
    ctx: Ctx,
    isa: Isa,
    logdet_a: f64,
    /// See [`UtilityEngine::base`].
    base: std::sync::OnceLock<Option<Factor>>,
    /// The dense path's data, one part per floor of `V` (see [`UtilityEngine::build`]).
    parts: Vec<Part>,
    /// The observations beyond the pilot data the engine is conditioned on.
    prior_obs: Vec<Observation>,
    /// The pilot locations, then `prior_obs`, with their extra noise.
    prior_points: Vec<(Point, f64)>,
}

impl UtilityEngine {
    /// Conditions on the building's pilot locations.
    pub fn new(building: Arc<Building>, kernel: Kernel, model: Surveyor) -> Result<Self> {
        Self::with_prior(building, kernel, model, &[])
    }

    /// Conditions on the pilot locations plus `prior` (for example samples already
    /// collected, or other surveyors' walks).
    pub fn with_prior(
        building: Arc<Building>,
        kernel: Kernel,
        model: Surveyor,
        prior: &[Observation],
    ) -> Result<Self> {
        let all: Vec<usize> = (0..building.len()).collect();
        Self::build(building, kernel, model, prior, &all, Isa::detect())
    }

    /// An engine whose `V` is the subset `vertices` of the building's vertices (indices):
    /// the search surrogate of [`crate::plan::scale`], which judges walks by what they
    /// tell about a coarser set of vertices. Its utilities are *not* SPEC 3's `f_D`
    /// (that needs every vertex); walks are still sampled on the whole building.
    pub fn with_vertex_subset(
        building: Arc<Building>,
        kernel: Kernel,
        model: Surveyor,
        prior: &[Observation],
        vertices: &[usize],
    ) -> Result<Self> {
        if let Some(&v) = vertices.iter().find(|&&v| v >= building.len()) {
            return Err(Error::InvalidRequest(format!(
                "vertex index {v} out of range"
            )));
        }
        Self::build(building, kernel, model, prior, vertices, Isa::detect())
    }

    fn build(
        building: Arc<Building>,
        kernel: Kernel,
        model: Surveyor,
        prior: &[Observation],
        subset: &[usize],
        isa: Isa,
    ) -> Result<Self> {
        kernel.validate("kernel")?;
        model.validate()?;
        let mut vertices = Points::default();
        for &v in subset {
            vertices.push(&building.vertices[v].pos);
        }
        let nv = vertices.len();
        let ctx = Ctx {
            sf2: kernel.sf2,
            inv_ell: 1.0 / kernel.ell,
            sn2: kernel.sn2,
            vertices,
            nv,
            isa,
        };
        let vpts: Vec<Point> = subset.iter().map(|&v| building.vertices[v].pos).collect();
        let mut obs: Vec<(Point, f64)> = building.pilot.iter().map(|f| (f.point(), 0.0)).collect();
        obs.extend(prior.iter().map(|o| (o.pos, o.extra_noise)));
        // Points on different floors are independent (SPEC 2), so the joint covariance is
        // block diagonal by floor and `f_D` is the sum of every floor's own: the dense
        // path works floor by floor, `sum n_f^3` instead of `(sum n_f)^3` (a quarter on
        // two equal floors), and holds only the floors' blocks of `A`. Observations on a
        // floor without vertices tell nothing about `y_V` and are left out there.
        let mut floors: Vec<i64> = vpts.iter().map(|p| p.floor).collect();
        floors.sort_unstable();
        floors.dedup();
        let parts = if floors.len() <= 1 {
            let index: Vec<usize> = (0..nv).collect();
            vec![Part::new(&kernel, isa, &vpts, &obs, index)?]
        } else {
            floors
                .iter()
                .map(|&fl| {
                    let index: Vec<usize> = (0..nv).filter(|&i| vpts[i].floor == fl).collect();
                    let vp: Vec<Point> = index.iter().map(|&i| vpts[i]).collect();
                    let op: Vec<(Point, f64)> =
                        obs.iter().filter(|(p, _)| p.floor == fl).copied().collect();
                    Part::new(&kernel, isa, &vp, &op, index)
                })
                .collect::<Result<Vec<_>>>()?
        };
        let logdet_a = parts.iter().map(|p| p.prior.logdet_a).sum();
        let engine = UtilityEngine {
            building,
            kernel,
            model,
            ctx,
            isa,
            logdet_a,
            base: std::sync::OnceLock::new(),
            parts,
            prior_obs: prior.to_vec(),
            prior_points: obs,
        };
        Ok(engine)
    }

    /// `A = K_VV + sn2 I` of every vertex (upper triangle, row-major), from the floors'
    /// blocks (zero between floors).
    fn full_a(&self) -> Vec<f64> {
        if let [one] = self.parts.as_slice()
            && !one.prior.a.is_empty()
        {
            return one.prior.a.clone();
        }
        let nv = self.ctx.nv;
        let mut a = vec![0.0; nv * nv];
        let mut row = Vec::new();
        for part in &self.parts {
            let pn = part.index.len();
            for (ii, &i) in part.index.iter().enumerate() {
                row.resize(pn - ii, 0.0);
                part.prior.a_row(ii, ii, &mut row);
                for (jj, &j) in part.index.iter().enumerate().skip(ii) {
                    a[i * nv + j] = row[jj - ii];
                }
            }
        }
        a
    }

    /// The factor of the prior observations alone, where the incremental path starts:
    /// built on first use (a third `|V| x |V|` matrix, which planning by whole walks on a
    /// building of thousands of vertices never needs).
    fn base(&self) -> Result<&Factor> {
        self.base
            .get_or_init(|| {
                let mut f = Factor {
                    sigma: self.full_a(),
                    ..Factor::default()
                };
                self.add(&mut f, &self.prior_points).ok().map(|()| f)
            })
            .as_ref()
            .ok_or_else(|| {
                Error::Numerical(
                    "K_SS + N_S of the prior observations is not positive definite".into(),
                )
            })
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
    pub fn model(&self) -> &Surveyor {
        &self.model
    }

    /// The observations beyond the pilot data this engine is conditioned on.
    pub fn prior_observations(&self) -> &[Observation] {
        &self.prior_obs
    }

    /// Number of vertices of `V` (all the building's, or the subset of
    /// [`with_vertex_subset`](Self::with_vertex_subset)).
    pub fn vertex_count(&self) -> usize {
        self.ctx.nv
    }

    /// The instruction set the numeric kernels run on.
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// `f_D` of the prior observations alone (no walk).
    pub fn prior_utility(&self) -> Result<f64> {
        let mut f = self.base()?.clone();
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
            factor: self.base()?.clone(),
            buf: Vec::new(),
            samples: 0,
        })
    }

    /// `f_D(P)` of a walk of vertex indices. All samples are added in one blocked batch.
    pub fn utility(&self, walk: &[usize]) -> Result<f64> {
        self.dense_utility(&self.walk_observations(walk)?)
    }

    /// The samples of `walk` as (position, extra noise).
    fn walk_observations(&self, walk: &[usize]) -> Result<Vec<(Point, f64)>> {
        if let Some(&v) = walk.iter().find(|&&v| v >= self.building.len()) {
            return Err(Error::InvalidWalk {
                step: 0,
                message: format!("vertex index {v} out of range"),
            });
        }
        let samples = crate::samples::sample_walk(&self.building, walk, &self.model, &self.kernel)?;
        Ok(samples.iter().map(|s| (s.pos, s.extra_noise)).collect())
    }

    /// Multiply-adds of [`UtilityEngine::utility`]'s factorisations for `walk` (about
    /// `N^3 / 6` per floor, in the form [`dense_gain`] takes there), for scaling a
    /// measured evaluation time to another walk: a search that cannot afford an exact
    /// evaluation early on times a shorter walk and scales by this.
    pub fn utility_work(&self, walk: &[usize]) -> Result<f64> {
        let cube = |x: usize| (x as f64).powi(3) / 6.0;
        Ok(self
            .parts
            .iter()
            .zip(self.observations_per_part(walk)?)
            .map(|(part, nr)| {
                let (ns, nv, known) = (part.prior.pts.len() + nr, part.ctx.nv, part.prior.known);
                if known > 0 && cube(known) > 1.5 * cube(ns) {
                    cube(ns) + cube(ns + nv) - cube(known)
                } else {
                    cube(ns + nv)
                }
            })
            .sum())
    }

    /// The number of `walk`'s observations (merged, as an evaluation merges them) on each
    /// floor part, in the order of `parts`.
    fn observations_per_part(&self, walk: &[usize]) -> Result<Vec<usize>> {
        let merged = merge_coincident(&self.walk_observations(walk)?, self.kernel.sn2);
        Ok(self
            .parts
            .iter()
            .map(|part| {
                if self.parts.len() == 1 {
                    merged.len()
                } else {
                    merged.iter().filter(|(p, _)| p.floor == part.floor).count()
                }
            })
            .collect())
    }

    /// Grows the calling thread's dense matrix to what an exact evaluation of `walk`
    /// needs, when the thread keeps one that large (inside a [`KeepScratch`]; else it
    /// does nothing): an evaluation timed after it measures the factorisation, not the
    /// allocation and page faults of a fresh matrix, which only the first evaluation of a
    /// plan pays. Without it, the large-building search timed a prefix on a fresh matrix
    /// and the next on a grown one, and estimated the generated 3,161-vertex floor's
    /// final evaluation (person 3,116 m) at 64 ms against 207 ms taken.
    pub fn warm_scratch(&self, walk: &[usize]) -> Result<()> {
        let need = self
            .parts
            .iter()
            .zip(self.observations_per_part(walk)?)
            .map(|(part, nr)| {
                // Either form's largest matrix is the joint one over D, R and V.
                dense::Layout::new(part.prior.pts.len() + nr + part.ctx.nv).len()
            })
            .max()
            .unwrap_or(0);
        if need <= KEEP.get() {
            DENSE.with_borrow_mut(|a| {
                if a.len() < need {
                    a.resize(need, 0.0);
                }
            });
        }
        Ok(())
    }

    /// `f_D` of the prior plus `obs` by one dense factorisation ([`super::dense`]): the
    /// fastest way to evaluate a whole walk from scratch.
    ///
    /// Observations at the same place (a walk that goes back along an edge, or passes a
    /// vertex twice, puts samples exactly where earlier ones were) are merged first
    /// ([`merge_coincident`]): that is exact and shrinks the factorisation, whose cost
    /// grows with the cube of the number of observations.
    fn dense_utility(&self, obs: &[(Point, f64)]) -> Result<f64> {
        // The dense path builds its own matrix; the dispatcher's factor goes unused.
        let mut unused = Factor::default();
        let mut gain = 0.0;
        for (part, obs) in self.parts.iter().zip(self.per_part(obs)) {
            match dispatch(
                self.isa,
                &mut unused,
                &part.ctx,
                DispatchArg::Dense(&part.prior, &obs),
            ) {
                DispatchOut::LogDet(Some(g)) => gain += g,
                _ => {
                    return Err(Error::Numerical(
                        "posterior covariance is not positive definite".into(),
                    ));
                }
            }
        }
        Ok((0.5 * gain).max(0.0))
    }

    /// `obs` merged where they coincide ([`merge_coincident`]) and split by floor, in the
    /// order of [`Self::parts`].
    fn per_part(&self, obs: &[(Point, f64)]) -> Vec<Vec<(Point, f64)>> {
        let merged = merge_coincident(obs, self.kernel.sn2);
        if self.parts.len() == 1 {
            return vec![merged];
        }
        self.parts
            .iter()
            .map(|part| {
                merged
                    .iter()
                    .filter(|(p, _)| p.floor == part.floor)
                    .copied()
                    .collect()
            })
            .collect()
    }

    /// `f_D` of many walks, in parallel.
    pub fn utilities(&self, walks: &[Vec<usize>]) -> Vec<Result<f64>> {
        walks.par_iter().map(|w| self.utility(w)).collect()
    }

    /// `f_D` of the prior plus arbitrary observations (for example samples actually
    /// collected, with their real label noise).
    pub fn utility_of_observations(&self, obs: &[Observation]) -> Result<f64> {
        let list: Vec<(Point, f64)> = obs.iter().map(|o| (o.pos, o.extra_noise)).collect();
        self.dense_utility(&list)
    }
}

/// Observations that share a place (same floor, `x` and `y` equal to [`COINCIDENT_M`])
/// merged into one, in the order of their first occurrence. Each observation is
/// `(position, extra noise)`, its noise variance `sn2 + extra`.
///
/// Why this is exact: `k` observations `y_i = f(p) + e_i` of the same value `f(p)` with
/// independent noise variances `v_i` carry what their precision-weighted mean `m` carries
/// (noise variance `1 / sum(1 / v_i)`): the residuals `y_i - m` are independent of `m`
/// (their covariance with it is `v_i w_i / W - 1 / W = 0`) and of `f`, so
/// `I(y_V; y_1..y_k, rest) = I(y_V; m, rest)`. The merged observation's extra noise is
/// `1 / sum(1 / v_i) - sn2`, negative, which the factorisation takes as it is (only the
/// diagonal `sn2 + extra` must be positive). An observation whose variance is not positive
/// is kept on its own, for the factorisation to refuse.
pub fn merge_coincident(obs: &[(Point, f64)], sn2: f64) -> Vec<(Point, f64)> {
    use std::collections::HashMap;
    let key = |p: &Point| {
        (
            p.floor,
            (p.x / COINCIDENT_M).round() as i64,
            (p.y / COINCIDENT_M).round() as i64,
        )
    };
    // Position of each place in `out`, and the summed precision of its observations.
    let mut at: HashMap<(i64, i64, i64), usize> = HashMap::with_capacity(obs.len());
    let mut out: Vec<(Point, f64)> = Vec::with_capacity(obs.len());
    let mut precision: Vec<f64> = Vec::with_capacity(obs.len());
    let mut merged_any = false;
    for &(p, extra) in obs {
        let v = sn2 + extra;
        if !(v > 0.0 && v.is_finite() && p.x.is_finite() && p.y.is_finite()) {
            out.push((p, extra));
            precision.push(f64::NAN);
            continue;
        }
        match at.entry(key(&p)) {
            std::collections::hash_map::Entry::Occupied(e) => {
                precision[*e.get()] += 1.0 / v;
                merged_any = true;
            }
            std::collections::hash_map::Entry::Vacant(e) => {
                e.insert(out.len());
                out.push((p, extra));
                precision.push(1.0 / v);
            }
        }
    }
    if merged_any {
        for ((_, extra), w) in out.iter_mut().zip(&precision) {
            if w.is_finite() {
                *extra = 1.0 / w - sn2;
            }
        }
    }
    out
}

/// Two observations closer than this on both axes (metres, on one floor) are at the same
/// place for [`merge_coincident`]. Sample positions are interpolated along edges, so the
/// same point reached from either end can differ in the last bits; a kernel value moves
/// by about `1e-9 / ell` relative across this distance, far inside SPEC 3's 1e-9.
pub const COINCIDENT_M: f64 = 1e-9;

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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::utility::reference::{pilot_observations, reference_utility};

    #[test]
    fn a_plan_holds_a_large_matrix_only_while_it_runs() {
        let kept = || DENSE.with_borrow(|a| a.capacity());
        let big = DENSE_KEEP_MAX + 8;
        // Outside a plan a matrix beyond the limit is freed after its evaluation.
        keep_dense(Vec::with_capacity(big));
        assert!(kept() < big);
        {
            let _plan = KeepScratch::new();
            keep_dense(Vec::with_capacity(big));
            assert!(kept() >= big);
            // A guard inside another (a stage of a portfolio) leaves the outer one's rule.
            drop(KeepScratch::new());
            assert!(kept() >= big);
        }
        assert!(kept() < big, "freed when the plan ends");
        // And a small matrix stays, as between any two evaluations.
        keep_dense(Vec::with_capacity(64));
        assert!(kept() >= 64);
    }

    /// The whole engine (dense walk path, incremental pushes, prior utility) built for
    /// `isa` agrees with SPEC 3's formula (the reference implementation) to 1e-9.
    pub(crate) fn check(isa: Isa) {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/area-one.json");
        let b = Arc::new(Building::load(&path).expect("fixture"));
        let kernel = Kernel::new(62.58, 7.93, 4.22);
        let model = Surveyor::robot();
        // Out along unvisited neighbours for eight edges from r0c0, and back the same way.
        let walk: Vec<usize> = {
            let mut out = vec![b.vertex_index("r0c0").expect("r0c0")];
            for _ in 0..8 {
                let v = *out.last().expect("non-empty");
                match b.neighbours(v).iter().find(|(w, _)| !out.contains(w)) {
                    Some(&(w, _)) => out.push(w),
                    None => break,
                }
            }
            let back: Vec<usize> = out.iter().rev().skip(1).copied().collect();
            out.extend(back);
            out
        };
        assert!(walk.len() >= 9, "{walk:?}");
        let mut obs = pilot_observations(&b.pilot_points());
        for s in crate::samples::sample_walk(&b, &walk, &model, &kernel).expect("samples") {
            obs.push(Observation::from(&s));
        }
        let want = reference_utility(&kernel, &b.vertex_points(), &obs).expect("reference");
        let all: Vec<usize> = (0..b.len()).collect();
        {
            let e = UtilityEngine::build(b.clone(), kernel, model, &[], &all, isa).expect("engine");
            assert_eq!(e.isa(), isa);
            let (dense, inc) = dense_and_incremental(&e, &walk);
            for (what, got) in [("dense", dense), ("incremental", inc)] {
                assert!(
                    (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                    "{isa:?} {what}: {got} vs {want}"
                );
            }
            let prior = e.prior_utility().expect("prior");
            let pw = reference_utility(
                &kernel,
                &b.vertex_points(),
                &pilot_observations(&b.pilot_points()),
            )
            .expect("reference");
            assert!(
                (prior - pw).abs() <= 1e-9 * pw.abs().max(1.0),
                "{isa:?} prior"
            );
        }
        check_s_side(isa);
        check_large_v_side(isa);
        check_floors(isa);
        check_near(isa);
    }

    /// Utilities from a base walk's factorisation ([`UtilityEngine::utility_near`]) agree
    /// with whole evaluations: walks that leave the base at its start, middle or end, on
    /// one floor or the other, that only add observations, the base itself, a walk that
    /// takes the V side, for a robot and a person, on one and on two floors.
    fn check_near(isa: Isa) {
        let kernel = Kernel::new(62.58, 7.93, 4.22);
        let k = 12;
        for floors in [1, 2] {
            let b = grid_floors(floors, k, 2.0);
            let all: Vec<usize> = (0..b.len()).collect();
            let up = k * k;
            // Along row r of floor 0 from column `from` to column `to`.
            let row = |r: usize, from: usize, to: usize| -> Vec<usize> {
                if from <= to {
                    (from..=to).map(|c| r * k + c).collect()
                } else {
                    (to..=from).rev().map(|c| r * k + c).collect()
                }
            };
            let mut base = row(0, 0, 11);
            base.extend(row(1, 11, 4));
            let mut turn_early = row(0, 0, 3);
            turn_early.extend(row(1, 3, 9));
            let mut turn_late = row(0, 0, 11);
            turn_late.extend(row(1, 11, 9));
            turn_late.extend(row(2, 9, 2));
            let mut longer = base.clone();
            longer.extend(row(2, 4, 8));
            let shorter = base[..base.len() - 3].to_vec();
            let mut walks = vec![base.clone(), turn_early, turn_late, longer, shorter];
            let mut long = Vec::new();
            for r in 0..6 {
                long.extend(if r % 2 == 0 {
                    row(r, 0, 11)
                } else {
                    row(r, 11, 0)
                });
            }
            walks.push(long);
            let mut two_bases = vec![base.clone()];
            if floors == 2 {
                // Up the stairs at vertex 0 of each floor: the change on floor 1 only.
                let mut b2: Vec<usize> = row(0, 4, 0);
                b2.push(up);
                b2.extend((1..8).map(|c| up + c));
                let mut other = b2.clone();
                other.truncate(other.len() - 3);
                other.extend([up + k + 4, up + 2 * k + 4]);
                two_bases.push(b2.clone());
                walks.extend([b2, other]);
            }
            for model in [Surveyor::robot(), Surveyor::human()] {
                let e =
                    UtilityEngine::build(b.clone(), kernel, model, &[], &all, isa).expect("engine");
                // With room for the factorisation, and with none (every floor whole).
                let bases = two_bases.iter().flat_map(|b| [(b, NEAR_BASE_MAX), (b, 0)]);
                for (base, max) in bases {
                    let nb = e.near_base(base, max).expect("base");
                    assert_eq!(nb.reuses(), max > 0, "{isa:?} {floors} floors {model:?}");
                    let whole = e.utility(base).expect("utility");
                    assert!(
                        (nb.utility() - whole).abs() <= 1e-12 * whole,
                        "{isa:?} base"
                    );
                    for w in &walks {
                        let want = e.utility(w).expect("utility");
                        let got = e.utility_near(&nb, w).expect("near");
                        assert!(
                            (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                            "{isa:?} {floors} floors {model:?}: {got} vs {want} for {w:?}"
                        );
                    }
                }
            }
        }
    }

    /// `walk`'s utility by the dense path and grown vertex by vertex.
    fn dense_and_incremental(e: &UtilityEngine, walk: &[usize]) -> (f64, f64) {
        let dense = e.utility(walk).expect("dense");
        let mut st = e.start(walk[0]).expect("start");
        for &v in &walk[1..] {
            st.push(v).expect("push");
        }
        (dense, st.utility().expect("incremental"))
    }

    /// `floors` square grid floors of `k x k` vertices `spacing` m apart (vertex index
    /// `f k^2 + i k + j` is `g{f}_{i}_{j}`), joined by 6 m stairs at their corner, with
    /// three pilot points per floor.
    fn grid_floors(floors: usize, k: usize, spacing: f64) -> Arc<Building> {
        let mut v = Vec::new();
        let mut e = Vec::new();
        let mut pilot = Vec::new();
        let side = (k - 1) as f64 * spacing;
        for f in 0..floors {
            for i in 0..k {
                for j in 0..k {
                    v.push(format!(
                        r#"{{"id":"g{f}_{i}_{j}","x":{},"y":{},"floor":{f}}}"#,
                        i as f64 * spacing,
                        j as f64 * spacing
                    ));
                    if i + 1 < k {
                        e.push(format!(
                            r#"{{"a":"g{f}_{i}_{j}","b":"g{f}_{}_{j}"}}"#,
                            i + 1
                        ));
                    }
                    if j + 1 < k {
                        e.push(format!(
                            r#"{{"a":"g{f}_{i}_{j}","b":"g{f}_{i}_{}"}}"#,
                            j + 1
                        ));
                    }
                }
            }
            if f > 0 {
                e.push(format!(
                    r#"{{"a":"g{}_0_0","b":"g{f}_0_0","length":6}}"#,
                    f - 1
                ));
            }
            for (fx, fy) in [(0.3, 0.2), (0.5, 0.9), (0.8, 0.4)] {
                pilot.push(format!(
                    r#"{{"x":{},"y":{},"floor":{f},"rss":{{"ap":-60}}}}"#,
                    fx * side,
                    fy * side
                ));
            }
        }
        let fl: Vec<String> = (0..floors)
            .map(|f| format!(r#"{{"id":{f},"name":"F{f}"}}"#))
            .collect();
        let text = format!(
            r#"{{"format":"survey-building/1","name":"grid","floors":[{}],"vertices":[{}],"edges":[{}],"pilot":[{}]}}"#,
            fl.join(","),
            v.join(","),
            e.join(","),
            pilot.join(",")
        );
        Arc::new(Building::from_json(&text, "grid").expect("grid building"))
    }

    fn grid(k: usize, spacing: f64) -> Arc<Building> {
        grid_floors(1, k, spacing)
    }

    /// On a building of two floors the dense path works floor by floor: the sum agrees
    /// with SPEC 3's formula on the whole building, with the incremental path (which
    /// works on the whole building), and so does the prior's utility.
    fn check_floors(isa: Isa) {
        let kernel = Kernel::new(62.58, 7.93, 4.22);
        let k = 9;
        let b = grid_floors(2, k, 2.0);
        let model = Surveyor::robot();
        // A short walk on floor 0, up the stairs, and a long one on floor 1: along its
        // first row and back three times (merged coincident samples included).
        let mut walk: Vec<usize> = (0..4).map(|i| i * k).collect();
        walk.extend((0..3).rev().map(|i| i * k));
        let up = k * k;
        walk.push(up);
        for _ in 0..3 {
            walk.extend((1..k).map(|i| up + i * k));
            walk.extend((0..k - 1).rev().map(|i| up + i * k));
        }
        let mut obs = pilot_observations(&b.pilot_points());
        for s in crate::samples::sample_walk(&b, &walk, &model, &kernel).expect("samples") {
            obs.push(Observation::from(&s));
        }
        let want = reference_utility(&kernel, &b.vertex_points(), &obs).expect("reference");
        let all: Vec<usize> = (0..b.len()).collect();
        let e = UtilityEngine::build(b.clone(), kernel, model, &[], &all, isa).expect("engine");
        assert_eq!(e.parts.len(), 2, "one dense part per floor");
        let (dense, inc) = dense_and_incremental(&e, &walk);
        let prior = e.prior_utility().expect("prior");
        let pw = reference_utility(
            &kernel,
            &b.vertex_points(),
            &pilot_observations(&b.pilot_points()),
        )
        .expect("reference");
        for (what, got, want) in [
            ("dense", dense, want),
            ("incremental", inc, want),
            ("prior", prior, pw),
        ] {
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                "{isa:?} two floors {what}: {got} vs {want}"
            );
        }
    }

    /// Buildings of many more vertices than the walk has samples take the S-side form of
    /// the dense path (the vertices' factor reused, below and beyond the size where the
    /// factorisation goes panel by panel): it agrees with SPEC 3's formula and with the
    /// incremental path.
    /// The engine for `b` and SPEC 3's utility of `walk` by the reference, and whether the
    /// dense path takes the S side for it (see [`dense_gain`]).
    fn reference_case(
        b: &Arc<Building>,
        kernel: Kernel,
        model: Surveyor,
        walk: &[usize],
        isa: Isa,
    ) -> (UtilityEngine, f64, bool) {
        let samples = crate::samples::sample_walk(b, walk, &model, &kernel).expect("samples");
        let ns = samples.len() + b.pilot.len();
        let known = b.len() / dense::KNOWN_STEP * dense::KNOWN_STEP;
        let s_side = known > 0 && (known as f64).powi(3) > 1.5 * (ns as f64).powi(3);
        let mut obs = pilot_observations(&b.pilot_points());
        obs.extend(samples.iter().map(Observation::from));
        let want = reference_utility(&kernel, &b.vertex_points(), &obs).expect("reference");
        let all: Vec<usize> = (0..b.len()).collect();
        let e = UtilityEngine::build(b.clone(), kernel, model, &[], &all, isa).expect("engine");
        (e, want, s_side)
    }

    /// A floor of more than [`DENSE_A_FROM`] vertices, where the engine keeps `A`'s factor
    /// and last columns but not `A`: a robot's serpentine over ten of its 33 rows has
    /// more samples than the S side takes, so the V side computes `A`'s rows again, and
    /// they must give SPEC 3's utility as the kept ones did.
    fn check_large_v_side(isa: Isa) {
        let kernel = Kernel::new(62.58, 7.93, 4.22);
        let k = 33;
        let b = grid(k, 1.5);
        assert!(b.len() > DENSE_A_FROM);
        let mut walk = Vec::new();
        for j in 0..10 {
            let row: Vec<usize> = (0..k).map(|i| i * k + j).collect();
            if j % 2 == 0 {
                walk.extend(row);
            } else {
                walk.extend(row.into_iter().rev());
            }
        }
        let (e, want, s_side) = reference_case(&b, kernel, Surveyor::robot(), &walk, isa);
        assert!(!s_side, "the walk's observations would take the S side");
        assert!(
            e.parts[0].prior.a.is_empty(),
            "A is kept on {} vertices",
            b.len()
        );
        let got = e.utility(&walk).expect("dense");
        assert!(
            (got - want).abs() <= 1e-9 * want.abs().max(1.0),
            "{isa:?} V side without A: {got} vs {want}"
        );
    }

    fn check_s_side(isa: Isa) {
        let kernel = Kernel::new(62.58, 7.93, 4.22);
        for (k, spacing, model) in [(12, 2.0, Surveyor::robot()), (33, 1.5, Surveyor::human())] {
            let b = grid(k, spacing);
            // Along the first row for six edges, then up one and back.
            let mut walk: Vec<usize> = (0..7).map(|i| i * k).collect();
            walk.extend([6 * k + 1, 5 * k + 1]);
            let (e, want, s_side) = reference_case(&b, kernel, model, &walk, isa);
            assert!(
                s_side,
                "{k}: the walk's observations would not take the S side"
            );
            let (dense, inc) = dense_and_incremental(&e, &walk);
            for (what, got) in [("dense S side", dense), ("incremental", inc)] {
                assert!(
                    (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                    "{isa:?} {k}x{k} {what}: {got} vs {want}"
                );
            }
        }
    }
}
