"""``ricochet.sweep``: the table equals the CSV file of ``ricochet sweep`` over the same
grid, row for row and bit for bit, whatever the threads; a run that cannot start is a row."""

from __future__ import annotations

import csv
import io

import numpy as np
import pandas as pd
import pytest

import ricochet
from conftest import SCENES, run_cli


def cli_table(cli, tmp_path, scene: str, params: list[str]) -> tuple[list[str], list[list[str]]]:
    out = tmp_path / "sweep.csv"
    args = ["sweep", str(SCENES / f"{scene}.toml"), "-o", str(out)]
    for p in params:
        args += ["--param", p]
    done = run_cli(cli, *args)
    assert done.returncode in (0, 1), done.stderr
    lines = [line for line in out.read_text().splitlines() if not line.startswith("#")]
    rows = list(csv.reader(io.StringIO("\n".join(lines))))
    return rows[0], rows[1:]


def assert_same_table(table: dict[str, np.ndarray], columns: list[str], rows: list[list[str]]) -> None:
    assert list(table) == columns
    for j, name in enumerate(columns):
        got = table[name]
        want = [r[j] for r in rows]
        assert len(got) == len(want), name
        if got.dtype.kind == "f":
            # Empty fields (a run that did not start) are NaN; the others read back exactly.
            w = np.array([float(x) if x else np.nan for x in want])
            assert np.array_equal(np.isnan(got), np.isnan(w)), name
            same = ~np.isnan(w)
            assert np.array_equal(got[same].view(np.int64), w[same].view(np.int64)), name
        elif got.dtype.kind == "i":
            assert got.tolist() == [int(x) if x else -1 for x in want], name
        else:
            assert got.tolist() == want, name


def test_a_sweep_equals_the_command_lines_csv(cli, tmp_path) -> None:
    e = np.linspace(0.0, 1.0, 21)
    params = {"e": e, "mu": [0, 0.3], "t_end": [1.2], "law": ["newton", "poisson"]}
    scene = ricochet.Scene.load(SCENES / "kane_double_pendulum.toml")
    table = ricochet.sweep(scene, params)
    columns, rows = cli_table(
        cli,
        tmp_path,
        "kane_double_pendulum",
        ["e=" + ",".join(repr(float(x)) for x in e), "mu=0,0.3", "t_end=1.2", "law=newton,poisson"],
    )
    assert len(rows) == 21 * 2 * 2
    assert_same_table(table, columns, rows)
    # The grid as nested loops, the first parameter slowest; e.g. 0.15000000000000002.
    assert np.array_equal(table["e"], np.repeat(e, 4))
    assert table["law"].tolist() == ["newton", "poisson"] * 42
    assert (table["stop"] == "t_end").all() and (table["impacts"] > 0).all()
    # One thread gives the same table; so does the scene's path.
    one = ricochet.sweep(SCENES / "kane_double_pendulum.toml", params, threads=1)
    for name, column in table.items():
        assert np.array_equal(column, one[name]), name
    frame = pd.DataFrame(table)
    assert frame.shape == (84, len(columns))


def test_failed_runs_are_rows(cli, tmp_path) -> None:
    # The ball put 5 m inside the floor (issue 12): an error row without numbers; the ball
    # 1e300 m up: a run that fails at its first step, with its numbers.
    params = {"q0.ball.q": [1.1, -5, 1e300], "t_end": "0.5:1:0.5"}
    table = ricochet.sweep(SCENES / "bouncing_ball.toml", params)
    columns, rows = cli_table(cli, tmp_path, "bouncing_ball", ["q0.ball.q=1.1,-5,1e300", "t_end=0.5:1:0.5"])
    assert_same_table(table, columns, rows)
    assert table["stop"].tolist() == ["t_end", "t_end", "error", "error", "error", "error"]
    assert np.isnan(table["energy_end"][2]) and table["steps"][2] == -1
    assert "overlap" in table["stop_detail"][2]
    assert table["steps"][4] >= 0 and table["t"][4] == 0.0


def test_bad_parameters_raise() -> None:
    scene = ricochet.Scene.load(SCENES / "bouncing_ball.toml")
    with pytest.raises(ValueError, match="e must lie in"):
        ricochet.sweep(scene, {"e": [0.5, 1.5]})
    with pytest.raises(ValueError, match="unknown parameter `gravity`"):
        ricochet.sweep(scene, {"gravity": [1.0]})
    with pytest.raises(ValueError, match="no coordinate `ball.x`"):
        ricochet.sweep(scene, {"q0.ball.x": [1.0]})
    with pytest.raises(ValueError, match="`mu` has no values"):
        ricochet.sweep(scene, {"mu": []})
    with pytest.raises(ValueError, match="threads"):
        ricochet.sweep(scene, {"mu": [0]}, threads=0)
    with pytest.raises(TypeError):
        ricochet.sweep(scene, {"mu": [object()]})


def test_ctrl_c_stops_a_sweep() -> None:
    import signal
    import subprocess
    import sys
    import textwrap
    import time

    script = textwrap.dedent(
        f"""
        import sys, numpy as np, ricochet
        # A child started from a background job (`cmd &` in a script) inherits SIGINT
        # ignored, and Python then installs no KeyboardInterrupt handler: restore it.
        import signal
        signal.signal(signal.SIGINT, signal.default_int_handler)
        print("running", flush=True)
        try:
            ricochet.sweep({str(SCENES / "rimless_wheel.toml")!r}, {{"e": np.linspace(0, 1, 50), "t_end": [1e4]}})
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
    out, _ = child.communicate(timeout=60)
    assert (child.returncode, out.strip()) == (3, "interrupted")
    assert time.monotonic() - started < 5.0
