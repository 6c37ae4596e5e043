//! What a log says of one of its topics: the leaf both readers fill.

use crate::codec::Encoding;

/// One topic of a log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicInfo {
    /// Its name (e.g. `/scan`).
    pub name: String,
    /// The recorded type name (`sensor_msgs/LaserScan` in ROS 1, `sensor_msgs/msg/LaserScan`
    /// in ROS 2).
    pub type_name: String,
    /// How its messages are serialised.
    pub encoding: Encoding,
    /// The ROS 1 MD5 sum of its definition, when the file records one.
    pub md5: Option<String>,
    /// How many messages it has, when the index says.
    pub count: Option<u64>,
}
