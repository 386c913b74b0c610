"""The exceptions of ricochet.

Every error of the package is a :class:`RicochetError`; each is also the built-in
exception a caller would expect (a bad scene is a ``ValueError``, a failed run a
``RuntimeError``), so ``except ValueError`` catches it too.
"""

from __future__ import annotations

from typing import Any


class RicochetError(Exception):
    """Base class of ricochet's exceptions."""


class SceneError(RicochetError, ValueError):
    """A scene that cannot be loaded.

    ``str(e)`` is ``path:line:column: field: what is wrong``, as on the command line.
    """

    def __init__(
        self,
        message: str,
        *,
        path: str | None = None,
        line: int | None = None,
        column: int | None = None,
        field: str | None = None,
        detail: str | None = None,
    ) -> None:
        super().__init__(message)
        #: The scene file (or the ``path`` given to ``Scene.from_toml``).
        self.path = path
        #: The line of the error, from 1 (``None`` if it is not located).
        self.line = line
        #: The column, in characters, from 1.
        self.column = column
        #: The dotted path of the field, e.g. ``body["rodB"].joint.angle``.
        self.field = field
        #: What is wrong, without the location.
        self.detail = detail


class ImpactError(RicochetError, ValueError):
    """An impact problem that has no answer (``ricochet.impact(..., errors="raise")``)."""

    def __init__(self, message: str, *, row: int, detail: str) -> None:
        super().__init__(message)
        #: The index of the row, from 0.
        self.row = row
        #: The error of that row, as ``ricochet impact`` says it.
        self.detail = detail


class SimulationError(RicochetError, RuntimeError):
    """A run that could not start (its settings) or that failed on the way.

    For a run that failed on the way, ``run`` holds what it did until then (its samples,
    its impacts, the audit that says why it stopped) and ``t`` the time of the failure;
    its log, if one was asked for, is written and finished.
    """

    def __init__(self, message: str, *, run: Any = None, t: float | None = None) -> None:
        super().__init__(message)
        #: The run until it failed (``None`` when it could not start).
        self.run = run
        #: The simulated time of the failure (s).
        self.t = t


class DriftBudgetError(SimulationError):
    """A run that reached its end with an energy drift beyond its budget (``max_drift``).

    ``run`` holds the whole run; ``run.drift`` the figures.
    """


class LogError(RicochetError, ValueError):
    """A log that is not a ricochet log, or that is damaged.

    For a damaged log, ``run`` holds what was read before the damage and ``offset`` the
    byte where it is.
    """

    def __init__(
        self, message: str, *, run: Any = None, offset: int | None = None
    ) -> None:
        super().__init__(message)
        #: What was read before the damage (``None`` if nothing could be).
        self.run = run
        #: The byte offset of the damage.
        self.offset = offset
