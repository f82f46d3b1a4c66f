//! Gaussian-process pieces: the kernel, the hyperparameter fit and posterior prediction.

pub mod fit;
pub mod kernel;
pub mod predict;

pub use fit::{FitResult, fit_kernel};
pub use kernel::{Extent, Kernel, Point};
