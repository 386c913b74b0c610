//! Issue 11: exact through an accumulation of impacts and the contact-mode changes after it,
//! on Kane's double pendulum with e = 0.5, μ = 0.2 for 5 s: 15 impacts accumulate at
//! t∞ ≈ 0.18966 s, the tip slides, stops at 1.33192 s, slides back and sticks for good at
//! 3.57899 s.
//!
//! Two independent determinations: the convergence of the state with the tolerance (a
//! defining property of a method that is exact to its tolerance), and a second integration
//! of the sliding phase from the equations of motion derived here.

use ricochet::sim::{ImpactCause, MaterialOverride, PairMode, Recorder, RunSummary, Simulation};

fn run(rtol: f64, t_end: f64) -> (Recorder, RunSummary) {
    let mut scene = ricochet::scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/kane_double_pendulum.toml"
    ))
    .unwrap();
    scene.settings.t_end = t_end;
    scene.settings.integrator.rtol = rtol;
    scene.settings.integrator.atol = 1e-14;
    let overrides = MaterialOverride {
        e: Some(0.5),
        mu: Some(MU),
        ..Default::default()
    };
    let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
    let mut rec = Recorder {
        keep_samples: true,
        ..Default::default()
    };
    let summary = sim.run(&scene.initial, &mut rec, None);
    assert!(
        matches!(summary.stop, ricochet::sim::StopReason::EndTime),
        "rtol {rtol}: {}",
        summary.stop
    );
    (rec, summary)
}

/// The 5 s state converges like the free flight: the differences between successive
/// tolerances fall in proportion to the tolerance (they fell like √rtol while the end of
/// the accumulation cancelled the last hop with a pulling impulse and no friction).
#[test]
fn the_state_after_an_accumulation_converges_with_the_tolerance() {
    let rtols = [1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13];
    let ends: Vec<Vec<f64>> = (rtols.iter())
        .map(|&r| run(r, 5.0).1.state.q.iter().copied().collect())
        .collect();
    let mut diffs = Vec::new();
    for k in 0..rtols.len() - 1 {
        let d = (0..2)
            .map(|i| (ends[k][i] - ends[k + 1][i]).abs())
            .fold(0.0, f64::max);
        println!(
            "rtol {:.0e} → {:.0e}: |Δq| = {d:.2e} rad",
            rtols[k],
            rtols[k + 1]
        );
        diffs.push(d);
    }
    // Proportional to the tolerance, down to 1e-12.
    for k in 0..4 {
        assert!(
            diffs[k] <= rtols[k],
            "rtol {:.0e}: |Δq| = {:.2e}",
            rtols[k],
            diffs[k]
        );
    }
    // Three decades of tolerance, three decades of difference (√rtol would give 1.5).
    assert!(diffs[0] / diffs[3] >= 100.0, "{diffs:?}");
    // The last two agree to 1e-10 rad.
    assert!(diffs[4] <= 1e-10, "{diffs:?}");
}

const M: f64 = 3.0;
const L: f64 = 2.0;
const G: f64 = 9.81;
const MU: f64 = 0.2;

/// The accelerations of the pendulum with its tip sliding on the floor in the direction
/// `s = sign(ẋ_tip)`, and the normal force `N`, from Lagrange's equations derived here
/// (absolute angles q1, q2 from the downward vertical; uniform rods of mass M, length L):
///
/// ```text
/// M(q) = m l² [[4/3, ½ cos(q1 − q2)], [½ cos(q1 − q2), 1/3]]
/// Q    = [−½ m l² sin(q1 − q2) q̇2² − 3/2 m g l sin q1,  ½ m l² sin(q1 − q2) q̇1² − ½ m g l sin q2]
/// tip  = (l sin q1 + l sin q2, −l cos q1 − l cos q2)
/// M q̈ = Q + (J_y − μ s J_x)ᵀ N,   ÿ_tip = J_y q̈ + l cos q1 q̇1² + l cos q2 q̇2² = 0
/// ```
fn sliding(q: [f64; 2], u: [f64; 2], s: f64) -> ([f64; 2], f64) {
    let (c, sn) = ((q[0] - q[1]).cos(), (q[0] - q[1]).sin());
    let ml2 = M * L * L;
    let (m11, m12, m22) = (4.0 / 3.0 * ml2, 0.5 * ml2 * c, ml2 / 3.0);
    let det = m11 * m22 - m12 * m12;
    let solve = |b: [f64; 2]| {
        [
            (m22 * b[0] - m12 * b[1]) / det,
            (m11 * b[1] - m12 * b[0]) / det,
        ]
    };
    let force = [
        -0.5 * ml2 * sn * u[1] * u[1] - 1.5 * M * G * L * q[0].sin(),
        0.5 * ml2 * sn * u[0] * u[0] - 0.5 * M * G * L * q[1].sin(),
    ];
    let jx = [L * q[0].cos(), L * q[1].cos()];
    let jy = [L * q[0].sin(), L * q[1].sin()];
    let jdot_y = L * q[0].cos() * u[0] * u[0] + L * q[1].cos() * u[1] * u[1];
    let a0 = solve(force);
    let b0 = solve([jy[0] - MU * s * jx[0], jy[1] - MU * s * jx[1]]);
    let n = (-jdot_y - (jy[0] * a0[0] + jy[1] * a0[1])) / (jy[0] * b0[0] + jy[1] * b0[1]);
    ([a0[0] + n * b0[0], a0[1] + n * b0[1]], n)
}

fn tip_vx(q: [f64; 2], u: [f64; 2]) -> f64 {
    L * (q[0].cos() * u[0] + q[1].cos() * u[1])
}

/// One classical Runge–Kutta step of the sliding equations.
fn rk4(y: [f64; 4], h: f64, s: f64) -> [f64; 4] {
    let f = |y: [f64; 4]| {
        let (a, _) = sliding([y[0], y[1]], [y[2], y[3]], s);
        [y[2], y[3], a[0], a[1]]
    };
    let add = |y: [f64; 4], k: [f64; 4], c: f64| std::array::from_fn(|i| y[i] + c * k[i]);
    let k1 = f(y);
    let k2 = f(add(y, k1, h / 2.0));
    let k3 = f(add(y, k2, h / 2.0));
    let k4 = f(add(y, k3, h));
    std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

/// Slides from `(t, y)` in the direction `s` until the tip stops (ẋ_tip = 0), with fixed
/// steps `h` and the last one found by bisection: the time and the state at the stop.
/// Asserts that the normal force stays positive.
fn slide_until_stop(t: f64, y: [f64; 4], s: f64, h: f64) -> (f64, [f64; 4]) {
    let (t0, mut y) = (t, y);
    for k in 0.. {
        // The time from the step count: a sum of 10⁵ steps would round to 1e-11 s.
        let t = t0 + k as f64 * h;
        let next = rk4(y, h, s);
        assert!(
            sliding([y[0], y[1]], [y[2], y[3]], s).1 > 0.0,
            "N ≤ 0 at {t}"
        );
        if tip_vx([next[0], next[1]], [next[2], next[3]]) * s <= 0.0 {
            let (mut lo, mut hi) = (0.0, h);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                let y_mid = rk4(y, mid, s);
                if tip_vx([y_mid[0], y_mid[1]], [y_mid[2], y_mid[3]]) * s > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
                if hi - lo <= 1e-16 {
                    break;
                }
            }
            return (t + hi, rk4(y, hi, s));
        }
        y = next;
    }
    unreachable!()
}

/// The friction and normal forces `(F, N)` that hold the tip still at `q` with `q̇ = 0`
/// (the mechanism is then locked: two constraints on two coordinates):
/// `J_xᵀ F + J_yᵀ N = ∂V/∂q`.
fn holding_forces(q: [f64; 2]) -> (f64, f64) {
    let dv = [1.5 * M * G * L * q[0].sin(), 0.5 * M * G * L * q[1].sin()];
    let (jx, jy) = (
        [L * q[0].cos(), L * q[1].cos()],
        [L * q[0].sin(), L * q[1].sin()],
    );
    // [jx0 jy0; jx1 jy1] [F; N] = dv
    let det = jx[0] * jy[1] - jy[0] * jx[1];
    (
        (dv[0] * jy[1] - jy[0] * dv[1]) / det,
        (jx[0] * dv[1] - dv[0] * jx[1]) / det,
    )
}

/// A second determination of the sliding phase: from the state just after the impact that
/// ends the accumulation, the tip on the floor is a one-constraint system, integrated here
/// from its own equations; the slip stops, reverses (sticking would need more than μ N),
/// stops again and sticks. The times of both stops and the state at the stick agree with
/// the run's.
#[test]
fn the_sliding_phase_agrees_with_an_independent_integration() {
    let (rec, summary) = run(1e-12, 5.0);
    // The impact that ends the accumulation, and the state just after it.
    let closing = (rec.impacts.iter())
        .find(|i| i.cause == ImpactCause::AccumulationEnd)
        .unwrap();
    assert!(closing.outcome.impulse.n > 0.0);
    let after = (rec.samples.iter()).rfind(|s| s.0 == closing.t).unwrap();
    let (q0, u0) = ([after.1[0], after.1[1]], [after.2[0], after.2[1]]);
    // The tip is on the floor and does not move normally: the coordinates are the ones of
    // the equations above.
    let floor = -3.6114360491406945;
    assert!((-L * (q0[0].cos() + q0[1].cos()) - floor).abs() <= 1e-9);
    assert!((L * (q0[0].sin() * u0[0] + q0[1].sin() * u0[1])).abs() <= 1e-12);

    let h = 2e-5;
    let s1 = tip_vx(q0, u0).signum();
    let (t_stop, y_stop) = slide_until_stop(closing.t, [q0[0], q0[1], u0[0], u0[1]], s1, h);
    // At the stop, sticking needs |F| > μ N: the slip reverses. Sliding back is consistent:
    // the tip accelerates in the direction −s1 with friction opposing it.
    let q_stop = [y_stop[0], y_stop[1]];
    let (f, n) = holding_forces(q_stop);
    assert!(n > 0.0 && f.abs() > MU * n, "F {f}, N {n}");
    let (a, _) = sliding(q_stop, [0.0, 0.0], -s1);
    assert!(L * (q_stop[0].cos() * a[0] + q_stop[1].cos() * a[1]) * -s1 > 0.0);
    let (t_stick, y_stick) = slide_until_stop(t_stop, y_stop, -s1, h);
    let q_stick = [y_stick[0], y_stick[1]];
    let (f, n) = holding_forces(q_stick);
    assert!(n > 0.0 && f.abs() < MU * n, "F {f}, N {n}: it sticks");

    // The run: a reversal, then sticking for good, at the same times and state.
    let tr = &rec.transitions;
    let reversal = (tr.iter())
        .find(|t| t.from == PairMode::Sliding && t.to == PairMode::Sliding)
        .expect("the reversal is reported");
    let stick = (tr.iter())
        .find(|t| t.to == PairMode::Sticking)
        .expect("the stick is reported");
    assert_eq!(tr.last().unwrap().t, stick.t, "{tr:?}");
    let q_end = &summary.state.q;
    let dq = (q_end[0] - q_stick[0])
        .abs()
        .max((q_end[1] - q_stick[1]).abs());
    println!(
        "slip stop {t_stop:.12} (run {:.12}, {:.1e} s); stick {t_stick:.12} (run {:.12}, \
         {:.1e} s); state at the stick {dq:.1e} rad",
        reversal.t,
        reversal.t - t_stop,
        stick.t,
        stick.t - t_stick
    );
    assert!(
        (reversal.t - t_stop).abs() <= 1e-9,
        "{} vs {t_stop}",
        reversal.t
    );
    assert!(
        (stick.t - t_stick).abs() <= 1e-7,
        "{} vs {t_stick}",
        stick.t
    );
    assert!(dq <= 1e-9, "{dq}");
    // The same with half the step: the second determination is converged.
    let (t_stop2, y2) = slide_until_stop(closing.t, [q0[0], q0[1], u0[0], u0[1]], s1, h / 2.0);
    let (t_stick2, _) = slide_until_stop(t_stop2, y2, -s1, h / 2.0);
    println!(
        "half step: slip stop {:.1e} s, stick {:.1e} s",
        t_stop2 - t_stop,
        t_stick2 - t_stick
    );
    assert!((t_stop2 - t_stop).abs() <= 1e-12 && (t_stick2 - t_stick).abs() <= 1e-10);
    // The samples show the slip direction flip at the reversal.
    let modes: Vec<_> = (rec.sample_modes.iter())
        .filter(|(t, _)| *t > closing.t && *t < stick.t)
        .map(|(t, m)| (*t < reversal.t, m[0]))
        .collect();
    assert!(modes.iter().all(|(_, m)| *m == PairMode::Sliding));
}
