#![doc = include_str!("../README.md")]

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
