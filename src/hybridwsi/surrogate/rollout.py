"""Hybrid rollout: the Cummins-type ODE with the force network in the loop.

For each case (a batch, evaluated in one torch call per network evaluation)::

    (m + A_k) z̈ = Σ_known F_i(t, z, ż, x) + F_prescribed(t) + F_net(features),

where the known components (hydrostatics, damping, radiation memory states ``x``...) are
:class:`~hybridwsi.forces.KnownComponent` objects, ``A_k`` their
acceleration-proportional part moved to the left-hand side, and ``F_net`` the network.

Time stepping: Newmark average acceleration (trapezoidal in z, ż, and in the internal states
``x``), with the new acceleration found by fixed-point iteration with Aitken relaxation.

- ``mode="lagged"`` (loosely coupled): the network sees the kinematics of the previous step,
  ``F_net^{n+1} = N(x^n)``; only the known physics is iterated. The one-step delay of the
  network force is a first-order error (for a radiation-memory network ~10 % of rms z at
  dt = 0.02 s on the sphere demo, whatever the network's accuracy).
- ``mode="corrected"`` (loosely coupled with ``corrections`` predictor-corrector passes): the
  lagged step predicts the end-of-step state, the network (and the known explicit forces)
  are evaluated again on it and the step is redone, a fixed number of times. Second order
  like Newmark; each pass multiplies the inertia coupling error by ``alpha_s/(m + A_k)``, so
  the added-mass threshold ``|alpha_s| < m + A_k`` is that of the lagged mode, and an even
  number of passes keeps the remaining lag dissipative (:func:`corrections_for`).
- ``mode="implicit"``: the network sees the current step, ``F_net^{n+1} = N(x^{n+1})``, and
  is re-evaluated inside the fixed point (it converges only while ``|alpha_s| < m + A_k``).

``lagged`` and ``corrected`` rollouts with the usual known components run in one compiled loop
(:mod:`hybridwsi.surrogate.fast`, when Numba is installed; ``compiled=False`` forces the NumPy
stepper, which the stability map always uses).

Before rolling out, :func:`check_stability` linearises the network (autograd) and computes the
spectral radius of the *same* step map with the network replaced by its Jacobian (all feature
lags included), and docs/THEORY.md §4b-c verdicts from :mod:`hybridwsi.diagnostic.stability`.
A partition predicted unstable raises :class:`UnstablePartitionError` unless ``force=True``
(then it only warns).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.forces import (
    AddedMass,
    Hydrostatic,
    KnownComponent,
    LinearDamping,
    QuadraticDamping,
    as_matrix,
    summed_linear_coefficients,
)
from hybridwsi.diagnostic import stability
from hybridwsi.diagnostic.integrators import LaggedIntegrator, check_scheme
from hybridwsi.errors import InputError, SolverError
from hybridwsi.history import make_history, time_step
from hybridwsi.surrogate import fast
from hybridwsi.surrogate.fast import folded_layers, numpy_forward
from hybridwsi.surrogate.features import channel_array
from hybridwsi.surrogate.linearise import feature_jacobian, linearise
from hybridwsi.surrogate.network import ForceNetwork, torch

MODES = ("lagged", "corrected", "implicit")
#: network evaluations of at most this many cases run in NumPy (per-call torch overhead)
_NUMPY_MAX_BATCH = 8
#: |z| beyond this many times the reference amplitude (or non-finite) counts as blown up
BLOWUP_FACTOR = 20.0
#: rms of the second difference of z̈ above this fraction of the reference rms z̈ is the
#: saw-tooth (period 2Δt) mode of an unstable lagged coupling, bounded only by the saturating
#: network; a resolved smooth signal has (ωΔt)² << 1 of it
SAWTOOTH_RATIO = 1.0


class UnstablePartitionError(SolverError):
    """The hybrid scheme is predicted unstable for this partition (pass force=True to run).

    ``reason`` is the prediction alone, for callers that name their own override (the CLI's
    ``--allow-unstable``).
    """

    def __init__(self, reason: str) -> None:
        super().__init__(f"{reason} (pass force=True to run anyway)")
        self.reason = reason


# ---------------------------------------------------------------------- batched physics
class BatchedPhysics:
    """Known components evaluated for a batch of cases, states ``(n_cases, n)`` arrays.

    Linear terms, quadratic damping and radiation memory are vectorised; any other
    component falls back to a loop over cases through its ``ode_force``/``state_derivative``.
    """

    def __init__(self, mass: np.ndarray, known: Sequence[KnownComponent], n_dof: int) -> None:
        self.n_dof = n_dof
        self.known = list(known)
        a_k, _, _ = summed_linear_coefficients(self.known, n_dof)
        self.m_eff = as_matrix(mass, n_dof, "mass") + a_k
        try:
            self.m_inv = np.linalg.inv(self.m_eff)
        except np.linalg.LinAlgError:
            raise InputError("m + A_k is singular; check the mass and added mass") from None
        self.b_lin = np.zeros((n_dof, n_dof))
        self.c_lin = np.zeros((n_dof, n_dof))
        self.quad = np.zeros(n_dof)
        self.ss: list[tuple[slice, np.ndarray, np.ndarray, np.ndarray]] = []
        self.other: list[tuple[slice, KnownComponent]] = []
        n = 0
        for comp in self.known:
            if comp.time_only:
                continue  # a time series: added by the rollout as a prescribed force
            if isinstance(comp, (Hydrostatic, LinearDamping, AddedMass)):
                _, b, c = comp.linear_coefficients(n_dof)
                self.b_lin += b
                self.c_lin += c
            elif type(comp) is QuadraticDamping:
                self.quad += np.diag(as_matrix(comp.value, n_dof, comp.name))
            elif hasattr(comp, "ss") and comp.n_states:  # forces.RadiationMemory
                sl = slice(n, n + comp.n_states)
                self.ss.append((sl, comp.ss.A, comp.ss.B, comp.ss.C))
                n += comp.n_states
            else:
                self.other.append((slice(n, n + comp.n_states), comp))
                n += comp.n_states
        self.n_states = n
        self._quad = bool(np.any(self.quad))
        self.other_states = any(comp.n_states for _, comp in self.other)
        self._trap: dict[float, list] = {}

    def ss_trapezoid(self, dt: float) -> list:
        """Per state-space block ``(slice, (I - dt/2 A)^-1, I + dt/2 A, B)`` (cached per dt)."""
        if dt not in self._trap:
            blocks = []
            for sl, a, b, _ in self.ss:
                eye = np.eye(a.shape[0])
                blocks.append((sl, np.linalg.inv(eye - 0.5 * dt * a), eye + 0.5 * dt * a, b))
            self._trap[dt] = blocks
        return self._trap[dt]

    @property
    def has_remainder(self) -> bool:
        """Whether any known force is not linear ``-B_k v - C_k z`` (quadratic damping,
        memory states, other components)."""
        return bool(self._quad or self.ss or self.other)

    def _add_remainder(self, f: np.ndarray, t: float, z: np.ndarray, v: np.ndarray,
                       x: np.ndarray) -> np.ndarray:
        """``f`` plus the known forces beyond the linear part [N], (n_cases, n_dof)."""
        if self._quad:  # an all-zero coefficient adds exactly nothing
            f = f - self.quad * np.abs(v) * v
        for sl, _, _, c in self.ss:
            f -= np.dot(x[:, sl], c.T)
        for sl, comp in self.other:
            f += np.stack([comp.ode_force(t, z[i], v[i], x[i, sl]) for i in range(len(z))])
        return f

    def force(self, t: float, z: np.ndarray, v: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Known force without its acceleration part [N], (n_cases, n_dof).

        Row-wise: with no ``other`` components (``t`` unused) the rows may stack any batch of
        states, e.g. all time steps of a trajectory at once.
        """
        # np.dot, not @: on tall (rows, n_dof) operands ``@`` runs a non-BLAS loop, ~15x
        # slower for one dof (the whole trajectory goes through here after a rollout)
        return self._add_remainder(-np.dot(v, self.b_lin.T) - np.dot(z, self.c_lin.T), t, z, v,
                                   x)

    def explicit_force(self, t: float, z: np.ndarray, v: np.ndarray, x: np.ndarray) -> np.ndarray:
        """The known force minus its linear ``-B_k v - C_k z`` part [N] (treated explicitly),
        computed directly (zero when :attr:`has_remainder` is False)."""
        return self._add_remainder(np.zeros(np.shape(z)), t, z, v, x)

    def state_derivative(self, t: float, z: np.ndarray, v: np.ndarray, x: np.ndarray) -> np.ndarray:
        dx = np.zeros_like(x)
        for sl, a, b, _ in self.ss:
            dx[:, sl] = x[:, sl] @ a.T + v @ b.T
        for sl, comp in self.other:
            if comp.n_states:
                dx[:, sl] = np.stack([comp.state_derivative(t, z[i], v[i], x[i, sl])
                                      for i in range(len(z))])
        return dx

    def linearised(self) -> BatchedPhysics:
        """The same physics with nonlinear memoryless components replaced by their
        ``linear_coefficients`` (used for the stability prediction)."""
        known = []
        for comp in self.known:
            if comp.time_only:
                continue
            if isinstance(comp, (Hydrostatic, LinearDamping, AddedMass)) or (
                    hasattr(comp, "ss") and comp.n_states):
                known.append(comp)
            else:
                _, b, c = comp.linear_coefficients(self.n_dof)
                known += [LinearDamping(b), Hydrostatic(c)]
        return BatchedPhysics(self.m_eff - summed_linear_coefficients(known, self.n_dof)[0],
                              known, self.n_dof)


# ------------------------------------------------------------------------------- stepper
@dataclass
class _State:
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


class _Stepper:
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
        # lagged mode: the implicit solve of lagged_step factorised once for the whole run
        self.integrator = LaggedIntegrator(self.scheme, self.dt, phys.m_eff, phys.b_lin,
                                           phys.c_lin) if mode != "implicit" else None
        self._remainder = phys.has_remainder
        self._has_eta = "eta" in spec.inputs and spec.n_probe > 0

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

    def _states(self, s: _State, t0: float, v1: np.ndarray, z1: np.ndarray,
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

    def step(self, s: _State, t1: float, f_pre: np.ndarray, eta1: np.ndarray) -> _State:
        if self.mode == "implicit":
            return self._implicit(s, t1, f_pre, eta1)
        return self._lagged(s, t1, f_pre, eta1)

    def _lagged(self, s: _State, t1: float, f_pre: np.ndarray, eta1: np.ndarray) -> _State:
        phys, t0 = self.phys, t1 - self.dt
        g0 = phys.state_derivative(t0, s.z, s.v, s.x) if phys.n_states else None
        # explicit part on the start-of-step state; the prescribed force is a known function
        # of time, so it is taken at the end of the step (no coupling lag to analyse)
        t_x, z_x, v_x, x_x, buf = t0, s.z, s.v, s.x, s.buf
        for _ in range(1 + self.corrections):
            f_x = self.net_force(self.feat(buf)) + f_pre
            if self._remainder:  # otherwise exactly zero
                f_x = f_x + phys.explicit_force(t_x, z_x, v_x, x_x)
            z1, v1, a1 = self.integrator.step(s.z.T, s.v.T, s.a.T, f_x.T)
            z1, v1, a1 = z1.T, v1.T, a1.T
            x1 = self._states(s, t0, v1, z1, g0)
            buf = self.shifted(s.buf, self.row(z1, v1, a1, eta1))
            # corrected: the explicit forces again, on the predicted end-of-step state
            t_x, z_x, v_x, x_x = t1, z1, v1, x1
        self.iterations.append(1 + self.corrections)
        return _State(z1, v1, a1, x1, buf)

    def _implicit(self, s: _State, t1: float, f_pre: np.ndarray, eta1: np.ndarray) -> _State:
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
            f_net = self.net_force(self.feat(buf1))
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
        return _State(z1, v1, a, x1, self.shifted(s.buf, self.row(z1, v1, a, eta1)))


def _torch_force(net: ForceNetwork) -> ForceFn:
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


# ------------------------------------------------------------------- stability prediction
@dataclass
class StabilityPrediction:
    """Predicted stability of a hybrid rollout.

    Attributes
    ----------
    spectral_radius : float
        Of the linearised one-step map (network replaced by its averaged feature Jacobian,
        all lags included) of the very scheme the rollout uses.
    stable : bool
        ``spectral_radius <= 1 + tol`` (and, for ``implicit``, a contracting fixed point).
    alpha_s, beta_s, gamma_s : ndarray
        Averaged lag-0 sensitivities of the network (docs/THEORY.md §4b).
    added_mass_ratio : float
        ``max |eig((m + A_k)^{-1} alpha_s)|``: >= 1 is the loosely coupled added-mass
        instability (docs/THEORY.md §4c), and for ``implicit`` the fixed point diverges.
    continuous_stable : bool
        Setting (b) of :func:`hybridwsi.diagnostic.stability.surrogate_stability` (the one
        continuous test: generalised eigenvalues of ``(m + A_k − α_s, B_k − β_s, C_k − γ_s)``).
    theory : dict
        Reports (b) ``surrogate`` and (c) ``loosely_coupled`` of
        :mod:`hybridwsi.diagnostic.stability` as dicts.
    """

    mode: str
    dt: float
    spectral_radius: float
    stable: bool
    alpha_s: np.ndarray
    beta_s: np.ndarray
    gamma_s: np.ndarray
    added_mass_ratio: float
    continuous_stable: bool
    theory: dict = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"mode": self.mode, "dt": self.dt, "spectral_radius": self.spectral_radius,
                "stable": bool(self.stable), "alpha_s": self.alpha_s.tolist(),
                "beta_s": self.beta_s.tolist(), "gamma_s": self.gamma_s.tolist(),
                "added_mass_ratio": self.added_mass_ratio,
                "continuous_stable": bool(self.continuous_stable), "theory": self.theory}


def _linear_map(phys: BatchedPhysics, spec, dt: float, mode: str, jac: np.ndarray,
                scheme: str = "newmark", corrections: int = 1) -> np.ndarray:
    """Matrix of the one-step map on (z, v, a, x, buffer lags 0..w-2) for a linear network
    ``F = jac @ features`` (eta channels carry no state: they are inputs)."""
    nd, ns, w, nch = spec.n_dof, phys.n_states, spec.span, spec.n_channels
    n_buf = (w - 1) * nch
    dim = 3 * nd + ns + n_buf
    stepper = _Stepper(phys, spec, dt, mode, lambda x: x @ jac.T, scheme, max_iter=200,
                       tol=1e-13, corrections=corrections)

    def unpack(vec: np.ndarray) -> _State:
        z, v, a = vec[:, :nd], vec[:, nd:2 * nd], vec[:, 2 * nd:3 * nd]
        x = vec[:, 3 * nd:3 * nd + ns]
        rest = vec[:, 3 * nd + ns:].reshape(len(vec), w - 1, nch)
        buf = np.concatenate([stepper.row(z, v, a, 0.0)[:, None, :], rest], axis=1)
        return _State(z, v, a, x, buf)

    def pack(s: _State) -> np.ndarray:
        return np.concatenate([s.z, s.v, s.a, s.x, s.buf[:, :-1].reshape(len(s.z), -1)], axis=1)

    basis = np.eye(dim)  # all basis vectors as one batch: the map is linear
    out = pack(stepper.step(unpack(basis), dt, np.zeros((dim, nd)), np.zeros((dim, spec.n_probe))))
    return out.T


def check_stability(
    net: ForceNetwork,
    reference: xr.Dataset | Sequence[xr.Dataset],
    *,
    mass: float | np.ndarray,
    known: Sequence[KnownComponent],
    dt: float | None = None,
    mode: str = "lagged",
    scheme: str = "newmark",
    tol: float = 1e-6,
    stride: int = 5,
    corrections: int = 1,
) -> StabilityPrediction:
    """Predict whether the hybrid rollout is stable, from the network's linearisation.

    Parameters
    ----------
    net : ForceNetwork
        Fitted network of the partition's residual force.
    reference : TimeHistory or list
        States at which the network is linearised (averaged Jacobian), e.g. training data.
    mass : float or array
        Rigid-body mass [kg].
    known : sequence of KnownComponent
        The partition's known components.
    dt : float, optional
        Time step [s] (default: the reference's).
    mode : {"lagged", "corrected", "implicit"}
    scheme : {"newmark", "semi_implicit_euler"}
        Integrator of the lagged mode (:mod:`hybridwsi.diagnostic.integrators`).
    tol : float
        Margin on the spectral radius.
    stride : int
        Every ``stride``-th reference sample is a linearisation state.
    corrections : int
        Predictor-corrector passes of the ``corrected`` mode.
    """
    refs = [reference] if isinstance(reference, xr.Dataset) else list(reference)
    dt = float(dt if dt is not None else time_step(refs[0]))
    nd = net.n_dof_
    phys = BatchedPhysics(mass, known, nd)
    lin_phys = phys.linearised()
    from hybridwsi.surrogate.features import build_features

    x = np.concatenate([build_features(h, net.spec_)[::max(1, stride)] for h in refs])
    jac = feature_jacobian(net, x).mean(0)
    step_map = _linear_map(lin_phys, net.spec_, dt, mode, jac, scheme, corrections)
    rho = float(np.max(np.abs(np.linalg.eigvals(step_map))))
    lin = linearise(net, refs[0], stride=stride)
    if len(refs) > 1:
        lins = [linearise(net, h, stride=stride) for h in refs]
        lin.alpha, lin.beta, lin.gamma = (np.mean([getattr(s, k) for s in lins], 0)
                                          for k in ("alpha", "beta", "gamma"))
    a_k, b_k, c_k = summed_linear_coefficients(list(known), nd)
    m = as_matrix(mass, nd, "mass")
    ratio = stability.added_mass_ratio(m, a_k, lin.alpha)
    stable = rho <= 1.0 + tol and (mode != "implicit" or ratio < 1.0)
    # docs/THEORY.md §4b-c for the network's lag-0 sensitivities: (b) is the continuous test
    cont = stability.surrogate_stability(m, a_k, b_k, c_k, lin.alpha, lin.beta, lin.gamma)
    lagged = stability.loosely_coupled_stability(m, a_k, b_k, c_k, lin.alpha, lin.beta,
                                                 lin.gamma, dt, scheme)
    theory = {"surrogate": cont.to_dict(), "loosely_coupled": lagged.to_dict()}
    return StabilityPrediction(mode, dt, rho, bool(stable), lin.alpha, lin.beta, lin.gamma,
                               ratio, cont.stable, theory)


# ---------------------------------------------------------------------------------- rollout
@dataclass
class RolloutResult:
    """Hybrid trajectories of a batch of cases.

    Attributes
    ----------
    histories : list of TimeHistory
        One per case, with ``F_net`` (network force) and ``F_known`` (known force) [N].
    blew_up : ndarray of bool
        Per case: observed unstable, i.e. non-finite state, |z| > BLOWUP_FACTOR x reference
        max |z|, or a saw-tooth acceleration (``sawtooth > SAWTOOTH_RATIO``).
    sawtooth : ndarray
        Per case: rms(second difference of z̈) / rms(reference z̈).
    prediction : StabilityPrediction or None
    iterations : ndarray
        Fixed-point iterations per step.
    """

    histories: list[xr.Dataset]
    blew_up: np.ndarray
    prediction: StabilityPrediction | None
    iterations: np.ndarray
    sawtooth: np.ndarray | None = None

    def errors(self, references: Sequence[xr.Dataset], var: str = "z") -> np.ndarray:
        """Normalised RMS error per case, ``rms(hybrid - ref) / rms(ref)`` of ``var``."""
        out = []
        for h, r in zip(self.histories, references):
            hyb = np.asarray(h[var].values, float)
            ref = np.asarray(r[var].sel(time=h["time"], method="nearest").values, float)
            if not np.all(np.isfinite(hyb)):
                out.append(np.inf)  # diverged
                continue
            out.append(float(np.sqrt(np.mean((hyb - ref) ** 2)) / max(np.sqrt(np.mean(ref ** 2)), 1e-300)))
        return np.asarray(out)


def _case_arrays(hs: list[xr.Dataset], spec, prescribed, known):
    n_t = {h.sizes["time"] for h in hs}
    if len(n_t) != 1:
        raise InputError("all cases of a batched rollout need the same number of time samples")
    nd = spec.n_dof
    eta = (np.stack([np.asarray(h["eta"].values, float).reshape(h.sizes["time"], -1) for h in hs])
           if "eta" in spec.inputs else np.zeros((len(hs), hs[0].sizes["time"], 0)))
    if prescribed is None:
        pre = np.zeros((len(hs), hs[0].sizes["time"], nd))
    elif isinstance(prescribed, str):
        if any(prescribed not in h for h in hs):
            raise InputError(f"prescribed force '{prescribed}' missing from a case history")
        pre = np.stack([np.asarray(h[prescribed].values, float) for h in hs])
    else:
        pre = np.asarray(prescribed, float).reshape(len(hs), hs[0].sizes["time"], nd)
    for comp in known:
        if comp.time_only:
            pre = pre + np.stack([comp.force(h) for h in hs])
    return eta, pre


def rollout(
    net: ForceNetwork,
    cases: xr.Dataset | Sequence[xr.Dataset],
    *,
    mass: float | np.ndarray,
    known: Sequence[KnownComponent],
    mode: str = "lagged",
    scheme: str = "newmark",
    prescribed: str | np.ndarray | None = None,
    n_steps: int | None = None,
    check: bool = True,
    force: bool = False,
    reference_for_check: xr.Dataset | Sequence[xr.Dataset] | None = None,
    max_iter: int = 50,
    tol: float = 1e-9,
    corrections: int = 1,
    compiled: bool | None = None,
    progress: bool = False,
) -> RolloutResult:
    """Integrate the hybrid model for a batch of cases.

    Each case history supplies the time grid (uniform, same length for all cases), the wave
    elevation ``eta`` when the network uses it, the initial conditions (its first ``window``
    samples fill the network's input window) and optionally a prescribed force.

    Parameters
    ----------
    net : ForceNetwork
        Fitted residual-force network.
    cases : TimeHistory or list of TimeHistory
        Case definitions / references.
    mass : float or array
        Rigid-body mass [kg].
    known : sequence of KnownComponent
        Known components in the ODE (hydrostatics, A∞, radiation memory ...).
    mode : {"lagged", "corrected", "implicit"}
        Network sees the previous step (loosely coupled), the predicted end of the step
        (``corrections`` times), or the current step (fixed point).
    scheme : {"newmark", "semi_implicit_euler"}
        Lagged-mode integrator (:func:`hybridwsi.diagnostic.integrators.lagged_step`).
    prescribed : str or array, optional
        A force [N] given as a function of time (e.g. ``"F_exc"``), read from the cases.
    n_steps : int, optional
        Steps to integrate (default: to the end of the case histories).
    check, force : bool
        Run :func:`check_stability` first; a predicted-unstable partition raises
        :class:`UnstablePartitionError` unless ``force`` (then a RuntimeWarning).
    reference_for_check : histories, optional
        States for the linearisation (default: the cases).
    max_iter, tol : int, float
        Fixed-point settings per step.
    corrections : int
        Predictor-corrector passes per step of the ``corrected`` mode (see
        :func:`corrections_for`).
    compiled : bool, optional
        Run ``lagged``/``corrected`` in the compiled loop of :mod:`hybridwsi.surrogate.fast`
        (default: whenever it supports the case; there a diverged case is NaN after the step
        its divergence was seen). False forces the NumPy stepper.
    progress : bool
        tqdm progress bar over steps (NumPy stepper only).
    """
    net._check_fitted()
    hs = [cases] if isinstance(cases, xr.Dataset) else list(cases)
    spec, nd, w, lead = net.spec_, net.n_dof_, net.spec_.span, net.spec_.lead
    dt = time_step(hs[0])
    eta, pre = _case_arrays(hs, spec, prescribed, known)
    n_total = hs[0].sizes["time"]
    n_max = n_total - w - lead
    n_steps = n_max if n_steps is None else min(int(n_steps), n_max)
    if n_steps < 1:
        raise InputError(f"cases have {n_total} samples; the network window needs more than {w}")
    prediction = None
    if check:
        prediction = check_stability(net, hs if reference_for_check is None else reference_for_check,
                                     mass=mass, known=known, dt=dt, mode=mode, scheme=scheme, corrections=corrections)
        if not prediction.stable:
            msg = (f"hybrid {mode} rollout predicted unstable: spectral radius "
                   f"{prediction.spectral_radius:.4f} > 1, |alpha_s|/(m+A_k) = "
                   f"{prediction.added_mass_ratio:.3f}")
            if not force:
                raise UnstablePartitionError(msg)
            warnings.warn("UNSTABLE PARTITION: " + msg, RuntimeWarning, stacklevel=2)
    phys = BatchedPhysics(mass, known, nd)
    stepper = _Stepper(phys, spec, dt, mode, _torch_force(net), scheme, max_iter, tol,
                       corrections)
    # initial window from the case histories (lag 0 = sample span-1)
    chans = np.stack([channel_array(h, spec) for h in hs])  # (nc, nt, nch)
    k0 = w - 1
    kin = {k: np.stack([np.asarray(h[k].values, float) for h in hs]) for k in ("z", "zdot", "zddot")}
    x0 = np.zeros((len(hs), phys.n_states))
    if phys.n_states:  # memory states consistent with the reference's past
        x0 = _initial_states(phys, known, hs, k0)
    s = _State(kin["z"][:, k0], kin["zdot"][:, k0], kin["zddot"][:, k0], x0,
               chans[:, k0::-1][:, :w] if k0 > 0 else chans[:, :1])
    t = np.asarray(hs[0]["time"].values, float)
    nc = len(hs)
    zs, vs, as_ = (np.empty((nc, n_steps + 1, nd)) for _ in range(3))
    fnet, fknown = np.empty((nc, n_steps + 1, nd)), np.empty((nc, n_steps + 1, nd))
    zs[:, 0], vs[:, 0], as_[:, 0] = s.z, s.v, s.a
    a_k = phys.m_eff - as_matrix(mass, nd, "mass")
    ref_amp = np.maximum(np.max(np.abs(kin["z"]), axis=(1, 2)), 1e-12)
    xs = np.empty((nc, n_steps + 1, phys.n_states))
    xs[:, 0] = s.x
    use_compiled = fast.supported(net.activation, phys.other, mode, scheme) if compiled is None \
        else bool(compiled)
    if use_compiled:  # the same step map in one compiled loop
        zs, vs, as_, xs, blew, n_done = fast.run_explicit(
            _explicit_problem(stepper), folded_layers(net), s.z, s.v, s.a, s.x, s.buf, pre, eta,
            k0, lead, n_steps, ref_amp, BLOWUP_FACTOR)
        iterations = np.full(n_done, 1 + stepper.corrections)
    else:
        blew, n_done = _step_loop(stepper, s, t, pre, eta, k0, lead, n_steps, ref_amp,
                                  (zs, vs, as_, xs), progress)
        iterations = np.asarray(stepper.iterations)
    # forces on the trajectory (the start sample included), after the loop
    if not phys.other:  # no explicit t dependence: all cases and steps in one evaluation
        rows, shape = nc * (n_steps + 1), (nc, n_steps + 1, nd)
        acc = as_.reshape(rows, nd)  # views: the trajectories are contiguous
        f_phys = phys.force(t[k0], zs.reshape(rows, nd), vs.reshape(rows, nd),
                            xs.reshape(rows, phys.n_states)).reshape(shape)
        fknown[:] = f_phys - np.dot(acc, a_k.T).reshape(shape)  # np.dot: see force()
        # the network force actually applied (lagged: the one evaluated on the step before)
        fnet[:] = np.dot(acc, phys.m_eff.T).reshape(shape) - f_phys - pre[:, k0:k0 + n_steps + 1]
    for n in range(n_steps + 1) if phys.other else ():  # one evaluation per time step
        k1 = k0 + n
        f_phys = phys.force(t[k1], zs[:, n], vs[:, n], xs[:, n])
        fknown[:, n] = f_phys - as_[:, n] @ a_k.T
        fnet[:, n] = as_[:, n] @ phys.m_eff.T - f_phys - pre[:, k1]
    a_ref = kin["zddot"][:, k0:k0 + n_steps + 1]
    d2 = np.diff(as_, 2, axis=1)
    with np.errstate(invalid="ignore", over="ignore"):
        if d2.size and np.isfinite(d2).all():  # the usual case: one pass, no NaN masks
            ms = np.einsum("ijk,ijk->i", d2, d2) / (d2.shape[1] * d2.shape[2])
        else:
            ms = np.nanmean(d2 ** 2, axis=(1, 2))
        saw = np.sqrt(ms) / np.maximum(np.sqrt(np.mean(a_ref ** 2, axis=(1, 2))), 1e-300)
    saw = np.where(np.isfinite(saw), saw, np.inf)
    blew |= saw > SAWTOOTH_RATIO
    out = []
    tt = t[k0:k0 + n_steps + 1]
    # the same for every case: described once (describe() formats matrices, ~0.1 ms each)
    described, spec_dict = [c.describe() for c in known], net.spec_.to_dict()
    for i in range(nc):
        forces = {"F_known": fknown[i], "F_net": fnet[i]}
        out.append(make_history(tt, zs[i], vs[i], as_[i], forces=forces, dof=list(hs[i]["dof"].values),
                                mass=mass, source=f"hybridwsi.surrogate.rollout ({mode})",
                                inputs={"mode": mode, "dt": dt, "n_steps": n_done,
                                        "known": list(described), "network": dict(spec_dict)},
                                check=False))
    return RolloutResult(out, blew, prediction, iterations, saw)


def _step_loop(stepper: _Stepper, s: _State, t, pre, eta, k0: int, lead: int, n_steps: int,
               ref_amp: np.ndarray, out: tuple, progress: bool) -> tuple[np.ndarray, int]:
    """The NumPy time loop: fills ``out = (zs, vs, as_, xs)`` in place; returns the per-case
    divergence flags and the number of steps done (NaN after when every case diverged)."""
    from tqdm.auto import tqdm

    zs, vs, as_, xs = out
    blew = np.zeros(len(ref_amp), bool)
    for n in tqdm(range(n_steps), disable=not progress, desc=f"hybrid {stepper.mode}",
                  unit="step"):
        k1 = k0 + n + 1
        s = stepper.step(s, t[k1], pre[:, k1], eta[:, k1 + lead])
        zs[:, n + 1], vs[:, n + 1], as_[:, n + 1], xs[:, n + 1] = s.z, s.v, s.a, s.x
        if n % 50 == 49 or n == n_steps - 1:  # cheap divergence watch
            zmax = np.max(np.abs(zs[:, n - min(n, 49):n + 2]), axis=(1, 2))
            blew |= ~np.isfinite(zmax) | (zmax > BLOWUP_FACTOR * ref_amp)
            if blew.all():  # every case diverged: stop early, pad with NaN
                zs[:, n + 2:], vs[:, n + 2:], as_[:, n + 2:] = np.nan, np.nan, np.nan
                xs[:, n + 2:] = np.nan
                return blew, n + 1
    return blew, n_steps


def _explicit_problem(stepper: _Stepper) -> fast.ExplicitProblem:
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
    return fast.ExplicitProblem(
        scheme=0 if stepper.scheme == "newmark" else 1, lhs_inv=integ._lhs_inv,
        damping=np.ascontiguousarray(phys.b_lin), stiffness=np.ascontiguousarray(phys.c_lin),
        # LaggedIntegrator's factorised solve and step coefficients (one definition of the step)
        coef=np.array([dt] + [getattr(integ, k, 0.0) for k in ("_c_v", "_c_z", "_c_z1", "_c_v1")]),
        quad=np.ascontiguousarray(phys.quad),
        p_ss=p_ss, q_ss=q_ss, c_out=c_out, chan_pos=pos, eta_pos=eta_pos, window=spec.window,
        stride=spec.stride, corrections=stepper.corrections)


def _initial_states(phys: BatchedPhysics, known, hs, k0: int) -> np.ndarray:
    """Internal states at sample ``k0``: integrate the state ODE along the reference ż."""
    x = np.zeros((len(hs), phys.n_states))
    if k0 == 0:
        return x
    dt = time_step(hs[0])
    z = np.stack([np.asarray(h["z"].values, float) for h in hs])
    v = np.stack([np.asarray(h["zdot"].values, float) for h in hs])
    t = np.asarray(hs[0]["time"].values, float)
    for k in range(k0):  # Heun: only a short warm-up window
        g0 = phys.state_derivative(t[k], z[:, k], v[:, k], x)
        xp = x + dt * g0
        x = x + 0.5 * dt * (g0 + phys.state_derivative(t[k + 1], z[:, k + 1], v[:, k + 1], xp))
    return x
