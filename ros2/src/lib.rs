//! # haunts-ros2
//!
//! The haunts live session as a ROS 2 node over DDS, with no ROS install: `ros2-client` on
//! RustDDS speaks the same wire protocol and topic naming as `rmw_fastrtps` and
//! `rmw_cyclonedds`, so the node talks to a robot's drivers and to Nav2 directly.
//!
//! - [`node::HauntsNode`]: subscribes to `sensor_msgs/LaserScan`, `nav_msgs/Odometry`, `/tf`
//!   and `/tf_static`; pushes them into a [`haunts::live::LiveSession`] in the order they
//!   were sent; publishes the people after every tracked scan as `geometry_msgs/PoseArray`
//!   and `visualization_msgs/MarkerArray`; serves a layout of the library as Nav2 reads it
//!   ([`maps`]); closes the day on request, at an hour, or when its owner says (a signal),
//!   merging it into the library atomically and serving the maps again.
//! - [`publish::DdsReplay`]: a recording published onto its topics with `/clock`.
//! - [`wire`]: topic types and QoS, and the messages the haunts message set lacks.
//!
//! # Example
//! A node and a replay on one machine (DDS discovery sends multicast on every interface; see
//! the crate's README for running it inside a network namespace):
//! ```no_run
//! use haunts_ros2::node::{HauntsNode, NodeParams};
//! use haunts_ros2::ros2_client::dds::Context;
//! use std::sync::atomic::AtomicBool;
//! use std::time::Duration;
//!
//! let context = Context::new()?;
//! let mut node = HauntsNode::new(&context, NodeParams::default().with_library("library.haunts", "day.mcap"))?;
//! let stop = AtomicBool::new(false); // set by a SIGINT handler, say
//! node.spin_until(&stop, Duration::from_millis(100))?;
//! let day = node.close_day()?;
//! println!("day {} joined layout {:?}", day.label, day.layout);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod maps;
pub mod node;
pub mod publish;
pub mod wire;

pub use ros2_client;

/// A DDS context on the domain `ROS_DOMAIN_ID` names (0 when it is unset), as every ROS 2
/// node picks its domain.
///
/// # Errors
/// `ROS_DOMAIN_ID` is not a number from 0 to 232 (the range ROS 2 allows on Linux); the
/// middleware's error.
pub fn context_from_env() -> Result<ros2_client::dds::Context> {
    let domain = match std::env::var("ROS_DOMAIN_ID") {
        Ok(v) if !v.trim().is_empty() => v
            .trim()
            .parse::<u16>()
            .ok()
            .filter(|d| *d <= 232)
            .ok_or_else(|| Error::Invalid(format!("ROS_DOMAIN_ID {v:?} is not 0 to 232")))?,
        _ => 0,
    };
    ros2_client::dds::Context::with_options(
        ros2_client::dds::ContextOptions::new().domain_id(domain),
    )
    .map_err(Error::dds)
}

/// What went wrong.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The middleware refused (creating a node, a topic, a reader or a writer).
    #[error("DDS: {0}")]
    Dds(String),
    /// A parameter or a name that does not check.
    #[error("{0}")]
    Invalid(String),
    /// The session's, the recording's or the library's error.
    #[error(transparent)]
    Pipeline(#[from] haunts::pipeline::PipelineError),
    /// The operating system's error (polling, a thread).
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

impl Error {
    fn dds(e: impl std::fmt::Debug) -> Self {
        Self::Dds(format!("{e:?}"))
    }
}

impl From<haunts::core::InvalidParameter> for Error {
    fn from(e: haunts::core::InvalidParameter) -> Self {
        Self::Invalid(e.to_string())
    }
}

/// The crate's result.
pub type Result<T, E = Error> = std::result::Result<T, E>;
