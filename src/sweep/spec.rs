//! One swept parameter: `name=start:stop:step` or `name=v1,v2,…`.

use std::fmt;

use crate::impact::Law;
use crate::integrate::Method;
use crate::math::Real;
use crate::settings::Simultaneous;

use super::SpecError;

/// Most runs a sweep may hold (a typo such as `e=0:1:1e-12` is refused, not run).
pub const MAX_RUNS: usize = 10_000_000;

/// How close to `stop` (in steps) the last value of a range must come to count as `stop`:
/// the range is inclusive within this tolerance, and its last value is then `stop` itself.
pub const RANGE_TOLERANCE: Real = 1e-9;

/// A parameter that a sweep may vary.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Param {
    /// `e`: coefficient of restitution of every contact, in [0, 1].
    E,
    /// `mu`: coefficient of friction of every contact, ≥ 0.
    Mu,
    /// `law`: impact law of every contact (`newton`, `kane-levinson`, `poisson`,
    /// `stronge`); lists only.
    Law,
    /// `method`: integration method (`dopri5`, `dop853`, `rk4`, `moreau-jean`); lists only.
    Method,
    /// `simultaneous`: the rule for simultaneous impacts (`generalized-newton`,
    /// `sequential`); lists only.
    Simultaneous,
    /// `t_end`: end time (s), > 0.
    TEnd,
    /// `rtol`: relative tolerance of DOPRI5, > 0.
    Rtol,
    /// `atol`: absolute tolerance of DOPRI5, > 0.
    Atol,
    /// `dt`: step of RK4 and Moreau–Jean (s), > 0.
    Dt,
    /// `h_max`: largest step of DOPRI5 (s), > 0.
    HMax,
    /// `q0.<coordinate>`: the initial value of a generalized coordinate, by its name in
    /// the model (`q0.ball.y`, `q0.rodA.q`) (m or rad).
    Q0(String),
    /// `u0.<coordinate>`: the initial value of a generalized speed (m/s or rad/s).
    U0(String),
}

/// The names of the parameters, for messages.
pub const PARAM_NAMES: &str = "e, mu, law, method, simultaneous, t_end, rtol, atol, dt, h_max, \
                               q0.<coordinate>, u0.<coordinate>";

impl Param {
    /// The parameter called `name`, if there is one.
    pub fn from_name(name: &str) -> Option<Param> {
        Some(match name {
            "e" => Param::E,
            "mu" => Param::Mu,
            "law" => Param::Law,
            "method" => Param::Method,
            "simultaneous" => Param::Simultaneous,
            "t_end" => Param::TEnd,
            "rtol" => Param::Rtol,
            "atol" => Param::Atol,
            "dt" => Param::Dt,
            "h_max" => Param::HMax,
            _ => {
                if let Some(c) = name.strip_prefix("q0.").filter(|c| !c.is_empty()) {
                    Param::Q0(c.to_owned())
                } else if let Some(c) = name.strip_prefix("u0.").filter(|c| !c.is_empty()) {
                    Param::U0(c.to_owned())
                } else {
                    return None;
                }
            }
        })
    }

    /// Whether the values are names (`law`, `method`, `simultaneous`) rather than numbers.
    fn is_named(&self) -> bool {
        matches!(self, Param::Law | Param::Method | Param::Simultaneous)
    }

    /// Why the number `v` is not a value of this parameter, if it is not.
    fn check(&self, v: Real) -> Option<&'static str> {
        match self {
            Param::E => (!(0.0..=1.0).contains(&v)).then_some("e must lie in [0, 1]"),
            Param::Mu => (!(v.is_finite() && v >= 0.0)).then_some("mu must be finite and ≥ 0"),
            Param::TEnd | Param::Rtol | Param::Atol | Param::Dt | Param::HMax => {
                (!(v.is_finite() && v > 0.0)).then_some("must be finite and > 0")
            }
            Param::Q0(_) | Param::U0(_) => (!v.is_finite()).then_some("must be finite"),
            Param::Law | Param::Method | Param::Simultaneous => Some("takes names, not numbers"),
        }
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Param::E => f.write_str("e"),
            Param::Mu => f.write_str("mu"),
            Param::Law => f.write_str("law"),
            Param::Method => f.write_str("method"),
            Param::Simultaneous => f.write_str("simultaneous"),
            Param::TEnd => f.write_str("t_end"),
            Param::Rtol => f.write_str("rtol"),
            Param::Atol => f.write_str("atol"),
            Param::Dt => f.write_str("dt"),
            Param::HMax => f.write_str("h_max"),
            Param::Q0(c) => write!(f, "q0.{c}"),
            Param::U0(c) => write!(f, "u0.{c}"),
        }
    }
}

/// One value of a parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// A number.
    Real(Real),
    /// An impact law.
    Law(Law),
    /// An integration method.
    Method(Method),
    /// A rule for simultaneous impacts.
    Simultaneous(Simultaneous),
}

impl fmt::Display for Value {
    /// Numbers in [`format_real`] (shortest round trip), names as on the command line.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Real(x) => f.write_str(&format_real(*x)),
            Value::Law(l) => f.write_str(l.name()),
            Value::Method(m) => f.write_str(m.name()),
            Value::Simultaneous(r) => f.write_str(r.name()),
        }
    }
}

/// `x` as the shortest decimal that reads back to the same `f64`: Rust's `{}` for
/// `1e-5 ≤ |x| < 1e16` and zero, `{:e}` beyond (so that `1e-300` is not 300 digits).
/// Both are exact round trips; the choice depends on `x` alone, so equal numbers always
/// print alike.
pub fn format_real(x: Real) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The values a parameter takes.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// `start:stop:step`: `value_k = start + k·step` for `k = 0 … count − 1`, where the
    /// last is `stop` itself when it comes within [`RANGE_TOLERANCE`] steps of it.
    Range {
        /// First value.
        start: Real,
        /// Last value asked for (inclusive within the tolerance).
        stop: Real,
        /// Increment, > 0.
        step: Real,
        /// Number of values.
        count: usize,
        /// The last value, `start + (count − 1)·step` or `stop`.
        last: Real,
    },
    /// `v1,v2,…`: the values in the order given.
    List(Vec<Value>),
}

/// One swept parameter and its values, parsed from `name=start:stop:step` or
/// `name=v1,v2,…`.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSpec {
    /// The parameter.
    pub param: Param,
    /// Its values.
    pub values: Values,
}

impl ParamSpec {
    /// Parses `name=start:stop:step` (numbers only; `step > 0`, `stop ≥ start`) or
    /// `name=v1,v2,…` (one value or more). Each value is checked against the parameter's
    /// range; an error names the spec.
    pub fn parse(spec: &str) -> Result<ParamSpec, SpecError> {
        let malformed = |reason: String| SpecError::Malformed {
            spec: spec.to_owned(),
            reason,
        };
        let (name, rhs) = spec
            .split_once('=')
            .ok_or_else(|| malformed("expected name=start:stop:step or name=v1,v2,…".to_owned()))?;
        let name = name.trim();
        let param = Param::from_name(name).ok_or_else(|| SpecError::UnknownParam {
            spec: spec.to_owned(),
            name: name.to_owned(),
        })?;
        let number = |text: &str| -> Result<Real, SpecError> {
            let t = text.trim();
            let v: Real = t
                .parse()
                .map_err(|_| malformed(format!("`{t}` is not a number")))?;
            match param.check(v) {
                Some(reason) => Err(SpecError::OutOfRange {
                    spec: spec.to_owned(),
                    value: t.to_owned(),
                    reason,
                }),
                None => Ok(v),
            }
        };
        let values = if rhs.contains(':') {
            if param.is_named() {
                return Err(malformed(format!(
                    "{param} takes a list of names (v1,v2,…), not a range"
                )));
            }
            let parts: Vec<&str> = rhs.split(':').collect();
            let [a, b, s] = parts[..] else {
                return Err(malformed(
                    "a range is start:stop:step, with three numbers".to_owned(),
                ));
            };
            let start = number(a)?;
            let stop = number(b)?;
            let step: Real = s
                .trim()
                .parse()
                .map_err(|_| malformed(format!("the step `{}` is not a number", s.trim())))?;
            if !(step.is_finite() && step > 0.0) {
                return Err(malformed(format!("the step must be > 0, not {step}")));
            }
            if stop < start {
                return Err(malformed(format!(
                    "the range runs from {start} down to {stop}: stop must be ≥ start"
                )));
            }
            let (count, last) = range_count(start, stop, step)
                .ok_or_else(|| malformed(format!("more than {MAX_RUNS} values in the range")))?;
            Values::Range {
                start,
                stop,
                step,
                count,
                last,
            }
        } else {
            let mut list = Vec::new();
            for item in rhs.split(',') {
                let t = item.trim();
                if t.is_empty() {
                    return Err(malformed("an empty value in the list".to_owned()));
                }
                list.push(match param {
                    Param::Law => Value::Law(t.parse().map_err(|e| malformed(format!("{e}")))?),
                    Param::Method => {
                        Value::Method(t.parse().map_err(|e| malformed(format!("{e}")))?)
                    }
                    Param::Simultaneous => {
                        Value::Simultaneous(t.parse().map_err(|e| malformed(format!("{e}")))?)
                    }
                    _ => Value::Real(number(t)?),
                });
            }
            Values::List(list)
        };
        Ok(ParamSpec { param, values })
    }

    /// The number of values.
    pub fn len(&self) -> usize {
        match &self.values {
            Values::Range { count, .. } => *count,
            Values::List(list) => list.len(),
        }
    }

    /// Whether there are no values (never, for a parsed spec).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The value `k` (`k < len()`): `start + k·step` for a range (its last one `stop` when
    /// within the tolerance), the `k`-th of a list.
    pub fn value(&self, k: usize) -> Value {
        match &self.values {
            Values::Range {
                start,
                step,
                count,
                last,
                ..
            } => Value::Real(if k + 1 == *count {
                *last
            } else {
                start + k as Real * step
            }),
            Values::List(list) => list[k],
        }
    }

    /// The spec written back in a canonical form (numbers in [`format_real`]), which a
    /// sweep's header stores: two specs with the same values print alike.
    pub fn canonical(&self) -> String {
        match &self.values {
            Values::Range {
                start, stop, step, ..
            } => format!(
                "{}={}:{}:{}",
                self.param,
                format_real(*start),
                format_real(*stop),
                format_real(*step)
            ),
            Values::List(list) => {
                let items: Vec<String> = list.iter().map(Value::to_string).collect();
                format!("{}={}", self.param, items.join(","))
            }
        }
    }
}

/// The number of values of `start:stop:step` and the last one:
/// `count − 1 = ⌊(stop − start)/step + tol⌋`, the last `stop` when
/// `|start + (count − 1)·step − stop| ≤ tol·step`. `None` beyond [`MAX_RUNS`] values.
fn range_count(start: Real, stop: Real, step: Real) -> Option<(usize, Real)> {
    let span = ((stop - start) / step + RANGE_TOLERANCE).floor();
    if !(span.is_finite() && span < MAX_RUNS as Real) {
        return None;
    }
    let n = span as usize;
    let last = start + n as Real * step;
    let last = if (last - stop).abs() <= RANGE_TOLERANCE * step {
        stop
    } else {
        last
    };
    Some((n + 1, last))
}
