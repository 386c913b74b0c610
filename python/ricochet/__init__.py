"""ricochet: planar multibody simulation with event-driven rigid impacts, from Python.

The library itself (Rust, through pyo3), with numpy arrays in and out:

- :func:`impact`: the impact laws of Djerassi (2009) over arrays of problems, the numbers
  of ``ricochet impact`` bit for bit;
- :class:`Scene`: a scene file loaded (``Scene.load``, ``Scene.from_toml``) and run
  (``scene.run(...)``), giving a :class:`Run`: samples, ledger, audit as arrays;
- :func:`read_log`: the same :class:`Run` from an MCAP log;
- :func:`sweep`: a grid of runs on every core, as a table of arrays (the rows of
  ``ricochet sweep``'s CSV file).

Errors are exceptions (:mod:`ricochet._errors`); nothing is written to disk unless a
``log=`` path is given.
"""

from __future__ import annotations

from typing import Any, Iterable, Literal, Sequence

import numpy as np

from . import _ricochet
from ._errors import (
    DriftBudgetError,
    ImpactError,
    LogError,
    RicochetError,
    SceneError,
    SimulationError,
)
from ._ricochet import LAWS, METHODS, Run, Scene, read_log, sweep

__version__: str = _ricochet.__version__

__all__ = [
    "LAWS",
    "METHODS",
    "DriftBudgetError",
    "ImpactError",
    "ImpactResult",
    "LogError",
    "RicochetError",
    "Run",
    "Scene",
    "SceneError",
    "SimulationError",
    "impact",
    "read_log",
    "sweep",
]

#: The names of the collision types, by their number in Table 2 of the paper (0: no answer).
_TYPE_NAMES = np.array(["", "sticking", "reverse_sliding", "forward_sliding"])


class ImpactResult:
    """The answers of :func:`impact`, one row per problem.

    Arrays of length ``n`` (``v_s`` is ``(n, 2)``): ``i_n``, ``i_t`` (N·s), ``v_s``
    (``[v_n^S, v_t^S]``, m/s), ``delta_e``, ``work_n``, ``work_t`` (J), ``type``
    (``sticking``, ``reverse_sliding``, ``forward_sliding``), ``case`` (the sign case 1–5
    of Table 1), ``alpha`` (``v_t^A/|v_n^A|``), ``g``, ``h``, ``p``, ``q`` (Eq. 35, in the
    frame where ``v_t^A ≥ 0``); ``error``, ``None`` or why the row has no answer; ``ok``,
    the rows that have one. A row without an answer holds NaN, type ``""`` and case 0.
    """

    __slots__ = (
        "i_n",
        "i_t",
        "v_s",
        "delta_e",
        "work_n",
        "work_t",
        "type",
        "case",
        "alpha",
        "g",
        "h",
        "p",
        "q",
        "error",
        "ok",
    )

    i_n: np.ndarray
    i_t: np.ndarray
    v_s: np.ndarray
    delta_e: np.ndarray
    work_n: np.ndarray
    work_t: np.ndarray
    type: np.ndarray
    case: np.ndarray
    alpha: np.ndarray
    g: np.ndarray
    h: np.ndarray
    p: np.ndarray
    q: np.ndarray
    error: np.ndarray
    ok: np.ndarray

    def __init__(self, columns: dict[str, Any]) -> None:
        n = len(columns["i_n"])
        for name in ("i_n", "i_t", "v_s", "delta_e", "work_n", "work_t", "alpha"):
            setattr(self, name, columns[name])
        for name in ("g", "h", "p", "q"):
            setattr(self, name, columns[name])
        self.type = _TYPE_NAMES[columns["type_number"]]
        self.case = columns["case"].astype(np.int64)
        self.error = np.full(n, None, dtype=object)
        for row, message in columns["errors"]:
            self.error[row] = message
        # A row has an answer exactly when it has a type (1, 2 or 3).
        self.ok = columns["type_number"] != 0

    def __len__(self) -> int:
        return len(self.i_n)

    def to_dict(self) -> dict[str, np.ndarray]:
        """The columns as a dict of 1-D arrays (``v_s`` split into ``v_s.n``, ``v_s.t``),
        for ``pandas.DataFrame(result.to_dict())``."""
        out: dict[str, np.ndarray] = {}
        for name in self.__slots__:
            if name == "v_s":
                out["v_s.n"] = self.v_s[:, 0]
                out["v_s.t"] = self.v_s[:, 1]
            else:
                out[name] = getattr(self, name)
        return out

    def __repr__(self) -> str:
        failed = int(len(self) - np.count_nonzero(self.ok))
        return f"ImpactResult({len(self)} rows, {failed} without an answer)"


def impact(
    w: Any,
    v_a: Any,
    e: Any,
    mu: Any,
    law: str | Sequence[str] = "newton",
    *,
    errors: Literal["coerce", "raise"] = "coerce",
) -> ImpactResult:
    """Solves impact problems, one per row, as ``ricochet impact`` solves one per line.

    ``w``: ``(n, 3)`` rows ``[m_nn, m_nt, m_tt]`` of ``W = J M⁻¹ Jᵀ`` (Eq. 20);
    ``v_a``: ``(n, 2)`` rows ``[v_n^A, v_t^A]`` (``v_n^A < 0``); ``e`` (in [0, 1]) and ``mu``
    (≥ 0): scalars or length ``n``; ``law``: ``newton`` (Routh's path with the bisection
    of the collision time, Table 1), ``kane-levinson``, ``poisson``, ``stronge``, or one
    name per row. A single problem may be given as 1-D ``w`` and ``v_a``.

    The numbers are those of ``ricochet impact`` bit for bit (the same library call). A
    problem without an answer (``W`` not positive definite, ``v_n^A ≥ 0``, ``e ∉ [0, 1]``,
    ``μ < 0``, a non-finite number, an answer beyond the doubles) is a row whose
    ``error`` says why, as ``ricochet impact``'s error line does; with
    ``errors="raise"``, the first such row raises :class:`ImpactError` (its ``row``).
    The rows are solved with the GIL released.
    """
    if errors not in ("coerce", "raise"):
        raise ValueError(f'errors must be "coerce" or "raise", not {errors!r}')
    w = np.asarray(w, dtype=np.float64)
    v_a = np.asarray(v_a, dtype=np.float64)
    if w.ndim == 1 and v_a.ndim == 1:
        w, v_a = w[np.newaxis, :], v_a[np.newaxis, :]
    if w.ndim != 2 or w.shape[1] != 3:
        raise ValueError(f"w must have the shape (n, 3), not {w.shape}")
    n = w.shape[0]
    if v_a.shape != (n, 2):
        raise ValueError(f"v_a must have the shape ({n}, 2), not {v_a.shape}")

    def per_row(name: str, x: Any) -> np.ndarray:
        a = np.asarray(x, dtype=np.float64)
        if a.ndim > 1 or (a.ndim == 1 and a.shape[0] != n):
            raise ValueError(f"{name} must be a number or have the shape ({n},), not {a.shape}")
        return np.ascontiguousarray(np.broadcast_to(a, (n,)))

    laws: str | list[str] = law if isinstance(law, str) else list(map(str, law))
    columns = _ricochet._solve_rows(
        np.ascontiguousarray(w),
        np.ascontiguousarray(v_a),
        per_row("e", e),
        per_row("mu", mu),
        laws,
        errors == "raise",
    )
    return ImpactResult(columns)
