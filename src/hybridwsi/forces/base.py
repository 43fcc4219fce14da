"""The force-component interface shared by every stage (docs/THEORY.md §1).

Known force components F_known(z, zdot, zddot), with their physical signs.

A component is removed from the total force with its physical sign,
``F_bb = F_tot - sum(F_known(z_ref, zdot_ref, zddot_ref))``; e.g. the hydrostatic restoring
force is ``F_hs = -C z`` so ``F_tot - F_hs = F_tot + C z`` and the regression gives ``gamma = +C``.

The same objects enter the ODE of the reconstruction (paper Eq. 4) and the stability analysis:

- ``linear_coefficients()`` returns the matrices ``(A_k, B_k, C_k)`` of the linear(ised) part,
  ``F ≈ -A_k zddot - B_k zdot - C_k z``. ``A_k`` is moved to the left-hand side of the ODE
  (``(m + A_k) zddot = ...``) because an acceleration-proportional force cannot be evaluated
  explicitly.
- ``ode_force(t, z, zdot, x)`` is the force without its acceleration part, evaluated on the ODE
  state; ``x`` are the component's internal states (``n_states`` of them, e.g. a radiation
  state-space realisation), whose derivative is ``state_derivative(t, z, zdot, x)``.

Optionally, ``compiled_force(n_dof)`` gives a Numba kernel of ``ode_force`` that the stepping
solver's compiled RK4 loop calls (:mod:`hybridwsi.forces._compiled`); without one the solver
runs its NumPy loop.

A component that advances a state of its own in fixed steps (a coupled mooring code such as
MoorDyn, a controller) defines ``begin_step(t, z, zdot, dt)``: the stepping integrators call it
once at the start of every step, on the start-of-step state and before that step's force
evaluations, and the component returns its force for the step from ``ode_force`` (e.g. the
force it computed in ``begin_step``, held over the step: a lagged coupling). Such a component
(:attr:`KnownComponent.stepped`) always runs the integrators' Python path, never a compiled loop.

Subclass :class:`KnownComponent` for new physics; the built-ins live beside this module
(:mod:`hybridwsi.forces.linear`, :mod:`hybridwsi.forces.radiation`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError


def as_matrix(value: float | np.ndarray, n_dof: int, name: str) -> np.ndarray:
    """A scalar (times identity), a vector (diagonal) or an (n_dof, n_dof) matrix."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return np.eye(n_dof) * float(arr)
    if arr.ndim == 1 and arr.size == n_dof:
        return np.diag(arr)
    if arr.shape == (n_dof, n_dof):
        return arr
    raise InputError(f"{name} must be a scalar, a length-{n_dof} vector or a {n_dof}x{n_dof} matrix")


def kinematic(hist: xr.Dataset, name: str) -> np.ndarray:
    if name not in hist:
        raise InputError(f"history has no '{name}', needed to evaluate a known component")
    return np.asarray(hist[name].values, dtype=float)


class KnownComponent(ABC):
    """A modelled force component. Subclasses set ``name`` and implement the methods."""

    name: str = "component"
    #: number of internal ODE states (0 for memoryless components)
    n_states: int = 0
    #: True when the force depends on time only (not on z, ż, z̈ or internal states): a
    #: generator evaluates it once on its time grid (:meth:`time_force`) and keeps its
    #: linear solver
    time_only: bool = False

    @abstractmethod
    def force(self, hist: xr.Dataset) -> np.ndarray:
        """Force [N] on the reference history, shape (n_time, n_dof), physical sign."""

    @abstractmethod
    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(A_k, B_k, C_k)`` with ``F ≈ -A_k zddot - B_k zdot - C_k z`` [kg, N s/m, N/m]."""

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Force [N] without its acceleration part, on an ODE state (default: linear B, C)."""
        _, b, c = self.linear_coefficients(z.size)
        return -b @ zdot - c @ z

    def state_derivative(
        self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray
    ) -> np.ndarray:
        """Time derivative of the internal states (none by default)."""
        return np.zeros(0)

    def begin_step(self, t: float, z: np.ndarray, zdot: np.ndarray, dt: float) -> None:
        """Advance the component's own state to the start of a time step (default: nothing).

        Called by the stepping integrators (:func:`hybridwsi.cummins.solvers.solve_rk4`, the
        hybrid rollout's NumPy stepper) once per step, before any ``ode_force`` of that step,
        and once more at the last output time (so that the force recorded there is the
        component's); never by adaptive integrators (the reconstruction refuses such a
        component).

        Parameters
        ----------
        t : float
            Start time of the step [s].
        z, zdot : ndarray, shape (n_dof,)
            Start-of-step displacement [m, rad] and velocity [m/s, rad/s] (copies).
        dt : float
            Step [s]: the step ends at ``t + dt``.
        """

    @property
    def stepped(self) -> bool:
        """True when the component overrides :meth:`begin_step` (it keeps a state of its own
        that the integrator advances step by step: Python path only)."""
        return type(self).begin_step is not KnownComponent.begin_step

    def compiled_force(self, n_dof: int) -> Any:
        """Optional Numba kernel of :meth:`ode_force` for the compiled RK4 loop, or None.

        Returns a :class:`hybridwsi.forces._compiled.CompiledForce` (a kernel with the same
        result as ``ode_force`` to rounding, and its data) or None, in which case the stepping
        solver runs its NumPy path. Components with internal states or with
        :meth:`begin_step` return None. The default
        compiles the default ``ode_force`` (``−B ż − C z`` of :meth:`linear_coefficients`)
        when a subclass keeps it; a subclass overriding ``ode_force`` returns None unless it
        overrides this method too. None without Numba.
        """
        if (self.n_states or self.stepped
                or type(self).ode_force is not KnownComponent.ode_force):
            return None
        from hybridwsi.forces._compiled import linear_force  # imports Numba: only on demand

        _, b, c = self.linear_coefficients(n_dof)
        return linear_force(b, c)

    def initial_state(self, hist: xr.Dataset) -> np.ndarray:
        """Internal states at the first sample of ``hist`` (zeros: start from rest)."""
        return np.zeros(self.n_states)

    def time_force(self, t: np.ndarray, n_dof: int | None = None) -> np.ndarray:
        """Force [N, N m per DOF] at times ``t`` [s], shape (nt, n_dof); time-only components.

        ``n_dof`` is the number of DOFs of the run (needed where the component alone cannot
        tell, e.g. a scalar constant); None keeps the component's own width.
        """
        raise InputError(f"force component '{self.describe()}' depends on the motion, not on "
                         "time only; it has no time series")

    def describe(self) -> str:
        return self.name


def total_known_force(hist: xr.Dataset, known: list[KnownComponent]) -> np.ndarray:
    """Sum of the known components on the reference history, shape (n_time, n_dof) [N]."""
    n_dof = hist.sizes["dof"]
    total = np.zeros((hist.sizes["time"], n_dof))
    for comp in known:
        total += comp.force(hist)
    return total


def black_box_force(hist: xr.Dataset, force: str, known: list[KnownComponent]) -> np.ndarray:
    """``F_bb = F_force - sum(F_known)`` on the reference (paper Eq. 3), shape (n_time, n_dof)."""
    if force not in hist:
        raise InputError(
            f"history has no force '{force}' (has: {', '.join(map(str, hist.data_vars)) or 'none'})"
        )
    return np.asarray(hist[force].values, dtype=float) - total_known_force(hist, known)


def summed_linear_coefficients(
    known: list[KnownComponent], n_dof: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(A_k, B_k, C_k)`` summed over the known components."""
    a, b, c = (np.zeros((n_dof, n_dof)) for _ in range(3))
    for comp in known:
        ai, bi, ci = comp.linear_coefficients(n_dof)
        a, b, c = a + ai, b + bi, c + ci
    return a, b, c
