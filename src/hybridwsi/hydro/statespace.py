"""Radiation state-space realisation of the Cummins memory kernel K(t) (paper Eq. 9–10).

The convolution ``F_mem(t) = -∫_0^t K(t - τ) ż(τ) dτ`` is replaced by a linear system with
internal states ``x``::

    ẋ = A_r x + B_r ż,        F_mem = -C_r x,        K(t) ≈ C_r exp(A_r t) B_r.

The realisation is found with the Eigensystem Realisation Algorithm (ERA, Kung's Hankel-SVD
method) applied to the sampled kernel ``K_k = K(k Δt) = C Φ^k B`` with ``Φ = exp(A Δt)``:

1. build the block-Hankel matrices ``H0[i, j] = K_{i+j}`` and ``H1[i, j] = K_{i+j+1}``;
2. truncate the SVD ``H0 = U S Vᵀ`` to order ``n``: ``Φ = S^{-1/2} Uᵀ H1 V S^{-1/2}``,
   ``B = S^{1/2} Vᵀ[:, :m]``, ``C = U[:p] S^{1/2}``;
3. convert to continuous time, ``A = log(Φ)/Δt`` (eigen-decomposition), reflect any pole with
   ``Re s ≥ 0`` into the left half-plane (reported as ``n_reflected``);
4. refine ``C`` by linear least squares on every sample of K (this also repairs the small
   misfit a reflection introduces).

The order is the smallest ``n ≤ max_order`` whose relative RMS fit error in time is below
``tol`` (or the best one, flagged ``converged=False``). The frequency response of the
realisation is ``K̂(ω) = C (iωI − A)^{-1} B = ∫_0^∞ K(t) e^{-iωt} dt``, so
``Re K̂(ω) = B(ω)`` (radiation damping) and ``Im K̂(ω)/ω = A(ω) − A∞`` (Ogilvie:
``A(ω) = A∞ − (1/ω)∫_0^∞ K(t) sin ωt dt``).

Layout: K is a DataArray ``K(time, radiating_dof, influenced_dof)`` as produced by
:func:`hybridwsi.hydro.irf.radiation_irf`; the force on the influenced DOF i is
``-Σ_j ∫ K[:, j, i] ż_j``. Internally the system maps velocities (radiating DOFs, inputs) to
forces (influenced DOFs, outputs), so the Markov parameters are ``K[k].T``. MIMO is handled by
one stacked realisation.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg
import xarray as xr

from hybridwsi.errors import InputError

#: largest Hankel block dimension (block rows = block columns); K is decimated to fit
MAX_HANKEL = 120


@dataclass
class RadiationSS:
    """Continuous-time state-space model of the radiation memory kernel.

    Attributes
    ----------
    A, B, C, D : ndarray
        ``A`` (n, n) [1/s], ``B`` (n, n_rad), ``C`` (n_inf, n) with ``K(t) ≈ C e^{At} B``
        [N s/m per s]; ``D`` (n_inf, n_rad) is zero (kept for the standard form).
    radiating_dof, influenced_dof : list of str
        DOF names of the inputs (velocities) and outputs (forces).
    fit_error : dict
        ``time``: relative RMS error of the impulse response on the fitted samples;
        ``frequency``: relative RMS error of ``Re K̂(ω)`` against the cosine transform of the
        sampled K (and ``frequency_bem`` against the coefficients' B(ω) when given).
    n_reflected : int
        Number of unstable identified poles reflected into the left half-plane.
    converged : bool
        False when no order up to ``max_order`` met ``tol``.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    radiating_dof: list[str]
    influenced_dof: list[str]
    fit_error: dict[str, float | None] = field(default_factory=dict)
    n_reflected: int = 0
    converged: bool = True
    dt_fit: float = float("nan")

    @property
    def order(self) -> int:
        """Number of internal states."""
        return int(self.A.shape[0])

    @property
    def poles(self) -> np.ndarray:
        """Continuous-time poles [1/s] (all with negative real part)."""
        return np.linalg.eigvals(self.A) if self.order else np.zeros(0, complex)

    def impulse(self, t: np.ndarray) -> np.ndarray:
        """Kernel ``K̂(t) = C e^{At} B`` at times ``t`` [s], shape (nt, n_rad, n_inf)."""
        t = np.asarray(t, dtype=float)
        nr, ni = len(self.radiating_dof), len(self.influenced_dof)
        if self.order == 0:
            return np.zeros((t.size, nr, ni))
        lam, vec = np.linalg.eig(self.A)
        cv = self.C @ vec  # (ni, n)
        vb = np.linalg.solve(vec, self.B)  # (n, nr)
        # modal sum: K(t)[i, j] = Σ_m cv[i, m] e^{λ_m t} vb[m, j]
        out = np.einsum("im,tm,mj->tji", cv, np.exp(np.outer(t, lam)), vb)
        return np.real(out)

    def frequency_response(self, omega: np.ndarray) -> np.ndarray:
        """``K̂(ω) = C (iωI − A)^{-1} B + D``, shape (nω, n_rad, n_inf), complex [N s/m].

        ``Re`` is the radiation damping B(ω); ``Im/ω`` is ``A(ω) − A∞`` [kg].
        """
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        n = self.order
        out = np.empty((omega.size, len(self.radiating_dof), len(self.influenced_dof)), complex)
        for k, w in enumerate(omega):
            g = self.D.astype(complex)
            if n:
                g = g + self.C @ np.linalg.solve(1j * w * np.eye(n) - self.A, self.B)
            out[k] = g.T
        return out

    def equivalent_damping(self, omega: float) -> np.ndarray:
        """Damping matrix ``Re K̂(ω)`` [N s/m] at one frequency, (n_inf, n_rad) orientation."""
        return np.real(self.frequency_response([omega])[0]).T

    def equivalent_added_mass(self, omega: float) -> np.ndarray:
        """``A(ω) − A∞ = Im K̂(ω)/ω`` [kg] at one frequency, (n_inf, n_rad) orientation."""
        if omega <= 0:
            raise InputError("equivalent_added_mass needs omega > 0")
        return np.imag(self.frequency_response([omega])[0]).T / omega

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable description (matrices as nested lists)."""
        return {
            "order": self.order,
            "A": self.A.tolist(),
            "B": self.B.tolist(),
            "C": self.C.tolist(),
            "D": self.D.tolist(),
            "radiating_dof": list(self.radiating_dof),
            "influenced_dof": list(self.influenced_dof),
            "fit_error": dict(self.fit_error),
            "n_reflected": self.n_reflected,
            "converged": self.converged,
            "dt_fit": self.dt_fit,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RadiationSS:
        """Inverse of :meth:`to_dict`."""
        arr = {k: np.asarray(d[k], dtype=float) for k in "ABCD"}
        n, ni, nr = int(d["order"]), len(d["influenced_dof"]), len(d["radiating_dof"])
        arr["A"] = arr["A"].reshape(n, n)
        arr["B"] = arr["B"].reshape(n, nr)
        arr["C"] = arr["C"].reshape(ni, n)
        arr["D"] = arr["D"].reshape(ni, nr)
        return cls(**arr, radiating_dof=list(d["radiating_dof"]),
                   influenced_dof=list(d["influenced_dof"]), fit_error=dict(d["fit_error"]),
                   n_reflected=int(d["n_reflected"]), converged=bool(d["converged"]),
                   dt_fit=float(d["dt_fit"]))


# --------------------------------------------------------------------------- input handling
def _kernel_array(K: xr.DataArray | np.ndarray, dt: float | None
                  ) -> tuple[np.ndarray, float, list[str], list[str]]:
    """K as an array (nt, n_rad, n_inf), its uniform step [s] and the DOF names."""
    if isinstance(K, xr.DataArray):
        if "time" not in K.dims:
            raise InputError("radiation kernel K needs a 'time' dimension")
        dims = [d for d in ("radiating_dof", "influenced_dof") if d in K.dims]
        K = K.transpose("time", *dims)
        t = np.asarray(K["time"].values, dtype=float)
        if t.size < 8:
            raise InputError(f"radiation kernel has {t.size} samples; at least 8 are needed")
        steps = np.diff(t)
        if np.any(steps <= 0) or np.ptp(steps) > 1e-6 * np.mean(steps):
            raise InputError("radiation kernel K must be sampled on a uniform increasing time grid")
        if abs(t[0]) > 1e-9 * steps[0] + 1e-12:
            raise InputError(f"radiation kernel must start at t = 0 (starts at {t[0]:g} s)")
        dt = float(np.mean(steps))
        rad = [str(v) for v in K["radiating_dof"].values] if "radiating_dof" in K.dims else ["Heave"]
        inf = [str(v) for v in K["influenced_dof"].values] if "influenced_dof" in K.dims else rad
        arr = np.asarray(K.values, dtype=float).reshape(t.size, len(rad), len(inf))
    else:
        if dt is None or not dt > 0:
            raise InputError("a plain-array radiation kernel needs its time step dt > 0 [s]")
        arr = np.asarray(K, dtype=float)
        if arr.ndim == 1:
            arr = arr[:, None, None]
        if arr.ndim != 3 or arr.shape[1] != arr.shape[2]:
            raise InputError(f"radiation kernel must have shape (nt,) or (nt, n, n), got {arr.shape}")
        rad = inf = ["Heave"] if arr.shape[1] == 1 else [f"dof{i}" for i in range(arr.shape[1])]
    if not np.all(np.isfinite(arr)):
        raise InputError("radiation kernel K contains NaN/inf")
    if not np.any(arr):
        raise InputError("radiation kernel K is identically zero; use radiation=None instead")
    return arr, float(dt), rad, inf


# --------------------------------------------------------------------------- ERA core
def _hankel(markov: np.ndarray, rows: int, cols: int, shift: int) -> np.ndarray:
    """Block Hankel matrix of Markov parameters ``markov[k]`` (p, m), starting at ``shift``."""
    p, m = markov.shape[1:]
    h = np.empty((rows * p, cols * m))
    for i in range(rows):
        blk = markov[i + shift: i + shift + cols]  # (cols, p, m)
        h[i * p:(i + 1) * p] = blk.transpose(1, 0, 2).reshape(p, cols * m)
    return h


def _to_continuous(phi: np.ndarray, dt: float) -> tuple[np.ndarray, int]:
    """``A = log(Φ)/Δt`` with poles reflected into Re s < 0; returns (A, n_reflected)."""
    lam, vec = np.linalg.eig(phi)
    if np.any(np.abs(lam) < 1e-300):
        raise InputError("ERA produced a zero discrete pole; reduce the model order")
    s = np.log(lam.astype(complex)) / dt
    bad = s.real >= 0
    # reflection keeps |Im s| (the oscillation) and the magnitude of the decay rate
    s = np.where(bad, -np.abs(s.real) - 1e-9 / dt + 1j * s.imag, s)
    a = vec @ np.diag(s) @ np.linalg.inv(vec)
    if np.max(np.abs(a.imag)) > 1e-6 * max(np.max(np.abs(a.real)), 1.0):
        # a negative real discrete pole has no real logarithm: the fit is aliased
        raise InputError("ERA realisation has no real continuous equivalent (aliasing); "
                         "sample K more finely or lower the order")
    return np.real(a), int(bad.sum())


def _refit_c(a: np.ndarray, b: np.ndarray, t: np.ndarray, markov: np.ndarray) -> np.ndarray:
    """Least-squares ``C`` so that ``C e^{A t_k} B ≈ K_k`` on all samples."""
    lam, vec = np.linalg.eig(a)
    vb = np.linalg.solve(vec, b)  # (n, m)
    # regressor e^{A t_k} B = V diag(e^{λ t_k}) V^{-1} B, stacked over k as columns
    reg = np.real(np.einsum("nq,kq,qm->nkm", vec, np.exp(np.outer(t, lam)), vb))
    n, nk, m = reg.shape
    lhs = reg.reshape(n, nk * m)  # C @ lhs = rhs
    rhs = markov.transpose(1, 0, 2).reshape(markov.shape[1], nk * m)
    c, *_ = np.linalg.lstsq(lhs.T, rhs.T, rcond=None)
    return c.T


def _cosine_transform(k: np.ndarray, dt: float, omega: np.ndarray) -> np.ndarray:
    """``∫_0^T K(t) cos ωt dt`` by the trapezoid rule, shape (nω, n_rad, n_inf)."""
    t = np.arange(k.shape[0]) * dt
    w = np.full(t.size, dt)
    w[[0, -1]] *= 0.5
    return np.einsum("wt,tij->wij", np.cos(np.outer(omega, t)) * w, k)


def _rel_rms(est: np.ndarray, ref: np.ndarray) -> float:
    return float(np.linalg.norm(est - ref) / max(np.linalg.norm(ref), 1e-300))


def fit_radiation_ss(
    K: xr.DataArray | np.ndarray,
    *,
    order: int | None = None,
    max_order: int = 20,
    tol: float = 0.01,
    method: str = "hankel",
    dt: float | None = None,
    coeffs: xr.Dataset | None = None,
    balance: bool = False,
) -> RadiationSS:
    """Realise the radiation kernel K(t) as a stable continuous state-space model.

    Parameters
    ----------
    K : xarray.DataArray or ndarray
        Kernel ``K(time, radiating_dof, influenced_dof)`` [N s/m / s = kg/s²], sampled
        uniformly from t = 0 (a 1-D array is one DOF).
    order : int, optional
        Fixed model order; by default the smallest order with time fit error < ``tol``.
    max_order : int
        Largest order tried by the automatic selection.
    tol : float
        Target relative RMS error of the impulse response (0.01 = 1 %).
    method : {"hankel"}
        Only ERA/Hankel-SVD is implemented.
    dt : float, optional
        Time step [s] of a plain-array K.
    coeffs : xarray.Dataset, optional
        BEM coefficients; when given, ``fit_error["frequency_bem"]`` compares ``Re K̂(ω)``
        with their ``radiation_damping`` B(ω).
    balance : bool
        Fit ``K_ij / (s_i s_j)`` with ``s_i = sqrt(max_t |K_ii|)`` (every diagonal kernel of
        peak 1) and scale the realisation back (``B`` by ``s_rad``, ``C`` by ``s_inf``): the
        joint fit then weighs every DOF alike instead of the largest entries (N m s/rad of a
        rotation against N s/m of a translation), and the order selection and ``tol`` refer to
        the balanced kernel. Needs the same DOFs radiating and influenced.

    Returns
    -------
    RadiationSS
    """
    if method != "hankel":
        raise InputError(f"unknown state-space fitting method '{method}' (use 'hankel')")
    if not 0 < tol < 1:
        raise InputError(f"tol must be in (0, 1), got {tol}")
    arr, dt0, rad, inf = _kernel_array(K, dt)
    scale = _balance_scale(arr, rad, inf) if balance else np.ones(arr.shape[1])
    markov = (arr / np.outer(scale, scale)).transpose(0, 2, 1)  # (nt, p=n_inf, m=n_rad)
    nt, p, m = markov.shape
    t_all = np.arange(nt) * dt0
    # decimate so that the Hankel matrix spans the whole kernel with at most MAX_HANKEL blocks
    step = max(1, int(np.ceil((nt - 1) / (2 * MAX_HANKEL))))
    mk = markov[::step]
    dth = dt0 * step
    rows = (mk.shape[0] - 1) // 2
    cols = mk.shape[0] - 1 - rows
    if rows < 2:
        raise InputError("radiation kernel is too short to fit a state-space model")
    h0, h1 = _hankel(mk, rows, cols, 0), _hankel(mk, rows, cols, 1)
    u, sv, vt = np.linalg.svd(h0, full_matrices=False)
    n_max = int(min(max_order, np.sum(sv > sv[0] * 1e-12), rows * p))
    if order is not None:
        if not 1 <= order <= min(rows * p, np.sum(sv > 0)):
            raise InputError(f"order must be between 1 and {min(rows * p, np.sum(sv > 0))}")
        candidates = [int(order)]
    else:
        if max_order < 1:
            raise InputError("max_order must be >= 1")
        candidates = list(range(1, max(n_max, 1) + 1))
    best: tuple[float, Any] | None = None
    for n in candidates:
        try:
            fit = _era_order(u, sv, vt, h1, n, p, m, dth, t_all, markov)
        except InputError:
            continue  # aliased/degenerate order: try the next one
        err = _rel_rms(_impulse_markov(fit, t_all), markov)
        if best is None or err < best[0]:
            best = (err, fit)
        if err < tol:
            break
    if best is None:
        raise InputError("no stable state-space realisation found for K; check the kernel")
    err, (a, b, c, n_ref) = best
    b, c = b * scale[None, :], scale[:, None] * c  # back to the kernel's units
    ss = RadiationSS(A=a, B=b, C=c, D=np.zeros((p, m)), radiating_dof=rad, influenced_dof=inf,
                     n_reflected=n_ref, converged=err < tol or order is not None, dt_fit=dth)
    ss.fit_error = _fit_errors(ss, arr, dt0, err, coeffs)
    if not ss.converged:
        warnings.warn(f"radiation state space: order {ss.order} reaches a fit error of "
                      f"{err:.3g} > tol={tol}", stacklevel=2)
    return ss


def _balance_scale(arr: np.ndarray, rad: list[str], inf: list[str]) -> np.ndarray:
    """``sqrt(max_t |K_ii(t)|)`` per DOF (1 for a DOF whose kernel vanishes)."""
    if list(rad) != list(inf):
        raise InputError("balance needs the same radiating and influenced DOFs")
    peak = np.abs(np.diagonal(arr, axis1=1, axis2=2)).max(axis=0)
    return np.sqrt(np.where(peak > 0, peak, 1.0))


def _era_order(u, sv, vt, h1, n, p, m, dth, t_all, markov):
    """ERA realisation of order n, continuous and stable, with C refitted on all samples."""
    s_half = np.sqrt(sv[:n])
    phi = (u[:, :n].T @ h1 @ vt[:n].T) / np.outer(s_half, s_half)
    b = (s_half[:, None] * vt[:n])[:, :m]
    a, n_ref = _to_continuous(phi, dth)
    c = _refit_c(a, b, t_all, markov)
    return a, b, c, n_ref


def _impulse_markov(fit, t: np.ndarray) -> np.ndarray:
    a, b, c, _ = fit
    lam, vec = np.linalg.eig(a)
    return np.real(np.einsum("in,tn,nj->tij", c @ vec, np.exp(np.outer(t, lam)),
                             np.linalg.solve(vec, b)))


def _fit_errors(ss: RadiationSS, arr: np.ndarray, dt: float, err_time: float,
                coeffs: xr.Dataset | None) -> dict[str, float | None]:
    """Time and frequency fit errors (relative RMS)."""
    t_end = (arr.shape[0] - 1) * dt
    # frequencies resolved by the sampled kernel: from 2π/T to a tenth of Nyquist
    omega = np.linspace(2 * np.pi / t_end, 0.1 * np.pi / dt, 200)
    b_ref = _cosine_transform(arr, dt, omega)
    out: dict[str, float | None] = {
        "time": err_time,
        "frequency": _rel_rms(np.real(ss.frequency_response(omega)), b_ref),
        "frequency_bem": None,
    }
    if coeffs is not None and "radiation_damping" in coeffs:
        bd = coeffs["radiation_damping"].sel(radiating_dof=ss.radiating_dof,
                                             influenced_dof=ss.influenced_dof)
        w = np.asarray(coeffs["omega"].values, dtype=float)
        out["frequency_bem"] = _rel_rms(np.real(ss.frequency_response(w)),
                                        np.asarray(bd.transpose("omega", ...).values))
    return out


# --------------------------------------------------------------------------- time stepping
def foh_matrices(a: np.ndarray, b: np.ndarray, dt: float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact discretisation of ``ẏ = A y + B u`` for piecewise-linear ``u`` (first-order hold).

    Returns ``(Φ, Γ_k, Γ_k1)`` with ``y_{k+1} = Φ y_k + Γ_k u_k + Γ_k1 u_{k+1}``.
    """
    n, m = b.shape
    big = np.zeros((n + 2 * m, n + 2 * m))
    big[:n, :n], big[:n, n:n + m] = a * dt, b * dt
    big[n:n + m, n + m:] = np.eye(m)
    e = scipy.linalg.expm(big)
    phi, g_a, g_b = e[:n, :n], e[:n, n:n + m], e[:n, n + m:]
    return phi, g_a - g_b, g_b


def simulate_states(ss: RadiationSS, velocity: np.ndarray, dt: float,
                    x0: np.ndarray | None = None) -> np.ndarray:
    """States ``x_k`` driven by sampled velocities ``velocity`` (nt, n_rad), FOH-exact."""
    phi, g0, g1 = foh_matrices(ss.A, ss.B, dt)
    x = np.zeros((velocity.shape[0], ss.order))
    x[0] = 0.0 if x0 is None else x0
    for k in range(velocity.shape[0] - 1):
        x[k + 1] = phi @ x[k] + g0 @ velocity[k] + g1 @ velocity[k + 1]
    return x
