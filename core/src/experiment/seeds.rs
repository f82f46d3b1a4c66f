//! The seeds of every run, derived from the master seed (see the module documentation of
//! [`crate::experiment`]: all algorithms of a run share them).

use crate::plan::Algorithm;

/// SplitMix64 finaliser: a bijective mix of 64 bits.
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A seed for run `run` on stream `stream`, from the master seed.
fn derive_seed(seed: u64, run: usize, stream: u64) -> u64 {
    splitmix64(splitmix64(splitmix64(seed) ^ stream) ^ run as u64)
}

/// The planner seed of run `run` (0-based).
pub fn plan_seed(seed: u64, run: usize) -> u64 {
    derive_seed(seed, run, 0x706c_616e) // "plan"
}

/// The evaluation seed of run `run` (0-based).
pub fn eval_seed(seed: u64, run: usize) -> u64 {
    derive_seed(seed, run, 0x6576_616c) // "eval"
}

/// Whether an algorithm's plan depends on the seed.
pub(super) fn seeded(a: Algorithm) -> bool {
    matches!(a, Algorithm::Genetic | Algorithm::Ero | Algorithm::Auto)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_differ_between_runs_and_streams_and_are_stable() {
        let p: Vec<u64> = (0..5).map(|r| plan_seed(1, r)).collect();
        let e: Vec<u64> = (0..5).map(|r| eval_seed(1, r)).collect();
        for i in 0..5 {
            for j in 0..5 {
                assert_ne!(p[i], e[j]);
                if i != j {
                    assert_ne!(p[i], p[j]);
                    assert_ne!(e[i], e[j]);
                }
            }
        }
        assert_eq!(p[0], plan_seed(1, 0));
        assert_ne!(plan_seed(1, 0), plan_seed(2, 0));
    }
}
