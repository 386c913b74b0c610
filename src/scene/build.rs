//! From the parsed file to a [`Model`], the initial [`State`] and the run [`Settings`],
//! with the physical validation located at the offending value.

use std::collections::HashMap;
use std::ops::Range;

use nalgebra::DVector;
use parry2d_f64::shape::SharedShape;
use toml::Spanned;

use crate::contact::{ContactError, signed_gap};
use crate::kinematics::update_positions;
use crate::math::{Pose, Real, Vec2, cross};
use crate::model::{
    Body, BodyId, Collider, ColliderId, Joint, JointForce, JointKind, Material, Model,
    ModelBuilder, PrescribedMotion,
};
use crate::settings::{IntegratorSettings, Settings};
use crate::state::{Data, State};

use super::SceneError;
use super::error::Locator;
use super::format::{
    BodySpec, ChainSpec, ContactSpec, DriveSpec, JointSpec, JointType, ObstacleSpec, ObstacleType,
    Pair, RunSpec, SceneFile, ShapeSpec, ShapeType,
};
use super::units::{Kind, Quantity};

/// The scene file version this loader reads.
pub const VERSION: i64 = 1;

/// Default largest overlap of two shapes at the start (m).
pub const DEFAULT_OVERLAP_TOLERANCE: Real = 1e-9;

/// Changes applied to a scene file while loading it.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Overrides {
    /// Number of links of the `[chain]` generator.
    pub chain_links: Option<usize>,
}

/// What a scene file describes.
pub(super) struct Built {
    pub name: String,
    pub description: String,
    pub model: Model,
    pub initial: State,
    pub settings: Settings,
}

/// Where a name points.
#[derive(Clone, Copy, Debug)]
enum Named {
    Body(BodyId),
    Obstacle(ColliderId),
}

/// The conversion in progress.
struct Builder<'a> {
    loc: &'a Locator<'a>,
    model: ModelBuilder,
    names: HashMap<String, Named>,
    q0: Vec<Real>,
    u0: Vec<Real>,
    /// For each collider, the span its errors point at.
    collider_spans: Vec<Range<usize>>,
    /// For each body, its colliders.
    body_colliders: HashMap<BodyId, Vec<ColliderId>>,
}

pub(super) fn build(
    file: SceneFile,
    loc: &Locator<'_>,
    ov: &Overrides,
) -> Result<Built, SceneError> {
    if *file.version.get_ref() != VERSION {
        return Err(loc.at(
            file.version.span(),
            format!(
                "unsupported scene version {} (this ricochet reads version {VERSION})",
                file.version.get_ref()
            ),
        ));
    }
    if file.name.get_ref().trim().is_empty() {
        return Err(loc.at(file.name.span(), "the scene needs a name"));
    }
    let settings = settings(&file.run, loc)?;
    let mut b = Builder {
        loc,
        model: ModelBuilder::new(),
        names: HashMap::new(),
        q0: Vec::new(),
        u0: Vec::new(),
        collider_spans: Vec::new(),
        body_colliders: HashMap::new(),
    };
    let gravity = match &file.gravity {
        Some(g) => b.pair(g)?,
        None => Vec2::new(0.0, -9.81),
    };
    b.model.gravity(gravity);
    if let Some(chain) = &file.chain {
        b.chain(chain, ov.chain_links)?;
    }
    for i in tree_order(&file.body, &b.names, loc)? {
        b.body(&file.body[i])?;
    }
    for obstacle in &file.obstacle {
        b.obstacle(obstacle)?;
    }
    let tolerance = b.contact(file.contact.as_ref())?;
    let Builder {
        model,
        q0,
        u0,
        collider_spans,
        ..
    } = b;
    let model = model.build().map_err(|e| loc.model(e))?;
    if let (None, Some(pair)) = (&file.contact, model.pairs().first()) {
        return Err(loc.at(
            collider_spans[pair.a.index()].clone(),
            "the scene has contact pairs but no [contact] table: give at least `e` and `mu`",
        ));
    }
    let initial = State::new(0.0, DVector::from_vec(q0), DVector::from_vec(u0));
    check_overlaps(&model, &initial, tolerance, &collider_spans, loc)?;
    Ok(Built {
        name: file.name.into_inner(),
        description: file.description.unwrap_or_default(),
        model,
        initial,
        settings,
    })
}

/// `[run]` → [`Settings`]: positive finite times, rates and tolerances.
fn settings(run: &RunSpec, loc: &Locator<'_>) -> Result<Settings, SceneError> {
    let positive = |v: &Spanned<Real>, what: &str| -> Result<Real, SceneError> {
        let x = *v.get_ref();
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            Err(loc.at(
                v.span(),
                format!("{what} must be a positive finite number, got {x}"),
            ))
        }
    };
    let mut settings = Settings {
        t_end: positive(&run.t_end, "the end time")?,
        ..Settings::default()
    };
    if let Some(rate) = &run.output_rate {
        settings.output_rate = positive(rate, "the output rate")?;
    }
    let mut integ = IntegratorSettings::default();
    if let Some(spec) = &run.integrator {
        if let Some(m) = spec.method {
            integ.method = m;
        }
        for (field, value, what) in [
            (&mut integ.rtol, &spec.rtol, "rtol"),
            (&mut integ.atol, &spec.atol, "atol"),
            (&mut integ.dt, &spec.dt, "the step dt"),
            (&mut integ.h_max, &spec.h_max, "h_max"),
        ] {
            if let Some(v) = value {
                *field = positive(v, what)?;
            }
        }
    }
    settings.integrator = integ;
    Ok(settings)
}

/// The order in which to add the bodies: parents before children, otherwise file order.
/// Unknown parents and cycles are errors at the `parent` field.
fn tree_order(
    bodies: &[Spanned<BodySpec>],
    generated: &HashMap<String, Named>,
    loc: &Locator<'_>,
) -> Result<Vec<usize>, SceneError> {
    let index: HashMap<&str, usize> = bodies
        .iter()
        .enumerate()
        .map(|(i, b)| (b.get_ref().name.get_ref().as_str(), i))
        .collect();
    // Parent of each body: None = world or a generated (chain) body.
    let mut parent: Vec<Option<usize>> = Vec::with_capacity(bodies.len());
    for body in bodies {
        let p = match &body.get_ref().joint.get_ref().parent {
            None => None,
            Some(name) if name.get_ref() == "world" => None,
            Some(name) => match (
                index.get(name.get_ref().as_str()),
                generated.get(name.get_ref()),
            ) {
                (Some(&i), _) => Some(i),
                (None, Some(Named::Body(_))) => None,
                _ => {
                    let mut known: Vec<&str> = index.keys().copied().collect();
                    known.sort_unstable();
                    return Err(loc.at(
                        name.span(),
                        format!(
                            "unknown parent body `{}` (bodies: world, {})",
                            name.get_ref(),
                            known.join(", ")
                        ),
                    ));
                }
            },
        };
        parent.push(p);
    }
    let mut placed = vec![false; bodies.len()];
    let mut order = Vec::with_capacity(bodies.len());
    while order.len() < bodies.len() {
        let before = order.len();
        for i in 0..bodies.len() {
            if !placed[i] && parent[i].is_none_or(|p| placed[p]) {
                placed[i] = true;
                order.push(i);
            }
        }
        if order.len() == before {
            // Every remaining body waits for another: a cycle.
            let cycle: Vec<&str> = (0..bodies.len())
                .filter(|&i| !placed[i])
                .map(|i| bodies[i].get_ref().name.get_ref().as_str())
                .collect();
            let first = (0..bodies.len()).find(|&i| !placed[i]).unwrap_or(0);
            let span = bodies[first]
                .get_ref()
                .joint
                .get_ref()
                .parent
                .as_ref()
                .map_or(bodies[first].span(), |p| p.span());
            return Err(loc.at(
                span,
                format!(
                    "the parents of {} form a cycle: a kinematic tree has none",
                    cycle.join(", ")
                ),
            ));
        }
    }
    Ok(order)
}

impl Builder<'_> {
    fn err(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        self.loc.at(span, message)
    }

    /// A finite `[x, y]`.
    fn pair(&self, v: &Spanned<Pair>) -> Result<Vec2, SceneError> {
        let [x, y] = *v.get_ref();
        if x.is_finite() && y.is_finite() {
            Ok(Vec2::new(x, y))
        } else {
            Err(self.err(
                v.span(),
                format!("[{x}, {y}] is not a pair of finite numbers"),
            ))
        }
    }

    fn pair_or(&self, v: &Option<Spanned<Pair>>, default: Vec2) -> Result<Vec2, SceneError> {
        v.as_ref().map_or(Ok(default), |v| self.pair(v))
    }

    /// A finite positive number.
    fn positive(&self, v: &Spanned<Real>, what: &str, unit: &str) -> Result<Real, SceneError> {
        let x = *v.get_ref();
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(
                v.span(),
                format!("{what} must be positive and finite, got {x} {unit}"),
            ))
        }
    }

    /// An optional quantity of the given kind.
    fn quantity(
        &self,
        v: &Option<Spanned<Quantity>>,
        kind: Kind,
    ) -> Result<Option<Real>, SceneError> {
        match v {
            None => Ok(None),
            Some(v) => v
                .get_ref()
                .si(kind)
                .map(Some)
                .map_err(|m| self.err(v.span(), m)),
        }
    }

    fn quantity_or(
        &self,
        v: &Option<Spanned<Quantity>>,
        kind: Kind,
        default: Real,
    ) -> Result<Real, SceneError> {
        Ok(self.quantity(v, kind)?.unwrap_or(default))
    }

    /// Registers a body or obstacle name (unique, not `world`).
    fn name(&mut self, name: &Spanned<String>, what: Named) -> Result<(), SceneError> {
        let n = name.get_ref();
        if n.is_empty() || n == "world" {
            return Err(self.err(
                name.span(),
                format!("`{n}` cannot name a body or an obstacle"),
            ));
        }
        if self.names.insert(n.clone(), what).is_some() {
            return Err(self.err(
                name.span(),
                format!("the name `{n}` is used twice (bodies and obstacles share names)"),
            ));
        }
        Ok(())
    }

    fn add_collider(&mut self, collider: Collider, span: Range<usize>) -> ColliderId {
        let body = collider.body;
        let id = self.model.add_collider(collider);
        self.collider_spans.push(span);
        if let Some(b) = body {
            self.body_colliders.entry(b).or_default().push(id);
        }
        id
    }

    /// `[chain]`: `links` uniform links hanging from `at`, relative angles, capsules.
    fn chain(&mut self, spec: &Spanned<ChainSpec>, links: Option<usize>) -> Result<(), SceneError> {
        let c = spec.get_ref();
        let n = match links {
            Some(n) => n as i64,
            None => *c.links.get_ref(),
        };
        if !(1..=10_000).contains(&n) {
            return Err(self.err(
                c.links.span(),
                format!("a chain has 1 to 10000 links, got {n}"),
            ));
        }
        let length = self.positive(&c.length, "the link length", "m")?;
        let mass = self.positive(&c.mass, "the link mass", "kg")?;
        let radius = self.positive(&c.radius, "the link radius", "m")?;
        let at = self.pair_or(&c.at, Vec2::ZERO)?;
        let angle = self.quantity_or(&c.angle, Kind::Angle, 0.0)?;
        let rate = self.quantity_or(&c.rate, Kind::AngularRate, 0.0)?;
        let prefix = c.name.as_ref().map_or("link", |s| s.get_ref().as_str());
        let mut parent = None;
        for i in 1..=n {
            let name = format!("{prefix}{i}");
            // A uniform rod along −y of the body frame: c = (0, −L/2), I_c = m L²/12.
            let body = Body::new(
                &name,
                mass,
                Vec2::new(0.0, -0.5 * length),
                mass * length * length / 12.0,
            );
            let placement = if i == 1 {
                Pose::from_translation(at)
            } else {
                Pose::translation(0.0, -length)
            };
            let id = self
                .model
                .add_body(body, Joint::revolute(&name, parent, placement));
            self.name(&Spanned::new(spec.span(), name.clone()), Named::Body(id))?;
            let shape = SharedShape::capsule(Vec2::ZERO, Vec2::new(0.0, -length), radius);
            self.add_collider(
                Collider::new(&name, Some(id), shape, Pose::IDENTITY),
                spec.span(),
            );
            self.q0.push(if i == 1 { angle } else { 0.0 });
            self.u0.push(if i == 1 { rate } else { 0.0 });
            parent = Some(id);
        }
        Ok(())
    }

    /// `[[body]]` with its joint and shapes. Its parent is already in the model.
    fn body(&mut self, spec: &Spanned<BodySpec>) -> Result<(), SceneError> {
        let s = spec.get_ref();
        let mass = self.positive(&s.mass, "the mass", "kg")?;
        let inertia = self.positive(&s.inertia, "the moment of inertia", "kg·m²")?;
        let com = self.pair_or(&s.com, Vec2::ZERO)?;
        let name = s.name.get_ref().clone();
        let parent = match &s.joint.get_ref().parent {
            Some(p) if p.get_ref() != "world" => match self.names.get(p.get_ref()) {
                Some(Named::Body(id)) => Some(*id),
                _ => return Err(self.err(p.span(), format!("`{}` is not a body", p.get_ref()))),
            },
            _ => None,
        };
        let (joint, q, u) = self.joint(&name, s.joint.get_ref(), parent)?;
        let id = self
            .model
            .add_body(Body::new(&name, mass, com, inertia), joint);
        self.name(&s.name, Named::Body(id))?;
        self.q0.extend(q);
        self.u0.extend(u);
        for (k, shape) in s.shape.iter().enumerate() {
            let collider_name = match &shape.get_ref().name {
                Some(n) => n.get_ref().clone(),
                None if s.shape.len() == 1 => name.clone(),
                None => format!("{name}/{k}"),
            };
            let (geometry, pose) = self.body_shape(shape)?;
            let span = shape.get_ref().kind.span();
            self.add_collider(Collider::new(collider_name, Some(id), geometry, pose), span);
        }
        Ok(())
    }

    /// The joint, its initial coordinates and speeds.
    fn joint(
        &self,
        name: &str,
        s: &JointSpec,
        parent: Option<BodyId>,
    ) -> Result<(Joint, Vec<Real>, Vec<Real>), SceneError> {
        use Kind::{Angle, AngularRate, Plain};
        let ty = *s.kind.get_ref();
        self.allowed_joint_fields(s, ty)?;
        let at = self.pair_or(&s.at, Vec2::ZERO)?;
        let orientation = self.quantity_or(&s.orientation, Angle, 0.0)?;
        let placement = Pose::new(at, orientation);
        let (kind, q, u) = match ty {
            JointType::Revolute => (
                JointKind::Revolute {
                    absolute: s.absolute.as_ref().is_some_and(|a| *a.get_ref()),
                },
                vec![self.quantity_or(&s.angle, Angle, 0.0)?],
                vec![self.quantity_or(&s.rate, AngularRate, 0.0)?],
            ),
            JointType::Prismatic => {
                let axis = match &s.axis {
                    None => {
                        return Err(self.err(s.kind.span(), "a prismatic joint needs its `axis`"));
                    }
                    Some(a) => {
                        let v = self.pair(a)?;
                        v.try_normalize()
                            .ok_or_else(|| self.err(a.span(), "the axis must not be zero"))?
                    }
                };
                (
                    JointKind::Prismatic { axis },
                    vec![self.quantity_or(&s.position, Plain, 0.0)?],
                    vec![self.quantity_or(&s.speed, Plain, 0.0)?],
                )
            }
            JointType::Translation => (
                JointKind::Translation,
                vec![
                    self.quantity_or(&s.x, Plain, 0.0)?,
                    self.quantity_or(&s.y, Plain, 0.0)?,
                ],
                vec![
                    self.quantity_or(&s.vx, Plain, 0.0)?,
                    self.quantity_or(&s.vy, Plain, 0.0)?,
                ],
            ),
            JointType::Planar => (
                JointKind::Planar,
                vec![
                    self.quantity_or(&s.x, Plain, 0.0)?,
                    self.quantity_or(&s.y, Plain, 0.0)?,
                    self.quantity_or(&s.angle, Angle, 0.0)?,
                ],
                vec![
                    self.quantity_or(&s.vx, Plain, 0.0)?,
                    self.quantity_or(&s.vy, Plain, 0.0)?,
                    self.quantity_or(&s.rate, AngularRate, 0.0)?,
                ],
            ),
            JointType::Fixed => (JointKind::Fixed, vec![], vec![]),
        };
        let mut joint = Joint::new(name, kind, parent, placement);
        let (coordinate, rate) = if ty == JointType::Revolute {
            (Angle, AngularRate)
        } else {
            (Plain, Plain)
        };
        joint.force = JointForce {
            stiffness: self.non_negative(&s.stiffness)?,
            rest: self.quantity_or(&s.rest, coordinate, 0.0)?,
            damping: self.non_negative(&s.damping)?,
            effort: self.quantity_or(
                if ty == JointType::Revolute {
                    &s.torque
                } else {
                    &s.force
                },
                Plain,
                0.0,
            )?,
        };
        if let Some(drive) = &s.drive {
            joint.drive = Some(self.drive(drive, q[0], coordinate, rate)?);
            return Ok((joint, vec![], vec![]));
        }
        Ok((joint, q, u))
    }

    fn non_negative(&self, v: &Option<Spanned<Quantity>>) -> Result<Real, SceneError> {
        let x = self.quantity_or(v, Kind::Plain, 0.0)?;
        match v {
            Some(v) if x < 0.0 => Err(self.err(v.span(), format!("must be non-negative, got {x}"))),
            _ => Ok(x),
        }
    }

    /// `drive = { rate, amplitude, angular_frequency, phase }` with `q₀` the joint's
    /// initial coordinate.
    fn drive(
        &self,
        d: &Spanned<DriveSpec>,
        q0: Real,
        coordinate: Kind,
        rate: Kind,
    ) -> Result<PrescribedMotion, SceneError> {
        let s = d.get_ref();
        Ok(PrescribedMotion {
            q0,
            rate: self.quantity_or(&s.rate, rate, 0.0)?,
            amplitude: self.quantity_or(&s.amplitude, coordinate, 0.0)?,
            angular_frequency: self.quantity_or(&s.angular_frequency, Kind::AngularRate, 0.0)?,
            phase: self.quantity_or(&s.phase, Kind::Angle, 0.0)?,
        })
    }

    /// Rejects the fields that a joint of type `ty` does not have.
    fn allowed_joint_fields(&self, s: &JointSpec, ty: JointType) -> Result<(), SceneError> {
        let span = |v: &Option<Spanned<Quantity>>| v.as_ref().map(|v| v.span());
        let present: [(&str, Option<Range<usize>>); 17] = [
            ("absolute", s.absolute.as_ref().map(|v| v.span())),
            ("axis", s.axis.as_ref().map(|v| v.span())),
            ("angle", span(&s.angle)),
            ("rate", span(&s.rate)),
            ("position", span(&s.position)),
            ("speed", span(&s.speed)),
            ("x", span(&s.x)),
            ("y", span(&s.y)),
            ("vx", span(&s.vx)),
            ("vy", span(&s.vy)),
            ("stiffness", span(&s.stiffness)),
            ("rest", span(&s.rest)),
            ("damping", span(&s.damping)),
            ("torque", span(&s.torque)),
            ("force", span(&s.force)),
            ("drive", s.drive.as_ref().map(|v| v.span())),
            ("orientation", span(&s.orientation)),
        ];
        let allowed: &[&str] = match ty {
            JointType::Revolute => &[
                "absolute",
                "angle",
                "rate",
                "stiffness",
                "rest",
                "damping",
                "torque",
                "drive",
            ],
            JointType::Prismatic => &[
                "axis",
                "position",
                "speed",
                "stiffness",
                "rest",
                "damping",
                "force",
                "drive",
            ],
            JointType::Translation => &["x", "y", "vx", "vy"],
            JointType::Planar => &["x", "y", "angle", "vx", "vy", "rate"],
            JointType::Fixed => &[],
        };
        let tyname = format!("{ty:?}").to_lowercase();
        for (field, span) in present {
            let Some(span) = span else { continue };
            if field == "orientation" {
                continue;
            }
            if !allowed.contains(&field) {
                let mut fields = vec!["type", "parent", "at", "orientation"];
                fields.extend_from_slice(allowed);
                return Err(self.err(
                    span,
                    format!(
                        "a {tyname} joint has no field `{field}` (its fields: {})",
                        fields.join(", ")
                    ),
                ));
            }
        }
        if s.drive.is_some() {
            let driven = [
                ("rate", span(&s.rate)),
                ("speed", span(&s.speed)),
                ("stiffness", span(&s.stiffness)),
                ("rest", span(&s.rest)),
                ("damping", span(&s.damping)),
                ("torque", span(&s.torque)),
                ("force", span(&s.force)),
            ];
            if let Some((field, Some(span))) = driven.into_iter().find(|(_, s)| s.is_some()) {
                return Err(self.err(
                    span,
                    format!("a driven joint has no `{field}`: its motion is prescribed by `drive`, which supplies whatever force it takes"),
                ));
            }
        }
        Ok(())
    }

    /// A shape on a body and its pose in the body frame.
    fn body_shape(&self, spec: &Spanned<ShapeSpec>) -> Result<(SharedShape, Pose), SceneError> {
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
    fn fields(
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

    fn radius(&self, r: &Option<Spanned<Real>>) -> Result<Real, SceneError> {
        match r {
            Some(r) => self.positive(r, "the radius", "m"),
            None => Err(self.err(0..0, "missing radius")),
        }
    }

    fn segment(
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

    fn cuboid(&self, h: &Option<Spanned<Pair>>) -> Result<SharedShape, SceneError> {
        let Some(h) = h else {
            return Err(self.err(0..0, "missing half extents"));
        };
        let v = self.pair(h)?;
        if v.x > 0.0 && v.y > 0.0 {
            Ok(SharedShape::cuboid(v.x, v.y))
        } else {
            Err(self.err(
                h.span(),
                format!(
                    "the half extents must be positive, got [{}, {}] m",
                    v.x, v.y
                ),
            ))
        }
    }

    /// A convex polygon from its vertices (either orientation, at least 3, strictly convex).
    fn polygon(&self, points: &Option<Spanned<Vec<Pair>>>) -> Result<SharedShape, SceneError> {
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
        if !convex {
            return Err(self.err(
                points.span(),
                "the points must be the vertices of a convex polygon, in order, no three in line",
            ));
        }
        SharedShape::convex_polyline(pts)
            .ok_or_else(|| self.err(points.span(), "parry2d rejected this polygon"))
    }

    fn points(&self, points: &Spanned<Vec<Pair>>, min: usize) -> Result<Vec<Vec2>, SceneError> {
        let pts: Vec<Vec2> = points
            .get_ref()
            .iter()
            .map(|&[x, y]| Vec2::new(x, y))
            .collect();
        if pts.len() < min {
            return Err(self.err(
                points.span(),
                format!("at least {min} points are needed, got {}", pts.len()),
            ));
        }
        if pts.iter().any(|p| !p.is_finite()) {
            return Err(self.err(points.span(), "the points must be finite"));
        }
        Ok(pts)
    }

    /// `[[obstacle]]`: a static shape of the world.
    fn obstacle(&mut self, spec: &Spanned<ObstacleSpec>) -> Result<(), SceneError> {
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
                (
                    SharedShape::polyline(self.points(points, 2)?, None),
                    Pose::IDENTITY,
                )
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

    /// `[contact]`: the default material and the pair rules. Returns the overlap tolerance.
    fn contact(&mut self, spec: Option<&Spanned<ContactSpec>>) -> Result<Real, SceneError> {
        let Some(spec) = spec else {
            return Ok(DEFAULT_OVERLAP_TOLERANCE);
        };
        let c = spec.get_ref();
        let base = Material {
            law: c.law.unwrap_or(crate::impact::Law::Newton),
            e: self.restitution(&c.e)?,
            mu: self.friction(&c.mu)?,
        };
        self.model.default_material(base);
        for p in &c.pair {
            let [a, b] = p.between.get_ref();
            let (ca, cb) = (self.colliders_named(a)?, self.colliders_named(b)?);
            if a.get_ref() == b.get_ref() {
                return Err(self.err(p.between.span(), "a pair needs two different names"));
            }
            if ca
                .iter()
                .chain(&cb)
                .all(|&c| self.collider_spans.len() > c.index() && !self.is_body_collider(c))
            {
                return Err(self.err(p.between.span(), "two obstacles of the world never touch"));
            }
            let material = Material {
                law: p.law.unwrap_or(base.law),
                e: p.e.as_ref().map_or(Ok(base.e), |e| self.restitution(e))?,
                mu: p.mu.as_ref().map_or(Ok(base.mu), |m| self.friction(m))?,
            };
            for &x in &ca {
                for &y in &cb {
                    if p.enabled == Some(false) {
                        self.model.disable_pair(x, y);
                    } else {
                        self.model.pair(x, y, Some(material));
                    }
                }
            }
        }
        match &c.overlap_tolerance {
            None => Ok(DEFAULT_OVERLAP_TOLERANCE),
            Some(t) if t.get_ref().is_finite() && *t.get_ref() >= 0.0 => Ok(*t.get_ref()),
            Some(t) => Err(self.err(
                t.span(),
                format!("the overlap tolerance must be ≥ 0, got {} m", t.get_ref()),
            )),
        }
    }

    fn is_body_collider(&self, c: ColliderId) -> bool {
        self.body_colliders.values().any(|v| v.contains(&c))
    }

    /// The colliders of the body or obstacle `name`.
    fn colliders_named(&self, name: &Spanned<String>) -> Result<Vec<ColliderId>, SceneError> {
        match self.names.get(name.get_ref()) {
            Some(Named::Obstacle(c)) => Ok(vec![*c]),
            Some(Named::Body(b)) => match self.body_colliders.get(b) {
                Some(v) if !v.is_empty() => Ok(v.clone()),
                _ => Err(self.err(
                    name.span(),
                    format!("body `{}` has no shape", name.get_ref()),
                )),
            },
            None => Err(self.err(
                name.span(),
                format!("no body or obstacle is named `{}`", name.get_ref()),
            )),
        }
    }

    fn restitution(&self, e: &Spanned<Real>) -> Result<Real, SceneError> {
        let x = *e.get_ref();
        if x.is_finite() && (0.0..=1.0).contains(&x) {
            Ok(x)
        } else {
            Err(self.err(
                e.span(),
                format!("the coefficient of restitution e must satisfy 0 ≤ e ≤ 1, got {x}"),
            ))
        }
    }

    fn friction(&self, mu: &Spanned<Real>) -> Result<Real, SceneError> {
        let x = *mu.get_ref();
        if x.is_finite() && x >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(
                mu.span(),
                format!("the coefficient of friction mu must be ≥ 0 and finite, got {x}"),
            ))
        }
    }
}

/// Every contact pair at the initial state: shapes may not overlap by more than
/// `tolerance` (m); parry must support the pair.
fn check_overlaps(
    model: &Model,
    initial: &State,
    tolerance: Real,
    spans: &[Range<usize>],
    loc: &Locator<'_>,
) -> Result<(), SceneError> {
    let mut data = Data::new(model);
    update_positions(model, &mut data, initial.t, initial.q.as_slice())
        .map_err(|e| loc.at(0..0, e.to_string()))?;
    for id in model.pair_ids() {
        let Some(pair) = model.pair(id) else { continue };
        let (a, b) = (
            &model.colliders()[pair.a.index()],
            &model.colliders()[pair.b.index()],
        );
        let span = spans.get(pair.a.index()).cloned().unwrap_or(0..0);
        match signed_gap(model, &data, id, 0.0) {
            Ok(Some(gap)) if gap < -tolerance => {
                return Err(loc.at(
                    span,
                    format!(
                        "`{}` and `{}` overlap by {:.3e} m at the start (tolerance {tolerance:.1e} m)",
                        a.name, b.name, -gap
                    ),
                ));
            }
            Ok(_) => {}
            Err(ContactError::Unsupported {
                shape_a, shape_b, ..
            }) => {
                return Err(loc.at(
                    span,
                    format!(
                        "`{}` ({shape_a}) and `{}` ({shape_b}) cannot be tested for contact",
                        a.name, b.name
                    ),
                ));
            }
            Err(e) => return Err(loc.at(span, e.to_string())),
        }
    }
    Ok(())
}
