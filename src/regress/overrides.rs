//! Overrides of a scene's run settings: what `ricochet run` takes on its command line and
//! what a golden file records, so that `golden check` re-runs a scene as it was recorded.

use serde::{Deserialize, Serialize};

use crate::impact::Law;
use crate::integrate::Method;
use crate::math::Real;
use crate::settings::{Settings, Simultaneous};
use crate::sim::MaterialOverride;

/// Overrides of a scene's settings and contact materials; `None` keeps the scene's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunOverrides {
    /// End time (s), > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t_end: Option<Real>,
    /// Impact law of every contact pair.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub law: Option<Law>,
    /// Coefficient of restitution of every contact pair, in [0, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub e: Option<Real>,
    /// Coefficient of friction of every contact pair, ≥ 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<Real>,
    /// Integration method.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<Method>,
    /// Relative tolerance of DOPRI5, > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rtol: Option<Real>,
    /// Absolute tolerance of DOPRI5, > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atol: Option<Real>,
    /// Step of RK4 and Moreau–Jean (s), > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt: Option<Real>,
    /// Energy-drift budget, relative, > 0 (see [`super::DriftCheck`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_drift: Option<Real>,
    /// The rule for simultaneous impacts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simultaneous: Option<Simultaneous>,
}

/// An override out of its range.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("`{field}` {}, not {value}", requirement(field))]
pub struct OverrideError {
    /// The override's name, as in [`RunOverrides`] (`t_end`, `e`, …).
    pub field: &'static str,
    /// The value given.
    pub value: Real,
}

impl OverrideError {
    /// What the value must be, e.g. `must lie in [0, 1]`.
    pub fn requirement(&self) -> &'static str {
        requirement(self.field)
    }
}

fn requirement(field: &str) -> &'static str {
    match field {
        "t_end" => "must be a positive number of seconds",
        "e" => "must lie in [0, 1]",
        "mu" => "must be a non-negative number",
        _ => "must be a positive number",
    }
}

impl RunOverrides {
    /// Whether nothing is overridden.
    pub fn is_empty(&self) -> bool {
        *self == RunOverrides::default()
    }

    /// Applies the overrides to `settings` and returns the material overrides. Checks each
    /// value: `t_end`, `rtol`, `atol`, `dt`, `max_drift` positive and finite, `e ∈ [0, 1]`,
    /// `μ ≥ 0` and finite.
    pub fn apply(&self, settings: &mut Settings) -> Result<MaterialOverride, OverrideError> {
        let positive = |field: &'static str, value: Option<Real>| match value {
            Some(v) if !(v.is_finite() && v > 0.0) => Err(OverrideError { field, value: v }),
            _ => Ok(value),
        };
        if let Some(t) = positive("t_end", self.t_end)? {
            settings.t_end = t;
        }
        if let Some(m) = self.method {
            settings.integrator.method = m;
        }
        let integ = &mut settings.integrator;
        for (field, value, target) in [
            ("rtol", self.rtol, &mut integ.rtol),
            ("atol", self.atol, &mut integ.atol),
            ("dt", self.dt, &mut integ.dt),
        ] {
            if let Some(v) = positive(field, value)? {
                *target = v;
            }
        }
        if let Some(rule) = self.simultaneous {
            settings.simultaneous = rule;
        }
        if let Some(b) = positive("max_drift", self.max_drift)? {
            settings.max_drift = Some(b);
        }
        if let Some(e) = self.e
            && !(0.0..=1.0).contains(&e)
        {
            return Err(OverrideError {
                field: "e",
                value: e,
            });
        }
        if let Some(mu) = self.mu
            && !(mu >= 0.0 && mu.is_finite())
        {
            return Err(OverrideError {
                field: "mu",
                value: mu,
            });
        }
        Ok(MaterialOverride {
            law: self.law,
            e: self.e,
            mu: self.mu,
        })
    }
}
