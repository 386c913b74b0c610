//! The `[chain]` generator: a pendulum chain of N uniform links.

use parry2d_f64::shape::SharedShape;
use toml::Spanned;

use crate::math::{Pose, Vec2};
use crate::model::{Body, Collider, Joint};

use super::SceneError;
use super::build::{Builder, Named};
use super::format::ChainSpec;
use super::ranges;
use super::units::Kind;

impl Builder<'_> {
    /// `[chain]`: `links` uniform links hanging from `at`, relative angles, capsules.
    pub(super) fn chain(
        &mut self,
        spec: &Spanned<ChainSpec>,
        links: Option<usize>,
    ) -> Result<(), SceneError> {
        let c = spec.get_ref();
        let n = match links {
            Some(n) => n as i64,
            None => *c.links.get_ref(),
        };
        if !(1..=10_000).contains(&n) {
            return Err(self.err(
                c.links.span(),
                format!("a chain has 1 to 10000 links, got {n}"),
            ));
        }
        let length = self.within(&c.length, "the link length", "m", ranges::SIZE)?;
        let mass = self.within(&c.mass, "the link mass", "kg", ranges::MASS)?;
        let radius = self.within(&c.radius, "the link radius", "m", ranges::SIZE)?;
        let at = self.pair_or(&c.at, Vec2::ZERO)?;
        let angle = self.quantity_or(&c.angle, Kind::Angle, 0.0)?;
        let rate = self.quantity_or(&c.rate, Kind::AngularRate, 0.0)?;
        let prefix = c.name.as_ref().map_or("link", |s| s.get_ref().as_str());
        if let Some(name) = &c.name
            && let Some(why) = ranges::bad_name(&format!("{prefix}{}", c.links.get_ref()))
        {
            return Err(self.err(name.span(), why));
        }
        let mut parent = None;
        for i in 1..=n {
            let name = format!("{prefix}{i}");
            // A uniform rod along −y of the body frame: c = (0, −L/2), I_c = m L²/12.
            let body = Body::new(
                &name,
                mass,
                Vec2::new(0.0, -0.5 * length),
                mass * length * length / 12.0,
            );
            let placement = if i == 1 {
                Pose::from_translation(at)
            } else {
                Pose::translation(0.0, -length)
            };
            let id = self
                .model
                .add_body(body, Joint::revolute(&name, parent, placement));
            self.body_spans
                .push(c.at.as_ref().map_or(spec.span(), |a| a.span()));
            self.name(&Spanned::new(spec.span(), name.clone()), Named::Body(id))?;
            let shape = SharedShape::capsule(Vec2::ZERO, Vec2::new(0.0, -length), radius);
            self.add_collider(
                Collider::new(&name, Some(id), shape, Pose::IDENTITY),
                spec.span(),
            );
            self.q0.push(if i == 1 { angle } else { 0.0 });
            self.u0.push(if i == 1 { rate } else { 0.0 });
            self.u_given.push(i == 1);
            parent = Some(id);
        }
        Ok(())
    }
}
