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

pub use engine::{Mark, UtilityEngine, WalkState, merge_coincident};
