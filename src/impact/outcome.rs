//! What an impact law returns: the type of the collision, the impulses, the velocity of
//! separation, the phases, and the energy change with its split.

use serde::{Deserialize, Serialize};

use super::Law;
use super::coefficients::{Coefficients, SignCase};
use super::path::Phases;
use super::problem::{ContactVelocity, Impulse};
use crate::math::Real;

/// The type of a collision [P, Sect. 3], named after the slip mode it ends in; also the
/// slip mode of one phase of a collision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CollisionType {
    /// Type 1: the contact ends stuck, `v_t^S = 0`.
    Sticking,
    /// Type 2: the slip reversed, `v_t^S < 0`.
    ReverseSliding,
    /// Type 3: the contact slides forward to the end, `v_t^S ≥ 0`.
    ForwardSliding,
}

impl CollisionType {
    /// The name used in JSON and logs: `sticking`, `reverse_sliding`, `forward_sliding`.
    pub fn name(self) -> &'static str {
        match self {
            CollisionType::Sticking => "sticking",
            CollisionType::ReverseSliding => "reverse_sliding",
            CollisionType::ForwardSliding => "forward_sliding",
        }
    }

    /// The type number of [P, Table 2]: 1 sticking, 2 reverse sliding, 3 forward sliding.
    pub fn number(self) -> u8 {
        match self {
            CollisionType::Sticking => 1,
            CollisionType::ReverseSliding => 2,
            CollisionType::ForwardSliding => 3,
        }
    }
}

impl std::fmt::Display for CollisionType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The solution of one impact problem, in the caller's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// The law that produced it.
    pub law: Law,
    /// The type of the collision.
    pub kind: CollisionType,
    /// The sign case of (g, h, p, q) [P, Table 1].
    pub case: SignCase,
    /// g, h, p, q, r_m, r_p, Δ, α in the paper's frame (`v_t^A ≥ 0`).
    pub coefficients: Coefficients,
    /// The impulses `(I_n, I_t)` (N·s), in the caller's frame.
    pub impulse: Impulse,
    /// The velocity of separation `v^S` (m/s), in the caller's frame.
    pub v_s: ContactVelocity,
    /// The phases of the collision, in the caller's frame: for the laws on Routh's path
    /// (forward sliding, then sticking or reverse sliding); a single straight phase for
    /// Kane–Levinson.
    pub phases: Phases,
    /// The change of mechanical energy `ΔE` (J) [P, Eq. (29)].
    pub delta_e: Real,
    /// The work of the normal impulse along the phases, `∫ v_n dI_n` (J).
    pub work_n: Real,
    /// The work of the tangential impulse along the phases, `∫ v_t dI_t` (J).
    pub work_t: Real,
    /// Whether `t` was mirrored to make `v_t^A ≥ 0` (the caller gave `v_t^A < 0`).
    pub mirrored: bool,
}

/// The change of mechanical energy at an impact when Eq. (28) holds.
///
/// Implements [P, Eq. (29)]:
/// `ΔE = ½ I_n (v_n^S + v_n^A) + ½ I_t (v_t^S + v_t^A)`.
#[inline(always)]
pub fn energy_change(i: Impulse, v_a: ContactVelocity, v_s: ContactVelocity) -> Real {
    0.5 * i.n * (v_s.n + v_a.n) + 0.5 * i.t * (v_s.t + v_a.t)
}
