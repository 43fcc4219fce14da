"""The RK4 loop of :func:`hybridwsi.cummins.solvers.solve_rk4` compiled with Numba.

Used when every state-dependent force component has a kernel
(:meth:`hybridwsi.forces.KnownComponent.compiled_force`, :mod:`hybridwsi.forces._compiled`),
none has internal states and the restoring force is the linear ``−C z``. It runs the
arithmetic of the NumPy loop (same stage order, same step formula; matrix-vector products
summed in index order, so results agree to rounding, ~1e-15 relative) with preallocated
scratch vectors and no Python per step. The components' force at each output time is the one
the first RK4 stage evaluates there, recorded instead of evaluated again.
The kernels are called through Numba's first-class function type: the loop is compiled once
per number of components and cached on disk, whatever the components are.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from hybridwsi.forces._compiled import (
    HAVE_NUMBA,
    MAX_KERNELS,
    CompiledForce,
    available,
    numba,
    packed,
    quiet,
    sum_forces,
)

__all__ = ["MAX_KERNELS", "available", "run_rk4"]


def _rhs(comps, mats, t, y, u, dy, fs, f, tmp):  # pragma: no cover - compiled
    """``dy = ẏ(t, y)`` and ``fs`` the components' force; returns (status, component).

    ``comps``: the packed kernels (:func:`hybridwsi.forces._compiled.packed`),
    ``mats = (M⁻¹, C, A_r, B_r, C_r)``.
    """
    minv, stiff, ar, br, cr = mats
    n = minv.shape[0]
    r = ar.shape[0]
    z = y[:n]
    v = y[n:2 * n]
    status, m = sum_forces(comps, t, z, v, fs, tmp)
    if status != 0:
        return status, m
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += stiff[i, j] * z[j]
        f[i] = -s + u[i] + fs[i]
        if r:
            s = 0.0
            for j in range(r):
                s += cr[i, j] * y[2 * n + j]
            f[i] = f[i] - s
    for i in range(n):
        dy[i] = v[i]
        s = 0.0
        for j in range(n):
            s += minv[i, j] * f[j]
        dy[n + i] = s
    for i in range(r):
        s = 0.0
        for j in range(r):
            s += ar[i, j] * y[2 * n + j]
        s2 = 0.0
        for j in range(n):
            s2 += br[i, j] * v[j]
        dy[2 * n + i] = s + s2
    return 0, -1


def _stage(comps, mats, t, yk, h, slope, u, ys, dy, fs, f, tmp):  # pragma: no cover
    """An RK4 stage: ``dy = ẏ(t, y_k + h slope)`` (``ys`` holds the stage state)."""
    for i in range(yk.size):
        ys[i] = yk[i] + h * slope[i]
    return _rhs(comps, mats, t, ys, u, dy, fs, f, tmp)


def _loop(comps, mats, u_half, dt, y, f_comp):  # pragma: no cover - compiled
    """RK4 over the rows of ``y`` (row 0 the initial state); returns (status, component, step)
    with status 0 (done), a kernel's code, or -1 (a non-finite state)."""
    nt, ns = y.shape
    n = mats[0].shape[0]
    k1, k2, k3, k4 = np.empty(ns), np.empty(ns), np.empty(ns), np.empty(ns)
    ys = np.empty(ns)
    fs, f, tmp, scratch = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    h2, h6 = dt / 2, dt / 6
    for k in range(nt - 1):
        tk = k * dt
        yk = y[k]
        st, m = _rhs(comps, mats, tk, yk, u_half[2 * k], k1, fs, f, tmp)
        if st == 0:
            f_comp[k] = fs
            st, m = _stage(comps, mats, tk + h2, yk, h2, k1, u_half[2 * k + 1], ys, k2,
                           scratch, f, tmp)
        if st == 0:
            st, m = _stage(comps, mats, tk + h2, yk, h2, k2, u_half[2 * k + 1], ys, k3,
                           scratch, f, tmp)
        if st == 0:
            st, m = _stage(comps, mats, tk + dt, yk, dt, k3, u_half[2 * k + 2], ys, k4,
                           scratch, f, tmp)
        if st != 0:
            return st, m, k
        finite = True
        for i in range(ns):
            val = yk[i] + h6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i])
            y[k + 1, i] = val
            finite = finite and np.isfinite(val)
        if not finite:
            return -1, -1, k
    last = nt - 1
    st, m = _rhs(comps, mats, last * dt, y[last], u_half[2 * last], k1, fs, f, tmp)
    f_comp[last] = fs
    return st, m, last


if HAVE_NUMBA:
    _rhs = numba.njit(cache=True)(_rhs)
    _stage = numba.njit(cache=True)(_stage)
    _loop = numba.njit(cache=True)(_loop)


def run_rk4(forces: Sequence[CompiledForce], minv: np.ndarray, stiffness: np.ndarray,
            ss_a: np.ndarray, ss_b: np.ndarray, ss_c: np.ndarray, u_half: np.ndarray,
            y0: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, str | None, int]:
    """Fixed-step RK4 of ``y = [z, ż, x_rad]`` with the components' kernels.

    Parameters
    ----------
    forces : sequence of CompiledForce
        The state-dependent components (at least one).
    minv, stiffness : ndarray (n, n)
        Inverse of the matrix multiplying z̈ [1/kg, ...] and C [N/m, N/rad, N m/m, N m/rad].
    ss_a, ss_b, ss_c : ndarray
        Radiation state space (r, r), (r, n), (n, r); r = 0 without memory.
    u_half : ndarray (2 nt − 1, n)
        Time-only force on the half-step grid [N, N m].
    y0 : ndarray (2 n + r,)
        Initial state.
    dt : float
        Step [s].

    Returns
    -------
    y : ndarray (nt, 2 n + r)
        The state at the output times (NaN after a failure).
    f_comp : ndarray (nt, n)
        The components' summed force at the output times [N, N m].
    message : str or None
        Why the integration stopped early (a kernel's message, or the divergence), None when
        it reached the end: failure is data here, as in every solver.
    steps : int
        Steps completed.
    """
    nt = (u_half.shape[0] + 1) // 2
    n = minv.shape[0]
    y = np.empty((nt, y0.size))
    y[0] = y0
    f_comp = np.empty((nt, n))
    c = np.ascontiguousarray
    with quiet():
        comps = packed(forces)
        mats = (c(minv), c(stiffness), c(ss_a), c(ss_b), c(ss_c))
        status, comp, step = _loop(comps, mats, c(u_half), float(dt), y, f_comp)
    if status == 0:
        return y, f_comp, None, nt - 1
    if status == -1:
        message = f"RK4 integration diverged at t = {step * dt + dt:.6g} s; reduce dt"
    else:
        message = forces[comp].messages.get(status,
                                             f"force kernel {comp} failed with status {status}")
    diverged = status == -1  # the step's stages ran (y[step + 1] is the non-finite state)
    y[step + 2 if diverged else step + 1:] = np.nan  # rows never written
    f_comp[step + 1 if diverged else step:] = np.nan
    return y, f_comp, message, step
