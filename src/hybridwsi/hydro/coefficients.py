"""The coefficient Dataset: its conventions and the one route that reads a quantity from it.

Every stage that needs A∞, C, the rigid-body mass, A(ω) or B(ω) reads it here, so there is one
orientation and one error message for a missing DOF.

Conventions (Capytaine's names, see docs/DATA_MODEL.md):

- dims ``omega`` [rad/s], ``radiating_dof`` (the DOF that moves), ``influenced_dof`` (the DOF
  that receives the force), ``wave_direction`` [rad]; DOFs are named ``Surge`` … ``Yaw``;
- variables stored as ``(…, radiating_dof, influenced_dof)`` as Capytaine stores them;
- :func:`matrix` returns the *force-equation* orientation ``M[i, j]`` with ``i`` the influenced
  and ``j`` the radiating DOF, so that the force on DOF i is ``F_i = −Σ_j M[i, j] q_j``;
- units per DOF pair: :func:`hybridwsi.dofs.coefficient_unit` (kg, kg m, kg m² for added mass…).

Matrix variables: ``added_mass_inf``, ``added_mass_zero``, ``hydrostatic_stiffness``, ``mass``
(rigid-body, about the reference point). Frequency variables: ``added_mass``,
``radiation_damping`` (omega, radiating_dof, influenced_dof); ``excitation_force``
(omega, wave_direction, influenced_dof), complex, per unit wave amplitude.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from hybridwsi.dofs import check_dofs, coefficient_unit
from hybridwsi.errors import InputError

PAIR = ("radiating_dof", "influenced_dof")
#: quantity kind of each matrix variable (for units)
KIND = {
    "added_mass": "mass", "added_mass_inf": "mass", "added_mass_zero": "mass", "mass": "mass",
    "radiation_damping": "damping", "hydrostatic_stiffness": "stiffness",
}


def dofs(coeffs: xr.Dataset) -> list[str]:
    """The DOFs the coefficients describe (their ``radiating_dof`` labels)."""
    if not isinstance(coeffs, xr.Dataset):
        raise InputError(f"coefficients must be an xarray.Dataset, got {type(coeffs).__name__}")
    if "radiating_dof" not in coeffs.coords:
        raise InputError("coefficients have no 'radiating_dof' coordinate (not a coefficient Dataset)")
    return [str(d) for d in coeffs["radiating_dof"].values]


def _select(coeffs: xr.Dataset, name: str, wanted: Sequence[str] | None) -> tuple[np.ndarray, tuple]:
    """``coeffs[name]`` restricted to ``wanted`` DOFs on both DOF axes, by position (xarray's
    label ``sel`` costs more than a short state-space run), plus the variable's dims."""
    if name not in coeffs.variables:
        raise InputError(f"coefficients have no '{name}'")
    var = coeffs.variables[name]
    vals = np.asarray(var.values)
    have = dofs(coeffs)
    want = have if wanted is None else list(check_dofs(wanted))
    missing = [d for d in want if d not in have]
    if missing:
        raise InputError(f"coefficients '{name}' have no DOF {missing} (they have {have})")
    for dim in PAIR:
        if dim not in var.dims:
            raise InputError(f"coefficient '{name}' has no '{dim}' dimension")
        labels = [str(v) for v in coeffs[dim].values]
        pos = [labels.index(d) for d in want]
        vals = vals.take(pos, axis=var.dims.index(dim))
    return vals, var.dims


def matrix(coeffs: xr.Dataset, name: str, dofs: Sequence[str] | None = None) -> np.ndarray:
    """A (dof, dof) coefficient in force-equation orientation ``M[influenced i, radiating j]``.

    Parameters
    ----------
    coeffs : xarray.Dataset
        Coefficient Dataset (BEM, WAMIT, BEMIO or Capytaine file).
    name : str
        ``added_mass_inf``, ``added_mass_zero``, ``hydrostatic_stiffness`` or ``mass``.
    dofs : sequence of str, optional
        DOFs to keep (any subset, any order); default all of them.

    Returns
    -------
    numpy.ndarray, shape (n, n)
        Units per pair :func:`hybridwsi.dofs.coefficient_unit` (kg, N/m, N m/rad, …).

    Raises
    ------
    InputError
        Missing variable or DOF, non-finite entries.
    """
    vals, dims = _select(coeffs, name, dofs)
    if len(dims) != 2:
        raise InputError(f"coefficient '{name}' is not a (dof, dof) matrix (dims {dims})")
    arr = np.asarray(vals, dtype=float)
    if dims[0] == "radiating_dof":
        arr = arr.T
    if not np.all(np.isfinite(arr)):
        raise InputError(f"coefficient '{name}' contains NaN/inf")
    return arr


def matrix_omega(coeffs: xr.Dataset, name: str, dofs: Sequence[str] | None = None) -> np.ndarray:
    """A frequency-dependent coefficient, shape (n_omega, n, n), ``[ω, influenced, radiating]``."""
    vals, dims = _select(coeffs, name, dofs)
    if dims != ("omega", *PAIR) and dims != ("omega", *PAIR[::-1]):
        raise InputError(f"coefficient '{name}' must have dims (omega, radiating_dof, "
                         f"influenced_dof), has {dims}")
    arr = np.asarray(vals, dtype=float)
    return np.swapaxes(arr, 1, 2) if dims[1] == "radiating_dof" else arr


def omega(coeffs: xr.Dataset) -> np.ndarray:
    """The finite frequencies [rad/s] of the coefficients, sorted."""
    if "omega" not in coeffs.coords:
        raise InputError("coefficients have no 'omega' coordinate")
    return np.asarray(coeffs["omega"].values, dtype=float)


def at_frequency(coeffs: xr.Dataset, name: str, w: float,
                 dofs: Sequence[str] | None = None) -> np.ndarray:
    """``added_mass`` or ``radiation_damping`` at ``w`` [rad/s] (linear interpolation, clamped
    to the computed range), force-equation orientation, shape (n, n)."""
    grid = omega(coeffs)
    vals = matrix_omega(coeffs, name, dofs)
    n = vals.shape[1]
    flat = vals.reshape(grid.size, -1)
    out = np.array([np.interp(w, grid, flat[:, k]) for k in range(flat.shape[1])])
    return out.reshape(n, n)


def has(coeffs: xr.Dataset | None, name: str) -> bool:
    """True when ``coeffs`` holds variable ``name``."""
    return coeffs is not None and name in coeffs.variables


def unit_matrix(name: str, dofs: Sequence[str]) -> list[list[str]]:
    """Units of coefficient ``name`` per DOF pair, force-equation orientation ``[i][j]``."""
    kind = KIND.get(name)
    if kind is None:
        raise InputError(f"no unit rule for coefficient '{name}'")
    dofs = check_dofs(dofs)
    return [[coefficient_unit(i, j, kind) for j in dofs] for i in dofs]


def pair_units_attr(name: str, dofs: Sequence[str]) -> str:
    """``units`` attribute text of a (dof, dof) variable: one unit, or per-pair when mixed."""
    units = unit_matrix(name, dofs)
    flat = {u for row in units for u in row}
    if len(flat) == 1:
        return flat.pop()
    return "per DOF pair (hybridwsi.dofs.coefficient_unit)"
