//! Drawing the scene for Foxglove's 3-D panel: parry2d shapes as Foxglove primitives in the
//! plane `z = 0`, body entities, frame transforms and impulse arrows.
//!
//! The layout of `/scene` and `/tf`:
//! - each body is an entity `body/<name>` in its own frame `body_<name>`, with
//!   `frame_locked: true`, written once; it then moves with the transforms;
//! - each static obstacle is an entity `world/<name>` in frame `world`;
//! - `/tf` carries, per output sample, one `FrameTransforms` with `world → body_<name>` for
//!   every body;
//! - each impact adds an entity `impulse/<index>` in frame `world`: an arrow from the
//!   contact point along the impulse, shown for a finite lifetime.
//!
//! Solid shapes are slabs of thickness [`DrawStyle::depth`] centred on `z = 0`, so that a
//! top-down view shows their outline; lines and markers lie just above the slabs.

use parry2d_f64::math::{Pose as Pose2, Vector};
use parry2d_f64::shape::{Shape, TypedShape};

use super::LogError;
use super::foxglove::{
    ArrowPrimitive, Color, CubePrimitive, CylinderPrimitive, Duration, FrameTransform,
    FrameTransforms, KeyValuePair, LinePrimitive, LineType, Point3, Pose, Quaternion, SceneEntity,
    TextPrimitive, Time, TriangleListPrimitive, Vector3,
};
use super::records::ImpactRecord;

/// The fixed frame of the scene.
pub const WORLD_FRAME: &str = "world";

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
    /// Side of the square that stands for a half-space (m).
    pub half_space_size: f64,
    /// Whether a body entity carries its name as a text label.
    pub labels: bool,
}

impl Default for DrawStyle {
    fn default() -> Self {
        Self {
            depth: 0.02,
            line_width: 0.01,
            half_space_size: 20.0,
            labels: true,
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
/// line; polyline: its segments. Other shapes: [`LogError::UnsupportedShape`].
pub fn add_shape(
    entity: &mut SceneEntity,
    shape: &dyn Shape,
    pose: &Pose2,
    color: Color,
    style: &DrawStyle,
) -> Result<(), LogError> {
    let slab = |sub: Pose2, size_x: f64, size_y: f64| CubePrimitive {
        pose: planar(&(*pose * sub)),
        size: Vector3::new(size_x, size_y, style.depth),
        color,
    };
    let outline = |line_type, points: Vec<Point3>| LinePrimitive {
        line_type,
        pose: planar(pose),
        thickness: style.line_width,
        scale_invariant: false,
        points,
        color: color.scaled(0.5),
        colors: vec![],
        indices: vec![],
    };
    let z = style.line_z();
    match shape.as_typed_shape() {
        TypedShape::Ball(ball) => {
            entity
                .cylinders
                .push(disc(pose, Vector::ZERO, ball.radius, color, style));
            let marker = vec![Point3::new(0.0, 0.0, z), Point3::new(ball.radius, 0.0, z)];
            entity.lines.push(outline(LineType::LineStrip, marker));
        }
        TypedShape::Capsule(capsule) => {
            let (a, b, r) = (capsule.segment.a, capsule.segment.b, capsule.radius);
            entity.cylinders.push(disc(pose, a, r, color, style));
            entity.cylinders.push(disc(pose, b, r, color, style));
            let axis = b - a;
            let mid = Pose2::new(0.5 * (a + b), axis.y.atan2(axis.x));
            entity.cubes.push(slab(mid, axis.length(), 2.0 * r));
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
            let points = vec![point(segment.a, 0.0), point(segment.b, 0.0)];
            entity.lines.push(LinePrimitive {
                color,
                ..outline(LineType::LineStrip, points)
            });
        }
        TypedShape::Polyline(polyline) => {
            let points = (polyline.segments())
                .flat_map(|s| [point(s.a, 0.0), point(s.b, 0.0)])
                .collect();
            entity.lines.push(LinePrimitive {
                color,
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
    let mut entity = entity(
        t,
        body_frame(name),
        format!("body/{name}"),
        true,
        shapes,
        style,
    )?;
    entity.metadata.push(key_value("body", name));
    if style.labels {
        entity.texts.push(TextPrimitive {
            pose: Pose::planar(0.0, 0.0, 0.0),
            billboard: true,
            font_size: 12.0,
            scale_invariant: true,
            color: Color::rgba(1.0, 1.0, 1.0, 1.0),
            text: name.to_owned(),
        });
    }
    Ok(entity)
}

/// The entity `world/<name>` in frame `world` (shown until deleted), drawing the static
/// `shapes` of an obstacle at simulated time `t` (s).
pub fn obstacle_entity(
    t: f64,
    name: &str,
    shapes: &[ShapeDrawing<'_>],
    style: &DrawStyle,
) -> Result<SceneEntity, LogError> {
    let mut entity = entity(
        t,
        WORLD_FRAME.into(),
        format!("world/{name}"),
        false,
        shapes,
        style,
    )?;
    entity.metadata.push(key_value("obstacle", name));
    Ok(entity)
}

/// The transform `world → body_<name>` at simulated time `t` (s) for the body pose `pose`
/// (m, rad) in the world frame.
pub fn body_transform(t: f64, name: &str, pose: &Pose2) -> Result<FrameTransform, LogError> {
    let (x, y) = (pose.translation.x, pose.translation.y);
    FrameTransform::planar(
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

/// How impulse arrows are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArrowStyle {
    /// Length of the arrow per unit impulse (m per N·s).
    pub scale: f64,
    /// How long the arrow stays after the impact, in simulated time (s).
    pub lifetime: f64,
    /// Diameter of the shaft (m); the head is twice as wide.
    pub shaft_diameter: f64,
    /// Height of the arrow above the plane, so that it is not hidden in a slab (m).
    pub elevation: f64,
    /// Colour.
    pub color: Color,
}

impl Default for ArrowStyle {
    fn default() -> Self {
        Self {
            scale: 0.1,
            lifetime: 0.25,
            shaft_diameter: 0.01,
            elevation: 0.05,
            color: Color::rgba(1.0, 0.2, 0.1, 1.0),
        }
    }
}

/// The entity `impulse/<index>` in frame `world`: an arrow from the contact point along
/// the impulse `I_n n + I_t t`, of length `scale·|I|`, shown for `lifetime` after the
/// impact. Its metadata carries the pair, `I_n` and `I_t`.
pub fn impulse_arrow(impact: &ImpactRecord, style: &ArrowStyle) -> Result<SceneEntity, LogError> {
    let impulse = impact.impulse();
    let length = style.scale * impulse.x.hypot(impulse.y);
    let mut pose = Pose::planar(impact.point.x, impact.point.y, impulse.y.atan2(impulse.x));
    pose.position.z = style.elevation;
    let arrow = ArrowPrimitive {
        pose,
        shaft_length: 0.75 * length,
        shaft_diameter: style.shaft_diameter,
        head_length: 0.25 * length,
        head_diameter: 2.0 * style.shaft_diameter,
        color: style.color,
    };
    Ok(SceneEntity {
        timestamp: Time::from_seconds(impact.t)?,
        frame_id: WORLD_FRAME.to_owned(),
        id: format!("impulse/{}", impact.index),
        lifetime: Duration::from_seconds(style.lifetime)?,
        frame_locked: false,
        metadata: vec![
            key_value("pair", &impact.pair),
            key_value("i_n", &impact.i_n.to_string()),
            key_value("i_t", &impact.i_t.to_string()),
        ],
        arrows: vec![arrow],
        ..SceneEntity::default()
    })
}

fn entity(
    t: f64,
    frame_id: String,
    id: String,
    frame_locked: bool,
    shapes: &[ShapeDrawing<'_>],
    style: &DrawStyle,
) -> Result<SceneEntity, LogError> {
    let mut entity = SceneEntity {
        timestamp: Time::from_seconds(t)?,
        frame_id,
        id,
        lifetime: Duration::FOREVER,
        frame_locked,
        ..SceneEntity::default()
    };
    for s in shapes {
        add_shape(&mut entity, s.shape, &s.pose, s.color, style)?;
    }
    Ok(entity)
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
        pose: planar(&(*pose * Pose2::from_translation(center))),
        size: Vector3::new(2.0 * r, 2.0 * r, style.depth),
        bottom_scale: 1.0,
        top_scale: 1.0,
        color,
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
        pose: planar(pose),
        points: fan,
        color,
        colors: vec![],
        indices: vec![],
    });
    entity.lines.push(LinePrimitive {
        line_type: LineType::LineLoop,
        pose: planar(pose),
        thickness: style.line_width,
        scale_invariant: false,
        points: points.iter().map(|&p| point(p, style.line_z())).collect(),
        color: color.scaled(0.5),
        colors: vec![],
        indices: vec![],
    });
}

/// The Foxglove pose of a planar pose: position `(x, y, 0)`, rotation about z.
fn planar(pose: &Pose2) -> Pose {
    Pose {
        position: Vector3::new(pose.translation.x, pose.translation.y, 0.0),
        orientation: Quaternion::about_z(pose.rotation.angle()),
    }
}

fn point(p: Vector, z: f64) -> Point3 {
    Point3::new(p.x, p.y, z)
}

fn key_value(key: &str, value: &str) -> KeyValuePair {
    KeyValuePair {
        key: key.to_owned(),
        value: value.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use parry2d_f64::shape::{Ball, Capsule, ConvexPolygon, Cuboid, HalfSpace, RoundShape};

    use super::*;

    const RED: Color = Color::rgba(1.0, 0.0, 0.0, 1.0);

    fn drawn(shape: &dyn Shape, pose: Pose2) -> SceneEntity {
        let mut e = SceneEntity::default();
        add_shape(&mut e, shape, &pose, RED, &DrawStyle::default()).unwrap();
        e
    }

    /// The angle of a z-rotation quaternion (rad).
    fn angle(q: Quaternion) -> f64 {
        2.0 * q.z.atan2(q.w)
    }

    #[test]
    fn ball_is_a_disc_at_the_composed_pose() {
        let e = drawn(&Ball::new(0.5), Pose2::new(Vector::new(1.0, 2.0), 0.3));
        let c = &e.cylinders[0];
        assert_eq!((c.size.x, c.size.y), (1.0, 1.0));
        assert_eq!((c.pose.position.x, c.pose.position.y), (1.0, 2.0));
        assert!((angle(c.pose.orientation) - 0.3).abs() < 1e-15);
        // The radius marker goes from the centre to the rim along the local x axis.
        assert_eq!(e.lines[0].points[1].x, 0.5);
    }

    #[test]
    fn capsule_discs_sit_on_its_segment_ends() {
        // A vertical capsule (half height 1) turned by 90°: its ends are at x = ∓1.
        let pose = Pose2::new(Vector::new(0.0, 3.0), std::f64::consts::FRAC_PI_2);
        let e = drawn(&Capsule::new_y(1.0, 0.25), pose);
        let ends: Vec<(f64, f64)> = (e.cylinders.iter())
            .map(|c| (c.pose.position.x, c.pose.position.y))
            .collect();
        assert!((ends[0].0 - 1.0).abs() < 1e-15 && (ends[0].1 - 3.0).abs() < 1e-15);
        assert!((ends[1].0 + 1.0).abs() < 1e-15 && (ends[1].1 - 3.0).abs() < 1e-15);
        // The rectangle spans the segment (length 2) and the diameter (0.5).
        assert_eq!((e.cubes[0].size.x, e.cubes[0].size.y), (2.0, 0.5));
    }

    #[test]
    fn half_space_lies_on_the_solid_side() {
        // Ground y ≤ 0: the square is centred straight below the origin, unrotated.
        let size = DrawStyle::default().half_space_size;
        let e = drawn(&HalfSpace::new(Vector::Y), Pose2::IDENTITY);
        let cube = &e.cubes[0];
        assert!(cube.pose.position.x.abs() < 1e-12);
        assert_eq!(cube.pose.position.y, -0.5 * size);
        assert!(angle(cube.pose.orientation).abs() < 1e-15);
        // A wall x ≥ 0 solid (outward normal −x): centred at +x.
        let e = drawn(&HalfSpace::new(-Vector::X), Pose2::IDENTITY);
        assert_eq!(e.cubes[0].pose.position.x, 0.5 * size);
    }

    #[test]
    fn polygon_is_a_fan_and_an_outline() {
        let square = Cuboid::new(Vector::new(1.0, 1.0));
        let poly = ConvexPolygon::from_convex_polyline(vec![
            Vector::new(0.0, 0.0),
            Vector::new(2.0, 0.0),
            Vector::new(2.0, 1.0),
            Vector::new(0.0, 1.0),
        ])
        .unwrap();
        let e = drawn(&poly, Pose2::IDENTITY);
        assert_eq!(e.triangles[0].points.len(), 6);
        assert_eq!(e.lines[0].points.len(), 4);
        assert_eq!(e.lines[0].line_type, LineType::LineLoop);
        assert_eq!(drawn(&square, Pose2::IDENTITY).cubes[0].size.x, 2.0);
    }

    #[test]
    fn unsupported_shapes_are_errors() {
        let round = RoundShape {
            inner_shape: Cuboid::new(Vector::new(1.0, 1.0)),
            border_radius: 0.1,
        };
        let mut e = SceneEntity::default();
        let err = add_shape(&mut e, &round, &Pose2::IDENTITY, RED, &DrawStyle::default());
        assert!(matches!(err, Err(LogError::UnsupportedShape { .. })));
    }

    #[test]
    fn transform_quaternion_is_about_z() {
        let tf = body_transform(0.5, "rod", &Pose2::new(Vector::new(1.0, -2.0), 1.2)).unwrap();
        assert_eq!(tf.child_frame_id, "body_rod");
        assert_eq!(tf.parent_frame_id, "world");
        assert_eq!(
            (tf.translation.x, tf.translation.y, tf.translation.z),
            (1.0, -2.0, 0.0)
        );
        assert_eq!((tf.rotation.x, tf.rotation.y), (0.0, 0.0));
        assert!((tf.rotation.z - 0.6f64.sin()).abs() < 1e-15);
        assert!((tf.rotation.w - 0.6f64.cos()).abs() < 1e-15);
    }
}
