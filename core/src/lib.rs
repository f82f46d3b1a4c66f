//! Trailprint core: informative path planning for Wi-Fi fingerprint site surveys.
//!
//! The model is the one of "Informative Path Planning for Location Fingerprint Collection"
//! (Wei, Frincu, Zheng), as stated in `shared/SPEC.md`: a building graph ([`building`]), a
//! Gaussian process with an exponential kernel fitted on pilot data ([`gp`]), sample
//! positions along a walk for a robot or a human surveyor ([`samples`]), and the mutual
//! information utility that the planners maximise ([`utility`]).
//!
//! What a phone runs (the crate without features, as `bindings/` uses it): the planners
//! ([`plan`]), several surveyors at once ([`team`]), floor plans in ([`floorplan`]),
//! survey sessions with dead reckoning, guidance and replanning ([`session`]), and one
//! SQLite file for everything the phone keeps, with the one planning kernel policy
//! ([`store`]); errors are [`error`].
//!
//! The research side, behind the `research` feature (on by default; the `cli` feature adds
//! the `trailprint` command line tool): synthetic buildings and their radio world
//! (`synth`), the localization evaluation of SPEC section 5 (`eval`), radio maps out
//! (`radiomap`), the paper's experiment (`experiment`), SVG drawings (`render`), the
//! planner benchmark (`plan::bench`) and the survey simulator (`session::sim`).
//!
//! This crate knows nothing of FFI; `bindings/` translates its types for Kotlin.

pub mod building;
pub mod error;
#[cfg(feature = "research")]
pub mod eval;
#[cfg(feature = "research")]
pub mod experiment;
pub mod floorplan;
pub mod gp;
pub mod plan;
#[cfg(feature = "research")]
pub mod radiomap;
#[cfg(feature = "research")]
pub mod render;
pub mod samples;
pub mod session;
pub mod store;
pub mod surveyor;
#[cfg(feature = "research")]
pub mod synth;
pub mod team;
pub mod utility;

pub use building::Building;
pub use error::{Error, Result};
pub use store::Store;
