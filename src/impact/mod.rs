//! The one-point planar impact laws with Coulomb friction of [P], as pure functions of
//! `(W, v^A, e, μ)`. Nothing here knows about bodies.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// The hypothesis that ends the collision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Law {
    /// Newton's kinematic restitution `v_n^S = −e v_n^A` on Routh's path, with the
    /// bisection of the collision time [P, Sect. 3–4, Table 1].
    Newton,
    /// Newton's restitution without the bisection of the collision time: one phase, the
    /// coherent one of three candidates [P, Appendix C].
    KaneLevinson,
    /// Poisson's kinetic restitution: the collision ends at `(1 + e)` times the
    /// compression impulse, on Routh's path.
    Poisson,
    /// Stronge's energetic restitution: the restitution work of the normal impulse is
    /// `e²` times minus its compression work, on Routh's path.
    Stronge,
}

impl Law {
    /// Every law, in the order shown to users.
    pub const ALL: [Law; 4] = [Law::Newton, Law::KaneLevinson, Law::Poisson, Law::Stronge];

    /// The name used on the command line, in scene files and in logs.
    pub fn name(self) -> &'static str {
        match self {
            Law::Newton => "newton",
            Law::KaneLevinson => "kane-levinson",
            Law::Poisson => "poisson",
            Law::Stronge => "stronge",
        }
    }
}

impl fmt::Display for Law {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A law name that is not known.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown impact law `{0}` (expected one of: newton, kane-levinson, poisson, stronge)")]
pub struct UnknownLaw(pub String);

impl FromStr for Law {
    type Err = UnknownLaw;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Law::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| UnknownLaw(s.to_owned()))
    }
}
