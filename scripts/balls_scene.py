#!/usr/bin/env python3
"""Writes a scene of N free balls falling on a floor (issue 15: a broad phase, pairs in
linear memory). The balls stand in a row 0.5 m apart (they never touch one another) at
heights spread by the golden ratio between 0.5 and 1.5 m, so that they land at different
instants (the first at 0.29 s, the last at 0.53 s).

    python3 scripts/balls_scene.py 2000 > /tmp/balls2000.toml
    /usr/bin/time -v ricochet run /tmp/balls2000.toml --t-end 0.6 -o /tmp/balls.mcap
"""
import sys


def scene(n: int, t_end: float = 0.6) -> str:
    out = [
        "version = 1",
        f'name = "balls{n}"',
        f'description = "{n} free balls falling on a floor at different instants"',
        "gravity = [0.0, -9.81]",
        "[run]",
        f"t_end = {t_end}",
        "output_rate = 20.0",
        "[contact]",
        "e = 0.5",
        "mu = 0.1",
        "[[obstacle]]",
        'name = "floor"',
        'type = "halfspace"',
        "point = [0.0, 0.0]",
        "normal = [0.0, 1.0]",
    ]
    for k in range(n):
        y = 0.5 + (k * 0.6180339887498949) % 1.0
        out += [
            "[[body]]",
            f'name = "b{k}"',
            "mass = 1.0",
            "inertia = 0.01",
            f'joint = {{ type = "planar", x = {0.5 * k!r}, y = {y!r} }}',
            "[[body.shape]]",
            'type = "ball"',
            "radius = 0.1",
        ]
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    sys.stdout.write(scene(int(sys.argv[1]) if len(sys.argv) > 1 else 2000))
