"""The Cummins solvers (paper Eq. 9) for y = [z, ż, x], under one contract.

Each is ``solve(sys, u, z0, v0, dt, *, progress=False, **options) -> SolverResult``
(:mod:`hybridwsi.cummins.result`): ``sys`` the :class:`~hybridwsi.cummins.system.CumminsSystem`,
``u`` the forcing known as a function of time [N, N m], ``z0, v0`` the initial state. A failed
integration is returned (``success=False`` and the reason), never raised.

- :func:`solve_linear` — the linear system with its radiation state space (or no memory):
  the augmented system ``ẏ = A y + B u`` is discretised exactly for piecewise-linear forcing
  (first-order hold) and solved in modal coordinates with ``scipy.signal.lfilter`` (one
  first-order filter per eigenvalue; plain stepping when A is defective or ill-conditioned).
  The only approximations are the state-space fit of K and the linear interpolation of the
  forcing between samples. Batched: ``u`` (n_case, nt, n) and ``z0, v0`` (n_case, n).
- :func:`solve_convolution` — the reference: Newmark average acceleration (β = 1/4, γ = 1/2,
  unconditionally stable, 2nd order) with the memory integral ∫K ż by the trapezoidal rule
  on the sampled K, the term K(0) ż_{n+1} treated implicitly. Cost O(N · N_K).
- :func:`solve_rk4` — fixed-step RK4 of the augmented system for forces that depend on
  the state: an exact (nonlinear) hydrostatic force and force components with or without
  internal states (``KnownComponent.ode_force`` / ``state_derivative``), and stateful
  components stepped by the solver (``KnownComponent.begin_step``, e.g. a coupled mooring
  code); the time-only forcing ``u`` is sampled at the steps and their midpoints. When the
  restoring force is linear and every component has a Numba kernel
  (``KnownComponent.compiled_force``: the linear defaults, quadratic damping, the mooring
  table, Morison drag, the rotor thrust), no internal states and no ``begin_step``, the same
  RK4 runs compiled (:mod:`hybridwsi.cummins.compiled`, ~15× faster, equal to rounding);
  otherwise, or without Numba, the NumPy loop below.

:data:`INTEGRATORS` lists them with what each can integrate; :func:`integrator_for` picks one
(:func:`hybridwsi.cummins.simulate` and ``simulate_batch`` ask it, instead of branching).
"""


from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.signal
from tqdm.auto import tqdm

from hybridwsi.cummins.forcing import state_force
from hybridwsi.cummins.result import SolverResult, failure, first_non_finite
from hybridwsi.cummins.system import RADIATION, CumminsSystem
from hybridwsi.errors import InputError, SolverError
from hybridwsi.forces import KnownComponent
from hybridwsi.hydro.statespace import foh_matrices

#: eigenvector condition number above which the modal solver falls back to plain stepping
_MODAL_COND = 1e6
#: solve_rk4 uses the Numba loop (:mod:`hybridwsi.cummins.compiled`) when it can; False
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


def lti_outputs(a: np.ndarray, b: np.ndarray, dt: float, u: np.ndarray, y0: np.ndarray,
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
        return _lti_stepping(*foh_matrices(a, b, dt), u, y0, out)
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


def _lti_stepping(phi, g0, g1, u, y0, out) -> np.ndarray:
    """Plain recursion (used when Φ is defective, e.g. a free body with C = 0, K = 0)."""
    y = y0.copy()
    res = np.empty((u.shape[0], out.shape[0], u.shape[2]))
    res[0] = out @ y
    for k in range(u.shape[0] - 1):
        y = phi @ y + g0 @ u[k] + g1 @ u[k + 1]
        res[k + 1] = out @ y
    return res


#: message of a linear or convolution solution that is not finite
NOT_FINITE = ("the Cummins solution is not finite (unstable system); check the coefficients "
              "and the state-space fit")


def _time(nt: int, dt: float) -> np.ndarray:
    """Output times ``0, dt, 2 dt, …`` [s] (the grid of :func:`.forcing.time_grid`)."""
    return np.arange(nt) * dt


def _finished(res: SolverResult, *arrays: np.ndarray) -> SolverResult:
    """``res``, marked failed (:data:`NOT_FINITE`) when one of ``arrays`` is not finite."""
    t_bad = first_non_finite(res.t, *arrays)
    if t_bad is not None:
        res.success, res.status = False, -1
        res.message = f"{NOT_FINITE} (from t = {t_bad:.6g} s)"
    return res


# --------------------------------------------------------------------------- linear
def solve_linear(sys: CumminsSystem, u: np.ndarray, z0: np.ndarray, v0: np.ndarray,
                 dt: float, *, progress: bool = False) -> SolverResult:
    """The linear system (radiation state space or none), FOH-exact; see the module doc.

    Parameters
    ----------
    sys : CumminsSystem
    u : ndarray, shape (nt, n) or (n_case, nt, n)
        Input force on the output grid [N, N m]; a 3-D array is a batch of cases.
    z0, v0 : ndarray, shape (n,) or (n_case, n)
        Initial displacement [m, rad] and velocity [m/s, rad/s].
    dt : float
        Step [s].
    progress : bool
        Unused (the modal solution has no time loop in Python).

    Returns
    -------
    SolverResult
        ``z, v`` and ``forces["F_rad_mem"]`` (−C_r x) [N, N m].
    """
    batch = u.ndim == 3
    # the kernel works on (nt, n, n_case): a view, no copy
    uu = np.moveaxis(u, 0, 2) if batch else u[:, :, None]
    z0c, v0c = (np.asarray(z0).T, np.asarray(v0).T) if batch else (z0[:, None], v0[:, None])
    n, r = sys.n, sys.n_states
    a, b = sys.augmented()
    y0 = np.concatenate([z0c, v0c, np.zeros((r, z0c.shape[1]))])
    out = np.zeros((3 * n, 2 * n + r))
    out[:2 * n, :2 * n] = np.eye(2 * n)
    if r:
        out[2 * n:, 2 * n:] = -sys.ss.C  # F_rad_mem = −C_r x
    res = lti_outputs(a, b, dt, uu, y0, out)  # (nt, 3 n, n_case)
    res = np.moveaxis(res, 2, 0) if batch else res[..., 0]
    z, v, mem = res[..., :n], res[..., n:2 * n], res[..., 2 * n:]
    sol = SolverResult(_time(uu.shape[0], dt), z, v, forces={"F_rad_mem": mem},
                       method="linear", counts={"steps": uu.shape[0] - 1})
    return _finished(sol, z, v, mem)


# --------------------------------------------------------------------------- convolution
def solve_convolution(sys: CumminsSystem, u: np.ndarray, z0: np.ndarray, v0: np.ndarray,
                      dt: float, *, progress: bool = False) -> SolverResult:
    """Newmark (β = 1/4, γ = 1/2) with the trapezoidal memory integral; see the module doc.

    ``u`` (nt, n) [N, N m] on the output grid, ``z0, v0`` (n,). Returns ``z, v, a`` and
    ``forces["F_rad_mem"]`` (−∫K ż) [N, N m]. A numerical kernel that reads better whole.
    """
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
    sol = SolverResult(_time(nt, dt), z, v, a=acc, forces={"F_rad_mem": mem},
                       method="convolution", nfev=nt, counts={"steps": nt - 1})
    return _finished(sol, z, v, mem)


# --------------------------------------------------------------------------- RK4
def _offsets(components: Sequence[KnownComponent]) -> list[int]:
    """Start of each component's internal states in the component part of the state vector."""
    return [int(o) for o in np.cumsum([0] + [c.n_states for c in components])[:-1]]


def solve_rk4(sys: CumminsSystem, u: np.ndarray, z0: np.ndarray, v0: np.ndarray, dt: float,
              *, progress: bool = False,
              restoring: Callable[[np.ndarray], np.ndarray] | None = None,
              components: Sequence[KnownComponent] = (), meff: np.ndarray | None = None
              ) -> SolverResult:
    """Fixed-step RK4 of ``y = [z, ż, x_rad, x_components]`` with state-dependent forces.

    Parameters
    ----------
    sys : CumminsSystem
    u : ndarray, shape (2 nt − 1, n)
        Time-only force [N, N m] at ``0, dt/2, dt, …`` (the steps and their midpoints, where
        the RK4 stages evaluate it).
    z0, v0 : ndarray, shape (n,)
        Initial state [m, rad; m/s, rad/s]; internal states start at zero (at rest before 0).
    dt : float
        Step [s].
    progress : bool
        tqdm progress bar (NumPy loop).
    restoring : callable, optional
        Hydrostatic force ``restoring(z)`` [N, N m]; default the linear ``−C z``.
    components : sequence of KnownComponent
        State-dependent forces (their ``ode_force``, ``state_derivative``; ``begin_step`` is
        called once at every output time, before the force evaluations of the step that
        starts there).
    meff : ndarray (n, n), optional
        The matrix multiplying z̈ (M + A∞ + the components' acceleration coefficients);
        default M + A∞.

    Returns
    -------
    SolverResult
        ``z, v``, the states ``x`` and ``forces``: ``F_rad_mem``, ``F_hs`` and
        ``F_components`` (the components' summed force, as the first stage of each step
        evaluates it) [N, N m]. With the linear restoring force, components that all have a
        Numba kernel, no internal states and no ``begin_step``, the compiled loop runs (same
        arithmetic, :data:`COMPILED`; ``method`` "rk4_compiled").
    """
    if meff is None:
        meff = sys.mass + sys.added_mass_inf
    comps = list(components)
    fast = _rk4_compiled(sys, restoring, comps, u, dt, z0, v0, meff)
    if fast is not None:
        return fast
    if restoring is None:
        restoring = lambda z: -sys.stiffness @ z  # noqa: E731
    n_comp = sum(c.n_states for c in comps)
    y0 = np.concatenate([z0, v0, np.zeros(sys.n_states + n_comp)])
    return _RK4(sys, restoring, comps, np.linalg.inv(meff), dt).run(u, y0, progress)


class _RK4:
    """The NumPy RK4 loop of :func:`solve_rk4` (state ``y = [z, ż, x_rad, x_components]``)."""

    def __init__(self, sys: CumminsSystem, restoring: Callable[[np.ndarray], np.ndarray],
                 components: list[KnownComponent], minv: np.ndarray, dt: float) -> None:
        self.sys, self.restoring, self.components = sys, restoring, components
        self.minv, self.dt = minv, dt
        self.offsets = _offsets(components)
        self.base = 2 * sys.n + sys.n_states
        self.stepped = [c for c in components if c.stepped]
        self.nfev = 0

    def rhs(self, tk: float, y: np.ndarray, uk: np.ndarray,
            record: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """``ẏ``; ``record = (f_hs, f_comp)`` receives the restoring and component forces."""
        sys, n, base = self.sys, self.sys.n, self.base
        z, v, x = y[:n], y[n:2 * n], y[2 * n:base]
        self.nfev += 1
        f_hs = self.restoring(z)
        f = f_hs + uk
        if self.components:
            f_comp = state_force(self.components, tk, z, v, y[base:], self.offsets)
            f = f + f_comp
            if record is not None:
                record[1][:] = f_comp
        if record is not None:
            record[0][:] = f_hs
        dx = np.zeros(0)
        if sys.n_states:
            f = f - sys.ss.C @ x
            dx = sys.ss.A @ x + sys.ss.B @ v
        parts = [v, self.minv @ f, dx]
        parts += [np.asarray(c.state_derivative(tk, z, v, y[base + o:base + o + c.n_states]),
                             dtype=float).reshape(c.n_states)
                  for c, o in zip(self.components, self.offsets) if c.n_states]
        return np.concatenate(parts)

    def begin(self, tk: float, yk: np.ndarray) -> None:
        """Every stateful component's ``begin_step`` at ``tk`` on the state ``yk``."""
        n = self.sys.n
        for comp in self.stepped:
            comp.begin_step(tk, yk[:n].copy(), yk[n:2 * n].copy(), self.dt)

    def run(self, u_half: np.ndarray, y0: np.ndarray, progress: bool) -> SolverResult:
        n, dt = self.sys.n, self.dt
        nt = (u_half.shape[0] + 1) // 2
        y = np.full((nt, y0.size), np.nan)
        y[0] = y0
        f_hs, f_comp = np.full((nt, n), np.nan), np.zeros((nt, n))
        message, k = None, 0
        try:
            for k in tqdm(range(nt - 1), disable=not progress, desc="RK4", unit="step",
                          mininterval=1.0):
                y[k + 1] = self.step(k * dt, y[k], u_half[2 * k:2 * k + 3], (f_hs[k], f_comp[k]))
                if not np.all(np.isfinite(y[k + 1])):
                    message = f"RK4 integration diverged at t = {k * dt + dt:.6g} s; reduce dt"
                    break
            else:  # the forces at the last output time
                k = nt - 1
                self.begin(k * dt, y[k])
                self.rhs(k * dt, y[k], u_half[2 * k], (f_hs[k], f_comp[k]))
        except SolverError as err:  # a force model refused the state (e.g. left its table)
            message = str(err)
            y[k + 1:] = np.nan
        return self._result(nt, y, f_hs, f_comp, message, k)

    def step(self, tk: float, yk: np.ndarray, u3: np.ndarray,
             record: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        """One RK4 step from ``yk`` at ``tk``; ``u3`` the input at tk, tk + dt/2, tk + dt."""
        dt = self.dt
        self.begin(tk, yk)
        k1 = self.rhs(tk, yk, u3[0], record)
        k2 = self.rhs(tk + dt / 2, yk + dt / 2 * k1, u3[1])
        k3 = self.rhs(tk + dt / 2, yk + dt / 2 * k2, u3[1])
        k4 = self.rhs(tk + dt, yk + dt * k3, u3[2])
        return yk + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    def _result(self, nt: int, y: np.ndarray, f_hs: np.ndarray, f_comp: np.ndarray,
                message: str | None, k: int) -> SolverResult:
        sys, n = self.sys, self.sys.n
        z, v = y[:, :n], y[:, n:2 * n]
        mem = -y[:, 2 * n:self.base] @ sys.ss.C.T if sys.n_states else np.zeros_like(z)
        kw: dict[str, Any] = dict(
            x=y[:, 2 * n:], forces={"F_rad_mem": mem, "F_hs": f_hs, "F_components": f_comp},
            method="rk4", nfev=self.nfev,
            counts={"steps": k, "begin_step": (k + 1) * len(self.stepped)})
        if message is not None:
            f_hs[k + 1:], f_comp[k + 1:] = np.nan, np.nan
            return failure(_time(nt, self.dt), z, v, message, **kw)
        return SolverResult(_time(nt, self.dt), z, v, **kw)


def _rk4_compiled(sys: CumminsSystem, restoring: Callable[[np.ndarray], np.ndarray] | None,
                  components: Sequence[KnownComponent], u_half: np.ndarray, dt: float,
                  z0: np.ndarray, v0: np.ndarray, meff: np.ndarray) -> SolverResult | None:
    """:func:`solve_rk4` by the compiled loop, or None when it does not apply."""
    if not (COMPILED and restoring is None and components
            and not any(c.n_states or c.stepped for c in components)):
        return None
    from hybridwsi.cummins import compiled  # imports Numba: only when stepping

    kernels = [c.compiled_force(sys.n) for c in components]
    if not compiled.available(kernels):
        return None
    n, r = sys.n, sys.n_states
    ss_a, ss_b, ss_c = ((sys.ss.A, sys.ss.B, sys.ss.C) if r else
                        (np.zeros((0, 0)), np.zeros((0, n)), np.zeros((n, 0))))
    y0 = np.concatenate([z0, v0, np.zeros(r)])
    y, f_comp, message, steps = compiled.run_rk4(kernels, np.linalg.inv(meff), sys.stiffness,
                                                 ss_a, ss_b, ss_c, u_half, y0, dt)
    z, v = y[:, :n], y[:, n:2 * n]
    mem = -y[:, 2 * n:] @ ss_c.T if r else np.zeros_like(z)
    kw: dict[str, Any] = dict(
        x=y[:, 2 * n:], method="rk4_compiled", nfev=4 * steps + 1, counts={"steps": steps},
        forces={"F_rad_mem": mem, "F_hs": -(z @ sys.stiffness.T), "F_components": f_comp})
    t = _time(y.shape[0], dt)
    return SolverResult(t, z, v, **kw) if message is None else failure(t, z, v, message, **kw)


# --------------------------------------------------------------------------- registry
@dataclass(frozen=True)
class CumminsIntegrator:
    """A Cummins solver of the common contract and what it can integrate.

    Attributes
    ----------
    name : str
    solve : callable
        ``solve(sys, u, z0, v0, dt, *, progress=False, **options) -> SolverResult``.
    radiation : tuple of str
        Memory representations it integrates (:data:`hybridwsi.cummins.system.RADIATION`).
    state_forces : bool
        Takes forces that depend on the state (components, the exact hydrostatic force).
    half_steps : bool
        Wants ``u`` at the steps and their midpoints (2 nt − 1 samples).
    batched : bool
        Integrates a batch of cases at once (``u`` (n_case, nt, n)).
    """

    name: str
    solve: Callable[..., SolverResult]
    radiation: tuple[str, ...]
    state_forces: bool = False
    half_steps: bool = False
    batched: bool = False


#: the Cummins solvers, in order of preference (the first that can integrate a run is used)
INTEGRATORS = (
    CumminsIntegrator("linear", solve_linear, ("statespace", "none"), batched=True),
    CumminsIntegrator("convolution", solve_convolution, ("convolution",)),
    CumminsIntegrator("rk4", solve_rk4, ("statespace", "none"), state_forces=True,
                      half_steps=True),
)


def integrator_for(radiation: str, *, state_forces: bool = False, batched: bool = False
                   ) -> CumminsIntegrator:
    """The first of :data:`INTEGRATORS` that integrates this memory representation, with
    state-dependent forces and/or a batch when asked; InputError naming what can."""
    if radiation not in RADIATION:
        raise InputError(f"radiation must be one of {', '.join(RADIATION)}, got '{radiation}'")
    for integ in INTEGRATORS:
        if (radiation in integ.radiation and integ.state_forces >= state_forces
                and integ.batched >= batched):
            return integ
    need = [k for k, v in (("state-dependent forces or nonlinear_hydrostatics", state_forces),
                           ("a batch of cases", batched)) if v]
    able = sorted({r for i in INTEGRATORS for r in i.radiation
                   if i.state_forces >= state_forces and i.batched >= batched})
    raise InputError(f"{' and '.join(need)}: radiation must be "
                     f"{' or '.join(repr(r) for r in able)}, not {radiation!r}")
