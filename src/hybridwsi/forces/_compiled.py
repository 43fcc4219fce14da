"""Optional Numba kernels of the state-dependent force components, for the compiled RK4 loop.

A component that can be evaluated without Python returns a :class:`CompiledForce` from
:meth:`hybridwsi.forces.KnownComponent.compiled_force`: a kernel of the ONE signature
:data:`KERNEL_SIGNATURE`,

    status = kernel(t, z, zdot, out, fdata, idata)

that writes the component's ``ode_force(t, z, zdot, x)`` [N, N m per DOF] into ``out`` and
returns 0 (or a nonzero code whose message is ``CompiledForce.messages[code]``), and the
component's data packed in one float64 and one int64 vector (layouts documented per kernel).
Every kernel runs the arithmetic of its component's NumPy method (rounding differs by the
summation order only, ~1e-16 relative; the tests compare both paths).
:func:`hybridwsi.cummins.compiled.run_rk4` and the hybrid rollout's loop
(:func:`hybridwsi.surrogate.fast.run_explicit`) call the kernels through Numba's first-class
function type (:func:`packed`, :func:`sum_forces`), so each loop is compiled once (cached on
disk) for any mix of components.

Without Numba (a core dependency, but the code runs without it) :data:`HAVE_NUMBA` is False,
every ``compiled_force`` returns None and the stepping solver keeps its NumPy path.
"""

from __future__ import annotations

import contextlib
import math
import warnings
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hybridwsi._numba import HAVE_NUMBA, numba

_nt = numba.types if HAVE_NUMBA else None

#: status codes a kernel may return besides 0 (ok)
OUTSIDE_TABLE = 1

#: ``int64(float64 t, z, zdot, out, fdata, int64 idata)``: arrays 1-D, C-contiguous
KERNEL_SIGNATURE = (_nt.int64(_nt.float64, _nt.float64[::1], _nt.float64[::1],
                              _nt.float64[::1], _nt.float64[::1], _nt.int64[::1])
                    if HAVE_NUMBA else None)


@dataclass(frozen=True)
class CompiledForce:
    """A component's Numba kernel and its packed data (module doc)."""

    kernel: Any
    fdata: np.ndarray
    idata: np.ndarray
    #: status code -> message of the SolverError the solver raises
    messages: Mapping[int, str] = field(default_factory=dict)


#: reassociation lets LLVM vectorise the sums over strips and wave components (rounding
#: differs by ~1e-16 relative); no "nnan"/"ninf": the range checks must see NaN
FASTMATH = {"reassoc", "contract", "nsz"}


def _kernel(fn):
    """A force kernel: compiled eagerly for :data:`KERNEL_SIGNATURE`, cached on disk."""
    return (numba.njit(KERNEL_SIGNATURE, cache=True, fastmath=FASTMATH)(fn) if HAVE_NUMBA
            else None)


def _floats(*parts: Any) -> np.ndarray:
    return np.ascontiguousarray(np.concatenate([np.ravel(np.asarray(p, dtype=float))
                                                for p in parts]))


def _ints(*parts: Any) -> np.ndarray:
    return np.ascontiguousarray(np.concatenate([np.ravel(np.asarray(p, dtype=np.int64))
                                                for p in parts]))


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Silence Numba's warning that the first-class function type is experimental (the
    kernels are passed as arguments; their use here is tested)."""
    with warnings.catch_warnings():
        if HAVE_NUMBA:
            warnings.simplefilter("ignore", numba.NumbaExperimentalFeatureWarning)
        yield


def rotation_from(s1: Any, c1: Any, s2: Any, c2: Any, s3: Any, c3: Any) -> tuple:
    """MoorPy's rotation ``Rz(yaw) Ry(pitch) Rx(roll)`` from the sines and cosines of yaw (1),
    pitch (2) and roll (3), as nested 3x3 tuples (floats or arrays alike)."""
    return (
        (c1 * c2, c1 * s2 * s3 - c3 * s1, s1 * s3 + c1 * c3 * s2),
        (c2 * s1, c1 * c3 + s1 * s2 * s3, c3 * s1 * s2 - c1 * s3),
        (-s2, c2 * s3, c2 * c3),
    )


def bicubic(c: Any, o: int, u: Any, v: Any) -> Any:
    """``Σ_pq c[o + 4p + q] u^p v^q`` by Horner's rule (floats or arrays alike)."""
    return ((c[o] + v * (c[o + 1] + v * (c[o + 2] + v * c[o + 3])))
            + u * ((c[o + 4] + v * (c[o + 5] + v * (c[o + 6] + v * c[o + 7])))
                   + u * ((c[o + 8] + v * (c[o + 9] + v * (c[o + 10] + v * c[o + 11])))
                          + u * (c[o + 12] + v * (c[o + 13] + v * (c[o + 14] + v * c[o + 15]))))))


def line_pull(horizontal: Any, vertical: Any, lh: Any, dx: Any, dy: Any, bx: Any, by: Any,
              bz: Any) -> tuple:
    """Force [N] and moment [N m] of one line on its fairlead at arm ``b`` from the reference
    point, ``(fx, fy, fz, mx, my, mz)``; ``(dx, dy)`` the fairlead's horizontal offset from
    the anchor, ``lh`` its length, ``horizontal``/``vertical`` the tabulated fairlead forces."""
    towards = -horizontal / lh  # horizontal pull points from the fairlead to the anchor
    fx, fy, fz = towards * dx, towards * dy, -vertical
    return fx, fy, fz, by * fz - bz * fy, bz * fx - bx * fz, bx * fy - by * fx


if HAVE_NUMBA:
    _rotation = numba.njit(cache=True, inline="always")(rotation_from)
    _bicubic = numba.njit(cache=True, inline="always")(bicubic)
    _line_pull = numba.njit(cache=True, inline="always")(line_pull)


def _rate(zdot, jac, k):  # pragma: no cover - compiled
    """``−J_k ż``: minus the velocity of strip k along one axis [m/s]."""
    s = 0.0
    for i in range(zdot.size):
        s += zdot[i] * jac[k, i]
    return -s


if HAVE_NUMBA:
    _rate = numba.njit(cache=True, inline="always", fastmath=True)(_rate)


# ------------------------------------------------------------------- sets of components
def _nothing(t, z, zdot, out, fdata, idata):  # pragma: no cover - compiled
    """The padding kernel: no force."""
    for i in range(out.size):
        out[i] = 0.0
    return 0


#: a compiled loop takes exactly this many kernels (padded with a zero force), so it is
#: compiled once, whatever the number of components (each tuple length would be a new
#: compilation)
MAX_KERNELS = 8

nothing_kernel = _kernel(_nothing)


def available(forces: Any) -> bool:
    """True when Numba is installed, every component has a kernel (not None) and there are
    at most :data:`MAX_KERNELS` of them."""
    return HAVE_NUMBA and len(forces) <= MAX_KERNELS and all(f is not None for f in forces)


def packed(forces: Any) -> tuple:
    """The components' kernels as a compiled loop takes them: ``(kernels, n_kernels, fdata,
    idata)``, tuples padded to :data:`MAX_KERNELS` with a zero force (call under
    :func:`quiet`)."""
    pad = [CompiledForce(nothing_kernel, np.zeros(0), np.zeros(0, dtype=np.int64))] * (
        MAX_KERNELS - len(forces))
    padded = list(forces) + pad
    return (tuple(f.kernel for f in padded), len(forces), tuple(f.fdata for f in padded),
            tuple(f.idata for f in padded))


def _sum_forces(comps, t, z, zdot, fs, tmp):  # pragma: no cover - compiled
    """``fs`` = the summed force of the packed components (:func:`packed`) at ``(t, z, ż)``,
    ``tmp`` scratch (n,); returns ``(status, component)``: (0, -1), or the first failing
    kernel's code and index."""
    kernels, n_kernels, fdata, idata = comps
    for i in range(fs.size):
        fs[i] = 0.0
    for m in range(n_kernels):
        status = kernels[m](t, z, zdot, tmp, fdata[m], idata[m])
        if status != 0:
            return status, m
        for i in range(fs.size):
            fs[i] = fs[i] + tmp[i]
    return 0, -1


def _force_rows(comps, t, z, zdot, out):  # pragma: no cover - compiled
    """:func:`_sum_forces` on every row of ``t`` (n,), ``z``, ``zdot`` (n, n_dof) into ``out``
    (n, n_dof). A row whose state is not finite gets NaN (a diverged case); returns
    ``(status, component, row)`` of the first failing finite row, else (0, -1, -1)."""
    n = z.shape[1]
    tmp = np.empty(n)
    for r in range(z.shape[0]):
        finite = True
        for i in range(n):
            finite = finite and np.isfinite(z[r, i]) and np.isfinite(zdot[r, i])
        if not finite:
            out[r, :] = np.nan
            continue
        status, m = sum_forces(comps, t[r], z[r], zdot[r], out[r], tmp)
        if status != 0:
            return status, m, r
    return 0, -1, -1


if HAVE_NUMBA:
    sum_forces = numba.njit(cache=True)(_sum_forces)
    force_rows = numba.njit(cache=True)(_force_rows)
else:
    sum_forces = force_rows = None


# ------------------------------------------------------------------------------- linear
def _linear(t, z, zdot, out, fdata, idata):  # pragma: no cover - compiled
    # fdata = [B (n×n, row-major), C (n×n)]: out = −B ż − C z (KnownComponent.ode_force)
    n = z.size
    nn = n * n
    for i in range(n):
        bv = 0.0
        cz = 0.0
        for j in range(n):
            bv += fdata[i * n + j] * zdot[j]
            cz += fdata[nn + i * n + j] * z[j]
        out[i] = -bv - cz
    return 0


linear_kernel = _kernel(_linear)


def linear_force(b: np.ndarray, c: np.ndarray) -> CompiledForce | None:
    """``F = −B ż − C z`` [N, N m], constant (n, n) matrices (the default ``ode_force``)."""
    if not HAVE_NUMBA:
        return None
    return CompiledForce(linear_kernel, _floats(b, c), np.zeros(0, dtype=np.int64))


def _quadratic(t, z, zdot, out, fdata, idata):  # pragma: no cover - compiled
    # fdata = [Bq diagonal (n)]: out = −Bq |ż| ż (QuadraticDamping.ode_force)
    for i in range(z.size):
        out[i] = (-fdata[i] * abs(zdot[i])) * zdot[i]
    return 0


quadratic_kernel = _kernel(_quadratic)


def quadratic_force(bq: np.ndarray) -> CompiledForce | None:
    """``F_i = −Bq_i |ż_i| ż_i`` [N, N m], ``bq`` (n,) the diagonal [N s²/m², N m s²/rad²]."""
    if not HAVE_NUMBA:
        return None
    return CompiledForce(quadratic_kernel, _floats(bq), np.zeros(0, dtype=np.int64))


def _rotor(t, z, zdot, out, fdata, idata):  # pragma: no cover - compiled
    # fdata = [T, B_aero, lever j (n)]: out = (T − B_aero jᵀż) j (RotorThrust.ode_force)
    n = z.size
    v = 0.0
    for i in range(n):
        v += zdot[i] * fdata[2 + i]
    hub = fdata[0] - fdata[1] * v
    for i in range(n):
        out[i] = hub * fdata[2 + i]
    return 0


rotor_kernel = _kernel(_rotor)


def rotor_force(thrust: float, aero_damping: float, lever: np.ndarray) -> CompiledForce | None:
    """Hub force ``T − B_aero v_hub`` [N] times the lever ``j`` (n,) (``v_hub = jᵀ ż`` [m/s]):
    the generalised force [N, N m] of :class:`hybridwsi.forces.rotor.RotorThrust`."""
    if not HAVE_NUMBA:
        return None
    return CompiledForce(rotor_kernel, _floats([thrust, aero_damping], lever),
                         np.zeros(0, dtype=np.int64))


def _operating_rotor(t, z, zdot, out, fdata, idata):  # pragma: no cover - compiled
    # idata = [n_dof, n_table, n_wind]; fdata = [wind dt, j_T (n), j_Q (n), U (n_table),
    # T (n_table), Q (n_table), wind samples (n_wind)]: OperatingRotor.ode_force
    n, nu, nw = idata[0], idata[1], idata[2]
    jt, jq = 1, 1 + n
    ug = 1 + 2 * n
    tg, qg, ws = ug + nu, ug + 2 * nu, ug + 3 * nu
    x = t / fdata[0]  # periodic linear interpolation of the wind (wind.periodic_interp)
    k = math.floor(x)
    w = x - k
    i = int(k) % nw
    wind = fdata[ws + i] * (1.0 - w) + fdata[ws + (i + 1) % nw] * w
    v = 0.0
    for m in range(n):
        v += zdot[m] * fdata[jt + m]
    u = wind - v
    if not (fdata[ug] <= u <= fdata[ug + nu - 1]):
        return OUTSIDE_TABLE
    lo, hi = 0, nu - 1  # bisection: fdata[ug + lo] <= u <= fdata[ug + hi]
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if fdata[ug + mid] <= u:
            lo = mid
        else:
            hi = mid
    f = (u - fdata[ug + lo]) / (fdata[ug + hi] - fdata[ug + lo])
    thrust = fdata[tg + lo] + f * (fdata[tg + hi] - fdata[tg + lo])
    torque = fdata[qg + lo] + f * (fdata[qg + hi] - fdata[qg + lo])
    for m in range(n):
        out[m] = thrust * fdata[jt + m] + torque * fdata[jq + m]
    return 0


operating_rotor_kernel = _kernel(_operating_rotor)


def operating_rotor_force(speeds: np.ndarray, thrust: np.ndarray, torque: np.ndarray,
                          lever: np.ndarray, torque_lever: np.ndarray, wind_dt: float,
                          wind: np.ndarray) -> CompiledForce | None:
    """``T(U_rel) j_T + Q(U_rel) j_Q`` [N, N m] with ``U_rel = U(t) − j_Tᵀ ż`` [m/s]: the
    tabulated operating curve (``speeds`` increasing, linear interpolation) and the wind's
    periodic samples (step ``wind_dt`` [s]) of
    :class:`hybridwsi.forces.rotor.OperatingRotor`."""
    if not HAVE_NUMBA:
        return None
    lo, hi = float(speeds[0]), float(speeds[-1])
    return CompiledForce(
        operating_rotor_kernel,
        _floats([wind_dt], lever, torque_lever, speeds, thrust, torque, wind),
        _ints([len(lever), len(speeds), len(wind)]),
        {OUTSIDE_TABLE: f"rotor: relative wind speed outside the table [{lo:g}, {hi:g}] m/s"})


# ------------------------------------------------------------------------------- mooring
def _mooring(t, z, zdot, out, fdata, idata):  # pragma: no cover - compiled
    # idata = [n_dof, n_lines, nh, nv, dof index × n_dof]
    # fdata = [h0, v0, dh, dv, yaw_spring, F0 (6), lines (6 per line: anchor xyz, fairlead
    #          xyz), cells (32 per cell: horizontal 16, vertical 16)]
    # the arithmetic of MooringTable._wrench (one state) and MooringForce.ode_force
    n_dof, n_lines, nh, nv = idata[0], idata[1], idata[2], idata[3]
    q = np.zeros(6)
    for i in range(n_dof):
        q[idata[4 + i]] = z[i]
    h0, v0, dh, dv, yaw_spring = fdata[0], fdata[1], fdata[2], fdata[3], fdata[4]
    lines0 = 11
    cells0 = lines0 + 6 * n_lines
    x0, y0, z0, roll, pitch, yaw = q[0], q[1], q[2], q[3], q[4], q[5]
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = _rotation(
        math.sin(yaw), math.cos(yaw), math.sin(pitch), math.cos(pitch), math.sin(roll),
        math.cos(roll))
    full = np.zeros(6)  # force [N] and moment [N m] of all lines
    for m in range(n_lines):
        o = lines0 + 6 * m
        ax, ay, az = fdata[o], fdata[o + 1], fdata[o + 2]
        px, py, pz = fdata[o + 3], fdata[o + 4], fdata[o + 5]
        bx = r00 * px + r01 * py + r02 * pz  # fairlead arm in global axes
        by = r10 * px + r11 * py + r12 * pz
        bz = r20 * px + r21 * py + r22 * pz
        dx, dy, dz = bx + x0 - ax, by + y0 - ay, bz + z0 - az
        lh = math.hypot(dx, dy)
        x = (lh - h0) / dh
        y = (dz - v0) / dv
        if not (0.0 <= x <= nh and 0.0 <= y <= nv):
            return OUTSIDE_TABLE
        i, j = min(int(x), nh - 1), min(int(y), nv - 1)
        u, v = x - i, y - j
        a = cells0 + 32 * (i * nv + j)
        pull = _line_pull(_bicubic(fdata, a, u, v), _bicubic(fdata, a + 16, u, v), lh, dx, dy,
                          bx, by, bz)
        for d in range(6):
            full[d] += pull[d]
    full[5] -= yaw_spring * q[5]
    for i in range(n_dof):
        k = idata[4 + i]
        out[i] = full[k] - fdata[5 + k]
    return 0


mooring_kernel = _kernel(_mooring)


def _mooring_rows(z, out, fdata, idata):  # pragma: no cover - compiled
    """The mooring kernel on every row of ``z`` (n, n_dof); the first nonzero status or 0."""
    zdot = np.zeros(z.shape[1])
    for r in range(z.shape[0]):
        status = mooring_kernel(0.0, z[r], zdot, out[r], fdata, idata)
        if status != 0:
            return status
    return 0


mooring_rows = numba.njit(cache=True)(_mooring_rows) if HAVE_NUMBA else None


def mooring_force(origin: tuple[float, float], step: tuple[float, float], n: tuple[int, int],
                  yaw_spring: float, f0: np.ndarray, anchors: np.ndarray,
                  fairleads: np.ndarray, cells: np.ndarray, index: list[int],
                  outside: str) -> CompiledForce | None:
    """The tabulated mooring ``F(q) − F0`` on the DOFs ``index`` (``MooringForce.ode_force``).

    ``cells`` (n_cells, 32): the bicubic coefficients of the horizontal and vertical fairlead
    force per (l_h, l_v) cell, ``outside`` the message when a fairlead leaves the table.
    """
    if not HAVE_NUMBA:
        return None
    lines = np.concatenate([anchors, fairleads], axis=1)
    return CompiledForce(
        mooring_kernel,
        _floats(origin, step, [yaw_spring], f0, lines, cells),
        _ints([len(index), lines.shape[0], n[0], n[1]], index),
        {OUTSIDE_TABLE: outside})


# ------------------------------------------------------------------------------- Morison
def _morison(t, z, zdot, out, fdata, idata):  # pragma: no cover - compiled
    # idata = [n_strips, n_dof, n_comp, two_d]; n_comp 0: no wave kinematics
    # fdata = [coef (ns), jx (ns × n_dof), jy (ns × n_dof), omega (nc), phase (nc),
    #          profile (ns × nc), cos β, sin β, ramp, cached t, cached speed (ns)]
    # the arithmetic of MorisonDrag.generalised_force for one state (and AiryKinematics.speed)
    ns, n, nc, two_d = idata[0], idata[1], idata[2], idata[3]
    coef = fdata[:ns]
    jx = fdata[ns:ns + ns * n].reshape((ns, n))
    jy = fdata[ns + ns * n:ns + 2 * ns * n].reshape((ns, n))
    o = ns + 2 * ns * n
    omega, phase = fdata[o:o + nc], fdata[o + nc:o + 2 * nc]
    profile = fdata[o + 2 * nc:o + 2 * nc + ns * nc].reshape((ns, nc))
    o += 2 * nc + ns * nc
    cb, sb, ramp = fdata[o], fdata[o + 1], fdata[o + 2]
    speed = fdata[o + 4:o + 4 + ns]
    if nc > 0 and not fdata[o + 3] == t:  # the wave speed at t, once per distinct t (RK4
        # stages 2 and 3 share their time); the cached t starts as NaN
        speed[:] = profile @ np.cos(omega * t + phase)
        if ramp > 0.0 and t < ramp:  # ramp 0: none, even at t < 0
            speed *= 0.5 * (1.0 - math.cos(math.pi * max(t, 0.0) / ramp))
        fdata[o + 3] = t
    for i in range(n):
        out[i] = 0.0
    for k in range(ns):
        ux = _rate(zdot, jx, k)
        if nc > 0:
            ux += speed[k] * cb
        if two_d:
            uy = _rate(zdot, jy, k)
            if nc > 0:
                uy += speed[k] * sb
            w = coef[k] * math.hypot(ux, uy)
            for i in range(n):
                out[i] += (w * ux) * jx[k, i] + (w * uy) * jy[k, i]
        else:
            w = coef[k] * abs(ux) * ux
            for i in range(n):
                out[i] += w * jx[k, i]
    return 0


morison_kernel = _kernel(_morison)


def morison_force(coef: np.ndarray, jx: np.ndarray, jy: np.ndarray, two_d: bool,
                  wave: Any = None) -> CompiledForce | None:
    """Morison strip drag ``Q = Σ J_kᵀ dF_k`` (``MorisonDrag.generalised_force``, one state).

    ``jx, jy`` (n_strips, n_dof) the strip Jacobians, ``wave`` the strips' ``AiryKinematics`` (its
    ``omega``, ``phase``, ``profile`` (n_strips, n_comp), ``cos_beta``, ``sin_beta``,
    ``ramp``) or None.
    """
    if not HAVE_NUMBA:
        return None
    ns = coef.size
    if wave is None:
        omega = phase = np.zeros(0)
        profile = np.zeros((ns, 0))
        cb = sb = ramp = 0.0
    else:
        omega, phase, profile = wave.omega, wave.phase, wave.profile
        cb, sb, ramp = wave.cos_beta, wave.sin_beta, wave.ramp
    return CompiledForce(
        morison_kernel,
        _floats(coef, jx, jy, omega, phase, profile, [cb, sb, ramp, np.nan], np.zeros(ns)),
        _ints([ns, jx.shape[1], omega.size, int(two_d)]))
