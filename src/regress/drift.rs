//! Energy-drift budgets: the integration drift of a run's energy audit against its energy
//! scale and the scene's `max_drift`.

use serde::{Deserialize, Serialize};

use crate::math::Real;

/// The integration drift of a run measured against its energy scale, and the budget.
///
/// The drift `δ` is the audit's: `E_end − E_0` less what the impacts, dampers, efforts,
/// drives and contact forces explain (`ARCHITECTURE.md`, the energy audit). It is measured
/// relative to the run's energy scale
///
/// ```text
/// E_ref = max(|E_0|, |E_end|, max over the samples of K + |V|)     (J)
/// relative = |δ| / E_ref
/// ```
///
/// For a body released from rest above the potential's datum `E_ref = E_0`, the initial
/// energy. The samples' `K + |V|` keep the scale away from zero where the energy's zero is
/// a matter of datum: a pendulum released horizontally from rest has `E_0 = 0`, and its
/// swing's `K + |V|` is the scale. A run with no energy at all at any sample has no scale:
/// its relative drift is 0 if `δ = 0` and is absent (the budget broken) otherwise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DriftCheck {
    /// The integration drift `δ` of the audit (J).
    pub integration_drift: Real,
    /// The energy scale `E_ref` (J).
    pub energy_scale: Real,
    /// `|δ| / E_ref` (dimensionless); absent when `E_ref = 0` and `δ ≠ 0`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relative: Option<Real>,
    /// The budget, the scene's `[run] max_drift` or `--max-drift` (dimensionless); absent
    /// when the run has none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_drift: Option<Real>,
}

impl DriftCheck {
    /// The check of the drift `drift` (J) against the energy scale `scale` (J) and the
    /// budget `max_drift`.
    pub fn new(drift: Real, scale: Real, max_drift: Option<Real>) -> DriftCheck {
        let relative = if drift == 0.0 {
            Some(0.0)
        } else if scale > 0.0 {
            Some(drift.abs() / scale).filter(|r| r.is_finite())
        } else {
            None
        };
        DriftCheck {
            integration_drift: drift,
            energy_scale: scale,
            relative,
            max_drift,
        }
    }

    /// Whether the run has a budget and breaks it (a drift that cannot be measured, or is
    /// not finite, breaks every budget).
    pub fn broken(&self) -> bool {
        match (self.max_drift, self.relative) {
            (None, _) => false,
            // `relative` is finite when present.
            (Some(budget), Some(r)) => r > budget,
            (Some(_), None) => true,
        }
    }

    /// How many times the budget the drift is (`relative / max_drift`), when both exist.
    pub fn ratio(&self) -> Option<Real> {
        Some(self.relative? / self.max_drift?)
    }

    /// One line for a person: the drift, its scale, and the budget with the verdict.
    pub fn describe(&self) -> String {
        let relative = self
            .relative
            .map_or_else(|| "unmeasurable".to_owned(), |r| format!("{r:.3e}"));
        let mut line = format!(
            "integration drift {:.3e} J, {relative} of the energy scale {:.6e} J",
            self.integration_drift, self.energy_scale
        );
        if let Some(budget) = self.max_drift {
            if self.broken() {
                let by = self.ratio().map_or_else(
                    || "no energy scale to measure it against".to_owned(),
                    |k| {
                        format!(
                            "{k:.3} times the budget, {:.3e} J over it",
                            self.integration_drift.abs() - budget * self.energy_scale
                        )
                    },
                );
                line += &format!(": BEYOND the budget max_drift = {budget:e} ({by})");
            } else {
                line += &format!(": within the budget max_drift = {budget:e}");
            }
        }
        line
    }
}
