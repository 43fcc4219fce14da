"""Memoryless built-in force components: linear hydrostatics, added mass A∞, linear and
quadratic damping, their command-line registry (``--known NAME=VALUE``), and the one route that
builds them from a coefficient Dataset or from the matrices a history carries.

A∞ has one name everywhere: ``added_mass_inf`` (the coefficient variable, the history variable,
the component, the partition candidate, the ``--known`` name and the JSON key); ``added_mass``
is accepted on the command line as an alias.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TypeVar

import numpy as np
import xarray as xr

from hybridwsi.dofs import check_dofs
from hybridwsi.errors import InputError
from hybridwsi.forces.base import KnownComponent, as_matrix, kinematic
from hybridwsi.hydro import coefficients


_T = TypeVar("_T", bound="_LinearTerm")


class _LinearTerm(KnownComponent):
    """``F = -coef * kinematic`` with a scalar/vector/matrix coefficient."""

    kinematic: str = "z"
    slot: int = 2  # index in (A, B, C)
    #: the (dof, dof) variable of coefficient Datasets and histories holding the coefficient
    variable: str | None = None

    def __init__(self, value: float | np.ndarray) -> None:
        self.value = value

    @classmethod
    def from_coefficients(cls: type[_T], coeffs: xr.Dataset,
                          dofs: Sequence[str] | None = None) -> _T:
        """The component with its matrix read from a coefficient Dataset.

        Parameters
        ----------
        coeffs : xarray.Dataset
            Coefficient Dataset (:mod:`hybridwsi.hydro.coefficients`).
        dofs : sequence of str, optional
            DOFs to keep (any subset, any order); default all of the coefficients'.

        Returns
        -------
        The component with an (n, n) matrix in force-equation orientation ``M[i, j]``
        (force on i per motion of j; units per pair, :func:`hybridwsi.dofs.coefficient_unit`).
        """
        if cls.variable is None:
            raise InputError(f"{cls.name} has no coefficient variable to read")
        return cls(coefficients.matrix(coeffs, cls.variable, dofs))

    @classmethod
    def from_history(cls: type[_T], hist: xr.Dataset) -> _T:
        """The component with its matrix read from the history's ``(dof, dof_j)`` variable."""
        if cls.variable is None:
            raise InputError(f"{cls.name} has no history variable to read")
        mat = history_matrix(hist, cls.variable)
        if mat is None:
            raise InputError(f"history has no '{cls.variable}' matrix")
        return cls(mat)

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
        value = np.asarray(self.value, dtype=float)
        if value.size == 1:  # a 1-DOF matrix reads as the scalar it is
            value = value.reshape(())
        return f"{self.name}={np.array2string(value, precision=6)}"


class Hydrostatic(_LinearTerm):
    """Linear hydrostatic restoring force ``F_hs = -C z`` (C [N/m, N/rad, N m/rad])."""

    name = "hydrostatic"
    kinematic = "z"
    slot = 2
    variable = "hydrostatic_stiffness"


class AddedMass(_LinearTerm):
    """Constant added-mass force ``F_A = -A zddot`` (A [kg, kg m, kg m²]; A∞ from BEM)."""

    name = "added_mass_inf"
    kinematic = "zddot"
    slot = 0
    variable = "added_mass_inf"


class LinearDamping(_LinearTerm):
    """Linear damping force ``F_B = -B zdot`` (B [N s/m, N m s/rad])."""

    name = "linear_damping"
    kinematic = "zdot"
    slot = 1

    @classmethod
    def from_coefficients(cls, coeffs: xr.Dataset, dofs: Sequence[str] | None = None,
                          omega: float | None = None) -> LinearDamping:
        """``B = B(omega)``, the radiation damping at ``omega`` [rad/s] (linear interpolation,
        :func:`hybridwsi.hydro.coefficients.at_frequency`), restricted to ``dofs``."""
        if omega is None or not np.isfinite(omega) or omega <= 0:
            raise InputError(f"linear damping from coefficients needs a frequency > 0 rad/s, "
                             f"got {omega}")
        return cls(coefficients.at_frequency(coeffs, "radiation_damping", float(omega), dofs))


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

    def compiled_force(self, n_dof: int) -> Any:
        """Numba kernel of :meth:`ode_force` (``−Bq |ż| ż``), or None without Numba."""
        from hybridwsi.forces._compiled import quadratic_force  # imports Numba: on demand

        return quadratic_force(self._diag(n_dof))


#: CLI names -> component classes (``--known hydrostatic=692.2``); the names are the
#: components' ``name`` and the partition candidates'
REGISTRY: dict[str, type[KnownComponent]] = {
    cls.name: cls for cls in (Hydrostatic, AddedMass, LinearDamping, QuadraticDamping)
}
#: older spellings still accepted on the command line
ALIASES = {"added_mass": "added_mass_inf", "damping": "linear_damping"}
#: components whose matrix a coefficient Dataset or a history can supply (``--known NAME``)
FROM_DATA: dict[str, type[_LinearTerm]] = {"hydrostatic": Hydrostatic,
                                           "added_mass_inf": AddedMass}


def canonical_name(name: str) -> str:
    """The registry name of a component (aliases resolved), or InputError."""
    name = ALIASES.get(name.strip(), name.strip())
    if name not in REGISTRY:
        raise InputError(f"unknown known component '{name}' (choose from {', '.join(REGISTRY)})")
    return name


def history_matrix(hist: xr.Dataset, name: str) -> np.ndarray | None:
    """A ``(dof, dof_j)`` matrix the history carries (``mass``, ``added_mass_inf``,
    ``hydrostatic_stiffness``), ``M[i, j]`` in the order of ``hist.dof``; None when absent.

    A scalar (0-d) variable counts as that value times the identity.
    """
    if name not in hist.variables:
        return None
    var = hist[name]
    n = hist.sizes["dof"]
    if var.ndim == 0:
        return as_matrix(float(var.values), n, name)
    if set(var.dims) != {"dof", "dof_j"}:
        raise InputError(f"history variable '{name}' must have dims (dof, dof_j), has {var.dims}")
    dofs = [str(d) for d in hist["dof"].values]
    cols = [str(d) for d in var["dof_j"].values] if "dof_j" in var.coords else dofs
    if sorted(cols) != sorted(dofs):
        raise InputError(f"history variable '{name}' has dof_j {cols}, the history has {dofs}")
    mat = np.asarray(var.transpose("dof", "dof_j").values, dtype=float)
    mat = mat[:, [cols.index(d) for d in dofs]]
    if not np.all(np.isfinite(mat)):
        raise InputError(f"history variable '{name}' contains NaN/inf")
    return mat


def _dofs_of(hist: xr.Dataset | None, dofs: Sequence[str] | None) -> list[str] | None:
    """The history's DOFs, else ``dofs`` (None: all of the coefficients')."""
    if hist is not None:
        return [str(d) for d in hist["dof"].values]
    return None if dofs is None else list(check_dofs(dofs))


def matrix_from(hist: xr.Dataset | None, coeffs: xr.Dataset | None, name: str,
                dofs: Sequence[str] | None = None) -> np.ndarray | None:
    """Matrix ``name`` from the history when it carries it, else from the coefficients
    restricted to the history's DOFs (or ``dofs``); None when neither has it.

    Units per DOF pair (:func:`hybridwsi.dofs.coefficient_unit`); orientation ``M[i, j]``.
    """
    if hist is not None:
        mat = history_matrix(hist, name)
        if mat is not None:
            return mat
    if coefficients.has(coeffs, name):
        return coefficients.matrix(coeffs, name, _dofs_of(hist, dofs))
    return None


def mass_from(hist: xr.Dataset | None, coeffs: xr.Dataset | None,
              dofs: Sequence[str] | None = None) -> np.ndarray | None:
    """Rigid-body mass matrix [kg, kg m, kg m²]: the history's ``mass``, else the
    coefficients' (restricted to the DOFs); None when neither carries one."""
    return matrix_from(hist, coeffs, "mass", dofs)


def has_known(hist: xr.Dataset | None, coeffs: xr.Dataset | None, name: str) -> bool:
    """True when :func:`known_from` can build component ``name`` from these inputs."""
    cls = FROM_DATA.get(ALIASES.get(name, name))
    return cls is not None and ((hist is not None and cls.variable in hist.variables)
                                or coefficients.has(coeffs, cls.variable))


def known_from(hist: xr.Dataset | None, coeffs: xr.Dataset | None, names: Sequence[str],
               *, dofs: Sequence[str] | None = None) -> list[KnownComponent]:
    """Known components by name with their matrices from the history or the coefficients.

    Parameters
    ----------
    hist : TimeHistory, optional
        Read first: its ``(dof, dof_j)`` variables (``hydrostatic_stiffness``,
        ``added_mass_inf``) when present; its DOFs select the coefficients' rows and columns.
    coeffs : xarray.Dataset, optional
        Coefficient Dataset, read through :mod:`hybridwsi.hydro.coefficients`.
    names : sequence of str
        ``hydrostatic``, ``added_mass_inf`` (alias ``added_mass``).
    dofs : sequence of str, optional
        DOFs when no history is given (default all of the coefficients').

    Returns
    -------
    list of KnownComponent
        With (n, n) matrices in force-equation orientation (any DOF subset, any order).

    Raises
    ------
    InputError
        Unknown name, or neither input holds the matrix.
    """
    out: list[KnownComponent] = []
    for raw in names:
        name = canonical_name(raw)
        cls = FROM_DATA.get(name)
        if cls is None:
            raise InputError(f"'{name}' cannot be read from coefficients or histories; give a "
                             f"value ({name}=VALUE); readable: {', '.join(FROM_DATA)}")
        mat = matrix_from(hist, coeffs, cls.variable, dofs)
        if mat is None:
            raise InputError(f"no '{cls.variable}' in the history or the coefficients for "
                             f"'{name}': give --coeffs FILE or {name}=VALUE")
        out.append(cls(mat))
    return out


def parse_known(spec: str) -> KnownComponent:
    """Parse ``NAME=VALUE`` (VALUE a number, or comma-separated diagonal) into a component."""
    if "=" not in spec:
        raise InputError(f"--known expects NAME=VALUE, got '{spec}' (names: {', '.join(REGISTRY)})")
    name, _, raw = spec.partition("=")
    name = canonical_name(name)
    try:
        vals = [float(v) for v in raw.split(",")]
    except ValueError:
        raise InputError(f"--known {name}: value '{raw}' is not a number") from None
    if not all(np.isfinite(vals)):
        raise InputError(f"--known {name}: value must be finite")
    return REGISTRY[name](vals[0] if len(vals) == 1 else np.asarray(vals))
