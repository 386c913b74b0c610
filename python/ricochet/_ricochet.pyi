"""Type stubs of the extension module ``ricochet._ricochet`` (Rust, pyo3).

Use it through the package: ``import ricochet``.
"""

from os import PathLike
from typing import Any, Mapping

import numpy as np
import numpy.typing as npt

__version__: str
#: The impact laws: ``newton``, ``kane-levinson``, ``poisson``, ``stronge``.
LAWS: list[str]
#: The integration methods: ``dopri5``, ``dop853``, ``rk4`` (event-driven), ``moreau-jean``.
METHODS: list[str]

def _solve_rows(
    w: npt.NDArray[np.float64],
    v_a: npt.NDArray[np.float64],
    e: npt.NDArray[np.float64],
    mu: npt.NDArray[np.float64],
    law: str | list[str],
    raise_errors: bool,
) -> dict[str, Any]:
    """The rows of :func:`ricochet.impact` (C-ordered float64 arrays of shapes (n, 3),
    (n, 2), (n,), (n,)); use :func:`ricochet.impact`."""

class Scene:
    """A scene: a model, its initial state and run settings, from a scene file (TOML, the
    format of ``scenes/README.md``).

    ``Scene.load(path)`` and ``Scene.from_toml(text)`` raise :class:`ricochet.SceneError`
    with the ``path``, ``line``, ``column`` and ``field`` of what is wrong, or an
    ``OSError`` for a file that cannot be read.
    """

    @staticmethod
    def load(path: str | PathLike[str]) -> Scene:
        """Reads and checks the scene file at ``path``."""

    @staticmethod
    def from_toml(text: str, path: str = "<string>") -> Scene:
        """Checks a scene given as text; ``path`` is the name its errors give."""

    @property
    def name(self) -> str:
        """The scene's ``name``."""
    @property
    def description(self) -> str:
        """The scene's ``description``."""
    @property
    def path(self) -> str:
        """The file it was read from."""
    @property
    def text(self) -> str:
        """The scene file's text, as read (a log stores it)."""
    @property
    def coordinates(self) -> list[str]:
        """The names of the generalized coordinates ``q``, e.g. ``ball.q``, ``rodA.q``."""
    @property
    def speeds(self) -> list[str]:
        """The names of the generalized speeds ``u``."""
    @property
    def q0(self) -> npt.NDArray[np.float64]:
        """The initial coordinates (m, rad)."""
    @property
    def u0(self) -> npt.NDArray[np.float64]:
        """The initial speeds (m/s, rad/s)."""
    @property
    def t_end(self) -> float:
        """The scene's end time (s)."""
    @property
    def output_rate(self) -> float:
        """The scene's output rate of samples (Hz)."""

    def run(
        self,
        *,
        t_end: float | None = None,
        law: str | None = None,
        e: float | None = None,
        mu: float | None = None,
        method: str | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        dt: float | None = None,
        max_drift: float | None = None,
        log: str | PathLike[str] | None = None,
    ) -> Run:
        """Simulates the scene as ``ricochet run`` does, and returns the :class:`Run`.

        The keywords override the scene's settings as ``ricochet run``'s options do:
        ``t_end`` (s), ``law`` (one of :data:`LAWS`), ``e`` (in [0, 1]), ``mu`` (≥ 0) for
        every contact, ``method`` (one of :data:`METHODS`), ``rtol``, ``atol`` (DOPRI5),
        ``dt`` (s, RK4 and Moreau–Jean), ``max_drift`` (the energy-drift budget, relative).
        A value out of range is a ``ValueError`` naming it.

        ``log``: the MCAP file to write (the log of ``ricochet run``, which Foxglove opens and
        :func:`read_log` reads back); nothing is written without it.

        Raises :class:`ricochet.SimulationError` when the run cannot start or fails on the
        way (``e.run``: the run until then; its log is finished),
        :class:`ricochet.DriftBudgetError` when it ends beyond its drift budget, and
        ``KeyboardInterrupt`` on Ctrl-C (the run stops at its next step and its log is
        finished). The run holds no lock on Python (the GIL is released).
        """

class Run:
    """A run: its samples as arrays, its ledger, its energy audit, its stop reason.

    The samples are those of the log's ``/state`` topic: one per output time (the scene's
    ``output_rate``), two at each impact instant (before and after the jump) and the
    final state.
    """

    #: The scene's name (``None`` for a log without its scene record).
    scene_name: str | None
    #: Sample times (s), shape ``(n,)``.
    t: npt.NDArray[np.float64]
    #: Generalized coordinates, shape ``(n, len(coordinates))`` (m, rad).
    q: npt.NDArray[np.float64]
    #: Generalized speeds, shape ``(n, len(speeds))`` (m/s, rad/s).
    u: npt.NDArray[np.float64]
    #: Kinetic energy ``½ uᵀ M u`` (J), shape ``(n,)``.
    kinetic: npt.NDArray[np.float64]
    #: Potential energy of gravity and springs (J), shape ``(n,)``.
    potential: npt.NDArray[np.float64]
    #: Total mechanical energy (J), shape ``(n,)``.
    total: npt.NDArray[np.float64]
    #: The names of the columns of ``q``.
    coordinates: list[str]
    #: The names of the columns of ``u``.
    speeds: list[str]
    #: The impact ledger, one array per field of the log's ``/impacts`` record, nested
    #: fields dotted (``t``, ``index``, ``pair``, ``law``, ``type``, ``case``, ``cause``,
    #: ``alpha``, ``w.mnn``, ``g`` … ``q``, ``v_a.n``, ``v_s.t``, ``i_n``, ``i_t``,
    #: ``support.i_n`` …, ``delta_u.<speed>``, ``energy_before``, ``delta_e``, ``work_n``,
    #: ``point.x``, ``normal.y``, …); absent values are NaN (α of an impact without
    #: approach speed; the support of all but a ``rocking_end``).
    #: ``pandas.DataFrame(run.impacts)`` is the ledger as a table.
    impacts: dict[str, np.ndarray]
    #: The energy audit (J): ``energy_initial``, ``energy_final``, ``impact_delta_e``
    #: (Eq. 29 summed), ``applied_work``, ``contact_work``, ``prescribed_work``,
    #: ``integration_drift`` (what the rest does not explain), and ``t_stop`` (s).
    #: ``None`` for a log of a run that did not finish.
    audit: dict[str, float] | None
    #: The work counters: ``impacts``, ``steps``, ``rejected_steps``,
    #: ``rhs_evaluations``, ``events``, ``state_samples``.
    counters: dict[str, int] | None
    #: ``t_end``, ``interrupted``, ``error``, or ``unfinished`` (a log without its audit).
    stop: str
    #: The stop reason in words, e.g. ``t_end: reached the end time``.
    stop_reason: str
    #: The drift against the run's energy scale: ``integration_drift`` (J),
    #: ``energy_scale`` (J), ``relative``, ``max_drift`` (the budget, or ``None``),
    #: ``broken``.
    drift: dict[str, Any] | None
    #: The run settings (``t_end``, ``output_rate``, ``integrator``, ``material_overrides``).
    settings: dict[str, Any] | None
    #: The log file the run wrote or was read from.
    log: str | None
    #: ``complete``, or how a log read ends (``truncated at byte …: …``).
    ending: str

def read_log(path: str | PathLike[str]) -> Run:
    """The run in an MCAP log written by ricochet (``ricochet run``, ``scene.run(log=…)``):
    every ``/state`` sample, every ``/impacts`` record, the audit.

    A log cut short (a killed run) gives what it holds, with a ``RuntimeWarning``
    (``ricochet repair`` makes the file whole); a damaged log raises
    :class:`ricochet.LogError` with what was read before (``e.run``) and the byte
    (``e.offset``); a file that is not a ricochet log raises :class:`ricochet.LogError`.
    """

def sweep(
    scene: Scene | str | PathLike[str],
    params: Mapping[str, Any],
    *,
    threads: int | None = None,
) -> dict[str, np.ndarray]:
    """Runs a scene over a grid of parameters on every core, as ``ricochet sweep`` does,
    and returns its table: one array per column of the CSV file, in its order, one row per
    run.

    ``params``: ``{name: values}``, each a sequence of numbers (``np.linspace(0, 1, 21)``),
    of names (``law``, ``method``), or a range string ``"start:stop:step"``; names ``e``,
    ``mu``, ``law``, ``method``, ``t_end``, ``rtol``, ``atol``, ``dt``, ``h_max``,
    ``q0.<coordinate>``, ``u0.<coordinate>``. The grid is their Cartesian product, the
    first parameter slowest. ``threads``: the number of threads (default: one per core,
    or ``RAYON_NUM_THREADS``); the table does not depend on it.

    Columns: ``run``, the parameters, ``stop``, ``impacts``, ``delta_e``, ``energy_0``,
    ``energy_end``, ``impact_prescribed_work``, ``damping_work``, ``applied_work``,
    ``drive_work``, ``contact_work``, ``drift`` (J), ``steps``, ``rejected``,
    ``rhs_evals``, ``events``, the final ``t``, ``q.<coordinate>``…, ``u.<speed>``…,
    ``stop_detail``. A run that fails is a row (``stop`` = ``error``, ``stop_detail``
    why); one that could not start has NaN numbers and −1 counters.
    ``pandas.DataFrame(ricochet.sweep(...))`` is the table.

    Raises ``ValueError`` for a bad parameter, ``KeyboardInterrupt`` on Ctrl-C (the runs
    under way stop at their next step). The GIL is released while the runs go.
    """
