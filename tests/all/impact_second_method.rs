//! A second method for the laws on Routh's path: integrate the impulse-plane equations
//! numerically with I_n as the independent variable (Routh, Keller) and compare with the
//! closed forms on many random cases.
//!
//! The marcher below knows only `dv = W dI` (Eqs. 22–23), Coulomb's law (the friction
//! opposes the slip; a stuck contact stays stuck if the cone can hold it), and each law's
//! end condition evaluated on the integrated state (Newton: `v_n = e V`; Poisson:
//! `I_n = (1+e) I_c`; Stronge: the normal work, integrated by quadrature, reaches
//! `(1 − e²) W_c`). It does not use g, h, p, q, Table 1, or any closed form. It steps in
//! I_n; within a step the slip mode is fixed, so the state is advanced exactly, and the
//! slip reversal and end events are located by bisection on the sub-step.

use nalgebra::Matrix2;
use proptest::prelude::*;
use ricochet::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law};

#[derive(Clone, Copy, Debug)]
struct State {
    i_n: f64,
    i_t: f64,
    v_n: f64,
    v_t: f64,
    work_n: f64,
    work_t: f64,
}

struct Marcher {
    w: Matrix2<f64>,
    mu: f64,
}

impl Marcher {
    /// dI_t/dI_n by Coulomb's law in the current slip state.
    fn friction_rate(&self, s: &State) -> f64 {
        let (nt, tt) = (self.w[(0, 1)], self.w[(1, 1)]);
        if s.v_t > 0.0 {
            -self.mu
        } else if s.v_t < 0.0 {
            self.mu
        } else if tt == 0.0 {
            0.0 // no tangential mobility: the least friction impulse
        } else if nt.abs() <= self.mu * tt {
            -nt / tt // stuck: the friction needed to keep v_t = 0 is inside the cone
        } else if nt > 0.0 {
            -self.mu // the slip starts forward
        } else {
            self.mu // the slip starts backward
        }
    }

    /// The state after the normal impulse x with the friction rate r held fixed.
    fn advance(&self, s: &State, x: f64, r: f64) -> State {
        let (nn, nt, tt) = (self.w[(0, 0)], self.w[(0, 1)], self.w[(1, 1)]);
        let (dvn, dvt) = (nn + nt * r, nt + tt * r);
        State {
            i_n: s.i_n + x,
            i_t: s.i_t + r * x,
            v_n: s.v_n + dvn * x,
            v_t: s.v_t + dvt * x,
            work_n: s.work_n + x * (s.v_n + 0.5 * dvn * x),
            work_t: s.work_t + r * x * (s.v_t + 0.5 * dvt * x),
        }
    }

    /// Bisection for the first x in (0, h] where `ev` becomes true.
    fn locate(&self, s: &State, h: f64, r: f64, ev: &dyn Fn(&State) -> bool) -> f64 {
        let (mut a, mut b) = (0.0, h);
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                break;
            }
            if ev(&self.advance(s, m, r)) {
                b = m
            } else {
                a = m
            }
        }
        b
    }

    /// Marches from `s` until `done` becomes true; returns the state there, or `None` if
    /// it has not ended after two million steps (the step doubling every thousand).
    fn march(&self, mut s: State, h0: f64, done: &dyn Fn(&State) -> bool) -> Option<State> {
        let mut h = h0;
        for k in 0..2_000_000u64 {
            if k > 0 && k % 1000 == 0 {
                h *= 2.0; // the end is far: coarsen (the march is exact within a mode)
            }
            let r = self.friction_rate(&s);
            let next = self.advance(&s, h, r);
            let reversal =
                |t: &State| (s.v_t > 0.0 && t.v_t <= 0.0) || (s.v_t < 0.0 && t.v_t >= 0.0);
            let x_end = done(&next).then(|| self.locate(&s, h, r, done));
            let x_rev = reversal(&next).then(|| self.locate(&s, h, r, &reversal));
            match (x_end, x_rev) {
                (Some(xe), Some(xr)) if xr < xe => {
                    s = self.advance(&s, xr, r);
                    s.v_t = 0.0;
                }
                (Some(xe), _) => return Some(self.advance(&s, xe, r)),
                (None, Some(xr)) => {
                    s = self.advance(&s, xr, r);
                    s.v_t = 0.0;
                }
                (None, None) => s = next,
            }
        }
        None
    }
}

/// Solves a problem in the paper's frame (v_t^A ≥ 0) by marching; `None` if it never
/// ends (a jam).
fn march_law(law: Law, pb: &ImpactProblem) -> Option<State> {
    let w = Matrix2::new(pb.w.nn, pb.w.nt, pb.w.nt, pb.w.tt);
    let m = Marcher { w, mu: pb.mu };
    let start = State {
        i_n: 0.0,
        i_t: 0.0,
        v_n: pb.v_a.n,
        v_t: pb.v_a.t,
        work_n: 0.0,
        work_t: 0.0,
    };
    let big_v = -pb.v_a.n;
    let h0 = big_v / pb.w.nn / 1000.0;
    let e = pb.e;
    match law {
        Law::Newton => m.march(start, h0, &|s| s.v_n >= e * big_v),
        Law::Poisson | Law::Stronge => {
            let c = m.march(start, h0, &|s| s.v_n >= 0.0)?;
            if law == Law::Poisson {
                let target = (1.0 + e) * c.i_n;
                m.march(c, h0, &|s| s.i_n >= target)
            } else {
                let target = (1.0 - e * e) * c.work_n;
                m.march(c, h0, &|s| s.work_n >= target)
            }
        }
        Law::KaneLevinson => unreachable!("not a path law"),
    }
}

fn spd() -> impl Strategy<Value = ImpactMatrix> {
    (-3.0..3.0f64, 0.0..6.0f64, 0.0..std::f64::consts::PI).prop_map(|(l1, k, th)| {
        let (l1, l2) = (10f64.powf(l1), 10f64.powf(l1 + k));
        let (c, s) = (th.cos(), th.sin());
        ImpactMatrix::new(
            c * c * l1 + s * s * l2,
            c * s * (l1 - l2),
            s * s * l1 + c * c * l2,
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn closed_forms_agree_with_the_march(
        w in spd(),
        vn in -3.0..2.0f64,
        vt in prop_oneof![1 => Just(0.0), 6 => (-3.0..2.0f64).prop_map(|x| 10f64.powf(x))],
        e in prop_oneof![1 => Just(0.0), 1 => Just(1.0), 6 => 0.0..=1.0f64],
        mu in prop_oneof![1 => Just(0.0), 6 => 0.0..3.0f64],
        law in prop_oneof![Just(Law::Newton), Just(Law::Poisson), Just(Law::Stronge)],
    ) {
        let pb = ImpactProblem::new(w, ContactVelocity::new(-(10f64.powf(vn)), vt), e, mu);
        let out = impact::solve(law, &pb).unwrap();
        let m = march_law(law, &pb).expect("the march ends");
        let iscale = m.i_n.abs() + m.i_t.abs();
        let vscale = pb.v_a.n.abs() + pb.v_a.t.abs() + (w.nn.abs() + w.nt.abs() + w.tt.abs()) * iscale;
        let escale = iscale * vscale;
        prop_assert!((out.impulse.n - m.i_n).abs() <= 1e-8 * iscale, "I_n {} vs {}", out.impulse.n, m.i_n);
        prop_assert!((out.impulse.t - m.i_t).abs() <= 1e-8 * iscale, "I_t {} vs {}", out.impulse.t, m.i_t);
        prop_assert!((out.v_s.n - m.v_n).abs() <= 1e-8 * vscale);
        prop_assert!((out.v_s.t - m.v_t).abs() <= 1e-8 * vscale, "v_t^S {} vs {}", out.v_s.t, m.v_t);
        prop_assert!((out.work_n - m.work_n).abs() <= 1e-8 * escale, "W_n {} vs {}", out.work_n, m.work_n);
        prop_assert!((out.work_t - m.work_t).abs() <= 1e-8 * escale, "W_t {} vs {}", out.work_t, m.work_t);
    }
}

#[test]
fn table_2_rows_by_the_march() {
    // The Sect. 5 pendulum (W and v^A to the printed digits): the march reproduces the
    // printed v_t^S of the Newton rows 1–3 and 5 (row 4's print is an error, see
    // tests/all/paper_table_2.rs).
    let w = ImpactMatrix::new(0.33652, -0.50710, 0.81345);
    for (e, mu, vts) in [
        (0.5, 0.2, -0.078),
        (0.5, 0.5, -0.070),
        (0.3, 0.5, -0.005),
        (0.9, 0.5, -0.200),
    ] {
        let pb = ImpactProblem::new(w, ContactVelocity::new(-0.26840, 0.53435), e, mu);
        let m = march_law(Law::Newton, &pb).unwrap();
        assert!(
            (m.v_t - vts).abs() <= 1e-3,
            "e {e} μ {mu}: {} vs {vts}",
            m.v_t
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    /// Singular W (rank 1, as for one degree of freedom): where the closed forms solve the
    /// impact the march agrees; where they report a jam, the march never ends.
    #[test]
    fn singular_w_agrees_with_the_march(
        tt in -2.0..2.0f64,
        k in -1.5..1.5f64,
        neg in any::<bool>(),
        vt in 0.0..3.0f64,
        e in 0.0..=1.0f64,
        mu in 0.0..2.0f64,
        law in prop_oneof![Just(Law::Newton), Just(Law::Poisson), Just(Law::Stronge)],
    ) {
        let (tt, k) = (10f64.powf(tt), if neg { -(10f64.powf(k)) } else { 10f64.powf(k) });
        let w = ImpactMatrix::new(tt * k * k, tt * k, tt);
        let pb = ImpactProblem::new(w, ContactVelocity::new(-1.0, vt), e, mu);
        let m = march_law(law, &pb);
        match impact::solve(law, &pb) {
            Ok(out) => {
                let m = m.expect("the march ends where the closed form solves");
                let iscale = m.i_n.abs() + m.i_t.abs();
                prop_assert!((out.impulse.n - m.i_n).abs() <= 1e-8 * iscale, "I_n {} vs {}", out.impulse.n, m.i_n);
                prop_assert!((out.impulse.t - m.i_t).abs() <= 1e-8 * iscale, "I_t {} vs {}", out.impulse.t, m.i_t);
            }
            Err(err) => {
                prop_assert!(matches!(err, impact::ImpactError::Jam { .. }), "{err}");
                // A jam never ends: the march may only "end" by rounding, after an impulse
                // of order 1/ε times the frictionless one (v_n drifts by ε per step).
                let frictionless = (1.0 + e) / w.nn;
                prop_assert!(m.is_none_or(|m| m.i_n > 1e10 * frictionless),
                    "the march ended at {m:?} where the closed form jams");
            }
        }
    }
}
