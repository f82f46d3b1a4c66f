//! Rate of the dense whole-walk factorisation (`utility::dense::factor`) on every
//! instruction set this CPU supports, at the sizes large buildings reach, in GFMA/s of
//! the `n^3 / 6` fused multiply-adds a Cholesky needs (decision 0004).
//! `cargo run --release -p trailprint-core --example factor_rate [-- N ...]`

use std::time::Instant;

use trailprint::utility::dense::{Layout, factor};
use trailprint::utility::simd::Isa;

/// A well-conditioned symmetric positive definite matrix (a squared-exponential kernel on
/// a line plus noise), upper triangle, in the dense layout.
fn fill(a: &mut [f64], layout: Layout) {
    let n = layout.n;
    for i in 0..n {
        for j in i..n {
            let d = (i as f64 - j as f64) * 0.37;
            let mut v = 100.0 * (-d * d / 200.0).exp();
            if i == j {
                v += 3.0;
            }
            a[i * layout.ld + j] = v;
        }
    }
}

fn main() {
    let sizes: Vec<usize> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("sizes are whole numbers"))
        .collect();
    let sizes = if sizes.is_empty() {
        vec![400, 1000, 1600, 2600, 4000]
    } else {
        sizes
    };
    for isa in Isa::supported() {
        for &n in &sizes {
            let layout = Layout::new(n);
            let mut a = vec![0.0; layout.len()];
            let runs = (2_000_000_000 / (n * n * n / 6).max(1)).clamp(2, 50);
            let mut best = f64::INFINITY;
            let mut logdet = 0.0;
            for _ in 0..runs {
                fill(&mut a, layout);
                let t = Instant::now();
                logdet = factor(isa, &mut a, layout, 0).expect("positive definite");
                best = best.min(t.elapsed().as_secs_f64());
            }
            let fmas = (n as f64).powi(3) / 6.0;
            println!(
                "{:10} n {n:5}  {:9.2} ms  {:6.2} GFMA/s  (ln det {logdet:.6e}, best of {runs})",
                format!("{isa:?}"),
                best * 1e3,
                fmas / best / 1e9
            );
        }
    }
}
