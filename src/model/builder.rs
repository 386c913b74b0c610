//! [`ModelBuilder`]: collects bodies, joints, colliders and contact rules, then validates
//! them into an immutable [`Model`].

use crate::math::Vec2;

use super::speeds::choose_speeds;
use super::validate::validate;
use super::{
    Body, BodyId, Collider, ColliderId, Constraint, ContactPair, Coordinate, Joint, JointId,
    JointKind, Material, Model, ModelError,
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
        let pairs = self.contact_pairs()?;
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

    /// The default pairs, then the rules in order (the last rule on a pair wins). The
    /// rules are sorted by pair and walked alongside the pairs, which are listed in the
    /// order of their smaller, then their larger collider index (no `n × n` table: a
    /// 4,000-link chain has 8 million pairs).
    fn contact_pairs(&self) -> Result<Vec<ContactPair>, ModelError> {
        let n = self.colliders.len();
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
        let mut next_rule = last.iter().peekable();
        let mut pairs = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                let material = match next_rule.peek() {
                    Some(&&(key, m)) if key == (i, j) => {
                        next_rule.next();
                        m
                    }
                    _ => self.default_touch(i, j).then_some(self.default_material),
                };
                if let Some(material) = material {
                    // `a` on a body; `b` on a body or the world.
                    let (a, b) = if self.colliders[i].body.is_some() {
                        (i, j)
                    } else {
                        (j, i)
                    };
                    super::validate::check_material(
                        &self.colliders[a].name,
                        &self.colliders[b].name,
                        &material,
                    )?;
                    pairs.push(ContactPair {
                        a: ColliderId(a),
                        b: ColliderId(b),
                        material,
                    });
                }
            }
        }
        Ok(pairs)
    }

    /// The default rule: different bodies (or a body and the world), not parent and child.
    fn default_touch(&self, i: usize, j: usize) -> bool {
        match (self.colliders[i].body, self.colliders[j].body) {
            (None, None) => false,
            (Some(_), None) | (None, Some(_)) => true,
            (Some(a), Some(b)) => {
                a != b && self.joints[a.0].parent != Some(b) && self.joints[b.0].parent != Some(a)
            }
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
