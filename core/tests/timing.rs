//! The integration tests that measure time: time limits, cancellation lag, SIGKILL in
//! the middle of a write. They run one at a time ([`serial`]): tests in one process share
//! rayon's thread pool and the machine's cores, and another test's work would count in
//! their timings. Every other integration test is in `main.rs`.

use std::sync::{Mutex, MutexGuard};

mod plan_common;
mod store_common;

mod plan_control;
mod plan_scale;
mod planners;
mod session_kill;
mod store_kill;

static SERIAL: Mutex<()> = Mutex::new(());

/// Held for the whole of each test of this binary, so that they run one at a time.
pub fn serial() -> MutexGuard<'static, ()> {
    // A failed test poisons the lock; the next one still runs alone.
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}
