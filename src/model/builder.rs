//! [`ModelBuilder`]: collects bodies, joints, colliders and contact rules, then validates
//! them into an immutable [`Model`].

use crate::math::Vec2;

use super::pairs::{PairRules, default_touch};
use super::speeds::choose_speeds;
use super::validate::validate;
use super::{
    Body, BodyId, Collider, ColliderId, Constraint, Coordinate, Joint, JointId, JointKind,
    Material, Model, ModelError,
};

/// How a pair of colliders is treated, beyond the default rule.
#[derive(Clone, Copy, Debug)]
enum PairRule {
    /// The pair may touch (even parent–child), with this material or the default one.
    Enable(ColliderId, ColliderId, Option<Material>),
    /// The pair never touches.
    Disable(ColliderId, ColliderId),
}

/// Builds a [`Model`]. Bodies are added with their joint, parents before children (so the
/// tree cannot have cycles); colliders go on bodies or on the world.
///
/// Contact pairs: by default every collider on a body may touch every collider of the world
/// and of every other body, except the colliders of a parent and its child, and those of
/// one body. [`ModelBuilder::pair`] enables a pair (parent–child included) or sets its
/// material; [`ModelBuilder::disable_pair`] removes one.
///
/// ```
/// use ricochet::math::{Pose, Vec2};
/// use ricochet::model::{Body, Joint, Model};
///
/// let mut b = Model::builder();
/// b.gravity(Vec2::new(0.0, -9.81));
/// let rod = b.add_body(
///     Body::new("rod", 1.0, Vec2::new(0.0, -0.5), 1.0 / 12.0),
///     Joint::revolute("rod", None, Pose::identity()),
/// );
/// let model = b.build()?;
/// assert_eq!(model.nq(), 1);
/// assert_eq!(model.coordinates()[0].name, "rod.q");
/// # let _ = rod;
/// # Ok::<(), ricochet::model::ModelError>(())
/// ```
#[derive(Clone, Debug)]
pub struct ModelBuilder {
    bodies: Vec<Body>,
    joints: Vec<Joint>,
    colliders: Vec<Collider>,
    gravity: Vec2,
    default_material: Material,
    rules: Vec<PairRule>,
    constraints: Vec<Constraint>,
}

impl Default for ModelBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl ModelBuilder {
    /// An empty builder: no body, zero gravity, the default material (Newton, `e = 0`,
    /// `μ = 0`).
    pub fn new() -> Self {
        ModelBuilder {
            bodies: Vec::new(),
            joints: Vec::new(),
            colliders: Vec::new(),
            gravity: Vec2::ZERO,
            default_material: Material::default(),
            rules: Vec::new(),
            constraints: Vec::new(),
        }
    }

    /// Sets the gravitational acceleration `g` (m/s², world frame).
    pub fn gravity(&mut self, g: Vec2) -> &mut Self {
        self.gravity = g;
        self
    }

    /// Sets the material of the pairs that have no material of their own.
    pub fn default_material(&mut self, material: Material) -> &mut Self {
        self.default_material = material;
        self
    }

    /// Adds a body with the joint that attaches it to its parent. The parent must have been
    /// added before (checked by [`ModelBuilder::build`]).
    pub fn add_body(&mut self, body: Body, joint: Joint) -> BodyId {
        self.bodies.push(body);
        self.joints.push(joint);
        BodyId(self.bodies.len() - 1)
    }

    /// Adds a collider (on a body, or on the world).
    pub fn add_collider(&mut self, collider: Collider) -> ColliderId {
        self.colliders.push(collider);
        ColliderId(self.colliders.len() - 1)
    }

    /// Adds a nonholonomic constraint (a knife edge or a wheel on a body). Its direction is
    /// normalized by [`ModelBuilder::build`] (a zero direction is an error).
    pub fn add_constraint(&mut self, constraint: Constraint) -> usize {
        self.constraints.push(constraint);
        self.constraints.len() - 1
    }

    /// The constraints added so far.
    pub fn constraints(&self) -> &[Constraint] {
        &self.constraints
    }

    /// Lets the colliders `a` and `b` touch (also for a parent and its child), with
    /// `material`, or the default material if `None`.
    pub fn pair(&mut self, a: ColliderId, b: ColliderId, material: Option<Material>) -> &mut Self {
        self.rules.push(PairRule::Enable(a, b, material));
        self
    }

    /// Keeps the colliders `a` and `b` from touching.
    pub fn disable_pair(&mut self, a: ColliderId, b: ColliderId) -> &mut Self {
        self.rules.push(PairRule::Disable(a, b));
        self
    }

    /// The bodies added so far.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// The colliders added so far.
    pub fn colliders(&self) -> &[Collider] {
        &self.colliders
    }

    /// Validates everything and returns the model.
    /// Prismatic axes are normalized first (a zero axis is an error).
    pub fn build(mut self) -> Result<Model, ModelError> {
        for joint in &mut self.joints {
            if let JointKind::Prismatic { axis } = &mut joint.kind
                && let Some(unit) = axis.try_normalize()
            {
                *axis = unit;
            }
        }
        validate(&self.bodies, &self.joints, &self.colliders, self.gravity)?;
        let pairs = self.pair_rules()?;
        let (coordinates, joint_q) = coordinates(&self.joints);
        let speeds = choose_speeds(
            &self.bodies,
            &self.joints,
            &mut self.constraints,
            &coordinates,
            &joint_q,
        )?;
        Ok(Model {
            nq: coordinates.len(),
            constraints: self.constraints,
            tree_speeds: speeds.tree,
            speeds: speeds.independent_speeds,
            roles: speeds.roles,
            independent: speeds.independent,
            dependent: speeds.dependent,
            body_frame: speeds.body_frame,
            bodies: self.bodies,
            joints: self.joints,
            colliders: self.colliders,
            pairs,
            gravity: self.gravity,
            coordinates,
            joint_q,
        })
    }

    /// The contact rules: the default rule and material, and the builder's rules sorted by
    /// pair (stable: the last rule on a pair wins). No pair is listed (a 4,000-link chain
    /// has 8 million); the materials are checked as if they were, and the first bad one in
    /// pair order is the error.
    fn pair_rules(&self) -> Result<PairRules, ModelError> {
        // (smaller, larger) → the last rule's material (None: disabled), in pair order.
        let mut rules: Vec<((usize, usize), Option<Material>)> =
            Vec::with_capacity(self.rules.len());
        for rule in &self.rules {
            let (a, b) = match *rule {
                PairRule::Enable(a, b, _) | PairRule::Disable(a, b) => (a.0, b.0),
            };
            self.check_pair(a, b)?;
            let material = match *rule {
                PairRule::Enable(_, _, m) => Some(m.unwrap_or(self.default_material)),
                PairRule::Disable(..) => None,
            };
            rules.push(((a.min(b), a.max(b)), material));
        }
        // A stable sort keeps the rules of one pair in their order; keep the last.
        rules.sort_by_key(|r| r.0);
        let mut last: Vec<((usize, usize), Option<Material>)> = Vec::with_capacity(rules.len());
        for r in rules {
            match last.last_mut() {
                Some(l) if l.0 == r.0 => *l = r,
                _ => last.push(r),
            }
        }
        let rules = PairRules {
            default: self.default_material,
            overrides: last,
        };
        self.check_materials(&rules)?;
        Ok(rules)
    }

    /// The first pair, in pair order, whose material is not valid: among the overrides,
    /// and the first pair of the default rule if the default material is not valid.
    fn check_materials(&self, rules: &PairRules) -> Result<(), ModelError> {
        let check = |(i, j): (usize, usize), m: &Material| {
            let p = PairRules::contact_pair(&self.colliders, i, j, *m);
            super::validate::check_material(
                &self.colliders[p.a.0].name,
                &self.colliders[p.b.0].name,
                m,
            )
        };
        let bad_override = (rules.overrides.iter())
            .find(|(key, m)| m.as_ref().is_some_and(|m| check(*key, m).is_err()))
            .map(|&(key, _)| key);
        let mut bad = bad_override;
        if super::validate::check_material("", "", &self.default_material).is_err() {
            // The first couple that the default rule lets touch, before `bad_override`.
            let n = self.colliders.len();
            'scan: for i in 0..n {
                for j in i + 1..n {
                    if bad_override.is_some_and(|b| b <= (i, j)) {
                        break 'scan;
                    }
                    let overridden = (rules.overrides)
                        .binary_search_by_key(&(i, j), |r| r.0)
                        .is_ok();
                    if !overridden && default_touch(&self.colliders, &self.joints, i, j) {
                        bad = Some((i, j));
                        break 'scan;
                    }
                }
            }
        }
        match bad {
            Some(key) => {
                let m = rules.material(&self.colliders, &self.joints, key.0, key.1);
                check(key, &m.unwrap_or(self.default_material))
            }
            None => Ok(()),
        }
    }

    fn check_pair(&self, a: usize, b: usize) -> Result<(), ModelError> {
        let n = self.colliders.len();
        for c in [a, b] {
            if c >= n {
                return Err(ModelError::UnknownCollider { collider: c });
            }
        }
        let reason = match (self.colliders[a].body, self.colliders[b].body) {
            _ if a == b => Some("a collider cannot touch itself"),
            (None, None) => Some("two obstacles of the world cannot touch"),
            (Some(x), Some(y)) if x == y => Some("two colliders of one body cannot touch"),
            _ => None,
        };
        match reason {
            Some(reason) => Err(ModelError::BadPair {
                a: self.colliders[a].name.clone(),
                b: self.colliders[b].name.clone(),
                reason,
            }),
            None => Ok(()),
        }
    }
}

/// The coordinate list, and for each joint the index of its first generalized coordinate
/// (`None` for prescribed and fixed joints).
fn coordinates(joints: &[Joint]) -> (Vec<Coordinate>, Vec<Option<usize>>) {
    let mut coords = Vec::new();
    let mut joint_q = Vec::with_capacity(joints.len());
    for (j, joint) in joints.iter().enumerate() {
        if joint.drive.is_some() || joint.kind.ndof() == 0 {
            joint_q.push(None);
            continue;
        }
        joint_q.push(Some(coords.len()));
        for (k, suffix) in joint.kind.coordinate_suffixes().iter().enumerate() {
            coords.push(Coordinate {
                name: format!("{}.{}", joint.name, suffix),
                joint: JointId(j),
                dof: k,
                is_angle: joint.kind.is_angle(k),
            });
        }
    }
    (coords, joint_q)
}
