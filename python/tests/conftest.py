"""Shared fixtures: the repository's folders and the ``ricochet`` command-line program,
whose answers the package must equal."""

from __future__ import annotations

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SCENES = REPO / "scenes"


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    """The ``ricochet`` binary: ``$RICOCHET_BIN``, else ``target/release/ricochet``."""
    path = pathlib.Path(os.environ.get("RICOCHET_BIN", REPO / "target" / "release" / "ricochet"))
    if not path.is_file():
        pytest.fail(
            f"the ricochet binary {path} is missing: build it (cargo build --release) or set "
            "RICOCHET_BIN; these tests compare the package with it"
        )
    return path


def run_cli(cli: pathlib.Path, *args: str, input: bytes | None = None) -> subprocess.CompletedProcess:
    """Runs ``ricochet ARGS`` and returns the finished process (its output as bytes)."""
    return subprocess.run([str(cli), *args], input=input, capture_output=True, check=False)
