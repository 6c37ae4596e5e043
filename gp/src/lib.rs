#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod error;
mod exact;
mod grid;
mod kernel;
mod kernels;
mod linalg;
mod optimise;
mod sparse;
mod sparse_optimise;

pub use error::{GpError, Result};
pub use exact::{ExactGp, GpRegression, Mean, Prediction};
pub use grid::{Grid2, GridCheck, GridMode, GridPrediction, chebyshev_interpolation};
pub use kernel::{Kernel, KernelClone, check_points, covariance, cross_covariance};
pub use kernels::{
    Constant, Constrained, Matern32, Matern52, Periodic, Product, Rbf, RbfArd, Scaled, Sum, White,
};
pub use linalg::JitterPolicy;
pub use optimise::{OptimisationReport, OptimiseOptions};
pub use sparse::{Inducing, SparseGp, SparseGpRegression, SparseMethod};
pub use sparse_optimise::SparseObjective;
