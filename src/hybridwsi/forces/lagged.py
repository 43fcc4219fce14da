"""A force component coupled one step lagged: what a loosely coupled code (or a lagged network)
does with it.

:class:`LaggedComponent` wraps another (memoryless or time-only) component and holds its force
at the start of every solver step over the whole step (a zero-order hold, as
:class:`~hybridwsi.forces.moordyn.MoorDynForce` couples MoorDyn): ``F(t) = F_inner(t_k, z_k,
ż_k)`` for ``t`` in ``[t_k, t_k + Δt)``. The force recorded at a sample is then the inner
component's own force there, so the history's components still sum to ``F_ext``. Used to
observe whether a component the diagnostic calls learnable with a lagged network stays stable
when it is lagged (docs/OC3_HYWIND.md "The diagnostic on the design-fidelity components").
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError, SolverError
from hybridwsi.forces.base import KnownComponent


class LaggedComponent(KnownComponent):
    """``inner``'s force held over each solver step from the step's start (module docstring).

    Parameters
    ----------
    inner : KnownComponent
        A component without internal states (``n_states = 0``) and without its own stepping.
    """

    def __init__(self, inner: KnownComponent) -> None:
        if not isinstance(inner, KnownComponent):
            raise InputError(f"LaggedComponent wraps a KnownComponent, got {type(inner).__name__}")
        if inner.n_states or inner.stepped:
            raise InputError(f"{inner.describe()}: a component with internal states or its own "
                             "stepping cannot be lagged by a hold")
        self.inner = inner
        self.name = f"lagged_{inner.name}"
        self._held: np.ndarray | None = None
        if callable(getattr(inner, "mean_force", None)):  # the mean offset sees it
            self.mean_force = inner.mean_force

    def begin_step(self, t: float, z: np.ndarray, zdot: np.ndarray, dt: float) -> None:
        """Evaluate the inner force at the step's start ``(t, z, ż)`` and hold it."""
        self._held = np.asarray(self.inner.ode_force(t, z, zdot, np.zeros(0)), dtype=float)

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        if self._held is None:
            raise SolverError("LaggedComponent is stepped: the solver must call begin_step "
                              "before ode_force")
        return self._held

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """The inner force at the samples: what was held over each following step [N, N m]."""
        return self.inner.force(hist)

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The inner component's (its linearisation does not see the lag)."""
        return self.inner.linear_coefficients(n_dof)

    def describe(self) -> str:
        return f"lagged one step({self.inner.describe()})"
