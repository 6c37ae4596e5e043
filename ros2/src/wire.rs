//! What goes on the wire: the topics' names and ROS 2 types, their QoS, and the few messages
//! the haunts message set (`haunts::bag::msg`) does not have.
//!
//! Every message is serialised by `ros2-client` as CDR with the serde derives of
//! `haunts::bag::msg`, the same types `haunts` reads from and writes to ROS 2 MCAP: the node
//! and a recording agree byte for byte.

use std::time::Duration;

use haunts::bag::msg::{Header, Time};
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::{MessageTypeName, Name, QosProfile};
use serde::{Deserialize, Serialize};

/// `rosgraph_msgs/msg/Clock`: the simulated time a replay publishes on `/clock`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Clock {
    /// The time.
    pub clock: Time,
}

impl Clock {
    /// Its ROS 2 type.
    pub const ROS2_TYPE: &'static str = "rosgraph_msgs/msg/Clock";
}

/// `std_msgs/msg/Empty`: a request with nothing to say (closing the day). Its CDR form has
/// the one byte rosidl gives an empty structure.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Empty {
    /// rosidl's placeholder member of an empty message.
    pub structure_needs_at_least_one_member: u8,
}

impl Empty {
    /// Its ROS 2 type.
    pub const ROS2_TYPE: &'static str = "std_msgs/msg/Empty";
}

/// `nav2_msgs/msg/CostmapFilterInfo`: how Nav2's costmap filters read a filter mask.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CostmapFilterInfo {
    /// Stamp and frame.
    pub header: Header,
    /// The filter: [`CostmapFilterInfo::KEEPOUT`], [`CostmapFilterInfo::SPEED_PERCENT`] or
    /// [`CostmapFilterInfo::SPEED_ABSOLUTE`].
    #[serde(rename = "type")]
    pub type_: u8,
    /// The topic of the mask (`nav_msgs/OccupancyGrid`).
    pub filter_mask_topic: String,
    /// `speed_limit = base + multiplier · mask_value` for a mask value in 1..=100 (0: no limit).
    pub base: f32,
    /// See [`CostmapFilterInfo::base`].
    pub multiplier: f32,
}

impl CostmapFilterInfo {
    /// Its ROS 2 type.
    pub const ROS2_TYPE: &'static str = "nav2_msgs/msg/CostmapFilterInfo";
    /// A keepout or lanes mask.
    pub const KEEPOUT: u8 = 0;
    /// A speed limit in percent of the robot's maximum speed.
    pub const SPEED_PERCENT: u8 = 1;
    /// A speed limit in metres per second.
    pub const SPEED_ABSOLUTE: u8 = 2;
}

/// The `ros2-client` type name of a ROS 2 type written `package/msg/Name` (as
/// [`haunts::bag::msg::Message::ROS2_TYPE`] writes it); `None` when it is not of that form.
///
/// ```
/// let name = haunts_ros2::wire::type_name("sensor_msgs/msg/LaserScan").unwrap();
/// assert_eq!(name.dds_msg_type(), "sensor_msgs::msg::dds_::LaserScan_");
/// assert!(haunts_ros2::wire::type_name("LaserScan").is_none());
/// ```
pub fn type_name(ros2: &str) -> Option<MessageTypeName> {
    let (package, name) = ros2.split_once("/msg/")?;
    (!package.is_empty() && !name.is_empty() && !name.contains('/'))
        .then(|| MessageTypeName::new(package, name))
}

/// A topic name (`/scan`, `/haunts/people`, or relative: `scan`) as `ros2-client` names it.
///
/// # Errors
/// The name breaks ROS 2's rules (empty, a character other than letters, digits, `_` and
/// `/`, a doubled `/`, a trailing `/`).
pub fn topic_name(topic: &str) -> Result<Name, String> {
    Name::parse(topic).map_err(|e| format!("topic name {topic:?}: {e:?}"))
}

/// QoS of the sensor streams the node reads (`/scan`, `/odom`, `/tf`): best effort, which a
/// reliable or a best-effort publisher both match (stock laser drivers publish best effort,
/// rclcpp's `SensorDataQoS`; odometry and tf are usually reliable), volatile, the last
/// `depth` messages kept.
pub fn sensor_qos(depth: usize) -> QosProfile {
    QosProfile::subscription_default()
        .reliability(Reliability::BestEffort)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth })
}

/// QoS of a stream the node publishes (people, markers) and a replay publishes: reliable,
/// volatile, the last `depth` kept; a best-effort reader matches it too.
pub fn stream_qos(depth: usize) -> QosProfile {
    QosProfile::publisher_default()
        .reliability(Reliability::Reliable {
            when_full: WhenFull::Wait(Duration::from_millis(100)),
        })
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth })
}

/// QoS of what a late subscriber must still get (`/tf_static`, the maps, the filter info):
/// reliable and transient local, the last message kept, as `tf2`'s static broadcaster and
/// Nav2's map server publish.
pub fn latched_qos() -> QosProfile {
    QosProfile::publisher_default()
        .reliability(Reliability::Reliable {
            when_full: WhenFull::Wait(Duration::from_millis(100)),
        })
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use byteorder::LittleEndian;

    fn encode<T: Serialize>(m: &T) -> Vec<u8> {
        cdr_encoding::to_vec::<T, LittleEndian>(m).unwrap()
    }

    /// The messages defined here have their ROS 2 wire layout: checked against bytes laid out
    /// by hand from the CDR rules (little endian, strings with their length and NUL, floats
    /// aligned to 4).
    #[test]
    fn costmap_filter_info_has_its_cdr_layout() {
        let info = CostmapFilterInfo {
            header: Header {
                stamp: Time { sec: 7, nanosec: 9 },
                frame_id: "map".into(),
            },
            type_: CostmapFilterInfo::SPEED_PERCENT,
            filter_mask_topic: "/m".into(),
            base: 100.0,
            multiplier: -0.5,
        };
        let bytes = encode(&info);
        let mut want = Vec::new();
        want.extend(7i32.to_le_bytes());
        want.extend(9u32.to_le_bytes());
        want.extend(4u32.to_le_bytes());
        want.extend(b"map\0");
        want.push(1); // type, then 3 bytes of padding before the string's length
        want.extend([0, 0, 0]);
        want.extend(3u32.to_le_bytes());
        want.extend(b"/m\0");
        want.push(0); // padding to 4 for the float
        want.extend(100f32.to_le_bytes());
        want.extend((-0.5f32).to_le_bytes());
        assert_eq!(bytes, want);
        let (back, _) =
            cdr_encoding::from_bytes::<CostmapFilterInfo, LittleEndian>(&bytes).unwrap();
        assert_eq!(back, info);
    }

    #[test]
    fn clock_and_empty_have_their_cdr_layout() {
        let clock = Clock {
            clock: Time { sec: 1, nanosec: 2 },
        };
        let mut want = Vec::new();
        want.extend(1i32.to_le_bytes());
        want.extend(2u32.to_le_bytes());
        assert_eq!(encode(&clock), want);
        assert_eq!(encode(&Empty::default()), [0]);
    }

    #[test]
    fn names_are_checked() {
        assert!(topic_name("/haunts/people").is_ok());
        assert!(topic_name("/haunts//people").is_err());
        assert!(topic_name("").is_err());
        assert!(type_name("nav2_msgs/msg/CostmapFilterInfo").is_some());
        assert!(type_name("/msg/X").is_none());
    }
}
