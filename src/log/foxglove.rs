//! Foxglove message types, mirrored field for field from the official JSON schemas shipped in
//! `schemas/foxglove/` (npm `@foxglove/schemas` 2.1.0, MIT).
//!
//! Foxglove's schemas mark every field as required, so every struct here serializes every
//! field, and the primitive lists of a [`SceneEntity`] are emitted even when empty. Enums
//! that the schemas encode as integers (`LineType`, `LogLevel`, `SceneEntityDeletionType`)
//! serialize as those integers.
//!
//! Units: lengths in metres, angles through unit quaternions, colours as RGBA in `0..=1`,
//! times as [`Time`] `{sec, nsec}` of *simulated* time since `t = 0`.

use serde::{Deserialize, Serialize};

use super::LogError;

/// One second in nanoseconds.
const NS_PER_S: u64 = 1_000_000_000;

/// A point in time (`foxglove.Time`, schema title `time`): whole seconds and nanoseconds
/// since the epoch. ricochet's epoch is the start of the simulation, `t = 0`.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
pub struct Time {
    /// Whole seconds (s).
    pub sec: u32,
    /// Nanoseconds past `sec`, in `0..1_000_000_000` (ns).
    pub nsec: u32,
}

impl Time {
    /// The time `t` (s) rounded to the nearest nanosecond.
    ///
    /// Errors with [`LogError::InvalidTime`] when `t` is negative, NaN or infinite, or not
    /// below `2³²` s (the range of `sec`). `−0.0` is taken as `0`.
    pub fn from_seconds(t: f64) -> Result<Time, LogError> {
        let ns = nanoseconds(t)?;
        Ok(Time::from_nanos(ns))
    }

    /// The time `ns` nanoseconds after the epoch. `ns` must be below `2³²` s for `sec` to
    /// hold it; [`nanoseconds`] guarantees that.
    fn from_nanos(ns: u64) -> Time {
        Time {
            sec: u32::try_from(ns / NS_PER_S).unwrap_or(u32::MAX),
            nsec: (ns % NS_PER_S) as u32,
        }
    }

    /// This time in nanoseconds since the epoch.
    pub fn as_nanos(self) -> u64 {
        u64::from(self.sec) * NS_PER_S + u64::from(self.nsec)
    }

    /// This time in seconds since the epoch (s).
    pub fn as_seconds(self) -> f64 {
        f64::from(self.sec) + f64::from(self.nsec) / 1e9
    }
}

/// The simulated time `t` (s) in whole nanoseconds, as MCAP `log_time` / `publish_time`.
///
/// Rounds to the nearest nanosecond. Rejects (with [`LogError::InvalidTime`]) a `t` that is
/// negative, NaN or infinite, or not below `2³²` s, the range of a Foxglove [`Time`]
/// (about 136 years). `−0.0` is taken as `0`.
pub fn nanoseconds(t: f64) -> Result<u64, LogError> {
    // `u32::MAX + 1` seconds: the first time that `Time::sec` cannot hold.
    const LIMIT_S: f64 = 4_294_967_296.0;
    // NaN and ±∞ fall outside the range; −0.0 is inside.
    if !(0.0..LIMIT_S).contains(&t) {
        return Err(LogError::InvalidTime { t });
    }
    // t < 2³² s, so t·10⁹ < 4.3·10¹⁸ < u64::MAX: the cast does not saturate.
    let ns = (t * 1e9).round() as u64;
    // Rounding may carry into second 2³²; refuse rather than wrap.
    if ns / NS_PER_S > u64::from(u32::MAX) {
        return Err(LogError::InvalidTime { t });
    }
    Ok(ns)
}

/// A signed span of time (`foxglove.Duration`, schema title `duration`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Duration {
    /// Whole seconds, may be negative (s).
    pub sec: i32,
    /// Nanoseconds in the positive direction, in `0..1_000_000_000` (ns).
    pub nsec: u32,
}

impl Duration {
    /// The zero duration. As a [`SceneEntity::lifetime`] it means "until deleted".
    pub const FOREVER: Duration = Duration { sec: 0, nsec: 0 };

    /// The non-negative duration `d` (s), rounded to the nearest nanosecond; the same
    /// checks as [`Time::from_seconds`].
    pub fn from_seconds(d: f64) -> Result<Duration, LogError> {
        let t = Time::from_seconds(d)?;
        Ok(Duration {
            // `Time::sec` may exceed `i32::MAX`; such lifetimes are clamped (~68 years).
            sec: i32::try_from(t.sec).unwrap_or(i32::MAX),
            nsec: t.nsec,
        })
    }
}

/// A 3-vector (`foxglove.Vector3`): a translation or a size (m).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x component (m).
    pub x: f64,
    /// y component (m).
    pub y: f64,
    /// z component (m).
    pub z: f64,
}

impl Vector3 {
    /// The vector `(x, y, z)`.
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }
}

/// A point (`foxglove.Point3`) in the frame of the primitive that holds it (m).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point3 {
    /// x coordinate (m).
    pub x: f64,
    /// y coordinate (m).
    pub y: f64,
    /// z coordinate (m).
    pub z: f64,
}

impl Point3 {
    /// The point `(x, y, z)`.
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }
}

/// A rotation as a unit quaternion `(x, y, z, w)` (`foxglove.Quaternion`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
    /// w (scalar) component.
    pub w: f64,
}

impl Quaternion {
    /// The identity rotation.
    pub const IDENTITY: Quaternion = Quaternion {
        x: 0.0,
        y: 0.0,
        z: 0.0,
        w: 1.0,
    };

    /// The rotation by `theta` (rad, counter-clockwise seen from +z) about the z axis:
    /// `(0, 0, sin θ/2, cos θ/2)`.
    pub fn about_z(theta: f64) -> Quaternion {
        let (s, c) = (0.5 * theta).sin_cos();
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }
}

impl Default for Quaternion {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// A position and orientation (`foxglove.Pose`) relative to the frame of the entity.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position (m).
    pub position: Vector3,
    /// Orientation.
    pub orientation: Quaternion,
}

impl Pose {
    /// The planar pose `(x, y, θ)` in the plane `z = 0`: position `(x, y, 0)` (m), rotation
    /// `θ` (rad) about z.
    pub fn planar(x: f64, y: f64, theta: f64) -> Pose {
        Pose {
            position: Vector3::new(x, y, 0.0),
            orientation: Quaternion::about_z(theta),
        }
    }
}

/// A colour (`foxglove.Color`): red, green, blue, alpha, each in `0..=1`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Color {
    /// Red in `0..=1`.
    pub r: f64,
    /// Green in `0..=1`.
    pub g: f64,
    /// Blue in `0..=1`.
    pub b: f64,
    /// Alpha (opacity) in `0..=1`.
    pub a: f64,
}

impl Color {
    /// The colour `(r, g, b, a)`, each in `0..=1`.
    pub const fn rgba(r: f64, g: f64, b: f64, a: f64) -> Self {
        Self { r, g, b, a }
    }

    /// The same colour with each of r, g, b multiplied by `factor` (clamped to `0..=1`).
    pub fn scaled(self, factor: f64) -> Self {
        let f = |c: f64| (c * factor).clamp(0.0, 1.0);
        Self::rgba(f(self.r), f(self.g), f(self.b), self.a)
    }
}

/// A key–value pair of strings (`foxglove.KeyValuePair`).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct KeyValuePair {
    /// Key.
    pub key: String,
    /// Value.
    pub value: String,
}

/// An arrow (`foxglove.ArrowPrimitive`) pointing along +x of its pose, tail at the pose's
/// position; its total length is `shaft_length + head_length`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ArrowPrimitive {
    /// Position of the tail and orientation of the arrow (+x points to the head).
    pub pose: Pose,
    /// Length of the shaft (m).
    pub shaft_length: f64,
    /// Diameter of the shaft (m).
    pub shaft_diameter: f64,
    /// Length of the head (m).
    pub head_length: f64,
    /// Diameter of the head (m).
    pub head_diameter: f64,
    /// Colour.
    pub color: Color,
}

/// A box (`foxglove.CubePrimitive`) centred at its pose.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CubePrimitive {
    /// Position of the centre and orientation.
    pub pose: Pose,
    /// Full extents along the pose's x, y, z axes (m).
    pub size: Vector3,
    /// Colour.
    pub color: Color,
}

/// An ellipsoid (`foxglove.SpherePrimitive`) centred at its pose.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SpherePrimitive {
    /// Position of the centre and orientation.
    pub pose: Pose,
    /// Diameters along the pose's x, y, z axes (m).
    pub size: Vector3,
    /// Colour.
    pub color: Color,
}

/// A cylinder or cone (`foxglove.CylinderPrimitive`) centred at its pose, axis along z.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CylinderPrimitive {
    /// Position of the centre and orientation (the axis is the pose's z axis).
    pub pose: Pose,
    /// Diameters along x and y of the bottom face, and the height along z (m).
    pub size: Vector3,
    /// Scale of the bottom face (1 for a cylinder, 0 for a cone pointing down).
    pub bottom_scale: f64,
    /// Scale of the top face (1 for a cylinder, 0 for a cone pointing up).
    pub top_scale: f64,
    /// Colour.
    pub color: Color,
}

/// How the points of a [`LinePrimitive`] are joined (`foxglove.LineType`, an integer).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(into = "u8", try_from = "u8")]
pub enum LineType {
    /// `0`: each point joined to the next.
    #[default]
    LineStrip,
    /// `1`: as a strip, and the last point joined back to the first.
    LineLoop,
    /// `2`: points taken in pairs, each pair a separate segment.
    LineList,
}

impl From<LineType> for u8 {
    fn from(t: LineType) -> u8 {
        match t {
            LineType::LineStrip => 0,
            LineType::LineLoop => 1,
            LineType::LineList => 2,
        }
    }
}

impl TryFrom<u8> for LineType {
    type Error = String;
    fn try_from(v: u8) -> Result<Self, Self::Error> {
        match v {
            0 => Ok(LineType::LineStrip),
            1 => Ok(LineType::LineLoop),
            2 => Ok(LineType::LineList),
            _ => Err(format!("invalid foxglove.LineType {v}")),
        }
    }
}

/// A polyline (`foxglove.LinePrimitive`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LinePrimitive {
    /// How the points are joined.
    #[serde(rename = "type")]
    pub line_type: LineType,
    /// Origin and orientation of the frame of `points`.
    pub pose: Pose,
    /// Width of the line: metres, or pixels when `scale_invariant`.
    pub thickness: f64,
    /// Whether `thickness` is in pixels, independent of the zoom.
    pub scale_invariant: bool,
    /// The points, in the frame of `pose` (m).
    pub points: Vec<Point3>,
    /// Colour of the whole line (used when `colors` is empty).
    pub color: Color,
    /// Per-point colours (empty, or one per point).
    pub colors: Vec<Color>,
    /// Indices into `points` to draw (empty: all points in order).
    pub indices: Vec<u32>,
}

/// A list of filled triangles (`foxglove.TriangleListPrimitive`): points taken in threes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TriangleListPrimitive {
    /// Origin and orientation of the frame of `points`.
    pub pose: Pose,
    /// The vertices, three per triangle, in the frame of `pose` (m).
    pub points: Vec<Point3>,
    /// Colour of all triangles (used when `colors` is empty).
    pub color: Color,
    /// Per-vertex colours (empty, or one per point).
    pub colors: Vec<Color>,
    /// Indices into `points` to draw (empty: all points in order).
    pub indices: Vec<u32>,
}

/// A text label (`foxglove.TextPrimitive`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TextPrimitive {
    /// Position of the text (and orientation, unless `billboard`).
    pub pose: Pose,
    /// Whether the text always faces the camera.
    pub billboard: bool,
    /// Font size: metres, or pixels when `scale_invariant`.
    pub font_size: f64,
    /// Whether `font_size` is in pixels, independent of the zoom.
    pub scale_invariant: bool,
    /// Colour.
    pub color: Color,
    /// The text.
    pub text: String,
}

/// A 3-D model (`foxglove.ModelPrimitive`). ricochet never draws one; the type exists so
/// that [`SceneEntity::models`] can be emitted (always empty) and read back.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ModelPrimitive {
    /// Origin and orientation of the model.
    pub pose: Pose,
    /// Scale factors along x, y, z.
    pub scale: Vector3,
    /// Solid colour applied when `override_color`.
    pub color: Color,
    /// Whether to replace the model's colours with `color`.
    pub override_color: bool,
    /// URL of the model, or empty when `data` holds it.
    pub url: String,
    /// Media type of `data` (e.g. `model/gltf-binary`).
    pub media_type: String,
    /// The model itself, base64-encoded, or empty when `url` is set.
    pub data: String,
}

/// A visual element of the 3-D scene (`foxglove.SceneEntity`): primitives sharing a frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SceneEntity {
    /// Simulated time at which the entity is valid.
    pub timestamp: Time,
    /// Frame of the primitives' poses (`world`, or `body_<name>` for a body).
    pub frame_id: String,
    /// Identifier, unique on the topic; a new entity with the same id replaces the old one.
    pub id: String,
    /// How long the entity is shown after `timestamp`; zero means until deleted.
    pub lifetime: Duration,
    /// Whether the entity moves with its frame (`true`) or stays where the frame was at
    /// `timestamp` (`false`).
    pub frame_locked: bool,
    /// Free-form key–value pairs shown on selection.
    pub metadata: Vec<KeyValuePair>,
    /// Arrows.
    pub arrows: Vec<ArrowPrimitive>,
    /// Boxes.
    pub cubes: Vec<CubePrimitive>,
    /// Ellipsoids.
    pub spheres: Vec<SpherePrimitive>,
    /// Cylinders.
    pub cylinders: Vec<CylinderPrimitive>,
    /// Lines.
    pub lines: Vec<LinePrimitive>,
    /// Triangle lists.
    pub triangles: Vec<TriangleListPrimitive>,
    /// Texts.
    pub texts: Vec<TextPrimitive>,
    /// Models (ricochet leaves this empty).
    pub models: Vec<ModelPrimitive>,
}

/// What a [`SceneEntityDeletion`] removes (`foxglove.SceneEntityDeletionType`, an integer).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(into = "u8", try_from = "u8")]
pub enum DeletionType {
    /// `0`: the entity whose id matches.
    #[default]
    MatchingId,
    /// `1`: every entity on the topic.
    All,
}

impl From<DeletionType> for u8 {
    fn from(t: DeletionType) -> u8 {
        match t {
            DeletionType::MatchingId => 0,
            DeletionType::All => 1,
        }
    }
}

impl TryFrom<u8> for DeletionType {
    type Error = String;
    fn try_from(v: u8) -> Result<Self, Self::Error> {
        match v {
            0 => Ok(DeletionType::MatchingId),
            1 => Ok(DeletionType::All),
            _ => Err(format!("invalid foxglove.SceneEntityDeletionType {v}")),
        }
    }
}

/// A command to remove entities (`foxglove.SceneEntityDeletion`).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SceneEntityDeletion {
    /// Only matching entities older than this are deleted.
    pub timestamp: Time,
    /// Which entities to delete.
    #[serde(rename = "type")]
    pub deletion_type: DeletionType,
    /// The id to match when `deletion_type` is [`DeletionType::MatchingId`].
    pub id: String,
}

/// An update of the 3-D scene (`foxglove.SceneUpdate`): deletions first, then new or
/// replaced entities. The message type of the `/scene` topic.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SceneUpdate {
    /// Entities to delete.
    pub deletions: Vec<SceneEntityDeletion>,
    /// Entities to add or replace.
    pub entities: Vec<SceneEntity>,
}

/// The pose of a child frame in its parent frame (`foxglove.FrameTransform`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameTransform {
    /// Simulated time of the transform.
    pub timestamp: Time,
    /// Parent frame (`world` for ricochet's bodies).
    pub parent_frame_id: String,
    /// Child frame (`body_<name>`).
    pub child_frame_id: String,
    /// Position of the child origin in the parent frame (m).
    pub translation: Vector3,
    /// Orientation of the child frame in the parent frame.
    pub rotation: Quaternion,
}

impl FrameTransform {
    /// The planar transform `parent → child` at simulated time `t` (s): the child origin at
    /// `(x, y, 0)` (m) of the parent, rotated by `theta` (rad) about z.
    pub fn planar(
        t: f64,
        parent: &str,
        child: &str,
        (x, y, theta): (f64, f64, f64),
    ) -> Result<FrameTransform, LogError> {
        let pose = Pose::planar(x, y, theta);
        Ok(FrameTransform {
            timestamp: Time::from_seconds(t)?,
            parent_frame_id: parent.to_owned(),
            child_frame_id: child.to_owned(),
            translation: pose.position,
            rotation: pose.orientation,
        })
    }
}

/// A set of frame transforms (`foxglove.FrameTransforms`), the message type of `/tf`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameTransforms {
    /// The transforms.
    pub transforms: Vec<FrameTransform>,
}

/// Severity of a [`Log`] message (`foxglove.LogLevel`, an integer).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
#[serde(into = "u8", try_from = "u8")]
pub enum LogLevel {
    /// `0`: unknown.
    #[default]
    Unknown,
    /// `1`: debugging detail.
    Debug,
    /// `2`: information, e.g. a contact mode change.
    Info,
    /// `3`: a warning, e.g. an accumulation of impacts or a large energy drift.
    Warning,
    /// `4`: an error that stopped the run.
    Error,
    /// `5`: a fatal error.
    Fatal,
}

impl From<LogLevel> for u8 {
    fn from(l: LogLevel) -> u8 {
        match l {
            LogLevel::Unknown => 0,
            LogLevel::Debug => 1,
            LogLevel::Info => 2,
            LogLevel::Warning => 3,
            LogLevel::Error => 4,
            LogLevel::Fatal => 5,
        }
    }
}

impl TryFrom<u8> for LogLevel {
    type Error = String;
    fn try_from(v: u8) -> Result<Self, String> {
        match v {
            0 => Ok(LogLevel::Unknown),
            1 => Ok(LogLevel::Debug),
            2 => Ok(LogLevel::Info),
            3 => Ok(LogLevel::Warning),
            4 => Ok(LogLevel::Error),
            5 => Ok(LogLevel::Fatal),
            _ => Err(format!("invalid foxglove.LogLevel {v}")),
        }
    }
}

/// A text log message (`foxglove.Log`), the message type of `/log`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Log {
    /// Simulated time of the message.
    pub timestamp: Time,
    /// Severity.
    pub level: LogLevel,
    /// The message.
    pub message: String,
    /// Name of the emitter (ricochet writes `ricochet`).
    pub name: String,
    /// Source file (ricochet writes an empty string).
    pub file: String,
    /// Source line (ricochet writes 0).
    pub line: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_splits_seconds_and_nanoseconds() {
        let t = Time::from_seconds(1.25).unwrap();
        assert_eq!(
            t,
            Time {
                sec: 1,
                nsec: 250_000_000
            }
        );
        assert_eq!(t.as_nanos(), 1_250_000_000);
        assert_eq!(Time::from_seconds(-0.0).unwrap(), Time::default());
        // 0.1 s is 100 000 000.000000006 ns in binary; rounding gives the decimal value.
        assert_eq!(nanoseconds(0.1).unwrap(), 100_000_000);
        // Rounding to the nearest ns carries into the next second.
        assert_eq!(
            Time::from_seconds(2.999_999_999_6).unwrap(),
            Time { sec: 3, nsec: 0 }
        );
    }

    #[test]
    fn invalid_times_are_rejected() {
        for t in [
            -1e-9,
            -1.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            4_294_967_296.0,
        ] {
            assert!(
                matches!(nanoseconds(t), Err(LogError::InvalidTime { .. })),
                "{t} accepted"
            );
        }
        // The last representable second is accepted.
        assert_eq!(Time::from_seconds(4_294_967_295.5).unwrap().sec, u32::MAX);
    }

    #[test]
    fn enums_serialize_as_the_schema_integers() {
        assert_eq!(serde_json::to_string(&LogLevel::Warning).unwrap(), "3");
        assert_eq!(serde_json::to_string(&LineType::LineList).unwrap(), "2");
        assert_eq!(serde_json::to_string(&DeletionType::All).unwrap(), "1");
        assert_eq!(
            serde_json::from_str::<LogLevel>("5").unwrap(),
            LogLevel::Fatal
        );
        assert!(serde_json::from_str::<LineType>("3").is_err());
    }

    #[test]
    fn quaternion_about_z_rotates_x_to_the_angle() {
        // Rotating (1, 0, 0) by q = (0, 0, s, c): x' = c² − s² = cos θ, y' = 2sc = sin θ.
        let theta = 0.7;
        let q = Quaternion::about_z(theta);
        assert!((q.w * q.w - q.z * q.z - theta.cos()).abs() < 1e-15);
        assert!((2.0 * q.w * q.z - theta.sin()).abs() < 1e-15);
        assert!((q.w * q.w + q.z * q.z - 1.0).abs() < 1e-15);
    }
}
