//! The few numeric kernels the utility engine spends its time in, written so that LLVM
//! vectorises them, and compiled three times on x86-64: AVX-512, AVX2+FMA and baseline
//! x86-64 (SSE2). On aarch64 there is one build, the portable loops vectorised with NEON
//! and using fused multiply-add, both part of that architecture's base instruction set
//! ([`GENERIC_FMA`]). [`Isa::detect`] picks one at run time, once per engine.
//!
//! Why not nalgebra here: the engine grows a Cholesky factor one row at a time (each walk
//! extension appends its samples), which is a sequence of short dot products and axpys on
//! packed rows. nalgebra's dense routines work on whole matrices and are compiled for the
//! baseline target, so they neither reuse a factor prefix nor use AVX-512. The kernels
//! below are plain loops over fixed-width chunks; `mul_add` is used only under a
//! `target_feature` that makes it a single FMA instruction.

/// Whether the portable kernels ([`Isa::generic`]) fuse their multiply-adds.
///
/// On aarch64 (the phone's architecture) fused multiply-add is part of the base
/// instruction set: `f64::mul_add` compiles to one `fmadd`, and the loops LLVM vectorises
/// with NEON (also baseline there, 128-bit) use `fmla`. On x86-64 it is not: without a
/// `target_feature` `mul_add` is a call into libm, so the baseline path stays unfused and
/// FMA is used only by the [`IsaKind::Avx2Fma`] and [`IsaKind::Avx512`] builds.
pub const GENERIC_FMA: bool = cfg!(target_arch = "aarch64");

/// Which instruction set an [`Isa`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IsaKind {
    /// x86-64 with AVX-512 F, DQ and VL, and FMA.
    Avx512,
    /// x86-64 with AVX2 and FMA.
    Avx2Fma,
    /// The portable loops compiled for the target's baseline: SSE2 on x86-64, NEON with
    /// fused multiply-add on aarch64 (see [`GENERIC_FMA`]).
    Generic,
}

/// An instruction set the running CPU has been checked to support: the only way to pick
/// the kernels the engine dispatches to.
///
/// Its field is private, so an `Isa` comes only from [`Isa::detect`], [`Isa::supported`]
/// (which ask the CPU) or [`Isa::generic`] (the portable code every CPU runs). That is
/// what makes the safe functions taking one ([`dot_isa`], [`gemv_sub_isa`],
/// [`kernel_row_isa`], [`super::dense::factor`]) sound: safe code cannot hand them an
/// AVX-512 value on a CPU without AVX-512.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Isa(IsaKind);

impl std::fmt::Debug for Isa {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?}", self.0)
    }
}

/// The CPU features the dispatch depends on.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Features {
    avx512f: bool,
    avx512dq: bool,
    avx512vl: bool,
    avx2: bool,
    fma: bool,
}

impl Features {
    /// What this CPU has.
    fn probe() -> Features {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            Features {
                avx512f: has!("avx512f"),
                avx512dq: has!("avx512dq"),
                avx512vl: has!("avx512vl"),
                avx2: has!("avx2"),
                fma: has!("fma"),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        Features::default()
    }

    /// The instruction sets these features allow, best first, always ending in
    /// `Generic`. Each requires everything its `#[target_feature(enable = ...)]` lists:
    /// `avx512f,avx512dq,avx512vl,fma` (LLVM may use VL's 128/256-bit EVEX forms anywhere
    /// in such a function) and `avx2,fma`.
    fn allowed(self) -> Vec<IsaKind> {
        let mut out = Vec::with_capacity(3);
        if cfg!(target_arch = "x86_64") {
            if self.avx512f && self.avx512dq && self.avx512vl && self.avx2 && self.fma {
                out.push(IsaKind::Avx512);
            }
            if self.avx2 && self.fma {
                out.push(IsaKind::Avx2Fma);
            }
        }
        out.push(IsaKind::Generic);
        out
    }
}

impl Isa {
    /// The best instruction set this CPU supports.
    pub fn detect() -> Isa {
        Isa(Features::probe().allowed()[0])
    }

    /// Every instruction set this CPU can run, best first: what the tests cover, so that
    /// a machine without AVX-512 still tests its AVX2+FMA path and one with it tests all.
    pub fn supported() -> Vec<Isa> {
        Features::probe().allowed().into_iter().map(Isa).collect()
    }

    /// The portable kernels, which run on every CPU of the target architecture.
    pub fn generic() -> Isa {
        Isa(IsaKind::Generic)
    }

    /// Which instruction set this is.
    pub fn kind(self) -> IsaKind {
        self.0
    }

    /// Whether this instruction set's kernels fuse multiply-adds (the `FMA` parameter
    /// of the generic kernels it runs).
    pub fn fma(self) -> bool {
        match self.0 {
            IsaKind::Avx512 | IsaKind::Avx2Fma => true,
            IsaKind::Generic => GENERIC_FMA,
        }
    }
}

/// Test support: runs `plain` (the `FMA = false` kernels) or `fused` (`FMA = true`) on
/// `arg` inside a function compiled for `isa`, with the `FMA` the engine's dispatch uses
/// for it ([`Isa::fma`]).
#[cfg(test)]
pub(crate) fn on_isa<T, R>(
    isa: Isa,
    arg: T,
    plain: impl FnOnce(T) -> R,
    fused: impl FnOnce(T) -> R,
) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx512f,avx512dq,avx512vl,fma")]
        fn avx512<T, R>(f: impl FnOnce(T) -> R, arg: T) -> R {
            f(arg)
        }
        #[target_feature(enable = "avx2,fma")]
        fn avx2<T, R>(f: impl FnOnce(T) -> R, arg: T) -> R {
            f(arg)
        }
        match isa.kind() {
            // SAFETY: an `Isa` of this kind exists only on a CPU with these features.
            IsaKind::Avx512 => return unsafe { avx512(fused, arg) },
            // SAFETY: as above.
            IsaKind::Avx2Fma => return unsafe { avx2(fused, arg) },
            IsaKind::Generic => {}
        }
    }
    if isa.fma() { fused(arg) } else { plain(arg) }
}

/// Test support: every way the kernels are run on this machine, as `(isa, fma)`: each
/// supported instruction set with its own `FMA`, plus the portable code with the other
/// `FMA` than this target's (on x86-64, the fused portable path aarch64's `Generic` runs;
/// `mul_add` is then a libm call, slow but exact), so that path is tested here too.
#[cfg(test)]
pub(crate) fn test_variants() -> Vec<(Isa, bool)> {
    let mut v: Vec<(Isa, bool)> = Isa::supported().into_iter().map(|i| (i, i.fma())).collect();
    v.push((Isa::generic(), !GENERIC_FMA));
    v
}

/// Test support: [`on_isa`] for one of [`test_variants`].
#[cfg(test)]
pub(crate) fn on_variant<T, R>(
    (isa, fma): (Isa, bool),
    arg: T,
    plain: impl FnOnce(T) -> R,
    fused: impl FnOnce(T) -> R,
) -> R {
    if isa.kind() == IsaKind::Generic {
        if fma { fused(arg) } else { plain(arg) }
    } else {
        on_isa(isa, arg, plain, fused)
    }
}

#[inline(always)]
fn fmadd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA { a.mul_add(b, c) } else { a * b + c }
}

/// `sum a[i] * b[i]` over the common length.
///
/// Two accumulators of eight lanes each (one zmm register apiece on AVX-512) and a plain
/// reduction at the end: a shape LLVM turns into straight vector FMAs. (An earlier version
/// with one sixteen-element array was vectorised as pairs of 128-bit halves shuffled
/// together, which made the forward substitutions of `WalkState::push` twice as slow.)
#[inline(always)]
pub fn dot<const FMA: bool>(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc0 = [0.0f64; 8];
    let mut acc1 = [0.0f64; 8];
    let mut ca = a.chunks_exact(16);
    let mut cb = b.chunks_exact(16);
    for (x, y) in (&mut ca).zip(&mut cb) {
        for i in 0..8 {
            acc0[i] = fmadd::<FMA>(x[i], y[i], acc0[i]);
        }
        for i in 0..8 {
            acc1[i] = fmadd::<FMA>(x[8 + i], y[8 + i], acc1[i]);
        }
    }
    let (ra, rb) = (ca.remainder(), cb.remainder());
    let mut i = 0;
    if ra.len() >= 8 {
        for k in 0..8 {
            acc0[k] = fmadd::<FMA>(ra[k], rb[k], acc0[k]);
        }
        i = 8;
    }
    let mut tail = 0.0;
    while i < ra.len() {
        tail = fmadd::<FMA>(ra[i], rb[i], tail);
        i += 1;
    }
    let mut lanes = [0.0f64; 8];
    for k in 0..8 {
        lanes[k] = acc0[k] + acc1[k];
    }
    let s4 = [
        lanes[0] + lanes[4],
        lanes[1] + lanes[5],
        lanes[2] + lanes[6],
        lanes[3] + lanes[7],
    ];
    (s4[0] + s4[2]) + (s4[1] + s4[3]) + tail
}

/// [`dot`] with the instruction set chosen at run time: AVX-512 intrinsics where the CPU
/// has them (LLVM vectorises the portable loop with 128-bit registers only, and forward
/// substitution is a long sequence of dot products), the portable loop elsewhere.
#[inline(always)]
pub fn dot_isa<const FMA: bool>(isa: Isa, a: &[f64], b: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if isa.kind() == IsaKind::Avx512 {
        // SAFETY: an `Isa` of kind `Avx512` exists only on a CPU with AVX-512F/DQ/VL and
        // FMA (`Isa::detect`, `Isa::supported`).
        return unsafe { dot_avx512(a, b) };
    }
    let _ = isa;
    dot::<FMA>(a, b)
}

/// `sum a[i] * b[i]` with AVX-512: two zmm accumulators, a masked tail.
///
/// # Safety
/// The CPU must support AVX-512F/DQ/VL and FMA.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,fma")]
pub unsafe fn dot_avx512(a: &[f64], b: &[f64]) -> f64 {
    use std::arch::x86_64::*;
    let n = a.len().min(b.len());
    let (pa, pb) = (a.as_ptr(), b.as_ptr());
    let mut acc0 = _mm512_setzero_pd();
    let mut acc1 = _mm512_setzero_pd();
    let mut i = 0;
    // SAFETY: every load below stays within the first n elements (masked at the tail).
    unsafe {
        while i + 16 <= n {
            acc0 = _mm512_fmadd_pd(_mm512_loadu_pd(pa.add(i)), _mm512_loadu_pd(pb.add(i)), acc0);
            acc1 = _mm512_fmadd_pd(
                _mm512_loadu_pd(pa.add(i + 8)),
                _mm512_loadu_pd(pb.add(i + 8)),
                acc1,
            );
            i += 16;
        }
        while i < n {
            let m: __mmask8 = if n - i >= 8 {
                0xff
            } else {
                (1u8 << (n - i)) - 1
            };
            acc0 = _mm512_fmadd_pd(
                _mm512_maskz_loadu_pd(m, pa.add(i)),
                _mm512_maskz_loadu_pd(m, pb.add(i)),
                acc0,
            );
            i += 8;
        }
    }
    _mm512_reduce_add_pd(_mm512_add_pd(acc0, acc1))
}

/// `y[c] -= sum_j x[j] m[j * ld + c]` for `c < y.len()`: a row-major matrix-vector
/// product subtracted from `y` (the new row of `W` in `WalkState::push`). On AVX-512, `y`
/// stays in registers, 32 columns at a time, while `j` runs over the matrix rows, instead
/// of being loaded and stored once per row as a sequence of [`axpy`]s would.
#[inline(always)]
pub fn gemv_sub_isa<const FMA: bool>(isa: Isa, x: &[f64], m: &[f64], ld: usize, y: &mut [f64]) {
    let w = y.len();
    assert!(
        x.is_empty() || (ld >= w && m.len() >= (x.len() - 1) * ld + w),
        "gemv_sub: matrix too small"
    );
    #[cfg(target_arch = "x86_64")]
    if isa.kind() == IsaKind::Avx512 {
        // SAFETY: an `Isa` of kind `Avx512` exists only on a CPU with AVX-512F/DQ/VL and
        // FMA; sizes checked above.
        unsafe { gemv_sub_avx512(x, m, ld, y) };
        return;
    }
    let _ = isa;
    for (j, &xj) in x.iter().enumerate() {
        axpy::<FMA>(-xj, &m[j * ld..j * ld + w], y);
    }
}

/// The AVX-512 body of [`gemv_sub_isa`].
///
/// # Safety
/// AVX-512F/DQ/VL and FMA; `m` holds `x.len()` rows of stride `ld >= y.len()`.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,fma")]
unsafe fn gemv_sub_avx512(x: &[f64], m: &[f64], ld: usize, y: &mut [f64]) {
    use std::arch::x86_64::*;
    let w = y.len();
    let mask = |c: usize| -> __mmask8 {
        if c >= w {
            0
        } else if w - c >= 8 {
            0xff
        } else {
            (1u8 << (w - c)) - 1
        }
    };
    let (pm, py) = (m.as_ptr(), y.as_mut_ptr());
    let mut c0 = 0;
    while c0 < w {
        let ks = [mask(c0), mask(c0 + 8), mask(c0 + 16), mask(c0 + 24)];
        // SAFETY: masked loads and stores touch only columns < w of rows < x.len(). The
        // pointers of fully masked-off vectors may lie past the end of `m` or `y`, so they
        // are formed with `wrapping_add` (never dereferenced), not `add`.
        unsafe {
            let mut acc: [__m512d; 4] =
                std::array::from_fn(|k| _mm512_maskz_loadu_pd(ks[k], py.wrapping_add(c0 + 8 * k)));
            for (j, &xj) in x.iter().enumerate() {
                let r = _mm512_set1_pd(xj);
                let row = pm.wrapping_add(j * ld + c0);
                for (k, a) in acc.iter_mut().enumerate() {
                    *a = _mm512_fnmadd_pd(
                        r,
                        _mm512_maskz_loadu_pd(ks[k], row.wrapping_add(8 * k)),
                        *a,
                    );
                }
            }
            for (k, a) in acc.iter().enumerate() {
                _mm512_mask_storeu_pd(py.wrapping_add(c0 + 8 * k), ks[k], *a);
            }
        }
        c0 += 32;
    }
}

/// `y[i] += alpha * x[i]` over the common length.
#[inline(always)]
pub fn axpy<const FMA: bool>(alpha: f64, x: &[f64], y: &mut [f64]) {
    let n = x.len().min(y.len());
    for (yi, xi) in y[..n].iter_mut().zip(&x[..n]) {
        *yi = fmadd::<FMA>(alpha, *xi, *yi);
    }
}

const LOG2E: f64 = std::f64::consts::LOG2_E;
const LN2_HI: f64 = 6.931_471_803_691_238e-1;
const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
/// 1.5 * 2^52: adding and subtracting it rounds a double of modest size to an integer.
const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;
/// 2^52: `(j + 2^52).to_bits()` holds the integer `j` in its low mantissa bits.
const TWO52: f64 = 4_503_599_627_370_496.0;

/// `1 / k!` for `k = 0..14`: the Taylor coefficients of `exp` both exponentials use.
const INV_FACTORIAL: [f64; 14] = [
    1.0,
    1.0,
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5040.0,
    1.0 / 40320.0,
    1.0 / 362880.0,
    1.0 / 3628800.0,
    1.0 / 39916800.0,
    1.0 / 479001600.0,
    1.0 / 6227020800.0,
];

/// `exp(x)` for `x <= 0`, branch-free so that it vectorises. Tested
/// (`tests::check_exp`, on every instruction set the CPU runs, with and without FMA):
/// relative error below 1e-15 against `f64::exp` at 200,000 points of [-700, 0], about
/// 4.5 ulp; the worst measured on AVX2+FMA and baseline x86-64 is 2.2e-16 (1 ulp), but
/// only the 1e-15 bound is enforced. Arguments below -700 are clamped (the result,
/// ~1e-304, is then not exact but far below any kernel value that matters).
#[inline(always)]
pub fn exp_nonpos<const FMA: bool>(x: f64) -> f64 {
    let x = x.max(-700.0);
    let kf = (x * LOG2E + ROUND_MAGIC) - ROUND_MAGIC;
    let r = fmadd::<FMA>(-kf, LN2_LO, fmadd::<FMA>(-kf, LN2_HI, x));
    // Taylor polynomial of degree 13 on |r| <= ln2/2: truncation error below 5e-18.
    const C: [f64; 14] = INV_FACTORIAL;
    let mut p = C[13];
    for i in (0..13).rev() {
        p = fmadd::<FMA>(p, r, C[i]);
    }
    let scale = f64::from_bits((kf + (TWO52 + 1023.0)).to_bits() << 52);
    p * scale
}

/// Positions in structure-of-arrays form, so kernel rows vectorise.
#[derive(Debug, Clone, Default)]
pub struct Points {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub floor: Vec<f64>,
}

impl Points {
    pub fn push(&mut self, p: &crate::gp::Point) {
        self.x.push(p.x);
        self.y.push(p.y);
        self.floor.push(p.floor as f64);
    }
    pub fn len(&self) -> usize {
        self.x.len()
    }
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
    /// Point `i` as the `(x, y, floor)` triple the kernel rows take.
    #[inline(always)]
    pub fn at(&self, i: usize) -> (f64, f64, f64) {
        (self.x[i], self.y[i], self.floor[i])
    }
    /// The coordinates of points `from..`, at most `len` of them (x, y, floor).
    pub fn tail(&self, from: usize, len: usize) -> (&[f64], &[f64], &[f64]) {
        let from = from.min(self.len());
        let n = (self.len() - from).min(len);
        (
            &self.x[from..from + n],
            &self.y[from..from + n],
            &self.floor[from..from + n],
        )
    }

    pub fn truncate(&mut self, n: usize) {
        self.x.truncate(n);
        self.y.truncate(n);
        self.floor.truncate(n);
    }
}

/// `out[j] = sf2 * exp(-|p - q_j| / ell)` on the same floor, 0 across floors.
#[inline(always)]
pub fn kernel_row<const FMA: bool>(
    sf2: f64,
    inv_ell: f64,
    p: (f64, f64, f64),
    q: &Points,
    out: &mut [f64],
) {
    kernel_row_from::<FMA>(sf2, inv_ell, p, q, 0, out)
}

/// [`kernel_row`] against the points of `q` from index `from` on.
#[inline(always)]
pub fn kernel_row_from<const FMA: bool>(
    sf2: f64,
    inv_ell: f64,
    p: (f64, f64, f64),
    q: &Points,
    from: usize,
    out: &mut [f64],
) {
    let (qx, qy, qf) = q.tail(from, out.len());
    let n = qx.len();
    for j in 0..n {
        let dx = p.0 - qx[j];
        let dy = p.1 - qy[j];
        let d = fmadd::<FMA>(dx, dx, dy * dy).sqrt();
        let v = sf2 * exp_nonpos::<FMA>(-d * inv_ell);
        out[j] = if qf[j] == p.2 { v } else { 0.0 };
    }
}

/// [`kernel_row_from`] with the instruction set chosen at run time: on AVX-512 the
/// hand-written [`kernel_row_avx512`], elsewhere the portable loop.
#[inline(always)]
pub fn kernel_row_isa<const FMA: bool>(
    isa: Isa,
    sf2: f64,
    inv_ell: f64,
    p: (f64, f64, f64),
    q: &Points,
    from: usize,
    out: &mut [f64],
) {
    #[cfg(target_arch = "x86_64")]
    if isa.kind() == IsaKind::Avx512 {
        // SAFETY: an `Isa` of kind `Avx512` exists only on a CPU with these features.
        unsafe { kernel_row_avx512(sf2, inv_ell, p, q, from, out) };
        return;
    }
    let _ = isa;
    kernel_row_from::<FMA>(sf2, inv_ell, p, q, from, out)
}

/// [`kernel_row_from`] written with AVX-512 intrinsics, for the dense whole-walk path
/// where kernel rows are a sizeable share of the time. Measured on this project's Zen 4
/// machine the portable loop is bound by the FMA pipes (the degree-13 polynomial of
/// [`exp_nonpos`]), while the square root runs on the divider beside them. So this
/// version keeps the hardware square root and shortens the exponential instead: the
/// argument is reduced by `ln 2 / 16` with a 16-entry table of `2^(j/16)` held in two
/// registers (`vpermt2pd`), which leaves `|r| <= ln 2 / 32` and a degree-7 polynomial
/// (truncation below 1.2e-18). Four vectors run side by side to hide latency, and a
/// row's tail is a masked vector, not scalar code. What is tested
/// (`tests::check_kernel_rows`, as for every instruction set): each value within
/// `8 eps (1 + d / ell)` relative of `sf2 * exp(-d / ell)` computed with `std`, i.e.
/// 8 eps for a point at the same place and up to about 150 eps for the farthest points
/// of the test (`d = 18 ell`), since `exp` multiplies the rounding error of its argument
/// by `d / ell`.
///
/// # Safety
/// The CPU must support AVX-512F/DQ/VL and FMA.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,fma")]
pub unsafe fn kernel_row_avx512(
    sf2: f64,
    inv_ell: f64,
    p: (f64, f64, f64),
    q: &Points,
    from: usize,
    out: &mut [f64],
) {
    use std::arch::x86_64::*;
    let (qx, qy, qf) = q.tail(from, out.len());
    let n = qx.len();
    /// Constants of one row, passed by reference so the helper stays small.
    #[derive(Clone, Copy)]
    struct Consts {
        px: __m512d,
        py: __m512d,
        pf: __m512d,
        neg_inv_ell: __m512d,
        lowest: __m512d,
        sixteen_log2e: __m512d,
        ln2_16_hi: __m512d,
        ln2_16_lo: __m512d,
        /// `sf2 * 2^(j/16)`, j = 0..8 and 8..16.
        t0: __m512d,
        t1: __m512d,
        c: [__m512d; 8],
    }
    // ln 2 / 16 split so that `k * LN2_16_HI` is exact for |k| < 2^20.
    const LN2_16_HI: f64 = LN2_HI / 16.0;
    const LN2_16_LO: f64 = LN2_LO / 16.0;
    // Degree 7 on |r| <= ln2/32: truncation error below 1.2e-18.
    const C: &[f64] = INV_FACTORIAL.split_at(8).0;
    let table: [f64; 16] = std::array::from_fn(|j| sf2 * (j as f64 / 16.0).exp2());
    // SAFETY: reading 8 doubles from each half of a 16-element array.
    let (t0, t1) = unsafe {
        (
            _mm512_loadu_pd(table.as_ptr()),
            _mm512_loadu_pd(table.as_ptr().add(8)),
        )
    };
    let consts = Consts {
        px: _mm512_set1_pd(p.0),
        py: _mm512_set1_pd(p.1),
        pf: _mm512_set1_pd(p.2),
        neg_inv_ell: _mm512_set1_pd(-inv_ell),
        lowest: _mm512_set1_pd(-700.0),
        sixteen_log2e: _mm512_set1_pd(16.0 * LOG2E),
        ln2_16_hi: _mm512_set1_pd(LN2_16_HI),
        ln2_16_lo: _mm512_set1_pd(LN2_16_LO),
        t0,
        t1,
        c: std::array::from_fn(|i| _mm512_set1_pd(C[i])),
    };
    /// Eight kernel values for the lanes in `m` (the others are 0).
    #[inline(always)]
    unsafe fn lanes(
        ptrs: (*const f64, *const f64, *const f64),
        m: __mmask8,
        k: &Consts,
    ) -> __m512d {
        // SAFETY: masked loads touch only the lanes in `m` (caller).
        unsafe {
            let dx = _mm512_sub_pd(k.px, _mm512_maskz_loadu_pd(m, ptrs.0));
            let dy = _mm512_sub_pd(k.py, _mm512_maskz_loadu_pd(m, ptrs.1));
            let same = _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(k.pf, _mm512_maskz_loadu_pd(m, ptrs.2));
            let d = _mm512_sqrt_pd(_mm512_fmadd_pd(dx, dx, _mm512_mul_pd(dy, dy)));
            let x = _mm512_max_pd(_mm512_mul_pd(d, k.neg_inv_ell), k.lowest);
            // x = (16 e + j) ln2/16 + r: exp(x) = 2^e * 2^(j/16) * exp(r).
            let kf = _mm512_roundscale_pd::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(
                _mm512_mul_pd(x, k.sixteen_log2e),
            );
            let r = _mm512_fnmadd_pd(kf, k.ln2_16_lo, _mm512_fnmadd_pd(kf, k.ln2_16_hi, x));
            let ki = _mm512_cvtpd_epi64(kf);
            // The low four bits of each index pick the table entry (two's complement,
            // so they are j = k mod 16 also for negative k); the shift floors k / 16.
            let tab = _mm512_permutex2var_pd(k.t0, ki, k.t1);
            let e = _mm512_cvtepi64_pd(_mm512_srai_epi64::<4>(ki));
            let mut poly = k.c[7];
            for i in (0..7).rev() {
                poly = _mm512_fmadd_pd(poly, r, k.c[i]);
            }
            let v = _mm512_scalef_pd(_mm512_mul_pd(poly, tab), e);
            _mm512_maskz_mov_pd(same, v)
        }
    }
    let at = |j: usize| {
        // SAFETY: j <= n, the slices' length (pointers one past the end are allowed).
        unsafe { (qx.as_ptr().add(j), qy.as_ptr().add(j), qf.as_ptr().add(j)) }
    };
    let o = out.as_mut_ptr();
    let mut j = 0;
    while j + 32 <= n {
        // SAFETY: lanes j..j + 32 are within the row.
        unsafe {
            let v0 = lanes(at(j), 0xff, &consts);
            let v1 = lanes(at(j + 8), 0xff, &consts);
            let v2 = lanes(at(j + 16), 0xff, &consts);
            let v3 = lanes(at(j + 24), 0xff, &consts);
            _mm512_storeu_pd(o.add(j), v0);
            _mm512_storeu_pd(o.add(j + 8), v1);
            _mm512_storeu_pd(o.add(j + 16), v2);
            _mm512_storeu_pd(o.add(j + 24), v3);
        }
        j += 32;
    }
    while j < n {
        let m: __mmask8 = if n - j >= 8 {
            0xff
        } else {
            (1u8 << (n - j)) - 1
        };
        // SAFETY: masked loads and stores touch only lanes j..min(j + 8, n).
        unsafe { _mm512_mask_storeu_pd(o.add(j), m, lanes(at(j), m, &consts)) };
        j += 8;
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The per-instruction-set tests (`utility::isa_tests`) are ignored where the CPU
    /// lacks that instruction set, which the build script decides from the CPU that built
    /// the tests. Running them on a CPU that disagrees (a target directory copied to
    /// another machine) would make `cargo test` report the wrong ones: this says so.
    #[test]
    #[cfg_attr(miri, ignore = "Miri detects no instruction set beyond the baseline")]
    fn supported_lists_the_detected_isa_first_and_always_generic() {
        let all = Isa::supported();
        println!("instruction sets tested on this CPU: {all:?}");
        println!("kernel variants tested (isa, fma): {:?}", test_variants());
        assert_eq!(all[0], Isa::detect());
        assert_eq!(all.last(), Some(&Isa::generic()));
        assert_eq!(Isa::generic().fma(), cfg!(target_arch = "aarch64"));
        let has = |k: IsaKind| all.iter().any(|i| i.kind() == k);
        for (kind, built_with) in [
            (IsaKind::Avx512, cfg!(trailprint_cpu_avx512)),
            (IsaKind::Avx2Fma, cfg!(trailprint_cpu_avx2_fma)),
        ] {
            assert_eq!(
                has(kind),
                built_with,
                "{kind:?}: this CPU {} it, the CPU that built the tests {}; rebuild them here \
                 (cargo clean -p trailprint-core) so the per-ISA tests run or skip correctly",
                if has(kind) { "has" } else { "lacks" },
                if built_with { "had" } else { "did not" },
            );
        }
    }

    /// Every feature an AVX-512 function enables is required before `Avx512` is chosen:
    /// a CPU with AVX-512F and DQ but not VL (LLVM may emit VL's EVEX-encoded 128/256-bit
    /// forms in those functions) gets the AVX2 build.
    #[test]
    fn avx512_needs_f_dq_vl_and_fma() {
        let all = Features {
            avx512f: true,
            avx512dq: true,
            avx512vl: true,
            avx2: true,
            fma: true,
        };
        let kinds = |f: Features| f.allowed();
        if cfg!(target_arch = "x86_64") {
            use IsaKind::*;
            assert_eq!(kinds(all), vec![Avx512, Avx2Fma, Generic]);
            for missing in 0..3 {
                let mut f = all;
                match missing {
                    0 => f.avx512f = false,
                    1 => f.avx512dq = false,
                    _ => f.avx512vl = false,
                }
                assert_eq!(kinds(f), vec![Avx2Fma, Generic], "{f:?}");
            }
            assert_eq!(kinds(Features { fma: false, ..all }), vec![Generic]);
            assert_eq!(kinds(Features { avx2: false, ..all }), vec![Generic]);
            assert_eq!(kinds(Features::default()), vec![Generic]);
        } else {
            assert_eq!(kinds(all), vec![IsaKind::Generic]);
        }
    }

    /// Kernel rows against `sf2 * exp(-d / ell)` from `std`, within
    /// `8 eps (1 + d / ell)` relative: `exp` turns a relative error of its argument into
    /// one `|x|` times larger, so far points get a looser bound (about 150 eps at
    /// `d = 18 ell`, the farthest point here).
    pub(crate) fn check_kernel_rows(v: (Isa, bool)) {
        let mut q = Points::default();
        for i in 0..203 {
            let t = i as f64;
            q.push(&crate::gp::Point {
                x: (t * 0.731).sin() * 40.0,
                y: (t * 0.377).cos() * 25.0,
                floor: i64::from(i % 7 == 0),
            });
        }
        let (sf2, ell) = (151.0, 22.7);
        let isa = v.0;
        // Includes a point equal to one of q (distance 0) and far points (tiny values).
        for (p, from) in [
            ((0.0, 25.0, 0.0), 0),
            ((3.5, -2.0, 1.0), 5),
            ((400.0, 0.0, 0.0), 11),
        ] {
            for len in [0, 1, 7, 8, 9, 64, 197] {
                let mut got = vec![-1.0; len + 3];
                on_variant(
                    v,
                    &mut got[..len],
                    |o| kernel_row_isa::<false>(isa, sf2, 1.0 / ell, p, &q, from, o),
                    |o| kernel_row_isa::<true>(isa, sf2, 1.0 / ell, p, &q, from, o),
                );
                let count = len.min(q.len() - from);
                for (j, &g) in got.iter().enumerate().take(count) {
                    let k = from + j;
                    let d = (p.0 - q.x[k]).hypot(p.1 - q.y[k]);
                    let want = if q.floor[k] == p.2 {
                        sf2 * (-d / ell).exp()
                    } else {
                        0.0
                    };
                    let tol = 8.0 * f64::EPSILON * (1.0 + d / ell) * want;
                    assert!((g - want).abs() <= tol, "{v:?} j={j}: {g} vs {want}");
                }
                assert!(
                    got[count..].iter().all(|&x| x == -1.0),
                    "{v:?}: wrote past the row"
                );
            }
        }
    }

    /// The bound `docs/decisions/0001-own-kernels.md` quotes: relative error below 1e-15
    /// (about 4.5 ulp of 2^-52) against `f64::exp` at 200,000 points of [-700, 0].
    /// Returns the worst relative error seen.
    pub(crate) fn check_exp(v: (Isa, bool)) -> f64 {
        let xs: Vec<f64> = (0..200_000).map(|i| -(i as f64) * 0.0035).collect();
        let got: Vec<f64> = on_variant(
            v,
            &xs,
            |xs| xs.iter().map(|&x| exp_nonpos::<false>(x)).collect(),
            |xs| xs.iter().map(|&x| exp_nonpos::<true>(x)).collect(),
        );
        let mut worst: f64 = 0.0;
        for (&x, &g) in xs.iter().zip(&got) {
            worst = worst.max((g - x.exp()).abs() / x.exp());
        }
        assert!(
            worst < 1e-15,
            "{v:?}: exp_nonpos worst relative error {worst}"
        );
        assert_eq!(got[0], 1.0, "{v:?}: exp(0)");
        worst
    }

    /// [`dot_isa`] (the engine's dispatching dot product) against a naive sum, every
    /// length from 0 to 69 (full chunks, ragged tails).
    pub(crate) fn check_dot_isa(v: (Isa, bool)) {
        let isa = v.0;
        for n in 0..70 {
            let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
            let naive: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let got = on_variant(
                v,
                (),
                |_| dot_isa::<false>(isa, &a, &b),
                |_| dot_isa::<true>(isa, &a, &b),
            );
            assert!((got - naive).abs() < 1e-12, "{v:?} n={n}");
        }
    }

    /// [`gemv_sub_isa`] against axpys written out, at widths around the chunk sizes.
    pub(crate) fn check_gemv_sub(v: (Isa, bool)) {
        let isa = v.0;
        for w in [0usize, 1, 7, 8, 9, 31, 32, 33, 61, 70] {
            for rows in [0usize, 1, 5, 40] {
                let ld = w + 3;
                let m: Vec<f64> = (0..rows * ld).map(|i| (i as f64 * 0.13).sin()).collect();
                let x: Vec<f64> = (0..rows).map(|i| (i as f64 * 0.7).cos()).collect();
                let y0: Vec<f64> = (0..w).map(|i| i as f64 * 0.25).collect();
                let want: Vec<f64> = (0..w)
                    .map(|c| y0[c] - (0..rows).map(|j| x[j] * m[j * ld + c]).sum::<f64>())
                    .collect();
                let mut y = y0.clone();
                on_variant(
                    v,
                    &mut y,
                    |y| gemv_sub_isa::<false>(isa, &x, &m, ld, y),
                    |y| gemv_sub_isa::<true>(isa, &x, &m, ld, y),
                );
                for c in 0..w {
                    assert!(
                        (y[c] - want[c]).abs() < 1e-12,
                        "{v:?} w={w} rows={rows} c={c}"
                    );
                }
            }
        }
    }

    /// The generic [`dot`] and [`axpy`] compiled for this instruction set, against naive
    /// sums at every length from 0 to 69.
    pub(crate) fn check_dot_and_axpy(v: (Isa, bool)) {
        for n in 0..70 {
            let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
            let naive: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let d = on_variant(v, (), |_| dot::<false>(&a, &b), |_| dot::<true>(&a, &b));
            assert!((d - naive).abs() < 1e-12, "{v:?} n={n}");
            let mut y = b.clone();
            on_variant(
                v,
                &mut y,
                |y| axpy::<false>(2.0, &a, y),
                |y| axpy::<true>(2.0, &a, y),
            );
            for i in 0..n {
                assert!(
                    (y[i] - (b[i] + 2.0 * a[i])).abs() < 1e-15,
                    "{v:?} n={n} i={i}"
                );
            }
        }
    }
}
