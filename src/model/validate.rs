//! Validation of a model's parts (called by [`super::ModelBuilder::build`]).

use std::collections::HashSet;

use crate::math::{Pose, Vec2};

use super::{Body, Collider, Joint, JointKind, Material, ModelError};

/// Checks bodies, joints, colliders and gravity: unique names, positive finite masses and
/// inertias, finite numbers, parents added before their children, unit prismatic axes,
/// drives and force elements only where they make sense.
pub(super) fn validate(
    bodies: &[Body],
    joints: &[Joint],
    colliders: &[Collider],
    gravity: Vec2,
) -> Result<(), ModelError> {
    finite_vec("gravity", gravity)?;
    unique("body", bodies.iter().map(|b| b.name.as_str()))?;
    unique("joint", joints.iter().map(|j| j.name.as_str()))?;
    unique("collider", colliders.iter().map(|c| c.name.as_str()))?;
    for body in bodies {
        check_body(body)?;
    }
    for (child, joint) in joints.iter().enumerate() {
        check_joint(child, joint)?;
    }
    for collider in colliders {
        if let Some(b) = collider.body
            && b.0 >= bodies.len()
        {
            return Err(ModelError::UnknownBody {
                collider: collider.name.clone(),
                body: b.0,
            });
        }
        finite_pose(
            &format!("collider `{}` pose", collider.name),
            &collider.pose,
        )?;
    }
    Ok(())
}

fn unique<'a>(what: &'static str, names: impl Iterator<Item = &'a str>) -> Result<(), ModelError> {
    let mut seen = HashSet::new();
    for name in names {
        if !seen.insert(name) {
            return Err(ModelError::DuplicateName {
                what,
                name: name.to_owned(),
            });
        }
    }
    Ok(())
}

fn check_body(body: &Body) -> Result<(), ModelError> {
    if !(body.mass.is_finite() && body.mass > 0.0) {
        return Err(ModelError::BadMass {
            body: body.name.clone(),
            mass: body.mass,
        });
    }
    if !(body.inertia.is_finite() && body.inertia > 0.0) {
        return Err(ModelError::BadInertia {
            body: body.name.clone(),
            inertia: body.inertia,
        });
    }
    finite_vec(&format!("body `{}` centre of mass", body.name), body.com)
}

fn check_joint(child: usize, joint: &Joint) -> Result<(), ModelError> {
    if let Some(p) = joint.parent
        && p.0 >= child
    {
        return Err(ModelError::BadParent {
            joint: joint.name.clone(),
            parent: p.0,
            child,
        });
    }
    finite_pose(
        &format!("joint `{}` placement", joint.name),
        &joint.placement,
    )?;
    if let JointKind::Prismatic { axis } = joint.kind
        && !(axis.is_finite() && (axis.length() - 1.0).abs() < 1e-9)
    {
        return Err(ModelError::BadAxis {
            joint: joint.name.clone(),
            x: axis.x,
            y: axis.y,
        });
    }
    if let Some(drive) = &joint.drive {
        if joint.kind.ndof() != 1 {
            return Err(ModelError::DriveOnMultiDof {
                joint: joint.name.clone(),
                kind: joint.kind.name(),
            });
        }
        if !drive.is_finite() {
            return Err(ModelError::NonFinite {
                what: format!("joint `{}` prescribed motion", joint.name),
                value: format!("{drive:?}"),
            });
        }
    }
    check_force(joint)
}

fn check_force(joint: &Joint) -> Result<(), ModelError> {
    let f = &joint.force;
    let values = [f.stiffness, f.rest, f.damping, f.effort];
    if values.iter().any(|x| !x.is_finite()) {
        return Err(ModelError::NonFinite {
            what: format!("joint `{}` force elements", joint.name),
            value: format!("{f:?}"),
        });
    }
    for (what, value) in [("stiffness", f.stiffness), ("damping", f.damping)] {
        if value < 0.0 {
            return Err(ModelError::NegativeCoefficient {
                joint: joint.name.clone(),
                what,
                value,
            });
        }
    }
    if f.is_zero() {
        return Ok(());
    }
    let reason = if joint.kind.ndof() != 1 {
        Some("this joint has more or fewer than one coordinate")
    } else if joint.drive.is_some() {
        Some("this joint is prescribed, its drive supplies whatever force is needed")
    } else {
        None
    };
    match reason {
        Some(reason) => Err(ModelError::ForceNotAllowed {
            joint: joint.name.clone(),
            reason,
        }),
        None => Ok(()),
    }
}

/// Checks `0 ≤ e ≤ 1` and `μ ≥ 0` (both finite).
pub(super) fn check_material(a: &str, b: &str, m: &Material) -> Result<(), ModelError> {
    let bad = |what, value, range| ModelError::BadMaterial {
        a: a.to_owned(),
        b: b.to_owned(),
        what,
        value,
        range,
    };
    if !(m.e.is_finite() && (0.0..=1.0).contains(&m.e)) {
        return Err(bad("e", m.e, "0 ≤ e ≤ 1"));
    }
    if !(m.mu.is_finite() && m.mu >= 0.0) {
        return Err(bad("mu", m.mu, "μ ≥ 0, finite"));
    }
    Ok(())
}

fn finite_vec(what: &str, v: Vec2) -> Result<(), ModelError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(ModelError::NonFinite {
            what: what.to_owned(),
            value: format!("({}, {})", v.x, v.y),
        })
    }
}

fn finite_pose(what: &str, pose: &Pose) -> Result<(), ModelError> {
    if pose.is_finite() {
        Ok(())
    } else {
        Err(ModelError::NonFinite {
            what: what.to_owned(),
            value: format!("{pose:?}"),
        })
    }
}
