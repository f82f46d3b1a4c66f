//! This core's double-precision FMA peak, the yardstick for the utility engine's kernels
//! (docs/decisions/0002-dense-micro-kernel.md): twelve independent chains of `vfmadd` on
//! 512-bit and 256-bit vectors, and the throughput of `vsqrtpd`.
//! `cargo run --release -p trailprint-core --example fma_peak`

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;
    use std::time::Instant;

    /// The twelve independent `acc = acc * a + b` chains, `iters` steps each, on the vectors
    /// `$set1` broadcasts to, multiplied and added by `$fmadd`: the same code at each width,
    /// expanded inside the `#[target_feature]` function that enables it.
    macro_rules! fma_chains {
        ($set1:ident, $fmadd:ident, $iters:expr) => {{
            let mut acc = [$set1(1.0); 12];
            let (a, b) = ($set1(0.999_999), $set1(1e-7));
            for _ in 0..$iters {
                for x in &mut acc {
                    *x = $fmadd(*x, a, b);
                }
            }
            acc
        }};
    }

    #[target_feature(enable = "avx512f")]
    fn fma512(iters: usize) -> f64 {
        let acc = fma_chains!(_mm512_set1_pd, _mm512_fmadd_pd, iters);
        acc.iter().map(|&x| _mm512_reduce_add_pd(x)).sum()
    }

    #[target_feature(enable = "avx2,fma")]
    fn fma256(iters: usize) -> f64 {
        let acc = fma_chains!(_mm256_set1_pd, _mm256_fmadd_pd, iters);
        let mut s = 0.0;
        for x in acc {
            let mut t = [0.0; 4];
            // SAFETY: storing 4 doubles into a 4-element array.
            unsafe { _mm256_storeu_pd(t.as_mut_ptr(), x) };
            s += t.iter().sum::<f64>();
        }
        s
    }

    #[target_feature(enable = "avx512f")]
    fn sqrt512(iters: usize) -> f64 {
        let mut acc = [_mm512_set1_pd(1.5); 12];
        for _ in 0..iters {
            for x in &mut acc {
                *x = _mm512_sqrt_pd(*x);
            }
        }
        acc.iter().map(|&x| _mm512_reduce_add_pd(x)).sum()
    }

    fn best<F: FnMut() -> f64>(mut f: F) -> f64 {
        (0..5)
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(f());
                t.elapsed().as_secs_f64()
            })
            .fold(f64::MAX, f64::min)
    }

    pub fn main() {
        let iters = 20_000_000;
        let avx512 = is_x86_feature_detected!("avx512f");
        if !(is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")) {
            println!("this CPU lacks AVX2+FMA");
            return;
        }
        if avx512 {
            // SAFETY: AVX-512F was detected above.
            let t = best(|| unsafe { fma512(iters) });
            println!(
                "512-bit FMA: {:.2} GFMA/s",
                (iters * 12 * 8) as f64 / t / 1e9
            );
        } else {
            println!("512-bit FMA: not on this CPU");
        }
        // SAFETY: AVX2 and FMA were detected above.
        let t = best(|| unsafe { fma256(iters) });
        println!(
            "256-bit FMA: {:.2} GFMA/s",
            (iters * 12 * 4) as f64 / t / 1e9
        );
        if avx512 {
            // SAFETY: AVX-512F was detected above.
            let t = best(|| unsafe { sqrt512(iters / 10) });
            println!(
                "512-bit sqrt: {:.2} ns per vector",
                t / (iters / 10 * 12) as f64 * 1e9
            );
        }
    }
}

fn main() {
    #[cfg(target_arch = "x86_64")]
    x86::main();
    #[cfg(not(target_arch = "x86_64"))]
    println!("x86_64 only");
}
