//! Gaussian-process pieces: the kernel, the hyperparameter fit and posterior prediction.

pub mod kernel;

pub use kernel::{Kernel, Point};
