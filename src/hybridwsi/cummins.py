"""Time-domain Cummins solver (paper Eq. 9), 1 DOF now, matrices ready for 6.

    (M + A∞) z̈ + ∫_0^t K(t − τ) ż(τ) dτ + C z = F_exc(t) + F_ext(t)

All matrices are taken from a coefficient Dataset (schema in ``docs/DATA_MODEL.md``) and
oriented "force on influenced DOF i from motion of radiating DOF j" (the Dataset stores them as
``[radiating_dof, influenced_dof]``, so they are transposed here).

Radiation (``radiation=``):

- ``"statespace"`` (default, fast): K(t) (from :func:`hybridwsi.hydro.irf.radiation_irf`) is
  realised by :func:`hybridwsi.hydro.statespace.fit_radiation_ss`; the augmented linear system
  ``y = [z, ż, x]`` is discretised exactly for piecewise-linear forcing (first-order hold,
  ``scipy.linalg.expm``) and the recursion ``y_{k+1} = Φ y_k + Γ0 u_k + Γ1 u_{k+1}`` is solved
  in modal coordinates with ``scipy.signal.lfilter`` (one first-order filter per eigenvalue of
  Φ; plain stepping when Φ is defective). The only approximations are the state-space fit of K
  and the linear interpolation of the forcing between samples.
- ``"convolution"`` (reference): Newmark average-acceleration (trapezoidal rule, β = 1/4,
  γ = 1/2, unconditionally stable, 2nd order) with the memory integral by the trapezoidal rule
  on the sampled K (2nd order), the term K(0) ż_{n+1} treated implicitly. Cost O(N · N_K).
- ``"none"``: no memory term (K ≡ 0).

``nonlinear_hydrostatics=True`` replaces ``−C z`` by the exact net hydrostatic force of ``body``
(``body.buoyancy_force(z) = ρ g V_sub(z) − m_body g``, zero at the floating equilibrium z = 0;
e.g. the spherical cap of :class:`hybridwsi.bodies.FloatingSphere`) and integrates with fixed-step RK4 (forcing evaluated at half steps); state-space radiation only.

A state-dependent external force ``external_force(t, z, zdot)`` (e.g. quadratic drag) takes the
same RK4 path.

The result is a TimeHistory (:func:`hybridwsi.history.make_history`) with the forces
``F_hs = −C z``, ``F_rad_inf = −A∞ z̈``, ``F_rad_mem = −∫K ż``, ``F_exc``, ``F_ext`` and
``F_tot`` = their sum, so that ``m z̈ = F_tot`` to round-off.
"""

from __future__ import annotations

import hashlib
import inspect
import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg
import scipy.signal
import xarray as xr
from tqdm.auto import tqdm

from hybridwsi.errors import InputError, SolverError
from hybridwsi.history import make_history
from hybridwsi.hydro.statespace import RadiationSS, fit_radiation_ss, foh_matrices
from hybridwsi.waves import Wave, excitation_force, wave_from_dict

RADIATION = ("statespace", "convolution", "none")
FORCES = ("F_tot", "F_hs", "F_rad_inf", "F_rad_mem", "F_exc", "F_ext")
#: eigenvector condition number above which the modal solver falls back to plain stepping
_MODAL_COND = 1e6


# --------------------------------------------------------------------------- system matrices
@dataclass
class CumminsSystem:
    """Matrices of the Cummins equation for the chosen DOFs (rows = influenced DOF)."""

    dofs: list[str]
    mass: np.ndarray  # rigid-body mass M [kg]
    added_mass_inf: np.ndarray  # A∞ [kg]
    stiffness: np.ndarray  # C [N/m]
    ss: RadiationSS | None = None
    kernel: np.ndarray | None = None  # K sampled at the simulation dt, (nk, n_inf, n_rad)

    @property
    def n(self) -> int:
        return len(self.dofs)

    @property
    def n_states(self) -> int:
        return 0 if self.ss is None else self.ss.order

    def augmented(self) -> tuple[np.ndarray, np.ndarray]:
        """``ẏ = A y + B u`` for ``y = [z, ż, x]`` and input force ``u`` [N]."""
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


def _dof_values(coeffs: xr.Dataset, name: str, dofs: list[str]) -> np.ndarray | None:
    """``coeffs[name]`` at ``dofs`` on both DOF axes, axes in stored order, by positional
    indexing (xarray's label ``sel`` costs more than a whole short state-space run); None when
    the fast path does not apply (unusual layout: the caller falls back to ``sel``)."""
    var = coeffs.variables[name]
    vals = var.values
    for dim in ("radiating_dof", "influenced_dof"):
        index = coeffs.indexes.get(dim)
        if dim not in var.dims or index is None or not index.is_unique:
            return None
        labels = [str(v) for v in index]  # a handful of DOFs: a list beats pandas' indexer
        if any(d not in labels for d in dofs):
            raise InputError(f"'{name}' has no entries for DOFs {dofs}")
        pos = [labels.index(d) for d in dofs]
        vals = vals.take(pos, axis=var.dims.index(dim))
    return vals


def _matrix(coeffs: xr.Dataset, name: str, dofs: list[str]) -> np.ndarray:
    if name not in coeffs:
        raise InputError(f"coefficients have no '{name}'")
    dims = coeffs.variables[name].dims
    vals = _dof_values(coeffs, name, dofs) if set(dims) == {"radiating_dof", "influenced_dof"} \
        else None
    if vals is not None:
        arr = np.asarray(vals, dtype=float)
        if dims[0] == "radiating_dof":
            arr = arr.T  # stored [radiating, influenced] -> [influenced i, radiating j]
        if not np.all(np.isfinite(arr)):
            raise InputError(f"coefficient '{name}' contains NaN/inf")
        return arr
    da = coeffs[name]
    try:
        da = da.sel(radiating_dof=dofs, influenced_dof=dofs)
    except KeyError:
        raise InputError(f"'{name}' has no entries for DOFs {dofs}") from None
    arr = np.asarray(da.transpose("radiating_dof", "influenced_dof").values, dtype=float).T
    if not np.all(np.isfinite(arr)):
        raise InputError(f"coefficient '{name}' contains NaN/inf")
    return arr


def _check_coeffs(coeffs: xr.Dataset, dofs: list[str], radiation: str) -> None:
    if not isinstance(coeffs, xr.Dataset):
        raise InputError(f"coeffs must be an xarray.Dataset, got {type(coeffs).__name__}")
    have = [str(v) for v in coeffs["radiating_dof"].values] if "radiating_dof" in coeffs else []
    missing = [d for d in dofs if d not in have]
    if missing:
        raise InputError(f"coefficients have no DOF {missing} (have {have})")
    if radiation != "none":
        b = _matrix_omega(coeffs, "radiation_damping", dofs)
        if not np.all(np.isfinite(b)):
            raise InputError("coefficient 'radiation_damping' contains NaN/inf")


def _matrix_omega(coeffs: xr.Dataset, name: str, dofs: list[str]) -> np.ndarray:
    if name not in coeffs:
        raise InputError(f"coefficients have no '{name}'")
    vals = _dof_values(coeffs, name, dofs)
    if vals is not None:
        return vals
    return np.asarray(coeffs[name].sel(radiating_dof=dofs, influenced_dof=dofs).values)


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
    """Cummins matrices, and the radiation kernel or its state-space model, for ``dofs``."""
    from hybridwsi.forces import as_matrix

    dofs = list(dofs)
    if radiation not in RADIATION:
        raise InputError(f"radiation must be one of {', '.join(RADIATION)}, got '{radiation}'")
    _check_coeffs(coeffs, dofs, radiation)
    if mass is None:
        if "mass" not in coeffs:
            raise InputError("no rigid-body mass: pass mass= or use coefficients with 'mass'")
        m = _matrix(coeffs, "mass", dofs)
    else:
        m = as_matrix(mass, len(dofs), "mass")
        if not np.all(np.isfinite(m)):
            raise InputError("mass must be finite")
    sys = CumminsSystem(dofs, m, _matrix(coeffs, "added_mass_inf", dofs),
                        _matrix(coeffs, "hydrostatic_stiffness", dofs))
    if np.any(np.linalg.eigvalsh(0.5 * (sys.mass + sys.mass.T) + sys.added_mass_inf) <= 0):
        raise InputError("m + A∞ must be positive definite (check mass and added_mass_inf)")
    if radiation == "statespace":
        if radiation_ss is None:
            k = _kernel(coeffs, dofs, irf, irf_t_max, dt=None)
            radiation_ss = fit_radiation_ss(k, order=ss_order, tol=ss_tol, coeffs=coeffs)
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
        from hybridwsi.hydro.irf import radiation_irf

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


# --------------------------------------------------------------------------- forcing
def _external(external_force: Any, t: np.ndarray, n: int) -> np.ndarray:
    """External force [N] on the time grid, shape (nt, n)."""
    if external_force is None:
        return np.zeros((t.size, n))
    if _is_feedback(external_force):
        raise InputError("a state-dependent external_force(t, z, zdot) is only supported by "
                         "simulate()")
    if callable(external_force):
        vals = np.asarray([external_force(ti) for ti in t], dtype=float)
    elif isinstance(external_force, xr.DataArray) and "time" in external_force.dims:
        vals = _interp_series(np.asarray(external_force["time"].values, float),
                              np.asarray(external_force.values, float), t)
    elif hasattr(external_force, "index") and hasattr(external_force, "to_numpy"):  # pandas
        vals = _interp_series(np.asarray(external_force.index, float),
                              np.asarray(external_force.to_numpy(), float), t)
    elif isinstance(external_force, tuple) and len(external_force) == 2:
        vals = _interp_series(np.asarray(external_force[0], float),
                              np.asarray(external_force[1], float), t)
    else:
        try:
            vals = np.asarray(external_force, dtype=float)
        except (TypeError, ValueError):
            raise InputError("external_force must be a number, an array on the time grid, "
                             "a callable f(t), or a (time, values) pair") from None
        if vals.ndim == 0 or (vals.ndim == 1 and vals.size == n and vals.size != t.size):
            vals = np.broadcast_to(vals, (t.size, n)).copy()
        elif vals.shape[0] != t.size:
            raise InputError(f"external_force has {vals.shape[0]} samples; the time grid has "
                             f"{t.size} (pass a (time, values) pair to interpolate)")
    vals = vals.reshape(t.size, -1)
    if vals.shape[1] != n:
        raise InputError(f"external_force has {vals.shape[1]} columns; expected {n} DOF")
    if not np.all(np.isfinite(vals)):
        raise InputError("external_force contains NaN/inf")
    return vals


def _interp_series(ts: np.ndarray, vs: np.ndarray, t: np.ndarray) -> np.ndarray:
    if ts.ndim != 1 or ts.size < 2 or np.any(np.diff(ts) <= 0):
        raise InputError("external force time must be strictly increasing with >= 2 samples")
    if ts[0] > t[0] + 1e-9 or ts[-1] < t[-1] - 1e-9:
        raise InputError(f"external force covers {ts[0]:g}–{ts[-1]:g} s but the simulation "
                         f"needs {t[0]:g}–{t[-1]:g} s")
    vs = vs.reshape(ts.size, -1)
    return np.stack([np.interp(t, ts, vs[:, i]) for i in range(vs.shape[1])], axis=1)


def _as_wave(wave: Wave | Mapping | None) -> Wave | None:
    if wave is None or isinstance(wave, Wave):
        return wave
    if isinstance(wave, Mapping):
        return wave_from_dict(dict(wave))
    raise InputError(f"wave must be a hybridwsi.waves wave or a dict, got {type(wave).__name__}")


def _excitation(wave: Wave | None, coeffs: xr.Dataset, t: np.ndarray, dofs: list[str],
                ramp: float) -> tuple[np.ndarray, np.ndarray | None]:
    """F_exc (nt, n) [N] and the incident elevation η (nt,) [m] (None without waves)."""
    if wave is None:
        return np.zeros((t.size, len(dofs))), None
    return excitation_force(wave, coeffs, t, list(dofs), ramp=ramp, with_elevation=True)


# --------------------------------------------------------------------------- solvers
def _foh_weights(x: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """FOH input weights ``(γ0, γ1)`` of a mode ``q̇ = s q + u`` over one step, ``x = s dt``.

    ``q_{k+1} = e^x q_k + γ0 u_k + γ1 u_{k+1}`` with ``γ1 = dt (e^x − 1 − x)/x²`` and
    ``γ0 = dt (1 + (x − 1) e^x)/x²``; a Taylor series below |x| = 0.1 avoids the cancellation
    (its truncation error is < 1e-16 there, the closed form's rounding < 2e-15 above).
    """
    x = np.asarray(x, dtype=complex)
    small = np.abs(x) < 0.1
    g0, g1 = np.empty_like(x), np.empty_like(x)
    xs = x[small]
    s0, s1, term, fact = np.zeros_like(xs), np.zeros_like(xs), np.ones_like(xs), 2.0
    for n in range(12):  # γ1/dt = Σ xⁿ/(n+2)!, γ0/dt = Σ (n+1) xⁿ/(n+2)!
        s1 += term / fact
        s0 += (n + 1) * term / fact
        term = term * xs
        fact *= n + 3
    g0[small], g1[small] = s0, s1
    xl = x[~small]
    em1 = np.expm1(xl)
    g1[~small] = (em1 - xl) / xl**2
    g0[~small] = (1.0 + (xl - 1.0) * (em1 + 1.0)) / xl**2
    return dt * g0, dt * g1


def _solve_linear(a: np.ndarray, b: np.ndarray, dt: float, u: np.ndarray, y0: np.ndarray,
                  out: np.ndarray) -> np.ndarray:
    """Outputs ``out @ y_k`` of ``ẏ = A y + B u`` (FOH-exact), batched over cases.

    ``u`` (nt, n_in, n_case), ``y0`` (n_state, n_case), ``out`` (n_out, n_state);
    returns (nt, n_out, n_case). The system is diagonalised in continuous time,
    ``A = V diag(s) V⁻¹``, and each mode is discretised exactly (``e^{s dt}`` and the FOH
    weights of :func:`_foh_weights`), which is cheaper than the matrix exponential of the
    augmented system; a defective or ill-conditioned ``A`` (e.g. a free body with C = 0, K = 0)
    falls back to stepping with :func:`~hybridwsi.hydro.statespace.foh_matrices`.
    """
    nt, n_case = u.shape[0], u.shape[2]
    s_cont, vec = np.linalg.eig(a)
    if np.linalg.cond(vec) > _MODAL_COND:
        return _solve_stepping(*foh_matrices(a, b, dt), u, y0, out)
    vinv = np.linalg.inv(vec)
    # A is real: a complex pair's modes are conjugate, so solve one and count it twice
    tol = 1e-12 * max(1.0, float(np.max(np.abs(s_cont))))
    keep = s_cont.imag >= -tol
    s_cont = s_cont[keep]
    lam = np.exp(s_cont * dt)
    weight = np.where(s_cont.imag > tol, 2.0, 1.0)
    g0, g1 = _foh_weights(s_cont * dt, dt)
    vb = vinv[keep] @ b
    w0, w1, q0 = g0[:, None] * vb, g1[:, None] * vb, vinv[keep] @ y0
    cw = (out @ vec)[:, keep] * weight  # (n_out, n_mode): output weights of the kept modes
    # modal recursions q_m[k] = λ_m q_m[k-1] + (W0 u_{k-1} + W1 u_k)_m with q_m[0] = q0_m: one
    # first-order filter per mode and input, numerator [W1, W0] (the FOH drive), time last
    # (contiguous for lfilter); the initial state zi makes the output start exactly at q0
    ut = np.ascontiguousarray(u.transpose(2, 1, 0))  # (n_case, n_in, nt)
    n_mode, n_in = lam.size, ut.shape[1]
    qs = np.empty((2 * n_mode, n_case, nt))  # Re q_m in rows m, Im q_m in rows n_mode + m
    for m, lm in enumerate(lam):
        # a real mode whose Im q is never used runs the real filter (half the cost)
        real = s_cont[m].imag == 0 and not np.any(cw[:, m].imag)
        cast = (lambda x: x.real) if real else (lambda x: x)
        for i in range(n_in):
            w1m, w0m = cast(w1[m, i]), cast(w0[m, i])
            zi = (-w1m * ut[:, i, :1]) + (cast(q0[m])[:, None] if i == 0 else 0.0)
            y = scipy.signal.lfilter([w1m, w0m], [1.0, -cast(lm)], ut[:, i], zi=zi)[0]
            q = y if i == 0 else q + y
        qs[m] = np.real(q)
        qs[n_mode + m] = np.imag(q) if not real else 0.0
    # real part of Σ_m cw[j, m] q_m = Σ_m (Re cw Re q_m − Im cw Im q_m): one real product
    coef = np.concatenate([cw.real, -cw.imag], axis=1)  # (n_out, 2 n_mode)
    res = (coef @ qs.reshape(2 * n_mode, -1)).reshape(-1, n_case, nt)  # one 2-D GEMM
    return res.transpose(2, 0, 1)  # (n_out, n_case, nt) -> (nt, n_out, n_case)


def _solve_stepping(phi, g0, g1, u, y0, out) -> np.ndarray:
    """Plain recursion (used when Φ is defective, e.g. a free body with C = 0, K = 0)."""
    y = y0.copy()
    res = np.empty((u.shape[0], out.shape[0], u.shape[2]))
    res[0] = out @ y
    for k in range(u.shape[0] - 1):
        y = phi @ y + g0 @ u[k] + g1 @ u[k + 1]
        res[k + 1] = out @ y
    return res


def _solve_convolution(sys: CumminsSystem, u: np.ndarray, z0: np.ndarray, v0: np.ndarray,
                       dt: float, progress: bool) -> tuple[np.ndarray, ...]:
    """Newmark (β = 1/4, γ = 1/2) with trapezoidal memory integral; see module doc."""
    nt, n = u.shape
    kern = sys.kernel  # (L, n, n), oriented [influenced, radiating]
    nl = kern.shape[0]
    meff, c = sys.mass + sys.added_mass_inf, sys.stiffness
    k0 = kern[0]
    lhs = np.linalg.inv(meff + dt**2 / 4 * (c + k0))
    z, v, acc, mem = (np.zeros((nt, n)) for _ in range(4))
    z[0], v[0] = z0, v0
    acc[0] = np.linalg.solve(meff, u[0] - c @ z0)  # memory integral is zero at t = 0
    for k in tqdm(range(nt - 1), disable=not progress, desc="convolution", unit="step",
                  mininterval=1.0):
        w = min(k + 1, nl - 1)  # lags 1..w fall inside the kernel
        hist = np.einsum("lij,lj->i", kern[1:w + 1], v[k::-1][:w])
        if k + 1 <= nl - 1:  # the window reaches τ = 0: trapezoid end weight ½
            hist -= 0.5 * kern[k + 1] @ v[0]
        hist *= dt
        z_pred = z[k] + dt * v[k] + dt**2 / 4 * acc[k]
        v_pred = v[k] + dt / 2 * acc[k]
        acc[k + 1] = lhs @ (u[k + 1] - c @ z_pred - hist - dt / 2 * k0 @ v_pred)
        z[k + 1] = z_pred + dt**2 / 4 * acc[k + 1]
        v[k + 1] = v_pred + dt / 2 * acc[k + 1]
        mem[k + 1] = -(hist + dt / 2 * k0 @ v[k + 1])
    return z, v, acc, mem


def _solve_rk4(sys: CumminsSystem, f_hs: Callable[[np.ndarray], np.ndarray],
               feedback: Callable | None, u_half: np.ndarray, y0: np.ndarray, dt: float,
               progress: bool) -> np.ndarray:
    """Fixed-step RK4 of the augmented system with a nonlinear restoring/feedback force.

    ``u_half`` is the time-only input force on the half-step grid (2 nt − 1, n);
    ``feedback(t, z, zdot)`` an optional state-dependent force. Returns y (nt, n_state).
    """
    n, r = sys.n, sys.n_states
    minv = np.linalg.inv(sys.mass + sys.added_mass_inf)
    ss = sys.ss

    def rhs(tk: float, y: np.ndarray, uk: np.ndarray) -> np.ndarray:
        z, v, x = y[:n], y[n:2 * n], y[2 * n:]
        f = f_hs(z) + uk
        if feedback is not None:
            f = f + _feedback_value(feedback, tk, z, v, n)
        dx = np.zeros(0)
        if r:
            f = f - ss.C @ x
            dx = ss.A @ x + ss.B @ v
        return np.concatenate([v, minv @ f, dx])

    nt = (u_half.shape[0] + 1) // 2
    y = np.empty((nt, 2 * n + r))
    y[0] = y0
    for k in tqdm(range(nt - 1), disable=not progress, desc="RK4", unit="step", mininterval=1.0):
        tk = k * dt
        ua, um, ub = u_half[2 * k], u_half[2 * k + 1], u_half[2 * k + 2]
        k1 = rhs(tk, y[k], ua)
        k2 = rhs(tk + dt / 2, y[k] + dt / 2 * k1, um)
        k3 = rhs(tk + dt / 2, y[k] + dt / 2 * k2, um)
        k4 = rhs(tk + dt, y[k] + dt * k3, ub)
        y[k + 1] = y[k] + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if not np.all(np.isfinite(y[k + 1])):
            raise SolverError(f"RK4 integration diverged at t = {tk + dt:.6g} s; reduce dt")
    return y


def _feedback_value(feedback: Callable, t: float, z: np.ndarray, v: np.ndarray,
                    n: int) -> np.ndarray:
    val = np.asarray(feedback(t, z, v), dtype=float).reshape(-1)
    if val.size == 1 and n > 1:
        val = np.full(n, val[0])
    if val.size != n or not np.all(np.isfinite(val)):
        raise InputError(f"external_force(t, z, zdot) must return {n} finite value(s)")
    return val


def _is_feedback(force: Any) -> bool:
    """A callable taking (t, z, zdot): a state-dependent external force."""
    if not callable(force) or isinstance(force, (xr.DataArray, np.ndarray)):
        return False
    try:
        params = inspect.signature(force).parameters.values()
    except (TypeError, ValueError):
        return False
    positional = [p for p in params if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    return len(positional) >= 3 or any(p.kind == p.VAR_POSITIONAL for p in params)


def _nonlinear_hs(body: Any, sys: CumminsSystem) -> Callable[[np.ndarray], np.ndarray]:
    """Exact net hydrostatic heave force ``body.buoyancy_force(z)`` = ρ g V_sub(z) − m_body g."""
    if body is None or not hasattr(body, "buoyancy_force"):
        raise InputError("nonlinear_hydrostatics needs body= with a buoyancy_force(z) method "
                         "(e.g. hybridwsi.bodies.FloatingSphere)")
    if sys.dofs != ["Heave"]:
        raise InputError("nonlinear_hydrostatics is implemented for the Heave DOF only")

    def f_hs(z: np.ndarray) -> np.ndarray:
        return np.array([float(body.buoyancy_force(float(z[0])))])

    return f_hs


# --------------------------------------------------------------------------- public API
def _time_grid(duration: float, dt: float) -> np.ndarray:
    for name, v in (("dt", dt), ("duration", duration)):
        if not isinstance(v, (int, float, np.floating, np.integer)) or not np.isfinite(v):
            raise InputError(f"{name} must be a finite number, got {v!r}")
    if dt <= 0:
        raise InputError(f"dt must be > 0, got {dt}")
    if duration < dt:
        raise InputError(f"duration ({duration} s) must be at least one time step dt ({dt} s)")
    n = int(round(duration / dt))
    return np.arange(n + 1) * dt


def _vector(value: Any, n: int, name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float).reshape(-1)
    if arr.size == 1:
        arr = np.full(n, arr[0])
    if arr.size != n or not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be a finite scalar or a length-{n} vector")
    return arr


def coeffs_hash(coeffs: xr.Dataset) -> str:
    """The coefficients' ``input_hash`` attribute, or a SHA-1 of their numerical content."""
    if coeffs.attrs.get("input_hash"):
        return str(coeffs.attrs["input_hash"])
    h = hashlib.sha1()
    for name in sorted(map(str, coeffs.data_vars)):
        h.update(name.encode())
        h.update(np.ascontiguousarray(coeffs[name].values).tobytes())
    return h.hexdigest()


def _describe_force(external_force: Any) -> Any:
    if external_force is None:
        return None
    if np.isscalar(external_force):
        return float(external_force)
    if callable(external_force):
        return f"callable {getattr(external_force, '__name__', 'f')}"
    try:
        arr = np.ascontiguousarray(np.asarray(external_force, dtype=float))
        return {"samples": int(arr.size), "sha1": hashlib.sha1(arr.tobytes()).hexdigest()}
    except (TypeError, ValueError):
        return type(external_force).__name__


def simulate(
    coeffs: xr.Dataset,
    *,
    mass: float | np.ndarray | None = None,
    duration: float,
    dt: float,
    wave: Wave | Mapping | None = None,
    z0: float | Sequence[float] = 0.0,
    zdot0: float | Sequence[float] = 0.0,
    external_force: Any = None,
    radiation: str = "statespace",
    nonlinear_hydrostatics: bool = False,
    body: Any = None,
    ramp: float = 0.0,
    dofs: Sequence[str] = ("Heave",),
    irf: xr.DataArray | None = None,
    radiation_ss: RadiationSS | None = None,
    ss_order: int | None = None,
    ss_tol: float = 0.005,
    irf_t_max: float | None = None,
    progress: bool = False,
) -> xr.Dataset:
    """Integrate the Cummins equation and return a TimeHistory.

    Parameters
    ----------
    coeffs : xarray.Dataset
        BEM coefficients (``hydro.bem.compute``): ``added_mass_inf``, ``hydrostatic_stiffness``,
        ``radiation_damping`` (unless ``radiation="none"``), ``excitation_force`` (with waves),
        ``mass`` (unless ``mass`` is given).
    mass : float or ndarray, optional
        Rigid-body mass [kg] (scalar or (n, n) matrix); default ``coeffs["mass"]``.
    duration, dt : float
        Simulated time and output/integration step [s].
    wave : Wave or dict, optional
        Incident wave (:mod:`hybridwsi.waves`); its excitation force is ``F_exc``.
    z0, zdot0 : float or sequence
        Initial displacement [m] and velocity [m/s] (free decay: ``z0 ≠ 0``).
    external_force : number, array (nt[, n]), callable, (time, values) pair or DataArray
        External force ``F_ext`` [N]: constant, time series, function ``f(t)``, or a
        state-dependent force ``f(t, z, zdot)`` (e.g. quadratic drag; integrated with RK4).
    radiation : {"statespace", "convolution", "none"}
        Memory-term evaluation (see module doc).
    nonlinear_hydrostatics : bool
        Exact hydrostatic force of ``body`` instead of ``−C z`` (state-space radiation, RK4).
    body : object, optional
        Body with ``buoyancy_force(z)`` [N], e.g. :class:`hybridwsi.bodies.FloatingSphere`.
    ramp : float
        Duration [s] of the half-cosine ramp on the wave excitation.
    dofs : sequence of str
        Degrees of freedom (Capytaine names).
    irf : xarray.DataArray, optional
        Precomputed kernel K(time, radiating_dof, influenced_dof); default from ``coeffs``.
    radiation_ss : RadiationSS, optional
        Precomputed state-space model (skips the fit).
    ss_order, ss_tol : int, float
        Passed to :func:`~hybridwsi.hydro.statespace.fit_radiation_ss` (default tolerance
        0.5 %: a higher order costs almost nothing here and keeps the RAO error < 0.5 %).
    irf_t_max : float, optional
        Kernel length [s] passed to ``radiation_irf``.
    progress : bool
        Show a tqdm progress bar for the stepping solvers.

    Returns
    -------
    xarray.Dataset
        TimeHistory with ``z, zdot, zddot, mass``, forces ``F_tot, F_hs, F_rad_inf,
        F_rad_mem, F_exc, F_ext`` [N] and ``eta(time, probe)`` [m] when ``wave`` is given.
    """
    t = _time_grid(duration, dt)
    wave = _as_wave(wave)
    if (nonlinear_hydrostatics or _is_feedback(external_force)) and radiation == "convolution":
        raise InputError("nonlinear_hydrostatics and state-dependent external forces are "
                         "implemented with radiation='statespace' or 'none' only")
    sys = build_system(coeffs, dofs=dofs, mass=mass, radiation=radiation, dt=dt, irf=irf,
                       radiation_ss=radiation_ss, ss_order=ss_order, ss_tol=ss_tol,
                       irf_t_max=irf_t_max)
    n = sys.n
    z0v, v0v = _vector(z0, n, "z0"), _vector(zdot0, n, "zdot0")
    f_exc, eta = _excitation(wave, coeffs, t, sys.dofs, ramp)
    feedback = external_force if _is_feedback(external_force) else None
    f_ext = _external(None if feedback else external_force, t, n)
    u = f_exc + f_ext
    if nonlinear_hydrostatics or feedback is not None:
        hs = _nonlinear_hs(body, sys) if nonlinear_hydrostatics else None
        z, v, mem, f_hs, f_fb = _run_rk4(sys, coeffs, hs, wave, f_ext, feedback, t, dt, ramp,
                                         z0v, v0v, progress)
        f_ext = f_ext + f_fb
    elif radiation == "convolution":
        z, v, _, mem = _solve_convolution(sys, u, z0v, v0v, dt, progress)
        f_hs = -z @ sys.stiffness.T
    else:
        z, v, mem = _run_linear(sys, u[:, :, None], z0v[:, None], v0v[:, None], dt)
        z, v, mem = z[..., 0], v[..., 0], mem[..., 0]
        f_hs = -z @ sys.stiffness.T
    inputs = _inputs(coeffs, sys, duration=duration, dt=dt, wave=wave, z0=z0v, zdot0=v0v,
                     external_force=external_force, radiation=radiation, ramp=ramp,
                     nonlinear_hydrostatics=nonlinear_hydrostatics, body=body)
    return _history(sys, t, z, v, f_hs, mem, f_exc, f_ext, eta, inputs)


def _run_linear(sys: CumminsSystem, u: np.ndarray, z0: np.ndarray, v0: np.ndarray, dt: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """z, ż, F_rad_mem, each (nt, n, n_case), of the linear system."""
    n, r = sys.n, sys.n_states
    a, b = sys.augmented()
    y0 = np.concatenate([z0, v0, np.zeros((r, z0.shape[1]))])
    out = np.zeros((3 * n, 2 * n + r))
    out[:2 * n, :2 * n] = np.eye(2 * n)
    if r:
        out[2 * n:, 2 * n:] = -sys.ss.C  # F_rad_mem = −C_r x
    res = _solve_linear(a, b, dt, u, y0, out)
    return res[:, :n], res[:, n:2 * n], res[:, 2 * n:]


def _run_rk4(sys, coeffs, f_hs, wave, f_ext, feedback, t, dt, ramp, z0, v0, progress):
    """RK4 path: nonlinear hydrostatics ``f_hs(z)`` (None: linear) and/or a feedback force."""
    n = sys.n
    if f_hs is None:
        f_hs = lambda z: -sys.stiffness @ z  # noqa: E731
    t_half = np.arange(2 * t.size - 1) * (dt / 2)
    u_half = _excitation(wave, coeffs, t_half, sys.dofs, ramp)[0]
    # time series are only known on the output grid: linear interpolation at half steps
    u_half += np.stack([np.interp(t_half, t, f_ext[:, i]) for i in range(n)], axis=1)
    y0 = np.concatenate([z0, v0, np.zeros(sys.n_states)])
    y = _solve_rk4(sys, f_hs, feedback, u_half, y0, dt, progress)
    z, v = y[:, :n], y[:, n:2 * n]
    mem = -y[:, 2 * n:] @ sys.ss.C.T if sys.n_states else np.zeros_like(z)
    fb = np.zeros_like(z)
    if feedback is not None:
        fb = np.stack([_feedback_value(feedback, tk, zk, vk, n) for tk, zk, vk in zip(t, z, v)])
    return z, v, mem, np.stack([f_hs(zk) for zk in z]), fb


def _inputs(coeffs: xr.Dataset, sys: CumminsSystem, **kw: Any) -> dict[str, Any]:
    wave = kw.pop("wave")
    body = kw.pop("body")
    kw["external_force"] = _describe_force(kw["external_force"])
    return {
        **{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in kw.items()},
        "coeffs_hash": coeffs_hash(coeffs),
        "dofs": sys.dofs,
        "mass": sys.mass.tolist(),
        "added_mass_inf": sys.added_mass_inf.tolist(),
        "hydrostatic_stiffness": sys.stiffness.tolist(),
        "wave": None if wave is None else wave.to_dict(),
        "body": None if body is None else repr(body),
        "radiation_ss": None if sys.ss is None else {
            "order": sys.ss.order, "fit_error": sys.ss.fit_error,
            "n_reflected": sys.ss.n_reflected},
        "kernel_length_s": None if sys.kernel is None else (sys.kernel.shape[0] - 1) * kw["dt"],
    }


def _forces(sys: CumminsSystem, z, v, f_hs, mem, f_exc, f_ext) -> dict[str, np.ndarray]:
    """Force components and the acceleration from the equation of motion (last axis = DOF)."""
    meff = sys.mass + sys.added_mass_inf
    rhs = f_hs + mem  # in-place sums below: same order (same rounding), fewer temporaries
    rhs += f_exc
    rhs += f_ext
    rhs = np.moveaxis(rhs, -1, 0).reshape(sys.n, -1)
    if sys.n == 1:  # a scalar mass: the solve is a division (LAPACK's getrs is slow here)
        acc = rhs / meff[0, 0]
    else:  # LAPACK getrf/getrs as np.linalg.solve, without its copies of the right-hand side
        acc = scipy.linalg.lu_solve(scipy.linalg.lu_factor(meff), rhs, check_finite=False,
                                    overwrite_b=True)
    acc = np.moveaxis(acc.reshape(sys.n, *z.shape[:-1]), 0, -1)
    f_inf = acc @ sys.added_mass_inf.T
    np.negative(f_inf, out=f_inf)
    tot = f_hs + f_inf
    tot += mem
    tot += f_exc
    tot += f_ext
    return {"zddot": acc, "F_hs": f_hs, "F_rad_inf": f_inf, "F_rad_mem": mem, "F_exc": f_exc,
            "F_ext": f_ext, "F_tot": tot}


def _history(sys, t, z, v, f_hs, mem, f_exc, f_ext, eta, inputs) -> xr.Dataset:
    # validated here rather than by make_history: the time grid is ours (uniform) and the
    # forcing was checked on input, so only the solution itself can be non-finite
    if not all(np.all(np.isfinite(a)) for a in (z, v, mem)):
        raise SolverError("the Cummins solution is not finite (unstable system); check the "
                          "coefficients and the state-space fit")
    f = _forces(sys, z, v, f_hs, mem, f_exc, f_ext)
    acc = f.pop("zddot")
    extra = None
    if eta is not None:  # built with the Dataset: a later assignment costs an xarray merge
        extra = {"eta": (("time", "probe"), eta[:, None],
                         {"units": "m", "long_name": "incident wave elevation"})}
    hist = make_history(t, z, v, acc, forces={k: f[k] for k in FORCES}, dof=sys.dofs,
                        mass=sys.mass, source="cummins", inputs=inputs, check=False,
                        extra_vars=extra, extra_coords={"probe": ["origin"]} if extra else None)
    if sys.ss is not None:
        hist.attrs["radiation_ss"] = json.dumps(sys.ss.to_dict())
    return hist


# --------------------------------------------------------------------------- batches
_CASE_KEYS = {"z0", "zdot0", "wave", "external_force"}
_REGULAR_KEYS = {"period", "height", "phase"}
_JONSWAP_KEYS = {"hs", "tp", "gamma", "seed"}


def _cases_from_dataset(ds: xr.Dataset) -> list[dict[str, Any]]:
    """Rows of a parameter Dataset (dim ``case``) → case dicts."""
    if "case" not in ds.dims:
        raise InputError("a cases Dataset needs a 'case' dimension")
    names = set(map(str, ds.data_vars))
    unknown = names - _CASE_KEYS - _REGULAR_KEYS - _JONSWAP_KEYS
    if unknown:
        raise InputError(f"unknown case parameters {sorted(unknown)}")
    cases = []
    for i in range(ds.sizes["case"]):
        row = {k: ds[k].values[i].item() for k in names}
        case = {k: row[k] for k in ("z0", "zdot0") if k in row}
        if {"period", "height"} <= names:
            case["wave"] = {"type": "regular", **{k: row[k] for k in _REGULAR_KEYS if k in row}}
        elif {"hs", "tp"} <= names:
            case["wave"] = {"type": "jonswap",
                            **{k: row[k] for k in _JONSWAP_KEYS if k in row}}
            if "seed" in case["wave"]:
                case["wave"]["seed"] = int(case["wave"]["seed"])
        cases.append(case)
    return cases


def simulate_batch(
    coeffs: xr.Dataset,
    cases: Sequence[Mapping[str, Any]] | xr.Dataset,
    *,
    mass: float | np.ndarray | None = None,
    duration: float,
    dt: float,
    ramp: float = 0.0,
    dofs: Sequence[str] = ("Heave",),
    radiation: str = "statespace",
    irf: xr.DataArray | None = None,
    radiation_ss: RadiationSS | None = None,
    ss_order: int | None = None,
    ss_tol: float = 0.005,
    irf_t_max: float | None = None,
) -> xr.Dataset:
    """Many linear Cummins runs at once (one system, cases stacked as columns).

    Parameters
    ----------
    cases : list of dict or xarray.Dataset
        Each case may set ``z0``, ``zdot0``, ``wave`` (Wave or dict) and ``external_force``
        (number or array on the time grid). A Dataset with dimension ``case`` may hold
        ``z0, zdot0`` and either ``period, height[, phase]`` (regular) or
        ``hs, tp[, gamma, seed]`` (JONSWAP).
    other parameters
        As :func:`simulate` (linear only: ``radiation`` "statespace" or "none").

    Returns
    -------
    xarray.Dataset
        Variables ``z, zdot, zddot`` and the forces with dims ``(case, time, dof)``, ``eta``
        ``(case, time)`` when any case has waves; ``mass``; attrs as a TimeHistory.
    """
    if radiation not in ("statespace", "none"):
        raise InputError("simulate_batch supports radiation='statespace' or 'none'")
    if isinstance(cases, xr.Dataset):
        cases = _cases_from_dataset(cases)
    cases = list(cases)
    if not cases:
        raise InputError("simulate_batch needs at least one case")
    t = _time_grid(duration, dt)
    sys = build_system(coeffs, dofs=dofs, mass=mass, radiation=radiation, dt=dt, irf=irf,
                       radiation_ss=radiation_ss, ss_order=ss_order, ss_tol=ss_tol,
                       irf_t_max=irf_t_max)
    n, nc = sys.n, len(cases)
    z0, v0 = np.zeros((n, nc)), np.zeros((n, nc))
    f_exc, f_ext = np.zeros((t.size, n, nc)), np.zeros((t.size, n, nc))
    eta = np.zeros((t.size, nc))
    waves: list[Any] = []
    for c, case in enumerate(cases):
        unknown = set(case) - _CASE_KEYS
        if unknown:
            raise InputError(f"case {c}: unknown keys {sorted(unknown)} (use {sorted(_CASE_KEYS)})")
        z0[:, c] = _vector(case.get("z0", 0.0), n, f"case {c} z0")
        v0[:, c] = _vector(case.get("zdot0", 0.0), n, f"case {c} zdot0")
        wave = _as_wave(case.get("wave"))
        waves.append(None if wave is None else wave.to_dict())
        if wave is not None:
            f_exc[:, :, c], eta[:, c] = _excitation(wave, coeffs, t, sys.dofs, ramp)
        f_ext[:, :, c] = _external(case.get("external_force"), t, n)
    z, v, mem = _run_linear(sys, f_exc + f_ext, z0, v0, dt)
    move = (lambda a: np.moveaxis(a, 2, 0))  # (time, dof, case) -> (case, time, dof)
    z, v, mem, f_exc, f_ext = map(move, (z, v, mem, f_exc, f_ext))
    forces = _forces(sys, z, v, -z @ sys.stiffness.T, mem, f_exc, f_ext)
    acc = forces.pop("zddot")
    inputs = _inputs(coeffs, sys, duration=duration, dt=dt, wave=None, z0=z0, zdot0=v0,
                     external_force=None, radiation=radiation, ramp=ramp,
                     nonlinear_hydrostatics=False, body=None)
    inputs["cases"] = [{"z0": z0[:, c].tolist(), "zdot0": v0[:, c].tolist(), "wave": waves[c],
                        "external_force": _describe_force(cases[c].get("external_force"))}
                       for c in range(nc)]
    dims = ("case", "time", "dof")
    data = {"z": (dims, z, {"units": "m"}), "zdot": (dims, v, {"units": "m/s"}),
            "zddot": (dims, acc, {"units": "m/s^2"})}
    data.update({k: (dims, forces[k], {"units": "N", "role": "force"}) for k in FORCES})
    data["mass"] = (("dof", "dof_j"), sys.mass, {"units": "kg"})
    if any(w is not None for w in waves):
        data["eta"] = (("case", "time"), eta.T, {"units": "m"})
    from hybridwsi.history import _version

    return xr.Dataset(
        data,
        coords={"case": np.arange(nc), "time": ("time", t, {"units": "s"}), "dof": sys.dofs,
                "dof_j": sys.dofs},
        attrs={"hybridwsi_version": _version(), "source": "cummins.simulate_batch",
               "inputs": json.dumps(inputs, default=str, sort_keys=True)},
    )
