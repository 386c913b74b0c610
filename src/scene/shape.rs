//! Shapes on bodies (`[[body.shape]]`) and obstacles of the world (`[[obstacle]]`) →
//! parry2d shapes, validated.

use std::ops::Range;

use parry2d_f64::shape::SharedShape;
use toml::Spanned;

use crate::math::{Pose, Real, Vec2, cross};
use crate::model::Collider;

use super::SceneError;
use super::build::{Builder, Named};
use super::format::{ObstacleSpec, ObstacleType, Pair, ShapeSpec, ShapeType, Two};
use super::ranges;
use super::units::Kind;

impl Builder<'_> {
    /// A shape on a body and its pose in the body frame.
    pub(super) fn body_shape(
        &self,
        spec: &Spanned<ShapeSpec>,
    ) -> Result<(SharedShape, Pose), SceneError> {
        let s = spec.get_ref();
        let ty = *s.kind.get_ref();
        let present = [
            ("radius", s.radius.as_ref().map(|v| v.span())),
            ("a", s.a.as_ref().map(|v| v.span())),
            ("b", s.b.as_ref().map(|v| v.span())),
            ("half_extents", s.half_extents.as_ref().map(|v| v.span())),
            ("points", s.points.as_ref().map(|v| v.span())),
            ("at", s.at.as_ref().map(|v| v.span())),
            ("angle", s.angle.as_ref().map(|v| v.span())),
        ];
        let (allowed, required): (&[&str], &[&str]) = match ty {
            ShapeType::Ball => (&["radius", "at"], &["radius"]),
            ShapeType::Capsule => (&["a", "b", "radius"], &["a", "b", "radius"]),
            ShapeType::Segment => (&["a", "b"], &["a", "b"]),
            ShapeType::Cuboid => (&["half_extents", "at", "angle"], &["half_extents"]),
            ShapeType::Polygon => (&["points", "at", "angle"], &["points"]),
        };
        let tyname = format!("{ty:?}").to_lowercase();
        self.fields(&present, allowed, required, &tyname, s.kind.span())?;
        let pose = Pose::new(
            self.pair_or(&s.at, Vec2::ZERO)?,
            self.quantity_or(&s.angle, Kind::Angle, 0.0)?,
        );
        let shape = match ty {
            ShapeType::Ball => SharedShape::ball(self.radius(&s.radius)?),
            ShapeType::Capsule => {
                let (a, b) = self.segment(&s.a, &s.b)?;
                SharedShape::capsule(a, b, self.radius(&s.radius)?)
            }
            ShapeType::Segment => {
                let (a, b) = self.segment(&s.a, &s.b)?;
                SharedShape::segment(a, b)
            }
            ShapeType::Cuboid => self.cuboid(&s.half_extents)?,
            ShapeType::Polygon => self.polygon(&s.points)?,
        };
        Ok((shape, pose))
    }

    /// Rejects fields not in `allowed` and asks for those in `required`.
    pub(super) fn fields(
        &self,
        present: &[(&str, Option<Range<usize>>)],
        allowed: &[&str],
        required: &[&str],
        what: &str,
        type_span: Range<usize>,
    ) -> Result<(), SceneError> {
        for (field, span) in present {
            if let Some(span) = span
                && !allowed.contains(field)
            {
                return Err(self.err(
                    span.clone(),
                    format!(
                        "a {what} has no field `{field}` (its fields: type, {})",
                        allowed.join(", ")
                    ),
                ));
            }
        }
        for field in required {
            if present.iter().any(|(f, s)| f == field && s.is_none()) {
                return Err(self.err(
                    type_span,
                    format!("a {what} needs `{}`", required.join("`, `")),
                ));
            }
        }
        Ok(())
    }

    pub(super) fn radius(&self, r: &Option<Spanned<Real>>) -> Result<Real, SceneError> {
        match r {
            Some(r) => self.within(r, "the radius", "m", ranges::SIZE),
            None => Err(self.err(0..0, "missing radius")),
        }
    }

    pub(super) fn segment(
        &self,
        a: &Option<Spanned<Pair>>,
        b: &Option<Spanned<Pair>>,
    ) -> Result<(Vec2, Vec2), SceneError> {
        let (Some(a), Some(b)) = (a, b) else {
            return Err(self.err(0..0, "missing segment end"));
        };
        let (pa, pb) = (self.pair(a)?, self.pair(b)?);
        if pa == pb {
            return Err(self.err(b.span(), "the two ends `a` and `b` must differ"));
        }
        Ok((pa, pb))
    }

    pub(super) fn cuboid(&self, h: &Option<Spanned<Pair>>) -> Result<SharedShape, SceneError> {
        let Some(h) = h else {
            return Err(self.err(0..0, "missing half extents"));
        };
        let v = self.pair(h)?;
        let size = |x: Real| ranges::inside(x, ranges::SIZE);
        if size(v.x) && size(v.y) {
            Ok(SharedShape::cuboid(v.x, v.y))
        } else {
            Err(self.err(
                h.span(),
                format!(
                    "the half extents must be within [{:e}, {:e}] m, got [{}, {}] m",
                    ranges::SIZE.0,
                    ranges::SIZE.1,
                    v.x,
                    v.y
                ),
            ))
        }
    }

    /// A convex polygon from its vertices (either orientation, at least 3, strictly convex).
    pub(super) fn polygon(
        &self,
        points: &Option<Spanned<Vec<Pair>>>,
    ) -> Result<SharedShape, SceneError> {
        let Some(points) = points else {
            return Err(self.err(0..0, "missing points"));
        };
        let mut pts = self.points(points, 3)?;
        let area2: Real = (0..pts.len())
            .map(|i| cross(pts[i], pts[(i + 1) % pts.len()]))
            .sum();
        if area2 < 0.0 {
            pts.reverse();
        }
        let n = pts.len();
        let convex = (0..n).all(|i| {
            cross(
                pts[(i + 1) % n] - pts[i],
                pts[(i + 2) % n] - pts[(i + 1) % n],
            ) > 0.0
        });
        // Convex turns alone admit a star (a pentagram turns left at every vertex, twice
        // around): a simple convex polygon turns once around, by 2π.
        let turning: Real = (0..n)
            .map(|i| {
                let (e1, e2) = (
                    pts[(i + 1) % n] - pts[i],
                    pts[(i + 2) % n] - pts[(i + 1) % n],
                );
                cross(e1, e2).atan2(e1.dot(e2))
            })
            .sum();
        let simple = (turning - std::f64::consts::TAU).abs() < 1e-6;
        if !convex || !simple {
            return Err(self.err(
                points.span(),
                if convex {
                    format!(
                        "the points turn {:.0} times around: a polygon must be simple (not a \
                         star), convex, its vertices in order",
                        turning / std::f64::consts::TAU
                    )
                } else {
                    "the points must be the vertices of a convex polygon, in order, no three \
                     in line"
                        .to_owned()
                },
            ));
        }
        SharedShape::convex_polyline(pts)
            .ok_or_else(|| self.err(points.span(), "parry2d rejected this polygon"))
    }

    pub(super) fn points(
        &self,
        points: &Spanned<Vec<Pair>>,
        min: usize,
    ) -> Result<Vec<Vec2>, SceneError> {
        let pts: Vec<Vec2> = points
            .get_ref()
            .iter()
            .map(|&Two([x, y])| Vec2::new(x, y))
            .collect();
        if pts.len() < min {
            return Err(self.err(
                points.span(),
                format!("at least {min} points are needed, got {}", pts.len()),
            ));
        }
        if pts
            .iter()
            .any(|p| !(p.x.abs() <= ranges::KINEMATIC && p.y.abs() <= ranges::KINEMATIC))
        {
            return Err(self.err(
                points.span(),
                format!(
                    "the points must be finite, each coordinate within ±{:e} m",
                    ranges::KINEMATIC
                ),
            ));
        }
        Ok(pts)
    }

    /// `[[obstacle]]`: a static shape of the world.
    pub(super) fn obstacle(&mut self, spec: &Spanned<ObstacleSpec>) -> Result<(), SceneError> {
        let s = spec.get_ref();
        let ty = *s.kind.get_ref();
        let present = [
            ("point", s.point.as_ref().map(|v| v.span())),
            ("normal", s.normal.as_ref().map(|v| v.span())),
            ("a", s.a.as_ref().map(|v| v.span())),
            ("b", s.b.as_ref().map(|v| v.span())),
            ("points", s.points.as_ref().map(|v| v.span())),
            ("half_extents", s.half_extents.as_ref().map(|v| v.span())),
            ("at", s.at.as_ref().map(|v| v.span())),
            ("angle", s.angle.as_ref().map(|v| v.span())),
        ];
        let (allowed, required): (&[&str], &[&str]) = match ty {
            ObstacleType::Halfspace => (&["point", "normal"], &["point", "normal"]),
            ObstacleType::Segment => (&["a", "b"], &["a", "b"]),
            ObstacleType::Polyline => (&["points"], &["points"]),
            ObstacleType::Cuboid => (&["half_extents", "at", "angle"], &["half_extents"]),
        };
        let tyname = format!("{ty:?} obstacle").to_lowercase();
        self.fields(&present, allowed, required, &tyname, s.kind.span())?;
        let (shape, pose) = match ty {
            ObstacleType::Halfspace => {
                let (Some(point), Some(normal)) = (&s.point, &s.normal) else {
                    return Err(self.err(s.kind.span(), "missing point or normal"));
                };
                let n = self.pair(normal)?;
                let n = n
                    .try_normalize()
                    .ok_or_else(|| self.err(normal.span(), "the normal must not be zero"))?;
                (
                    SharedShape::halfspace(n),
                    Pose::from_translation(self.pair(point)?),
                )
            }
            ObstacleType::Segment => {
                let (a, b) = self.segment(&s.a, &s.b)?;
                (SharedShape::segment(a, b), Pose::IDENTITY)
            }
            ObstacleType::Polyline => {
                let Some(points) = &s.points else {
                    return Err(self.err(s.kind.span(), "missing points"));
                };
                let pts = self.points(points, 2)?;
                if pts.windows(2).any(|w| w[0] == w[1]) {
                    return Err(self.err(
                        points.span(),
                        "two consecutive points of a polyline are the same",
                    ));
                }
                (SharedShape::polyline(pts, None), Pose::IDENTITY)
            }
            ObstacleType::Cuboid => (
                self.cuboid(&s.half_extents)?,
                Pose::new(
                    self.pair_or(&s.at, Vec2::ZERO)?,
                    self.quantity_or(&s.angle, Kind::Angle, 0.0)?,
                ),
            ),
        };
        let name = s.name.get_ref().clone();
        let id = self.add_collider(Collider::new(&name, None, shape, pose), s.kind.span());
        self.name(&s.name, Named::Obstacle(id))
    }
}
