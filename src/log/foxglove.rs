//! Foxglove's well-known message types, from Foxglove's own crate (`foxglove`, the
//! Foxglove SDK, MIT), and the few helpers ricochet needs to fill them from planar
//! quantities.
//!
//! The types are the SDK's protobuf messages (prost); the log writes them
//! protobuf-encoded, with the schema (a `FileDescriptorSet`) the SDK gives for each, as
//! the SDK's own writer does. Nested messages are `Option`s in protobuf; the helpers here
//! always fill them.
//!
//! Units: lengths in metres, angles through unit quaternions, colours as RGBA in `0..=1`,
//! times as [`Timestamp`] `{sec, nsec}` of *simulated* time since `t = 0` (which a viewer
//! shows as seconds after 1970-01-01).

pub use foxglove::messages::line_primitive::Type as LineType;
pub use foxglove::messages::log::Level as LogLevel;
pub use foxglove::messages::{
    ArrowPrimitive, Color, CubePrimitive, CylinderPrimitive, Duration, FrameTransform,
    FrameTransforms, KeyValuePair, LinePrimitive, Log, Point3, Pose, Quaternion, SceneEntity,
    SceneEntityDeletion, SceneUpdate, TextPrimitive, Timestamp, TriangleListPrimitive, Vector3,
};
pub use foxglove::{Decode, Encode};

use super::LogError;

/// One second in nanoseconds.
const NS_PER_S: u64 = 1_000_000_000;

/// The simulated time `t` (s) in whole nanoseconds, as MCAP `log_time` / `publish_time`.
///
/// Rounds to the nearest nanosecond. Rejects (with [`LogError::InvalidTime`]) a `t` that is
/// negative, NaN or infinite, or not below `2³²` s, the range of a Foxglove [`Timestamp`]
/// (about 136 years). `−0.0` is taken as `0`.
pub fn nanoseconds(t: f64) -> Result<u64, LogError> {
    // `u32::MAX + 1` seconds: the first time that `Timestamp::sec` cannot hold.
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

/// The simulated time `t` (s) as a Foxglove [`Timestamp`], rounded to the nearest
/// nanosecond; the checks of [`nanoseconds`].
pub fn timestamp(t: f64) -> Result<Timestamp, LogError> {
    let ns = nanoseconds(t)?;
    // `nanoseconds` keeps `ns / 10⁹` within u32.
    let sec = u32::try_from(ns / NS_PER_S).map_err(|_| LogError::InvalidTime { t })?;
    Ok(Timestamp::new(sec, (ns % NS_PER_S) as u32))
}

/// A [`Timestamp`] in seconds (s).
pub fn seconds(time: &Timestamp) -> f64 {
    f64::from(time.sec()) + f64::from(time.nsec()) / 1e9
}

/// The non-negative duration `d` (s) as an entity lifetime, rounded to the nearest
/// nanosecond (the checks of [`nanoseconds`]; lifetimes beyond `i32::MAX` s are clamped).
/// A zero lifetime means "until replaced or deleted".
pub fn lifetime(d: f64) -> Result<Duration, LogError> {
    let t = timestamp(d)?;
    Ok(Duration::new(
        i32::try_from(t.sec()).unwrap_or(i32::MAX),
        t.nsec(),
    ))
}

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

/// The 3-vector `(x, y, z)` (m).
pub fn vector3(x: f64, y: f64, z: f64) -> Vector3 {
    Vector3 { x, y, z }
}

/// The point `(x, y, z)` (m).
pub fn point3(x: f64, y: f64, z: f64) -> Point3 {
    Point3 { x, y, z }
}

/// The planar pose `(x, y, θ)` lifted to the height `z`: position `(x, y, z)` (m), rotation
/// `θ` (rad) about z.
pub fn planar_pose(x: f64, y: f64, theta: f64, z: f64) -> Pose {
    Pose {
        position: Some(vector3(x, y, z)),
        orientation: Some(about_z(theta)),
    }
}

/// The colour `(r, g, b, a)`, each in `0..=1`.
pub const fn rgba(r: f64, g: f64, b: f64, a: f64) -> Color {
    Color { r, g, b, a }
}

/// `color` with each of r, g, b multiplied by `factor` (clamped to `0..=1`).
pub fn scaled(color: Color, factor: f64) -> Color {
    let f = |c: f64| (c * factor).clamp(0.0, 1.0);
    rgba(f(color.r), f(color.g), f(color.b), color.a)
}

/// The planar transform `parent → child` at simulated time `t` (s): the child origin at
/// `(x, y, 0)` (m) of the parent, rotated by `theta` (rad) about z.
pub fn planar_transform(
    t: f64,
    parent: &str,
    child: &str,
    (x, y, theta): (f64, f64, f64),
) -> Result<FrameTransform, LogError> {
    Ok(FrameTransform {
        timestamp: Some(timestamp(t)?),
        parent_frame_id: parent.to_owned(),
        child_frame_id: child.to_owned(),
        translation: Some(vector3(x, y, 0.0)),
        rotation: Some(about_z(theta)),
    })
}

/// Appends `message`, protobuf-encoded as the Foxglove SDK encodes it, to `buffer`; on an
/// error `buffer` is left as it was.
pub fn append_protobuf<M: Encode>(
    buffer: &mut Vec<u8>,
    what: &'static str,
    message: &M,
) -> Result<(), LogError> {
    let start = buffer.len();
    message.encode(buffer).map_err(|e| {
        buffer.truncate(start);
        LogError::Protobuf {
            what,
            message: e.to_string(),
        }
    })
}

/// Appends `tf` protobuf-encoded to `buffer`: byte for byte what prost (the SDK's
/// [`Encode`]) writes for it, written field by field without prost's generic length passes
/// — the writer thread encodes ~100 of these per simulated second (issue 16). proto3 as
/// prost writes it: fields in tag order, a scalar equal to zero (`±0.0`, `0`) or an empty
/// string left out, a present sub-message (even empty) written with its length, doubles as
/// 8 little-endian bytes, integers and lengths as varints.
///
/// Each transform's timestamp and its translation and rotation are laid out in small
/// buffers on the stack first (their lengths then give the transform's, with no separate
/// length pass), and reach `buffer` in five copies (with the two names), not byte by byte:
/// 1,720 instructions for the three transforms of Kane's pendulum before, ~1,370 now
/// (callgrind, stop 31).
/// The test `frame_transforms_encode_as_prost_does` (`tests/all/unit/log_foxglove.rs`)
/// holds it to [`append_protobuf`].
pub fn append_frame_transforms(buffer: &mut Vec<u8>, tf: &FrameTransforms) {
    for t in &tf.transforms {
        // The timestamp sub-message, with its tag and length: at most 2 + 2 × 6 bytes.
        let mut time = Bytes::<14>::new();
        if let Some(ts) = &t.timestamp {
            let mut fields = Bytes::<12>::new();
            fields.uint32_field(1, ts.sec());
            fields.uint32_field(2, ts.nsec());
            time.push(1 << 3 | 2);
            time.push(fields.len as u8);
            time.extend(fields.as_slice());
        }
        // The translation and rotation sub-messages: at most 2 + 27 and 2 + 36 bytes.
        let mut pose = Bytes::<67>::new();
        if let Some(v) = &t.translation {
            pose.nested_doubles(4, &[v.x, v.y, v.z]);
        }
        if let Some(r) = &t.rotation {
            pose.nested_doubles(5, &[r.x, r.y, r.z, r.w]);
        }
        let string = |s: &str| {
            if s.is_empty() {
                0
            } else {
                1 + varint_len(s.len() as u64) + s.len()
            }
        };
        let len = time.len + string(&t.parent_frame_id) + string(&t.child_frame_id) + pose.len;
        // FrameTransforms.transforms = 1 (message, repeated).
        buffer.reserve(len + 11);
        buffer.push(1 << 3 | 2);
        varint(buffer, len as u64);
        buffer.extend_from_slice(time.as_slice());
        string_field(buffer, 2, &t.parent_frame_id);
        string_field(buffer, 3, &t.child_frame_id);
        buffer.extend_from_slice(pose.as_slice());
    }
}

/// A few bytes of protobuf laid out on the stack (at most `N`; the callers' sizes are
/// bounds of what they write).
struct Bytes<const N: usize> {
    bytes: [u8; N],
    len: usize,
}

impl<const N: usize> Bytes<N> {
    fn new() -> Self {
        Bytes {
            bytes: [0; N],
            len: 0,
        }
    }

    fn as_slice(&self) -> &[u8] {
        &self.bytes[..self.len]
    }

    fn push(&mut self, b: u8) {
        if let Some(slot) = self.bytes.get_mut(self.len) {
            *slot = b;
            self.len += 1;
        }
    }

    fn extend(&mut self, bytes: &[u8]) {
        if let Some(slots) = self.bytes.get_mut(self.len..self.len + bytes.len()) {
            slots.copy_from_slice(bytes);
            self.len += bytes.len();
        }
    }

    /// A uint32 field `tag` (below 16) holding `n`; left out when zero.
    fn uint32_field(&mut self, tag: u8, n: u32) {
        if n != 0 {
            self.push(tag << 3);
            let mut n = n;
            while n >= 0x80 {
                self.push((n as u8) | 0x80);
                n >>= 7;
            }
            self.push(n as u8);
        }
    }

    /// The sub-message field `tag` (below 16) of double fields 1, 2, … holding `values`
    /// (fixed64; zeros left out), with its length (below 128: at most 4 doubles).
    fn nested_doubles(&mut self, tag: u8, values: &[f64]) {
        self.push(tag << 3 | 2);
        self.push(doubles_len(values) as u8);
        for (k, &x) in values.iter().enumerate() {
            if x != 0.0 {
                self.push(((k as u8 + 1) << 3) | 1);
                self.extend(&x.to_le_bytes());
            }
        }
    }
}

/// The encoded length of double fields 1, 2, … holding `values` (bytes).
fn doubles_len(values: &[f64]) -> usize {
    9 * values.iter().filter(|&&x| x != 0.0).count()
}

/// A string field `tag` (below 16) holding `s`; left out when empty.
fn string_field(buffer: &mut Vec<u8>, tag: u8, s: &str) {
    if !s.is_empty() {
        buffer.push(tag << 3 | 2);
        varint(buffer, s.len() as u64);
        buffer.extend_from_slice(s.as_bytes());
    }
}

/// `n` as a protobuf varint: 7 bits a byte, least significant first.
fn varint(buffer: &mut Vec<u8>, mut n: u64) {
    while n >= 0x80 {
        buffer.push((n as u8) | 0x80);
        n >>= 7;
    }
    buffer.push(n as u8);
}

/// The length of `n` as a varint (bytes).
fn varint_len(n: u64) -> usize {
    (64 - (n | 1).leading_zeros() as usize).div_ceil(7)
}

/// One step of the path to a number: a field, or an element of a list field.
#[derive(Clone, Copy)]
enum Segment {
    Field(&'static str),
    Item(&'static str, usize),
}

/// Finds the first non-finite number of a message and names it by its path
/// (`entities[0].cubes[1].size.x`). The path is kept as segments on the stack and written
/// out only when a number is found, so that checking a clean message allocates nothing.
#[derive(Default)]
struct Finite {
    path: arrayvec::ArrayVec<Segment, 8>,
    found: Option<String>,
}

impl Finite {
    /// Checks the numbers `values` (with their names) under the current path.
    fn numbers(&mut self, values: &[(&'static str, f64)]) {
        if self.found.is_some() {
            return;
        }
        if let Some(&(name, _)) = values.iter().find(|(_, v)| !v.is_finite()) {
            let mut path = String::new();
            for segment in self.path.iter().copied().chain([Segment::Field(name)]) {
                let dot = if path.is_empty() { "" } else { "." };
                match segment {
                    Segment::Field(f) => path.push_str(&format!("{dot}{f}")),
                    Segment::Item(f, k) => path.push_str(&format!("{dot}{f}[{k}]")),
                }
            }
            self.found = Some(path);
        }
    }

    /// Runs `check` with `segment` appended to the path.
    fn at(&mut self, segment: Segment, check: impl FnOnce(&mut Self)) {
        if self.found.is_some() || self.path.try_push(segment).is_err() {
            return;
        }
        check(self);
        self.path.pop();
    }

    fn vector(&mut self, name: &'static str, v: Option<&Vector3>) {
        if let Some(v) = v {
            self.at(Segment::Field(name), |f| {
                f.numbers(&[("x", v.x), ("y", v.y), ("z", v.z)])
            });
        }
    }

    fn quaternion(&mut self, name: &'static str, q: Option<&Quaternion>) {
        if let Some(q) = q {
            self.at(Segment::Field(name), |f| {
                f.numbers(&[("x", q.x), ("y", q.y), ("z", q.z), ("w", q.w)])
            });
        }
    }

    fn pose(&mut self, pose: Option<&Pose>) {
        if let Some(p) = pose {
            self.at(Segment::Field("pose"), |f| {
                f.vector("position", p.position.as_ref());
                f.quaternion("orientation", p.orientation.as_ref());
            });
        }
    }

    fn color(&mut self, color: Option<&Color>) {
        if let Some(c) = color {
            self.at(Segment::Field("color"), |f| {
                f.numbers(&[("r", c.r), ("g", c.g), ("b", c.b), ("a", c.a)])
            });
        }
    }

    fn points(&mut self, points: &[Point3]) {
        for (k, p) in points.iter().enumerate() {
            self.at(Segment::Item("points", k), |f| {
                f.numbers(&[("x", p.x), ("y", p.y), ("z", p.z)])
            });
        }
    }

    fn entity(&mut self, e: &SceneEntity) {
        for (k, a) in e.arrows.iter().enumerate() {
            self.at(Segment::Item("arrows", k), |f| {
                f.pose(a.pose.as_ref());
                f.numbers(&[
                    ("shaft_length", a.shaft_length),
                    ("shaft_diameter", a.shaft_diameter),
                    ("head_length", a.head_length),
                    ("head_diameter", a.head_diameter),
                ]);
                f.color(a.color.as_ref());
            });
        }
        for (k, c) in e.cubes.iter().enumerate() {
            self.at(Segment::Item("cubes", k), |f| {
                f.pose(c.pose.as_ref());
                f.vector("size", c.size.as_ref());
                f.color(c.color.as_ref());
            });
        }
        for (k, c) in e.cylinders.iter().enumerate() {
            self.at(Segment::Item("cylinders", k), |f| {
                f.pose(c.pose.as_ref());
                f.vector("size", c.size.as_ref());
                f.numbers(&[("bottom_scale", c.bottom_scale), ("top_scale", c.top_scale)]);
                f.color(c.color.as_ref());
            });
        }
        for (k, l) in e.lines.iter().enumerate() {
            self.at(Segment::Item("lines", k), |f| {
                f.pose(l.pose.as_ref());
                f.numbers(&[("thickness", l.thickness)]);
                f.points(&l.points);
                f.color(l.color.as_ref());
            });
        }
        for (k, t) in e.triangles.iter().enumerate() {
            self.at(Segment::Item("triangles", k), |f| {
                f.pose(t.pose.as_ref());
                f.points(&t.points);
                f.color(t.color.as_ref());
            });
        }
        for (k, t) in e.texts.iter().enumerate() {
            self.at(Segment::Item("texts", k), |f| {
                f.pose(t.pose.as_ref());
                f.numbers(&[("font_size", t.font_size)]);
                f.color(t.color.as_ref());
            });
        }
    }
}

/// The first non-finite number of a scene update (a NaN or an infinity, which a viewer
/// cannot draw), named by its path, e.g. `entities[0].cubes[1].size.x`.
pub fn first_non_finite_scene(update: &SceneUpdate) -> Option<String> {
    let mut f = Finite::default();
    for (k, e) in update.entities.iter().enumerate() {
        f.at(Segment::Item("entities", k), |f| f.entity(e));
    }
    f.found
}

/// The first non-finite number of frame transforms, named by its path, e.g.
/// `transforms[1].rotation.w`.
pub fn first_non_finite_transforms(tf: &FrameTransforms) -> Option<String> {
    // The common case, checked once per sample: every number finite.
    let finite = |xs: &[f64]| xs.iter().all(|x| x.is_finite());
    let clean = tf.transforms.iter().all(|t| {
        (t.translation.as_ref()).is_none_or(|v| finite(&[v.x, v.y, v.z]))
            && (t.rotation.as_ref()).is_none_or(|r| finite(&[r.x, r.y, r.z, r.w]))
    });
    if clean {
        return None;
    }
    let mut f = Finite::default();
    for (k, t) in tf.transforms.iter().enumerate() {
        f.at(Segment::Item("transforms", k), |f| {
            f.vector("translation", t.translation.as_ref());
            f.quaternion("rotation", t.rotation.as_ref());
        });
    }
    f.found
}
