//! The utility `f_D(P)` of SPEC section 3: mutual information between the fingerprints at
//! all vertices and the samples of a walk plus the pilot data, in nats.
//!
//! [`reference`](mod@reference) evaluates the formula directly; [`engine`] is the fast, incremental
//! evaluator the planners use.

pub mod reference;

pub use reference::{Observation, reference_utility};
pub mod blocked;
pub mod dense;
pub mod engine;
pub mod simd;

#[cfg(test)]
mod isa_tests;

pub use engine::{KeepScratch, Mark, NearBase, UtilityEngine, WalkState, merge_coincident};

/// Estimated peak memory, bytes, of evaluating walks of at most `samples` samples each
/// exactly on `building` with `threads` evaluations at a time: the engine's vertex
/// covariance and its factor (two `|V| x |V|` matrices, one on floors where `A` is not
/// kept: [`unkept_covariance`]) and, per evaluation, one dense
/// matrix of the pilot locations, the samples and the vertices. (The plan's estimate,
/// [`crate::plan::estimate_memory`], adds what planners keep besides.)
pub fn evaluation_memory(building: &crate::Building, samples: usize, threads: usize) -> u64 {
    let nv = building.len() as f64;
    let n = (building.pilot.len() + samples) as f64 + nv;
    let vertex = 2.0 * nv * nv - unkept_covariance(building);
    let bytes = 8.0 * (vertex + threads.max(1) as f64 * n * n) + 16.0 * 1024.0 * 1024.0;
    bytes.min(u64::MAX as f64) as u64
}

/// Entries (doubles) of the vertex covariance `A = K_VV + sn2 I` that the engine does not
/// keep: on a floor of more than [`engine::DENSE_A_FROM`] vertices it keeps `A`'s factor
/// and a few of its columns, not `A` itself (`n_f^2` entries less), so estimates that count
/// `A` take them off.
pub(crate) fn unkept_covariance(building: &crate::Building) -> f64 {
    let mut floors: Vec<i64> = building.vertices.iter().map(|v| v.pos.floor).collect();
    floors.sort_unstable();
    floors
        .chunk_by(|a, b| a == b)
        .map(|f| f.len())
        .filter(|&nf| nf > engine::DENSE_A_FROM)
        .map(|nf| (nf * nf) as f64)
        .sum()
}

/// Refuses to evaluate walks whose [`evaluation_memory`] exceeds `budget` bytes, before
/// anything is allocated, with the size and what would do. Measured without it:
/// `trailprint utility` on a line of 20,000 vertices took 6.4 GB and 79 s for a walk of
/// 2 m (the vertex covariance alone is 3.2 GB), and aborted under a 2 GB limit.
///
/// # Errors
/// [`crate::Error::InvalidRequest`] naming the building, its vertex count, the samples
/// and the memory needed.
pub fn check_evaluation_memory(
    building: &crate::Building,
    samples: usize,
    threads: usize,
    budget: u64,
) -> crate::Result<()> {
    let need = evaluation_memory(building, samples, threads);
    if need <= budget {
        return Ok(());
    }
    let mib = |b: u64| b.div_ceil(1 << 20);
    Err(crate::Error::InvalidRequest(format!(
        "evaluating a walk of {samples} samples on {:?} ({} vertices) needs about {} MiB, \
         more than the memory budget of {} MiB: the vertex covariance grows with the square \
         of the vertex count and a walk's matrix with its samples; evaluate on one floor or \
         part of the building, or raise the memory budget (--memory-budget MIB) if the \
         device has {} MiB to spare",
        building.name,
        building.len(),
        mib(need),
        mib(budget),
        mib(need)
    )))
}
