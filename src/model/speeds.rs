//! The choice of the generalized speeds of a model with nonholonomic constraints (see
//! [`super::Constraint`]'s module): which tree speeds are in the body's frame, and which
//! one each constraint removes.

use crate::math::{Real, Vec2, perp};

use super::constraint::MIN_COEFFICIENT;
use super::{
    Body, Constraint, Coordinate, Joint, JointId, JointKind, ModelError, Speed, SpeedRole,
};

/// The speeds of a model.
pub(super) struct Speeds {
    pub tree: Vec<Speed>,
    pub independent_speeds: Vec<Speed>,
    pub roles: Vec<SpeedRole>,
    pub independent: Vec<usize>,
    pub dependent: Vec<usize>,
    pub body_frame: Vec<bool>,
}

/// The constant coefficients of a blade (unit normal `n`, point `p`, body frame) on the
/// speeds of its own body's joint: `n · v^P` per unit speed. They do not depend on the
/// configuration: every joint moves its body along or about axes fixed in the body (a
/// revolute joint turns it about its origin; prismatic and translation joints do not turn
/// it; a planar joint with body-frame speeds moves it along its own axes).
fn own_coefficients(kind: &JointKind, n: Vec2, p: Vec2) -> ([Real; 3], usize) {
    match *kind {
        JointKind::Revolute { .. } => ([n.dot(perp(p)), 0.0, 0.0], 1),
        JointKind::Prismatic { axis } => ([n.dot(axis), 0.0, 0.0], 1),
        JointKind::Translation => ([n.x, n.y, 0.0], 2),
        JointKind::Planar => ([n.x, n.y, n.dot(perp(p))], 3),
        JointKind::Fixed => ([0.0; 3], 0),
    }
}

fn bad(c: &Constraint, bodies: &[Body], reason: impl Into<String>) -> ModelError {
    ModelError::BadConstraint {
        constraint: c.name.clone(),
        body: bodies
            .get(c.body.0)
            .map_or(String::new(), |b| b.name.clone()),
        reason: reason.into(),
    }
}

/// Checks the constraints, normalizes their directions and chooses the speeds.
pub(super) fn choose_speeds(
    bodies: &[Body],
    joints: &[Joint],
    constraints: &mut [Constraint],
    coordinates: &[Coordinate],
    joint_q: &[Option<usize>],
) -> Result<Speeds, ModelError> {
    // Checks: body, direction, point, names.
    let mut seen = std::collections::HashSet::new();
    for c in constraints.iter_mut() {
        if c.body.0 >= bodies.len() {
            let reason = format!("body #{} does not exist", c.body.0);
            return Err(bad(c, bodies, reason));
        }
        if !seen.insert(c.name.clone()) {
            return Err(ModelError::DuplicateName {
                what: "constraint",
                name: c.name.clone(),
            });
        }
        if !(c.point.is_finite()) {
            return Err(bad(c, bodies, "its point is not finite"));
        }
        match c.direction.try_normalize() {
            Some(d) => c.direction = d,
            None => {
                return Err(bad(
                    c,
                    bodies,
                    "its direction must be a finite non-zero vector",
                ));
            }
        }
    }
    let body_frame: Vec<bool> = (0..joints.len())
        .map(|j| {
            matches!(joints[j].kind, JointKind::Planar)
                && joint_q[j].is_some()
                && constraints.iter().any(|c| c.body.0 == j)
        })
        .collect();
    let mut tree: Vec<Speed> = coordinates
        .iter()
        .map(|c| {
            let name = if body_frame[c.joint.0] {
                let suffix = ["vx_body", "vy_body", "omega"][c.dof];
                format!("{}.{}", joints[c.joint.0].name, suffix)
            } else {
                c.name.clone()
            };
            Speed {
                name,
                joint: c.joint,
                dof: c.dof,
                is_angle: c.is_angle,
                removed_by: None,
            }
        })
        .collect();
    // Each constraint removes a speed; per joint, the reduced constant rows of the
    // constraints that removed one of its speeds (pivot column, row).
    let mut reduced: Vec<Vec<(usize, [Real; 3])>> = vec![Vec::new(); joints.len()];
    let mut dependent = Vec::with_capacity(constraints.len());
    for (k, c) in constraints.iter().enumerate() {
        let j = c.body.0;
        let (mut row, nd) = own_coefficients(&joints[j].kind, c.normal(), c.point);
        let own = joint_q[j];
        let nd = if own.is_some() { nd } else { 0 };
        for (pivot, prev) in &reduced[j] {
            let f = row[*pivot] / prev[*pivot];
            for (r, p) in row.iter_mut().zip(prev) {
                *r -= f * p;
            }
        }
        let index = match &c.removes {
            Some(name) => {
                let Some(i) = tree.iter().position(|s| &s.name == name) else {
                    return Err(bad(
                        c,
                        bodies,
                        format!("`removes`: no speed is named `{name}`"),
                    ));
                };
                let sj = tree[i].joint;
                let on_path = sj.0 == j || ancestors(joints, JointId(j)).any(|a| a == sj);
                if !on_path {
                    let reason = format!(
                        "`removes`: `{name}` is not a speed of `{}` or of one of its ancestors",
                        bodies[j].name
                    );
                    return Err(bad(c, bodies, reason));
                }
                if sj.0 == j && row[tree[i].dof].abs() < MIN_COEFFICIENT {
                    let reason = format!("`removes`: the blade does not involve `{name}`");
                    return Err(bad(c, bodies, reason));
                }
                i
            }
            None => {
                let taken = |d: usize| reduced[j].iter().any(|(p, _)| *p == d);
                let rotational = |d: usize| joints[j].kind.is_angle(d);
                let best = |want_angle: bool| {
                    (0..nd)
                        .filter(|&d| !taken(d) && rotational(d) == want_angle)
                        .filter(|&d| row[d].abs() >= MIN_COEFFICIENT)
                        .max_by(|&a, &b| row[a].abs().total_cmp(&row[b].abs()))
                };
                let Some(d) = best(false).or_else(|| best(true)) else {
                    let reason = if nd == 0 {
                        format!(
                            "the joint of `{}` has no speed to remove (fixed or driven): name \
                             the speed it removes with `removes`",
                            bodies[j].name
                        )
                    } else {
                        format!(
                            "the blade involves no speed of `{}`'s joint that the constraints \
                             before it leave (it repeats one, or it lies on the joint's axis): \
                             name the speed it removes with `removes`",
                            bodies[j].name
                        )
                    };
                    return Err(bad(c, bodies, reason));
                };
                own.map_or(0, |s| s) + d
            }
        };
        if let Some(other) = tree[index].removed_by {
            let by = if c.removes.is_some() {
                "`removes`: "
            } else {
                ""
            };
            let reason = format!(
                "{by}`{}` is already removed by `{}`",
                tree[index].name, constraints[other].name
            );
            return Err(bad(c, bodies, reason));
        }
        tree[index].removed_by = Some(k);
        if tree[index].joint.0 == j {
            reduced[j].push((tree[index].dof, row));
        }
        dependent.push(index);
    }
    let mut roles = Vec::with_capacity(tree.len());
    let mut independent = Vec::new();
    for (i, s) in tree.iter().enumerate() {
        roles.push(match s.removed_by {
            Some(k) => SpeedRole::Dependent(k),
            None => {
                independent.push(i);
                SpeedRole::Independent(independent.len() - 1)
            }
        });
    }
    let independent_speeds = independent.iter().map(|&i| tree[i].clone()).collect();
    Ok(Speeds {
        tree,
        independent_speeds,
        roles,
        independent,
        dependent,
        body_frame,
    })
}

/// The ancestors' joints of joint `j`, from its parent up.
fn ancestors(joints: &[Joint], j: JointId) -> impl Iterator<Item = JointId> + '_ {
    let mut next = joints[j.0].parent;
    std::iter::from_fn(move || {
        let b = next?;
        next = joints[b.0].parent;
        Some(JointId(b.0))
    })
}
