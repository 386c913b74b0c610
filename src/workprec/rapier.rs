//! rapier2d-f64 on a ricochet scene (feature `rapier`): the same bodies (pose, mass,
//! centre of mass, inertia), the same parry2d shapes, the same `e` and `μ`, gravity, and
//! the joints as rapier impulse joints or locked axes; and the rapier trajectory read back
//! as ricochet's generalized coordinates, so that its impacts, energies and end state are
//! measured with ricochet's own kinematics.
//!
//! What is matched, and how (`notes/crates.md` §3e):
//!
//! - masses: every collider has density 0 and each body gets the scene's mass, centre of
//!   mass and inertia as additional mass properties;
//! - restitution and friction: set on both colliders of a pair with the `Max` combine
//!   rule, so the pair's coefficient is the scene's whatever rapier's default rule;
//! - `contact_recycling` off (contacts recomputed every step), bodies never sleep;
//! - revolute joints: impulse joints at the joint position (rapier's constraint solver,
//!   maximal coordinates), contacts between the jointed bodies off; a prismatic joint
//!   along a world axis, and a translation joint: locked axes (exact); a planar joint: a
//!   free body. Other joints (prismatic off-axis or on a moving parent, welds, prescribed
//!   motions) are [`WorkprecError::Unsupported`].
//!
//! What cannot be matched: rapier's contacts are soft (a spring-damper regularization
//! solved in substeps) and its restitution is a separate end-of-step pass for new contacts;
//! friction at an impact is not the impulsive Coulomb law of [P] (the tangential impulse
//! comes from the regularized friction of the substeps). The charts show the consequences.

use rapier2d_f64::prelude::{
    CoefficientCombineRule, ColliderBuilder, MassProperties, PhysicsWorld, RevoluteJointBuilder,
    RigidBodyBuilder, RigidBodyHandle,
};

use super::{ImpactRecord, Trace, WorkprecError};
use crate::contact::{FrameWorkspace, Tangent, frame_at, pair_contact};
use crate::dynamics::energy;
use crate::kinematics::{forward_kinematics, update_positions, update_velocities};
use crate::math::{Pose, Real, Vec2};
use crate::model::{JointKind, Model, PairId};
use crate::scene::Scene;
use crate::state::Data;

/// How a body's generalized coordinates are read from its rapier pose and velocity.
#[derive(Clone, Copy, Debug)]
enum Reading {
    /// `q = φ_b − φ_parent − φ_placement` (absolute: `φ_b − φ_placement`).
    Revolute {
        parent: Option<usize>,
        absolute: bool,
    },
    /// `q = (origin − p₀)·a`.
    Prismatic { axis: Vec2 },
    /// `q = R₀ᵀ (origin − p₀)`.
    Translation,
    /// `q = (R₀ᵀ (origin − p₀), φ_b − φ₀)`.
    Planar,
}

/// A rapier world built from a scene.
pub struct RapierWorld<'m> {
    model: &'m Model,
    /// The rapier world (public for inspection and tests).
    pub world: PhysicsWorld,
    /// The rapier body of each ricochet body, in body order.
    pub bodies: Vec<RigidBodyHandle>,
    readings: Vec<Reading>,
    data: Data,
    ws: FrameWorkspace,
    j_n: Vec<Real>,
    j_t: Vec<Real>,
    t: Real,
}

fn unsupported(scene: &Scene, reason: impl Into<String>) -> WorkprecError {
    WorkprecError::Unsupported {
        method: "rapier",
        scene: scene.name.clone(),
        reason: reason.into(),
    }
}

fn query(t: Real, e: impl std::fmt::Display) -> WorkprecError {
    WorkprecError::Query {
        t,
        what: e.to_string(),
    }
}

impl<'m> RapierWorld<'m> {
    /// The rapier world of `scene` at its initial state, stepping by `dt` (s).
    pub fn new(scene: &'m Scene, dt: Real) -> Result<Self, WorkprecError> {
        let model = &scene.model;
        let mut data = Data::new(model);
        let (q0, u0) = (scene.initial.q.as_slice(), scene.initial.u.as_slice());
        forward_kinematics(model, &mut data, 0.0, q0, u0).map_err(|e| query(0.0, e))?;
        let mut world = PhysicsWorld::new();
        world.gravity = model.gravity();
        let p = &mut world.integration_parameters;
        p.dt = dt;
        p.contact_recycling = false;
        // The joints' anchor, and the obstacles on a body of their own: a joint with its
        // contacts off would otherwise disable the contacts with the obstacles too.
        let ground = world.insert_body(RigidBodyBuilder::fixed());
        let obstacles = world.insert_body(RigidBodyBuilder::fixed());

        let mut bodies = Vec::with_capacity(model.nbody());
        let mut readings = Vec::with_capacity(model.nbody());
        for (i, body) in model.bodies().iter().enumerate() {
            let joint = &model.joints()[i];
            if joint.drive.is_some() {
                return Err(unsupported(scene, "a prescribed motion"));
            }
            let pose = data.body_pose[i];
            let twist = data.body_twist[i];
            let com = pose.transform_point(body.com);
            let mut b = RigidBodyBuilder::dynamic()
                .pose(pose)
                .linvel(twist.velocity_at(com))
                .angvel(twist.w)
                .can_sleep(false)
                .additional_mass_properties(MassProperties::new(body.com, body.mass, body.inertia));
            let world_parent = joint.parent.is_none();
            let reading = match joint.kind {
                JointKind::Revolute { absolute } => Reading::Revolute {
                    parent: joint.parent.map(|p| p.index()),
                    absolute,
                },
                JointKind::Prismatic { axis } if world_parent => {
                    let a = joint.placement.rotation * axis;
                    if a.y.abs() <= 1e-15 {
                        b = b.enabled_translations(true, false).lock_rotations();
                    } else if a.x.abs() <= 1e-15 {
                        b = b.enabled_translations(false, true).lock_rotations();
                    } else {
                        return Err(unsupported(scene, "a prismatic joint off the world axes"));
                    }
                    Reading::Prismatic { axis: a }
                }
                JointKind::Translation if world_parent => {
                    b = b.lock_rotations();
                    Reading::Translation
                }
                JointKind::Planar if world_parent => Reading::Planar,
                _ => {
                    return Err(unsupported(
                        scene,
                        format!("a {} joint on a moving parent", joint.kind.name()),
                    ));
                }
            };
            let handle = world.insert_body(b);
            if let JointKind::Revolute { .. } = joint.kind {
                let parent = joint.parent.map_or(ground, |p| bodies[p.index()]);
                let pin = RevoluteJointBuilder::new()
                    .local_anchor1(joint.placement.translation)
                    .local_anchor2(Vec2::ZERO)
                    .contacts_enabled(false);
                world.impulse_joints.insert(parent, handle, pin, true);
            }
            bodies.push(handle);
            readings.push(reading);
        }

        // Each collider's e and μ: those of its pairs (which must agree).
        let mut material: Vec<Option<(Real, Real)>> = vec![None; model.colliders().len()];
        for pair in model.pairs() {
            let m = (pair.material.e, pair.material.mu);
            for c in [pair.a, pair.b] {
                match material[c.index()] {
                    Some(old) if old != m => {
                        return Err(unsupported(scene, "a shape with two materials"));
                    }
                    _ => material[c.index()] = Some(m),
                }
            }
        }
        for (k, c) in model.colliders().iter().enumerate() {
            let (e, mu) = material[k].unwrap_or((0.0, 0.0));
            let builder = ColliderBuilder::new(c.shape.clone())
                .position(c.pose)
                .density(0.0)
                .restitution(e)
                .friction(mu)
                .restitution_combine_rule(CoefficientCombineRule::Max)
                .friction_combine_rule(CoefficientCombineRule::Max);
            let parent = c.body.map_or(obstacles, |b| bodies[b.index()]);
            world.insert_collider(builder, Some(parent));
        }
        Ok(Self {
            model,
            world,
            bodies,
            readings,
            data,
            ws: FrameWorkspace::new(model),
            j_n: vec![0.0; model.nu()],
            j_t: vec![0.0; model.nu()],
            t: 0.0,
        })
    }

    /// One rapier step.
    pub fn step(&mut self) {
        self.world.step();
        self.t += self.world.integration_parameters.dt;
    }

    /// The time (s).
    pub fn t(&self) -> Real {
        self.t
    }

    /// The generalized coordinates and speeds of the rapier state, written into `q`, `u`;
    /// angles are unwrapped to within π of the values already in `q`.
    pub fn read(&self, q: &mut [Real], u: &mut [Real]) {
        let angle = |h: RigidBodyHandle| self.world.bodies[h].position().rotation.angle();
        let mut k = 0;
        for (i, reading) in self.readings.iter().enumerate() {
            let rb = &self.world.bodies[self.bodies[i]];
            let pose: &Pose = rb.position();
            let origin = pose.translation;
            let v = rb.velocity_at_point(origin);
            let w = rb.angvel();
            let placement = self.model.joints()[i].placement;
            let unwrap = |old: Real, new: Real| {
                new + (2.0 * std::f64::consts::PI)
                    * ((old - new) / (2.0 * std::f64::consts::PI)).round()
            };
            match *reading {
                Reading::Revolute { parent, absolute } => {
                    let (phi_p, w_p) = match parent {
                        Some(p) if !absolute => {
                            let h = self.bodies[p];
                            (angle(h), self.world.bodies[h].angvel())
                        }
                        _ => (0.0, 0.0),
                    };
                    let phi = pose.rotation.angle() - phi_p - placement.rotation.angle();
                    q[k] = unwrap(q[k], phi);
                    u[k] = w - if absolute { 0.0 } else { w_p };
                    k += 1;
                }
                Reading::Prismatic { axis } => {
                    q[k] = (origin - placement.translation).dot(axis);
                    u[k] = v.dot(axis);
                    k += 1;
                }
                Reading::Translation | Reading::Planar => {
                    let r = placement.rotation.inverse();
                    let x = r * (origin - placement.translation);
                    let vx = r * v;
                    (q[k], q[k + 1], u[k], u[k + 1]) = (x.x, x.y, vx.x, vx.y);
                    k += 2;
                    if let Reading::Planar = reading {
                        let phi = pose.rotation.angle() - placement.rotation.angle();
                        q[k] = unwrap(q[k], phi);
                        u[k] = w;
                        k += 1;
                    }
                }
            }
        }
    }

    /// Runs to `t_end` (s) and reads the trajectory: a contact pair whose normal velocity
    /// at the contact point approached (`v_n < −v_imp`) within rapier's prediction
    /// distance (0.02 m) plus two steps of travel is armed; the first step after which it
    /// separates (`v_n⁺ > 0`) is an impact at the end of that step (rapier's soft contacts
    /// may take several steps to turn the velocity). `v_n = J_n u`,
    /// `v^S = (J_n u⁺, J_t u⁺)`, with `J` of the end-of-step configuration and the
    /// tangent along the slip before the step [P, Eq. (10)]; the energy after is the
    /// model's at `(q⁺, u⁺)`. `v_imp = 1e-3 √(|g| L)`, `L` the largest shape.
    pub fn trace(&mut self, t_end: Real) -> Result<Trace, WorkprecError> {
        let model = self.model;
        let n = model.nq();
        let (mut q, mut u) = (vec![0.0; n], vec![0.0; n]);
        self.read(&mut q, &mut u);
        let mut trace = Trace {
            energy_initial: energy(model, &mut self.data, 0.0, &q, &u)
                .map_err(|e| query(0.0, e))?
                .total(),
            ..Trace::default()
        };
        let length = (model.colliders().iter())
            .filter(|c| c.body.is_some())
            .map(|c| 2.0 * c.shape.compute_local_bounding_sphere().radius)
            .fold(0.0, Real::max);
        let v_imp = 1e-3 * (model.gravity().length() * length).sqrt();
        let dt = self.world.integration_parameters.dt;
        let steps = (t_end / dt).round() as u64;
        let mut u_before = u.clone();
        let pairs: Vec<PairId> = model.pair_ids().collect();
        let mut armed = vec![false; pairs.len()];
        for _ in 0..steps {
            u_before.copy_from_slice(&u);
            self.step();
            let t = self.t;
            self.read(&mut q, &mut u);
            update_positions(model, &mut self.data, t, &q).map_err(|e| query(t, e))?;
            update_velocities(model, &mut self.data, &u_before).map_err(|e| query(t, e))?;
            for (&pair, armed) in pairs.iter().zip(armed.iter_mut()) {
                let Some(c) = pair_contact(model, &self.data, pair, Real::INFINITY)
                    .map_err(|e| query(t, e))?
                else {
                    continue;
                };
                let frame = frame_at(
                    model,
                    &self.data,
                    pair,
                    c,
                    Tangent::AlongSlip,
                    &mut self.ws,
                    &mut self.j_n,
                    &mut self.j_t,
                )
                .map_err(|e| query(t, e))?;
                let dot =
                    |j: &[Real], v: &[Real]| j.iter().zip(v).map(|(a, b)| a * b).sum::<Real>();
                let v_minus = dot(&self.j_n, &u_before);
                let v_plus = [dot(&self.j_n, &u), dot(&self.j_t, &u)];
                let near = frame.gap <= 0.02 + 2.0 * v_minus.abs() * dt;
                if !near {
                    *armed = false;
                    continue;
                }
                *armed |= v_minus < -v_imp;
                if *armed && v_plus[0] > 0.0 {
                    *armed = false;
                    let e = energy(model, &mut self.data, t, &q, &u).map_err(|e| query(t, e))?;
                    trace.push(ImpactRecord {
                        t,
                        v_s: v_plus,
                        energy_after: e.total(),
                    });
                    // `energy` moved the velocities to u⁺: restore u⁻ for the next pair.
                    update_velocities(model, &mut self.data, &u_before).map_err(|e| query(t, e))?;
                }
            }
        }
        trace.t_end = self.t;
        trace.q = q;
        trace.u = u;
        Ok(trace)
    }
}
