//! The few numeric kernels the utility engine spends its time in, written so that LLVM
//! vectorises them, and compiled three times: AVX-512, AVX2+FMA and baseline x86-64 (or
//! whatever the target is). [`Isa::detect`] picks one at run time, once per engine.
//!
//! Why not nalgebra here: the engine grows a Cholesky factor one row at a time (each walk
//! extension appends its samples), which is a sequence of short dot products and axpys on
//! packed rows. nalgebra's dense routines work on whole matrices and are compiled for the
//! baseline target, so they neither reuse a factor prefix nor use AVX-512. The kernels
//! below are plain loops over fixed-width chunks; `mul_add` is used only under a
//! `target_feature` that makes it a single FMA instruction.

/// The instruction set a computation is dispatched to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Isa {
    Avx512,
    Avx2Fma,
    Generic,
}

impl Isa {
    /// The best instruction set this CPU supports.
    pub fn detect() -> Isa {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512dq")
                && std::arch::is_x86_feature_detected!("fma")
            {
                return Isa::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                return Isa::Avx2Fma;
            }
        }
        Isa::Generic
    }
}

#[inline(always)]
fn fmadd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA { a.mul_add(b, c) } else { a * b + c }
}

/// `sum a[i] * b[i]` over the common length.
#[inline(always)]
pub fn dot<const FMA: bool>(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 16];
    let mut ca = a.chunks_exact(16);
    let mut cb = b.chunks_exact(16);
    for (x, y) in (&mut ca).zip(&mut cb) {
        for i in 0..16 {
            acc[i] = fmadd::<FMA>(x[i], y[i], acc[i]);
        }
    }
    let (ra, rb) = (ca.remainder(), cb.remainder());
    let mut i = 0;
    while i + 4 <= ra.len() {
        for k in 0..4 {
            acc[k] = fmadd::<FMA>(ra[i + k], rb[i + k], acc[k]);
        }
        i += 4;
    }
    let mut tail = 0.0;
    while i < ra.len() {
        tail = fmadd::<FMA>(ra[i], rb[i], tail);
        i += 1;
    }
    let mut s = [0.0f64; 4];
    for k in 0..4 {
        s[k] = (acc[k] + acc[k + 4]) + (acc[k + 8] + acc[k + 12]);
    }
    (s[0] + s[1]) + (s[2] + s[3]) + tail
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

/// `exp(x)` for `x <= 0` to about 1 ulp, branch-free so that it vectorises. Arguments
/// below -700 are clamped (the result, ~1e-304, is then not exact but far below any
/// kernel value that matters).
#[inline(always)]
pub fn exp_nonpos<const FMA: bool>(x: f64) -> f64 {
    let x = x.max(-700.0);
    let kf = (x * LOG2E + ROUND_MAGIC) - ROUND_MAGIC;
    let r = fmadd::<FMA>(-kf, LN2_LO, fmadd::<FMA>(-kf, LN2_HI, x));
    // Taylor polynomial of degree 13 on |r| <= ln2/2: truncation error below 5e-18.
    const C: [f64; 14] = [
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
    let from = from.min(q.len());
    let n = (q.len() - from).min(out.len());
    let (qx, qy, qf) = (
        &q.x[from..from + n],
        &q.y[from..from + n],
        &q.floor[from..from + n],
    );
    for j in 0..n {
        let dx = p.0 - qx[j];
        let dy = p.1 - qy[j];
        let d = fmadd::<FMA>(dx, dx, dy * dy).sqrt();
        let v = sf2 * exp_nonpos::<FMA>(-d * inv_ell);
        out[j] = if qf[j] == p.2 { v } else { 0.0 };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_matches_std_to_a_few_ulp() {
        let mut worst: f64 = 0.0;
        for i in 0..200_000 {
            let x = -(i as f64) * 0.0035;
            let rel = (exp_nonpos::<false>(x) - x.exp()).abs() / x.exp();
            worst = worst.max(rel);
        }
        assert!(worst < 1e-15, "worst relative error {worst}");
        assert_eq!(exp_nonpos::<false>(0.0), 1.0);
    }

    #[test]
    fn dot_and_axpy_match_naive_sums_for_every_length() {
        for n in 0..70 {
            let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
            let naive: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            assert!((dot::<false>(&a, &b) - naive).abs() < 1e-12);
            let mut y = b.clone();
            axpy::<false>(2.0, &a, &mut y);
            for i in 0..n {
                assert!((y[i] - (b[i] + 2.0 * a[i])).abs() < 1e-15);
            }
        }
    }
}
