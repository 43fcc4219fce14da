"""The three solvers of the Cummins equation (paper Eq. 9) for y = [z, ż, x].

- :func:`run_linear` — the linear system with its radiation state space (or no memory):
  the augmented system ``ẏ = A y + B u`` is discretised exactly for piecewise-linear forcing
  (first-order hold) and solved in modal coordinates with ``scipy.signal.lfilter`` (one
  first-order filter per eigenvalue; plain stepping when A is defective or ill-conditioned).
  The only approximations are the state-space fit of K and the linear interpolation of the
  forcing between samples. Batched over cases (columns).
- :func:`solve_convolution` — the reference: Newmark average acceleration (β = 1/4, γ = 1/2,
  unconditionally stable, 2nd order) with the memory integral ∫K ż by the trapezoidal rule
  on the sampled K, the term K(0) ż_{n+1} treated implicitly. Cost O(N · N_K).
- :func:`run_stepping` — fixed-step RK4 of the augmented system for forces that depend on
  the state: an exact (nonlinear) hydrostatic force and force components with or without
  internal states (``KnownComponent.ode_force`` / ``state_derivative``); the time-only
  forcing is evaluated at half steps. When the restoring force is linear and every component
  has a Numba kernel (``KnownComponent.compiled_force``: the linear defaults, quadratic
  damping, the mooring table, Morison drag, the rotor thrust) and no internal states, the same RK4 runs compiled
  (:mod:`hybridwsi.cummins.compiled`, ~15× faster, equal to rounding); otherwise, or without
  Numba, the NumPy loop below.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import scipy.signal
from tqdm.auto import tqdm

from hybridwsi.cummins.forcing import state_force
from hybridwsi.cummins.system import CumminsSystem
from hybridwsi.errors import SolverError
from hybridwsi.forces import KnownComponent
from hybridwsi.hydro.statespace import foh_matrices

#: eigenvector condition number above which the modal solver falls back to plain stepping
_MODAL_COND = 1e6
#: run_stepping uses the Numba loop (:mod:`hybridwsi.cummins.compiled`) when it can; False
#: forces the NumPy loop (the tests compare both)
COMPILED = True


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


def solve_linear(a: np.ndarray, b: np.ndarray, dt: float, u: np.ndarray, y0: np.ndarray,
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


def solve_convolution(sys: CumminsSystem, u: np.ndarray, z0: np.ndarray, v0: np.ndarray,
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



def run_linear(sys: CumminsSystem, u: np.ndarray, z0: np.ndarray, v0: np.ndarray, dt: float
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """z, ż, F_rad_mem, each (nt, n, n_case), of the linear system driven by ``u``
    (nt, n, n_case) [N, N m] from ``z0``, ``v0`` (n, n_case)."""
    n, r = sys.n, sys.n_states
    a, b = sys.augmented()
    y0 = np.concatenate([z0, v0, np.zeros((r, z0.shape[1]))])
    out = np.zeros((3 * n, 2 * n + r))
    out[:2 * n, :2 * n] = np.eye(2 * n)
    if r:
        out[2 * n:, 2 * n:] = -sys.ss.C  # F_rad_mem = −C_r x
    res = solve_linear(a, b, dt, u, y0, out)
    return res[:, :n], res[:, n:2 * n], res[:, 2 * n:]


def _offsets(components: Sequence[KnownComponent]) -> list[int]:
    """Start of each component's internal states in the component part of the state vector."""
    return [int(o) for o in np.cumsum([0] + [c.n_states for c in components])[:-1]]


def solve_rk4(sys: CumminsSystem, restoring: Callable[[np.ndarray], np.ndarray],
              components: Sequence[KnownComponent], u_half: np.ndarray, y0: np.ndarray,
              dt: float, progress: bool, meff: np.ndarray) -> np.ndarray:
    """Fixed-step RK4 of ``y = [z, ż, x_rad, x_components]``; returns y (nt, n_state).

    ``restoring(z)`` is the hydrostatic force, ``u_half`` the time-only input force on the
    half-step grid (2 nt − 1, n), ``components`` the state-dependent forces, ``meff`` the
    matrix multiplying z̈ (M + A∞ + the components' acceleration coefficients).
    """
    n, r = sys.n, sys.n_states
    minv = np.linalg.inv(meff)
    ss = sys.ss
    offsets = _offsets(components)
    base = 2 * n + r

    def rhs(tk: float, y: np.ndarray, uk: np.ndarray) -> np.ndarray:
        z, v, x = y[:n], y[n:2 * n], y[2 * n:base]
        f = restoring(z) + uk
        if components:
            f = f + state_force(components, tk, z, v, y[base:], offsets)
        dx = np.zeros(0)
        if r:
            f = f - ss.C @ x
            dx = ss.A @ x + ss.B @ v
        parts = [v, minv @ f, dx]
        parts += [np.asarray(c.state_derivative(tk, z, v, y[base + o:base + o + c.n_states]),
                             dtype=float).reshape(c.n_states)
                  for c, o in zip(components, offsets) if c.n_states]
        return np.concatenate(parts)

    nt = (u_half.shape[0] + 1) // 2
    y = np.empty((nt, y0.size))
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


def run_stepping(sys: CumminsSystem, restoring: Callable[[np.ndarray], np.ndarray] | None,
                 components: Sequence[KnownComponent], u_half: np.ndarray, t: np.ndarray,
                 dt: float, z0: np.ndarray, v0: np.ndarray, progress: bool, meff: np.ndarray
                 ) -> tuple[np.ndarray, ...]:
    """RK4 path: z, ż, F_rad_mem, F_hs and the components' force on the output grid t.

    ``restoring`` None means the linear ``−C z``. Internal states of the components start
    at zero (body at rest before t = 0). With the linear restoring force and components that
    all have a Numba kernel (:meth:`~hybridwsi.forces.KnownComponent.compiled_force`) and no
    internal states, the compiled loop runs (same arithmetic, :data:`COMPILED`).
    """
    n = sys.n
    fast = _run_compiled(sys, restoring, components, u_half, dt, z0, v0, meff)
    if fast is not None:
        return fast
    if restoring is None:
        restoring = lambda z: -sys.stiffness @ z  # noqa: E731
    n_comp = sum(c.n_states for c in components)
    y0 = np.concatenate([z0, v0, np.zeros(sys.n_states + n_comp)])
    y = solve_rk4(sys, restoring, components, u_half, y0, dt, progress, meff)
    z, v = y[:, :n], y[:, n:2 * n]
    base = 2 * n + sys.n_states
    mem = -y[:, 2 * n:base] @ sys.ss.C.T if sys.n_states else np.zeros_like(z)
    f_comp = np.zeros_like(z)
    if components:
        offsets = _offsets(components)
        f_comp = np.stack([state_force(components, tk, zk, vk, yk[base:], offsets)
                           for tk, zk, vk, yk in zip(t, z, v, y)])
    return z, v, mem, np.stack([restoring(zk) for zk in z]), f_comp


def _run_compiled(sys: CumminsSystem, restoring: Callable[[np.ndarray], np.ndarray] | None,
                  components: Sequence[KnownComponent], u_half: np.ndarray, dt: float,
                  z0: np.ndarray, v0: np.ndarray, meff: np.ndarray
                  ) -> tuple[np.ndarray, ...] | None:
    """:func:`run_stepping` by the compiled loop, or None when it does not apply."""
    if not (COMPILED and restoring is None and components
            and not any(c.n_states for c in components)):
        return None
    from hybridwsi.cummins import compiled  # imports Numba: only when stepping

    kernels = [c.compiled_force(sys.n) for c in components]
    if not compiled.available(kernels):
        return None
    n, r = sys.n, sys.n_states
    ss_a, ss_b, ss_c = ((sys.ss.A, sys.ss.B, sys.ss.C) if r else
                        (np.zeros((0, 0)), np.zeros((0, n)), np.zeros((n, 0))))
    y0 = np.concatenate([z0, v0, np.zeros(r)])
    y, f_comp = compiled.run_rk4(kernels, np.linalg.inv(meff), sys.stiffness, ss_a, ss_b, ss_c,
                                 u_half, y0, dt)
    z, v = y[:, :n], y[:, n:2 * n]
    mem = -y[:, 2 * n:] @ ss_c.T if r else np.zeros_like(z)
    return z, v, mem, -(z @ sys.stiffness.T), f_comp
