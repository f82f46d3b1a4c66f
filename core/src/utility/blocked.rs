//! Blocked dense kernels for adding many observations to a factor at once.
//!
//! All matrices here are row-major and symmetric ones keep their *upper* triangle, so
//! that a Cholesky factor `U` (with `U^T U = S`) is stored row by row and every update
//! is an `axpy` along a contiguous row. Updates are applied [`BLOCK`] rows at a time
//! ([`update_block`]): each element of the destination is loaded and stored once per
//! block instead of once per row, which keeps the loops compute-bound on AVX-512 rather
//! than bound by L2 bandwidth (a 300 x 300 matrix does not fit in L1).

use super::simd;

/// Rows applied per update pass.
pub const BLOCK: usize = 8;

/// The first `n` entries of each of the [`BLOCK`] rows `srcs`, as an array of slices
/// whose lengths the compiler knows are `n`, so that the loops of [`update_block`] and
/// [`update_block4`] over `0..n` run without bounds checks.
#[inline(always)]
fn heads<'a>(srcs: &[&'a [f64]], n: usize) -> [&'a [f64]; BLOCK] {
    [
        &srcs[0][..n],
        &srcs[1][..n],
        &srcs[2][..n],
        &srcs[3][..n],
        &srcs[4][..n],
        &srcs[5][..n],
        &srcs[6][..n],
        &srcs[7][..n],
    ]
}

/// `dst[j] -= sum_t coeffs[t] * srcs[t][j]` for `t < coeffs.len() <= BLOCK`.
#[inline(always)]
pub fn update_block<const FMA: bool>(dst: &mut [f64], coeffs: &[f64], srcs: &[&[f64]]) {
    let n = dst.len();
    if coeffs.len() == BLOCK && srcs.len() == BLOCK && srcs.iter().all(|s| s.len() >= n) {
        let c: [f64; BLOCK] = [
            coeffs[0], coeffs[1], coeffs[2], coeffs[3], coeffs[4], coeffs[5], coeffs[6], coeffs[7],
        ];
        let s = heads(srcs, n);
        for j in 0..n {
            let mut acc = dst[j];
            for t in 0..BLOCK {
                acc = fma::<FMA>(-c[t], s[t][j], acc);
            }
            dst[j] = acc;
        }
    } else {
        for (c, s) in coeffs.iter().zip(srcs) {
            simd::axpy::<FMA>(-c, s, dst);
        }
    }
}

/// Four destination rows at once sharing the [`BLOCK`] source rows:
/// `d[r][j] -= sum_t c[r][t] * s[t][j]`. Each source element loaded feeds four FMAs, so
/// the loop is bound by arithmetic, not by loads. All rows of `d` have the same length
/// and every source is at least that long.
#[inline(always)]
pub fn update_block4<const FMA: bool>(
    d: [&mut [f64]; 4],
    c: &[[f64; BLOCK]; 4],
    s: &[&[f64]; BLOCK],
) {
    let [d0, d1, d2, d3] = d;
    let n = d0.len().min(d1.len()).min(d2.len()).min(d3.len());
    let (d0, d1, d2, d3) = (&mut d0[..n], &mut d1[..n], &mut d2[..n], &mut d3[..n]);
    let s = heads(s, n);
    for j in 0..n {
        let (mut a0, mut a1, mut a2, mut a3) = (d0[j], d1[j], d2[j], d3[j]);
        for t in 0..BLOCK {
            let v = s[t][j];
            a0 = fma::<FMA>(-c[0][t], v, a0);
            a1 = fma::<FMA>(-c[1][t], v, a1);
            a2 = fma::<FMA>(-c[2][t], v, a2);
            a3 = fma::<FMA>(-c[3][t], v, a3);
        }
        d0[j] = a0;
        d1[j] = a1;
        d2[j] = a2;
        d3[j] = a3;
    }
}

#[inline(always)]
fn fma<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA { a.mul_add(b, c) } else { a * b + c }
}

/// In-place Cholesky `U^T U = S` of the upper triangle of a row-major `n x n` matrix
/// (entries below the diagonal are neither read nor written). Returns `ln det S`, or
/// `None` if `S` is not positive definite.
#[inline(always)]
pub fn cholesky_upper<const FMA: bool>(a: &mut [f64], n: usize) -> Option<f64> {
    let mut logdet = 0.0;
    let mut k0 = 0;
    while k0 < n {
        let kb = BLOCK.min(n - k0);
        // Factor the panel rows k0..k0+kb among themselves (earlier panels are applied).
        for k in k0..k0 + kb {
            for kp in k0..k {
                let (head, tail) = a.split_at_mut(k * n);
                let c = head[kp * n + k];
                simd::axpy::<FMA>(-c, &head[kp * n + k..kp * n + n], &mut tail[k..n]);
            }
            let d2 = a[k * n + k];
            if d2.is_nan() || d2 <= 0.0 || !d2.is_finite() {
                return None;
            }
            let d = d2.sqrt();
            logdet += d2.ln();
            a[k * n + k] = d;
            let inv = 1.0 / d;
            for x in &mut a[k * n + k + 1..k * n + n] {
                *x *= inv;
            }
        }
        // Trailing update of the rows below the panel: a rank-kb update by its rows.
        let end = k0 + kb;
        let (panel, rest) = a.split_at_mut(end * n);
        rank_update_upper::<FMA>(rest, &panel[k0 * n..], n, end, n - end, kb);
        k0 = end;
    }
    Some(logdet)
}

/// Solves `U^T X = B` in place for `B` with `m` rows of width `w` (row-major), `U` the
/// upper Cholesky factor of an `m x m` matrix as left by [`cholesky_upper`].
#[inline(always)]
pub fn solve_upper_transposed<const FMA: bool>(u: &[f64], m: usize, b: &mut [f64], w: usize) {
    let mut k0 = 0;
    while k0 < m {
        let kb = BLOCK.min(m - k0);
        for k in k0..k0 + kb {
            for kp in k0..k {
                let (head, tail) = b.split_at_mut(k * w);
                simd::axpy::<FMA>(-u[kp * m + k], &head[kp * w..kp * w + w], &mut tail[..w]);
            }
            let inv = 1.0 / u[k * m + k];
            for x in &mut b[k * w..k * w + w] {
                *x *= inv;
            }
        }
        let end = k0 + kb;
        let (done, rest) = b.split_at_mut(end * w);
        let mut i = end;
        if kb == BLOCK {
            let mut srcs: [&[f64]; BLOCK] = [&[]; BLOCK];
            for (t, o) in srcs.iter_mut().enumerate() {
                *o = &done[(k0 + t) * w..(k0 + t) * w + w];
            }
            while i + 4 <= m {
                let mut c = [[0.0; BLOCK]; 4];
                for (r, cr) in c.iter_mut().enumerate() {
                    for (t, x) in cr.iter_mut().enumerate() {
                        *x = u[(k0 + t) * m + i + r];
                    }
                }
                let base = |r: usize| (i + r - end) * w;
                let Ok(rows) = rest.get_disjoint_mut([
                    base(0)..base(0) + w,
                    base(1)..base(1) + w,
                    base(2)..base(2) + w,
                    base(3)..base(3) + w,
                ]) else {
                    break;
                };
                update_block4::<FMA>(rows, &c, &srcs);
                i += 4;
            }
        }
        for i in i..m {
            let mut coeffs = [0.0; BLOCK];
            let mut srcs: [&[f64]; BLOCK] = [&[]; BLOCK];
            for (t, k) in (k0..end).enumerate() {
                coeffs[t] = u[k * m + i];
                srcs[t] = &done[k * w..k * w + w];
            }
            update_block::<FMA>(
                &mut rest[(i - end) * w..(i - end) * w + w],
                &coeffs[..kb],
                &srcs[..kb],
            );
        }
        k0 = end;
    }
}

/// `S -= sum_i r_i^T r_i` on the upper triangle of a row-major `n x n` matrix, for the
/// `rows` rows `r_i` of width `n` in `r`.
#[inline(always)]
pub fn syrk_upper_sub<const FMA: bool>(s: &mut [f64], n: usize, r: &[f64], rows: usize) {
    let mut i0 = 0;
    while i0 < rows {
        let ib = BLOCK.min(rows - i0);
        rank_update_upper::<FMA>(s, &r[i0 * n..], n, 0, n, ib);
        i0 += ib;
    }
}

/// `T -= R^T R` on the upper triangle of an `m x m` block `T`, for `kb <= BLOCK` rows `R`
/// of width `m`: the one rank-`kb` update behind both the Cholesky's trailing update (`R`
/// the panel's rows, `T` the rows below it) and [`syrk_upper_sub`]. Both are row-major with
/// leading dimension `ld` and start at column `col0`: `T(a, b)` is `t[a * ld + col0 + b]`
/// and `R(q, b)` is `r[q * ld + col0 + b]`. With a full block, four rows of `T` at a time
/// share each load of `R` ([`update_block4`]), after the small triangle in front of their
/// common column range.
#[inline(always)]
fn rank_update_upper<const FMA: bool>(
    t: &mut [f64],
    r: &[f64],
    ld: usize,
    col0: usize,
    m: usize,
    kb: usize,
) {
    let ti = |a: usize| a * ld + col0;
    let ri = |q: usize| q * ld + col0;
    let mut a0 = 0;
    if kb == BLOCK {
        let srcs_at = |b: usize| -> [&[f64]; BLOCK] {
            let mut out: [&[f64]; BLOCK] = [&[]; BLOCK];
            for (q, o) in out.iter_mut().enumerate() {
                *o = &r[ri(q) + b..ri(q) + m];
            }
            out
        };
        while a0 + 4 <= m {
            let mut c = [[0.0; BLOCK]; 4];
            for (k, ck) in c.iter_mut().enumerate() {
                for (q, x) in ck.iter_mut().enumerate() {
                    *x = r[ri(q) + a0 + k];
                }
            }
            for k in 0..3 {
                let row = &mut t[ti(a0 + k) + a0 + k..ti(a0 + k) + a0 + 3];
                update_block::<FMA>(row, &c[k], &srcs_at(a0 + k));
            }
            let Ok(rows) = t.get_disjoint_mut([
                ti(a0) + a0 + 3..ti(a0) + m,
                ti(a0 + 1) + a0 + 3..ti(a0 + 1) + m,
                ti(a0 + 2) + a0 + 3..ti(a0 + 2) + m,
                ti(a0 + 3) + a0 + 3..ti(a0 + 3) + m,
            ]) else {
                break;
            };
            update_block4::<FMA>(rows, &c, &srcs_at(a0 + 3));
            a0 += 4;
        }
    }
    for a in a0..m {
        let mut coeffs = [0.0; BLOCK];
        let mut srcs: [&[f64]; BLOCK] = [&[]; BLOCK];
        for q in 0..kb {
            coeffs[q] = r[ri(q) + a];
            srcs[q] = &r[ri(q) + a..ri(q) + m];
        }
        update_block::<FMA>(&mut t[ti(a) + a..ti(a) + m], &coeffs[..kb], &srcs[..kb]);
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::utility::simd::{Isa, on_variant};

    fn spd(n: usize) -> Vec<f64> {
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] =
                    (-((i as f64 - j as f64).abs()) / 7.0).exp() + if i == j { 0.5 } else { 0.0 };
            }
        }
        a
    }

    /// The blocked Cholesky factor, its log-determinant and the triangular solve against
    /// nalgebra at sizes around the block width; the rank update against the Gram matrix
    /// written out; a matrix that is not positive definite reported as such.
    pub(crate) fn check(isa: (Isa, bool)) {
        for n in [1, 2, 7, 8, 9, 17, 40] {
            let a = spd(n);
            let m = nalgebra::DMatrix::from_row_slice(n, n, &a);
            let chol = m.clone().cholesky().expect("pd");
            let l = chol.l();
            let mut u = a.clone();
            let ld = on_variant(
                isa,
                &mut u,
                |u| cholesky_upper::<false>(u, n),
                |u| cholesky_upper::<true>(u, n),
            )
            .expect("pd");
            assert!(
                (ld - chol.ln_determinant()).abs() < 1e-10 * ld.abs().max(1.0),
                "{isa:?} n={n}"
            );
            for i in 0..n {
                for j in i..n {
                    assert!(
                        (u[i * n + j] - l[(j, i)]).abs() < 1e-12,
                        "{isa:?} n={n} ({i},{j})"
                    );
                }
            }
            // Solve U^T X = B against nalgebra.
            let w = 3;
            let b: Vec<f64> = (0..n * w).map(|i| (i as f64 * 0.3).sin()).collect();
            let mut x = b.clone();
            on_variant(
                isa,
                &mut x,
                |x| solve_upper_transposed::<false>(&u, n, x, w),
                |x| solve_upper_transposed::<true>(&u, n, x, w),
            );
            let bm = nalgebra::DMatrix::from_row_slice(n, w, &b);
            let xm = l.solve_lower_triangular(&bm).expect("solve");
            for i in 0..n {
                for c in 0..w {
                    assert!((x[i * w + c] - xm[(i, c)]).abs() < 1e-11, "{isa:?} n={n}");
                }
            }
        }

        let (n, rows) = (11, 13);
        let r: Vec<f64> = (0..rows * n).map(|i| (i as f64 * 0.7).cos()).collect();
        let mut s = vec![0.0; n * n];
        on_variant(
            isa,
            &mut s,
            |s| syrk_upper_sub::<false>(s, n, &r, rows),
            |s| syrk_upper_sub::<true>(s, n, &r, rows),
        );
        for a in 0..n {
            for b in a..n {
                let g: f64 = (0..rows).map(|i| r[i * n + a] * r[i * n + b]).sum();
                assert!((s[a * n + b] + g).abs() < 1e-12, "{isa:?} syrk ({a},{b})");
            }
        }

        let mut a = vec![1.0, 2.0, 2.0, 1.0];
        let r = on_variant(
            isa,
            &mut a,
            |a| cholesky_upper::<false>(a, 2),
            |a| cholesky_upper::<true>(a, 2),
        );
        assert!(r.is_none(), "{isa:?}: indefinite matrix not reported");
    }
}
