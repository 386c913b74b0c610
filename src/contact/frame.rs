//! The contact frame of a pair at an impact and the Jacobians of its relative velocity
//! [P, Sect. 2].

use nalgebra::Matrix2xX;

use super::gap::{ContactError, PairContact, pair_contact};
use crate::kinematics::{point_jacobian, point_velocity};
use crate::math::{Real, Vec2, perp};
use crate::model::{ColliderId, ContactPair, Model, PairId};
use crate::state::Data;

/// The contact frame of a pair: where the shapes touch, the normal `n` and tangent `t`,
/// and the relative velocity there.
///
/// The pair's collider `a` (always on a body) carries the point `P` and `b` (another body
/// or an obstacle) the point `P'` of [P, Eq. (3)]: `v^R = v^P − v^{P'} = v_a − v_b`. `n`
/// points from `b` towards `a` (for an obstacle, its outward normal, as the floor's `n` in
/// [P, Fig. 3]), so that approach means `v^R·n < 0` [P, Eq. (9)]; `t = ±perp(n)` is chosen
/// so that `v^R·t ≥ 0` [P, Eq. (10)] (`t = perp(n)` when the tangential velocity is zero).
/// The impulse `I_n n + I_t t` acts on `a`, its opposite on `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactFrame {
    /// The pair.
    pub pair: PairId,
    /// Signed gap `g` (m).
    pub gap: Real,
    /// Witness point on `a` (m, world frame).
    pub point_a: Vec2,
    /// Witness point on `b` (m, world frame).
    pub point_b: Vec2,
    /// Unit normal `n`, from `b` towards `a` (world frame).
    pub n: Vec2,
    /// Unit tangent `t` (world frame).
    pub t: Vec2,
    /// Relative velocity `v^R = v_a(P) − v_b(P')` (m/s, world frame) [P, Eq. (3)].
    pub v_r: Vec2,
    /// Its remainder part, due to prescribed motions alone (m/s, world frame)
    /// [P, Eq. (5)].
    pub v_rem: Vec2,
}

impl ContactFrame {
    /// The contact point (m, world frame): the middle of the two witness points.
    pub fn point(&self) -> Vec2 {
        0.5 * (self.point_a + self.point_b)
    }

    /// `v^R·n` (m/s): negative while the points approach.
    pub fn v_n(&self) -> Real {
        self.v_r.dot(self.n)
    }

    /// `v^R·t ≥ 0` (m/s).
    pub fn v_t(&self) -> Real {
        self.v_r.dot(self.t)
    }
}

/// Scratch for [`contact_frame`]: the point Jacobians of both sides (2×nu each).
#[derive(Clone, Debug)]
pub struct FrameWorkspace {
    jac_a: Matrix2xX<Real>,
    jac_b: Matrix2xX<Real>,
}

impl FrameWorkspace {
    /// Scratch for a model with `nu` generalized speeds.
    pub fn new(model: &Model) -> Self {
        Self {
            jac_a: Matrix2xX::zeros(model.nu()),
            jac_b: Matrix2xX::zeros(model.nu()),
        }
    }
}

/// How the tangent of a frame is oriented.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tangent {
    /// Along the slip: `v^R·t ≥ 0` [P, Eq. (10)] (impacts).
    AlongSlip,
    /// `t = perp(n)` whatever the slip (persistent contact, where the slip is a sign).
    Perp,
}

/// The contact frame of `pair` at its closest points, and the rows `J_n`, `J_t` of the
/// Jacobian of the relative velocity (see [`frame_at`]), with the tangent along the slip.
/// `Ok(None)` if the shapes are farther apart than `prediction` (m). Requires
/// [`crate::kinematics::update_velocities`].
pub fn contact_frame(
    model: &Model,
    data: &Data,
    pair: PairId,
    prediction: Real,
    ws: &mut FrameWorkspace,
    j_n: &mut [Real],
    j_t: &mut [Real],
) -> Result<Option<ContactFrame>, ContactError> {
    match pair_contact(model, data, pair, prediction)? {
        None => Ok(None),
        Some(c) => frame_at(model, data, pair, c, Tangent::AlongSlip, ws, j_n, j_t).map(Some),
    }
}

/// The contact frame of `pair` at the contact point `contact` and the rows `J_n`, `J_t`
/// (nu each) of the Jacobian of the relative velocity: `v^R·n = J_n u + v_rem·n`,
/// `v^R·t = J_t u + v_rem·t`, i.e.
///
/// ```text
/// J = J_a(P) − J_b(P'),   J_n = nᵀ J,   J_t = tᵀ J
/// ```
///
/// whose entries are the paper's `v_r^R·n`, `v_r^R·t` [P, Eqs. (5), (11)]. Requires
/// [`crate::kinematics::update_velocities`].
#[allow(clippy::too_many_arguments)]
pub fn frame_at(
    model: &Model,
    data: &Data,
    pair: PairId,
    contact: PairContact,
    tangent: Tangent,
    ws: &mut FrameWorkspace,
    j_n: &mut [Real],
    j_t: &mut [Real],
) -> Result<ContactFrame, ContactError> {
    let p = model
        .pair(pair)
        .ok_or(ContactError::UnknownPair { pair: pair.index() })?;
    frame_of(model, data, (pair, &p), contact, tangent, ws, (j_n, j_t))
}

/// [`frame_at`] of a pair already resolved (`p = model.pair(pair)`): the same frame and
/// rows, without looking the pair up (persistent contact evaluates the same closed points
/// at every right-hand side).
pub fn frame_of(
    model: &Model,
    data: &Data,
    (pair, p): (PairId, &ContactPair),
    contact: PairContact,
    tangent: Tangent,
    ws: &mut FrameWorkspace,
    (j_n, j_t): (&mut [Real], &mut [Real]),
) -> Result<ContactFrame, ContactError> {
    let PairContact {
        gap,
        point_a,
        point_b,
        normal,
    } = contact;
    // The Jacobian and velocity of each witness point (zero on the world).
    let (va, rem_a) = side(model, data, p.a, point_a, &mut ws.jac_a)?;
    let on_world = model.colliders()[p.b.index()].body.is_none();
    let (v_r, v_rem) = if on_world {
        // `x − 0 = x` to the bit (−0 − 0 = −0 too): the rows of `a` alone are the same
        // numbers as the differences with the world's zero rows.
        (va, rem_a)
    } else {
        let (vb, rem_b) = side(model, data, p.b, point_b, &mut ws.jac_b)?;
        (va - vb, rem_a - rem_b)
    };
    let n = -normal;
    let t = if tangent == Tangent::Perp || v_r.dot(perp(n)) >= 0.0 {
        perp(n)
    } else {
        -perp(n)
    };
    // The 2 × nu Jacobians column by column (column-major storage: column r is
    // entries 2r, 2r + 1).
    let nu = model.nu();
    let (ja, jb) = (
        &ws.jac_a.as_slice()[..2 * nu],
        &ws.jac_b.as_slice()[..2 * nu],
    );
    let rows = j_n[..nu].iter_mut().zip(&mut j_t[..nu]);
    for (r, (jn, jt)) in rows.enumerate() {
        let (a0, a1) = (ja[2 * r], ja[2 * r + 1]);
        let col = if on_world {
            Vec2::new(a0, a1)
        } else {
            Vec2::new(a0 - jb[2 * r], a1 - jb[2 * r + 1])
        };
        *jn = n.dot(col);
        *jt = t.dot(col);
    }
    Ok(ContactFrame {
        pair,
        gap,
        point_a,
        point_b,
        n,
        t,
        v_r,
        v_rem,
    })
}

/// The relative velocity `v^R` of the witness points of `contact` (the `v_r` of
/// [`frame_at`]'s frame, the same numbers) without the Jacobian rows: for the velocity
/// products of persistent contact, which difference velocities only. Requires
/// [`crate::kinematics::update_velocities`].
pub fn relative_velocity(
    model: &Model,
    data: &Data,
    pair: PairId,
    contact: &PairContact,
) -> Result<Vec2, ContactError> {
    let p = model
        .pair(pair)
        .ok_or(ContactError::UnknownPair { pair: pair.index() })?;
    relative_velocity_of(model, data, &p, contact)
}

/// [`relative_velocity`] of a pair already resolved (`model.pair(pair)`).
pub fn relative_velocity_of(
    model: &Model,
    data: &Data,
    p: &ContactPair,
    contact: &PairContact,
) -> Result<Vec2, ContactError> {
    let v = |collider: ColliderId, at: Vec2| match model.colliders()[collider.index()].body {
        Some(body) => point_velocity(model, data, body, at).map(|v| v.total),
        None => Ok(Vec2::ZERO),
    };
    Ok(v(p.a, contact.point_a)? - v(p.b, contact.point_b)?)
}

/// The velocity, remainder velocity and Jacobian of the point `p` of a collider's body;
/// zeros for an obstacle of the world.
fn side(
    model: &Model,
    data: &Data,
    collider: ColliderId,
    p: Vec2,
    jac: &mut Matrix2xX<Real>,
) -> Result<(Vec2, Vec2), ContactError> {
    match model.colliders()[collider.index()].body {
        Some(body) => {
            point_jacobian(model, data, body, p, jac)?;
            let v = point_velocity(model, data, body, p)?;
            Ok((v.total, v.remainder))
        }
        None => {
            jac.fill(0.0);
            Ok((Vec2::ZERO, Vec2::ZERO))
        }
    }
}
