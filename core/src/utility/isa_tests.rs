//! One test per instruction set the kernels are built for, named after it, so that the
//! ordinary `cargo test` output says which ran: each runs every kernel (dot, gemv, axpy,
//! kernel rows, `exp`), the blocked and dense Cholesky factors and the whole utility
//! engine built for that instruction set against the reference (std, nalgebra, SPEC 3's
//! formula). An instruction set this CPU lacks is listed as
//! `ignored, not on this CPU (...)`: the build script (`core/build.rs`) sets
//! `trailprint_cpu_*` from the CPU that builds the tests, and
//! `simd::tests::supported_lists_the_detected_isa_first_and_always_generic` fails if the
//! CPU running them disagrees (a target directory moved to another machine).

use super::simd::{Isa, IsaKind, test_variants};
use super::{blocked, dense, engine, simd};

/// Runs every check on `kind`, which the tests were built to expect on this CPU.
fn check_isa(kind: IsaKind) {
    let isa = Isa::supported()
        .into_iter()
        .find(|i| i.kind() == kind)
        .unwrap_or_else(|| {
            panic!(
                "the tests were built on a CPU with {kind:?}, but this CPU lacks it: \
                 rebuild them here (cargo clean -p trailprint-core)"
            )
        });
    let v = (isa, isa.fma());
    check_kernels(v);
    dense::tests::check(isa);
    dense::tests::check_indefinite(isa);
    dense::tests::check_known(isa);
    dense::tests::check_blocked_path(isa);
    dense::tests::check_threads(isa);
    engine::tests::check(isa);
}

/// The kernels and the blocked factor on one `(isa, fma)` variant.
fn check_kernels(v: (Isa, bool)) {
    simd::tests::check_dot_and_axpy(v);
    simd::tests::check_dot_isa(v);
    simd::tests::check_gemv_sub(v);
    simd::tests::check_kernel_rows(v);
    let worst = simd::tests::check_exp(v);
    println!("{v:?}: exp_nonpos worst relative error {worst:e}");
    blocked::tests::check(v);
}

#[test]
#[cfg_attr(
    any(miri, not(trailprint_cpu_avx512)),
    ignore = "not on this CPU (needs AVX-512 F, DQ, VL and FMA; Miri detects none)"
)]
fn avx512_kernels_factor_and_engine_match_the_reference() {
    check_isa(IsaKind::Avx512);
}

#[test]
#[cfg_attr(
    any(miri, not(trailprint_cpu_avx2_fma)),
    ignore = "not on this CPU (needs x86-64 AVX2 and FMA; Miri detects none)"
)]
fn avx2_fma_kernels_factor_and_engine_match_the_reference() {
    check_isa(IsaKind::Avx2Fma);
}

/// The portable build every CPU runs: baseline SSE2 without FMA on x86-64, NEON with
/// fused multiply-add on aarch64 (`simd::GENERIC_FMA`).
#[test]
fn generic_kernels_factor_and_engine_match_the_reference() {
    check_isa(IsaKind::Generic);
}

/// The portable kernels with the other `FMA` than this target's: on x86-64 the fused
/// code aarch64's `Generic` runs (`mul_add` is then a libm call, slow but exact), so the
/// phone's arithmetic is tested on a machine without an aarch64 toolchain.
#[test]
fn generic_with_the_other_fma_kernels_and_factor_match_the_reference() {
    let other = test_variants()
        .into_iter()
        .find(|&(i, fma)| i.kind() == IsaKind::Generic && fma != i.fma())
        .expect("test_variants lists the portable code with the other FMA");
    check_kernels(other);
    dense::tests::check_portable_with_the_other_fma();
}
