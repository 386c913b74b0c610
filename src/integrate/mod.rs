//! Time integration of `ẏ = f(t, y)`: DOPRI5(4) with dense output, RK4 with a fixed step.
//! This module knows nothing about bodies or contacts.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// The time-integration method of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Dormand–Prince 5(4), adaptive step, dense output of order 4 [HNW, II.5–6].
    Dopri5,
    /// The classical Runge–Kutta method of order 4 with a fixed step.
    Rk4,
}

impl Method {
    /// Every method, in the order shown to users.
    pub const ALL: [Method; 2] = [Method::Dopri5, Method::Rk4];

    /// The name used on the command line and in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Method::Dopri5 => "dopri5",
            Method::Rk4 => "rk4",
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A method name that is not known.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown method `{0}` (expected one of: dopri5, rk4)")]
pub struct UnknownMethod(pub String);

impl FromStr for Method {
    type Err = UnknownMethod;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| UnknownMethod(s.to_owned()))
    }
}
