//! One dense Cholesky factorisation of everything a whole walk needs, built around a
//! register-tiled micro-kernel.
//!
//! # What it computes
//! The observations `S = D ∪ R` (prior, then the walk's samples) and the vertices `V` form
//! one joint covariance, ordered `[D, R, V]`:
//!
//! ```text
//! J = | K_SS + N_S   K_SV          |
//!     | K_VS         K_VV + sn2 I  |
//! ```
//!
//! Its upper Cholesky factor `U` (`U^T U = J`) ends in the factor of the Schur complement
//! of `V`, which is exactly the posterior covariance `Sigma = A - K_VS (K_SS + N_S)^-1 K_SV`
//! of SPEC section 3. So `ln det Sigma` is the sum of `2 ln U_ii` over the `V` rows, and
//! `f_D = (ln det A - ln det Sigma) / 2` costs one factorisation of `|D| + |R| + |V|` rows,
//! about `N^3 / 6` fused multiply-adds, and nothing else.
//!
//! # Why it is fast
//! The factorisation is left-looking, eight rows at a time. The update of an `8 x 16`
//! tile by all rows above it, `C -= U[..k0, rows]^T U[..k0, cols]`, runs over the whole
//! depth `k0` with the tile held in sixteen AVX-512 registers: per row of `U` read, two
//! vector loads and eight broadcasts feed sixteen FMAs, so the loop runs at the FMA
//! port's rate rather than at the cache's. The triangular solve of the tile against the
//! block's own `8 x 8` diagonal factor is done in the same registers before the single
//! store. Measured on area-two (`examples/engine_timing.rs` against `examples/fma_peak.rs`)
//! the factorisation runs at about 90% of the core's FMA peak; see
//! `docs/decisions/0002-dense-micro-kernel.md`.
//!
//! # Storage
//! Row-major, leading dimension [`Layout::ld`], only the upper triangle meaningful. The
//! columns from `n` to `ld` are zero (tiles may run over the end of a row), and there are
//! eight spare rows after the last (a final block of fewer than eight rows is computed as
//! a whole tile; its spare rows are never stored to nor read from as results).

use super::simd::Isa;

/// Rows per block (the tile height).
const MR: usize = 8;

/// Sizes of one dense problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Number of rows and columns of the joint matrix.
    pub n: usize,
    /// Leading dimension (row stride), at least `n + 16` and a multiple of 8.
    pub ld: usize,
}

impl Layout {
    pub fn new(n: usize) -> Layout {
        Layout {
            n,
            ld: (n + 16).div_ceil(8) * 8,
        }
    }

    /// Length of the buffer a matrix of this layout needs.
    pub fn len(&self) -> usize {
        (self.n + MR) * self.ld
    }

    /// Whether the matrix has no rows.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
}

/// Factors the matrix in `a` in place (upper triangle, as described in the module
/// documentation) and returns `sum_{i >= logdet_from} ln U_ii^2`, the log-determinant of
/// the Schur complement of rows `logdet_from..n`; `None` if the matrix is not positive
/// definite. The columns `n..ld` of every row must be zero.
pub fn factor(isa: Isa, a: &mut [f64], layout: Layout, logdet_from: usize) -> Option<f64> {
    factor_after(isa, a, layout, 0, logdet_from)
}

/// Multiple of which [`factor_after`]'s already factored block must be: the block height
/// (a panel of the large-matrix path may be partly known). The engine's S side reuses
/// the factor of all but at most seven of its vertices: on the 565-vertex mall, 560
/// rows instead of the 512 a step of 64 kept, which left 53 rows of `A` to refactor and
/// their triangular solve with every walk (a quarter of a person's 509 m walk's cost).
pub const KNOWN_STEP: usize = MR;

/// [`factor`] of a matrix whose leading `known x known` block is already factored: rows
/// `..known` hold their factor in columns `..known` (upper triangle; the leading block of
/// a Cholesky factor is the factor of the leading block), and the raw matrix elsewhere.
/// Only the rest is computed, which saves `known^3 / 6` fused multiply-adds: the engine's
/// "S side" form puts the vertices first, whose factor is the same for every walk.
/// `known` is a multiple of [`KNOWN_STEP`] and at most `n`; the log-determinant counts the
/// rows from `logdet_from` as in [`factor`] (known rows included, from their diagonal).
pub fn factor_after(
    isa: Isa,
    a: &mut [f64],
    layout: Layout,
    known: usize,
    logdet_from: usize,
) -> Option<f64> {
    let job = Job {
        known,
        logdet_from,
        blocked_from: CHUNK_FROM,
    };
    factor_checked(isa, a, layout, job)
}

/// [`factor_after`] of `job`, which also says from how many rows on the large-matrix
/// path (panels, packed depth chunks) is taken: [`CHUNK_FROM`] in use; the tests pass
/// smaller values to check that path on matrices small enough for Miri.
fn factor_checked(isa: Isa, a: &mut [f64], layout: Layout, job: Job) -> Option<f64> {
    let known = job.known;
    assert!(a.len() >= layout.len(), "dense buffer too short");
    assert!(
        layout.ld >= layout.n + 16 && layout.ld.is_multiple_of(8),
        "bad leading dimension"
    );
    assert!(
        known <= layout.n && known.is_multiple_of(KNOWN_STEP),
        "bad known block"
    );
    match isa.kind() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: an `Isa` of kind `Avx512` exists only on a CPU with AVX-512F/DQ/VL and
        // FMA (`Isa::detect`, `Isa::supported`); the buffer bounds were checked above and
        // every access stays within `layout.len()`.
        super::simd::IsaKind::Avx512 => unsafe { factor_avx512(a, layout, job) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above, for AVX2 and FMA.
        super::simd::IsaKind::Avx2Fma => unsafe { factor_avx2(a, layout, job) },
        // SAFETY: bounds checked above; the portable build fuses multiply-adds where the
        // base instruction set has them (aarch64).
        _ => unsafe {
            factor_with::<Plain<{ super::simd::GENERIC_FMA }>>(a, layout, job, Some(strip_generic))
        },
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,fma")]
unsafe fn factor_avx512(a: &mut [f64], layout: Layout, job: Job) -> Option<f64> {
    // SAFETY: forwarded from `factor_after`.
    unsafe { factor_with::<std::arch::x86_64::__m512d>(a, layout, job, Some(strip_avx512)) }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn factor_avx2(a: &mut [f64], layout: Layout, job: Job) -> Option<f64> {
    // SAFETY: forwarded from `factor_after`.
    unsafe { factor_with::<Plain<true>>(a, layout, job, Some(strip_avx2)) }
}

/// What one factorisation is asked: the leading block already factored (`known` rows),
/// the first row counted in the log-determinant, and the size from which the
/// large-matrix path is taken (see [`factor_checked`]).
#[derive(Clone, Copy)]
struct Job {
    known: usize,
    logdet_from: usize,
    blocked_from: usize,
}

/// The driver shared by every instruction set.
///
/// # Safety
/// `a` holds at least `layout.len()` elements (checked by [`factor_checked`]),
/// `job.known` is a multiple of [`KNOWN_STEP`] at most `n`, and `L`'s instruction set is
/// available.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // `r` indexes the matrix too, through `at`
unsafe fn factor_with<L: Lanes>(
    a: &mut [f64],
    layout: Layout,
    job: Job,
    strip: Option<StripFn>,
) -> Option<f64> {
    let Layout { n, ld } = layout;
    let Job {
        known,
        logdet_from,
        blocked_from,
    } = job;
    let len = a.len();
    let ptr = a.as_mut_ptr();
    // Every access below goes through `ptr`, the kernels' and these loops' alike: indexing
    // `a` after taking the pointer would invalidate it for the kernels' later reads (a
    // Stacked Borrows violation Miri found in `tile`'s reads after the diagonal block was
    // written through `a`). `at` keeps the bounds check the indexing had.
    let at = |i: usize| -> *mut f64 {
        assert!(
            i < len,
            "index {i} outside the {len} elements of the matrix"
        );
        // SAFETY: in bounds, checked above.
        unsafe { ptr.add(i) }
    };
    let mut logdet = 0.0;
    // Large matrices (beyond the caches) go panel by panel: the rows of a panel of
    // `PANEL` rows are first updated by every row above the panel, in depth chunks of `KC`
    // rows and column strips of `STRIP` columns, so that each chunk-strip block is read
    // from the L2 cache by all the panel's block rows in turn; the single pass below then
    // only has the depth inside the panel left. Smaller matrices keep the single pass
    // (bit for bit the results of decision 0002).
    let blocked = n > blocked_from;
    let mut pack: Option<Pack> = None;
    let mut k0 = 0;
    while k0 < n {
        let mr = MR.min(n - k0);
        let panel0 = if blocked { k0 - k0 % PANEL } else { 0 };
        if blocked && k0 == panel0 && panel0 > 0 {
            // SAFETY: rows below panel0 + PANEL <= n + PANEL - 1 may run past n by less
            // than PANEL rows: only the first `n + 8` rows exist, so block rows are
            // limited to those starting below n.
            unsafe {
                update_panel::<L>(
                    ptr,
                    ld,
                    n,
                    panel0,
                    known,
                    pack.get_or_insert_with(Pack::new),
                    strip,
                )
            };
        }
        let p0 = panel0;
        if k0 < known {
            // A block row of the factored block: its diagonal block is known; only the
            // columns right of the block are computed, solved against that diagonal.
            let mut inv = [0.0; MR];
            for r in 0..mr {
                // SAFETY: `at` checks the bounds; nothing else holds a reference.
                let d = unsafe { *at((k0 + r) * ld + k0 + r) };
                if d.is_nan() || d <= 0.0 || !d.is_finite() {
                    return None;
                }
                if k0 + r >= logdet_from {
                    logdet += (d * d).ln();
                }
                inv[r] = 1.0 / d;
            }
            // SAFETY: as for the sweep below; columns from `known` only.
            unsafe { sweep::<L>(ptr, ld, n, k0, mr, Some(&inv), p0, k0, known) };
            k0 += MR;
            continue;
        }
        // SAFETY: k0 + 8 <= n + 8 rows exist; k0 + 8 <= n + 8 <= ld columns.
        unsafe {
            tile::<L, 1>(
                ptr,
                ld,
                k0,
                k0,
                mr,
                None,
                Depth::in_matrix(ptr, ld, k0, k0, p0, k0),
            )
        };
        // The tile also wrote the strict lower triangle of the diagonal block; keep it
        // zero so that no stale value lingers in the buffer between factorisations.
        for r in 1..mr {
            for c in 0..r {
                // SAFETY: as above.
                unsafe { *at((k0 + r) * ld + k0 + c) = 0.0 };
            }
        }
        // Factor the diagonal block in place (it is small: plain loops).
        let mut inv = [0.0; MR];
        for r in 0..mr {
            let row = (k0 + r) * ld + k0;
            for q in 0..r {
                let qrow = (k0 + q) * ld + k0;
                // SAFETY: as above.
                let c = unsafe { *at(qrow + r) };
                for cc in r..mr {
                    // SAFETY: as above.
                    unsafe { *at(row + cc) -= c * *at(qrow + cc) };
                }
            }
            // SAFETY: as above.
            let d2 = unsafe { *at(row + r) };
            if d2.is_nan() || d2 <= 0.0 || !d2.is_finite() {
                return None;
            }
            let d = d2.sqrt();
            if k0 + r >= logdet_from {
                logdet += d2.ln();
            }
            // SAFETY: as above.
            unsafe { *at(row + r) = d };
            inv[r] = 1.0 / d;
            for cc in r + 1..mr {
                // SAFETY: as above.
                unsafe { *at(row + cc) *= inv[r] };
            }
        }
        // SAFETY: as for the diagonal tile.
        unsafe { sweep::<L>(ptr, ld, n, k0, mr, Some(&inv), p0, k0, 0) };
        k0 += MR;
    }
    Some(logdet)
}

/// Matrices of more rows than this are factorised in depth chunks of [`KC`] rows (the
/// joint matrix then no longer fits in the L2 cache: 1,024 rows are 8 MiB). Smaller ones
/// keep the single pass, so their results are bit for bit those of decision 0002.
const CHUNK_FROM: usize = 1024;

/// Depth chunk of one tile's update when its rows go in groups (`Lanes::ROWS_AT_ONCE`):
/// 128 rows of a 16-column strip are 16 KiB, half of a typical L1 data cache.
const TILE_DEPTH: usize = 128;

/// Depth chunk of large factorisations, rows.
const KC: usize = 256;

/// Rows per panel of large factorisations (sixteen block rows): each packed chunk-strip
/// block serves them all. 128 against 64 (AVX-512, one core, n = 4,000): 478 ms against
/// 521 ms; 256 was no faster on AVX2 and makes the in-panel pass deeper.
const PANEL: usize = 128;

/// Column strip of the panel update: a packed `KC x STRIP` block is 128 KiB (64 against
/// 128 and 256 columns: 521, 544 and 545 ms at n = 4,000, AVX-512, one core).
const STRIP: usize = 64;

/// Contiguous copies of one depth chunk of the large-matrix path, so that a tile's
/// update streams its operands from consecutive addresses instead of reading one row of
/// `U` every `ld` doubles: at 4,000 rows that stride is 32 KiB, a new page per row read,
/// and the unpacked update ran at 15 GFMA/s against 25 for matrices that fit the caches
/// (AVX-512, one core; `examples/factor_rate.rs`, decision 0002's addendum of 5 December).
struct Pack {
    /// The panel's multipliers: block row `blk`, depth `p`, row `r` at
    /// `(blk * KC + p) * MR + r` (16 KiB a block row).
    u: Vec<f64>,
    /// One column strip, tile by tile: the tile at strip offset `o` (a multiple of 8),
    /// `w` columns wide, holds depth `p`, column `c` at `o * KC + p * w + c`.
    b: Vec<f64>,
}

impl Pack {
    fn new() -> Pack {
        Pack {
            u: vec![0.0; PANEL * KC],
            // A strip's last tile may run up to 8 columns past it.
            b: vec![0.0; (STRIP + 8) * KC],
        }
    }
}

/// Updates the rows `panel0..panel0 + PANEL` (those below `n`), columns from each block
/// row's diagonal to the end, by all rows above `panel0`: `C -= U[..panel0, rows]^T
/// U[..panel0, cols]`, in depth chunks of [`KC`] rows and column strips of [`STRIP`]
/// columns. Each chunk's multipliers and each chunk-strip block are first copied into
/// `pack` ([`Pack`]); every entry then sees the same fused multiply-adds in the same
/// order as without the copies. Tiles that straddle a block row's diagonal also update a
/// few entries below it, which nothing reads. A panel inside the known block (rows below
/// `known`, see [`factor_after`]) is updated from column `known` on only.
///
/// # Safety
/// As for [`tile`]: the buffer has `n + 8` rows of `ld >= n + 16` columns, `panel0 < n`.
#[inline(always)]
unsafe fn update_panel<L: Lanes>(
    ptr: *mut f64,
    ld: usize,
    n: usize,
    panel0: usize,
    known: usize,
    pack: &mut Pack,
    strip: Option<StripFn>,
) {
    let end = (panel0 + PANEL).min(n);
    let pu = pack.u.as_mut_ptr();
    let pb = pack.b.as_mut_ptr();
    let mut p0 = 0;
    while p0 < panel0 {
        let p1 = (p0 + KC).min(panel0);
        let depth = p1 - p0;
        // SAFETY (the copies): rows p0..p1 < n exist; columns k..k + 8 <= n + 8 and
        // j0..j0 + w <= n + 16 are within `ld`; the packs hold PANEL * KC and
        // (STRIP + 8) * KC doubles, and depth <= KC.
        for (blk, k) in (panel0..end).step_by(MR).enumerate() {
            for p in 0..depth {
                unsafe {
                    std::ptr::copy_nonoverlapping(
                        ptr.add((p0 + p) * ld + k),
                        pu.add((blk * KC + p) * MR),
                        MR,
                    )
                };
            }
        }
        let first = if panel0 < known { known } else { panel0 };
        let base = SharedStrip(Strip {
            a: ptr,
            ld,
            n,
            panel0,
            end,
            p0,
            depth,
            pu,
            pb,
            s0: first,
        });
        match strip {
            // Enough strips for several threads: each strip writes only its own columns
            // of the panel's rows and reads the packed multipliers and the rows above the
            // panel, which nothing writes meanwhile; each task packs into its own buffer.
            Some(f) if rayon::current_num_threads() > 1 && n - first > 2 * STRIP => {
                use rayon::prelude::*;
                let base = &base;
                (first..n)
                    .step_by(STRIP)
                    .collect::<Vec<_>>()
                    .into_par_iter()
                    .for_each_init(
                        || vec![0.0; (STRIP + 8) * KC],
                        |buf, s0| {
                            let st = Strip {
                                pb: buf.as_mut_ptr(),
                                s0,
                                ..base.0
                            };
                            // SAFETY: as for the sequential strips below; the strips'
                            // writes are disjoint.
                            unsafe { f(&st) }
                        },
                    );
            }
            _ => {
                for s0 in (first..n).step_by(STRIP) {
                    // SAFETY: forwarded from this function's contract.
                    unsafe { update_strip::<L>(&Strip { s0, ..base.0 }) };
                }
            }
        }
        p0 = p1;
    }
}

/// A strip's pointers shared by the tasks of a parallel panel update.
struct SharedStrip(Strip);
// SAFETY: the tasks write disjoint columns of the matrix, read what no task writes (see
// `update_panel`) and pack into buffers of their own.
unsafe impl Sync for SharedStrip {}

/// One column strip of a panel update, from column `s0` to `s0 + STRIP` (or `n`): the
/// panel's rows `panel0..end` updated by the depth chunk `p0..p0 + depth`, whose
/// multipliers are packed at `pu`; the strip's block is packed into `pb`.
#[derive(Clone, Copy)]
struct Strip {
    a: *mut f64,
    ld: usize,
    n: usize,
    panel0: usize,
    end: usize,
    p0: usize,
    depth: usize,
    pu: *mut f64,
    pb: *mut f64,
    s0: usize,
}

/// A strip update compiled for one instruction set: what a task of a parallel panel
/// update runs (a rayon task does not inherit the driver's target features, so it calls
/// one of these rather than the generic code).
type StripFn = unsafe fn(&Strip);

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,fma")]
unsafe fn strip_avx512(s: &Strip) {
    // SAFETY: forwarded from `update_panel`.
    unsafe { update_strip::<std::arch::x86_64::__m512d>(s) }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn strip_avx2(s: &Strip) {
    // SAFETY: forwarded from `update_panel`.
    unsafe { update_strip::<Plain<true>>(s) }
}

unsafe fn strip_generic(s: &Strip) {
    // SAFETY: forwarded from `update_panel`.
    unsafe { update_strip::<Plain<{ super::simd::GENERIC_FMA }>>(s) }
}

/// Updates one column strip ([`Strip`]): packs its chunk-strip block, then updates the
/// tiles of every block row of the panel at or right of the block's diagonal.
///
/// # Safety
/// As for [`update_panel`], whose strip this is; `pb` holds `(STRIP + 8) * KC` doubles.
#[inline(always)]
unsafe fn update_strip<L: Lanes>(st: &Strip) {
    let (ptr, ld, n, s0) = (st.a, st.ld, st.n, st.s0);
    let (panel0, end, p0, depth, pu, pb) = (st.panel0, st.end, st.p0, st.depth, st.pu, st.pb);
    let width = |j0: usize, s1: usize| if L::PAIRS && j0 + 8 < s1 { 16 } else { 8 };
    let s1 = (s0 + STRIP).min(n);
    let mut j0 = s0;
    while j0 < s1 {
        let w = width(j0, s1);
        for p in 0..depth {
            unsafe {
                std::ptr::copy_nonoverlapping(
                    ptr.add((p0 + p) * ld + j0),
                    pb.add((j0 - s0) * KC + p * w),
                    w,
                )
            };
        }
        j0 += w;
    }
    for (blk, k) in (panel0..end).step_by(MR).enumerate() {
        let mr = MR.min(n - k);
        // Tiles of this strip at or right of the block's diagonal.
        let mut j0 = s0;
        while j0 < s1 {
            let w = width(j0, s1);
            if j0 + w > k {
                let src = Depth {
                    // SAFETY: inside the packs, as filled above.
                    u: unsafe { pu.add(blk * KC * MR) },
                    u_stride: MR,
                    b: unsafe { pb.add((j0 - s0) * KC) },
                    b_stride: w,
                    len: depth,
                };
                // SAFETY: j0 + 16 <= n + 16 <= ld; rows k..k + 8 <= n + 8.
                unsafe {
                    if w == 16 {
                        tile::<L, 2>(ptr, ld, k, j0, mr, None, src);
                    } else {
                        tile::<L, 1>(ptr, ld, k, j0, mr, None, src);
                    }
                }
            }
            j0 += w;
        }
    }
}

/// Updates the tiles of block row `k0` right of its diagonal block, from column `from` if
/// that is further right, by rows `p0..p1` (and with `solve`, solves them against the
/// diagonal factor).
///
/// # Safety
/// As for [`tile`], for every `j0` from `k0 + 8` below `n`; `from` is a multiple of 8.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
unsafe fn sweep<L: Lanes>(
    ptr: *mut f64,
    ld: usize,
    n: usize,
    k0: usize,
    mr: usize,
    solve: Option<&[f64; MR]>,
    p0: usize,
    p1: usize,
    from: usize,
) {
    let mut j0 = (k0 + MR).max(from);
    while j0 < n {
        let at = |j: usize| Depth::in_matrix(ptr, ld, k0, j, p0, p1);
        if j0 + 8 >= n {
            // SAFETY: j0 + 8 <= n + 8 <= ld.
            unsafe { tile::<L, 1>(ptr, ld, k0, j0, mr, solve, at(j0)) };
            j0 += 8;
        } else {
            // SAFETY: j0 + 16 <= n + 16 <= ld.
            unsafe {
                if L::PAIRS {
                    tile::<L, 2>(ptr, ld, k0, j0, mr, solve, at(j0));
                } else {
                    tile::<L, 1>(ptr, ld, k0, j0, mr, solve, at(j0));
                    tile::<L, 1>(ptr, ld, k0, j0 + 8, mr, solve, at(j0 + 8));
                }
            }
            j0 += 16;
        }
    }
}

/// Eight doubles side by side: one zmm register on AVX-512, a plain array elsewhere (which
/// LLVM vectorises for AVX2, NEON on phones, or SSE2). The tile below is written once over
/// this trait.
///
/// # Safety
/// Every method is `unsafe`: the AVX-512 implementation needs the CPU feature, and `load`
/// and `store` take raw pointers to eight valid doubles.
trait Lanes: Copy {
    /// Whether a tile of two vectors per row (16 columns) keeps its accumulators in
    /// registers; if not, the driver updates 16 columns as two tiles of 8.
    const PAIRS: bool;
    /// Rows of the tile updated together in the depth loop. Eight rows of eight lanes
    /// are sixteen 256-bit accumulators (or thirty-two 128-bit NEON ones), which with the
    /// row loaded and the broadcast leaves too few registers on AVX2 and NEON, so
    /// the compiler spills accumulators inside the loop. Four rows at a time keep
    /// everything in registers (the row of `U` is then read twice, from L1).
    const ROWS_AT_ONCE: usize;
    unsafe fn load(p: *const f64) -> Self;
    unsafe fn store(self, p: *mut f64);
    unsafe fn splat(x: f64) -> Self;
    /// `c - a * b`, fused where the target has it.
    unsafe fn fnmadd(a: Self, b: Self, c: Self) -> Self;
    unsafe fn mul(self, b: Self) -> Self;
}

/// Portable lanes; `FMA` selects fused multiply-adds (only under a `target_feature` that
/// has them, where `mul_add` is one instruction rather than a library call).
#[derive(Clone, Copy)]
struct Plain<const FMA: bool>([f64; 8]);

impl<const FMA: bool> Lanes for Plain<FMA> {
    // 2 x 8 x 8 accumulators would not fit in NEON's or AVX2's registers.
    const PAIRS: bool = false;
    const ROWS_AT_ONCE: usize = 4;

    #[inline(always)]
    unsafe fn load(p: *const f64) -> Self {
        // SAFETY: the caller passes eight valid doubles.
        Plain(std::array::from_fn(|c| unsafe { *p.add(c) }))
    }

    #[inline(always)]
    unsafe fn store(self, p: *mut f64) {
        for (c, x) in self.0.into_iter().enumerate() {
            // SAFETY: as for `load`.
            unsafe { *p.add(c) = x };
        }
    }

    #[inline(always)]
    unsafe fn splat(x: f64) -> Self {
        Plain([x; 8])
    }

    #[inline(always)]
    unsafe fn fnmadd(a: Self, b: Self, c: Self) -> Self {
        Plain(std::array::from_fn(|i| {
            if FMA {
                (-a.0[i]).mul_add(b.0[i], c.0[i])
            } else {
                c.0[i] - a.0[i] * b.0[i]
            }
        }))
    }

    #[inline(always)]
    unsafe fn mul(self, b: Self) -> Self {
        Plain(std::array::from_fn(|i| self.0[i] * b.0[i]))
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::Lanes;
    use std::arch::x86_64::*;

    // Each method carries the target features so that its intrinsic inlines into it,
    // and it into the AVX-512 driver (`factor_avx512`), which has the same features.
    impl Lanes for __m512d {
        const PAIRS: bool = true;
        const ROWS_AT_ONCE: usize = 8;

        #[inline]
        #[target_feature(enable = "avx512f")]
        unsafe fn load(p: *const f64) -> Self {
            // SAFETY: the caller passes eight valid doubles.
            unsafe { _mm512_loadu_pd(p) }
        }

        #[inline]
        #[target_feature(enable = "avx512f")]
        unsafe fn store(self, p: *mut f64) {
            // SAFETY: as for `load`.
            unsafe { _mm512_storeu_pd(p, self) }
        }

        #[inline]
        #[target_feature(enable = "avx512f")]
        unsafe fn splat(x: f64) -> Self {
            _mm512_set1_pd(x)
        }

        #[inline]
        #[target_feature(enable = "avx512f")]
        unsafe fn fnmadd(a: Self, b: Self, c: Self) -> Self {
            _mm512_fnmadd_pd(a, b, c)
        }

        #[inline]
        #[target_feature(enable = "avx512f")]
        unsafe fn mul(self, b: Self) -> Self {
            _mm512_mul_pd(self, b)
        }
    }
}

/// Where a tile's update reads the rows of `U` above it: for depth `p < len`, the eight
/// multipliers `U[p][k0..k0 + 8]` at `u + p * u_stride` and the `8 * NV` columns
/// `U[p][j0..]` at `b + p * b_stride`. Either the matrix itself (strides `ld`,
/// [`Depth::in_matrix`]) or the packed copies of the large-matrix path ([`Pack`]).
#[derive(Clone, Copy)]
struct Depth {
    u: *const f64,
    u_stride: usize,
    b: *const f64,
    b_stride: usize,
    len: usize,
}

impl Depth {
    /// Rows `p0..p1` of the matrix at `a` (leading dimension `ld`) for the tile at block
    /// row `k0` and column `j0`.
    #[inline(always)]
    fn in_matrix(a: *const f64, ld: usize, k0: usize, j0: usize, p0: usize, p1: usize) -> Depth {
        // `wrapping_add`: the pointers are only read through, by `tile`, whose contract
        // keeps them inside the buffer.
        Depth {
            u: a.wrapping_add(p0 * ld + k0),
            u_stride: ld,
            b: a.wrapping_add(p0 * ld + j0),
            b_stride: ld,
            len: p1 - p0,
        }
    }
}

/// Updates the tile of rows `k0..k0+8` and columns `j0..j0+8*NV` by the rows of `U` that
/// `src` reads, `C[r][c] -= sum_p U[p][k0+r] U[p][c]` in the order of `p`, with the tile
/// held in `8 * NV` lanes vectors; with `solve` (which holds `1 / U_rr`), then solves
/// `U_kk^T X = C` against the block's diagonal factor in the same vectors. Rows `r < mr`
/// are stored.
///
/// # Safety
/// `a` points to a buffer of leading dimension `ld` with at least `k0 + 8` rows and
/// `j0 + 8 * NV <= ld`, `src` reads `len` valid rows of eight and `8 * NV` doubles, and
/// `L`'s instruction set is available.
// Index loops over the register arrays read as the algebra does (acc[r] -= u acc[q]).
#[allow(clippy::needless_range_loop, clippy::too_many_arguments)]
#[inline(always)]
unsafe fn tile<L: Lanes, const NV: usize>(
    a: *mut f64,
    ld: usize,
    k0: usize,
    j0: usize,
    mr: usize,
    solve: Option<&[f64; MR]>,
    src: Depth,
) {
    // SAFETY: every pointer below stays in rows < k0 + 8 and columns < j0 + 8 NV or
    // < k0 + 8, all within the buffer (caller's contract).
    unsafe {
        let zero = L::splat(0.0);
        let mut acc = [[zero; NV]; MR];
        for (r, accr) in acc.iter_mut().enumerate() {
            for (v, x) in accr.iter_mut().enumerate() {
                *x = L::load(a.add((k0 + r) * ld + j0 + 8 * v));
            }
        }
        // Row groups in turn (one group of eight on AVX-512, two of four elsewhere: see
        // `Lanes::ROWS_AT_ONCE`), over the depth in chunks of `TILE_DEPTH` rows so that
        // the second group reads the chunk's columns from L1. Each accumulator still
        // sees the same sums in the same order, so the results are those of one pass.
        let mut c0 = 0;
        while c0 < src.len {
            let c1 = (c0 + TILE_DEPTH).min(src.len);
            // Constant bounds throughout, so that the loops unroll and every accumulator
            // is a register.
            for g in 0..MR / L::ROWS_AT_ONCE {
                let g0 = g * L::ROWS_AT_ONCE;
                for p in c0..c1 {
                    let urow = src.u.add(p * src.u_stride);
                    let brow = src.b.add(p * src.b_stride);
                    let mut b = [zero; NV];
                    for (v, x) in b.iter_mut().enumerate() {
                        *x = L::load(brow.add(8 * v));
                    }
                    for r in g0..g0 + L::ROWS_AT_ONCE {
                        let s = L::splat(*urow.add(r));
                        for v in 0..NV {
                            acc[r][v] = L::fnmadd(s, b[v], acc[r][v]);
                        }
                    }
                }
            }
            c0 = c1;
        }
        if let Some(inv) = solve {
            for r in 0..MR {
                for q in 0..r {
                    let u = L::splat(*a.add((k0 + q) * ld + k0 + r));
                    for v in 0..NV {
                        acc[r][v] = L::fnmadd(u, acc[q][v], acc[r][v]);
                    }
                }
                let s = L::splat(inv[r]);
                for v in 0..NV {
                    acc[r][v] = acc[r][v].mul(s);
                }
            }
        }
        for (r, accr) in acc.iter().enumerate().take(mr) {
            for (v, x) in accr.iter().enumerate() {
                x.store(a.add((k0 + r) * ld + j0 + 8 * v));
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A symmetric positive definite test matrix in the dense layout (and as nalgebra).
    fn spd(n: usize) -> (Vec<f64>, nalgebra::DMatrix<f64>, Layout) {
        let layout = Layout::new(n);
        let m = nalgebra::DMatrix::from_fn(n, n, |i, j| {
            let (x, y) = ((i as f64 * 0.37).sin() * 9.0, (j as f64 * 0.37).sin() * 9.0);
            let d = ((x - y).powi(2) + ((i as f64) - (j as f64)).powi(2) * 0.01).sqrt();
            40.0 * (-d / 6.0).exp() + if i == j { 2.0 + (i % 3) as f64 } else { 0.0 }
        });
        let mut a = vec![0.0; layout.len()];
        for i in 0..n {
            for j in i..n {
                a[i * layout.ld + j] = m[(i, j)];
            }
        }
        (a, m, layout)
    }

    /// The upper factor in `a` is nalgebra's `L^T` of `m`.
    fn assert_factor(a: &[f64], layout: Layout, m: &nalgebra::DMatrix<f64>, what: &str) {
        let l = m.clone().cholesky().expect("pd").l();
        for i in 0..layout.n {
            for j in i..layout.n {
                assert!(
                    (a[i * layout.ld + j] - l[(j, i)]).abs() < 1e-9,
                    "{what} U[{i}][{j}]"
                );
            }
        }
    }

    fn schur_logdet(m: &nalgebra::DMatrix<f64>, from: usize) -> f64 {
        let full = m.clone().cholesky().expect("pd").ln_determinant();
        if from == 0 {
            return full;
        }
        let head = m.view((0, 0), (from, from)).into_owned();
        full - head.cholesky().expect("pd").ln_determinant()
    }

    /// The dense factor's log-determinant (of the Schur complement from row `from`) and
    /// the factor itself against nalgebra.
    pub(crate) fn check(isa: Isa) {
        // 1,300 rows: beyond CHUNK_FROM, so the depth-chunked pass (several chunks and a
        // ragged last one) is checked too.
        for n in [1usize, 2, 7, 8, 9, 15, 16, 17, 23, 24, 25, 40, 71, 1300] {
            let froms = if n > 100 {
                vec![n / 3]
            } else {
                vec![0, n / 3, n.saturating_sub(5), n - 1]
            };
            for from in froms {
                let (mut a, m, layout) = spd(n);
                let got = factor(isa, &mut a, layout, from).expect("pd");
                assert_logdet(
                    got,
                    schur_logdet(&m, from),
                    &format!("{isa:?} n={n} from={from}"),
                );
                // The factor itself matches nalgebra's L^T.
                assert_factor(&a, layout, &m, &format!("{isa:?} n={n}"));
            }
        }
    }

    /// The large-matrix path's column strips run on several threads where there are
    /// (`update_panel`), and every entry sees the same multiply-adds in the same order:
    /// one thread and three give the same factor and log-determinant bit for bit, with
    /// and without a known block, and the factor is right.
    pub(crate) fn check_threads(isa: Isa) {
        let n = 1300;
        let run = |threads: usize, known: usize| {
            let (mut a, m, layout) = spd(n);
            if known > 0 {
                // Factor the leading block first, as the engine's S side does.
                let lead = Layout::new(known);
                let mut b = vec![0.0; lead.len()];
                for i in 0..known {
                    b[i * lead.ld..i * lead.ld + known]
                        .copy_from_slice(&a[i * layout.ld..i * layout.ld + known]);
                }
                factor(isa, &mut b, lead, 0).expect("pd");
                for i in 0..known {
                    a[i * layout.ld..i * layout.ld + known]
                        .copy_from_slice(&b[i * lead.ld..i * lead.ld + known]);
                }
            }
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let d = pool
                .install(|| factor_after(isa, &mut a, layout, known, n / 3))
                .expect("pd");
            (a, d, m, layout)
        };
        for known in [0, 640] {
            let (one, d1, m, layout) = run(1, known);
            let (three, d3, _, _) = run(3, known);
            assert_eq!(d1.to_bits(), d3.to_bits(), "{isa:?} known {known}");
            for i in 0..n {
                let row = i * layout.ld;
                for j in i..n {
                    assert_eq!(
                        one[row + j].to_bits(),
                        three[row + j].to_bits(),
                        "{isa:?} known {known}: entry ({i}, {j})"
                    );
                }
            }
            assert_logdet(
                d3,
                schur_logdet(&m, n / 3),
                &format!("{isa:?} known {known}"),
            );
            assert_factor(&three, layout, &m, &format!("{isa:?} three threads"));
        }
    }

    /// A log-determinant within `1e-10` relative of the reference.
    fn assert_logdet(got: f64, want: f64, what: &str) {
        assert!(
            (got - want).abs() <= 1e-10 * want.abs().max(1.0),
            "{what}: {got} vs {want}"
        );
    }

    /// [`factor_after`] with the leading block already factored gives the factor and the
    /// log-determinant of a whole factorisation, below and beyond [`CHUNK_FROM`] rows.
    pub(crate) fn check_known(isa: Isa) {
        // (1300, 576), (1300, 1000), ...: a panel of the large path partly known.
        for (n, known) in [
            (64, 64),
            (70, 64),
            (70, 56),
            (200, 128),
            (200, 136),
            (1300, 1024),
            (1300, 640),
            (1300, 576),
            (1300, 1000),
            (1300, 1296),
        ] {
            let (mut whole, m, layout) = spd(n);
            factor(isa, &mut whole, layout, 0).expect("pd");
            let (mut a, _, _) = spd(n);
            for i in 0..known {
                let row = i * layout.ld;
                a[row + i..row + known].copy_from_slice(&whole[row + i..row + known]);
            }
            let got = factor_after(isa, &mut a, layout, known, known).expect("pd");
            assert_logdet(
                got,
                schur_logdet(&m, known),
                &format!("{isa:?} n={n} known={known}"),
            );
            assert_factor(&a, layout, &m, &format!("{isa:?} n={n} known={known}"));
        }
    }

    /// The large-matrix path (panels, packed depth chunks) gives the single pass's factor
    /// bit for bit: every entry sees the same multiply-adds in the same order. Forced on
    /// small matrices (`blocked_from` 0), so that several panels, strips, depth chunks
    /// and partly known panels are covered at sizes Miri can run.
    pub(crate) fn check_blocked_path(isa: Isa) {
        let cases: &[(usize, usize)] = if cfg!(miri) {
            // Two panels, the second packed and partly known; the smallest that cover it
            // (Miri ran (150, 0) and (200, 136) for over 20 minutes without finishing).
            &[(136, 0), (144, 136)]
        } else {
            // 700 rows: three depth chunks of KC above the last panel.
            &[
                (150, 0),
                (300, 0),
                (300, 136),
                (300, 200),
                (700, 0),
                (700, 264),
            ]
        };
        for &(n, known) in cases {
            let run = |blocked_from: usize| {
                let (mut a, _, layout) = spd(n);
                if known > 0 {
                    let (mut whole, _, _) = spd(n);
                    factor(isa, &mut whole, layout, 0).expect("pd");
                    for i in 0..known {
                        let row = i * layout.ld;
                        a[row + i..row + known].copy_from_slice(&whole[row + i..row + known]);
                    }
                }
                let job = Job {
                    known,
                    logdet_from: n / 3,
                    blocked_from,
                };
                let ld = factor_checked(isa, &mut a, layout, job);
                (ld.expect("pd"), a, layout)
            };
            let (single, a1, layout) = run(usize::MAX);
            let (blocked, a2, _) = run(0);
            assert_eq!(
                single.to_bits(),
                blocked.to_bits(),
                "{isa:?} n={n} known={known}: log-determinant"
            );
            for i in 0..n {
                for j in i..n {
                    let k = i * layout.ld + j;
                    assert_eq!(
                        a1[k].to_bits(),
                        a2[k].to_bits(),
                        "{isa:?} n={n} known={known}: U[{i}][{j}]"
                    );
                }
            }
        }
    }

    /// [`check_blocked_path`] on the portable lanes alone: the `isa_tests` run it on every
    /// instruction set among slower checks; this is the one Miri runs in seconds
    /// (`cargo +nightly miri test -p trailprint-core --no-default-features --lib
    /// blocked_path`).
    #[test]
    fn blocked_path_matches_the_single_pass_on_the_portable_lanes() {
        let generic = Isa::supported()
            .into_iter()
            .find(|i| i.kind() == super::super::simd::IsaKind::Generic)
            .expect("the portable lanes are always supported");
        check_blocked_path(generic);
    }

    /// A matrix that is not positive definite is reported, not factored.
    pub(crate) fn check_indefinite(isa: Isa) {
        let layout = Layout::new(3);
        let mut a = vec![0.0; layout.len()];
        a[0] = 1.0;
        a[1] = 2.0;
        a[layout.ld + 1] = 1.0;
        a[2 * layout.ld + 2] = 1.0;
        assert!(factor(isa, &mut a, layout, 0).is_none(), "{isa:?}");
    }

    /// The portable driver with the other `FMA` than this target's `Generic` uses: on
    /// x86-64 the fused build aarch64 runs (`mul_add` is a libm call here, slow but exact).
    pub(crate) fn check_portable_with_the_other_fma() {
        const OTHER: bool = !super::super::simd::GENERIC_FMA;
        for n in [1usize, 7, 8, 9, 17, 40, 71] {
            for from in [0, n / 3, n - 1] {
                let (mut a, m, layout) = spd(n);
                // SAFETY: `a` holds `layout.len()` elements; the portable lanes need no
                // CPU feature.
                let job = Job {
                    known: 0,
                    logdet_from: from,
                    blocked_from: CHUNK_FROM,
                };
                let got =
                    unsafe { factor_with::<Plain<OTHER>>(&mut a, layout, job, None) }.expect("pd");
                let want = schur_logdet(&m, from);
                assert!(
                    (got - want).abs() <= 1e-10 * want.abs().max(1.0),
                    "n={n} from={from}"
                );
            }
        }
    }
}
