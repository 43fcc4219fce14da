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
   misfit a reflection introduces), restricted to ``C A⁻¹ B = 0`` so that ``K̂(0) = B(0) = 0``
   (``low_frequency``);
5. make the model passive, ``Re K̂(iω) ⪰ 0`` at every ω, by the least change of ``C``
   (residue perturbation on a grid covering the poles and both asymptotes; ``passive``).
   docs/THEORY.md ("Radiation state space") says what is enforced and how.

The order is the smallest ``n ≤ max_order`` whose fit error in time (worst DOF pair) is below
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
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import scipy.linalg
import scipy.optimize
import xarray as xr

from hybridwsi.errors import InputError

#: largest Hankel block dimension (block rows = block columns); K is decimated to fit
MAX_HANKEL = 120
#: low-frequency treatments of :func:`fit_radiation_ss`
LOW_FREQUENCY = ("auto", "zero", "free")
#: |∫K_ii dt| / ∫|K_ii| dt above which "auto" leaves B(0) free (a kernel with B(0) ≠ 0)
DC_AUTO = 0.05
#: the passivity grid spans [min|λ|, max|λ|] of the poles widened by this factor each way
#: (plus ω = 0 and the two asymptotes, :func:`_asymptotes`)
PASSIVITY_SPAN = 100.0
#: log-spaced frequencies of the passivity grid (plus the poles' |Im λ|)
PASSIVITY_POINTS = 3000
#: smallest eigenvalue of Re K̂(iω), relative to the largest, accepted as passive (round-off)
PASSIVITY_TOL = 1e-8
#: orders made passive when none meets ``tol`` (those of smallest unconstrained error)
PASSIVITY_TRIES = 5
#: rounds of linearised constraints in the passivity enforcement
PASSIVITY_ITER = 20


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
        ``time``: the impulse response's RMS error on the fitted samples, worst DOF pair,
        relative to the geometric mean RMS of the pair's diagonal kernels;
        ``frequency``: relative RMS error of ``Re K̂(ω)`` against the cosine transform of the
        sampled K (and ``frequency_bem`` against the coefficients' B(ω) when given).
    n_reflected : int
        Number of unstable identified poles reflected into the left half-plane.
    converged : bool
        False when no order up to ``max_order`` met ``tol``.
    dt_fit : float
        Sampling step [s] of the Hankel matrices.
    low_frequency : {"zero", "free"}
        Whether ``K̂(0) = 0`` was imposed.
    passivity_min : float or None
        Smallest eigenvalue of the Hermitian part of ``K̂(iω)`` over the fit's passivity grid,
        relative to the largest, in the DOF-scaled units of the fit (passive: >= -PASSIVITY_TOL);
        None when passivity was not checked.
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
    low_frequency: str = "free"
    passivity_min: float | None = None

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

    def passivity(self, omega: np.ndarray) -> np.ndarray:
        """Smallest eigenvalue of the Hermitian part of ``S⁻¹ K̂(iω) S⁻¹`` at each ω [rad/s].

        ``S = diag(√b_i)`` with ``b_i`` the largest ``Re K̂_ii`` over ``omega``: a
        dimensionless index, comparable across DOFs in m and rad, negative where the model
        generates energy (a passive radiation force absorbs it at every ω). Needs as many
        radiating as influenced DOFs.
        """
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        h = self.frequency_response(omega)  # (nω, n_rad, n_inf)
        if h.shape[1] != h.shape[2]:
            raise InputError("passivity needs as many radiating as influenced DOFs")
        peak = np.real(np.einsum("wii->wi", h)).max(axis=0)
        inv = 1.0 / np.sqrt(np.where(peak > 0, peak, 1.0))
        g = h * np.outer(inv, inv)[None]
        return np.linalg.eigvalsh(0.5 * (g + np.conj(g.transpose(0, 2, 1))))[:, 0]

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
            "low_frequency": self.low_frequency,
            "passivity_min": self.passivity_min,
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
                   dt_fit=float(d["dt_fit"]), low_frequency=str(d.get("low_frequency", "free")),
                   passivity_min=d.get("passivity_min"))


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
    balance: bool | None = None,
    low_frequency: str = "auto",
    passive: bool = True,
    max_pole: float | None = None,
) -> RadiationSS:
    """Realise the radiation kernel K(t) as a stable, passive continuous state-space model.

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
        Target fit error of the impulse response (0.01 = 1 %; worst DOF pair, module docstring).
    method : {"hankel"}
        Only ERA/Hankel-SVD is implemented.
    dt : float, optional
        Time step [s] of a plain-array K.
    coeffs : xarray.Dataset, optional
        BEM coefficients; when given, ``fit_error["frequency_bem"]`` compares ``Re K̂(ω)``
        with their ``radiation_damping`` B(ω).
    balance : bool, optional
        Fit ``K_ij / (s_i s_j)``, every DOF weighed alike (:func:`_dof_scales`). ``None``
        (default): whenever the same DOFs radiate and are influenced; ``True`` requires that;
        ``False`` fits K in SI units.
    low_frequency : {"auto", "zero", "free"}
        ``"zero"`` imposes ``K̂(0) = B(0) = 0`` exactly, ``"free"`` leaves it to the fit,
        ``"auto"`` decides from the kernel (:func:`_low_frequency_mode`); recorded in
        ``RadiationSS.low_frequency``.
    passive : bool
        Enforce passivity, ``Re K̂(iω)`` (its Hermitian part) positive semi-definite at every
        ω, by a least perturbation of ``C`` (module docstring).
    max_pole : float, optional
        Largest pole magnitude ``|λ|`` [1/s] accepted (faster orders skipped): RK4 with step
        Δt needs ``|λ| Δt`` ≲ 2; ``cummins`` passes ``2/Δt`` when it fits the model itself.

    Returns
    -------
    RadiationSS
    """
    _check_fit_options(method, tol)
    arr, dt0, rad, inf = _kernel_array(K, dt)
    low_frequency = _low_frequency_mode(arr, dt0, low_frequency)
    s_rad, s_inf = _dof_scales(arr, rad, inf, balance)
    # scaled Markov parameters (output force, input velocity): every DOF pair weighs alike
    markov = (arr / np.outer(s_rad, s_inf)[None]).transpose(0, 2, 1)
    nt, p, m = markov.shape
    t_all = np.arange(nt) * dt0
    u, sv, vt, h1, dth, candidates = _hankel_svd(markov, dt0, order, max_order)

    def fit_n(n: int) -> _Fit | None:
        fit = _fit_order(u, sv, vt, h1, n, m, dth, t_all, markov, low_frequency)
        too_fast = max_pole is not None and fit is not None and \
            np.abs(np.linalg.eigvals(fit.a)).max() > max_pole
        return None if too_fast else fit

    best = _select_order(fit_n, candidates, tol, markov, passive, fixed=order is not None)
    if best is None:
        raise InputError("no stable state-space realisation found for K; check the kernel")
    ss = RadiationSS(A=best.a, B=best.b * s_rad[None], C=s_inf[:, None] * best.c,
                     D=np.zeros((p, m)), radiating_dof=rad, influenced_dof=inf,
                     n_reflected=best.n_reflected,
                     converged=best.error < tol or order is not None,
                     dt_fit=dth, low_frequency=low_frequency, passivity_min=best.passivity)
    ss.fit_error = _fit_errors(ss, arr, dt0, best.error, coeffs)
    _warn_fit(ss, best.error, tol, passive)
    return ss


def _check_fit_options(method: str, tol: float) -> None:
    """:class:`InputError` for an unknown method or a tolerance outside (0, 1)."""
    if method != "hankel":
        raise InputError(f"unknown state-space fitting method '{method}' (use 'hankel')")
    if not 0 < tol < 1:
        raise InputError(f"tol must be in (0, 1), got {tol}")


def _warn_fit(ss: RadiationSS, err: float, tol: float, passive: bool) -> None:
    """Warn when the fit did not reach ``tol`` or (``passive``) passivity."""
    if not ss.converged:
        warnings.warn(f"radiation state space: order {ss.order} reaches a fit error of "
                      f"{err:.3g} > tol={tol}", stacklevel=3)
    if passive and ss.passivity_min < -PASSIVITY_TOL:
        warnings.warn(f"radiation state space: passivity not reached (smallest relative "
                      f"eigenvalue of Re K̂(iω) {ss.passivity_min:.3g})", stacklevel=3)


def _low_frequency_mode(arr: np.ndarray, dt: float, low_frequency: str) -> str:
    """``"zero"`` or ``"free"``, the low-frequency constraint of :func:`fit_radiation_ss`.

    ``"zero"`` imposes ``K̂(0) = B(0) = 0`` exactly (a radiation kernel: the damping of a
    floating body vanishes at zero frequency); ``"free"`` leaves ``K̂(0)`` to the fit (a kernel
    with ``∫K dt ≠ 0``, e.g. a closed form that is not a radiation kernel); ``"auto"``:
    ``"zero"`` unless the kernel's own ``|∫K_ii dt|`` exceeds ``DC_AUTO`` (5 %) of
    ``∫|K_ii| dt`` for some DOF (``radiation_irf`` kernels are at most 4 % for the shipped
    bodies, the truncation; B sampled from a nonzero B(0) gives more). A ``"zero"`` imposed
    on a kernel with B(0) ≠ 0 is warned.
    """
    if low_frequency not in LOW_FREQUENCY:
        raise InputError(f"low_frequency must be one of {', '.join(LOW_FREQUENCY)}, "
                         f"got {low_frequency!r}")
    dc = _dc_ratio(arr, dt)
    if low_frequency == "auto":
        return "zero" if dc <= DC_AUTO else "free"
    if low_frequency == "zero" and dc > DC_AUTO:
        warnings.warn(f"radiation state space: the kernel has ∫K dt = B(0) ≠ 0 ({dc:.0%} of "
                      "∫|K| dt) but low_frequency='zero' imposes B(0) = 0", stacklevel=3)
    return low_frequency


def _hankel_svd(markov: np.ndarray, dt: float, order: int | None, max_order: int
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, list[int]]:
    """SVD ``u, sv, vt`` of the Hankel matrix of the Markov parameters (sampled every
    ``dt`` [s]), the shifted Hankel matrix, the decimated step [s] and the orders to try."""
    nt, p, _ = markov.shape
    # decimate so that the Hankel matrix spans the whole kernel with at most MAX_HANKEL blocks
    step = max(1, int(np.ceil((nt - 1) / (2 * MAX_HANKEL))))
    mk = markov[::step]
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
        return u, sv, vt, h1, dt * step, [int(order)]
    if max_order < 1:
        raise InputError("max_order must be >= 1")
    return u, sv, vt, h1, dt * step, list(range(1, max(n_max, 1) + 1))


def _select_order(fit_n, candidates: list[int], tol: float, markov: np.ndarray,
                  passive: bool, fixed: bool) -> _Fit | None:
    """The smallest order whose fit, made passive, has an error below ``tol``; when none has,
    the best passive one among the ``PASSIVITY_TRIES`` orders of smallest unconstrained error
    (the enforcement may fail for one set of poles and succeed for the next)."""
    best: _Fit | None = None
    pending: list[tuple[float, int]] = []  # (unconstrained error, order) of the misses
    for n in candidates:
        fit = fit_n(n)
        if fit is None:
            continue  # aliased/degenerate order, or none left by the K̂(0) = 0 constraint
        if fit.error >= tol and not fixed:
            pending.append((fit.error, n))
            continue
        fit = _enforce_passivity(fit, markov) if passive else fit
        best = fit if best is None or _rank(fit) < _rank(best) else best
        if (fit.error < tol or fixed) and _rank(fit)[0] == 0:
            return fit
    for _, n in sorted(pending)[:PASSIVITY_TRIES]:
        fit = fit_n(n)
        fit = _enforce_passivity(fit, markov) if passive else fit
        best = fit if best is None or _rank(fit) < _rank(best) else best
    return best


def _rank(fit: _Fit) -> tuple[int, float]:
    """Passive (or not checked) fits first, then by fit error."""
    return (int(fit.passivity is not None and fit.passivity < -PASSIVITY_TOL), fit.error)


@dataclass
class _Fit:
    """One order's realisation in scaled units, with the least-squares problem for ``C``:
    ``C = Z Pᵀ`` and ``‖R z_i − f_i‖`` per output row i (QR-reduced)."""

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    n_reflected: int
    error: float
    basis: np.ndarray  # P (n, q): the rows of C allowed by the K̂(0) constraint
    r: np.ndarray  # (q, q)
    f: np.ndarray  # (q, p)
    reg: np.ndarray  # (n, nt, m): e^{A t_k} B, the impulse response is C times it
    passivity: float | None = None


def _dof_scales(arr: np.ndarray, rad: list[str], inf: list[str], balance: bool | None
                ) -> tuple[np.ndarray, np.ndarray]:
    """Per-DOF scales ``s_i = √max|K_ii|`` [√(kg/s²) or per rad] of the inputs and outputs.

    The fit works on ``K_ij / (s_i s_j)``, a congruence that leaves passivity unchanged and
    makes every diagonal kernel of size 1: in SI units a spar's pitch kernel is ~10⁴ times
    its surge kernel (N m s/rad of a rotation against N s/m of a translation) and would
    otherwise decide the fit alone; the realisation is scaled back (``B`` by ``s_rad``, ``C``
    by ``s_inf``)."""
    if balance and list(rad) != list(inf):
        raise InputError("balance needs the same radiating and influenced DOFs")
    if balance is False or list(rad) != list(inf):
        return np.ones(len(rad)), np.ones(len(inf))
    peak = np.abs(np.einsum("tii->ti", arr)).max(axis=0)
    peak = np.where(peak > 0, peak, np.abs(arr).max())
    return np.sqrt(peak), np.sqrt(peak)


def _dc_ratio(arr: np.ndarray, dt: float) -> float:
    """Largest ``|∫K_ii dt| / ∫|K_ii| dt`` over the diagonal kernels (all pairs when the kernel
    is not square): how far the sampled kernel's own ``B(0)`` is from zero."""
    dc = np.abs(np.trapezoid(arr, dx=dt, axis=0))
    size = np.trapezoid(np.abs(arr), dx=dt, axis=0)
    ratio = dc / np.where(size > 0, size, np.inf)
    return float(np.max(np.diagonal(ratio) if ratio.shape[0] == ratio.shape[1] else ratio))


def _pair_error(est: np.ndarray, ref: np.ndarray) -> float:
    """Worst DOF pair's RMS error of ``est`` (nt, p, m) against ``ref``, relative to the
    geometric mean RMS of the pair's two diagonal kernels (the global relative error when
    the kernel is not square or a diagonal is zero)."""
    p, m = ref.shape[1:]
    rms = np.sqrt(np.mean(ref**2, axis=0))
    err = np.sqrt(np.mean((est - ref) ** 2, axis=0))
    diag = np.diagonal(rms) if p == m else np.zeros(0)
    if p != m or np.any(diag <= 0):
        return _rel_rms(est, ref)
    return float(np.max(err / np.sqrt(np.outer(diag, diag))))


def _fit_order(u, sv, vt, h1, n, m, dth, t_all, markov, low_frequency) -> _Fit | None:
    """ERA realisation of order n, continuous and stable; ``C`` by least squares on all
    samples of K, constrained to ``K̂(0) = −C A⁻¹ B = 0`` when ``low_frequency="zero"``."""
    s_half = np.sqrt(sv[:n])
    phi = (u[:, :n].T @ h1 @ vt[:n].T) / np.outer(s_half, s_half)
    b = (s_half[:, None] * vt[:n])[:, :m]
    try:
        a, n_ref = _to_continuous(phi, dth)
    except InputError:
        return None
    reg = _regressor(a, b, t_all)  # (n, nt, m): e^{A t_k} B
    if low_frequency == "zero":
        basis = scipy.linalg.null_space(np.linalg.solve(a, b).T)  # rows c with c A⁻¹B = 0
        if basis.shape[1] == 0:
            return None
    else:
        basis = np.eye(n)
    nt, p, _ = markov.shape
    lhs = (basis.T @ reg.reshape(n, nt * m)).T  # (nt m, q): Z Pᵀ reg = K
    rhs = markov.transpose(1, 0, 2).reshape(p, nt * m).T
    q_mat, r = np.linalg.qr(lhs)
    f = q_mat.T @ rhs
    z = np.linalg.lstsq(r, f, rcond=None)[0].T
    c = z @ basis.T
    err = _pair_error(np.einsum("in,ntm->tim", c, reg), markov)
    return _Fit(a, b, c, n_ref, err, basis, r, f, reg)


def _regressor(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``e^{A t_k} B`` for every sample time, shape (n, nt, m) (C times it is the kernel)."""
    lam, vec = np.linalg.eig(a)
    vb = np.linalg.solve(vec, b)  # (n, m)
    # (vec · diag e^{λ t_k}) @ vb per sample: one batched product (a 3-operand einsum loops)
    return np.real((vec[None] * np.exp(np.outer(t, lam))[:, None, :]) @ vb).transpose(1, 0, 2)


def _resolvent(a: np.ndarray, b: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """``(iωI − A)⁻¹ B`` at each ω [rad/s], shape (nω, n, m), by the eigen-decomposition of A."""
    lam, vec = np.linalg.eig(a)
    vb = np.linalg.solve(vec, b)
    return (vec[None] * (1.0 / (1j * omega[:, None] - lam[None]))[:, None, :]) @ vb


def _passivity_grid(a: np.ndarray) -> np.ndarray:
    """Frequencies [rad/s] of the passivity check: log-spaced from ``min|λ|/PASSIVITY_SPAN``
    to ``max|λ| · PASSIVITY_SPAN`` (beyond them ``Re K̂`` follows its ω² and ω⁻² asymptotes,
    whose signs the end points show), plus every pole's ``|Im λ|`` (where dips are sharpest)."""
    lam = np.linalg.eigvals(a)
    mag = np.abs(lam)
    grid = np.geomspace(mag.min() / PASSIVITY_SPAN, mag.max() * PASSIVITY_SPAN, PASSIVITY_POINTS)
    return np.unique(np.concatenate([grid, np.abs(lam.imag[lam.imag > 0])]))


def _hermitian_eig(c: np.ndarray, res: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenpairs of the Hermitian part of ``K̂(iω) = C (iωI − A)⁻¹ B`` at each ω."""
    h = c @ res  # (w, i, m): a batched product (BLAS), not einsum's loop
    return np.linalg.eigh(0.5 * (h + np.conj(h.transpose(0, 2, 1))))


def _enforce_passivity(fit: _Fit, markov: np.ndarray) -> _Fit:
    """The least change of ``C`` (in the fit's least-squares sense) that makes the Hermitian
    part of ``K̂(iω)`` positive semi-definite on the passivity grid.

    Residue perturbation (Gustavsen & Semlyen 2001, IEEE Trans. Power Syst. 16(1) 97–104):
    the poles (A, B) stay; each round linearises every negative eigenvalue at its eigenvector,
    ``vᴴ Re K̂(iω; C) v ≥ 0`` (linear in C), adds it to the constraints of the earlier rounds
    and solves the constrained least squares (:func:`_lsi`). ``passivity`` is the smallest
    eigenvalue on the grid relative to the largest."""
    # ω = 0 itself only when K̂(0) is free (imposed K̂(0) = 0 has nothing to constrain there)
    zero = [0.0] if fit.basis.shape[1] == fit.a.shape[0] else []
    omega = np.concatenate([zero, _passivity_grid(fit.a)])
    res = np.concatenate([_resolvent(fit.a, fit.b, omega), _asymptotes(fit)])
    n_grid = omega.size
    p, q = fit.f.shape[1], fit.basis.shape[1]
    e, f = np.kron(np.eye(p), fit.r), fit.f.T.ravel()  # unknowns: Z row by row
    rows: list[np.ndarray] = []
    c = fit.c
    for it in range(PASSIVITY_ITER + 1):
        lam, vec = _hermitian_eig(c, res)
        worst = min(_relative_min(lam[:n_grid]), _relative_min(lam[n_grid:]))
        if worst >= -PASSIVITY_TOL or it == PASSIVITY_ITER:
            break
        for w, k in _local_minima(lam, n_grid):
            v = vec[w, :, k]
            # vᴴ Re K̂(iω; C) v is linear in C: the constraint is exact along this v
            g = (np.real(np.outer(np.conj(v), res[w] @ v)) @ fit.basis).ravel()
            rows.append(g / max(np.linalg.norm(g), 1e-300))
        x = _lsi(e, f, np.array(rows), np.zeros(len(rows)))
        if x is None:  # infeasible with these poles: keep the last C, report the violation
            break
        c = x.reshape(p, q) @ fit.basis.T
    if c is fit.c:
        return replace(fit, passivity=worst)
    err = _pair_error(np.einsum("in,ntm->tim", c, fit.reg), markov)
    return replace(fit, c=c, error=err, passivity=worst)


def _asymptotes(fit: _Fit) -> np.ndarray:
    """"Resolvents" whose ``Re K̂`` are the asymptotes' coefficients, shape (k, n, m):
    ``Re K̂(iω) → −C A B / ω²`` as ω → ∞ (D = 0) and, when ``K̂(0) = 0`` is imposed,
    ``Re K̂(iω) → ω² C A⁻³ B`` as ω → 0. Their symmetric parts ⪰ 0 make the model passive
    beyond the grid's ends too (both are linear in C, like the grid's constraints)."""
    out = [-fit.a @ fit.b]
    if fit.basis.shape[1] < fit.a.shape[0]:  # the K̂(0) = 0 constraint is on
        ainv_b = np.linalg.solve(fit.a, fit.b)
        out.append(np.linalg.solve(fit.a, np.linalg.solve(fit.a, ainv_b)))
    return np.asarray(out, dtype=complex)


def _local_minima(lam: np.ndarray, n_grid: int) -> list[tuple[int, int]]:
    """(frequency, eigen-index) of the negative eigenvalues that are local minima along the
    grid (one constraint per dip, not one per grid point), and every negative asymptote's."""
    neg = lam < 0
    dip = neg.copy()
    g = lam[:n_grid]
    dip[1:n_grid - 1] &= (g[1:-1] <= g[:-2]) & (g[1:-1] <= g[2:])
    return list(zip(*np.nonzero(dip)))


def _relative_min(lam: np.ndarray) -> float:
    """Smallest eigenvalue relative to the largest magnitude (0 when all vanish)."""
    top = float(np.abs(lam).max()) if lam.size else 0.0
    return float(lam[:, 0].min()) / top if top > 0 else 0.0


def _lsi(e: np.ndarray, f: np.ndarray, g: np.ndarray, h: np.ndarray) -> np.ndarray | None:
    """``min ‖e x − f‖`` subject to ``g x ≥ h``; None when infeasible.

    Lawson & Hanson (1974), *Solving Least Squares Problems*, Ch. 23: with ``e = U S Vᵀ`` and
    ``y = S Vᵀ x − Uᵀ f`` the problem is the least-distance programme ``min ‖y‖, G̃ y ≥ h̃``,
    whose solution is the residual of a non-negative least squares (:func:`scipy.optimize.nnls`).
    """
    u, s, vt = np.linalg.svd(e, full_matrices=False)
    keep = s > s[0] * 1e-13
    w = vt[keep].T / s[keep]  # x = w (y + Uᵀ f)
    f1 = u[:, keep].T @ f
    gt = g @ w
    ht = h - gt @ f1
    mat = np.vstack([gt.T, ht[None]])
    rhs = np.zeros(mat.shape[0])
    rhs[-1] = 1.0
    sol, _ = scipy.optimize.nnls(mat, rhs, maxiter=50 * mat.shape[1])
    r = mat @ sol - rhs
    if abs(r[-1]) < 1e-12:
        return None
    return w @ (-r[:-1] / r[-1] + f1)


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
