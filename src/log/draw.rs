//! Drawing the scene for Foxglove's 3-D panel: parry2d shapes as Foxglove primitives in the
//! plane `z = 0`, body entities, frame transforms and impulse arrows.
//!
//! The layout of `/geometry`, `/scene` and `/tf`:
//! - `/geometry` holds one `SceneUpdate` that draws everything static or frame-locked, so
//!   that its latest message, at any time, describes the whole mechanism (a viewer that
//!   seeks shows, per topic, the latest message before the time it seeks to):
//!   - each body is an entity `body/<name>` in its own frame `body_<name>`, with
//!     `frame_locked: true`; it moves with the transforms;
//!   - a body without a collision shape gets a visual, the entity `visual/<name>`: its
//!     *skeleton*, a bar from its joint to each joint of its children and to its centre
//!     of mass, with a disc at the centre of mass ([`skeleton_entity`]), drawn
//!     translucent so that it is not taken for a shape that collides;
//!   - each static obstacle is an entity `world/<name>` in frame `world`;
//! - `/tf` carries, per output sample, one `FrameTransforms` with `world → body_<name>` for
//!   every body and `view → world`, where `view` is a frame that keeps the mechanism in view
//!   ([`ViewTracker`]), the root of the tree;
//! - `/scene` carries the impacts: each adds an entity `impulse/<pair>` in frame `world`,
//!   an arrow from the contact point along the impulse with its magnitude as text, shown
//!   for a finite lifetime. Successive impacts of a pair replace its arrow, so that an
//!   accumulation of impacts shows its latest impulse, not a smear of them.
//!
//! Solid shapes are slabs of thickness [`DrawStyle::depth`] centred on `z = 0`, so that a
//! top-down view shows their outline; lines and markers lie just above the slabs.

use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::math::{Pose as Pose2, Vector};
use parry2d_f64::shape::{Shape, TypedShape};

use super::LogError;
use super::foxglove::{
    ArrowPrimitive, Color, CubePrimitive, CylinderPrimitive, FrameTransform, FrameTransforms,
    KeyValuePair, LinePrimitive, LineType, Point3, Pose, SceneEntity, TextPrimitive,
    TriangleListPrimitive, lifetime, planar_pose, planar_transform, point3, rgba, scaled,
    timestamp, vector3,
};
use super::records::ImpactRecord;

/// The fixed frame of the scene.
pub const WORLD_FRAME: &str = "world";

/// The frame that follows the mechanism ([`ViewTracker`]); a layout's camera follows it.
pub const VIEW_FRAME: &str = "view";

/// The frame of body `name`: `body_<name>`.
pub fn body_frame(name: &str) -> String {
    format!("body_{name}")
}

/// How shapes are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawStyle {
    /// Thickness along z of the slab that stands for a solid shape (m).
    pub depth: f64,
    /// Width of lines: segments, polylines, outlines, markers (m).
    pub line_width: f64,
    /// Side of the square that stands for a half-space (m): 10 km by default, so that a
    /// long run (a rimless wheel rolls 740 m down its slope in 1000 s) stays on it.
    pub half_space_size: f64,
}

impl Default for DrawStyle {
    fn default() -> Self {
        Self {
            depth: 0.02,
            line_width: 0.01,
            half_space_size: 10_000.0,
        }
    }
}

impl DrawStyle {
    /// Height of lines and markers: just above the top face of the slabs (m).
    fn line_z(&self) -> f64 {
        0.5 * self.depth + self.line_width
    }
}

/// One shape to draw: the shape, its pose in the frame of its entity (the body frame, or the
/// world frame for an obstacle), and its colour.
#[derive(Clone, Copy)]
pub struct ShapeDrawing<'a> {
    /// The shape.
    pub shape: &'a dyn Shape,
    /// Pose of the shape in the entity's frame (m, rad).
    pub pose: Pose2,
    /// Colour.
    pub color: Color,
}

/// Adds the primitives that draw `shape`, placed at `pose` (m, rad) in the frame of
/// `entity`, to `entity`.
///
/// Ball: a disc (thin cylinder) with a radius line showing its rotation. Capsule: two discs
/// and a rectangle. Cuboid: a thin box. Convex polygon and triangle: a filled triangle
/// fan and its outline. Half-space: a large thin box below its boundary line. Segment: a
/// thin bar and its centre line; polyline: its segments as lines. Other shapes: [`LogError::UnsupportedShape`].
pub fn add_shape(
    entity: &mut SceneEntity,
    shape: &dyn Shape,
    pose: &Pose2,
    color: Color,
    style: &DrawStyle,
) -> Result<(), LogError> {
    let slab = |sub: Pose2, size_x: f64, size_y: f64| CubePrimitive {
        pose: Some(planar(&(*pose * sub), 0.0)),
        size: Some(vector3(size_x, size_y, style.depth)),
        color: Some(color),
    };
    let outline = |line_type: LineType, points: Vec<Point3>| LinePrimitive {
        r#type: line_type as i32,
        pose: Some(planar(pose, 0.0)),
        thickness: style.line_width,
        scale_invariant: false,
        points,
        color: Some(scaled(color, 0.5)),
        colors: vec![],
        indices: vec![],
    };
    let z = style.line_z();
    match shape.as_typed_shape() {
        TypedShape::Ball(ball) => {
            entity
                .cylinders
                .push(disc(pose, Vector::ZERO, ball.radius, color, style));
            let marker = vec![point3(0.0, 0.0, z), point3(ball.radius, 0.0, z)];
            entity.lines.push(outline(LineType::LineStrip, marker));
        }
        TypedShape::Capsule(capsule) => {
            let (a, b, r) = (capsule.segment.a, capsule.segment.b, capsule.radius);
            entity.cylinders.push(disc(pose, a, r, color, style));
            entity.cylinders.push(disc(pose, b, r, color, style));
            entity
                .cubes
                .push(slab(bar(a, b), (b - a).length(), 2.0 * r));
        }
        TypedShape::Cuboid(cuboid) => {
            let h = cuboid.half_extents;
            entity
                .cubes
                .push(slab(Pose2::IDENTITY, 2.0 * h.x, 2.0 * h.y));
        }
        TypedShape::HalfSpace(half_space) => {
            // The solid side is −n: a square whose top face lies on the boundary line,
            // its local +y turned onto n.
            let n = half_space.normal;
            let size = style.half_space_size;
            let angle = n.y.atan2(n.x) - std::f64::consts::FRAC_PI_2;
            entity
                .cubes
                .push(slab(Pose2::new(-0.5 * size * n, angle), size, size));
        }
        TypedShape::ConvexPolygon(polygon) => {
            add_polygon(entity, pose, polygon.points(), color, style);
        }
        TypedShape::Triangle(tri) => {
            add_polygon(entity, pose, &[tri.a, tri.b, tri.c], color, style);
        }
        TypedShape::Segment(segment) => {
            // A bar 3 % of its length wide (at least the line width), so that a rod
            // drawn as a segment is seen at any zoom, and its centre line.
            let (a, b) = (segment.a, segment.b);
            let width = (0.03 * (b - a).length()).max(style.line_width);
            entity.cubes.push(slab(bar(a, b), (b - a).length(), width));
            let points = vec![point(a, z), point(b, z)];
            entity.lines.push(outline(LineType::LineStrip, points));
        }
        TypedShape::Polyline(polyline) => {
            let points = (polyline.segments())
                .flat_map(|s| [point(s.a, 0.0), point(s.b, 0.0)])
                .collect();
            entity.lines.push(LinePrimitive {
                color: Some(color),
                ..outline(LineType::LineList, points)
            });
        }
        _ => {
            return Err(LogError::UnsupportedShape {
                shape: format!("{:?}", shape.shape_type()),
            });
        }
    }
    Ok(())
}

/// The entity `body/<name>` in frame `body_<name>` (frame-locked, shown until deleted),
/// drawing `shapes` at simulated time `t` (s).
pub fn body_entity(
    t: f64,
    name: &str,
    shapes: &[ShapeDrawing<'_>],
    style: &DrawStyle,
) -> Result<SceneEntity, LogError> {
    let mut entity = entity(t, body_frame(name), format!("body/{name}"), true)?;
    for s in shapes {
        add_shape(&mut entity, s.shape, &s.pose, s.color, style)?;
    }
    entity.metadata.push(key_value("body", name));
    Ok(entity)
}

/// The skeleton of a body: the entity `visual/<name>` in frame `body_<name>`
/// (frame-locked), a bar from the body's joint (the origin of its frame) to each point of
/// `anchors` (the joints of its children) and to its centre of mass `com` (in the body
/// frame, m), in `color` made translucent, and, if `com_disc`, a disc at `com`. The bars
/// are `0.05 L` wide and the disc's radius `0.06 L`, with `L` the longest bar (at least
/// 0.1 m). It is the visual of a body without a collision shape, and shows the link of a
/// hinged body whose shapes do not reach its joint (a pendulum's bob).
pub fn skeleton_entity(
    t: f64,
    name: &str,
    anchors: &[Vector],
    (com, com_disc): (Vector, bool),
    color: Color,
    style: &DrawStyle,
) -> Result<SceneEntity, LogError> {
    let mut entity = entity(t, body_frame(name), format!("visual/{name}"), true)?;
    let color = Color { a: 0.6, ..color };
    let longest = (anchors.iter().chain([&com]))
        .map(|p| p.length())
        .fold(0.1, f64::max);
    let width = 0.05 * longest;
    for &p in anchors.iter().chain([&com]) {
        if p.length() > 0.0 {
            entity.cubes.push(CubePrimitive {
                pose: Some(planar(&bar(Vector::ZERO, p), 0.0)),
                size: Some(vector3(p.length(), width, 0.5 * style.depth)),
                color: Some(color),
            });
        }
    }
    if com_disc {
        entity.cylinders.push(disc(
            &Pose2::IDENTITY,
            com,
            0.06 * longest,
            scaled(color, 0.7),
            style,
        ));
    }
    entity.metadata.push(key_value("visual", name));
    Ok(entity)
}

/// A nonholonomic constraint drawn on its body: the entity `constraint/<name>` in frame
/// `body_<body>` (frame-locked), a dark bar of `length` (m) along the blade's `direction`
/// through its point `at` (body frame) — a knife edge thin, a wheel as wide as a tyre
/// (a fifth of its length) — raised above the body's shapes so that it shows on them.
pub fn constraint_entity(
    t: f64,
    (name, body): (&str, &str),
    (at, direction): (Vector, Vector),
    wheel: bool,
    length: f64,
    style: &DrawStyle,
) -> Result<SceneEntity, LogError> {
    let mut entity = entity(t, body_frame(body), format!("constraint/{name}"), true)?;
    let half = 0.5 * length * direction;
    let width = if wheel { 0.2 * length } else { 0.04 * length };
    let mut pose = planar(&bar(at - half, at + half), 0.0);
    if let Some(p) = pose.position.as_mut() {
        p.z = style.line_z() + 0.5 * style.depth;
    }
    entity.cubes.push(CubePrimitive {
        pose: Some(pose),
        size: Some(vector3(length, width, style.depth)),
        color: Some(Color {
            r: 0.1,
            g: 0.1,
            b: 0.1,
            a: 0.9,
        }),
    });
    entity.metadata.push(key_value("constraint", name));
    entity.metadata.push(key_value(
        "type",
        if wheel { "wheel" } else { "knife_edge" },
    ));
    Ok(entity)
}

/// The entity `world/<name>` in frame `world` (frame-locked, shown until deleted), drawing
/// the static `shapes` of an obstacle at simulated time `t` (s).
///
/// Entities in `world` are frame-locked too: a viewer keeps an entity that is not in the
/// *fixed* frame, the root of the transform tree, which is `view` (see
/// [`ViewTracker::transform`]).
pub fn obstacle_entity(
    t: f64,
    name: &str,
    shapes: &[ShapeDrawing<'_>],
    style: &DrawStyle,
) -> Result<SceneEntity, LogError> {
    let mut entity = entity(t, WORLD_FRAME.into(), format!("world/{name}"), true)?;
    for s in shapes {
        add_shape(&mut entity, s.shape, &s.pose, s.color, style)?;
    }
    entity.metadata.push(key_value("obstacle", name));
    Ok(entity)
}

/// The transform `world → body_<name>` at simulated time `t` (s) for the body pose `pose`
/// (m, rad) in the world frame.
pub fn body_transform(t: f64, name: &str, pose: &Pose2) -> Result<FrameTransform, LogError> {
    let (x, y) = (pose.translation.x, pose.translation.y);
    planar_transform(
        t,
        WORLD_FRAME,
        &body_frame(name),
        (x, y, pose.rotation.angle()),
    )
}

/// The transforms `world → body_<name>` of every body at simulated time `t` (s).
pub fn body_transforms<'a>(
    t: f64,
    bodies: impl IntoIterator<Item = (&'a str, Pose2)>,
) -> Result<FrameTransforms, LogError> {
    let transforms = (bodies.into_iter())
        .map(|(name, pose)| body_transform(t, name, &pose))
        .collect::<Result<_, _>>()?;
    Ok(FrameTransforms { transforms })
}

/// Keeps the mechanism in view: the origin of the frame `view`, which a camera follows.
///
/// It starts at the centre of the mechanism's bounding box and stays still while the box
/// lies within the *dead zone*, a square of half-side `margin` about it; when the box
/// leaves it, the centre moves just enough to hold it again (per axis). A pendulum's
/// swing thus leaves the camera still, and a wheel rolling away is followed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewTracker {
    /// The origin of `view` in the world (m).
    pub center: Vector,
    /// Half-side of the dead zone (m).
    pub margin: f64,
}

impl ViewTracker {
    /// A tracker for a mechanism whose bounding box is `aabb` at the start: centred on it,
    /// with a dead zone of half-side `max(0.75 × the larger half-extent, 0.25 m)`.
    ///
    /// A box that is not finite (a body at 1e308 m) gives the origin and the smallest
    /// zone, so that the view stays drawable.
    pub fn new(aabb: &Aabb) -> ViewTracker {
        let half = 0.5 * (aabb.maxs - aabb.mins);
        let center = 0.5 * (aabb.mins + aabb.maxs);
        let margin = (0.75 * half.x.max(half.y)).max(0.25);
        ViewTracker {
            center: if center.is_finite() {
                center
            } else {
                Vector::ZERO
            },
            margin: if margin.is_finite() { margin } else { 0.25 },
        }
    }

    /// Moves the centre so that `aabb` lies in the dead zone (per axis; a box larger than
    /// the zone is centred), and returns it (m). A box with a NaN or an infinity is not
    /// followed: the view stays where it is.
    pub fn follow(&mut self, aabb: &Aabb) -> Vector {
        if !(aabb.mins.is_finite() && aabb.maxs.is_finite()) {
            return self.center;
        }
        let axis = |c: f64, lo: f64, hi: f64| {
            if hi - lo > 2.0 * self.margin {
                0.5 * (lo + hi)
            } else {
                c.max(hi - self.margin).min(lo + self.margin)
            }
        };
        let center = Vector::new(
            axis(self.center.x, aabb.mins.x, aabb.maxs.x),
            axis(self.center.y, aabb.mins.y, aabb.maxs.y),
        );
        if center.is_finite() {
            self.center = center;
        }
        self.center
    }

    /// The transform `view → world` at simulated time `t` (s): the world seen from the view,
    /// a translation by `−center`.
    ///
    /// The view is the *root* of the transform tree, so that a viewer that picks its
    /// display frame by itself (Foxglove takes the root with the most frames when no
    /// layout says otherwise) keeps the mechanism in view; a layout follows `view`.
    pub fn transform(&self, t: f64) -> Result<FrameTransform, LogError> {
        planar_transform(
            t,
            VIEW_FRAME,
            WORLD_FRAME,
            (-self.center.x, -self.center.y, 0.0),
        )
    }
}

/// How impulse arrows are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArrowStyle {
    /// Length of the arrow of the largest impulse so far (m).
    pub length: f64,
    /// Shortest arrow, as a fraction of `length`, so that a tiny impulse is still seen.
    pub min_fraction: f64,
    /// How long the arrow stays after the impact, in simulated time (s).
    pub lifetime: f64,
    /// Height of the arrow above the plane, so that it is not hidden in a slab (m).
    pub elevation: f64,
    /// Colour.
    pub color: Color,
}

impl ArrowStyle {
    /// Arrows for a mechanism of size `size` (m, the larger side of its bounding box): the
    /// largest impulse is drawn `0.4 size` long (at least 0.1 m), the smallest `0.2` of that.
    /// A size that is not finite gives the default length.
    pub fn for_size(size: f64) -> ArrowStyle {
        let length = (0.4 * size).max(0.1);
        ArrowStyle {
            length: if length.is_finite() { length } else { 0.5 },
            ..ArrowStyle::default()
        }
    }
}

impl Default for ArrowStyle {
    fn default() -> Self {
        Self {
            length: 0.5,
            min_fraction: 0.2,
            lifetime: 0.25,
            elevation: 0.05,
            color: rgba(1.0, 0.2, 0.1, 1.0),
        }
    }
}

/// The length of impulse arrows: proportional to the impulse, the largest impulse so far
/// drawn [`ArrowStyle::length`] long, with a floor of [`ArrowStyle::min_fraction`] of it.
///
/// A log is written as the run goes, so the run's largest impulse is not known in
/// advance; scaling to the largest so far keeps every arrow legible (the first impact of
/// most runs is their largest) and the text beside each arrow gives its value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ArrowScale {
    /// The largest impulse magnitude so far (N·s).
    pub largest: f64,
}

impl ArrowScale {
    /// The length (m) of the arrow of an impulse of magnitude `impulse` (N·s), which
    /// becomes the largest so far if it is.
    pub fn length(&mut self, impulse: f64, style: &ArrowStyle) -> f64 {
        self.largest = self.largest.max(impulse);
        let fraction = if self.largest > 0.0 {
            impulse / self.largest
        } else {
            0.0
        };
        style.length * fraction.max(style.min_fraction)
    }
}

/// The entity `impulse/<pair>` in frame `world`: an arrow `length` long (m) from the
/// contact point along the impulse `I_n n + I_t t`, and the magnitude `|I|` as text at its
/// tip, shown for `style.lifetime` after the impact; the next impact of the pair replaces
/// it. Its metadata carries the impact's index, the pair, `I_n` and `I_t`.
pub fn impulse_arrow(
    impact: &ImpactRecord,
    length: f64,
    style: &ArrowStyle,
) -> Result<SceneEntity, LogError> {
    let impulse = impact.impulse();
    let angle = impulse.y.atan2(impulse.x);
    let (p, z) = (impact.point, style.elevation);
    let shaft_diameter = 0.06 * style.length;
    let arrow = ArrowPrimitive {
        pose: Some(planar_pose(p.x, p.y, angle, z)),
        shaft_length: 0.7 * length,
        shaft_diameter,
        head_length: 0.3 * length,
        head_diameter: 2.5 * shaft_diameter,
        color: Some(style.color),
    };
    let tip = length + 0.05 * style.length;
    let text = TextPrimitive {
        pose: Some(planar_pose(
            p.x + tip * angle.cos(),
            p.y + tip * angle.sin(),
            0.0,
            z,
        )),
        billboard: true,
        font_size: 14.0,
        scale_invariant: true,
        color: Some(rgba(1.0, 1.0, 1.0, 1.0)),
        text: format!("{} N·s", significant(impulse.x.hypot(impulse.y))),
    };
    Ok(SceneEntity {
        timestamp: Some(timestamp(impact.t)?),
        frame_id: WORLD_FRAME.to_owned(),
        id: format!("impulse/{}", impact.pair),
        lifetime: Some(lifetime(style.lifetime)?),
        frame_locked: true,
        metadata: vec![
            key_value("impact", &impact.index.to_string()),
            key_value("pair", &impact.pair),
            key_value("i_n", &impact.i_n.to_string()),
            key_value("i_t", &impact.i_t.to_string()),
        ],
        arrows: vec![arrow],
        texts: vec![text],
        ..SceneEntity::default()
    })
}

/// `x` with three significant digits: `1.02`, `0.0451`, `3.20e-7`.
pub fn significant(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && !(1e-3..1e4).contains(&a) {
        format!("{x:.2e}")
    } else {
        let digits = if a == 0.0 {
            2
        } else {
            (2 - a.log10().floor() as i32).max(0) as usize
        };
        format!("{x:.digits$}")
    }
}

fn entity(
    t: f64,
    frame_id: String,
    id: String,
    frame_locked: bool,
) -> Result<SceneEntity, LogError> {
    Ok(SceneEntity {
        timestamp: Some(timestamp(t)?),
        frame_id,
        id,
        // Zero: shown until replaced or deleted.
        lifetime: Some(lifetime(0.0)?),
        frame_locked,
        ..SceneEntity::default()
    })
}

/// The pose of a bar from `a` to `b`: centred between them, its x axis along `b − a`.
fn bar(a: Vector, b: Vector) -> Pose2 {
    let axis = b - a;
    Pose2::new(0.5 * (a + b), axis.y.atan2(axis.x))
}

/// A disc of radius `r` (m) centred at `center` in the shape frame `pose`.
fn disc(
    pose: &Pose2,
    center: Vector,
    r: f64,
    color: Color,
    style: &DrawStyle,
) -> CylinderPrimitive {
    CylinderPrimitive {
        pose: Some(planar(&(*pose * Pose2::from_translation(center)), 0.0)),
        size: Some(vector3(2.0 * r, 2.0 * r, style.depth)),
        bottom_scale: 1.0,
        top_scale: 1.0,
        color: Some(color),
    }
}

/// A convex polygon (counter-clockwise `points` in the shape frame `pose`) as a triangle
/// fan on `z = 0` and its outline above the slabs.
fn add_polygon(
    entity: &mut SceneEntity,
    pose: &Pose2,
    points: &[Vector],
    color: Color,
    style: &DrawStyle,
) {
    let fan = (1..points.len().saturating_sub(1))
        .flat_map(|i| [points[0], points[i], points[i + 1]])
        .map(|p| point(p, 0.0))
        .collect();
    entity.triangles.push(TriangleListPrimitive {
        pose: Some(planar(pose, 0.0)),
        points: fan,
        color: Some(color),
        colors: vec![],
        indices: vec![],
    });
    entity.lines.push(LinePrimitive {
        r#type: LineType::LineLoop as i32,
        pose: Some(planar(pose, 0.0)),
        thickness: style.line_width,
        scale_invariant: false,
        points: points.iter().map(|&p| point(p, style.line_z())).collect(),
        color: Some(scaled(color, 0.5)),
        colors: vec![],
        indices: vec![],
    });
}

/// The Foxglove pose of a planar pose at height `z`: position `(x, y, z)`, rotation about z.
fn planar(pose: &Pose2, z: f64) -> Pose {
    planar_pose(
        pose.translation.x,
        pose.translation.y,
        pose.rotation.angle(),
        z,
    )
}

fn point(p: Vector, z: f64) -> Point3 {
    point3(p.x, p.y, z)
}

fn key_value(key: &str, value: &str) -> KeyValuePair {
    KeyValuePair {
        key: key.to_owned(),
        value: value.to_owned(),
    }
}
