//! The built-in kernels.

mod combinators;
#[cfg(feature = "serde")]
mod repr;
mod simple;
mod stationary;

pub use combinators::{Constrained, Product, Scaled, Sum};
pub use simple::{Constant, White};
pub use stationary::{Matern32, Matern52, Periodic, Rbf, RbfArd};
