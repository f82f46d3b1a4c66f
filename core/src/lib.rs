//! Trailprint core: informative path planning for Wi-Fi fingerprint site surveys.
//!
//! The model is the one of "Informative Path Planning for Location Fingerprint Collection"
//! (Wei, Frincu, Zheng), as stated in `shared/SPEC.md`: a building graph ([`building`]), a
//! Gaussian process with an exponential kernel fitted on pilot data ([`gp`]), sample
//! positions along a walk for a robot or a human surveyor ([`samples`]), and the mutual
//! information utility that the planners maximise ([`utility`]).
//!
//! This crate knows nothing of FFI; `bindings/` translates its types for Kotlin.

pub mod building;
pub mod error;
pub mod gp;
pub mod plan;
pub mod samples;
pub mod utility;

pub use building::Building;
pub use error::{Error, Result};
