//! `[body.joint]` → [`Joint`], its initial coordinates and speeds.

use std::ops::Range;

use toml::Spanned;

use crate::math::{Pose, Real, Vec2};
use crate::model::{BodyId, Joint, JointForce, JointKind, PrescribedMotion};

use super::SceneError;
use super::build::Builder;
use super::format::{DriveSpec, JointSpec, JointType};
use super::ranges;
use super::units::{Kind, Quantity};

/// A joint read from a file: the joint, its initial coordinates and coordinate rates, and
/// for each of its speeds whether the file gives it.
pub(super) type ReadJoint = (Joint, Vec<Real>, Vec<Real>, Vec<bool>);

impl Builder<'_> {
    /// The joint, its initial coordinates and coordinate rates, and for each of its
    /// speeds whether the file gives it (a speed that a constraint removes and the file
    /// does not give is computed from the others; one it gives must agree).
    pub(super) fn joint(
        &self,
        name: &str,
        s: &JointSpec,
        parent: Option<BodyId>,
    ) -> Result<ReadJoint, SceneError> {
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
            JointType::Planar => {
                let angle = self.quantity_or(&s.angle, Angle, 0.0)?;
                let (vx, vy) = if s.vx_body.is_some() || s.vy_body.is_some() {
                    if let Some(v) = s.vx.as_ref().or(s.vy.as_ref()) {
                        return Err(self.err(
                            v.span(),
                            "give the initial velocity either along the joint's axes (`vx`, \
                             `vy`) or along the body's (`vx_body`, `vy_body`), not both",
                        ));
                    }
                    // (ẋ, ẏ) = R(θ₀) (vx_body, vy_body).
                    let body = Vec2::new(
                        self.quantity_or(&s.vx_body, Plain, 0.0)?,
                        self.quantity_or(&s.vy_body, Plain, 0.0)?,
                    );
                    let v = Vec2::from_angle(angle).rotate(body);
                    (v.x, v.y)
                } else {
                    (
                        self.quantity_or(&s.vx, Plain, 0.0)?,
                        self.quantity_or(&s.vy, Plain, 0.0)?,
                    )
                };
                (
                    JointKind::Planar,
                    vec![
                        self.quantity_or(&s.x, Plain, 0.0)?,
                        self.quantity_or(&s.y, Plain, 0.0)?,
                        angle,
                    ],
                    vec![vx, vy, self.quantity_or(&s.rate, AngularRate, 0.0)?],
                )
            }
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
            effort: self.force_element(if ty == JointType::Revolute {
                &s.torque
            } else {
                &s.force
            })?,
        };
        if let Some(drive) = &s.drive {
            joint.drive = Some(self.drive(drive, q[0], coordinate, rate)?);
            return Ok((joint, vec![], vec![], vec![]));
        }
        let (vx, vy) = (
            s.vx.is_some() || s.vy.is_some(),
            s.vx.is_some() || s.vy.is_some(),
        );
        let given = match ty {
            JointType::Revolute => vec![s.rate.is_some()],
            JointType::Prismatic => vec![s.speed.is_some()],
            JointType::Translation => vec![vx, vy],
            JointType::Planar => vec![
                vx || s.vx_body.is_some(),
                vy || s.vy_body.is_some(),
                s.rate.is_some(),
            ],
            JointType::Fixed => vec![],
        };
        Ok((joint, q, u, given))
    }

    pub(super) fn non_negative(&self, v: &Option<Spanned<Quantity>>) -> Result<Real, SceneError> {
        let x = self.force_element(v)?;
        match v {
            Some(v) if x < 0.0 => Err(self.err(v.span(), format!("must be non-negative, got {x}"))),
            _ => Ok(x),
        }
    }

    /// A force element of a joint (stiffness, damping, torque or force; SI, plain), within
    /// `±1e12` ([`ranges::FORCE_ELEMENT`]); 0 when absent.
    pub(super) fn force_element(&self, v: &Option<Spanned<Quantity>>) -> Result<Real, SceneError> {
        let x =
            self.quantity_within(v, Kind::Plain, ranges::FORCE_ELEMENT, " (a force element)")?;
        Ok(x.unwrap_or(0.0))
    }

    /// `drive = { rate, amplitude, angular_frequency, phase }` with `q₀` the joint's
    /// initial coordinate.
    pub(super) fn drive(
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
    pub(super) fn allowed_joint_fields(
        &self,
        s: &JointSpec,
        ty: JointType,
    ) -> Result<(), SceneError> {
        let span = |v: &Option<Spanned<Quantity>>| v.as_ref().map(|v| v.span());
        let present: [(&str, Option<Range<usize>>); 18] = [
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
            ("vx_body", span(&s.vx_body)),
            ("vy_body", span(&s.vy_body)),
            ("stiffness", span(&s.stiffness)),
            ("rest", span(&s.rest)),
            ("damping", span(&s.damping)),
            ("torque", span(&s.torque)),
            ("force", span(&s.force)),
            ("drive", s.drive.as_ref().map(|v| v.span())),
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
            JointType::Planar => &["x", "y", "angle", "vx", "vy", "vx_body", "vy_body", "rate"],
            JointType::Fixed => &[],
        };
        let tyname = format!("{ty:?}").to_lowercase();
        for (field, span) in present {
            let Some(span) = span else { continue };
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
}
