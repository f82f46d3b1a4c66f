//! Kotlin bindings for Trailprint (filled in by the bindings issue).
uniffi::setup_scaffolding!();
