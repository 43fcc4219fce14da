"""Memoryless built-in force components: linear hydrostatics, added mass, linear and
quadratic damping, and their command-line registry (``--known NAME=VALUE``)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.forces.base import KnownComponent, as_matrix, kinematic


class _LinearTerm(KnownComponent):
    """``F = -coef * kinematic`` with a scalar/vector/matrix coefficient."""

    kinematic: str = "z"
    slot: int = 2  # index in (A, B, C)

    def __init__(self, value: float | np.ndarray) -> None:
        self.value = value

    def _matrix(self, n_dof: int) -> np.ndarray:
        return as_matrix(self.value, n_dof, self.name)

    def force(self, hist: xr.Dataset) -> np.ndarray:
        q = kinematic(hist, self.kinematic)
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
        v = kinematic(hist, "zdot")
        return -self._diag(v.shape[1]) * np.abs(v) * v

    def linearise_on(self, hist: xr.Dataset) -> QuadraticDamping:
        v = kinematic(hist, "zdot")
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
