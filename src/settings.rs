//! Run settings: end time, output rate and integrator settings. A scene file supplies
//! them; the command line may override them.

use serde::{Deserialize, Serialize};

use crate::integrate::Method;
use crate::math::Real;

/// Settings of one simulation run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// End time of the run (s).
    pub t_end: Real,
    /// Rate of `/state` samples in the log (Hz).
    pub output_rate: Real,
    /// How the equations of motion are integrated.
    pub integrator: IntegratorSettings,
    /// The energy-drift budget: the largest integration drift of the energy audit that a
    /// run may show, relative to the run's energy scale (dimensionless; see
    /// `regress::DriftCheck`). `None`: no budget. A run that breaks it still runs to its
    /// end and writes its log, and `ricochet run` exits with 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_drift: Option<Real>,
    /// How several coupled contact points that strike at one instant are resolved (scene
    /// `[contact] simultaneous`, `--simultaneous`). Left out of the log's settings record
    /// when it is the default.
    #[serde(default, skip_serializing_if = "Simultaneous::is_default")]
    pub simultaneous: Simultaneous,
}

/// The rule for a simultaneous impact: several coupled contact points that approach at
/// one instant, or an impact that makes another touching point of the same group approach
/// (a cascade). A point alone in its group always gets the scene's one-point law \[P\].
///
/// The two rules differ on the classic cases: in Newton's cradle (a row of touching equal
/// balls, struck at one end, `e = 1`) the sequential rule passes the momentum down the row
/// and only the last ball leaves; the generalized Newton law moves every ball of the row.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Simultaneous {
    /// Moreau's generalized Newton law with Coulomb friction over the group's touching
    /// points at once: `v_n⁺ + e v_n⁻ ≥ 0 ⊥ P_n ≥ 0`, `|P_t| ≤ μ P_n` (a complementarity
    /// problem). A single approaching point is struck first with the one-point law; the
    /// cascade it starts is resolved by this law.
    #[default]
    GeneralizedNewton,
    /// One point at a time: the scene's one-point law \[P\] on the most approaching point of
    /// the group, then again on whichever point approaches after it, until none does.
    Sequential,
}

impl Simultaneous {
    /// Every rule, in the order shown to users.
    pub const ALL: [Simultaneous; 2] = [Simultaneous::GeneralizedNewton, Simultaneous::Sequential];

    /// The name in scene files, on the command line and in logs.
    pub fn name(self) -> &'static str {
        match self {
            Simultaneous::GeneralizedNewton => "generalized-newton",
            Simultaneous::Sequential => "sequential",
        }
    }

    /// `true` for the default rule (the generalized Newton law).
    pub fn is_default(&self) -> bool {
        *self == Simultaneous::GeneralizedNewton
    }
}

/// Integrator settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IntegratorSettings {
    /// The method.
    pub method: Method,
    /// Relative tolerance of the adaptive methods (dimensionless).
    pub rtol: Real,
    /// Absolute tolerance of the adaptive methods (units of the state).
    pub atol: Real,
    /// Step of the fixed-step methods (s).
    pub dt: Real,
    /// Largest step of the adaptive methods (s).
    pub h_max: Real,
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        Self {
            method: Method::Dopri5,
            rtol: 1e-10,
            atol: 1e-12,
            dt: 1e-3,
            h_max: 0.1,
        }
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            t_end: 1.0,
            output_rate: 100.0,
            integrator: IntegratorSettings::default(),
            max_drift: None,
            simultaneous: Simultaneous::default(),
        }
    }
}

/// A rule name for simultaneous impacts that is not known.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown rule for simultaneous impacts `{0}` (expected one of: generalized-newton, sequential)"
)]
pub struct UnknownSimultaneous(pub String);

impl std::str::FromStr for Simultaneous {
    type Err = UnknownSimultaneous;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Simultaneous::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| UnknownSimultaneous(s.to_owned()))
    }
}
