//! What the bag tests share: the shared data, and the zipped ROS 1 bag unzipped once.
#![allow(dead_code)]

#[allow(unused_imports)]
pub use bag::{moving_bag, moving_mcap};
#[allow(unused_imports)]
pub use data::shared_data;
use haunts_test_support::bag;
use haunts_test_support::data;
