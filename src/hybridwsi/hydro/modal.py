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


def _external(value: np.ndarray | None, names: Sequence[str], what: str) -> np.ndarray:
    """An external (n, n) matrix in the order of ``names`` (zeros when None)."""
    n = len(names)
    if value is None:
        return np.zeros((n, n))
    extra = np.asarray(value, dtype=float)
    if extra.shape != (n, n) or not np.all(np.isfinite(extra)):
        raise InputError(f"{what} must be a finite {n}x{n} matrix for DOFs {list(names)}, "
                         f"got shape {extra.shape}")
    return extra


def _matrices(coeffs: xr.Dataset, stiffness: np.ndarray | None, dofs: Sequence[str] | None,
              hydrostatics: bool) -> tuple[list[str], np.ndarray, np.ndarray]:
    """DOF names, the rigid-body mass and C_hs (optional) + K of the analysis."""
    names = list(co.dofs(coeffs) if dofs is None else dofs)
    n = len(names)
    mass = co.matrix(coeffs, "mass", names)
    c = co.matrix(coeffs, "hydrostatic_stiffness", names) if hydrostatics else np.zeros((n, n))
    return names, mass, c + _external(stiffness, names, "stiffness")


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
    names, mass, c = _matrices(coeffs, stiffness, dofs, hydrostatics)

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


@dataclass(frozen=True)
class DampedMode:
    """One complex mode ``x = v e^{λt}``, ``λ = −ζω ± iω√(1 − ζ²)``, of the damped system.

    Attributes
    ----------
    omega : float
        Undamped natural frequency |λ| [rad/s].
    zeta : float
        Damping ratio −Re λ / |λ| (negative: the mode grows).
    dominant_dof : str
        DOF with the largest share of the mode's displacement (scaled as in :class:`Mode`).
    iterations : int
        Fixed-point iterations used.
    """

    omega: float
    zeta: float
    dominant_dof: str
    iterations: int

    @property
    def damped_omega(self) -> float:
        """Im λ [rad/s], the frequency the decay oscillates at."""
        return self.omega * math.sqrt(max(1.0 - self.zeta**2, 0.0))


def damped_modes(coeffs: xr.Dataset, stiffness: np.ndarray | None = None,
                 damping: np.ndarray | None = None, dofs: Sequence[str] | None = None, *,
                 state_force: tuple[np.ndarray, ...] | None = None,
                 hydrostatics: bool = True, radiation: bool = True, rtol: float = 1e-10,
                 max_iter: int = 100) -> list[DampedMode]:
    """Complex modes of ``(M + A(ω)) ẍ + (B(ω) + B_ext) ẋ + (C_hs + K) x = 0``.

    A and the radiation damping B are taken at each mode's own oscillation frequency Im λ (a
    fixed-point iteration started from, and tracking, the undamped modes of
    :func:`natural_frequencies`). The damping ratio ζ of a mode is what a free decay of that
    mode shows (for light damping; the memory of the radiation force is represented by its
    value at the mode's frequency).

    Parameters
    ----------
    coeffs, stiffness, dofs, hydrostatics, rtol, max_iter
        As :func:`natural_frequencies`.
    damping : (n, n) array, optional
        External linear damping B_ext [N s/m, N s, N m s/rad per DOF pair], e.g. additional
        viscous damping plus an aerodynamic one.
    state_force : (A_s, B_s, C_s, D_s), optional
        A linear force with states of its own (e.g. a controlled rotor,
        :meth:`hybridwsi.forces.PIControlledRotor.state_space`): ``y' = A_s y + B_s ż``,
        ``F = C_s y + D_s ż`` [N, N m]; its states join the eigenproblem.
    radiation : bool
        Include the Dataset's ``radiation_damping`` B(ω).

    Returns
    -------
    list of DampedMode
        One per undamped mode, sorted by ω.
    """
    names, mass, c = _matrices(coeffs, stiffness, dofs, hydrostatics)
    b_ext = _external(damping, names, "damping")
    n = len(names)
    out = []
    for mode in natural_frequencies(coeffs, stiffness, names, hydrostatics=hydrostatics,
                                    rtol=rtol, max_iter=max_iter):
        w, shape = mode.omega, np.asarray(mode.shape)
        for it in range(1, max_iter + 1):
            inertia = mass + co.at_frequency(coeffs, "added_mass", w, names)
            b = b_ext + (co.at_frequency(coeffs, "radiation_damping", w, names) if radiation
                         else 0.0)
            minv = np.linalg.inv(inertia)
            state = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ c, -minv @ b]])
            if state_force is not None:
                a_s, b_s, c_s, d_s = (np.asarray(m, dtype=float) for m in state_force)
                m_s = a_s.shape[0]
                state[n:, n:] += minv @ d_s
                state = np.block([[state, np.vstack([np.zeros((n, m_s)), minv @ c_s])],
                                  [np.zeros((m_s, n)), b_s, a_s]])
            lam, vec = np.linalg.eig(state)
            scale = np.sqrt(np.abs(np.diag(inertia)))
            u = scale[:, None] * vec[:n]
            overlap = np.abs(np.conj(scale * shape) @ u) / np.linalg.norm(u, axis=0)
            j = int(np.argmax(np.where(lam.imag > 0, overlap, -1.0)))
            w_new, done = abs(lam[j].imag), abs(abs(lam[j].imag) - w) <= rtol * max(w, 1e-300)
            shape = vec[:n, j] / vec[:n, j][np.argmax(np.abs(u[:, j]))]
            w = w_new
            if done:
                break
        else:
            raise SolverError(f"damped modes: no convergence in {max_iter} iterations")
        out.append(DampedMode(omega=float(abs(lam[j])), zeta=float(-lam[j].real / abs(lam[j])),
                              dominant_dof=mode.dominant_dof, iterations=it))
    return sorted(out, key=lambda m: m.omega)


def decay_modes(t: np.ndarray, y: np.ndarray, omegas: Sequence[float],
                zeta0: float = 0.02, aperiodic: int = 0) -> list[tuple[float, float]]:
    """Damping ratio and frequency of each mode in a free decay, by least squares.

    Fits ``y(t) = Σ_m e^{−σ_m t} (a_m cos ω_m t + b_m sin ω_m t)`` (one damped oscillation per
    mode of the linear system, e.g. the surge and pitch modes a surge release excites) from
    starting frequencies ``omegas`` [rad/s], plus ``aperiodic`` terms ``c_k e^{−r_k t}`` (real
    modes, e.g. a rotor's speed); ``y`` is the displacement about the equilibrium.

    Returns
    -------
    list of (zeta, omega_n)
        Per mode, in the order of ``omegas``: ζ = σ/ω_n (negative for a growing mode) and the
        undamped frequency ω_n = √(σ² + ω_d²) [rad/s].

    Raises
    ------
    SolverError
        The fit did not converge or leaves more than 1 % of the signal unexplained.
    """
    import scipy.optimize

    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    scale = float(np.max(np.abs(y))) or 1.0

    n_osc = 4 * len(omegas)

    def model(p: np.ndarray) -> np.ndarray:
        out = np.zeros_like(t)
        for s, w, a, b in p[:n_osc].reshape(-1, 4):
            out += np.exp(np.clip(-s * t, -50.0, 50.0)) * (a * np.cos(w * t) + b * np.sin(w * t))
        for r, c in p[n_osc:].reshape(-1, 2):
            out += c * np.exp(np.clip(-r * t, -50.0, 50.0))
        return out

    p0 = np.concatenate([np.ravel([[zeta0 * w, w, y[0] / scale if m == 0 else 0.0, 0.0]
                                   for m, w in enumerate(omegas)]),
                         np.tile([0.1 * omegas[0], 0.0], aperiodic)])
    # each mode's ω stays within a factor 2 of its start and |σ| ≤ 2ω: the modes of a decay
    # are known that well from the linear model, and without bounds a weakly excited mode can
    # escape to the sampling frequency or swap with the other (the fit then depends on
    # round-off, e.g. on the BLAS thread count)
    lo = np.concatenate([np.ravel([[-2 * w, 0.5 * w, -np.inf, -np.inf] for w in omegas]),
                         np.tile([-np.inf, -np.inf], aperiodic)])
    hi = np.concatenate([np.ravel([[2 * w, 2 * w, np.inf, np.inf] for w in omegas]),
                         np.tile([np.inf, np.inf], aperiodic)])
    fit = scipy.optimize.least_squares(lambda p: model(p) - y / scale, p0, bounds=(lo, hi),
                                       x_scale="jac")
    if not fit.success or np.sqrt(np.mean(fit.fun**2)) > 0.01 * np.std(y / scale):
        raise SolverError("decay_modes: the damped-mode fit does not describe the decay")
    return [(float(s / math.hypot(s, w)), float(math.hypot(s, w)))
            for s, w, _, _ in fit.x[:n_osc].reshape(-1, 4)]
