"""Runs a scene, then plots its energy and its impacts with matplotlib and saves a PNG.

    python python/examples/energy_and_impacts.py [SCENE.toml] [-o OUT.png]

Default: the bouncing ball (scenes/bouncing_ball.toml, e = 0.8), whose impacts accumulate
at t∞ = 4.0637 s, after which it rests on the floor. The picture in
docs/python/energy_and_impacts.png was made with the defaults.
"""

from __future__ import annotations

import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

import ricochet

REPO = pathlib.Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=REPO / "scenes" / "bouncing_ball.toml")
    parser.add_argument("-o", "--output", default=REPO / "docs" / "python" / "energy_and_impacts.png")
    args = parser.parse_args()

    scene = ricochet.Scene.load(args.scene)
    run = scene.run()  # no log written: the arrays are in memory
    impacts = pd.DataFrame(run.impacts)
    print(f"{scene.name}: {len(run.t)} samples, {len(impacts)} impacts, stop: {run.stop_reason}")
    print(impacts[["t", "type", "case", "i_n", "i_t", "delta_e"]].head(10).to_string(index=False))

    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 6), constrained_layout=True)
    top.plot(run.t, run.kinetic, label="kinetic")
    top.plot(run.t, run.potential, label="potential")
    top.plot(run.t, run.total, label="total", color="black", linewidth=1.5)
    for t in impacts["t"]:
        top.axvline(t, color="grey", linewidth=0.4, alpha=0.5)
    top.set_ylabel("energy [J]")
    top.set_title(f"{scene.name}: energy, and the impacts (grey lines)")
    top.legend(loc="upper right")

    colours = {"sticking": "tab:green", "reverse_sliding": "tab:red", "forward_sliding": "tab:blue"}
    for kind, rows in impacts.groupby("type"):
        bottom.scatter(rows["t"], rows["i_n"], s=14, color=colours.get(kind, "grey"), label=f"$I_n$, {kind}")
    bottom.scatter(impacts["t"], impacts["delta_e"], s=10, marker="x", color="black", label=r"$\Delta E$ (Eq. 29)")
    bottom.axhline(0.0, color="grey", linewidth=0.5)
    bottom.set_yscale("symlog", linthresh=1e-3)
    bottom.set_xlabel("t [s]")
    bottom.set_ylabel(r"$I_n$ [N·s], $\Delta E$ [J]")
    bottom.legend(loc="upper right", fontsize="small")
    drift = run.audit["integration_drift"]
    bottom.set_title(
        f"{len(impacts)} impacts, ΣΔE = {impacts['delta_e'].sum():.4g} J, integration drift {drift:.1e} J"
    )
    out = pathlib.Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")
    assert np.isfinite(run.total).all()


if __name__ == "__main__":
    main()
