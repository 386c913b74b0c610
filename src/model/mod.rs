//! The mechanical model: a kinematic tree of rigid bodies with minimal generalized
//! coordinates, their force elements, prescribed motions, colliders and contact pairs.
//! A [`Model`] is built once by a [`ModelBuilder`], validated, and never changes.
//!
//! ## Coordinates
//!
//! Body `i` is attached to its parent (a body added before it, or the world) by joint `i`
//! ([`JointKind`]: revolute, prismatic, translation, planar or fixed). The joint
//! coordinates of the free joints, in body order, are the generalized coordinates `q`
//! (`nq` of them), and the generalized speeds are their rates, `u = q̇` (`nu = nq`),
//! unless the model has nonholonomic [`Constraint`]s: then `nu = nq − m` speeds remain and
//! `q̇ = A(q, t) u + b(q, t)` (see [`Constraint`]'s module, the simple nonholonomic systems
//! of [P, Sect. 2]). A
//! joint with a [`PrescribedMotion`] contributes no coordinate: its position, rate and
//! acceleration are known functions of time, and its rate produces the *remainder*
//! velocities of [P, Eq. (2)]:
//!
//! ```text
//! v^P = Σ_r v_r^P u_r + v_t^P
//! ```
//!
//! ## Frames
//!
//! The world frame has `y` up when gravity is `(0, −g)`, angles are counter-clockwise. A
//! body's frame is placed by its joint: `X_body = X_parent · placement · motion(q)`
//! (see [`JointKind`]); for an absolute revolute joint the rotation of `X_parent` is
//! dropped.

mod body;
mod builder;
mod collider;
mod constraint;
mod error;
mod joint;
#[doc(hidden)]
pub mod pairs;
pub mod spatial;
mod speeds;
mod validate;

pub use body::Body;
pub use builder::ModelBuilder;
pub use collider::{Collider, ContactPair, Material};
pub use constraint::{Constraint, ConstraintKind, Speed, SpeedRole};
pub use error::ModelError;
pub use joint::{Joint, JointForce, JointKind, PrescribedMotion};

use crate::math::Vec2;

/// Index of a body of a [`Model`] (also the index of its joint, [`JointId`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BodyId(pub(crate) usize);

/// Index of a joint of a [`Model`]; joint `i` attaches body `i` to its parent.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct JointId(pub(crate) usize);

/// Index of a collider of a [`Model`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ColliderId(pub(crate) usize);

/// A contact pair of a [`Model`], derived from its two collider indices `i < j`
/// (`i · 2³² + j`: stable, in the order of `i`, then `j`; see [`Model::pair_between`]).
/// The model answers for any pair on demand; it lists none.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PairId(#[doc(hidden)] pub usize);

macro_rules! id_index {
    ($($t:ty),*) => {$(
        impl $t {
            /// The index in the model's list.
            #[inline]
            pub fn index(self) -> usize {
                self.0
            }
        }
    )*};
}
id_index!(BodyId, JointId, ColliderId, PairId);

impl BodyId {
    /// The joint that attaches this body to its parent.
    #[inline]
    pub fn joint(self) -> JointId {
        JointId(self.0)
    }
}

impl PairId {
    /// The two colliders `(i, j)`, `i < j`, of the pair among `ncolliders` colliders (the
    /// inverse of its definition); `None` beyond the last couple.
    pub fn colliders(self, ncolliders: usize) -> Option<(ColliderId, ColliderId)> {
        pairs::decode(ncolliders, self.0).map(|(i, j)| (ColliderId(i), ColliderId(j)))
    }
}

impl JointId {
    /// The body this joint moves.
    #[inline]
    pub fn body(self) -> BodyId {
        BodyId(self.0)
    }
}

/// One generalized coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct Coordinate {
    /// Name `"<joint>.<suffix>"`, e.g. `"rodA.q"`, `"ball.y"`, `"rod.theta"`.
    pub name: String,
    /// The joint it belongs to.
    pub joint: JointId,
    /// Its index among the joint's coordinates.
    pub dof: usize,
    /// `true` for an angle (rad, rad/s), `false` for a length (m, m/s).
    pub is_angle: bool,
}

/// The constant mechanical model (see the [module documentation](self)).
#[derive(Clone, Debug)]
pub struct Model {
    bodies: Vec<Body>,
    joints: Vec<Joint>,
    colliders: Vec<Collider>,
    /// The contact rules (no list of pairs: see `pairs.rs`).
    pairs: pairs::PairRules,
    gravity: Vec2,
    coordinates: Vec<Coordinate>,
    /// For each joint, the index in `q` of its first coordinate; `None` if prescribed or
    /// fixed.
    joint_q: Vec<Option<usize>>,
    nq: usize,
    /// The nonholonomic constraints (empty for a holonomic model).
    constraints: Vec<Constraint>,
    /// The tree speeds `v` `[nv = nq]`, in the order of `q`.
    tree_speeds: Vec<Speed>,
    /// The generalized speeds `u` `[nu]`: the tree speeds no constraint removes.
    speeds: Vec<Speed>,
    /// For each tree speed, its role.
    roles: Vec<SpeedRole>,
    /// The tree-speed index of each `u`.
    independent: Vec<usize>,
    /// The tree-speed index each constraint removes, in constraint order.
    dependent: Vec<usize>,
    /// For each joint: its planar speeds are in the body's frame.
    body_frame: Vec<bool>,
}

impl Model {
    /// A builder for a model.
    pub fn builder() -> ModelBuilder {
        ModelBuilder::new()
    }

    /// Number of generalized coordinates `nq`.
    #[inline]
    pub fn nq(&self) -> usize {
        self.nq
    }

    /// Number of generalized speeds `nu` (`p` of [P, Sect. 2]): `nq` less one per
    /// nonholonomic constraint (`= nq`, `u = q̇`, for a holonomic model).
    #[inline]
    pub fn nu(&self) -> usize {
        self.independent.len()
    }

    /// Number of tree speeds `nv` (`= nq`): the joint rates, before the constraints remove
    /// some (see [`constraint`](crate::model::Constraint)).
    #[inline]
    pub fn nv(&self) -> usize {
        self.nq
    }

    /// `true` if the model has no nonholonomic constraint: `u = v = q̇`.
    #[inline]
    pub fn is_holonomic(&self) -> bool {
        self.constraints.is_empty()
    }

    /// The nonholonomic constraints.
    #[inline]
    pub fn constraints(&self) -> &[Constraint] {
        &self.constraints
    }

    /// The generalized speeds `u`, in order (for a holonomic model, one per coordinate
    /// with the coordinate's name).
    #[inline]
    pub fn speeds(&self) -> &[Speed] {
        &self.speeds
    }

    /// The tree speeds `v` (one per coordinate), the removed ones included.
    #[inline]
    pub fn tree_speeds(&self) -> &[Speed] {
        &self.tree_speeds
    }

    /// The role of each tree speed.
    #[inline]
    pub fn speed_roles(&self) -> &[SpeedRole] {
        &self.roles
    }

    /// The tree-speed index of each generalized speed.
    #[inline]
    pub fn independent_speeds(&self) -> &[usize] {
        &self.independent
    }

    /// The tree-speed index each constraint removes, in constraint order.
    #[inline]
    pub fn dependent_speeds(&self) -> &[usize] {
        &self.dependent
    }

    /// `true` if the speeds of joint `id` are in its body's frame (a planar joint whose
    /// body carries a constraint).
    #[inline]
    pub fn has_body_frame_speeds(&self, id: JointId) -> bool {
        self.body_frame.get(id.0).copied().unwrap_or(false)
    }

    /// Number of bodies (and of joints).
    #[inline]
    pub fn nbody(&self) -> usize {
        self.bodies.len()
    }

    /// The bodies, in tree order (parents before children).
    #[inline]
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// The joints; joint `i` attaches body `i`.
    #[inline]
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// The colliders.
    #[inline]
    pub fn colliders(&self) -> &[Collider] {
        &self.colliders
    }

    /// The contact pairs that may touch, in pair order, computed one by one from the rules
    /// (nothing is stored: a 4,000-link chain has 8 million; `O(n²)` to walk them all).
    pub fn pairs(&self) -> impl Iterator<Item = ContactPair> + '_ {
        let (n, colliders) = (self.colliders.len(), &self.colliders);
        (0..n).flat_map(move |i| {
            (i + 1..n).filter_map(move |j| {
                let material = self.pairs.material(colliders, &self.joints, i, j)?;
                Some(pairs::PairRules::contact_pair(colliders, i, j, material))
            })
        })
    }

    /// The number of pairs that may touch, counted without storing them (`O(n²)` time for
    /// `n` colliders, `O(1)` memory).
    pub fn pair_count(&self) -> usize {
        self.pairs.count(&self.colliders, &self.joints)
    }

    /// Gravitational acceleration `g` (m/s², world frame).
    #[inline]
    pub fn gravity(&self) -> Vec2 {
        self.gravity
    }

    /// The generalized coordinates, in the order of `q` and `u`.
    #[inline]
    pub fn coordinates(&self) -> &[Coordinate] {
        &self.coordinates
    }

    /// The body `id`, if it exists.
    #[inline]
    pub fn body(&self, id: BodyId) -> Option<&Body> {
        self.bodies.get(id.0)
    }

    /// The joint `id`, if it exists.
    #[inline]
    pub fn joint(&self, id: JointId) -> Option<&Joint> {
        self.joints.get(id.0)
    }

    /// The collider `id`, if it exists.
    #[inline]
    pub fn collider(&self, id: ColliderId) -> Option<&Collider> {
        self.colliders.get(id.0)
    }

    /// The contact pair `id`, if its colliders may touch.
    pub fn pair(&self, id: PairId) -> Option<ContactPair> {
        let n = self.colliders.len();
        let (i, j) = pairs::decode(n, id.0)?;
        let material = self.pairs.material(&self.colliders, &self.joints, i, j)?;
        Some(pairs::PairRules::contact_pair(
            &self.colliders,
            i,
            j,
            material,
        ))
    }

    /// The contact pair `id` of a pair the model gave out ([`Model::pair_between`],
    /// [`Model::pair_ids`], the broad phase): its colliders decoded from the id and its
    /// material. An id of colliders that may not touch gets the default material; an id
    /// beyond the last couple, the colliders 0 and 1 (neither happens in the loop).
    pub fn pair_of(&self, id: PairId) -> ContactPair {
        let n = self.colliders.len();
        let (i, j) = pairs::decode(n, id.0).unwrap_or((0, 1));
        let material = (self.pairs)
            .material(&self.colliders, &self.joints, i, j)
            .unwrap_or(self.pairs.default);
        pairs::PairRules::contact_pair(&self.colliders, i, j, material)
    }

    /// The pair of the colliders `x` and `y` (in either order), if they may touch: its id
    /// from the two collider indices, after the rules (`O(log r)` for `r` pair rules).
    pub fn pair_between(&self, x: ColliderId, y: ColliderId) -> Option<PairId> {
        let (i, j) = (x.0.min(y.0), x.0.max(y.0));
        let n = self.colliders.len();
        if i == j || j >= n {
            return None;
        }
        (self.pairs.material(&self.colliders, &self.joints, i, j)).map(|_| pairs::encode(n, i, j))
    }

    /// Index in `q` of the first coordinate of joint `id`; `None` for a prescribed or fixed
    /// joint (or an unknown id).
    #[inline]
    pub fn q_index(&self, id: JointId) -> Option<usize> {
        self.joint_q.get(id.0).copied().flatten()
    }

    /// All body ids, in tree order.
    pub fn body_ids(&self) -> impl Iterator<Item = BodyId> + use<> {
        (0..self.bodies.len()).map(BodyId)
    }

    /// The ids of the pairs that may touch, in pair order, found one by one from the rules
    /// (`O(n²)` to walk them all, nothing stored).
    pub fn pair_ids(&self) -> impl Iterator<Item = PairId> + '_ {
        let n = self.colliders.len();
        (0..n).flat_map(move |i| {
            (i + 1..n)
                .filter(move |&j| {
                    (self.pairs)
                        .material(&self.colliders, &self.joints, i, j)
                        .is_some()
                })
                .map(move |j| pairs::encode(n, i, j))
        })
    }

    /// All collider ids.
    pub fn collider_ids(&self) -> impl Iterator<Item = ColliderId> + use<> {
        (0..self.colliders.len()).map(ColliderId)
    }

    /// The body named `name`.
    pub fn body_by_name(&self, name: &str) -> Option<BodyId> {
        self.bodies.iter().position(|b| b.name == name).map(BodyId)
    }

    /// The collider named `name`.
    pub fn collider_by_name(&self, name: &str) -> Option<ColliderId> {
        self.colliders
            .iter()
            .position(|c| c.name == name)
            .map(ColliderId)
    }

    /// `true` if some joint has a prescribed motion (the model is rheonomic).
    pub fn has_prescribed_motion(&self) -> bool {
        self.joints.iter().any(|j| j.drive.is_some())
    }

    /// The ancestors of `body` from its parent up to the root (bodies only, not the world).
    pub fn ancestors(&self, body: BodyId) -> impl Iterator<Item = BodyId> + '_ {
        let mut next = self.joints.get(body.0).and_then(|j| j.parent);
        std::iter::from_fn(move || {
            let b = next?;
            next = self.joints.get(b.0).and_then(|j| j.parent);
            Some(b)
        })
    }
}
