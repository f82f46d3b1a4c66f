//! Kotlin bindings for Trailprint: a thin uniffi layer that only translates types.
//!
//! All logic lives in the core crate (`trailprint`); this crate maps its types onto uniffi
//! records, enums and objects, and its rich `trailprint::Error` onto the small public
//! [`TrailprintError`] (Kotlin: `TrailprintException`) in exactly one `From` impl.
//!
//! Threading: every exported object is `Send + Sync` with a `Mutex` inside where it holds
//! mutable state, so Kotlin may call it from any thread; long calls (fit, plan) block the
//! calling thread and should run on a background dispatcher.

mod building;
mod error;
mod model;
mod plan;
mod session;
mod store;
mod team;

pub use building::*;
pub use error::{Result, TrailprintError};
pub use model::*;
pub use plan::*;
pub use session::*;
pub use store::*;
pub use team::*;

uniffi::setup_scaffolding!();
