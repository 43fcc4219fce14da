"""Natural frequencies of a floating body from an eigen-analysis of its linear system.

The undamped free motion ``(M + A(ω)) ẍ + C x = 0`` has modes ``x = v e^{iωt}`` with

    C v = ω² (M + A(ω)) v,

a generalised eigenproblem whose matrix depends on the eigenvalue through the frequency-dependent
added mass A(ω). Each mode is found by fixed-point iteration on its own frequency: solve the
eigenproblem with A at the current estimate ω_k, take the eigenvalue of the mode that continues
mode k (largest overlap of the scaled mode shapes), repeat until ω_k stops changing. A(ω)
changes slowly, so a few iterations converge. A(ω) is interpolated linearly between the
computed frequencies and held constant outside them (:func:`coefficients.at_frequency`). C is the body's hydrostatic + gravity stiffness
from the coefficient Dataset plus any external stiffness (mooring, a yaw spring).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import xarray as xr

from hybridwsi.errors import InputError, SolverError
from hybridwsi.hydro import coefficients as co


@dataclass(frozen=True)
class Mode:
    """One natural mode of the linear system.

    Attributes
    ----------
    omega : float
        Natural angular frequency [rad/s] (0 for a mode without stiffness).
    dominant_dof : str
        DOF with the largest share of the mode's kinetic energy.
    energy_share : dict
        Share of ``|u_i|²`` per DOF, ``u = sqrt(diag(M + A)) v`` (sums to 1; couplings ignored).
    shape : tuple of float
        Mode shape v per DOF, 1 for the dominant DOF (m/m, rad/m, m/rad…).
    iterations : int
        Fixed-point iterations used.
    """

    omega: float
    dominant_dof: str
    energy_share: dict[str, float]
    shape: tuple[float, ...]
    iterations: int

    @property
    def frequency(self) -> float:
        """Natural frequency [Hz]."""
        return self.omega / (2.0 * math.pi)

    @property
    def period(self) -> float:
        """Natural period [s] (``inf`` for a mode without stiffness)."""
        return 2.0 * math.pi / self.omega if self.omega > 0 else math.inf


def _eigen(stiffness: np.ndarray, inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ω² and mode shapes (columns) of ``C v = ω² M v``; real parts (C may be slightly
    unsymmetric: the roll/pitch-yaw weight terms of an off-centre CM)."""
    lam, vec = scipy.linalg.eig(stiffness, inertia)
    if not np.all(np.isfinite(lam)):
        raise SolverError("natural frequencies: the mass + added-mass matrix is singular")
    return lam.real, vec.real


def natural_frequencies(coeffs: xr.Dataset, stiffness: np.ndarray | None = None,
                        dofs: Sequence[str] | None = None, *, hydrostatics: bool = True,
                        rtol: float = 1e-10, max_iter: int = 100) -> list[Mode]:
    """Natural modes of ``(M + A(ω)) ẍ + (C_hs + K) x = 0``, A at each mode's own frequency.

    Parameters
    ----------
    coeffs : xarray.Dataset
        Coefficient Dataset (``mass``, ``added_mass``, ``hydrostatic_stiffness``; read through
        :mod:`hybridwsi.hydro.coefficients`).
    stiffness : (n, n) array, optional
        External stiffness K [influenced, radiating] added to the hydrostatic one, e.g. a
        mooring's ``-∂F/∂q`` [N/m, N/rad, N m/m, N m/rad]; in the order of ``dofs``.
    dofs : sequence of str, optional
        DOFs of the analysis (default: all of the Dataset's).
    hydrostatics : bool
        Include the Dataset's ``hydrostatic_stiffness`` C_hs (with the weight term).
    rtol : float
        Relative change of ω that ends the fixed-point iteration.
    max_iter : int
        Iteration limit per mode.

    Returns
    -------
    list of Mode
        One per DOF, sorted by frequency.

    Raises
    ------
    InputError
        A stiffness of the wrong shape or non-finite.
    SolverError
        A mode with ω² < 0 (statically unstable), a singular inertia or no convergence.
    """
    names = list(co.dofs(coeffs) if dofs is None else dofs)
    n = len(names)
    mass = co.matrix(coeffs, "mass", names)
    c = co.matrix(coeffs, "hydrostatic_stiffness", names) if hydrostatics else np.zeros((n, n))
    if stiffness is not None:
        extra = np.asarray(stiffness, dtype=float)
        if extra.shape != (n, n) or not np.all(np.isfinite(extra)):
            raise InputError(f"stiffness must be a finite {n}x{n} matrix for DOFs {names}, "
                             f"got shape {extra.shape}")
        c = c + extra

    def inertia(w: float) -> np.ndarray:
        return mass + co.at_frequency(coeffs, "added_mass", w, names)

    def scaled(vec: np.ndarray, w: float) -> np.ndarray:
        """Mode shapes in energy-like units (each DOF by the root of its inertia), unit norm:
        comparable across m and rad."""
        u = np.sqrt(np.abs(np.diag(inertia(w))))[:, None] * vec
        return u / np.linalg.norm(u, axis=0)

    w0 = float(co.omega(coeffs)[0])
    lam0, vec0 = _eigen(c, inertia(w0))
    modes = []
    for k in np.argsort(lam0):
        lam, u_prev, w = lam0[k], scaled(vec0[:, [k]], w0)[:, 0], w0
        for it in range(1, max_iter + 1):
            if lam < -1e-9 * np.abs(np.diag(c)).max(initial=1.0) / np.abs(np.diag(mass)).max():
                raise SolverError(f"natural frequencies: a mode has omega^2 = {lam:.4g} < 0 "
                                  "(statically unstable)")
            w_new = math.sqrt(max(lam, 0.0))
            lams, vecs = _eigen(c, inertia(w_new))
            u = scaled(vecs, w_new)
            j = int(np.argmax(np.abs(u_prev @ u)))  # the same mode at the new frequency
            lam, u_prev = lams[j], u[:, j]
            done = abs(math.sqrt(max(lam, 0.0)) - w_new) <= rtol * max(w_new, 1e-300)
            w = w_new
            if done:
                break
        else:
            raise SolverError(f"natural frequencies: no convergence in {max_iter} iterations "
                              f"(last omega {w:.6g} rad/s)")
        share = u_prev**2 / np.sum(u_prev**2)
        dominant = int(np.argmax(share))
        modes.append(Mode(omega=math.sqrt(max(lam, 0.0)), dominant_dof=names[dominant],
                          energy_share=dict(zip(names, share.tolist())),
                          shape=tuple((vecs[:, j] / vecs[dominant, j]).tolist()),
                          iterations=it))
    return sorted(modes, key=lambda m: m.omega)
