//! Models and random numbers shared by the model, kinematics and dynamics tests
//! (`use crate::common::model_fixtures as fixtures;`).
#![allow(dead_code)]

use ricochet::math::{Pose, Real, Vec2};
use ricochet::model::{Body, BodyId, Joint, JointForce, JointKind, Model, PrescribedMotion};

/// A small deterministic generator (xorshift64*), so that failures reproduce.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: Real, hi: Real) -> Real {
        let x = (self.next_u64() >> 11) as Real / (1u64 << 53) as Real;
        lo + (hi - lo) * x
    }

    /// Uniform in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }

    pub fn vec2(&mut self, r: Real) -> Vec2 {
        Vec2::new(self.uniform(-r, r), self.uniform(-r, r))
    }

    pub fn vector(&mut self, n: usize, r: Real) -> Vec<Real> {
        (0..n).map(|_| self.uniform(-r, r)).collect()
    }
}

/// Kane and Levinson's double pendulum [P, Sect. 5]: two uniform rods of mass `m` and
/// length `l`, angles measured from the downward vertical and from the world (absolute),
/// pivot at the origin.
pub fn double_pendulum(m: Real, l: Real, g: Real) -> Model {
    let mut b = Model::builder();
    b.gravity(Vec2::new(0.0, -g));
    let rod = |name: &str| Body::new(name, m, Vec2::new(0.0, -l / 2.0), m * l * l / 12.0);
    let a = b.add_body(rod("rodA"), Joint::revolute("rodA", None, Pose::identity()));
    b.add_body(
        rod("rodB"),
        Joint::revolute_absolute("rodB", Some(a), Pose::translation(0.0, -l)),
    );
    b.build().expect("double pendulum")
}

/// A chain of `n` uniform links of mass `m` and length `l` with relative angles, hanging
/// from the origin, with gravity `g`.
pub fn chain(n: usize, m: Real, l: Real, g: Real) -> Model {
    let mut b = Model::builder();
    b.gravity(Vec2::new(0.0, -g));
    let mut parent = None;
    for i in 0..n {
        let name = format!("link{}", i + 1);
        let placement = if i == 0 {
            Pose::identity()
        } else {
            Pose::translation(0.0, -l)
        };
        let id = b.add_body(
            Body::new(&name, m, Vec2::new(0.0, -l / 2.0), m * l * l / 12.0),
            Joint::revolute(&name, parent, placement),
        );
        parent = Some(id);
    }
    b.build().expect("chain")
}

/// What a random tree may contain.
#[derive(Clone, Copy, Debug)]
pub struct TreeOptions {
    /// Gravity magnitude (m/s²), in a random direction.
    pub gravity: Real,
    /// Put springs on free one-coordinate joints.
    pub springs: bool,
    /// Put dampers and constant efforts on free one-coordinate joints.
    pub dissipation: bool,
    /// Prescribe some one-coordinate joints.
    pub prescribed: bool,
}

impl TreeOptions {
    pub const CONSERVATIVE: TreeOptions = TreeOptions {
        gravity: 9.81,
        springs: true,
        dissipation: false,
        prescribed: false,
    };
    pub const EVERYTHING: TreeOptions = TreeOptions {
        gravity: 9.81,
        springs: true,
        dissipation: true,
        prescribed: true,
    };
}

/// A random tree of 1 to 6 bodies with every joint kind (relative and absolute revolute,
/// prismatic, translation, planar, fixed), random placements and inertias, and the force
/// elements and drives that `opts` allows. Applies the rigid motion `world` to everything
/// fixed in the world (joint placements on the world, absolute angle references, gravity),
/// so that the same seed with another `world` gives the same mechanism moved rigidly.
pub fn random_tree(seed: u64, opts: TreeOptions, world: Pose) -> Model {
    let mut rng = Rng::new(seed);
    let mut b = Model::builder();
    let angle = rng.uniform(-3.0, 3.0);
    let g = Vec2::new(angle.sin(), -angle.cos()) * opts.gravity;
    b.gravity(world.transform_vector(g));
    let n = 1 + rng.below(6);
    let mut ids: Vec<BodyId> = Vec::new();
    let mut nfree = 0;
    for i in 0..n {
        let parent = match rng.below(i + 1) {
            0 => None,
            k => Some(ids[k - 1]),
        };
        let kind = match rng.below(6) {
            0 => JointKind::Revolute { absolute: false },
            1 => JointKind::Revolute { absolute: true },
            2 => JointKind::Prismatic {
                axis: Vec2::from_angle(rng.uniform(-3.0, 3.0)),
            },
            3 => JointKind::Translation,
            4 => JointKind::Planar,
            _ => JointKind::Fixed,
        };
        let mut placement = Pose::new(rng.vec2(1.0), rng.uniform(-3.0, 3.0));
        if parent.is_none() {
            placement = world * placement;
        } else if kind == (JointKind::Revolute { absolute: true }) {
            placement.rotation = world.rotation * placement.rotation;
        }
        let name = format!("b{i}");
        let mut joint = Joint::new(&name, kind, parent, placement);
        if kind.ndof() == 1 {
            if opts.prescribed && rng.below(3) == 0 {
                joint.drive = Some(PrescribedMotion {
                    q0: rng.uniform(-1.0, 1.0),
                    rate: rng.uniform(-2.0, 2.0),
                    amplitude: rng.uniform(0.0, 0.5),
                    angular_frequency: rng.uniform(0.5, 4.0),
                    phase: rng.uniform(-3.0, 3.0),
                });
            } else {
                joint.force = JointForce {
                    stiffness: if opts.springs {
                        rng.uniform(0.0, 20.0)
                    } else {
                        0.0
                    },
                    rest: rng.uniform(-1.0, 1.0),
                    damping: if opts.dissipation {
                        rng.uniform(0.0, 2.0)
                    } else {
                        0.0
                    },
                    effort: if opts.dissipation {
                        rng.uniform(-2.0, 2.0)
                    } else {
                        0.0
                    },
                };
            }
        }
        if joint.drive.is_none() {
            nfree += kind.ndof();
        }
        let body = Body::new(
            &name,
            rng.uniform(0.5, 2.0),
            rng.vec2(0.6),
            rng.uniform(0.05, 0.5),
        );
        ids.push(b.add_body(body, joint));
    }
    // Make sure there is something to integrate.
    if nfree == 0 {
        let name = format!("b{n}");
        b.add_body(
            Body::new(&name, 1.0, Vec2::new(0.1, -0.3), 0.2),
            Joint::planar(&name, Some(ids[0]), Pose::translation(0.2, 0.1)),
        );
    }
    b.build().expect("random tree")
}
