"""The hybrid rollout's coupled step and its integrators (docs/THEORY.md §4c).

    (m + A_k) z̈ = Σ_known F_i(t, z, ż, x) + F_prescribed(t) + F_net(features)

:class:`CoupledStepper` is one step of this ODE for a batch of cases, in the three couplings
of the network force:

- ``lagged`` (loosely coupled): the network sees the kinematics of the previous step; the
  step is a :class:`~hybridwsi.diagnostic.integrators.LaggedIntegrator` (the map whose
  amplification matrix :mod:`hybridwsi.diagnostic.stability` analyses);
- ``corrected``: the lagged step, then ``corrections`` passes with the network (and the known
  explicit forces) evaluated again on the predicted end-of-step state;
- ``implicit``: Newmark average acceleration with the network inside the fixed point
  (Aitken relaxation).

:func:`solve_coupled` integrates a batch with it under the solver contract of
:mod:`hybridwsi.cummins.result` (``solve(system, u, z0, v0, dt, *, progress, **options) ->
SolverResult``; a diverging case is reported in ``failed``, never raised), by the NumPy
stepper or, for ``lagged``/``corrected`` when every nonlinear known component has a Numba
kernel (:meth:`BatchedPhysics.compiled_forces`), by the compiled loop of
:mod:`hybridwsi.surrogate.fast`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from hybridwsi.cummins.result import SolverResult
from hybridwsi.diagnostic.integrators import LaggedIntegrator, check_scheme
from hybridwsi.errors import InputError
from hybridwsi.surrogate import fast
from hybridwsi.surrogate.fast import folded_layers, numpy_forward
from hybridwsi.surrogate.network import ForceNetwork, torch
from hybridwsi.surrogate.physics import BatchedPhysics

MODES = ("lagged", "corrected", "implicit")
#: network evaluations of at most this many cases run in NumPy (per-call torch overhead)
_NUMPY_MAX_BATCH = 8


# ------------------------------------------------------------------------------- stepper
@dataclass
class State:
    """The carried state of a batch: z [m, rad], ż, z̈ (n_cases, n_dof), the known
    components' internal states (n_cases, n_states) and the feature-channel window."""

    z: np.ndarray  # (nc, nd)
    v: np.ndarray
    a: np.ndarray
    x: np.ndarray  # (nc, n_states)
    buf: np.ndarray  # (nc, span, n_channels), lag 0 first


ForceFn = Callable[[np.ndarray], np.ndarray]  # features (nc, n_feat) -> force (nc, nd)


def _index(positions) -> slice | list[int]:
    """Channel positions as a slice when consecutive (basic indexing: no fancy-index copy)."""
    pos = list(positions)
    if pos and pos == list(range(pos[0], pos[0] + len(pos))):
        return slice(pos[0], pos[0] + len(pos))
    return pos


class CoupledStepper:
    """One step of the hybrid ODE, shared by the rollout and its stability map.

    ``lagged`` steps a :class:`hybridwsi.diagnostic.integrators.LaggedIntegrator` (the
    arithmetic of ``lagged_step``, whose amplification matrix
    :mod:`hybridwsi.diagnostic.stability` analyses) with the
    network, the radiation-memory force and nonlinear known terms as the explicit force on the
    start-of-step state; the linear known part (M = m + A_k, B_k, C_k) is implicit.
    ``implicit`` uses Newmark average acceleration with the network in the fixed point.
    Internal states (radiation memory) advance by the trapezoidal rule.
    """

    def __init__(self, phys: BatchedPhysics, spec, dt: float, mode: str, net_force: ForceFn,
                 scheme: str = "newmark", max_iter: int = 50, tol: float = 1e-9,
                 corrections: int = 1) -> None:
        if mode not in MODES:
            raise InputError(f"mode must be one of {', '.join(MODES)}, got '{mode}'")
        if mode == "corrected" and (scheme != "newmark" or int(corrections) < 1):
            raise InputError("mode 'corrected' needs scheme 'newmark' and corrections >= 1")
        self.corrections = int(corrections) if mode == "corrected" else 0
        self.phys, self.spec, self.dt, self.mode = phys, spec, float(dt), mode
        self.scheme = check_scheme(scheme)
        self.net_force, self.max_iter, self.tol = net_force, int(max_iter), float(tol)
        self.kin_idx = {name: _index(spec.channels.index((name, k)) for k in range(spec.n_dof))
                        for name in ("z", "zdot", "zddot") if name in spec.inputs}
        self.eta_idx = _index(spec.channels.index(("eta", k)) for k in range(spec.n_probe)) \
            if "eta" in spec.inputs else []
        self.iterations: list[int] = []
        self.n_network = 0  # network evaluations (each over the whole batch)
        # lagged mode: the implicit solve of lagged_step factorised once for the whole run
        self.integrator = LaggedIntegrator(self.scheme, self.dt, phys.m_eff, phys.b_lin,
                                           phys.c_lin) if mode != "implicit" else None
        self._remainder = phys.has_remainder
        self._has_eta = "eta" in spec.inputs and spec.n_probe > 0

    def _net(self, features: np.ndarray) -> np.ndarray:
        """The network force [N, N m] of feature rows (n_cases, n_features), counted."""
        self.n_network += 1
        return self.net_force(features)

    def row(self, z, v, a, eta) -> np.ndarray:
        """Feature channels of one time step, (nc, n_channels)."""
        out = np.empty((z.shape[0], self.spec.n_channels))
        for name, val in (("z", z), ("zdot", v), ("zddot", a)):
            if name in self.kin_idx:
                out[:, self.kin_idx[name]] = val
        if self._has_eta:
            out[:, self.eta_idx] = eta
        return out

    def feat(self, buf: np.ndarray) -> np.ndarray:
        """Network features of a buffer: the taps ``0, stride, ...``, flattened lag-major."""
        return buf[:, :: self.spec.stride].reshape(len(buf), -1)

    @staticmethod
    def shifted(buf: np.ndarray, row: np.ndarray) -> np.ndarray:
        return np.concatenate([row[:, None, :], buf[:, :-1, :]], axis=1)

    def _states(self, s: State, t0: float, v1: np.ndarray, z1: np.ndarray,
                g0: np.ndarray | None) -> np.ndarray:
        """Trapezoidal update of the internal states (fixed point; linear ones converge fast)."""
        phys, dt = self.phys, self.dt
        if not phys.n_states:
            return s.x
        if not phys.other_states:  # linear state space: the trapezoidal rule solved exactly
            x1 = np.empty_like(s.x)
            for sl, lhs_inv, rhs, b in phys.ss_trapezoid(dt):
                x1[:, sl] = (s.x[:, sl] @ rhs.T + 0.5 * dt * (s.v + v1) @ b.T) @ lhs_inv.T
            return x1
        x1 = s.x + dt * g0
        for _ in range(3):
            x1 = s.x + 0.5 * dt * (g0 + phys.state_derivative(t0 + dt, z1, v1, x1))
        return x1

    def step(self, s: State, t1: float, f_pre: np.ndarray, eta1: np.ndarray) -> State:
        if self.mode == "implicit":
            return self._implicit(s, t1, f_pre, eta1)
        return self._lagged(s, t1, f_pre, eta1)

    def _lagged(self, s: State, t1: float, f_pre: np.ndarray, eta1: np.ndarray) -> State:
        phys, t0 = self.phys, t1 - self.dt
        g0 = phys.state_derivative(t0, s.z, s.v, s.x) if phys.n_states else None
        # explicit part on the start-of-step state; the prescribed force is a known function
        # of time, so it is taken at the end of the step (no coupling lag to analyse)
        t_x, z_x, v_x, x_x, buf = t0, s.z, s.v, s.x, s.buf
        for _ in range(1 + self.corrections):
            f_x = self._net(self.feat(buf)) + f_pre
            if self._remainder:  # otherwise exactly zero
                f_x = f_x + phys.explicit_force(t_x, z_x, v_x, x_x)
            z1, v1, a1 = self.integrator.step(s.z.T, s.v.T, s.a.T, f_x.T)
            z1, v1, a1 = z1.T, v1.T, a1.T
            x1 = self._states(s, t0, v1, z1, g0)
            buf = self.shifted(s.buf, self.row(z1, v1, a1, eta1))
            # corrected: the explicit forces again, on the predicted end-of-step state
            t_x, z_x, v_x, x_x = t1, z1, v1, x1
        self.iterations.append(1 + self.corrections)
        return State(z1, v1, a1, x1, buf)

    def _implicit(self, s: State, t1: float, f_pre: np.ndarray, eta1: np.ndarray) -> State:
        dt, m_inv, phys = self.dt, self.phys.m_inv, self.phys
        t0 = t1 - dt
        g0 = phys.state_derivative(t0, s.z, s.v, s.x) if phys.n_states else None
        a, x1 = s.a.copy(), s.x
        r_prev, omega = None, 1.0
        for it in range(1, self.max_iter + 1):
            v1 = s.v + 0.5 * dt * (s.a + a)
            z1 = s.z + dt * s.v + 0.25 * dt * dt * (s.a + a)
            x1 = self._states(s, t0, v1, z1, g0)
            buf1 = self.shifted(s.buf, self.row(z1, v1, a, eta1))
            f_net = self._net(self.feat(buf1))
            a_new = (phys.force(t1, z1, v1, x1) + f_pre + f_net) @ m_inv.T
            r = a_new - a
            # Aitken's dynamic relaxation (Kuettler & Wall 2008) for the interface fixed point
            if r_prev is not None:
                dr = r - r_prev
                den = float(np.sum(dr * dr))
                if den > 0:
                    omega = float(np.clip(-omega * np.sum(r_prev * dr) / den, -2.0, 2.0))
            a = a + omega * r
            r_prev = r
            if not np.all(np.isfinite(a)) or \
                    float(np.max(np.abs(r))) <= self.tol * (1.0 + float(np.max(np.abs(a)))):
                break
        self.iterations.append(it)
        v1 = s.v + 0.5 * dt * (s.a + a)
        z1 = s.z + dt * s.v + 0.25 * dt * dt * (s.a + a)
        x1 = self._states(s, t0, v1, z1, g0)
        return State(z1, v1, a, x1, self.shifted(s.buf, self.row(z1, v1, a, eta1)))


def network_force(net: ForceNetwork) -> ForceFn:
    """Fast inference closure on the folded layers (:func:`.fast.folded_layers`): NumPy for
    a few cases per call (a torch call's fixed overhead exceeds the arithmetic),
    raw ``addmm``/activation torch calls for larger batches."""
    layers = folded_layers(net)
    wts = [torch.from_numpy(w) for w in layers.weights]
    bs = [torch.from_numpy(b) for b in layers.biases]
    act = {"tanh": torch.tanh, "relu": torch.relu, "silu": torch.nn.functional.silu,
           "gelu": torch.nn.functional.gelu}[layers.activation]

    def f(x: np.ndarray) -> np.ndarray:
        if len(x) <= _NUMPY_MAX_BATCH:
            return numpy_forward(layers, x)
        with torch.inference_mode():
            h = torch.from_numpy(np.ascontiguousarray(x))
            for k, (w, b) in enumerate(zip(wts, bs)):
                h = torch.addmm(b, h, w)
                if k < len(wts) - 1:
                    h = act(h)
            return h.numpy()
    return f


def corrections_for(ratio: float, reduction: float = 0.01, max_corrections: int = 8) -> int:
    """Corrections of the ``corrected`` coupling for a network with added-mass ratio ``ratio``.

    Each correction re-evaluates the network on the end-of-step state just predicted, which
    multiplies the acceleration error of the previous pass by ``alpha_s / (m + A_k)``
    (docs/THEORY.md §4c). The lagged pass's error acts as a damping (for ``alpha_s < 0``, the
    usual added mass), so an odd number of corrections leaves a *negative* damping of
    ``ratio^k`` times it (unstable without physical damping) and an even number a positive
    one. Hence: 1 when the network has no inertia part (``ratio = 0``), else the smallest
    even ``k`` with ``ratio^k <= reduction``, at most ``max_corrections``. A ratio >= 1
    diverges whatever k (2 returned; the stability check says so).
    """
    if ratio <= 0.0:
        return 1
    if ratio >= 1.0:
        return 2
    k = int(np.ceil(np.log(reduction) / np.log(ratio) - 1e-9))
    return int(min(max_corrections, max(2, k + k % 2)))


# --------------------------------------------------------------------------- integrators
#: |z| beyond this many times the reference amplitude (or non-finite) counts as blown up
BLOWUP_FACTOR = 20.0

#: what a time loop returns: z, ż, z̈ (n_cases, n_steps + 1, n_dof), states, per-case
#: divergence flags, steps done, fixed-point iterations per step, network evaluations and
#: the known force recorded on the way (stepped components; else None)
Loop = tuple[Any, ...]


def solve_coupled(stepper: CoupledStepper, u: np.ndarray, z0: np.ndarray, v0: np.ndarray,
                  dt: float, *, progress: bool = False, a0: np.ndarray, x0: np.ndarray,
                  window: np.ndarray, eta: np.ndarray, t: np.ndarray, start: int, lead: int,
                  n_steps: int, ref_amp: np.ndarray, layers: fast.FoldedLayers | None = None
                  ) -> SolverResult:
    """Integrate a batch of cases with the coupled step (the solver contract).

    Parameters
    ----------
    stepper : CoupledStepper
        The coupled step (known physics, network force, coupling mode, Δt).
    u : ndarray, shape (n_cases, n_time, n_dof)
        Prescribed force [N, N m] on the cases' time grid ``t``.
    z0, v0 : ndarray, shape (n_cases, n_dof)
        State at sample ``start`` [m, rad; m/s, rad/s].
    dt : float
        Step [s] (the stepper's).
    progress : bool
        tqdm progress bar (NumPy stepper).
    a0 : ndarray, shape (n_cases, n_dof)
        Acceleration at ``start`` [m/s², rad/s²].
    x0 : ndarray, shape (n_cases, n_states)
        Internal states of the known components at ``start``.
    window : ndarray, shape (n_cases, span, n_channels)
        Feature channels of samples ``start, start − 1, …`` (lag 0 first).
    eta : ndarray, shape (n_cases, n_time, n_probe)
        Wave elevation [m] (network input).
    t : ndarray, shape (n_time,)
        The cases' time grid [s]; ``start`` the first sample integrated from, ``lead`` the
        network's look-ahead on ``eta`` (samples), ``n_steps`` the steps to take.
    ref_amp : ndarray, shape (n_cases,)
        Reference max |z| per case: beyond :data:`BLOWUP_FACTOR` times it a case diverged.
    layers : FoldedLayers, optional
        The network's folded layers: run the compiled loop (``lagged``/``corrected`` with
        known components it supports, :func:`.fast.supported`); None runs the NumPy stepper.

    Returns
    -------
    SolverResult
        ``z, v, a, x`` (n_cases, n_steps + 1, …) from ``t[start]``, ``forces`` ``F_known``
        (the known force, acceleration part included) and ``F_net`` (the network force as
        applied, lagged where the coupling lags) [N, N m]; ``failed`` per case (diverged: NaN
        after the step its divergence was seen), ``nfev`` the network evaluations (each over
        the whole batch), ``counts["iterations"]`` per step.
    """
    if not np.isclose(dt, stepper.dt, rtol=1e-12, atol=0.0):
        raise InputError(f"dt {dt} s differs from the coupled step's {stepper.dt} s")
    s = State(z0, v0, a0, x0, window)
    if layers is None:
        run = _numpy_loop(stepper, s, t, u, eta, start, lead, n_steps, ref_amp, progress)
    else:
        run = _compiled_loop(stepper, layers, s, t, u, eta, start, lead, n_steps, ref_amp)
    zs, vs, as_, xs, blew, n_done, iterations, n_net, f_rec = run
    f_known, f_net = _trajectory_forces(stepper.phys, t, start, u, (zs, vs, as_, xs), f_rec,
                                        compiled=layers is not None)
    n_bad = int(blew.sum())
    message = (f"{n_bad} of {len(blew)} case(s) diverged (|z| above {BLOWUP_FACTOR:g} x the "
               "reference's largest, or not finite)" if n_bad else
               f"{stepper.mode} coupling: {n_done} steps of every case")
    return SolverResult(
        t[start:start + n_steps + 1], zs, vs, a=as_, x=xs,
        forces={"F_known": f_known, "F_net": f_net}, success=not n_bad, message=message,
        method=stepper.mode, nfev=n_net, failed=blew,
        counts={"steps": n_done, "iterations": iterations})


def _numpy_loop(stepper: CoupledStepper, s: State, t, pre, eta, k0: int, lead: int,
                n_steps: int, ref_amp: np.ndarray, progress: bool) -> Loop:
    """The NumPy time loop (NaN after the step where every case had diverged)."""
    phys, (nc, nd) = stepper.phys, s.z.shape
    zs, vs, as_ = (np.empty((nc, n_steps + 1, nd)) for _ in range(3))
    xs = np.empty((nc, n_steps + 1, phys.n_states))
    zs[:, 0], vs[:, 0], as_[:, 0], xs[:, 0] = s.z, s.v, s.a, s.x
    f_rec = np.full((nc, n_steps + 1, nd), np.nan) if phys.stepped else None
    blew, n_done = np.zeros(len(ref_amp), bool), n_steps
    for n in tqdm(range(n_steps + (f_rec is not None)), disable=not progress,
                  desc=f"hybrid {stepper.mode}", unit="step"):
        if f_rec is not None:  # stepped components: advanced, and their force recorded, here
            phys.begin_step(t[k0 + n], s.z, s.v, stepper.dt)
            f_rec[:, n] = phys.force(t[k0 + n], s.z, s.v, s.x)
            if n == n_steps:
                break
        k1 = k0 + n + 1
        s = stepper.step(s, t[k1], pre[:, k1], eta[:, k1 + lead])
        zs[:, n + 1], vs[:, n + 1], as_[:, n + 1], xs[:, n + 1] = s.z, s.v, s.a, s.x
        if n % 50 == 49 or n == n_steps - 1:  # cheap divergence watch
            zmax = np.max(np.abs(zs[:, n - min(n, 49):n + 2]), axis=(1, 2))
            blew |= ~np.isfinite(zmax) | (zmax > BLOWUP_FACTOR * ref_amp)
            if blew.all():  # every case diverged: stop early, pad with NaN
                zs[:, n + 2:], vs[:, n + 2:], as_[:, n + 2:] = np.nan, np.nan, np.nan
                xs[:, n + 2:] = np.nan
                n_done = n + 1
                break
    return (zs, vs, as_, xs, blew, n_done, np.asarray(stepper.iterations), stepper.n_network,
            f_rec)


def _compiled_loop(stepper: CoupledStepper, layers: fast.FoldedLayers, s: State, t, pre, eta,
                   k0: int, lead: int, n_steps: int, ref_amp: np.ndarray) -> Loop:
    """The same step map in one compiled loop (:func:`.fast.run_explicit`)."""
    zs, vs, as_, xs, blew, n_done = fast.run_explicit(
        explicit_problem(stepper), layers, s.z, s.v, s.a, s.x, s.buf, pre, eta, k0, lead,
        n_steps, ref_amp, BLOWUP_FACTOR, t)
    passes = 1 + stepper.corrections
    return zs, vs, as_, xs, blew, n_done, np.full(n_done, passes), passes * n_done, None


def _trajectory_forces(phys: BatchedPhysics, t: np.ndarray, k0: int, pre: np.ndarray,
                       traj: tuple[np.ndarray, ...], f_rec: np.ndarray | None,
                       compiled: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """``F_known`` and ``F_net`` [N, N m] on the trajectory (the start sample included):
    the known force (its acceleration part from z̈) and the network force actually applied
    (lagged: the one evaluated on the step before), from the equation of motion. ``compiled``:
    the :attr:`~BatchedPhysics.other` components by their kernels (as the compiled loop)."""
    zs, vs, as_, xs = traj
    nc, n1, nd = zs.shape
    a_k = phys.m_eff - phys.mass
    fknown, fnet = np.empty((nc, n1, nd)), np.empty((nc, n1, nd))
    if not phys.other or compiled:  # all cases and steps in one evaluation
        rows, shape = nc * n1, (nc, n1, nd)
        acc = as_.reshape(rows, nd)  # views: the trajectories are contiguous
        z_r, v_r = zs.reshape(rows, nd), vs.reshape(rows, nd)
        f_phys = phys.force(t[k0], z_r, v_r, xs.reshape(rows, phys.n_states), other=False)
        if phys.other:  # explicit t dependence: each row at its own time
            f_phys += fast.known_forces(phys.compiled_forces, np.tile(t[k0:k0 + n1], nc),
                                        z_r, v_r)
        f_phys = f_phys.reshape(shape)
        fknown[:] = f_phys - np.dot(acc, a_k.T).reshape(shape)  # np.dot: see force()
        fnet[:] = np.dot(acc, phys.m_eff.T).reshape(shape) - f_phys - pre[:, k0:k0 + n1]
        return fknown, fnet
    for n in range(n1):  # one evaluation per time step (or the force recorded there)
        k1 = k0 + n
        f_phys = (phys.force(t[k1], zs[:, n], vs[:, n], xs[:, n]) if f_rec is None
                  else f_rec[:, n])
        fknown[:, n] = f_phys - as_[:, n] @ a_k.T
        fnet[:, n] = as_[:, n] @ phys.m_eff.T - f_phys - pre[:, k1]
    return fknown, fnet


def explicit_problem(stepper: CoupledStepper) -> fast.ExplicitProblem:
    """The arrays of a lagged/corrected stepper for :func:`.fast.run_explicit`."""
    phys, spec, integ, dt = stepper.phys, stepper.spec, stepper.integrator, stepper.dt
    nd, ns = spec.n_dof, phys.n_states
    p_ss, q_ss, c_out = np.zeros((ns, ns)), np.zeros((ns, nd)), np.zeros((nd, ns))
    for (sl, lhs_inv, rhs, b), (_, _, _, c) in zip(phys.ss_trapezoid(dt), phys.ss):
        # trapezoidal rule solved for x1: x1 = P x + Q (v + v1)
        p_ss[sl, sl], q_ss[sl], c_out[:, sl] = lhs_inv @ rhs, 0.5 * dt * lhs_inv @ b, c
    pos = np.full((3, nd), -1, dtype=np.int64)
    for i, name in enumerate(("z", "zdot", "zddot")):
        if name in spec.inputs:
            pos[i] = [spec.channels.index((name, k)) for k in range(nd)]
    eta_pos = np.array([spec.channels.index(("eta", k)) for k in range(spec.n_probe)]
                       if stepper._has_eta else [], dtype=np.int64)
    if phys.compiled_forces is None:
        raise InputError("the compiled rollout loop needs a Numba kernel of every nonlinear "
                         "known component: " + ", ".join(c.describe() for _, c in phys.other))
    return fast.ExplicitProblem(
        scheme=0 if stepper.scheme == "newmark" else 1, lhs_inv=integ._lhs_inv,
        damping=np.ascontiguousarray(phys.b_lin), stiffness=np.ascontiguousarray(phys.c_lin),
        # LaggedIntegrator's factorised solve and step coefficients (one definition of the step)
        coef=np.array([dt] + [getattr(integ, k, 0.0) for k in ("_c_v", "_c_z", "_c_z1", "_c_v1")]),
        quad=np.ascontiguousarray(phys.quad),
        p_ss=p_ss, q_ss=q_ss, c_out=c_out, chan_pos=pos, eta_pos=eta_pos, window=spec.window,
        stride=spec.stride, corrections=stepper.corrections,
        forces=tuple(phys.compiled_forces))

