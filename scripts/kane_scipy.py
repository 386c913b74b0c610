#!/usr/bin/env python3
"""Kane's double pendulum (scenes/kane_double_pendulum.toml) for 5 s in SciPy, written
independently of ricochet: a second determination of the run that issue 16 times.

The model is derived here by hand (absolute angles q1, q2 of two uniform rods, mass 3 kg,
length 2 m, inertia 1 kg m^2 about the centre of mass, pivot at the origin, the floor
through the tip's initial position); the impacts follow Newton's hypothesis on Routh's
path, integrated segment by segment in the normal impulse (no closed form of the paper
is used); the accumulation of bounces is followed bounce by bounce until the rebound
speed is below 1e-11 m/s; the persistent contact slides with Coulomb friction (the
normal force from the constraint's acceleration) until the slip stops, then sticks.

    python scripts/kane_scipy.py [--ricochet target/release/ricochet] [--repeat N]

prints the impacts, the end of the accumulation, the instant the slip stops and the
state at 5 s, and with --ricochet compares them with the ricochet run at rtol 1e-10
(its summary JSON). Needs numpy and scipy.
"""

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp

M_ROD, L, I_ROD, G = 3.0, 2.0, 1.0, 9.81
E_REST, MU = 0.5, 0.2
Q0 = np.array([math.radians(20.0), math.radians(30.0)])
U0 = np.array([-0.1, -0.2])
FLOOR_Y = -L * (math.cos(Q0[0]) + math.cos(Q0[1]))
T_END = 5.0
RTOL, ATOL = 1e-12, 1e-14  # of SciPy here (--rtol)


def mass(q):
    c = 6.0 * math.cos(q[0] - q[1])
    return np.array([[16.0, c], [c, 4.0]])


def forces(q, u):
    """Q − c: gravity minus the velocity-product terms."""
    s = 6.0 * math.sin(q[0] - q[1])
    return np.array(
        [-9.0 * G * math.sin(q[0]) - s * u[1] ** 2, -3.0 * G * math.sin(q[1]) + s * u[0] ** 2]
    )


def tip(q):
    return L * np.array([math.sin(q[0]) + math.sin(q[1]), -math.cos(q[0]) - math.cos(q[1])])


def jac(q):
    """Rows: tangent (x) and normal (y) of the tip."""
    return L * np.array(
        [[math.cos(q[0]), math.cos(q[1])], [math.sin(q[0]), math.sin(q[1])]]
    )


def jdot_u(q, u):
    """d/dt(J) u: the tip's velocity-product acceleration (tangent, normal)."""
    return L * np.array(
        [-math.sin(q[0]) * u[0] ** 2 - math.sin(q[1]) * u[1] ** 2,
         math.cos(q[0]) * u[0] ** 2 + math.cos(q[1]) * u[1] ** 2]
    )


def gap(q):
    return tip(q)[1] - FLOOR_Y


def energy(q, u):
    return 0.5 * u @ mass(q) @ u + M_ROD * G * (-3.0 * math.cos(q[0]) - math.cos(q[1]))


def free(t, y):
    q, u = y[:2], y[2:]
    return np.concatenate([u, np.linalg.solve(mass(q), forces(q, u))])


def newton_impact(q, u, e=E_REST):
    """Newton's hypothesis on Routh's path: v_n ends at −e v_n^A. The contact velocity
    moves along dv/dI_n = W (1, −μ s) while sliding (s = sign v_t), and with the
    sticking ratio while stuck; each segment is linear in I_n, so its end is exact."""
    J = jac(q)
    Minv = np.linalg.inv(mass(q))
    W = J @ Minv @ J.T  # [[tt, tn], [nt, nn]]
    v = J @ u  # (v_t, v_n)
    target = -e * v[1]
    i_n, i_t = 0.0, 0.0
    for _ in range(4):
        if v[0] != 0.0:
            s = math.copysign(1.0, v[0])
            di = np.array([-MU * s, 1.0])  # dI/dI_n: (dI_t, dI_n)
        else:
            # Sticking needs dI_t/dI_n = −W_tn/W_tt (keeps v_t = 0) within the cone.
            r = -W[0, 1] / W[0, 0]
            if abs(r) <= MU:
                di = np.array([r, 1.0])
            else:
                di = np.array([MU * math.copysign(1.0, r), 1.0])
        dv = W @ di  # (dv_t, dv_n) per unit I_n
        x_end = (target - v[1]) / dv[1]  # where v_n reaches its target
        x, stops = x_end, False
        if v[0] != 0.0 and dv[0] * v[0] < 0.0 and -v[0] / dv[0] < x_end:
            x, stops = -v[0] / dv[0], True  # the slip stops first
        v = v + dv * x
        i_n += x
        i_t += di[0] * x
        if not stops:
            break
        v[0] = 0.0
    du = Minv @ J.T @ np.array([i_t, i_n])
    return u + du, i_n, i_t


def sliding_rhs(s):
    def f(t, y):
        q, u = y[:2], y[2:]
        Minv = np.linalg.inv(mass(q))
        J = jac(q)
        d = J[1] - MU * s * J[0]  # direction of the contact force per unit λ
        a0 = Minv @ forces(q, u)
        lam = -(jdot_u(q, u)[1] + J[1] @ a0) / (J[1] @ Minv @ d)
        return np.concatenate([u, a0 + Minv @ d * lam])

    return f


def normal_force(q, u, s):
    Minv = np.linalg.inv(mass(q))
    J = jac(q)
    d = J[1] - MU * s * J[0]
    a0 = Minv @ forces(q, u)
    return -(jdot_u(q, u)[1] + J[1] @ a0) / (J[1] @ Minv @ d)


def tip_normal_accel(q, u):
    """The tip's normal acceleration in free flight."""
    return jdot_u(q, u)[1] + jac(q)[1] @ np.linalg.solve(mass(q), forces(q, u))


def slide_direction(q, u):
    """At rest (u = 0, tip closed): the direction s = ±1 of a consistent slide (λ > 0 and
    the tip accelerating along s), or 0 if sticking holds (the force in the cone)."""
    J = jac(q)
    lam = np.linalg.solve(J.T, -forces(q, u))  # Jᵀ (F_t, F_n) = −(Q − c): holding forces
    if lam[1] > 0 and abs(lam[0]) <= MU * lam[1]:
        return 0, lam
    for s in (1.0, -1.0):
        a = sliding_rhs(s)(0.0, np.concatenate([q, u]))[2:]
        if normal_force(q, u, s) > 0 and s * (J[0] @ a) > 0:
            return s, lam
    raise SystemExit("no consistent mode at rest")


def simulate(h_rest):
    """The run to T_END. h_rest: ricochet's accumulation rule (an impact whose hop would
    stay below h_rest is made plastic, e = 0, with its friction); 0 follows the bounces
    until their rebound speed is below 1e-11 m/s."""
    t, y = 0.0, np.concatenate([Q0, U0])
    impacts, notes = [], []
    # The tip touches the floor at t = 0, approaching: the first impact now.
    while True:
        u, i_n, i_t = newton_impact(y[:2], y[2:])
        v_n = jac(y[:2])[1] @ u
        a_n = tip_normal_accel(y[:2], u)
        if h_rest > 0 and a_n < 0 and v_n <= math.sqrt(2.0 * -a_n * h_rest):
            u, i_n, i_t = newton_impact(y[:2], y[2:], e=0.0)
            v_n = 0.0
        y = np.concatenate([y[:2], u])
        impacts.append((t, i_n, i_t))
        if v_n < 1e-11:
            break
        ev = lambda t, y: gap(y[:2])
        ev.terminal, ev.direction = True, -1
        sol = solve_ivp(free, (t, T_END), y, method="DOP853", rtol=RTOL, atol=ATOL,
                        events=ev, first_step=1e-9)
        if sol.status != 1:
            raise SystemExit("no impact found")
        t, y = sol.t_events[0][0], sol.y_events[0][0]
    notes.append(("accumulation ends", t))
    # Remove the rebound left (below 1e-11 m/s) along the normal: the contact closes.
    J = jac(y[:2])
    Minv = np.linalg.inv(mass(y[:2]))
    y[2:] -= Minv @ J[1] * ((J[1] @ y[2:]) / (J[1] @ Minv @ J[1]))
    s = math.copysign(1.0, (jac(y[:2]) @ y[2:])[0])
    lam = None
    while t < T_END:
        # Persistent contact, sliding along s until the slip stops.
        stop = lambda t, y: (jac(y[:2]) @ y[2:])[0]
        stop.terminal, stop.direction = True, -s
        lift = lambda t, y, s=s: normal_force(y[:2], y[2:], s)
        lift.terminal = True
        sol = solve_ivp(sliding_rhs(s), (t, T_END), y, method="DOP853", rtol=RTOL,
                        atol=ATOL, events=[stop, lift])
        if sol.status != 1:
            notes.append(("slides to the end", T_END))
            return impacts, notes, sol.y[:, -1], None
        if len(sol.t_events[1]):
            raise SystemExit(f"the tip lifts at {sol.t_events[1][0]}")
        t, y = sol.t_events[0][0], sol.y_events[0][0].copy()
        # Two constraints on two coordinates: with v_t = v_n = 0 the rods are at rest.
        y[2:] = 0.0
        s, lam = slide_direction(y[:2], y[2:])
        notes.append(("the slip stops; " + ("sticks" if s == 0 else f"slides along {s:+.0f} t"), t))
        if s == 0:
            break
    return impacts, notes, y, lam


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ricochet", help="the ricochet binary, to compare with its run")
    ap.add_argument("--repeat", type=int, default=1, help="time N runs")
    ap.add_argument("--exact-accumulation", action="store_true",
                    help="follow the bounces to 1e-11 m/s instead of ricochet's rule")
    ap.add_argument("--rtol", type=float, default=RTOL, help="SciPy's rtol (atol = rtol / 100)")
    args = ap.parse_args()
    globals().update(RTOL=args.rtol, ATOL=args.rtol / 100)
    # ricochet's h_rest = 100 (atol + rtol L) at rtol 1e-10, atol 1e-12, L = 1 m (the
    # segment's bounding radius).
    h_rest = 0.0 if args.exact_accumulation else 100.0 * (1e-12 + 1e-10 * 1.0)
    t0 = time.perf_counter()
    for _ in range(args.repeat):
        impacts, notes, y, lam = simulate(h_rest)
    dt = (time.perf_counter() - t0) / args.repeat
    print(f"{len(impacts)} impacts, {dt * 1e3:.1f} ms per run")
    for k, (t, i_n, i_t) in enumerate(impacts[:12]):
        print(f"  {k:3d}  t = {t:.12f}  I_n = {i_n:.10e}  I_t = {i_t:.10e}")
    for what, t in notes:
        print(f"  t = {t:.12f}: {what}")
    print(f"  q(5 s) = {y[:2].tolist()}, holding force (F_t, F_n) = {lam}")
    if args.ricochet:
        with tempfile.TemporaryDirectory() as d:
            out = subprocess.run(
                [args.ricochet, "run", "scenes/kane_double_pendulum.toml", "--t-end", "5",
                 "--rtol", "1e-10", "-q", "-o", f"{d}/k.mcap", "--summary", f"{d}/s.json"],
                capture_output=True, text=True)
            if out.returncode != 0:
                sys.exit(out.stderr)
            summary = json.load(open(f"{d}/s.json"))
        ri = summary["impacts"]
        if len(ri) != len(impacts):
            sys.exit(f"ricochet: {len(ri)} impacts, here {len(impacts)}")
        dt_imp = max(abs(a["t"] - b[0]) for a, b in zip(ri, impacts))
        # ricochet's tangent is −x here (its I_t has the other sign): compare magnitudes.
        di = max(max(abs(a["i_n"] - b[1]), abs(abs(a["i_t"]) - abs(b[2])))
                 for a, b in zip(ri, impacts))
        dq = max(abs(a - b) for a, b in zip(summary["final_state"]["q"], y[:2]))
        print(f"ricochet (rtol 1e-10): {summary['audit']['counters']['impacts']} impacts; "
              f"max |Δt| of the impacts {dt_imp:.1e} s, max |ΔI| {di:.1e} N s, "
              f"max |Δq(5 s)| {dq:.1e} rad")


if __name__ == "__main__":
    main()
