//! Step-size control of the adaptive methods: the weighted error norm, the PI controller and the
//! initial step guess of [HNW, II.4] as in Hairer's code `DOPRI5`, and the clipping of a
//! step to a stop time (shared with RK4).

use crate::math::Real;

/// Weighted RMS norm of the local error estimate [HNW, II.4, Eq. (4.11)]:
///
/// ```text
///   err = √( (1/n) Σᵢ (eᵢ / skᵢ)² ),   skᵢ = atol + rtol · max(|y₀ᵢ|, |y₁ᵢ|)
/// ```
///
/// A step is accepted when `err ≤ 1`.
#[doc(hidden)]
pub fn error_norm(e: &[Real], y0: &[Real], y1: &[Real], rtol: Real, atol: Real) -> Real {
    if e.is_empty() {
        return 0.0;
    }
    let sum: Real = e
        .iter()
        .zip(y0.iter().zip(y1))
        .map(|(e, (y0, y1))| {
            let sk = atol + rtol * y0.abs().max(y1.abs());
            let r = e / sk;
            r * r
        })
        .sum();
    (sum / e.len() as Real).sqrt()
}

/// The PI step-size controller with Lund's stabilization [HNW, II.4, Eq. (4.13) and the
/// text after it; Gustafsson, ACM TOMS 20 (1994)], with the constants of Hairer's
/// `DOPRI5` (`DOP853`: the exponent `1/8 − 0.2 β`):
///
/// ```text
///   fac = err^(1/5 − 0.75 β) · err_old^(−β) / safety,  clamped to [1/fac_max, 1/fac_min]
///   h_new = h / fac
///   accepted (err ≤ 1): err_old ← max(err, 1e-4); after a rejection h_new ≤ h
///   rejected (err > 1): h_new = h · max(fac_min, safety · err^(−(1/5 − 0.75 β)))
/// ```
///
/// `β = 0` is the classical I (elementary) controller; `β ≈ 0.04` damps oscillating step
/// sequences.
#[derive(Clone, Debug)]
#[doc(hidden)]
pub struct PiController {
    pub safety: Real,
    pub beta: Real,
    pub fac_min: Real,
    pub fac_max: Real,
    /// The exponent of `err`: `κ₀ − κ₁ β` (DOPRI5: `1/5 − 0.75 β`; DOP853:
    /// `1/8 − 0.2 β`, Hairer's `EXPO1`).
    expo: Real,
    err_old: Real,
    rejected_last: bool,
}

/// The controller's verdict on one attempted step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[doc(hidden)]
pub struct Verdict {
    pub accept: bool,
    /// The next step to try (s).
    pub h_new: Real,
}

impl PiController {
    /// The controller of a method whose exponents are `(κ₀, κ₁)` (see
    /// [`Tableau::controller`](super::tableau::Tableau::controller)).
    pub fn new(
        (k0, k1): (Real, Real),
        safety: Real,
        beta: Real,
        fac_min: Real,
        fac_max: Real,
    ) -> Self {
        Self {
            safety,
            beta,
            fac_min,
            fac_max,
            expo: k0 - k1 * beta,
            err_old: 1e-4,
            rejected_last: false,
        }
    }

    /// Forgets the history (after a start or a reset).
    pub fn restart(&mut self) {
        self.err_old = 1e-4;
        self.rejected_last = false;
    }

    /// Judges a step of length `h` with error norm `err`. A non-finite `err` rejects the
    /// step with the smallest factor.
    pub fn judge(&mut self, h: Real, err: Real) -> Verdict {
        if !err.is_finite() {
            self.rejected_last = true;
            return Verdict {
                accept: false,
                h_new: h * self.fac_min,
            };
        }
        let fac11 = err.powf(self.expo);
        if err <= 1.0 {
            let fac = (fac11 / self.err_old.powf(self.beta) / self.safety)
                .clamp(1.0 / self.fac_max, 1.0 / self.fac_min);
            let mut h_new = h / fac;
            if self.rejected_last {
                h_new = h_new.min(h);
            }
            self.err_old = err.max(1e-4);
            self.rejected_last = false;
            Verdict {
                accept: true,
                h_new,
            }
        } else {
            self.rejected_last = true;
            let fac = (fac11 / self.safety).min(1.0 / self.fac_min);
            Verdict {
                accept: false,
                h_new: h / fac,
            }
        }
    }
}

/// DOP853's error norm [HNW, II.10; Hairer's `DOP853`] from its two estimates `e5 = Σ ê₅ k`
/// and `e3 = Σ ê₃ k` (without the factor `h`):
///
/// ```text
///   skᵢ = atol + rtol · max(|y₀ᵢ|, |y₁ᵢ|),  E5 = Σ (e5ᵢ/skᵢ)²,  E3 = Σ (e3ᵢ/skᵢ)²
///   err = |h| · E5 / √(n (E5 + 0.01 E3))     (the denominator 1 when it is 0)
/// ```
pub(crate) fn dop853_error_norm(
    e5: &[Real],
    e3: &[Real],
    y0: &[Real],
    y1: &[Real],
    rtol: Real,
    atol: Real,
    h: Real,
) -> Real {
    if e5.is_empty() {
        return 0.0;
    }
    let (mut err5, mut err3) = (0.0, 0.0);
    for i in 0..e5.len() {
        let sk = atol + rtol * y0[i].abs().max(y1[i].abs());
        let (a, b) = (e5[i] / sk, e3[i] / sk);
        err5 += a * a;
        err3 += b * b;
    }
    let mut deno = err5 + 0.01 * err3;
    if deno <= 0.0 {
        deno = 1.0;
    }
    h.abs() * err5 * (1.0 / (e5.len() as Real * deno)).sqrt()
}

/// The step to try from `t` toward `t_stop`, `remaining = t_stop − t > 0`: `h_try` capped
/// by `h_max`; the step that reaches `t_stop` lands on it exactly. As in Hairer's codes,
/// a step that would leave a sliver shorter than 1 % of itself is stretched to
/// `t_stop` when that stays within `h_max` (to a relative 1e-12), otherwise the rest is
/// split into two equal steps. Returns the step and whether it reaches `t_stop`.
#[doc(hidden)]
pub fn clip_step(h_try: Real, h_max: Real, remaining: Real) -> (Real, bool) {
    let h = h_try.min(h_max);
    if remaining <= h {
        (remaining, true)
    } else if remaining <= 1.01 * h {
        if remaining <= h_max * (1.0 + 1e-12) {
            (remaining, true)
        } else {
            (0.5 * remaining, false)
        }
    } else {
        (h, false)
    }
}

/// The smallest admissible step at `t` after rejections: `max(h_min, 10 ε |t|)` (below
/// `10 ε |t|` the step is lost in the rounding of `t + h`; Hairer's `DOPRI5` test).
pub(crate) fn smallest_step(h_min: Real, t: Real) -> Real {
    h_min.max(10.0 * Real::EPSILON * t.abs())
}

/// After a right-hand side failed at a trial stage (a state the accepted solution never
/// reaches): the step to try next, `h / 4`, counting the failure in `failures`; `None` —
/// the failure is returned — after 30 in a row (a factor 1e18) or below `h_min`.
pub(crate) fn after_failed_stage(h: Real, failures: &mut u32, h_min: Real) -> Option<Real> {
    *failures += 1;
    let h_new = 0.25 * h;
    (*failures < 30 && h_new >= h_min).then_some(h_new)
}

/// Scaled squared norms used by the initial step guess [HNW, II.4, p. 169]:
/// `Σ (vᵢ / skᵢ)²` with `skᵢ = atol + rtol |y₀ᵢ|` (no division by `n`, as in `HINIT`).
pub(crate) fn scaled_sq(v: &[Real], y0: &[Real], rtol: Real, atol: Real) -> Real {
    v.iter()
        .zip(y0)
        .map(|(v, y)| {
            let r = v / (atol + rtol * y.abs());
            r * r
        })
        .sum()
}
