//! The kinematics of nonholonomic constraints (see [`crate::model::Constraint`]): the
//! constraint rows `C(q, t)`, the map `v = S u + s` from the generalized speeds to the tree
//! speeds, the removed speeds' accelerations, and the kinematic equations `q̇ = A u + b`.
//!
//! With `C_d` the columns of `C` of the removed speeds and `C_i` the others,
//!
//! ```text
//! C v + c = 0   ⇒   v_d = −C_d⁻¹ (C_i u + c)                      [P, Eq. (1)–(2)]
//! C v̇ + γ = 0,  γ = Ċ v + ċ   ⇒   v̇ = S u̇ + v̇₀,  v̇₀ = [0; −C_d⁻¹ γ]
//! ```
//!
//! and each row's `γ_k` is the rate of the blade's cross velocity `n · v^P` of the body
//! point `P` when `v̇ = 0`:
//!
//! ```text
//! γ_k = ṅ · v^P + n · a^P,   ṅ = ω perp(n),   a^P = a₀ + α perp(P) + ω perp(v^P)
//! ```
//!
//! with `(α, a₀)` the body's spatial acceleration when `v̇ = 0` (the Newton–Euler forward
//! pass: velocity products and prescribed accelerations).
//!
//! Every function here is for a model with constraints; a holonomic model never calls
//! them (its speeds are the tree's, `S = I`).

use crate::kinematics::{KinematicsError, for_each_tree_column, tree_velocities};
use crate::math::{Real, perp};
use crate::model::{JointId, Model, SpeedRole};
use crate::state::Data;

/// Calls `f(i, S[index, i])` for each generalized speed `i` that the tree speed `index`
/// depends on: `1` for its own `u_i`, the row of `S` for a removed speed.
#[inline]
pub(crate) fn add_tree_column(
    model: &Model,
    data: &Data,
    index: usize,
    mut f: impl FnMut(usize, Real),
) {
    match model.speed_roles()[index] {
        SpeedRole::Independent(i) => f(i, 1.0),
        SpeedRole::Dependent(_) => {
            for i in 0..model.nu() {
                let w = data.speed_map[(index, i)];
                if w != 0.0 {
                    f(i, w);
                }
            }
        }
    }
}

/// Writes the constraints' world frames, their rows `C`, the factors of `C_d` and the map
/// `S` at the positions of `data`. Called by [`crate::kinematics::update_positions`].
pub(crate) fn update_map(model: &Model, data: &mut Data) -> Result<(), KinematicsError> {
    let m = model.constraints().len();
    // World frames and rows.
    let mut rows = std::mem::take(&mut data.constraint_rows);
    rows.fill(0.0);
    for (k, c) in model.constraints().iter().enumerate() {
        let pose = data.body_pose[c.body.index()];
        let p = pose.transform_point(c.point);
        let n = pose.transform_vector(c.normal());
        data.constraint_frame[k] = (p, n);
        for_each_tree_column(model, data, c.body, p, |i, col| rows[(k, i)] = n.dot(col));
    }
    data.constraint_rows = rows;
    // P C_d = L U, partial pivoting (`constraint_pivots[col]`: the row swapped in).
    let dep = model.dependent_speeds();
    for r in 0..m {
        for (d, &i) in dep.iter().enumerate() {
            data.constraint_lu[(r, d)] = data.constraint_rows[(r, i)];
        }
    }
    let scale = data.constraint_lu.amax();
    for col in 0..m {
        let lu = &mut data.constraint_lu;
        let best = (col..m)
            .max_by(|&a, &b| lu[(a, col)].abs().total_cmp(&lu[(b, col)].abs()))
            .unwrap_or(col);
        lu.swap_rows(col, best);
        data.constraint_pivots[col] = best;
        let pivot = lu[(col, col)];
        if pivot.abs().partial_cmp(&(1e-10 * scale)) != Some(std::cmp::Ordering::Greater) {
            // The constraint whose row came to `col` (replaying the swaps: the cold path).
            let mut order: Vec<usize> = (0..m).collect();
            for (r, &p) in data.constraint_pivots[..=col].iter().enumerate() {
                order.swap(r, p);
            }
            let constraint = &model.constraints()[order[col]];
            return Err(KinematicsError::SingularConstraints {
                constraint: constraint.name.clone(),
                speed: model.tree_speeds()[dep[col]].name.clone(),
                pivot: pivot.abs() / scale,
            });
        }
        for r in col + 1..m {
            let f = lu[(r, col)] / pivot;
            lu[(r, col)] = f;
            for c2 in col + 1..m {
                let x = lu[(col, c2)];
                lu[(r, c2)] -= f * x;
            }
        }
    }
    // S: unit rows for the generalized speeds, −C_d⁻¹ C_i for the removed ones.
    data.speed_map.fill(0.0);
    for (i, &vi) in model.independent_speeds().iter().enumerate() {
        data.speed_map[(vi, i)] = 1.0;
        let mut x = std::mem::take(&mut data.constraint_scratch);
        for r in 0..m {
            x[r] = data.constraint_rows[(r, vi)];
        }
        solve_removed(data, x.as_mut_slice());
        for (d, &vd) in dep.iter().enumerate() {
            data.speed_map[(vd, i)] = -x[d];
        }
        data.constraint_scratch = x;
    }
    Ok(())
}

/// Solves `C_d x = b` in place with the factors of [`update_map`]: the row swaps in
/// their order, then `L y = P b` forward and `U x = y` backward.
fn solve_removed(data: &Data, b: &mut [Real]) {
    let m = b.len();
    let lu = &data.constraint_lu;
    for (r, &p) in data.constraint_pivots.iter().enumerate() {
        b.swap(r, p);
    }
    for r in 0..m {
        for c in 0..r {
            b[r] -= lu[(r, c)] * b[c];
        }
    }
    for r in (0..m).rev() {
        for c in r + 1..m {
            b[r] -= lu[(r, c)] * b[c];
        }
        b[r] /= lu[(r, r)];
    }
}

/// The tree speeds `v = S u + s` at the generalized speeds `u`, and the twists they give:
/// a velocity pass with the removed speeds at zero gives the residuals `C_i u + c` of the
/// blades, `v_d = −C_d⁻¹ (C_i u + c)`, and a second pass the twists. Called by
/// [`crate::kinematics::update_velocities`].
pub(crate) fn tree_speeds(model: &Model, data: &mut Data, u: &[Real]) {
    let mut v = std::mem::take(&mut data.tree_speed);
    for (i, &vi) in model.independent_speeds().iter().enumerate() {
        v[vi] = u[i];
    }
    for &vd in model.dependent_speeds() {
        v[vd] = 0.0;
    }
    tree_velocities(model, data, v.as_slice());
    let mut r = std::mem::take(&mut data.constraint_scratch);
    for (k, c) in model.constraints().iter().enumerate() {
        let (p, n) = data.constraint_frame[k];
        r[k] = n.dot(data.body_twist[c.body.index()].velocity_at(p));
    }
    solve_removed(data, r.as_mut_slice());
    for (d, &vd) in model.dependent_speeds().iter().enumerate() {
        v[vd] = -r[d];
    }
    data.constraint_scratch = r;
    tree_velocities(model, data, v.as_slice());
    data.tree_speed = v;
}

/// The cross velocity `n · v^P` of each blade at the velocities of `data` (m/s): zero up
/// to rounding when the constraints hold. Requires `update_velocities`.
pub fn cross_velocities<'a>(model: &'a Model, data: &'a Data) -> impl Iterator<Item = Real> + 'a {
    model.constraints().iter().enumerate().map(|(k, c)| {
        let (p, n) = data.constraint_frame[k];
        n.dot(data.body_twist[c.body.index()].velocity_at(p))
    })
}

/// Writes `v̇₀` into `data.tree_accel0`: zero but for the removed speeds, `−C_d⁻¹ γ`, with
/// `γ` from the body accelerations of a Newton–Euler forward pass at `v̇ = 0` (in
/// `data.body_accel`).
pub(crate) fn removed_accelerations(model: &Model, data: &mut Data) {
    let mut g = std::mem::take(&mut data.constraint_scratch);
    for (k, c) in model.constraints().iter().enumerate() {
        let b = c.body.index();
        let (p, n) = data.constraint_frame[k];
        let twist = data.body_twist[b];
        let accel = data.body_accel[b];
        let vp = twist.velocity_at(p);
        let ap = accel.v + perp(p) * accel.w + perp(vp) * twist.w;
        g[k] = (perp(n) * twist.w).dot(vp) + n.dot(ap);
    }
    solve_removed(data, g.as_mut_slice());
    data.tree_accel0.fill(0.0);
    for (d, &vd) in model.dependent_speeds().iter().enumerate() {
        data.tree_accel0[vd] = -g[d];
    }
    data.constraint_scratch = g;
}

/// The coordinate rates `q̇ = T(q) v` at the tree speeds of the last
/// `update_velocities`: the joint rates, with the body-frame speeds of a planar joint
/// turned into the joint frame, `(ẋ, ẏ) = R(θ) (vx, vy)`.
pub fn coordinate_rates(model: &Model, data: &Data, qdot: &mut [Real]) {
    let v = &data.tree_speed;
    qdot.copy_from_slice(v.as_slice());
    for (j, _) in model.joints().iter().enumerate() {
        if model.has_body_frame_speeds(JointId(j))
            && let Some(s) = model.q_index(JointId(j))
        {
            let (sin, cos) = data.joint_q[j][2].sin_cos();
            qdot[s] = cos * v[s] - sin * v[s + 1];
            qdot[s + 1] = sin * v[s] + cos * v[s + 1];
        }
    }
}

/// The tree speeds `v = T(q)⁻¹ q̇` of the coordinate rates `q̇` at the positions of
/// `data` (the body-frame speeds of a planar joint turned into its body's axes). They
/// respect the constraints only if `q̇` does.
pub fn tree_speeds_from_rates(model: &Model, data: &Data, qdot: &[Real]) -> Vec<Real> {
    let mut v: Vec<Real> = qdot.to_vec();
    for (j, _) in model.joints().iter().enumerate() {
        if model.has_body_frame_speeds(JointId(j))
            && let Some(s) = model.q_index(JointId(j))
        {
            let (sin, cos) = data.joint_q[j][2].sin_cos();
            v[s] = cos * qdot[s] + sin * qdot[s + 1];
            v[s + 1] = -sin * qdot[s] + cos * qdot[s + 1];
        }
    }
    v
}
