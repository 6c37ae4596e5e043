//! The ROS 2 message definitions (`ros2msg` text, dependencies after `MSG:` separators) and
//! ROS 1 MD5 sums of the built-in messages, generated once from the `rosbags` Python
//! package's type stores (ROS 2 Humble, ROS 1 Noetic; `benches/peers/ros_definitions.py`).

/// `sensor_msgs/msg/LaserScan` in ROS 2 (`ros2msg`).
pub const LASERSCAN_DEFINITION: &str = "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";

/// MD5 sum of `sensor_msgs/LaserScan` in ROS 1.
pub const LASERSCAN_MD5: &str = "90c7ef2dc6895d81024acba2ac42f369";

/// `nav_msgs/msg/Odometry` in ROS 2 (`ros2msg`).
pub const ODOMETRY_DEFINITION: &str = "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: geometry_msgs/PoseWithCovariance\ngeometry_msgs/Pose pose\nfloat64[36] covariance\n================================================================================\nMSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n================================================================================\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n================================================================================\nMSG: geometry_msgs/TwistWithCovariance\ngeometry_msgs/Twist twist\nfloat64[36] covariance\n================================================================================\nMSG: geometry_msgs/Twist\ngeometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n================================================================================\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";

/// MD5 sum of `nav_msgs/Odometry` in ROS 1.
pub const ODOMETRY_MD5: &str = "cd5e73d190d741a2f92e81eda573aca7";

/// `tf2_msgs/msg/TFMessage` in ROS 2 (`ros2msg`).
pub const TFMESSAGE_DEFINITION: &str = "geometry_msgs/TransformStamped[] transforms\n================================================================================\nMSG: geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: geometry_msgs/Transform\ngeometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n================================================================================\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";

/// MD5 sum of `tf2_msgs/TFMessage` in ROS 1.
pub const TFMESSAGE_MD5: &str = "94810edda583a504dfda3829e70d7eec";

/// `geometry_msgs/msg/PoseStamped` in ROS 2 (`ros2msg`).
pub const POSESTAMPED_DEFINITION: &str = "std_msgs/Header header\ngeometry_msgs/Pose pose\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n================================================================================\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";

/// MD5 sum of `geometry_msgs/PoseStamped` in ROS 1.
pub const POSESTAMPED_MD5: &str = "d3812c3cbc69362b77dc0b19b345f8f5";

/// `geometry_msgs/msg/PoseWithCovarianceStamped` in ROS 2 (`ros2msg`).
pub const POSEWITHCOVARIANCESTAMPED_DEFINITION: &str = "std_msgs/Header header\ngeometry_msgs/PoseWithCovariance pose\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: geometry_msgs/PoseWithCovariance\ngeometry_msgs/Pose pose\nfloat64[36] covariance\n================================================================================\nMSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n================================================================================\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";

/// MD5 sum of `geometry_msgs/PoseWithCovarianceStamped` in ROS 1.
pub const POSEWITHCOVARIANCESTAMPED_MD5: &str = "953b798c0f514ff060a53a3498ce6246";

/// `geometry_msgs/msg/PoseArray` in ROS 2 (`ros2msg`).
pub const POSEARRAY_DEFINITION: &str = "std_msgs/Header header\ngeometry_msgs/Pose[] poses\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n================================================================================\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";

/// MD5 sum of `geometry_msgs/PoseArray` in ROS 1.
pub const POSEARRAY_MD5: &str = "916c28c5764443f268b296bb671b9d97";

/// `nav_msgs/msg/OccupancyGrid` in ROS 2 (`ros2msg`).
pub const OCCUPANCYGRID_DEFINITION: &str = "std_msgs/Header header\nnav_msgs/MapMetaData info\nint8[] data\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: nav_msgs/MapMetaData\nbuiltin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 height\ngeometry_msgs/Pose origin\n================================================================================\nMSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n================================================================================\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";

/// MD5 sum of `nav_msgs/OccupancyGrid` in ROS 1.
pub const OCCUPANCYGRID_MD5: &str = "3381f2d731d4076ec5c71b0759edbe4e";

/// `nav_msgs/msg/Path` in ROS 2 (`ros2msg`).
pub const PATH_DEFINITION: &str = "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: geometry_msgs/PoseStamped\nstd_msgs/Header header\ngeometry_msgs/Pose pose\n================================================================================\nMSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n================================================================================\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";

/// MD5 sum of `nav_msgs/Path` in ROS 1.
pub const PATH_MD5: &str = "6227e2b7e9cce15051f669a5e197bbf7";
