"""The Cummins system for the chosen DOFs: rigid-body mass M, A∞, C and the radiation memory.

Every matrix is read from the coefficient Dataset through :mod:`hybridwsi.hydro.coefficients`
(force-equation orientation ``M[i influenced, j radiating]``, so the force on DOF i is
``F_i = −Σ_j M_ij q_j``). The memory term is either a state-space realisation of the kernel
K(t) (:func:`hybridwsi.hydro.statespace.fit_radiation_ss`) or K sampled on the time grid (for
the direct convolution).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.forces import as_matrix
from hybridwsi.hydro import coefficients
from hybridwsi.hydro.irf import radiation_irf
from hybridwsi.hydro.ss_cache import cached_radiation_ss
from hybridwsi.hydro.statespace import RadiationSS, fit_radiation_ss

RADIATION = ("statespace", "convolution", "none")


@dataclass
class CumminsSystem:
    """Matrices of the Cummins equation for ``dofs`` (rows = influenced DOF).

    Units per DOF pair (:func:`hybridwsi.dofs.coefficient_unit`): ``mass`` and
    ``added_mass_inf`` kg, kg m, kg m²; ``stiffness`` N/m, N/rad, N m/m, N m/rad.
    """

    dofs: list[str]
    mass: np.ndarray  # rigid-body mass M
    added_mass_inf: np.ndarray  # A∞
    stiffness: np.ndarray  # C
    ss: RadiationSS | None = None
    kernel: np.ndarray | None = None  # K sampled at the simulation dt, (nk, n_inf, n_rad)

    @property
    def n(self) -> int:
        return len(self.dofs)

    @property
    def n_states(self) -> int:
        return 0 if self.ss is None else self.ss.order

    def augmented(self) -> tuple[np.ndarray, np.ndarray]:
        """``ẏ = A y + B u`` for ``y = [z, ż, x]`` and input force ``u`` [N, N m]."""
        n, r = self.n, self.n_states
        minv = np.linalg.inv(self.mass + self.added_mass_inf)
        a = np.zeros((2 * n + r, 2 * n + r))
        a[:n, n:2 * n] = np.eye(n)
        a[n:2 * n, :n] = -minv @ self.stiffness
        if r:
            a[n:2 * n, 2 * n:] = -minv @ self.ss.C
            a[2 * n:, n:2 * n] = self.ss.B
            a[2 * n:, 2 * n:] = self.ss.A
        b = np.zeros((2 * n + r, n))
        b[n:2 * n] = minv
        return a, b


def build_system(
    coeffs: xr.Dataset,
    *,
    dofs: Sequence[str] = ("Heave",),
    mass: float | np.ndarray | None = None,
    radiation: str = "statespace",
    dt: float = 0.01,
    irf: xr.DataArray | None = None,
    radiation_ss: RadiationSS | None = None,
    ss_order: int | None = None,
    ss_tol: float = 0.005,
    irf_t_max: float | None = None,
) -> CumminsSystem:
    """Cummins matrices, and the radiation kernel or its state-space model, for ``dofs``.

    Parameters
    ----------
    coeffs : xarray.Dataset
        Coefficient Dataset with ``added_mass_inf``, ``hydrostatic_stiffness``,
        ``radiation_damping`` (unless ``radiation="none"``) and ``mass`` (unless given).
    dofs : sequence of str
        DOFs of the run (any subset of the coefficients' DOFs, any order).
    mass : float or ndarray, optional
        Rigid-body mass matrix (n, n) [kg, kg m, kg m²] (a scalar: times identity);
        default the coefficients' ``mass``.
    radiation : {"statespace", "convolution", "none"}
        How the memory term is represented.
    dt : float
        Time step [s] the convolution kernel is resampled to.
    irf, radiation_ss, ss_order, ss_tol, irf_t_max
        Precomputed kernel K(time, radiating_dof, influenced_dof), precomputed state-space
        model, and the options of the fit and of ``radiation_irf``.
    """
    dofs = list(dofs)
    if radiation not in RADIATION:
        raise InputError(f"radiation must be one of {', '.join(RADIATION)}, got '{radiation}'")
    have = coefficients.dofs(coeffs)
    missing = [d for d in dofs if d not in have]
    if missing:
        raise InputError(f"coefficients have no DOF {missing} (have {have})")
    if radiation != "none" and not np.all(np.isfinite(
            coefficients.matrix_omega(coeffs, "radiation_damping", dofs))):
        raise InputError("coefficient 'radiation_damping' contains NaN/inf")
    if mass is None:
        if not coefficients.has(coeffs, "mass"):
            raise InputError("no rigid-body mass: pass mass= or use coefficients with 'mass'")
        m = coefficients.matrix(coeffs, "mass", dofs)
    else:
        m = as_matrix(mass, len(dofs), "mass")
        if not np.all(np.isfinite(m)):
            raise InputError("mass must be finite")
    sys = CumminsSystem(dofs, m, coefficients.matrix(coeffs, "added_mass_inf", dofs),
                        coefficients.matrix(coeffs, "hydrostatic_stiffness", dofs))
    if np.any(np.linalg.eigvalsh(0.5 * (sys.mass + sys.mass.T) + sys.added_mass_inf) <= 0):
        raise InputError("m + A∞ must be positive definite (check mass and added_mass_inf)")
    if radiation == "statespace":
        if radiation_ss is None and irf is not None:
            radiation_ss = _fit_for_step(_kernel(coeffs, dofs, irf, irf_t_max, dt=None),
                                         ss_order, ss_tol, coeffs, dt)
        elif radiation_ss is None:
            radiation_ss = _fitted_radiation_ss(coeffs, dofs, irf_t_max, ss_order, ss_tol, dt)
        if radiation_ss.radiating_dof != dofs or radiation_ss.influenced_dof != dofs:
            raise InputError(f"radiation_ss is for DOFs {radiation_ss.radiating_dof}, not {dofs}")
        sys.ss = radiation_ss
    elif radiation == "convolution":
        sys.kernel = _kernel_on_grid(_kernel(coeffs, dofs, irf, irf_t_max, dt=dt), dt)
    return sys


def _kernel(coeffs: xr.Dataset, dofs: list[str], irf: xr.DataArray | None,
            t_max: float | None, dt: float | None) -> xr.DataArray:
    """K(time, radiating_dof, influenced_dof) for ``dofs``, computed from B(ω) unless given."""
    if irf is None:
        kw: dict[str, Any] = {} if t_max is None else {"t_max": t_max}
        if dt is not None:
            kw["dt"] = dt
        irf = radiation_irf(coeffs, **kw)
    if not isinstance(irf, xr.DataArray) or "time" not in irf.dims:
        raise InputError("irf must be a DataArray K(time, radiating_dof, influenced_dof)")
    if "radiating_dof" in irf.dims:
        irf = irf.sel(radiating_dof=dofs, influenced_dof=dofs)
    else:  # a 1-D kernel: one DOF
        irf = irf.expand_dims(radiating_dof=dofs, influenced_dof=dofs, axis=(1, 2))
    if not np.all(np.isfinite(irf.values)):
        raise InputError("radiation kernel K contains NaN/inf")
    return irf.transpose("time", "radiating_dof", "influenced_dof")


def _fitted_radiation_ss(coeffs: xr.Dataset, dofs: list[str], t_max: float | None,
                         order: int | None, tol: float, dt: float) -> RadiationSS:
    """:func:`_fit_for_step` of the coefficients' own kernel, fitted once per content
    (:func:`hybridwsi.hydro.ss_cache.cached_radiation_ss`: a copy, the fit's warnings
    repeated)."""
    return cached_radiation_ss(
        coeffs, ("cummins", dofs, t_max, order, tol, dt),
        lambda: _fit_for_step(_kernel(coeffs, dofs, None, t_max, dt=None), order, tol, coeffs,
                              dt))


def _kernel_on_grid(k: xr.DataArray, dt: float) -> np.ndarray:
    """K resampled (linear interpolation) at multiples of the simulation step, oriented [i, j]."""
    t = np.asarray(k["time"].values, dtype=float)
    tk = np.arange(0.0, t[-1] + 1e-9 * dt, dt)
    vals = np.asarray(k.values, dtype=float)
    out = np.empty((tk.size, vals.shape[2], vals.shape[1]))
    for j in range(vals.shape[1]):
        for i in range(vals.shape[2]):
            out[:, i, j] = np.interp(tk, t, vals[:, j, i])
    return out


def _fit_for_step(k, order: int | None, tol: float, coeffs: xr.Dataset, dt: float
                  ) -> RadiationSS:
    """The state-space fit with no pole faster than the RK4 step resolves (``|λ| dt ≤ 2``);
    when no order satisfies that, the unrestricted fit (a smaller ``dt`` may then be needed)."""
    try:
        return fit_radiation_ss(k, order=order, tol=tol, coeffs=coeffs, max_pole=2.0 / dt)
    except InputError:
        return fit_radiation_ss(k, order=order, tol=tol, coeffs=coeffs)

