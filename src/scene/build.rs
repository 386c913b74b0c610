//! From the parsed file to a [`Model`], the initial [`State`] and the run [`Settings`],
//! with the physical validation located at the offending value.

use std::collections::HashMap;
use std::ops::Range;

use nalgebra::DVector;
use toml::Spanned;

use crate::contact::{ContactError, broad, signed_gap};
use crate::kinematics::update_positions;
use crate::math::{Real, Vec2};
use crate::model::{
    Body, BodyId, Collider, ColliderId, Constraint, Material, Model, ModelBuilder, ModelError,
};
use crate::settings::{IntegratorSettings, Settings};
use crate::state::{Data, State};

use super::SceneError;
use super::error::Locator;
use super::format::{
    BodySpec, ConstraintSpec, ConstraintType, ContactSpec, Pair, RunSpec, SceneFile, Two,
};
use super::ranges;
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
    pub overlap_tolerance: Real,
}

/// Where a name points.
#[derive(Clone, Copy, Debug)]
pub(super) enum Named {
    Body(BodyId),
    Obstacle(ColliderId),
}

/// The conversion in progress.
pub(super) struct Builder<'a> {
    pub(super) loc: &'a Locator<'a>,
    pub(super) model: ModelBuilder,
    pub(super) names: HashMap<String, Named>,
    pub(super) q0: Vec<Real>,
    pub(super) u0: Vec<Real>,
    /// For each coordinate, whether the file gives its speed.
    pub(super) u_given: Vec<bool>,
    /// For each collider, the span its errors point at.
    pub(super) collider_spans: Vec<Range<usize>>,
    /// For each body, the span its errors point at (its joint).
    pub(super) body_spans: Vec<Range<usize>>,
    /// For each body, its colliders.
    pub(super) body_colliders: HashMap<BodyId, Vec<ColliderId>>,
    /// For each nonholonomic constraint, the span its errors point at (its name or type),
    /// and its `removes` field's if it has one.
    pub(super) constraint_spans: Vec<(Range<usize>, Option<Range<usize>>)>,
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
    if let Some(why) = ranges::bad_name(file.name.get_ref()) {
        return Err(loc.at(file.name.span(), format!("the scene's name: {why}")));
    }
    if file.body.is_empty() && file.chain.is_none() {
        return Err(loc.at(
            file.name.span(),
            "the scene has no body: give at least one [[body]] (or a [chain])",
        ));
    }
    let mut settings = settings(&file.run, loc)?;
    if let Some(rule) = file.contact.as_ref().and_then(|c| c.get_ref().simultaneous) {
        settings.simultaneous = rule;
    }
    let mut b = Builder {
        loc,
        model: ModelBuilder::new(),
        names: HashMap::new(),
        q0: Vec::new(),
        u0: Vec::new(),
        u_given: Vec::new(),
        collider_spans: Vec::new(),
        body_spans: Vec::new(),
        body_colliders: HashMap::new(),
        constraint_spans: Vec::new(),
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
        u_given,
        collider_spans,
        body_spans,
        constraint_spans,
        ..
    } = b;
    let constraint_names: Vec<String> = (model.constraints().iter())
        .map(|c| c.name.clone())
        .collect();
    let model = model.build().map_err(|e| match &e {
        ModelError::BadConstraint {
            constraint, reason, ..
        } => {
            let k = constraint_names.iter().position(|n| n == constraint);
            let span = k.map_or(file.name.span(), |k| {
                let (name, removes) = &constraint_spans[k];
                match removes {
                    Some(r) if reason.starts_with("`removes`") => r.clone(),
                    _ => name.clone(),
                }
            });
            loc.at(span, e.to_string())
        }
        _ => locate_model_error(e, &file, loc),
    })?;
    if let (None, Some(pair)) = (&file.contact, model.pairs().next()) {
        return Err(loc.at(
            collider_spans[pair.a.index()].clone(),
            "the scene has contact pairs but no [contact] table: give at least `e` and `mu`",
        ));
    }
    let u0 = if model.is_holonomic() {
        u0
    } else {
        let spans: Vec<Range<usize>> = constraint_spans.into_iter().map(|(n, _)| n).collect();
        initial_speeds(&model, &q0, &u0, &u_given, &spans, loc)?
    };
    let initial = State::new(0.0, DVector::from_vec(q0), DVector::from_vec(u0));
    let data = positions(&model, &initial).map_err(|e| loc.at(0..0, e))?;
    check_reach(&model, &data, &body_spans, loc)?;
    check_overlaps(&model, &data, tolerance, &collider_spans, loc)?;
    Ok(Built {
        name: file.name.into_inner(),
        description: file.description.unwrap_or_default(),
        model,
        initial,
        settings,
        overlap_tolerance: tolerance,
    })
}

/// The generalized speeds of the initial coordinate rates `q̇₀` the joints give (their
/// `vx`, `vy`, `rate`, …): the speeds no constraint removes are taken as given (zero when
/// absent), the removed ones follow from the constraints; a removed speed that the file
/// gives must agree with them (a blade that starts moving sideways is an error at its
/// constraint, with both values).
fn initial_speeds(
    model: &Model,
    q0: &[Real],
    qdot0: &[Real],
    given: &[bool],
    spans: &[Range<usize>],
    loc: &Locator<'_>,
) -> Result<Vec<Real>, SceneError> {
    let mut data = Data::for_kinematics(model);
    update_positions(model, &mut data, 0.0, q0).map_err(|e| {
        let span = match &e {
            crate::kinematics::KinematicsError::SingularConstraints { constraint, .. } => {
                (model.constraints().iter())
                    .position(|c| &c.name == constraint)
                    .map_or(0..0, |k| spans[k].clone())
            }
            _ => 0..0,
        };
        loc.at(span, format!("at the initial state: {e}"))
    })?;
    let v0 = crate::constraints::tree_speeds_from_rates(model, &data, qdot0);
    let u: Vec<Real> = (model.independent_speeds().iter())
        .map(|&i| v0[i])
        .collect();
    crate::kinematics::update_velocities(model, &mut data, &u)
        .map_err(|e| loc.at(0..0, format!("at the initial state: {e}")))?;
    let v = &data.tree_speed;
    let scale = (v0.iter().chain(v.iter())).fold(0.0 as Real, |m, x| m.max(x.abs()));
    for (k, &d) in model.dependent_speeds().iter().enumerate() {
        if given[d] && (v0[d] - v[d]).abs() > 1e-9 * scale {
            let (c, speed) = (&model.constraints()[k], &model.tree_speeds()[d]);
            let unit = if speed.is_angle { "rad/s" } else { "m/s" };
            return Err(loc.at(
                spans[k].clone(),
                format!(
                    "the initial velocity breaks constraint `{}`: it removes the speed `{}`, \
                     which it makes {} {unit}, and the joint's initial velocity gives {} \
                     {unit}; leave that speed out (give the body-frame speeds `vx_body`, \
                     `vy_body` and `rate` that the constraints leave) or make them agree",
                    c.name,
                    speed.name,
                    ranges::number(v[d]),
                    ranges::number(v0[d]),
                ),
            ));
        }
    }
    Ok(u)
}

/// A model error located at the body, joint, shape or obstacle it names (its `name`
/// field), or at the file's `name` when it names none of them: every scene error has a
/// line and a field.
fn locate_model_error(e: ModelError, file: &SceneFile, loc: &Locator<'_>) -> SceneError {
    let named = match &e {
        ModelError::DuplicateName { name, .. } => Some(name.as_str()),
        ModelError::BadMass { body, .. } | ModelError::BadInertia { body, .. } => {
            Some(body.as_str())
        }
        ModelError::BadParent { joint, .. }
        | ModelError::BadAxis { joint, .. }
        | ModelError::DriveOnMultiDof { joint, .. }
        | ModelError::ForceNotAllowed { joint, .. }
        | ModelError::NegativeCoefficient { joint, .. } => Some(joint.as_str()),
        ModelError::UnknownBody { collider, .. } => Some(collider.as_str()),
        ModelError::BadPair { a, .. } | ModelError::BadMaterial { a, .. } => Some(a.as_str()),
        _ => None,
    };
    let span = named
        .and_then(|n| {
            (file.body.iter().map(|b| &b.get_ref().name))
                .chain(file.obstacle.iter().map(|o| &o.get_ref().name))
                .find(|name| name.get_ref() == n)
                .map(|name| name.span())
        })
        .unwrap_or(file.name.span());
    loc.at(span, e.to_string())
}

/// `[run]` → [`Settings`]: times, rates and tolerances within their ranges
/// ([`ranges`]), and no more output samples or fixed steps than a run can take.
fn settings(run: &RunSpec, loc: &Locator<'_>) -> Result<Settings, SceneError> {
    let within = |v: &Spanned<Real>, what: &str, range: (Real, Real)| -> Result<Real, SceneError> {
        let (what, unit) = what.split_once('|').unwrap_or((what, ""));
        ranges::check(*v.get_ref(), range, what, unit).map_err(|m| loc.at(v.span(), m))
    };
    let mut settings = Settings {
        t_end: within(&run.t_end, "the end time|s", ranges::T_END)?,
        ..Settings::default()
    };
    if let Some(rate) = &run.output_rate {
        settings.output_rate = within(rate, "the output rate|Hz", ranges::OUTPUT_RATE)?;
        let samples = settings.t_end * settings.output_rate;
        if samples > ranges::SAMPLES {
            return Err(loc.at(
                rate.span(),
                format!(
                    "t_end × output_rate = {samples:.3e} samples, more than {:e}: lower the rate",
                    ranges::SAMPLES
                ),
            ));
        }
    }
    if let Some(budget) = &run.max_drift {
        settings.max_drift = Some(within(
            budget,
            "the drift budget max_drift",
            ranges::MAX_DRIFT,
        )?);
    }
    let mut integ = IntegratorSettings::default();
    if let Some(spec) = &run.integrator {
        if let Some(m) = spec.method {
            integ.method = m;
        }
        for (field, value, what, range) in [
            (&mut integ.rtol, &spec.rtol, "rtol", ranges::RTOL),
            (&mut integ.atol, &spec.atol, "atol", ranges::ATOL),
            (&mut integ.dt, &spec.dt, "the step dt|s", ranges::DT),
            (&mut integ.h_max, &spec.h_max, "h_max|s", ranges::H_MAX),
        ] {
            if let Some(v) = value {
                *field = within(v, what, range)?;
            }
        }
        let steps = settings.t_end / integ.dt;
        if let (true, Some(dt)) = (integ.method.is_fixed_step(), &spec.dt)
            && steps > ranges::FIXED_STEPS
        {
            return Err(loc.at(
                dt.span(),
                format!(
                    "t_end / dt = {steps:.3e} steps, more than {:e}: take a longer step",
                    ranges::FIXED_STEPS
                ),
            ));
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
    pub(super) fn err(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        self.loc.at(span, message)
    }

    /// A finite `[x, y]`.
    pub(super) fn pair(&self, v: &Spanned<Pair>) -> Result<Vec2, SceneError> {
        let Two([x, y]) = *v.get_ref();
        if x.abs() <= ranges::KINEMATIC && y.abs() <= ranges::KINEMATIC {
            Ok(Vec2::new(x, y))
        } else {
            Err(self.err(
                v.span(),
                format!(
                    "[{}, {}]: each component must be a finite number within ±{:e}",
                    ranges::number(x),
                    ranges::number(y),
                    ranges::KINEMATIC
                ),
            ))
        }
    }

    pub(super) fn pair_or(
        &self,
        v: &Option<Spanned<Pair>>,
        default: Vec2,
    ) -> Result<Vec2, SceneError> {
        v.as_ref().map_or(Ok(default), |v| self.pair(v))
    }

    /// A number within `range` ([`ranges`]).
    pub(super) fn within(
        &self,
        v: &Spanned<Real>,
        what: &str,
        unit: &str,
        range: (Real, Real),
    ) -> Result<Real, SceneError> {
        ranges::check(*v.get_ref(), range, what, unit).map_err(|m| self.err(v.span(), m))
    }

    /// An optional quantity of the given kind.
    pub(super) fn quantity(
        &self,
        v: &Option<Spanned<Quantity>>,
        kind: Kind,
    ) -> Result<Option<Real>, SceneError> {
        self.quantity_within(
            v,
            kind,
            ranges::KINEMATIC,
            ": lengths, speeds, angles and rates are bounded by it",
        )
    }

    /// An optional quantity of the given kind, in SI, within `±bound`; `why` ends the
    /// message of a value beyond it.
    pub(super) fn quantity_within(
        &self,
        v: &Option<Spanned<Quantity>>,
        kind: Kind,
        bound: Real,
        why: &str,
    ) -> Result<Option<Real>, SceneError> {
        let Some(v) = v else { return Ok(None) };
        let x = v.get_ref().si(kind).map_err(|m| self.err(v.span(), m))?;
        if x.abs() <= bound {
            Ok(Some(x))
        } else {
            Err(self.err(
                v.span(),
                format!("got {} (SI), beyond ±{bound:e}{why}", ranges::number(x)),
            ))
        }
    }

    pub(super) fn quantity_or(
        &self,
        v: &Option<Spanned<Quantity>>,
        kind: Kind,
        default: Real,
    ) -> Result<Real, SceneError> {
        Ok(self.quantity(v, kind)?.unwrap_or(default))
    }

    /// Registers a body or obstacle name (unique, not `world`).
    pub(super) fn name(&mut self, name: &Spanned<String>, what: Named) -> Result<(), SceneError> {
        let n = name.get_ref();
        if let Some(why) = ranges::bad_name(n) {
            return Err(self.err(name.span(), why));
        }
        if n == "world" {
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

    pub(super) fn add_collider(&mut self, collider: Collider, span: Range<usize>) -> ColliderId {
        let body = collider.body;
        let id = self.model.add_collider(collider);
        self.collider_spans.push(span);
        if let Some(b) = body {
            self.body_colliders.entry(b).or_default().push(id);
        }
        id
    }

    /// `[[body]]` with its joint and shapes. Its parent is already in the model.
    pub(super) fn body(&mut self, spec: &Spanned<BodySpec>) -> Result<(), SceneError> {
        let s = spec.get_ref();
        let mass = self.within(&s.mass, "the mass", "kg", ranges::MASS)?;
        let inertia = self.within(
            &s.inertia,
            "the moment of inertia",
            "kg·m²",
            ranges::INERTIA,
        )?;
        let com = self.pair_or(&s.com, Vec2::ZERO)?;
        let name = s.name.get_ref().clone();
        let parent = match &s.joint.get_ref().parent {
            Some(p) if p.get_ref() != "world" => match self.names.get(p.get_ref()) {
                Some(Named::Body(id)) => Some(*id),
                _ => return Err(self.err(p.span(), format!("`{}` is not a body", p.get_ref()))),
            },
            _ => None,
        };
        let (joint, q, u, given) = self.joint(&name, s.joint.get_ref(), parent)?;
        let id = self
            .model
            .add_body(Body::new(&name, mass, com, inertia), joint);
        self.body_spans.push(s.joint.span());
        self.name(&s.name, Named::Body(id))?;
        self.q0.extend(q);
        self.u0.extend(u);
        self.u_given.extend(given);
        for (k, shape) in s.shape.iter().enumerate() {
            let collider_name = self.part_name(&shape.get_ref().name, &name, k, s.shape.len())?;
            if (self.model.colliders().iter()).any(|c| c.name == collider_name)
                || (self.names.get(&collider_name)).is_some_and(|n| matches!(n, Named::Obstacle(_)))
            {
                let span = shape
                    .get_ref()
                    .name
                    .as_ref()
                    .map_or(shape.span(), |n| n.span());
                return Err(self.err(
                    span,
                    format!("the shape name `{collider_name}` is used twice"),
                ));
            }
            let (geometry, pose) = self.body_shape(shape)?;
            let span = shape.get_ref().kind.span();
            self.add_collider(Collider::new(collider_name, Some(id), geometry, pose), span);
        }
        for (k, c) in s.constraint.iter().enumerate() {
            self.constraint(c, id, &name, k, s.constraint.len())?;
        }
        Ok(())
    }

    /// The name of the `k`-th of `count` parts (shapes, constraints) of `body`: the one
    /// the file gives (a valid name), else the body's own if it is the only one, else
    /// `<body>/<k>`.
    fn part_name(
        &self,
        given: &Option<Spanned<String>>,
        body: &str,
        k: usize,
        count: usize,
    ) -> Result<String, SceneError> {
        Ok(match given {
            Some(n) => {
                if let Some(why) = ranges::bad_name(n.get_ref()) {
                    return Err(self.err(n.span(), why));
                }
                n.get_ref().clone()
            }
            None if count == 1 => body.to_owned(),
            None => format!("{body}/{k}"),
        })
    }

    /// `[[body.constraint]]` of body `id`: its `k`-th of `count`.
    fn constraint(
        &mut self,
        spec: &Spanned<ConstraintSpec>,
        id: BodyId,
        body: &str,
        k: usize,
        count: usize,
    ) -> Result<(), SceneError> {
        let c = spec.get_ref();
        let name = self.part_name(&c.name, body, k, count)?;
        let name_span = c.name.as_ref().map_or(c.kind.span(), |n| n.span());
        if self.model.constraints().iter().any(|o| o.name == name) {
            return Err(self.err(
                name_span,
                format!("the constraint name `{name}` is used twice"),
            ));
        }
        let point = self.pair_or(&c.at, Vec2::ZERO)?;
        let angle = self.quantity_or(&c.direction, Kind::Angle, 0.0)?;
        let direction = Vec2::new(angle.cos(), angle.sin());
        let mut constraint = match c.kind.get_ref() {
            ConstraintType::KnifeEdge => Constraint::knife_edge(name, id, point, direction),
            ConstraintType::Wheel => Constraint::wheel(name, id, point, direction),
        };
        if let Some(r) = &c.removes {
            constraint = constraint.removing(r.get_ref().clone());
        }
        self.model.add_constraint(constraint);
        let removes_span = c.removes.as_ref().map(|r| r.span());
        self.constraint_spans.push((name_span, removes_span));
        Ok(())
    }

    /// `[contact]`: the default material and the pair rules. Returns the overlap tolerance.
    pub(super) fn contact(
        &mut self,
        spec: Option<&Spanned<ContactSpec>>,
    ) -> Result<Real, SceneError> {
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
            let Two([a, b]) = p.between.get_ref();
            let (ca, cb) = (self.colliders_named(a)?, self.colliders_named(b)?);
            if a.get_ref() == b.get_ref() {
                return Err(self.err(p.between.span(), "a pair needs two different names"));
            }
            if !ca
                .iter()
                .chain(&cb)
                .any(|&c| self.model.colliders()[c.index()].body.is_some())
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
            Some(t) => self.within(t, "the overlap tolerance", "m", ranges::OVERLAP),
        }
    }

    /// The colliders of the body or obstacle `name`.
    pub(super) fn colliders_named(
        &self,
        name: &Spanned<String>,
    ) -> Result<Vec<ColliderId>, SceneError> {
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

    pub(super) fn restitution(&self, e: &Spanned<Real>) -> Result<Real, SceneError> {
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

    pub(super) fn friction(&self, mu: &Spanned<Real>) -> Result<Real, SceneError> {
        self.within(mu, "the coefficient of friction mu", "", ranges::FRICTION)
    }
}

/// Every body at the initial state within `1e4 L` of the world origin (`L` the largest
/// shape of a body, [`crate::sim::Scales`]): the dynamics refers its spatial quantities to
/// the origin, and a body far from it loses digits as `(r/L)²` (the chain moved to
/// x = 1e3 m, 3700 L, takes 7 times the steps; at 2e4 m, 300 times).
fn check_reach(
    model: &Model,
    data: &Data,
    spans: &[Range<usize>],
    loc: &Locator<'_>,
) -> Result<(), SceneError> {
    let length = crate::sim::Scales::of(model, &IntegratorSettings::default()).length;
    let reach = ranges::REACH * length;
    for (k, body) in model.bodies().iter().enumerate() {
        let r = data.body_com[k]
            .length()
            .max(data.body_pose[k].translation.length());
        if r.is_nan() || r > reach {
            return Err(loc.at(
                spans.get(k).cloned().unwrap_or(0..0),
                format!(
                    "body `{}` starts {} m from the world origin, beyond 1e4 times the largest \
                     shape ({} m): move the scene nearer the origin",
                    body.name,
                    ranges::number(r),
                    ranges::number(reach)
                ),
            ));
        }
    }
    Ok(())
}

/// Every contact pair at the initial state: shapes may not overlap by more than
/// `tolerance` (m); parry must support the pair.
fn check_overlaps(
    model: &Model,
    data: &Data,
    tolerance: Real,
    spans: &[Range<usize>],
    loc: &Locator<'_>,
) -> Result<(), SceneError> {
    overlaps(model, data, tolerance)
        .map_err(|(pair, message)| loc.at(spans.get(pair).cloned().unwrap_or(0..0), message))
}

/// The first overlap beyond `tolerance` at `initial` (or a pair parry cannot test), in
/// words.
pub(super) fn first_overlap(model: &Model, initial: &State, tolerance: Real) -> Result<(), String> {
    let data = positions(model, initial)?;
    overlaps(model, &data, tolerance).map_err(|(_, message)| message)
}

/// The poses of `model` at `initial` (a workspace with its positions updated).
fn positions(model: &Model, initial: &State) -> Result<Data, String> {
    let mut data = Data::for_kinematics(model);
    update_positions(model, &mut data, initial.t, initial.q.as_slice())
        .map_err(|e| e.to_string())?;
    Ok(data)
}

/// The first overlap beyond `tolerance` at the poses of `data`, with the index of the
/// pair's collider `a`, or the first pair whose shapes parry cannot test.
///
/// Only the pairs that can fail are tested, in pair order (so the first failure is the
/// same as over all pairs): those whose bounding boxes overlap (shapes whose boxes are
/// disjoint do not overlap; [`broad`]), and the first pair of each combination of shape
/// types (parry refuses a combination whatever the poses). A 4,000-link chain has 8
/// million pairs and about 4,000 of these.
fn overlaps(model: &Model, data: &Data, tolerance: Real) -> Result<(), (usize, String)> {
    let boxes = broad::collider_boxes(model, data, |_| 0.0).map_err(|e| (0, e.to_string()))?;
    let mut tested = broad::overlapping_pairs(model, &boxes);
    let kind = |c: crate::model::ColliderId| model.colliders()[c.index()].shape.shape_type();
    // The first pair of each combination, in pair order; the walk stops once every
    // combination that can occur (a shape type on a body with any shape type) is found.
    let types = |on_body: bool| {
        let mut t: Vec<_> = (model.colliders().iter())
            .filter(|c| !on_body || c.body.is_some())
            .map(|c| c.shape.shape_type())
            .collect();
        t.sort_by_key(|k| *k as u32);
        t.dedup();
        t.len()
    };
    let possible = types(true) * types(false);
    let mut combinations = Vec::new();
    for p in model.pairs() {
        let key = (kind(p.a), kind(p.b));
        if !combinations.iter().any(|(k, _)| *k == key) {
            combinations.extend(model.pair_between(p.a, p.b).map(|id| (key, id)));
            if combinations.len() >= possible {
                break;
            }
        }
    }
    tested.extend(combinations.into_iter().map(|(_, id)| id));
    tested.sort_unstable();
    tested.dedup();
    for id in tested {
        let Some(pair) = model.pair(id) else { continue };
        let (a, b) = (
            &model.colliders()[pair.a.index()],
            &model.colliders()[pair.b.index()],
        );
        let at = pair.a.index();
        match signed_gap(model, data, id, 0.0) {
            Ok(Some(gap)) if gap < -tolerance => {
                return Err((
                    at,
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
                return Err((
                    at,
                    format!(
                        "`{}` ({shape_a}) and `{}` ({shape_b}) cannot be tested for contact",
                        a.name, b.name
                    ),
                ));
            }
            Err(e) => return Err((at, e.to_string())),
        }
    }
    Ok(())
}
