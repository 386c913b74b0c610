//! Forward kinematics of the tree: body poses at `(t, q)`, body twists at `(t, q, u)`, and
//! the position, velocity and Jacobian of any body point, so that a point's velocity is
//!
//! ```text
//! v^P = J_P(t, q) u + v_t^P(t, q)          [P, Eq. (2)]
//! ```
//!
//! with `J_P` the 2×nu matrix of its partial velocities `v_r^P` and `v_t^P` its remainder
//! velocity (non-zero only below a prescribed joint).
//!
//! ## Propagation
//!
//! Twists are in world coordinates referred to the world origin `O`
//! ([`crate::model::spatial`]). With `S` a joint's motion subspace columns and `P` the
//! identity, or the projection [`Twist::projected_at`] at the joint's position `a` for an
//! absolute revolute joint, the twist and spatial acceleration of body `b` are
//!
//! ```text
//! V_b = P_b V_parent + Σ_k S_k q̇_k
//! A_b = P_b A_parent + c_b + Σ_k S_k q̈_k,     c_b = Ṗ_b V_parent + Σ_k Ṡ_k q̇_k
//! ```
//!
//! where, with `ȧ = V_parent(a)` the velocity of the joint's position:
//!
//! | joint | `S` | `Ṡ` |
//! |---|---|---|
//! | revolute at `a` | `(1, −perp(a))` | `(0, −perp(ȧ))` |
//! | prismatic, axis `d` | `(0, d)` | `V_parent ×ₘ S = (0, ω_parent perp(d))` |
//! | translation, axes `e₁, e₂` | `(0, e₁)`, `(0, e₂)` | `(0, ω_parent perp(eᵢ))` |
//! | planar, body origin `o` | `(0, e₁)`, `(0, e₂)`, `(1, −perp(o))` | as above, `(0, −perp(ȯ))` |
//!
//! and `Ṗ_b V_parent = (0, ω_parent perp(ȧ))` for an absolute joint.
//!
//! ## Absolute angles
//!
//! An absolute revolute joint (the paper's double pendulum, [P, Sect. 5]) is handled
//! natively: its body is carried by the parent's motion through `P(a)` — translated with
//! the velocity of `a`, not turned. The same projection appears wherever the tree is
//! walked: in Jacobians (the point at which ancestors' partial velocities are evaluated
//! moves to `a`), and in [`crate::dynamics`] (the subtree presents itself to its ancestors
//! as a point mass at `a`). This is equivalent to the constant change of coordinates
//! `q_rel = T q` to relative angles, without forming `T`.

use nalgebra::Matrix2xX;

use crate::math::{Pose, Real, Vec2, perp};
use crate::model::spatial::{Inertia, Twist};
use crate::model::{Body, BodyId, ColliderId, Joint, JointId, JointKind, Model};
use crate::state::Data;

/// A kinematics query that cannot be answered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KinematicsError {
    /// A vector of the wrong length.
    #[error("{what} has length {got}, expected {expected}")]
    DimensionMismatch {
        /// Which vector (`"q"`, `"u"`, `"tau"`, `"jacobian columns"`, …).
        what: &'static str,
        /// The expected length.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A body id that is not in the model.
    #[error("body #{body} is not in the model ({nbody} bodies)")]
    UnknownBody {
        /// The index given.
        body: usize,
        /// The number of bodies.
        nbody: usize,
    },
    /// A collider id that is not in the model.
    #[error("collider #{collider} is not in the model")]
    UnknownCollider {
        /// The index given.
        collider: usize,
    },
    /// The speeds removed by the nonholonomic constraints cannot be solved for at this
    /// configuration (`C_d` singular): a blade lines up with a speed it removes.
    #[error(
        "the speed `{speed}` removed by constraint `{constraint}` cannot be solved for at this configuration (the constraints' matrix is singular, pivot {pivot:e}): choose another speed with `removes`"
    )]
    SingularConstraints {
        /// The constraint whose pivot vanished.
        constraint: String,
        /// The speed it removes.
        speed: String,
        /// The pivot, relative to the largest coefficient.
        pivot: Real,
    },
}

/// The velocity of a body point, split as in [P, Eq. (2)].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointVelocity {
    /// The velocity `v^P = J_P u + v_t^P` (m/s, world frame).
    pub total: Vec2,
    /// The remainder velocity `v_t^P`, due to prescribed motions alone (m/s, world frame).
    pub remainder: Vec2,
}

#[doc(hidden)]
pub fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), KinematicsError> {
    if expected == got {
        Ok(())
    } else {
        Err(KinematicsError::DimensionMismatch {
            what,
            expected,
            got,
        })
    }
}

fn check_body(model: &Model, body: BodyId) -> Result<usize, KinematicsError> {
    if body.index() < model.nbody() {
        Ok(body.index())
    } else {
        Err(KinematicsError::UnknownBody {
            body: body.index(),
            nbody: model.nbody(),
        })
    }
}

/// Computes the joint coordinates (prescribed ones at time `t`), joint frames, motion
/// subspaces, body poses, centres of mass and spatial inertias at `(t, q)`.
///
/// `X_b = X_parent · placement · motion(q)` (see [`JointKind`]); for an absolute revolute
/// joint the joint frame is `(X_parent · a_placement, R_placement)`.
///
/// Writes `data.time`, `joint_q`, `joint_qdd_prescribed`, `joint_frame`, `subspace`,
/// `body_pose`, `body_com`, `body_inertia`.
pub fn update_positions(
    model: &Model,
    data: &mut Data,
    t: Real,
    q: &[Real],
) -> Result<(), KinematicsError> {
    check_len("q", model.nq(), q.len())?;
    data.time = t;
    let joints = model.joints();
    let n = joints.len();
    // Every per-joint array sliced to the number of joints once, so that the loop indexes
    // them without bounds checks.
    let bodies = &model.bodies()[..n];
    let joint_q = &mut data.joint_q[..n];
    let joint_qdd = &mut data.joint_qdd_prescribed[..n];
    let joint_frame = &mut data.joint_frame[..n];
    let subspace = &mut data.subspace[..n];
    let body_pose = &mut data.body_pose[..n];
    let body_com = &mut data.body_com[..n];
    let body_inertia = &mut data.body_inertia[..n];
    for (i, (joint, body)) in joints.iter().zip(bodies).enumerate() {
        let parent = joint
            .parent
            .map_or(Pose::IDENTITY, |p| body_pose[p.index()]);
        let place = place_joint(model, (i, joint, joint.kind), body, t, q, &parent);
        joint_q[i] = place.q;
        joint_qdd[i] = place.qdd;
        joint_frame[i] = place.frame;
        subspace[i] = place.subspace;
        body_pose[i] = place.pose;
        body_com[i] = place.com;
        body_inertia[i] = place.inertia;
    }
    if !model.is_holonomic() {
        crate::constraints::update_map(model, data)?;
    }
    Ok(())
}

/// What [`update_positions`] computes for one joint and its body.
#[derive(Clone, Copy)]
#[doc(hidden)]
pub struct JointPlacement {
    /// The joint coordinates (the drive's at `t` for a prescribed joint).
    pub q: [Real; 3],
    /// The prescribed accelerations (zero for a free joint).
    pub qdd: [Real; 3],
    /// The joint frame in the world.
    pub frame: Pose,
    /// The motion subspace columns (world, referred to `O`).
    pub subspace: [Twist; 3],
    /// The body pose.
    pub pose: Pose,
    /// The centre of mass (m, world).
    pub com: Vec2,
    /// The spatial inertia (world, referred to `O`).
    pub inertia: Inertia,
}

/// The positions of joint `i` (`joint`, of kind `kind` = `joint.kind`, carrying `body`) at
/// `(t, q)` below its parent's pose `parent` (the identity for a root): one step of
/// [`update_positions`], shared with the fused pass of
/// [`crate::dynamics::forward_dynamics_with`] so that both compute the same numbers. The
/// kind is passed by value so that a caller that knows it gets the code of that kind alone.
#[inline(always)]
#[doc(hidden)]
pub fn place_joint(
    model: &Model,
    (i, joint, kind): (usize, &Joint, JointKind),
    body: &Body,
    t: Real,
    q: &[Real],
    parent: &Pose,
) -> JointPlacement {
    // Joint coordinates: from the drive, from q, or none.
    let mut jq = [0.0; 3];
    let mut jqdd = [0.0; 3];
    match (&joint.drive, model.q_index(JointId(i))) {
        (Some(drive), _) => {
            jq[0] = drive.position(t);
            jqdd[0] = drive.acceleration(t);
        }
        (None, Some(s)) => copy_dofs(&mut jq, q, s, kind.ndof()),
        (None, None) => {}
    }
    // Joint frame in the world.
    let frame = if kind.is_absolute() {
        Pose::from_parts(
            parent.transform_point(joint.placement.translation),
            joint.placement.rotation,
        )
    } else {
        *parent * joint.placement
    };
    // Body pose and motion subspace.
    let (pose, mut s) = joint_motion(&kind, &frame, &jq);
    if model.has_body_frame_speeds(JointId(i)) {
        // Body-frame speeds: translations along the body's own axes.
        s[0] = Twist::translation_along(pose.transform_vector(Vec2::X));
        s[1] = Twist::translation_along(pose.transform_vector(Vec2::Y));
    }
    let com = pose.transform_point(body.com);
    JointPlacement {
        q: jq,
        qdd: jqdd,
        frame,
        subspace: s,
        pose,
        com,
        inertia: Inertia::from_body(body.mass, com, body.inertia),
    }
}

/// `dst[..nd] = src[s..s + nd]` for the `nd ≤ 3` coordinates (or rates) of one joint,
/// entry by entry: `copy_from_slice` of a length unknown at compile time calls `memcpy`,
/// dearer than the three moves.
#[inline]
fn copy_dofs(dst: &mut [Real; 3], src: &[Real], s: usize, nd: usize) {
    match src[s..s + nd] {
        [a] => dst[0] = a,
        [a, b] => [dst[0], dst[1]] = [a, b],
        [a, b, c] => *dst = [a, b, c],
        _ => {}
    }
}

/// The body pose `frame · motion(q)` and the motion subspace columns (world, referred to
/// `O`) of a joint with world frame `frame` at joint coordinates `q`.
#[inline(always)]
fn joint_motion(kind: &JointKind, frame: &Pose, q: &[Real; 3]) -> (Pose, [Twist; 3]) {
    let e1 = || frame.transform_vector(Vec2::X);
    let e2 = || frame.transform_vector(Vec2::Y);
    match *kind {
        JointKind::Revolute { .. } => (
            *frame * Pose::rotation(q[0]),
            [
                Twist::rotation_about(frame.translation),
                Twist::ZERO,
                Twist::ZERO,
            ],
        ),
        JointKind::Prismatic { axis } => (
            *frame * Pose::from_translation(axis * q[0]),
            [
                Twist::translation_along(frame.transform_vector(axis)),
                Twist::ZERO,
                Twist::ZERO,
            ],
        ),
        JointKind::Translation => (
            *frame * Pose::translation(q[0], q[1]),
            [
                Twist::translation_along(e1()),
                Twist::translation_along(e2()),
                Twist::ZERO,
            ],
        ),
        JointKind::Planar => {
            let pose = *frame * Pose::new(Vec2::new(q[0], q[1]), q[2]);
            (
                pose,
                [
                    Twist::translation_along(e1()),
                    Twist::translation_along(e2()),
                    Twist::rotation_about(pose.translation),
                ],
            )
        }
        JointKind::Fixed => (*frame, [Twist::ZERO; 3]),
    }
}

/// Computes the joint rates (prescribed ones at `data.time`), the body twists, their
/// remainder parts and the velocity-product accelerations `c_b` at `u` (see the
/// [module documentation](self) for the recursion).
///
/// Requires [`update_positions`] at the same state. Writes `data.joint_qd`, `body_twist`,
/// `body_twist_remainder`, `body_accel_vp`.
pub fn update_velocities(
    model: &Model,
    data: &mut Data,
    u: &[Real],
) -> Result<(), KinematicsError> {
    check_len("u", model.nu(), u.len())?;
    if model.is_holonomic() {
        tree_velocities(model, data, u);
    } else {
        crate::constraints::tree_speeds(model, data, u);
    }
    Ok(())
}

/// The velocity pass of [`update_velocities`] at the tree speeds `v` `[nv]`.
pub(crate) fn tree_velocities(model: &Model, data: &mut Data, v_tree: &[Real]) {
    let u = v_tree;
    let t = data.time;
    let joints = model.joints();
    let n = joints.len();
    // Sliced to the number of joints once: no bounds checks in the loop.
    let joint_frame = &data.joint_frame[..n];
    let subspace = &data.subspace[..n];
    let body_pose = &data.body_pose[..n];
    let joint_qd = &mut data.joint_qd[..n];
    let body_twist = &mut data.body_twist[..n];
    let body_twist_remainder = &mut data.body_twist_remainder[..n];
    let body_accel_vp = &mut data.body_accel_vp[..n];
    for (i, joint) in joints.iter().enumerate() {
        // What the parent carries.
        let (vp, vp_rem) = match joint.parent {
            Some(p) => (body_twist[p.index()], body_twist_remainder[p.index()]),
            None => (Twist::ZERO, Twist::ZERO),
        };
        let m = move_joint(
            model,
            (i, joint, joint.kind),
            t,
            u,
            (vp, vp_rem),
            (
                joint_frame[i].translation,
                &subspace[i],
                body_pose[i].translation,
            ),
        );
        joint_qd[i] = m.qd;
        body_twist[i] = m.twist;
        body_twist_remainder[i] = m.remainder;
        body_accel_vp[i] = m.accel_vp;
    }
}

/// What [`update_velocities`] computes for one joint and its body.
#[derive(Clone, Copy)]
#[doc(hidden)]
pub struct JointMotion {
    /// The joint rates (the drive's at `t` for a prescribed joint).
    pub qd: [Real; 3],
    /// The body twist `V_b`.
    pub twist: Twist,
    /// Its remainder part, due to the prescribed motions alone.
    pub remainder: Twist,
    /// The velocity-product acceleration `c_b`.
    pub accel_vp: Twist,
}

/// The velocities of joint `i` (`joint`, of kind `kind` = `joint.kind`) at the speeds `u`
/// and time `t`: the body twist
/// from the parent's twist and remainder `(vp, vp_rem)` (zero for a root), with `a` the
/// joint frame's origin, `s` the motion subspace and `o` the body origin (see the
/// [module documentation](self) for the recursion). One step of [`tree_velocities`],
/// shared with the fused pass of [`crate::dynamics::forward_dynamics_with`].
#[inline(always)]
#[doc(hidden)]
pub fn move_joint(
    model: &Model,
    (i, joint, kind): (usize, &Joint, JointKind),
    t: Real,
    u: &[Real],
    (vp, vp_rem): (Twist, Twist),
    (a, s, o): (Vec2, &[Twist; 3], Vec2),
) -> JointMotion {
    // Joint rates.
    let nd = kind.ndof();
    let mut qd = [0.0; 3];
    let prescribed = joint.drive.is_some();
    match (&joint.drive, model.q_index(JointId(i))) {
        (Some(drive), _) => qd[0] = drive.velocity(t),
        (None, Some(s)) => copy_dofs(&mut qd, u, s, nd),
        (None, None) => {}
    }
    // What the parent carries: all of its twist, or only the velocity of `a`.
    let a_dot = vp.velocity_at(a);
    let (mut v, mut v_rem, mut c) = if kind.is_absolute() {
        // Ṗ V_parent = (0, ω_parent perp(ȧ)).
        (
            vp.projected_at(a),
            vp_rem.projected_at(a),
            Twist::new(0.0, perp(a_dot) * vp.w),
        )
    } else {
        (vp, vp_rem, Twist::ZERO)
    };
    // Joint motion: V += S q̇ (and the remainder, for a prescribed joint).
    for (s_k, qd_k) in s.iter().zip(&qd).take(nd) {
        v += *s_k * *qd_k;
    }
    if prescribed {
        for (s_k, qd_k) in s.iter().zip(&qd).take(nd) {
            v_rem += *s_k * *qd_k;
        }
    }
    // c += Ṡ q̇.
    match kind {
        JointKind::Revolute { .. } => c += Twist::new(0.0, -perp(a_dot)) * qd[0],
        JointKind::Prismatic { .. } | JointKind::Translation => {
            for (s_k, qd_k) in s.iter().zip(&qd).take(nd) {
                c += vp.cross_motion(s_k) * *qd_k;
            }
        }
        JointKind::Planar => {
            // Joint-frame axes turn with the parent, body-frame axes with the body.
            let turns = if model.has_body_frame_speeds(JointId(i)) {
                v
            } else {
                vp
            };
            c += turns.cross_motion(&s[0]) * qd[0];
            c += turns.cross_motion(&s[1]) * qd[1];
            c += Twist::new(0.0, -perp(v.velocity_at(o))) * qd[2];
        }
        JointKind::Fixed => {}
    }
    JointMotion {
        qd,
        twist: v,
        remainder: v_rem,
        accel_vp: c,
    }
}

/// The spatial acceleration of each body at `u̇ = 0`, into `out` `[nbody]` (rad/s², m/s²):
/// the velocity-product part with the prescribed coordinates' accelerations, the forward
/// pass of the recursive Newton–Euler algorithm [F, §5.3] with the free `q̈` set to zero,
///
/// ```text
/// A_b = P_b A_parent + c_b + Σ_k S_k q̈_p,k
/// ```
///
/// (`P_b` the projection of an absolute revolute joint, the identity otherwise). For a
/// holonomic model it is `d/dt (J u)` at fixed `u`, what a closed contact point adds to
/// `J u̇` ([`point_acceleration`]). Requires [`update_velocities`].
pub fn velocity_product_accelerations(model: &Model, data: &Data, out: &mut [Twist]) {
    for (i, joint) in model.joints().iter().enumerate() {
        let mut a = match joint.parent {
            Some(p) => out[p.index()],
            None => Twist::ZERO,
        };
        if joint.is_absolute() {
            a = a.projected_at(data.joint_frame[i].translation);
        }
        a += data.body_accel_vp[i];
        let (s, qdd) = (&data.subspace[i], &data.joint_qdd_prescribed[i]);
        for (s_k, qdd_k) in s.iter().zip(qdd).take(joint.kind.ndof()) {
            a += *s_k * *qdd_k;
        }
        out[i] = a;
    }
}

/// The acceleration (m/s², world frame) of the material point of `body` at the world
/// position `p`, from its spatial acceleration `accel` (e.g. of
/// [`velocity_product_accelerations`]): the classical acceleration of a point carried by
/// the body [F, ch. 2],
///
/// ```text
/// a_p = A.v + A.ω perp(p) + ω perp(v_p),   v_p = v_O + ω perp(p)
/// ```
///
/// Requires [`update_velocities`].
pub fn point_acceleration(data: &Data, body: BodyId, p: Vec2, accel: Twist) -> Vec2 {
    let v = data.body_twist[body.index()];
    accel.velocity_at(p) + perp(v.velocity_at(p)) * v.w
}

/// [`update_positions`] then [`update_velocities`].
pub fn forward_kinematics(
    model: &Model,
    data: &mut Data,
    t: Real,
    q: &[Real],
    u: &[Real],
) -> Result<(), KinematicsError> {
    update_positions(model, data, t, q)?;
    update_velocities(model, data, u)
}

/// The world position (m) of the point `p` given in the frame of `body`: `X_b p`.
/// Requires [`update_positions`].
pub fn point_world(
    model: &Model,
    data: &Data,
    body: BodyId,
    p: Vec2,
) -> Result<Vec2, KinematicsError> {
    let b = check_body(model, body)?;
    Ok(data.body_pose[b].transform_point(p))
}

/// The world pose of a collider's shape: `X_b · pose` on a body, `pose` in the world.
/// Requires [`update_positions`].
pub fn collider_pose(
    model: &Model,
    data: &Data,
    collider: ColliderId,
) -> Result<Pose, KinematicsError> {
    let c = model
        .collider(collider)
        .ok_or(KinematicsError::UnknownCollider {
            collider: collider.index(),
        })?;
    Ok(match c.body {
        Some(b) => data.body_pose[check_body(model, b)?] * c.pose,
        None => c.pose,
    })
}

/// The velocity of the point of `body` that is at the world position `p`, and its
/// remainder part [P, Eq. (2)]: `v = V_b(p) = v_O + ω perp(p)`, `v_t = V_b^rem(p)`.
/// Requires [`update_velocities`].
pub fn point_velocity(
    model: &Model,
    data: &Data,
    body: BodyId,
    p: Vec2,
) -> Result<PointVelocity, KinematicsError> {
    let b = check_body(model, body)?;
    Ok(PointVelocity {
        total: data.body_twist[b].velocity_at(p),
        remainder: data.body_twist_remainder[b].velocity_at(p),
    })
}

/// The translational Jacobian `J_P` (2×nu) of the point of `body` at the world position `p`:
/// column `r` is the partial velocity `v_r^P` [P, Eq. (2)], so that `v^P = J_P u + v_t^P`.
///
/// Walking from `body` to the root, each free coordinate `k` of a joint on the path gives
/// the column `S_k(r) = S_k.v + S_k.ω perp(r)`, where `r` starts at `p` and moves to the
/// joint position `a` whenever an absolute revolute joint is crossed (the ancestors only
/// translate what lies behind it). The other columns are zero.
///
/// Requires [`update_positions`]. `jac` must have `nu` columns. For a point given in the
/// body's frame, get its world position with [`point_world`] first.
pub fn point_jacobian(
    model: &Model,
    data: &Data,
    body: BodyId,
    p: Vec2,
    jac: &mut Matrix2xX<Real>,
) -> Result<(), KinematicsError> {
    check_len("jacobian columns", model.nu(), jac.ncols())?;
    check_body(model, body)?;
    // On the column-major storage: `jac[(k, i)]` is `js[2 i + k]`.
    let js = jac.as_mut_slice();
    js.fill(0.0);
    for_each_tree_column(model, data, body, p, |index, col| {
        if model.is_holonomic() {
            // Always there: `index < nu`, the columns checked above.
            if let Some([x, y]) = js.get_mut(2 * index..2 * index + 2) {
                [*x, *y] = [col.x, col.y];
            }
        } else {
            crate::constraints::add_tree_column(model, data, index, |i, w| {
                js[2 * i] += w * col.x;
                js[2 * i + 1] += w * col.y;
            });
        }
    });
    Ok(())
}

/// Calls `f(index, column)` for each tree speed that moves the world point `p` of `body`,
/// from the body to the root: its partial velocity `v_r^P` over the tree speeds,
/// `S_k(r) = S_k.v + S_k.ω perp(r)`, with `r` moving to the joint position `a` whenever an
/// absolute revolute joint is crossed. `body` must be in the model.
pub(crate) fn for_each_tree_column(
    model: &Model,
    data: &Data,
    body: BodyId,
    p: Vec2,
    mut f: impl FnMut(usize, Vec2),
) {
    let mut b = body.index();
    let mut r = p;
    loop {
        let joint = &model.joints()[b];
        if let Some(s) = model.q_index(JointId(b)) {
            for k in 0..joint.kind.ndof() {
                f(s + k, data.subspace[b][k].velocity_at(r));
            }
        }
        if joint.is_absolute() {
            r = data.joint_frame[b].translation;
        }
        match joint.parent {
            Some(parent) => b = parent.index(),
            None => return,
        }
    }
}

/// The angular Jacobian (1×nu) of `body`: `ω_b = Σ_r row[r] u_r + ω_t`. Each free
/// rotational coordinate on the path to the root contributes 1, up to and including the
/// first absolute revolute joint (above it the ancestors no longer turn the body).
///
/// Requires [`update_positions`]. `row` must have `nu` entries.
pub fn angular_jacobian(
    model: &Model,
    data: &Data,
    body: BodyId,
    row: &mut [Real],
) -> Result<(), KinematicsError> {
    check_len("angular jacobian", model.nu(), row.len())?;
    let mut b = check_body(model, body)?;
    row.fill(0.0);
    loop {
        let joint = &model.joints()[b];
        if let Some(s) = model.q_index(JointId(b)) {
            for k in 0..joint.kind.ndof() {
                let w = data.subspace[b][k].w;
                if model.is_holonomic() {
                    row[s + k] = w;
                } else {
                    crate::constraints::add_tree_column(model, data, s + k, |i, x| {
                        row[i] += x * w;
                    });
                }
            }
        }
        if joint.is_absolute() {
            return Ok(());
        }
        match joint.parent {
            Some(parent) => b = parent.index(),
            None => return Ok(()),
        }
    }
}
