//! Tells the per-instruction-set tests (`utility::isa_tests`) which instruction sets the
//! CPU building them has, so that `cargo test` lists those it lacks as ignored "not on
//! this CPU" instead of reporting a pass for a test that ran nothing. The library itself
//! does not use these flags: it picks its kernels at run time (`Isa::detect`).

fn main() {
    println!("cargo::rustc-check-cfg=cfg(trailprint_cpu_avx512)");
    println!("cargo::rustc-check-cfg=cfg(trailprint_cpu_avx2_fma)");
    println!("cargo::rerun-if-changed=build.rs");
    // Only when the tests run where they are built: not when cross-compiling.
    let target = std::env::var("TARGET").unwrap_or_default();
    let host = std::env::var("HOST").unwrap_or_default();
    if target != host {
        return;
    }
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        // The same conditions as `Features::allowed` in `src/utility/simd.rs`.
        let avx2_fma = has!("avx2") && has!("fma");
        if avx2_fma && has!("avx512f") && has!("avx512dq") && has!("avx512vl") {
            println!("cargo::rustc-cfg=trailprint_cpu_avx512");
        }
        if avx2_fma {
            println!("cargo::rustc-cfg=trailprint_cpu_avx2_fma");
        }
    }
}
