#![doc = include_str!("../README.md")]
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod error;
mod kernel;
mod kernels;

pub use error::{GpError, Result};
pub use kernel::{Kernel, KernelClone, check_points, covariance, cross_covariance};
pub use kernels::{
    Constant, Matern32, Matern52, Periodic, Product, Rbf, RbfArd, Scaled, Sum, White,
};
