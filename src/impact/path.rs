//! Routh's path in the impulse plane [P, Sect. 4.1, Fig. 2]: forward sliding along
//! `L_FS` until the slip stops at point G, then sticking along `L_ST` or reverse sliding
//! along `L_RS`. Along each phase the contact velocity, the tangential impulse and the
//! works are linear or quadratic in `I_n`, so every end condition closes in algebra.

use serde::{Deserialize, Serialize};

use super::coefficients::Coefficients;
use super::outcome::CollisionType;
use super::problem::{ContactVelocity, ImpactMatrix, Impulse};
use super::scale::Rescale;
use crate::math::Real;

/// A point of the collision, reached after the normal impulse `i.n`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PathPoint {
    /// Accumulated impulse `(Ĩ_n, Ĩ_t)` [P, Eq. (54)] (N·s).
    pub i: Impulse,
    /// Contact velocity there, `v^A + W Ĩ` [P, Eqs. (22)–(23)] (m/s).
    pub v: ContactVelocity,
    /// Work of the normal impulse so far, `∫ v_n dĨ_n` (J).
    pub work_n: Real,
    /// Work of the tangential impulse so far, `∫ v_t dĨ_t` (J).
    pub work_t: Real,
}

/// Rates of change along a phase, per unit normal impulse.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Slope {
    /// `dĨ_t / dĨ_n`.
    di_t: Real,
    /// `dv_n / dĨ_n`.
    dv_n: Real,
    /// `dv_t / dĨ_n`.
    dv_t: Real,
}

impl Slope {
    /// The point reached from `p0` after the normal impulse `x` along this slope: the
    /// velocities are linear in `x`, the works quadratic,
    /// `W_n += v_n0 x + ½ dv_n x²`, `W_t += dĨ_t (v_t0 x + ½ dv_t x²)`.
    #[inline(always)]
    fn advance(&self, p0: &PathPoint, x: Real) -> PathPoint {
        PathPoint {
            i: Impulse::new(p0.i.n + x, p0.i.t + self.di_t * x),
            v: ContactVelocity::new(p0.v.n + self.dv_n * x, p0.v.t + self.dv_t * x),
            work_n: p0.work_n + x * (p0.v.n + 0.5 * self.dv_n * x),
            work_t: p0.work_t + self.di_t * x * (p0.v.t + 0.5 * self.dv_t * x),
        }
    }
}

/// One phase of a collision: its slip mode and its end points.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Phase {
    /// The slip mode during the phase.
    pub kind: CollisionType,
    /// Where the phase starts.
    pub start: PathPoint,
    /// Where it ends.
    pub end: PathPoint,
}

/// The phases of a collision, one or two, stored compactly: the end of each phase (the
/// next one starts there; the first starts at the origin of the impulse plane, at the
/// velocity of approach). The end of the collision is always the second entry: a single
/// phase is stored as two equal ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phases {
    /// Velocity of approach: the contact velocity where the first phase starts (m/s).
    v_a: ContactVelocity,
    /// The end of each phase (twice the end of a single phase).
    ends: [PathPoint; 2],
    /// The slip mode of each phase.
    kinds: [CollisionType; 2],
    /// The number of phases, 1 or 2.
    len: u8,
}

impl Phases {
    /// A single phase from the origin to `end`.
    #[inline(always)]
    pub(super) fn one(v_a: ContactVelocity, kind: CollisionType, end: PathPoint) -> Self {
        Self {
            v_a,
            ends: [end, end],
            kinds: [kind, kind],
            len: 1,
        }
    }

    /// Two phases: from the origin to `mid`, then to `end`.
    #[inline(always)]
    pub(super) fn two(
        v_a: ContactVelocity,
        first: CollisionType,
        mid: PathPoint,
        second: CollisionType,
        end: PathPoint,
    ) -> Self {
        Self {
            v_a,
            ends: [mid, end],
            kinds: [first, second],
            len: 2,
        }
    }

    /// A single straight phase of type `kind` from the origin of the impulse plane to the
    /// impulse `i`, ending at the velocity `v_s`: the path of a law without phases (the
    /// generalized Newton law of several contacts, time-stepping). Along a straight path
    /// the works are `½ I_n (v_n^A + v_n^S)` and `½ I_t (v_t^A + v_t^S)`.
    pub fn straight(
        v_a: ContactVelocity,
        kind: CollisionType,
        i: Impulse,
        v_s: ContactVelocity,
    ) -> Self {
        let end = PathPoint {
            i,
            v: v_s,
            work_n: 0.5 * i.n * (v_a.n + v_s.n),
            work_t: 0.5 * i.t * (v_a.t + v_s.t),
        };
        Self::one(v_a, kind, end)
    }

    /// The number of phases (1 or 2).
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// Always false: a collision has at least one phase.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The phases, in order.
    #[inline(always)]
    pub fn iter(&self) -> impl Iterator<Item = Phase> + '_ {
        (0..self.len()).map(|k| Phase {
            kind: self.kinds[k],
            start: if k == 0 {
                PathPoint {
                    v: self.v_a,
                    ..PathPoint::default()
                }
            } else {
                self.ends[k - 1]
            },
            end: self.ends[k],
        })
    }

    /// The end of the collision.
    #[inline(always)]
    pub fn end(&self) -> &PathPoint {
        &self.ends[1]
    }

    /// The end of the first phase (of the collision, when there is one phase).
    #[inline(always)]
    pub(super) fn first_end(&self) -> &PathPoint {
        &self.ends[0]
    }

    /// The same phases ending exactly at the impulse `i` and velocity `v` (a closed form's
    /// values, equal to the path's own end up to rounding).
    #[inline(always)]
    pub(super) fn ending_at(mut self, i: Impulse, v: ContactVelocity) -> Self {
        self.ends[1].i = i;
        self.ends[1].v = v;
        if self.len == 1 {
            self.ends[0] = self.ends[1];
        }
        self
    }

    /// The phases of the problem `(s W, c v^A)` from those of `(W, v^A)`, with the powers
    /// of two of [`Scale::exponents`](super::scale::Scale::exponents).
    #[inline(always)]
    pub(super) fn scaled<R: Rescale>(mut self, k: &R) -> Self {
        self.v_a = ContactVelocity::new(k.velocity(self.v_a.n), k.velocity(self.v_a.t));
        for p in &mut self.ends {
            *p = PathPoint {
                i: Impulse::new(k.impulse(p.i.n), k.impulse(p.i.t)),
                v: ContactVelocity::new(k.velocity(p.v.n), k.velocity(p.v.t)),
                work_n: k.work(p.work_n),
                work_t: k.work(p.work_t),
            };
        }
        self
    }

    /// The phases with every point and the velocity of approach mapped by `point` and
    /// `velocity` (a change of frame or of scales).
    #[inline(always)]
    pub(super) fn map(
        self,
        point: impl Fn(&PathPoint) -> PathPoint,
        velocity: impl Fn(ContactVelocity) -> ContactVelocity,
    ) -> Self {
        Self {
            v_a: velocity(self.v_a),
            ends: [point(&self.ends[0]), point(&self.ends[1])],
            ..self
        }
    }

    /// Mirrors the phases into the frame whose tangent is `−t`.
    #[inline(always)]
    pub(super) fn mirror(&mut self) {
        self.v_a.t = -self.v_a.t;
        for p in &mut self.ends {
            p.i.t = -p.i.t;
            p.v.t = -p.v.t;
        }
    }
}

/// Routh's path for given `W`, `μ` and a velocity of approach with `v_t^A ≥ 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RouthPath {
    /// The origin: no impulse yet, velocity `v^A`.
    origin: PathPoint,
    /// Phase 1, forward sliding along `L_FS`.
    slide: Slope,
    /// `Ĩ_n(G)` where the slip stops [P, Eq. (58)]; infinite when it never does.
    i_g: Real,
    /// The point G (meaningful when `i_g` is finite).
    at_g: PathPoint,
    /// The mode after G: sticking or reverse sliding.
    after: CollisionType,
    /// Phase 2 along `L_ST` or `L_RS`.
    after_slope: Slope,
}

impl RouthPath {
    /// Builds the path.
    ///
    /// Implements [P, Eqs. (55)–(61)], rewritten per unit normal impulse with
    /// `v = v^A + W Ĩ`:
    /// - forward sliding (`L_FS`, Eq. 55): `dĨ_t = −μ dĨ_n`, so `dv_n = h dĨ_n`,
    ///   `dv_t = −g dĨ_n`;
    /// - the slip stops at `Ĩ_n(G) = v_t^A / g` (Eq. 58) if `g > 0`, never if `g ≤ 0`
    ///   (for `v_t^A = 0`: at once if `g ≥ 0`);
    /// - then sticking (`L_ST`, Eq. 56) if the friction cone holds the contact,
    ///   `|m_nt| ≤ μ m_tt` ⇔ `g ≥ 0, p ≥ 0` (Eq. 59): `dĨ_t = −(m_nt/m_tt) dĨ_n`,
    ///   `dv_n = (Δ/m_tt) dĨ_n`, `dv_t = 0` (for `m_tt = 0`: `dĨ_t = 0`, `dv_n = m_nn`);
    /// - or reverse sliding (`L_RS`, Eq. 57) if `p < 0` (Eq. 60): `dĨ_t = μ dĨ_n`,
    ///   `dv_n = q dĨ_n`, `dv_t = p dĨ_n`.
    pub fn new(w: &ImpactMatrix, mu: Real, v_a: ContactVelocity) -> Self {
        Self::with_coefficients(w, mu, v_a, &Coefficients::new(w, mu, v_a))
    }

    /// [`RouthPath::new`] with g, h, p, q already computed.
    #[inline(always)]
    pub fn with_coefficients(
        w: &ImpactMatrix,
        mu: Real,
        v_a: ContactVelocity,
        c: &Coefficients,
    ) -> Self {
        debug_assert!(v_a.t >= 0.0, "the path is built in the paper's frame");
        let (g, h, p, q) = (c.g, c.h, c.p, c.q);
        let origin = PathPoint {
            i: Impulse::default(),
            v: v_a,
            work_n: 0.0,
            work_t: 0.0,
        };
        let slide = Slope {
            di_t: -mu,
            dv_n: h,
            dv_t: -g,
        };
        let i_g = if v_a.t == 0.0 {
            if g >= 0.0 { 0.0 } else { Real::INFINITY }
        } else if g > 0.0 {
            v_a.t / g
        } else {
            Real::INFINITY
        };
        let mut at_g = slide.advance(&origin, if i_g.is_finite() { i_g } else { 0.0 });
        // At G the slip is zero by definition (Eq. 39); do not keep the rounding residue.
        at_g.v.t = 0.0;
        let (after, after_slope) = if p >= 0.0 {
            // Sticking. With m_tt = 0 (then m_nt = 0) the tangential impulse does nothing:
            // take the least, I_t = 0, and v_n grows at m_nn. With a singular W and
            // m_tt > 0, Δ = 0 and v_n is frozen: the contact jams.
            let (di_t, dv_n) = if w.tt > 0.0 {
                (-w.nt / w.tt, c.det / w.tt)
            } else {
                (0.0, w.nn)
            };
            (
                CollisionType::Sticking,
                Slope {
                    di_t,
                    dv_n,
                    dv_t: 0.0,
                },
            )
        } else {
            (
                CollisionType::ReverseSliding,
                Slope {
                    di_t: mu,
                    dv_n: q,
                    dv_t: p,
                },
            )
        };
        Self {
            origin,
            slide,
            i_g,
            at_g,
            after,
            after_slope,
        }
    }

    /// `Ĩ_n(G)`, infinite when the slip never stops [P, Eq. (58)].
    pub fn i_g(&self) -> Real {
        self.i_g
    }

    /// The slip mode after G.
    pub fn after_g(&self) -> CollisionType {
        self.after
    }

    /// `dv_n/dĨ_n` of the first phase, forward sliding: `h`.
    #[inline(always)]
    #[doc(hidden)]
    pub fn slide_dv_n(&self) -> Real {
        self.slide.dv_n
    }

    /// `dv_n/dĨ_n` of the phase after G: `q` (reverse sliding), `Δ/m_tt` (sticking), or
    /// `m_nn` (sticking with `m_tt = 0`).
    #[inline(always)]
    #[doc(hidden)]
    pub fn after_dv_n(&self) -> Real {
        self.after_slope.dv_n
    }

    /// The point G (meaningful when [`i_g`](Self::i_g) is finite).
    #[inline(always)]
    #[doc(hidden)]
    pub fn at_g(&self) -> &PathPoint {
        &self.at_g
    }

    /// The slip mode of a collision that ends at the normal impulse `i_n`: forward
    /// sliding up to and including G, then the mode after G.
    #[inline(always)]
    pub fn kind_at(&self, i_n: Real) -> CollisionType {
        if i_n <= self.i_g {
            CollisionType::ForwardSliding
        } else {
            self.after
        }
    }

    /// The point of the path at the normal impulse `i_n ≥ 0`.
    #[inline(always)]
    pub fn at(&self, i_n: Real) -> PathPoint {
        if i_n <= self.i_g {
            let mut pt = self.slide.advance(&self.origin, i_n);
            if self.i_g.is_finite() {
                // v_t = v_t^A − g Ĩ_n = g (Ĩ_n(G) − Ĩ_n): exactly zero at G, never negative.
                pt.v.t = -self.slide.dv_t * (self.i_g - i_n);
            }
            pt
        } else {
            self.after_slope.advance(&self.at_g, i_n - self.i_g)
        }
    }

    /// The normal impulse at which the normal velocity reaches `target > v_n^A` on its
    /// way up (the last crossing: in Case 4, `h < 0`, `v_n` first decreases).
    ///
    /// Phase 1: `Ĩ_n = (target − v_n^A)/h` if `h > 0` and this is before G; else
    /// phase 2: `Ĩ_n = Ĩ_n(G) + (target − v_n(G)) / (dv_n/dĨ_n)`.
    /// `None` if the path never gets there (impossible for positive definite `W`).
    #[inline(always)]
    pub fn reach_normal_velocity(&self, target: Real) -> Option<Real> {
        if self.slide.dv_n > 0.0 {
            let x = (target - self.origin.v.n) / self.slide.dv_n;
            if x <= self.i_g {
                return Some(x);
            }
        }
        if !self.i_g.is_finite() || self.after_slope.dv_n <= 0.0 {
            return None;
        }
        let x = (target - self.at_g.v.n) / self.after_slope.dv_n;
        (x >= 0.0).then_some(self.i_g + x)
    }

    /// [`reach_normal_velocity`](Self::reach_normal_velocity)`(0)`, the end of
    /// compression, bit for bit, with `−v` for `0 − v` (a sign flip instead of a
    /// subtraction on the laws' dependency chain, issue 16): `0 − v_n^A = −v_n^A` for
    /// `v_n^A < 0`; after G, `0 − v_n(G)` and `−v_n(G)` differ only for `v_n(G) = +0`
    /// (`+0` against `−0`), a quotient `±0` that passes `x ≥ 0` and adds nothing to
    /// `Ĩ_n(G)`, which is never `−0` (`0`, `v_t^A/g` with both positive, or `+∞`).
    #[inline(always)]
    #[doc(hidden)]
    pub fn end_of_compression(&self) -> Option<Real> {
        debug_assert!(self.origin.v.n < 0.0, "the contact approaches");
        if self.slide.dv_n > 0.0 {
            let x = -self.origin.v.n / self.slide.dv_n;
            if x <= self.i_g {
                return Some(x);
            }
        }
        if !self.i_g.is_finite() || self.after_slope.dv_n <= 0.0 {
            return None;
        }
        let x = -self.at_g.v.n / self.after_slope.dv_n;
        (x >= 0.0).then_some(self.i_g + x)
    }

    /// The normal impulse at which the work of the normal impulse, counted from the point
    /// `from` (where `v_n ≥ 0`, rising), reaches `work ≥ 0`.
    ///
    /// On a phase starting at `v_n0` with slope `s`, the work after `x` is
    /// `v_n0 x + ½ s x² = R`, so `x = 2R / (v_n0 + √(v_n0² + 2 s R))` (the stable root).
    #[inline(always)]
    pub fn reach_normal_work(&self, from: &PathPoint, work: Real) -> Option<Real> {
        let mut remaining = work;
        let (mut p0, mut slope, mut room) = if from.i.n < self.i_g {
            (*from, self.slide, self.i_g - from.i.n)
        } else {
            (*from, self.after_slope, Real::INFINITY)
        };
        loop {
            let x = rising_root(p0.v.n, slope.dv_n, remaining)?;
            if x <= room {
                return Some(p0.i.n + x);
            }
            // The phase ends first: spend its work and go on after G.
            remaining -= room * (p0.v.n + 0.5 * slope.dv_n * room);
            p0 = self.at_g;
            slope = self.after_slope;
            room = Real::INFINITY;
        }
    }

    /// The phases travelled until the normal impulse `i_n` (an empty first phase, when
    /// the slip is zero from the start, is left out).
    #[inline(always)]
    pub fn phases_until(&self, i_n: Real) -> Phases {
        let end = self.at(i_n);
        let v_a = self.origin.v;
        if i_n <= self.i_g {
            Phases::one(v_a, CollisionType::ForwardSliding, end)
        } else if self.i_g == 0.0 {
            Phases::one(v_a, self.after, end)
        } else {
            Phases::two(
                v_a,
                CollisionType::ForwardSliding,
                self.at_g,
                self.after,
                end,
            )
        }
    }
}

/// The root `x ≥ 0` of `v0 x + ½ s x² = r` for `r ≥ 0` on a rising branch, in the form
/// without cancellation; `None` if there is none.
#[inline(always)]
#[doc(hidden)]
pub fn rising_root(v0: Real, s: Real, r: Real) -> Option<Real> {
    if r <= 0.0 {
        return Some(0.0);
    }
    let disc = v0 * v0 + 2.0 * s * r;
    if disc < 0.0 {
        return None;
    }
    let den = v0 + disc.sqrt();
    (den > 0.0).then(|| 2.0 * r / den)
}
