//! Seeded random numbers that stay bit-identical across platforms and `rand` releases.
//!
//! Every draw goes through `next_u64` of a [`ChaCha8Rng`] and through `libm` (pure Rust)
//! for the transcendental functions, so a generated building depends on the seed alone,
//! not on the C library of the machine. Separate concerns use separate ChaCha streams of
//! the same seed, so that (for example) asking for more pilot points does not move the
//! access points.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A generator for `seed`, on ChaCha stream `stream`.
pub(crate) fn stream_rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// Uniform in `[0, 1)` with 53 random bits.
pub(crate) fn unit<R: Rng>(rng: &mut R) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Uniform in `[lo, hi)`.
pub(crate) fn uniform<R: Rng>(rng: &mut R, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * unit(rng)
}

/// Uniform index in `0..n` (`n > 0`); the modulo bias is below 2⁻⁴⁰ for any `n` we use.
pub(crate) fn index<R: Rng>(rng: &mut R, n: usize) -> usize {
    (rng.next_u64() % n.max(1) as u64) as usize
}

/// Standard normal by Box-Muller (one of the pair; simple and stable).
pub(crate) fn normal<R: Rng>(rng: &mut R) -> f64 {
    let u1 = 1.0 - unit(rng); // (0, 1]
    let u2 = unit(rng);
    libm::sqrt(-2.0 * libm::log(u1)) * libm::cos(2.0 * std::f64::consts::PI * u2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_has_unit_moments_and_streams_differ() {
        let mut r = stream_rng(7, 0);
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|_| normal(&mut r)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "{mean}");
        assert!((var - 1.0).abs() < 0.04, "{var}");
        let a = unit(&mut stream_rng(7, 1));
        let b = unit(&mut stream_rng(7, 2));
        assert_ne!(a, b);
        assert_eq!(a, unit(&mut stream_rng(7, 1)));
    }
}
