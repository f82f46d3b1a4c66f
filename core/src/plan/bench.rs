//! Benchmark runner (see `trailprint bench`).
