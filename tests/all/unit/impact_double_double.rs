//! Double-double numbers for the tests (the laws' ulp references): a value `hi + lo` with `|lo| ≤ ½ ulp(hi)`, about
//! 106 bits, from the error-free transformations (Knuth's two-sum, the product's error by
//! a fused multiply-add). Reference values against which the laws' doubles are measured in
//! ulps.

use std::ops::{Add, Div, Mul, Neg, Sub};

use ricochet::math::Real;

/// A double-double number `hi + lo`.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub(crate) struct Dd {
    pub(crate) hi: Real,
    pub(crate) lo: Real,
}

/// `a + b = s + err` exactly.
fn two_sum(a: Real, b: Real) -> (Real, Real) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// `a · b = p + err` exactly (barring underflow).
fn two_prod(a: Real, b: Real) -> (Real, Real) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

impl Dd {
    /// The double `x`, exactly.
    pub(crate) fn from(x: Real) -> Self {
        Self { hi: x, lo: 0.0 }
    }

    /// `hi + lo` renormalised.
    fn norm(hi: Real, lo: Real) -> Self {
        let (hi, lo) = two_sum(hi, lo);
        Self { hi, lo }
    }

    /// The square root, by one Newton step from the double's.
    pub(crate) fn sqrt(self) -> Self {
        if self.hi <= 0.0 {
            return Self::from(0.0);
        }
        let x = self.hi.sqrt();
        let r = self - Dd::from(x) * Dd::from(x);
        Dd::norm(x, r.hi / (2.0 * x))
    }

    /// The nearest double.
    pub(crate) fn value(self) -> Real {
        self.hi + self.lo
    }
}

impl Add for Dd {
    type Output = Dd;
    fn add(self, b: Dd) -> Dd {
        let (s, e) = two_sum(self.hi, b.hi);
        let (t, f) = two_sum(self.lo, b.lo);
        let (s, e) = two_sum(s, e + t);
        Dd::norm(s, e + f)
    }
}

impl Neg for Dd {
    type Output = Dd;
    fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}

impl Sub for Dd {
    type Output = Dd;
    fn sub(self, b: Dd) -> Dd {
        self + -b
    }
}

impl Mul for Dd {
    type Output = Dd;
    fn mul(self, b: Dd) -> Dd {
        let (p, e) = two_prod(self.hi, b.hi);
        Dd::norm(p, e + (self.hi * b.lo + self.lo * b.hi))
    }
}

impl Div for Dd {
    type Output = Dd;
    fn div(self, b: Dd) -> Dd {
        let q1 = self.hi / b.hi;
        let r = self - b * Dd::from(q1);
        let q2 = r.hi / b.hi;
        let r = r - b * Dd::from(q2);
        let q3 = r.hi / b.hi;
        Dd::norm(q1, q2) + Dd::from(q3)
    }
}

/// The distance from the double `x` to the reference `r`, in units of the last place of
/// `r` (of its double value).
pub(crate) fn ulps(x: Real, r: Dd) -> Real {
    let v = r.value();
    let ulp = if v == 0.0 {
        Real::MIN_POSITIVE
    } else {
        let bits = v.abs().to_bits();
        Real::from_bits(bits + 1) - Real::from_bits(bits)
    };
    ((Dd::from(x) - r).value() / ulp).abs()
}

// ---------------------------------------------------------------------------------------
// Its own tests

#[test]
fn double_double_keeps_what_doubles_round_away() {
    // 1/3 · 3 = 1 to ~1e-32; (1 + 2^-60) − 1 = 2^-60; √2 · √2 = 2.
    let third = Dd::from(1.0) / Dd::from(3.0);
    assert!(((third * Dd::from(3.0)) - Dd::from(1.0)).value().abs() < 1e-31);
    let tiny = (Dd::from(1.0) + Dd::from(2f64.powi(-60))) - Dd::from(1.0);
    assert_eq!(tiny.value(), 2f64.powi(-60));
    let r2 = Dd::from(2.0).sqrt();
    assert!(((r2 * r2) - Dd::from(2.0)).value().abs() < 1e-31);
    assert_eq!(r2.hi, 2f64.sqrt());
    assert_eq!(ulps(1.0 + f64::EPSILON, Dd::from(1.0)), 1.0);
}
