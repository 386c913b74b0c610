"""Regression tests of a scene with pytest, on ricochet's run summary (`--summary`).

Run from the top of the repository (python3 -m pip install pytest):

    RICOCHET=target/release/ricochet pytest examples/pytest

RICOCHET is the ricochet program (default: `ricochet` on the PATH).
"""
import json
import math
import os
import pathlib
import subprocess

import pytest

RICOCHET = os.environ.get("RICOCHET", "ricochet")
SCENES = pathlib.Path(__file__).resolve().parents[2] / "scenes"


def summary(tmp_path, scene, *options):
    """Runs `scene` and returns its summary (a dict), written by `ricochet run --summary`."""
    out = tmp_path / "summary.json"
    subprocess.run(
        [RICOCHET, "run", str(SCENES / scene), "-q", "-o", str(tmp_path / "run.mcap"),
         "--summary", str(out), *options],
        check=True, stdout=subprocess.DEVNULL,
    )
    return json.loads(out.read_text())


@pytest.mark.parametrize("e", [0.5, 0.8, 0.95])
def test_bouncing_ball_against_its_closed_form(tmp_path, e):
    s = summary(tmp_path, "bouncing_ball.toml", "--e", str(e))
    assert s["format"] == "ricochet.summary" and s["version"] == 1
    assert s["audit"]["stop_reason"].startswith("t_end")
    # Dropped from 1 m: v = sqrt(2 g h) at the floor, e v after the first bounce, and the
    # n-th impact at t_n = t_1 (1 + 2 (e + … + e^(n-1))).
    v = math.sqrt(2 * 9.81 * 1.0)
    first = s["impacts"][0]
    assert first["v_a"]["n"] == pytest.approx(-v, rel=1e-9)
    assert first["v_s"]["n"] == pytest.approx(e * v, rel=1e-9)
    t1 = v / 9.81
    for n, impact in enumerate(s["impacts"][:5], start=1):
        expected = t1 * (1 + 2 * sum(e**k for k in range(1, n)))
        assert impact["t"] == pytest.approx(expected, rel=1e-9)


def test_energy_budget_and_balance(tmp_path):
    s = summary(tmp_path, "kane_double_pendulum.toml", "--max-drift", "1e-9")
    a, d = s["audit"], s["drift"]
    # The audit closes: E_end - E_0 = ΣΔE + works + drift.
    explained = a["impact_delta_e"] + a["applied_work"] + a["contact_work"] + a["prescribed_work"]
    assert a["energy_final"] - a["energy_initial"] == pytest.approx(
        explained + a["integration_drift"], abs=1e-12)
    # ΣΔE is the ledger's sum, and the budget holds.
    assert a["impact_delta_e"] == pytest.approx(sum(i["delta_e"] for i in s["impacts"]), abs=1e-12)
    assert d["relative"] <= d["max_drift"] == 1e-9


def test_numbers_read_back_bit_exact(tmp_path):
    # The summary of a run and the summary of its log (`inspect --json`), read by Python's
    # json module: the same floats, to the bit.
    s = summary(tmp_path, "rocking_block.toml")
    text = subprocess.run([RICOCHET, "inspect", str(tmp_path / "run.mcap"), "--json"],
                          check=True, capture_output=True, text=True).stdout
    assert json.loads(text) == s
    q = s["final_state"]["q"]
    assert all(float(repr(x)) == x for x in q)
