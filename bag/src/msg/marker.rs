//! `visualization_msgs/Marker` and `MarkerArray`: shapes, lines and labels that Foxglove,
//! Lichtblick and RViz draw (tracks and people of a run, replayed with `ros2 bag play`).
//!
//! The fields are those of ROS 2 **Humble** (`rosbags`' Humble type store, the definition
//! written as the MCAP schema). Humble and later carry the texture and mesh fields
//! (`texture_resource`, `texture`, `uv_coordinates`, `mesh_file`) that ROS 1 Noetic's
//! `Marker` lacks; Jazzy's definition is Humble's plus the constant `ARROW_STRIP = 12`, the
//! same bytes on the wire. `visualization_msgs` was chosen over the `foxglove` schemas
//! because `ros2 bag play` and RViz understand it as well as Foxglove and Lichtblick do, and
//! no crate is needed: the types are written here like every other message.
//!
//! A ROS 1 bag's `Marker` ([`Ros1Marker`], MD5 checked: Noetic's, or Indigo-to-Lunar's whose
//! constants differ but not the fields) reads into a [`Marker`] with empty texture and mesh
//! fields; writing one to ROS 1 drops them.

use serde::{Deserialize, Serialize};

use super::{Header, Message, Point, Pose, Ros1Header, Vector3, definitions};

/// `builtin_interfaces/Duration` (ROS 1 `duration`: the same eight bytes, its nanoseconds
/// read unsigned).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Duration {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds, 0..1e9.
    pub nanosec: u32,
}

/// `std_msgs/ColorRGBA`: each channel 0–1.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ColorRgba {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Opacity (0 is invisible).
    pub a: f32,
}

/// `sensor_msgs/CompressedImage` (a marker's texture).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CompressedImage {
    /// Stamp and frame.
    pub header: Header,
    /// `jpeg` or `png`.
    pub format: String,
    /// The compressed image.
    pub data: Vec<u8>,
}

/// `visualization_msgs/UVCoordinate`: a texture coordinate.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct UvCoordinate {
    /// u.
    pub u: f32,
    /// v.
    pub v: f32,
}

/// `visualization_msgs/MeshFile`: a mesh sent inside the marker.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MeshFile {
    /// The mesh's file name (its extension tells the format).
    pub filename: String,
    /// The file's bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/Marker` as ROS 2 Humble has it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// Stamp and frame.
    pub header: Header,
    /// Namespace: with `id`, names the marker.
    pub ns: String,
    /// Id within the namespace.
    pub id: i32,
    /// The shape: [`Marker::SPHERE`], [`Marker::LINE_STRIP`], … (`type` in ROS).
    #[serde(rename = "type")]
    pub type_: i32,
    /// [`Marker::ADD`], [`Marker::DELETE`] or [`Marker::DELETEALL`].
    pub action: i32,
    /// Pose of the shape (points are relative to it).
    pub pose: Pose,
    /// Size, metres (a line's width is `scale.x`).
    pub scale: Vector3,
    /// Colour (where `colors` is empty).
    pub color: ColorRgba,
    /// How long the marker stays (0: until replaced or deleted).
    pub lifetime: Duration,
    /// Whether the marker moves with its frame.
    pub frame_locked: bool,
    /// Points of lists and strips.
    pub points: Vec<Point>,
    /// A colour per point (or empty).
    pub colors: Vec<ColorRgba>,
    /// Texture resource URI (Humble and later).
    pub texture_resource: String,
    /// Texture image (Humble and later).
    pub texture: CompressedImage,
    /// Texture coordinates, one per point (Humble and later).
    pub uv_coordinates: Vec<UvCoordinate>,
    /// Text of `TEXT_VIEW_FACING`.
    pub text: String,
    /// Mesh resource URI of `MESH_RESOURCE`.
    pub mesh_resource: String,
    /// Mesh sent inline (Humble and later).
    pub mesh_file: MeshFile,
    /// Whether a mesh's own materials are used.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// An arrow.
    pub const ARROW: i32 = 0;
    /// A box.
    pub const CUBE: i32 = 1;
    /// A sphere (an ellipsoid of `scale`).
    pub const SPHERE: i32 = 2;
    /// A cylinder.
    pub const CYLINDER: i32 = 3;
    /// A line through `points`.
    pub const LINE_STRIP: i32 = 4;
    /// A line per pair of `points`.
    pub const LINE_LIST: i32 = 5;
    /// A box at each point.
    pub const CUBE_LIST: i32 = 6;
    /// A sphere at each point.
    pub const SPHERE_LIST: i32 = 7;
    /// A square at each point.
    pub const POINTS: i32 = 8;
    /// `text`, facing the viewer.
    pub const TEXT_VIEW_FACING: i32 = 9;
    /// The mesh of `mesh_resource`.
    pub const MESH_RESOURCE: i32 = 10;
    /// A triangle per three `points`.
    pub const TRIANGLE_LIST: i32 = 11;
    /// Add or replace the marker `ns`/`id`.
    pub const ADD: i32 = 0;
    /// The same as [`Marker::ADD`].
    pub const MODIFY: i32 = 0;
    /// Delete the marker `ns`/`id`.
    pub const DELETE: i32 = 2;
    /// Delete every marker (of every namespace) shown so far.
    pub const DELETEALL: i32 = 3;
}

/// `visualization_msgs/Marker` as ROS 1 (Noetic) serialises it: no texture or mesh-file
/// fields.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Ros1Marker {
    /// Stamp and frame, with `seq`.
    pub header: Ros1Header,
    /// Namespace.
    pub ns: String,
    /// Id within the namespace.
    pub id: i32,
    /// The shape.
    #[serde(rename = "type")]
    pub type_: i32,
    /// The action.
    pub action: i32,
    /// Pose.
    pub pose: Pose,
    /// Size.
    pub scale: Vector3,
    /// Colour.
    pub color: ColorRgba,
    /// Lifetime.
    pub lifetime: Duration,
    /// Whether it moves with its frame.
    pub frame_locked: bool,
    /// Points.
    pub points: Vec<Point>,
    /// Colours per point.
    pub colors: Vec<ColorRgba>,
    /// Text.
    pub text: String,
    /// Mesh resource URI.
    pub mesh_resource: String,
    /// Whether a mesh's own materials are used.
    pub mesh_use_embedded_materials: bool,
}

/// A `$ty` with the fields that ROS 1 and ROS 2 markers share moved from `$m` (the header
/// through `$h`), and `$rest` (the ROS 2 fields, or nothing).
macro_rules! shared_fields {
    ($ty:ident, $m:expr, $h:expr, $($rest:tt)*) => {{
        let m = $m;
        $ty {
            header: $h(m.header),
            ns: m.ns,
            id: m.id,
            type_: m.type_,
            action: m.action,
            pose: m.pose,
            scale: m.scale,
            color: m.color,
            lifetime: m.lifetime,
            frame_locked: m.frame_locked,
            points: m.points,
            colors: m.colors,
            text: m.text,
            mesh_resource: m.mesh_resource,
            mesh_use_embedded_materials: m.mesh_use_embedded_materials,
            $($rest)*
        }
    }};
}

impl Message for Marker {
    const ROS2_TYPE: &'static str = "visualization_msgs/msg/Marker";
    const ROS1_MD5: Option<&'static str> = Some(definitions::MARKER_MD5);
    /// Indigo to Lunar: `uint8` constants, no `DELETEALL` (leg_tracker's training bags).
    const ROS1_OTHER_MD5S: &'static [&'static str] = &["18326976df9d29249efc939e00342cde"];
    const ROS2_DEFINITION: &'static str = definitions::MARKER_DEFINITION;
    type Ros1 = Ros1Marker;

    fn from_ros1(m: Ros1Marker) -> Self {
        shared_fields!(Self, m, Header::from, ..Self::default())
    }

    /// The ROS 1 form: the texture and mesh-file fields are dropped.
    fn to_ros1(&self) -> Ros1Marker {
        shared_fields!(Ros1Marker, self.clone(), |h: Header| Ros1Header::from(&h),)
    }
}

/// `visualization_msgs/MarkerArray`: markers shown together (`M` is [`Ros1Marker`] in the
/// ROS 1 wire form).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MarkerArray<M = Marker> {
    /// The markers, applied in order (a `DELETEALL` first clears what came before).
    pub markers: Vec<M>,
}

impl Message for MarkerArray {
    const ROS2_TYPE: &'static str = "visualization_msgs/msg/MarkerArray";
    const ROS1_MD5: Option<&'static str> = Some(definitions::MARKERARRAY_MD5);
    /// Indigo to Lunar (their `Marker`'s constants differ, not its fields).
    const ROS1_OTHER_MD5S: &'static [&'static str] = &["90da67007c26525f655c1c269094e39f"];
    const ROS2_DEFINITION: &'static str = definitions::MARKERARRAY_DEFINITION;
    type Ros1 = MarkerArray<Ros1Marker>;

    fn from_ros1(wire: Self::Ros1) -> Self {
        Self {
            markers: wire.markers.into_iter().map(Marker::from_ros1).collect(),
        }
    }

    /// The ROS 1 form: the texture and mesh-file fields are dropped.
    fn to_ros1(&self) -> Self::Ros1 {
        MarkerArray {
            markers: self.markers.iter().map(Marker::to_ros1).collect(),
        }
    }
}
