"""The solver contract: one call shape and one result type for every time integrator.

Every integrator of the equation of motion — the Cummins solvers of
:mod:`hybridwsi.cummins.solvers` (linear state space, direct convolution, RK4 with
state-dependent forces, batched), the hybrid rollout's lagged/corrected/implicit coupling
(:mod:`hybridwsi.surrogate.coupled`) and the reconstruction with a prescribed force
(:mod:`hybridwsi.diagnostic.reconstruct`) — is called as

    solve(system, u, z0, v0, dt, *, progress=False, **options) -> SolverResult

``system`` holds the matrices and force models (a :class:`~hybridwsi.cummins.CumminsSystem`, a
coupled step...), ``u`` the forcing known as a function of time [N, N m] on the solver's time
grid, ``z0, v0`` the initial state [m, rad; m/s, rad/s] and ``dt`` the step [s]; the options
are keyword-only. Like :func:`scipy.integrate.solve_ivp`, a solver never raises on a failed
integration (divergence, a force model that refuses the state): it returns a
:class:`SolverResult` with ``success=False`` and a one-line ``message``. The caller decides
what failure means: a command turns it into one ``error:`` line
(:meth:`SolverResult.raise_on_failure`), the partition ranking scores it as infinitely bad.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from hybridwsi.errors import SolverError

#: ``status`` of a completed integration and of a failed one (as SciPy's ``OdeResult``)
FINISHED, FAILED = 0, -1


@dataclass
class SolverResult:
    """Solution of a time integrator and what was evaluated to get it.

    Arrays are ``(n_time, n_dof)`` for one case and ``(n_case, n_time, n_dof)`` for a batch;
    units per DOF m or rad (``z``), m/s or rad/s (``v``), m/s² or rad/s² (``a``), N or N m
    (forces).

    Attributes
    ----------
    t : ndarray, shape (n_time,)
        Output times [s].
    z, v : ndarray
        Displacement and velocity.
    a : ndarray or None
        Acceleration, where the integrator computes it (None where it is formed afterwards
        from the equation of motion, e.g. the linear state-space solver).
    x : ndarray or None
        Internal states (radiation state space, force components' states), ``(..., n_time,
        n_states)``, where the integrator carries them.
    forces : dict of str to ndarray
        Force components evaluated on the solution, same shape as ``z`` (e.g. ``F_rad_mem``,
        ``F_hs``, ``F_components``; ``F_net``/``F_known`` of a hybrid rollout).
    success : bool
        The integration reached the last time.
    message : str
        What happened, in one line (the failure's cause when ``success`` is False).
    status : int
        :data:`FINISHED` (0) or :data:`FAILED` (-1).
    method : str
        The integrator (``"linear"``, ``"convolution"``, ``"rk4"``, ``"rk4_compiled"``,
        ``"lagged"``, ``"corrected"``, ``"implicit"``, ``"DOP853"``...).
    nfev : int
        Evaluations of the right-hand side (of the force models) made.
    counts : dict of str to int or ndarray
        Other counts: ``steps`` done, ``begin_step`` calls of stateful components,
        ``network`` evaluations, fixed-point ``iterations`` per step...
    failed : ndarray of bool or None
        Per case of a batch: that case failed (e.g. a hybrid case that blew up).
    """

    t: np.ndarray
    z: np.ndarray
    v: np.ndarray
    a: np.ndarray | None = None
    x: np.ndarray | None = None
    forces: dict[str, np.ndarray] = field(default_factory=dict)
    success: bool = True
    message: str = "the integration reached the end of the time grid"
    status: int = FINISHED
    method: str = ""
    nfev: int = 0
    counts: dict[str, Any] = field(default_factory=dict)
    failed: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.status = FINISHED if self.success else FAILED

    def raise_on_failure(self) -> SolverResult:
        """Self when the integration succeeded, else :class:`~hybridwsi.errors.SolverError`
        with :attr:`message` (for callers that cannot go on without a solution: the commands
        turn it into one ``error:`` line)."""
        if not self.success:
            raise SolverError(self.message)
        return self


def failure(t: np.ndarray, z: np.ndarray, v: np.ndarray, message: str, **kw: Any
            ) -> SolverResult:
    """A failed :class:`SolverResult` (the arrays as far as they were computed)."""
    return SolverResult(t, z, v, success=False, message=message, **kw)


def first_non_finite(t: np.ndarray, *arrays: np.ndarray | None) -> float | None:
    """The first time [s] at which any of ``arrays`` (time on axis -2, or axis 0 for 2-D
    arrays of one case) is not finite, or None when all are finite."""
    bad = np.zeros(t.size, dtype=bool)
    for arr in arrays:
        if arr is None or arr.size == 0 or np.all(np.isfinite(arr)):
            continue
        a = np.asarray(arr)
        rows = ~np.isfinite(a)
        time_axis = a.ndim - 2 if a.ndim >= 2 else 0
        other = tuple(i for i in range(a.ndim) if i != time_axis)
        bad |= rows.any(axis=other) if other else rows
    return float(t[np.flatnonzero(bad)[0]]) if bad.any() else None


class Integrator(Protocol):
    """The call shape every integrator of the package has (see the module doc)."""

    def __call__(self, system: Any, u: np.ndarray, z0: np.ndarray, v0: np.ndarray, dt: float,
                 *, progress: bool = False, **options: Any) -> SolverResult: ...
