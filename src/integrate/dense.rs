//! The continuous extension of one step: a polynomial in `θ = (t − t₀)/h` that
//! interpolates both ends of the step and their slopes (see [`tableau`](super::tableau)
//! for its derivation).
//!
//! ```text
//!   u(θ)  = y₀ + θ (r₂ + (1−θ) (r₃ + θ (r₄ + (1−θ) r₅)))
//!   u'(θ) = r₂ + (1 − 2θ) r₃ + θ (2 − 3θ) r₄ + 2θ (1−θ) (1 − 2θ) r₅      (d/dθ)
//!   r₂ = y₁ − y₀,  r₃ = h f₀ − r₂,  r₄ = r₂ − h f₁ − r₃
//! ```
//!
//! With `r₅ = 0` this is the cubic Hermite interpolant of `(y₀, f₀, y₁, f₁)` (order 3,
//! used by RK4); DOPRI5 adds Shampine's `r₅` for order 4. `u'(0) = h f₀`, `u'(1) = h f₁`.
//!
//! DOP853's extension of order 7 continues the same nesting with `r₆, r₇, r₈` [HNW, II.10;
//! Hairer's `CONTD8`]:
//!
//! ```text
//!   u(θ) = y₀ + θ (r₂ + (1−θ) (r₃ + θ (r₄ + (1−θ) (r₅ + θ (r₆ + (1−θ) (r₇ + θ r₈))))))
//! ```
//!
//! Its derivative is evaluated from the inside out: with `q₈ = r₈` and
//! `qₘ = rₘ + φₘ qₘ₊₁` (`φ` alternating `θ`, `1−θ`), `qₘ' = φₘ' qₘ₊₁ + φₘ qₘ₊₁'`, and
//! `u' = q₂ + θ q₂'`. The quartic keeps its own formulas (RK4 and DOPRI5 bit for bit).

use crate::math::Real;

/// Whether the coefficients of the last step are all there (see [`Dense::completion`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Completion {
    /// Every coefficient is computed: the polynomial can be evaluated.
    Done,
    /// DOP853's `r₅ … r₈` wait for the step's extra stages, which its stages `k₂ … k₁₂`
    /// kept in the stepper's work vectors allow to evaluate.
    Pending,
    /// They were pending when another step overwrote those stages (a step or re-step that
    /// failed): they cannot be computed any more.
    Lost,
}

/// Coefficients of the continuous extension of the last step. `y₀` itself is not stored:
/// the stepper passes its `y_prev`.
#[derive(Clone, Debug)]
pub(crate) struct Dense {
    /// Start of the step `t₀` (s).
    pub t0: Real,
    /// Length of the step `h` (s); 0 for an empty step.
    pub h: Real,
    pub r2: Vec<Real>,
    pub r3: Vec<Real>,
    pub r4: Vec<Real>,
    /// Shampine's quartic term (all zeros for the cubic Hermite interpolant).
    pub r5: Vec<Real>,
    /// DOP853's terms `r₆, r₇, r₈` (empty for the quartic).
    pub r678: [Vec<Real>; 3],
    /// Whether the polynomial is DOP853's of degree 7.
    pub septic: bool,
    /// Whether `r₅ … r₈` are computed ([`Completion::Done`]) or wait for DOP853's extra
    /// stages: [`Self::eval`] and [`Self::eval_derivative`] may be called only when done.
    pub completion: Completion,
}

impl Dense {
    pub fn new(n: usize) -> Self {
        Self {
            t0: 0.0,
            h: 0.0,
            r2: vec![0.0; n],
            r3: vec![0.0; n],
            r4: vec![0.0; n],
            r5: vec![0.0; n],
            r678: Default::default(),
            septic: false,
            completion: Completion::Done,
        }
    }

    /// The polynomial of degree 7 of DOP853 (allocates `r₆ … r₈`).
    pub fn septic(n: usize) -> Self {
        Self {
            r678: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            septic: true,
            ..Self::new(n)
        }
    }

    pub fn resize(&mut self, n: usize) {
        for v in [&mut self.r2, &mut self.r3, &mut self.r4, &mut self.r5] {
            v.resize(n, 0.0);
        }
        if self.septic {
            for v in &mut self.r678 {
                v.resize(n, 0.0);
            }
        }
    }

    /// Sets the cubic Hermite part `r₂, r₃, r₄` from the ends of a step of length `h`.
    /// `r₅` is left untouched.
    pub fn set_hermite(
        &mut self,
        t0: Real,
        h: Real,
        y0: &[Real],
        f0: &[Real],
        y1: &[Real],
        f1: &[Real],
    ) {
        self.t0 = t0;
        self.h = h;
        let coeffs = self.r2.iter_mut().zip(&mut self.r3).zip(&mut self.r4);
        let ends = y0.iter().zip(f0).zip(y1.iter().zip(f1));
        for (((r2, r3), r4), ((y0, f0), (y1, f1))) in coeffs.zip(ends) {
            let ydiff = y1 - y0;
            let bspl = h * f0 - ydiff;
            *r2 = ydiff;
            *r3 = bspl;
            *r4 = ydiff - h * f1 - bspl;
        }
    }

    /// An empty step at `t0`: `u ≡ y₀`.
    pub fn set_empty(&mut self, t0: Real) {
        self.t0 = t0;
        self.h = 0.0;
        self.completion = Completion::Done;
        for v in [&mut self.r2, &mut self.r3, &mut self.r4, &mut self.r5] {
            v.fill(0.0);
        }
        for v in &mut self.r678 {
            v.fill(0.0);
        }
    }

    /// `θ` of `t`; 0 on an empty step.
    #[inline]
    fn theta(&self, t: Real) -> Real {
        if self.h == 0.0 {
            0.0
        } else {
            (t - self.t0) / self.h
        }
    }

    /// `u(θ(t))` into `out`.
    pub fn eval(&self, y0: &[Real], t: Real, out: &mut [Real]) {
        let th = self.theta(t);
        let th1 = 1.0 - th;
        if self.septic {
            let [r6, r7, r8] = &self.r678;
            for (i, o) in out.iter_mut().enumerate() {
                let inner = self.r5[i] + th * (r6[i] + th1 * (r7[i] + th * r8[i]));
                *o = y0[i]
                    + th * (self.r2[i] + th1 * (self.r3[i] + th * (self.r4[i] + th1 * inner)));
            }
            return;
        }
        let coeffs = self
            .r2
            .iter()
            .zip(&self.r3)
            .zip(self.r4.iter().zip(&self.r5));
        for ((o, y0), ((r2, r3), (r4, r5))) in out.iter_mut().zip(y0).zip(coeffs) {
            *o = y0 + th * (r2 + th1 * (r3 + th * (r4 + th1 * r5)));
        }
    }

    /// `u'(θ(t)) / h` (the time derivative) into `out`; `f0` on an empty step.
    pub fn eval_derivative(&self, f0: &[Real], t: Real, out: &mut [Real]) {
        if self.h == 0.0 {
            out.copy_from_slice(f0);
            return;
        }
        let th = self.theta(t);
        let inv_h = 1.0 / self.h;
        if self.septic {
            let th1 = 1.0 - th;
            let [r6, r7, r8] = &self.r678;
            let r = [&self.r2, &self.r3, &self.r4, &self.r5, r6, r7];
            for (i, o) in out.iter_mut().enumerate() {
                // q = r₈; for m = 7 … 2: q ← rₘ + φₘ q, with φₘ = θ for odd m, 1 − θ for
                // even m (u = y₀ + θ q₂).
                let (mut q, mut dq) = (r8[i], 0.0);
                for (m, rm) in (2..8usize).zip(r).rev() {
                    let (phi, dphi) = if m % 2 == 1 { (th, 1.0) } else { (th1, -1.0) };
                    dq = dphi * q + phi * dq;
                    q = rm[i] + phi * q;
                }
                *o = (q + th * dq) * inv_h;
            }
            return;
        }
        let a3 = 1.0 - 2.0 * th;
        let a4 = th * (2.0 - 3.0 * th);
        let a5 = 2.0 * th * (1.0 - th) * (1.0 - 2.0 * th);
        let coeffs = self
            .r2
            .iter()
            .zip(&self.r3)
            .zip(self.r4.iter().zip(&self.r5));
        for (o, ((r2, r3), (r4, r5))) in out.iter_mut().zip(coeffs) {
            *o = (r2 + a3 * r3 + a4 * r4 + a5 * r5) * inv_h;
        }
    }
}
