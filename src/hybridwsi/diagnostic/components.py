"""Known force components F_known(z, zdot, zddot), with their physical signs (THEORY.md §1).

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

Subclass :class:`KnownComponent` for new physics (radiation memory in
:mod:`hybridwsi.hydro.statespace`, quadratic drag, nonlinear hydrostatics...).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

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


def _kin(hist: xr.Dataset, name: str) -> np.ndarray:
    if name not in hist:
        raise InputError(f"history has no '{name}', needed to evaluate a known component")
    return np.asarray(hist[name].values, dtype=float)


class KnownComponent(ABC):
    """A modelled force component. Subclasses set ``name`` and implement the methods."""

    name: str = "component"
    #: number of internal ODE states (0 for memoryless components)
    n_states: int = 0

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

    def initial_state(self, hist: xr.Dataset) -> np.ndarray:
        """Internal states at the first sample of ``hist`` (zeros: start from rest)."""
        return np.zeros(self.n_states)

    def describe(self) -> str:
        return self.name


class _LinearTerm(KnownComponent):
    """``F = -coef * kinematic`` with a scalar/vector/matrix coefficient."""

    kinematic: str = "z"
    slot: int = 2  # index in (A, B, C)

    def __init__(self, value: float | np.ndarray) -> None:
        self.value = value

    def _matrix(self, n_dof: int) -> np.ndarray:
        return as_matrix(self.value, n_dof, self.name)

    def force(self, hist: xr.Dataset) -> np.ndarray:
        q = _kin(hist, self.kinematic)
        return -q @ self._matrix(q.shape[1]).T

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        out = [np.zeros((n_dof, n_dof)) for _ in range(3)]
        out[self.slot] = self._matrix(n_dof)
        return out[0], out[1], out[2]

    def describe(self) -> str:
        return f"{self.name}={np.array2string(np.asarray(self.value), precision=6)}"


class Hydrostatic(_LinearTerm):
    """Linear hydrostatic restoring force ``F_hs = -C z`` (C [N/m])."""

    name = "hydrostatic"
    kinematic = "z"
    slot = 2


class AddedMass(_LinearTerm):
    """Constant added-mass force ``F_A = -A zddot`` (A [kg]; e.g. A∞ from BEM)."""

    name = "added_mass"
    kinematic = "zddot"
    slot = 0


class LinearDamping(_LinearTerm):
    """Linear damping force ``F_B = -B zdot`` (B [N s/m])."""

    name = "damping"
    kinematic = "zdot"
    slot = 1


class QuadraticDamping(KnownComponent):
    """Quadratic (Morison-type) drag ``F_q = -Bq |zdot| zdot`` (Bq [N s²/m²], diagonal).

    Its linearisation about a reference uses the mean of ``2 Bq |zdot_ref|``, set by
    :meth:`linearise_on`; before that it counts as zero damping in the stability analysis.
    """

    name = "quadratic_damping"

    def __init__(self, value: float | np.ndarray) -> None:
        self.value = value
        self._b_eq: np.ndarray | None = None

    def _diag(self, n_dof: int) -> np.ndarray:
        return np.diag(as_matrix(self.value, n_dof, self.name))

    def force(self, hist: xr.Dataset) -> np.ndarray:
        v = _kin(hist, "zdot")
        return -self._diag(v.shape[1]) * np.abs(v) * v

    def linearise_on(self, hist: xr.Dataset) -> QuadraticDamping:
        v = _kin(hist, "zdot")
        self._b_eq = np.diag(2.0 * self._diag(v.shape[1]) * np.abs(v).mean(axis=0))
        return self

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        z = np.zeros((n_dof, n_dof))
        return z, (self._b_eq if self._b_eq is not None else z.copy()), z.copy()

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        return -self._diag(z.size) * np.abs(zdot) * zdot


#: CLI names -> component classes (``--known hydrostatic=692.2``)
REGISTRY: dict[str, type[KnownComponent]] = {
    "hydrostatic": Hydrostatic,
    "added_mass": AddedMass,
    "damping": LinearDamping,
    "quadratic_damping": QuadraticDamping,
}


def parse_known(spec: str) -> KnownComponent:
    """Parse ``NAME=VALUE`` (VALUE a number, or comma-separated diagonal) into a component."""
    if "=" not in spec:
        raise InputError(f"--known expects NAME=VALUE, got '{spec}' (names: {', '.join(REGISTRY)})")
    name, _, raw = spec.partition("=")
    name = name.strip()
    if name not in REGISTRY:
        raise InputError(f"unknown known component '{name}' (choose from {', '.join(REGISTRY)})")
    try:
        vals = [float(v) for v in raw.split(",")]
    except ValueError:
        raise InputError(f"--known {name}: value '{raw}' is not a number") from None
    if not all(np.isfinite(vals)):
        raise InputError(f"--known {name}: value must be finite")
    return REGISTRY[name](vals[0] if len(vals) == 1 else np.asarray(vals))


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
