//! Gaussian-process pieces: the kernel, the hyperparameter fit and posterior prediction.

pub mod kernel;
pub mod predict;

pub use kernel::{Kernel, Point};
