//! What the bag tests share: the shared data, and the zipped ROS 1 bag unzipped once.
#![allow(dead_code)]

#[path = "../../../tests/support/bag.rs"]
mod bag;
#[path = "../../../tests/support/data.rs"]
mod data;
pub use bag::{moving_bag, moving_mcap};
#[allow(unused_imports)]
pub use data::shared_data;
