"""``Scene`` and ``Run``: a run's arrays equal its MCAP log's ``/state`` and ``/impacts``
messages (read with the ``mcap`` package, not with ricochet), ``read_log`` gives the same
``Run`` back, bad scenes and bad keywords raise with their line, field or keyword, a
failed run raises with what it did, and Ctrl-C stops a run with its log finished."""

from __future__ import annotations

import json
import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pandas as pd
import pytest
from mcap.reader import make_reader

import ricochet
from conftest import SCENES


def bits(x) -> np.ndarray:
    return np.asarray(x, dtype=np.float64).view(np.int64)


def messages(path: pathlib.Path, topic: str) -> list[dict]:
    """The JSON messages of ``topic`` in the log, in order (the ``mcap`` package)."""
    with open(path, "rb") as f:
        return [json.loads(m.data) for _, _, m in make_reader(f).iter_messages(topics=[topic])]


@pytest.mark.parametrize(
    "scene", ["kane_double_pendulum", "bouncing_ball", "rocking_block", "wagon_curb"]
)
def test_a_runs_arrays_are_its_logs_messages(tmp_path, scene) -> None:
    log = tmp_path / "run.mcap"
    run = ricochet.Scene.load(SCENES / f"{scene}.toml").run(t_end=1.5, log=str(log))
    assert run.log == str(log) and run.stop == "t_end"
    states = messages(log, "/state")
    n = len(states)
    assert n == len(run.t) == run.counters["state_samples"]
    assert n > 300
    assert run.q.shape == (n, len(run.coordinates)) and run.u.shape == (n, len(run.speeds))
    assert np.array_equal(bits(run.t), bits([s["t"] for s in states]))
    assert np.array_equal(bits(run.q), bits([s["q"] for s in states]))
    assert np.array_equal(bits(run.u), bits([s["u"] for s in states]))
    for name in ("kinetic", "potential", "total"):
        assert np.array_equal(bits(getattr(run, name)), bits([s["energy"][name] for s in states])), name
    # The ledger: every field of every /impacts record.
    records = pd.json_normalize(messages(log, "/impacts"))
    assert len(records) == len(run.impacts["t"]) == run.counters["impacts"] > 0
    table = pd.DataFrame(run.impacts)
    for column in records.columns:
        if column == "delta_u":
            got = table[[f"delta_u.{s}" for s in run.speeds]].to_numpy()
            assert np.array_equal(bits(got), bits(np.stack(records["delta_u"].to_list())))
        elif not pd.api.types.is_numeric_dtype(records[column]):
            assert table[column].tolist() == records[column].tolist(), column
        else:
            assert np.array_equal(bits(table[column]), bits(records[column].astype(float))), column
    # The log read back by the package is the same run.
    again = ricochet.read_log(log)
    assert again.ending == "complete" and again.log == str(log)
    for name in ("t", "q", "u", "kinetic", "potential", "total"):
        assert np.array_equal(bits(getattr(again, name)), bits(getattr(run, name))), name
    assert again.impacts.keys() == run.impacts.keys()
    for name, column in run.impacts.items():
        assert np.array_equal(column, again.impacts[name], equal_nan=column.dtype.kind == "f"), name
    assert (again.audit, again.counters, again.drift, again.settings) == (
        run.audit,
        run.counters,
        run.drift,
        run.settings,
    )
    assert (again.coordinates, again.speeds, again.stop, again.stop_reason) == (
        run.coordinates,
        run.speeds,
        run.stop,
        run.stop_reason,
    )


def test_a_run_without_a_log_writes_nothing_and_is_the_same_run(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    scene = ricochet.Scene.load(SCENES / "bouncing_ball.toml")
    run = scene.run(e=0.5, t_end=2.0)
    assert os.listdir(tmp_path) == []
    assert run.log is None
    logged = scene.run(e=0.5, t_end=2.0, log="ball.mcap")
    assert os.listdir(tmp_path) == ["ball.mcap"]
    assert np.array_equal(run.q, logged.q) and run.audit == logged.audit
    # The overrides took: e = 0.5 in the ledger and the settings record, the first impact
    # at the closed form's speed, the rebound speed e √(2 g h0).
    collision = run.impacts["cause"] == "collision"
    assert collision.sum() > 10 and (run.impacts["e"][collision] == 0.5).all()
    # The impact that ends the accumulation is plastic (ARCHITECTURE.md, the contacts stage).
    assert run.impacts["cause"][-1] == "accumulation_end" and run.impacts["e"][-1] == 0.0
    assert run.settings["material_overrides"]["e"] == 0.5 and run.settings["t_end"] == 2.0
    v1 = np.sqrt(2 * 9.81 * 1.0)
    assert abs(run.impacts["v_s.n"][0] - 0.5 * v1) < 1e-9


def test_the_energy_audit_closes() -> None:
    run = ricochet.Scene.load(SCENES / "kane_double_pendulum.toml").run()
    a = run.audit
    explained = a["impact_delta_e"] + a["applied_work"] + a["contact_work"] + a["prescribed_work"]
    assert a["energy_final"] - a["energy_initial"] - explained == a["integration_drift"]
    assert abs(a["integration_drift"]) < 1e-6
    assert a["energy_initial"] == run.total[0] and a["energy_final"] == run.total[-1]
    assert run.impacts["delta_e"].sum() == pytest.approx(a["impact_delta_e"], abs=1e-15)
    assert run.coordinates == ["rodA.q", "rodB.q"] == run.speeds


BAD_SCENE = """\
version = 1
name = "bad"
run = { t_end = 1.0 }

[[body]]
name = "ball"
mass = -0.1
inertia = 0.0005
joint = { type = "prismatic", axis = [0.0, 1.0], position = 1.1, speed = 0.0 }
"""


def test_a_bad_scene_raises_with_its_line_and_field(tmp_path) -> None:
    with pytest.raises(ricochet.SceneError) as raised:
        ricochet.Scene.from_toml(BAD_SCENE)
    e = raised.value
    assert (e.path, e.line, e.column, e.field) == ("<string>", 7, 8, 'body["ball"].mass')
    assert str(e).startswith('<string>:7:8: body["ball"].mass: ') and "mass" in e.detail
    assert isinstance(e, ValueError)
    path = tmp_path / "bad.toml"
    path.write_text(BAD_SCENE.replace("version = 1", "version = 1\n# a comment"))
    with pytest.raises(ricochet.SceneError, match=rf'^{path}:8:8: body\["ball"\].mass: ') as raised:
        ricochet.Scene.load(path)
    assert raised.value.line == 8
    with pytest.raises(ricochet.SceneError, match="<string>:1:") as raised:
        ricochet.Scene.from_toml("version = ")
    assert raised.value.line == 1
    with pytest.raises(FileNotFoundError):
        ricochet.Scene.load(tmp_path / "missing.toml")


def test_bad_keywords_raise_naming_them() -> None:
    scene = ricochet.Scene.load(SCENES / "bouncing_ball.toml")
    with pytest.raises(ValueError, match=r"^`e` must lie in \[0, 1\], not 1.5$"):
        scene.run(e=1.5)
    with pytest.raises(ValueError, match="^`t_end` must be a positive number of seconds"):
        scene.run(t_end=-1.0)
    with pytest.raises(ValueError, match="^method: .*`euler`"):
        scene.run(method="euler")
    with pytest.raises(ValueError, match="^law: unknown impact law `newtn`"):
        scene.run(law="newtn")
    with pytest.raises(TypeError):
        scene.run(2.0)  # keywords only


def test_a_failed_run_raises_with_what_it_did(tmp_path) -> None:
    # Tolerances of 1e-300: DOPRI5's error norm is not finite at the first step.
    scene = ricochet.Scene.load(SCENES / "bouncing_ball.toml")
    log = tmp_path / "failed.mcap"
    with pytest.raises(ricochet.SimulationError) as raised:
        scene.run(rtol=1e-300, atol=1e-300, log=log)
    e = raised.value
    assert isinstance(e, RuntimeError)
    assert str(e) == "bouncing_ball: stopped at t = 0 s, failed: non-finite state or derivative"
    assert e.t == 0.0 and e.run.stop == "error" and len(e.run.t) == 1
    assert e.run.stop_reason == "error: non-finite state or derivative at t = 0"
    # Its log is finished, and says so.
    logged = ricochet.read_log(log)
    assert logged.ending == "complete" and logged.stop_reason == e.run.stop_reason


def test_a_broken_drift_budget_raises_with_the_run() -> None:
    scene = ricochet.Scene.load(SCENES / "kane_double_pendulum.toml")
    with pytest.raises(ricochet.DriftBudgetError) as raised:
        scene.run(max_drift=1e-300, rtol=1e-4)
    run = raised.value.run
    assert run.stop == "t_end" and run.drift["broken"] and run.drift["max_drift"] == 1e-300
    assert scene.run(max_drift=1.0).drift["broken"] is False


def test_ctrl_c_stops_a_run_and_finishes_its_log(tmp_path) -> None:
    log = tmp_path / "long.mcap"
    script = textwrap.dedent(
        f"""
        import sys, ricochet
        # A child started from a background job (`cmd &` in a script) inherits SIGINT
        # ignored, and Python then installs no KeyboardInterrupt handler: restore it.
        import signal
        signal.signal(signal.SIGINT, signal.default_int_handler)
        scene = ricochet.Scene.load({str(SCENES / "rimless_wheel.toml")!r})
        print("running", flush=True)
        try:
            scene.run(t_end=1e5, log={str(log)!r})
        except KeyboardInterrupt:
            print("interrupted", flush=True)
            sys.exit(3)
        """
    )
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "running"
    time.sleep(1.0)
    started = time.monotonic()
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=30)
    assert time.monotonic() - started < 5.0
    assert child.returncode == 3 and out.strip() == "interrupted"
    run = ricochet.read_log(log)
    assert run.ending == "complete" and run.stop == "interrupted"
    assert 0.0 < run.t[-1] < 1e5 and run.audit["t_stop"] == run.t[-1]


def test_logs_cut_short_damaged_or_foreign(tmp_path) -> None:
    log = tmp_path / "whole.mcap"
    whole = ricochet.Scene.load(SCENES / "rocking_block.toml").run(log=log)
    data = log.read_bytes()
    # Cut short (a killed run): what it holds, with a warning; its samples are the run's.
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.warns(RuntimeWarning, match="truncated at byte"):
        part = ricochet.read_log(cut)
    assert part.stop == "unfinished" and part.audit is None and part.ending.startswith("truncated")
    n = len(part.t)
    assert 0 < n < len(whole.t)
    assert np.array_equal(bits(part.q), bits(whole.q[:n])) and np.array_equal(part.t, whole.t[:n])
    # Damaged (one byte changed): LogError with the byte and what was read before it.
    bad = bytearray(data)
    bad[len(data) // 3] ^= 0xFF
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(bad))
    with pytest.raises(ricochet.LogError, match="damaged at byte") as raised:
        ricochet.read_log(damaged)
    assert 0 < raised.value.offset <= len(data) // 3
    m = len(raised.value.run.t)
    assert 0 < m < len(whole.t) and np.array_equal(raised.value.run.q, whole.q[:m])
    # Not a log at all.
    foreign = tmp_path / "foreign.mcap"
    foreign.write_text("not a log")
    with pytest.raises(ricochet.LogError, match="not an MCAP file"):
        ricochet.read_log(foreign)
    with pytest.raises(FileNotFoundError):
        ricochet.read_log(tmp_path / "missing.mcap")


def test_a_log_that_cannot_be_created_is_an_os_error(tmp_path) -> None:
    scene = ricochet.Scene.load(SCENES / "bouncing_ball.toml")
    with pytest.raises(FileNotFoundError) as raised:
        scene.run(log=tmp_path / "no" / "such" / "folder.mcap")
    assert raised.value.filename == str(tmp_path / "no" / "such" / "folder.mcap")
    assert "(os error" not in str(raised.value)


def test_a_nonholonomic_scene_names_its_speeds() -> None:
    """The wagon: four coordinates, two generalized speeds with names of their own."""
    run = ricochet.Scene.load(SCENES / "wagon_curb.toml").run(t_end=0.5)
    assert run.coordinates == ["wagon.x", "wagon.y", "wagon.theta", "front.q"]
    assert run.speeds == ["wagon.vx_body", "wagon.omega"]
    assert run.q.shape[1] == 4 and run.u.shape[1] == 2
