//! The serde image of a scene file, version 1 (see `scenes/README.md`). Every table
//! rejects unknown fields; values that are checked after parsing keep their span so that
//! errors point at them.

use serde::Deserialize;
use toml::Spanned;

use crate::impact::Law;
use crate::integrate::Method;
use crate::math::Real;
use crate::settings::Simultaneous;

use super::units::Quantity;

/// A 2-D vector written `[x, y]`.
pub(super) type Pair = Two<Real>;

/// Exactly two values written `[a, b]`: more or fewer are an error (serde's arrays read
/// the first two of a longer list and drop the rest silently).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Two<T>(pub [T; 2]);

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Two<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Exactly<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for Exactly<T> {
            type Value = Two<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a list of exactly two values")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Two<T>, A::Error> {
                use serde::de::Error;
                let short = |n| A::Error::invalid_length(n, &"a list of exactly two values");
                let a = seq.next_element()?.ok_or_else(|| short(0))?;
                let b = seq.next_element()?.ok_or_else(|| short(1))?;
                let mut more = 0;
                while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    more += 1;
                }
                if more > 0 {
                    return Err(short(2 + more));
                }
                Ok(Two([a, b]))
            }
        }
        d.deserialize_seq(Exactly(std::marker::PhantomData))
    }
}

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub version: Spanned<i64>,
    pub name: Spanned<String>,
    #[serde(default)]
    pub description: Option<String>,
    #[serde(default)]
    pub gravity: Option<Spanned<Pair>>,
    pub run: RunSpec,
    #[serde(default)]
    pub contact: Option<Spanned<ContactSpec>>,
    #[serde(default)]
    pub chain: Option<Spanned<ChainSpec>>,
    #[serde(default)]
    pub body: Vec<Spanned<BodySpec>>,
    #[serde(default)]
    pub obstacle: Vec<Spanned<ObstacleSpec>>,
}

/// `[run]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RunSpec {
    pub t_end: Spanned<Real>,
    #[serde(default)]
    pub output_rate: Option<Spanned<Real>>,
    #[serde(default)]
    pub max_drift: Option<Spanned<Real>>,
    #[serde(default)]
    pub integrator: Option<IntegratorSpec>,
}

/// `[run.integrator]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct IntegratorSpec {
    #[serde(default)]
    pub method: Option<Method>,
    #[serde(default)]
    pub rtol: Option<Spanned<Real>>,
    #[serde(default)]
    pub atol: Option<Spanned<Real>>,
    #[serde(default)]
    pub dt: Option<Spanned<Real>>,
    #[serde(default)]
    pub h_max: Option<Spanned<Real>>,
}

/// `[contact]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ContactSpec {
    #[serde(default)]
    pub law: Option<Law>,
    pub e: Spanned<Real>,
    pub mu: Spanned<Real>,
    #[serde(default)]
    pub overlap_tolerance: Option<Spanned<Real>>,
    /// The rule for simultaneous impacts.
    #[serde(default)]
    pub simultaneous: Option<Simultaneous>,
    #[serde(default)]
    pub pair: Vec<PairSpec>,
}

/// `[[contact.pair]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PairSpec {
    pub between: Spanned<Two<Spanned<String>>>,
    #[serde(default)]
    pub law: Option<Law>,
    #[serde(default)]
    pub e: Option<Spanned<Real>>,
    #[serde(default)]
    pub mu: Option<Spanned<Real>>,
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// `[chain]`: a generated pendulum chain.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ChainSpec {
    pub links: Spanned<i64>,
    #[serde(default)]
    pub name: Option<Spanned<String>>,
    pub length: Spanned<Real>,
    pub mass: Spanned<Real>,
    pub radius: Spanned<Real>,
    #[serde(default)]
    pub at: Option<Spanned<Pair>>,
    #[serde(default)]
    pub angle: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub rate: Option<Spanned<Quantity>>,
}

/// `[[body]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BodySpec {
    pub name: Spanned<String>,
    pub mass: Spanned<Real>,
    #[serde(default)]
    pub com: Option<Spanned<Pair>>,
    pub inertia: Spanned<Real>,
    pub joint: Spanned<JointSpec>,
    #[serde(default)]
    pub shape: Vec<Spanned<ShapeSpec>>,
    #[serde(default)]
    pub constraint: Vec<Spanned<ConstraintSpec>>,
}

/// The nonholonomic constraint types.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(super) enum ConstraintType {
    KnifeEdge,
    Wheel,
}

/// `[[body.constraint]]`: a knife edge or a wheel that does not slip sideways.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ConstraintSpec {
    #[serde(rename = "type")]
    pub kind: Spanned<ConstraintType>,
    #[serde(default)]
    pub name: Option<Spanned<String>>,
    #[serde(default)]
    pub at: Option<Spanned<Pair>>,
    #[serde(default)]
    pub direction: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub removes: Option<Spanned<String>>,
}

/// The joint types.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum JointType {
    Revolute,
    Prismatic,
    Translation,
    Planar,
    Fixed,
}

/// `[body.joint]`: one flat table; which fields a type accepts is checked after parsing.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct JointSpec {
    #[serde(rename = "type")]
    pub kind: Spanned<JointType>,
    #[serde(default)]
    pub parent: Option<Spanned<String>>,
    #[serde(default)]
    pub at: Option<Spanned<Pair>>,
    #[serde(default)]
    pub orientation: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub absolute: Option<Spanned<bool>>,
    #[serde(default)]
    pub axis: Option<Spanned<Pair>>,
    #[serde(default)]
    pub angle: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub rate: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub position: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub speed: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub x: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub y: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub vx: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub vy: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub vx_body: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub vy_body: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub stiffness: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub rest: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub damping: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub torque: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub force: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub drive: Option<Spanned<DriveSpec>>,
}

/// `drive = { … }`: a prescribed motion `q(t) = q₀ + rate·t + amplitude·sin(Ω t + phase)`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DriveSpec {
    #[serde(default)]
    pub rate: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub amplitude: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub angular_frequency: Option<Spanned<Quantity>>,
    #[serde(default)]
    pub phase: Option<Spanned<Quantity>>,
}

/// Shapes on bodies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum ShapeType {
    Ball,
    Capsule,
    Segment,
    Cuboid,
    Polygon,
}

/// `[[body.shape]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ShapeSpec {
    #[serde(rename = "type")]
    pub kind: Spanned<ShapeType>,
    #[serde(default)]
    pub name: Option<Spanned<String>>,
    #[serde(default)]
    pub radius: Option<Spanned<Real>>,
    #[serde(default)]
    pub a: Option<Spanned<Pair>>,
    #[serde(default)]
    pub b: Option<Spanned<Pair>>,
    #[serde(default)]
    pub half_extents: Option<Spanned<Pair>>,
    #[serde(default)]
    pub points: Option<Spanned<Vec<Pair>>>,
    #[serde(default)]
    pub at: Option<Spanned<Pair>>,
    #[serde(default)]
    pub angle: Option<Spanned<Quantity>>,
}

/// Static shapes of the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum ObstacleType {
    Halfspace,
    Segment,
    Polyline,
    Cuboid,
}

/// `[[obstacle]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ObstacleSpec {
    pub name: Spanned<String>,
    #[serde(rename = "type")]
    pub kind: Spanned<ObstacleType>,
    #[serde(default)]
    pub point: Option<Spanned<Pair>>,
    #[serde(default)]
    pub normal: Option<Spanned<Pair>>,
    #[serde(default)]
    pub a: Option<Spanned<Pair>>,
    #[serde(default)]
    pub b: Option<Spanned<Pair>>,
    #[serde(default)]
    pub points: Option<Spanned<Vec<Pair>>>,
    #[serde(default)]
    pub half_extents: Option<Spanned<Pair>>,
    #[serde(default)]
    pub at: Option<Spanned<Pair>>,
    #[serde(default)]
    pub angle: Option<Spanned<Quantity>>,
}
