//! Quantities written with their unit: angles (`"20 deg"`, `"0.35 rad"`) and angular rates
//! (`"-0.1 rad/s"`, `"90 deg/s"`, `"60 rpm"`, `"2 Hz"`). Lengths, masses and the other SI
//! quantities are plain numbers; angles must say their unit.

use std::fmt;

use serde::de::{self, Deserialize, Deserializer, Visitor};

use crate::math::Real;

/// A scene value that is either a plain number or a number with a unit.
#[derive(Clone, Debug, PartialEq)]
#[doc(hidden)]
pub enum Quantity {
    /// A plain number (SI).
    Number(Real),
    /// A number followed by a unit, e.g. `"20 deg"`.
    WithUnit(Real, Unit),
}

/// The units a scene file may write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[doc(hidden)]
pub enum Unit {
    /// Radian.
    Rad,
    /// Degree.
    Deg,
    /// Radian per second.
    RadPerS,
    /// Degree per second.
    DegPerS,
    /// Revolution per minute.
    Rpm,
    /// Revolution per second.
    Hz,
}

impl Unit {
    const ALL: [(&'static str, Unit); 6] = [
        ("rad", Unit::Rad),
        ("deg", Unit::Deg),
        ("rad/s", Unit::RadPerS),
        ("deg/s", Unit::DegPerS),
        ("rpm", Unit::Rpm),
        ("Hz", Unit::Hz),
    ];

    fn parse(s: &str) -> Option<Unit> {
        Unit::ALL.iter().find(|(n, _)| *n == s).map(|(_, u)| *u)
    }
}

/// What a field holds, to convert and check a [`Quantity`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[doc(hidden)]
pub enum Kind {
    /// A plain SI number (m, m/s, N, …).
    Plain,
    /// An angle: `rad` or `deg`.
    Angle,
    /// An angular rate: `rad/s`, `deg/s`, `rpm` or `Hz`.
    AngularRate,
}

impl Quantity {
    /// The SI value of this quantity read as `kind`, or a message saying what is wrong.
    #[doc(hidden)]
    pub fn si(&self, kind: Kind) -> Result<Real, String> {
        use std::f64::consts::PI;
        let value = match (kind, self) {
            (Kind::Plain, Quantity::Number(x)) => *x,
            (Kind::Plain, Quantity::WithUnit(..)) => {
                return Err(
                    "this is a plain number in SI units (m, m/s, N, …), without a unit".into(),
                );
            }
            (Kind::Angle, Quantity::Number(_)) => {
                return Err(
                    "an angle needs its unit: write e.g. \"20 deg\" or \"0.35 rad\"".into(),
                );
            }
            (Kind::AngularRate, Quantity::Number(_)) => {
                return Err("an angular rate needs its unit: write e.g. \"-0.1 rad/s\", \"90 deg/s\", \"60 rpm\" or \"2 Hz\"".into());
            }
            (Kind::Angle, Quantity::WithUnit(x, Unit::Rad)) => *x,
            (Kind::Angle, Quantity::WithUnit(x, Unit::Deg)) => x.to_radians(),
            (Kind::AngularRate, Quantity::WithUnit(x, Unit::RadPerS)) => *x,
            (Kind::AngularRate, Quantity::WithUnit(x, Unit::DegPerS)) => x.to_radians(),
            (Kind::AngularRate, Quantity::WithUnit(x, Unit::Rpm)) => x * 2.0 * PI / 60.0,
            (Kind::AngularRate, Quantity::WithUnit(x, Unit::Hz)) => x * 2.0 * PI,
            (Kind::Angle, Quantity::WithUnit(..)) => {
                return Err("an angle is in \"deg\" or \"rad\"".into());
            }
            (Kind::AngularRate, Quantity::WithUnit(..)) => {
                return Err("an angular rate is in \"rad/s\", \"deg/s\", \"rpm\" or \"Hz\"".into());
            }
        };
        if value.is_finite() {
            Ok(value)
        } else {
            Err(format!("{value} is not a finite number"))
        }
    }
}

/// Parses `"<number> <unit>"`.
#[doc(hidden)]
pub fn parse(s: &str) -> Result<Quantity, String> {
    let mut parts = s.split_whitespace();
    let (Some(number), unit, None) = (parts.next(), parts.next(), parts.next()) else {
        return Err(format!(
            "expected a number and a unit, like \"20 deg\", got \"{s}\""
        ));
    };
    let value: Real = number
        .parse()
        .map_err(|_| format!("`{number}` is not a number (in \"{s}\")"))?;
    match unit {
        None => Err(format!(
            "\"{s}\" has no unit; write a plain number, or e.g. \"{s} deg\""
        )),
        Some(u) => Unit::parse(u)
            .map(|u| Quantity::WithUnit(value, u))
            .ok_or_else(|| {
                let known: Vec<&str> = Unit::ALL.iter().map(|(n, _)| *n).collect();
                format!("unknown unit `{u}` (known: {})", known.join(", "))
            }),
    }
}

impl<'de> Deserialize<'de> for Quantity {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Quantity;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number, or a string with a number and its unit such as \"20 deg\"")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Quantity, E> {
                Ok(Quantity::Number(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Quantity, E> {
                Ok(Quantity::Number(v as Real))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Quantity, E> {
                Ok(Quantity::Number(v as Real))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Quantity, E> {
                parse(v).map_err(E::custom)
            }
        }
        d.deserialize_any(V)
    }
}
