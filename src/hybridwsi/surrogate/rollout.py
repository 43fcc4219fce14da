"""Hybrid rollout: the Cummins-type ODE with the force network in the loop.

For each case (a batch, evaluated in one torch call per network evaluation)::

    (m + A_k) z̈ = Σ_known F_i(t, z, ż, x) + F_prescribed(t) + F_net(features),

where the known components (hydrostatics, damping, radiation memory states ``x``...) are
:class:`~hybridwsi.forces.KnownComponent` objects (:mod:`hybridwsi.surrogate.physics`), ``A_k``
their acceleration-proportional part moved to the left-hand side, and ``F_net`` the network.

Time stepping (:mod:`hybridwsi.surrogate.coupled`, under the solver contract of
:mod:`hybridwsi.cummins.result`): Newmark average acceleration (trapezoidal in z, ż, and in
the internal states ``x``), with the new acceleration found by fixed-point iteration with
Aitken relaxation.

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

``lagged`` and ``corrected`` rollouts run in one compiled loop (:mod:`hybridwsi.surrogate.fast`,
when Numba is installed) when every nonlinear known component has a Numba kernel (the
tabulated mooring, the operating rotor, Morison drag...; a component with internal states or
``begin_step`` keeps the NumPy stepper); ``compiled=False`` forces the NumPy stepper, which the
stability map always uses.

Before rolling out, :func:`check_stability` linearises the network (autograd) and computes the
spectral radius of the *same* step map with the network replaced by its Jacobian (all feature
lags included), and docs/THEORY.md §4b-c verdicts from :mod:`hybridwsi.diagnostic.stability`.
A partition predicted unstable raises :class:`UnstablePartitionError` unless ``force=True``
(then it only warns).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.cummins.result import SolverResult
from hybridwsi.diagnostic import stability
from hybridwsi.errors import InputError, SolverError
from hybridwsi.forces import KnownComponent
from hybridwsi.history import make_history, time_step
from hybridwsi.surrogate import fast
from hybridwsi.surrogate.coupled import (
    BLOWUP_FACTOR,
    MODES,
    CoupledStepper,
    State,
    corrections_for,
    network_force,
    solve_coupled,
)
from hybridwsi.surrogate.fast import folded_layers
from hybridwsi.surrogate.features import build_features, channel_array
from hybridwsi.surrogate.linearise import feature_jacobian, linearise
from hybridwsi.surrogate.network import ForceNetwork
from hybridwsi.surrogate.physics import BatchedPhysics, initial_states

__all__ = ["BLOWUP_FACTOR", "MODES", "SAWTOOTH_RATIO", "RolloutResult", "UnstablePartitionError",
           "check_stability", "corrections_for", "rollout"]

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


# ------------------------------------------------------------------- stability prediction
def _linear_map(phys: BatchedPhysics, spec, dt: float, mode: str, jac: np.ndarray,
                scheme: str = "newmark", corrections: int = 1) -> np.ndarray:
    """Matrix of the one-step map on (z, v, a, x, buffer lags 0..w-2) for a linear network
    ``F = jac @ features`` (eta channels carry no state: they are inputs)."""
    nd, ns, w, nch = spec.n_dof, phys.n_states, spec.span, spec.n_channels
    n_buf = (w - 1) * nch
    dim = 3 * nd + ns + n_buf
    stepper = CoupledStepper(phys, spec, dt, mode, lambda x: x @ jac.T, scheme, max_iter=200,
                       tol=1e-13, corrections=corrections)

    def unpack(vec: np.ndarray) -> State:
        z, v, a = vec[:, :nd], vec[:, nd:2 * nd], vec[:, 2 * nd:3 * nd]
        x = vec[:, 3 * nd:3 * nd + ns]
        rest = vec[:, 3 * nd + ns:].reshape(len(vec), w - 1, nch)
        buf = np.concatenate([stepper.row(z, v, a, 0.0)[:, None, :], rest], axis=1)
        return State(z, v, a, x, buf)

    def pack(s: State) -> np.ndarray:  # lag 0 is (z, v, a): the carried lags are 1 … w−1
        return np.concatenate([s.z, s.v, s.a, s.x, s.buf[:, 1:].reshape(len(s.z), -1)], axis=1)

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
) -> stability.StabilityReport:
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

    Returns
    -------
    StabilityReport
        ``spectral_radius`` of the rollout's one-step map with the network replaced by its
        averaged feature Jacobian (all lags), ``stable`` (≤ 1 + ``tol``, and for ``implicit``
        a contracting fixed point), ``added_mass_ratio``, the network's averaged lag-0
        sensitivities in ``step.alpha, beta, gamma``, settings (b) ``continuous`` and (c)
        ``loosely_coupled`` of :func:`hybridwsi.diagnostic.stability.assess`.
    """
    refs = [reference] if isinstance(reference, xr.Dataset) else list(reference)
    dt = float(dt if dt is not None else time_step(refs[0]))
    phys = BatchedPhysics(mass, known, net.n_dof_)
    x = np.concatenate([build_features(h, net.spec_)[::max(1, stride)] for h in refs])
    jac = feature_jacobian(net, x).mean(0)
    lin_phys = phys.linearised()

    def step_map(at_dt: float) -> np.ndarray:  # the same map at any Δt: max_stable_dt's
        return _linear_map(lin_phys, net.spec_, at_dt, mode, jac, scheme, corrections)

    lin = linearise(net, refs[0], stride=stride)
    if len(refs) > 1:
        lins = [linearise(net, h, stride=stride) for h in refs]
        lin.alpha, lin.beta, lin.gamma = (np.mean([getattr(s, k) for s in lins], 0)
                                          for k in ("alpha", "beta", "gamma"))
    # docs/THEORY.md §4b-c for the network's lag-0 sensitivities, with the spectral radius and
    # the largest stable Δt of the rollout's own map (every lag, the known part's states)
    step = stability.CoupledStep.from_components(
        mass, known, lin, dt=dt, scheme=scheme, mode=mode,
        corrections=corrections if mode == "corrected" else 0)
    return stability.assess(step, step_map=step_map, rho_tol=tol)


# ---------------------------------------------------------------------------------- rollout
@dataclass
class RolloutResult:
    """Hybrid trajectories of a batch of cases: not a solver result of its own, but the
    histories built from one (``solution``, :class:`~hybridwsi.cummins.result.SolverResult`),
    with the stability prediction made before and the saw-tooth check made after.

    Attributes
    ----------
    histories : list of TimeHistory
        One per case, with ``F_net`` (network force) and ``F_known`` (known force) [N].
    prediction : StabilityReport or None
        :func:`check_stability` before the run (:mod:`hybridwsi.diagnostic.stability`).
    solution : SolverResult
        The coupled integration (:func:`hybridwsi.surrogate.coupled.solve_coupled`): ``failed``
        per case, network evaluations ``nfev``, ``counts["iterations"]`` per step.
    sawtooth : ndarray
        Per case: rms(second difference of z̈) / rms(reference z̈).
    """

    histories: list[xr.Dataset]
    prediction: stability.StabilityReport | None
    solution: SolverResult
    sawtooth: np.ndarray

    @property
    def blew_up(self) -> np.ndarray:
        """Per case: observed unstable, i.e. non-finite state, |z| > BLOWUP_FACTOR x reference
        max |z|, or a saw-tooth acceleration (``sawtooth > SAWTOOTH_RATIO``)."""
        return self.solution.failed | (self.sawtooth > SAWTOOTH_RATIO)

    @property
    def iterations(self) -> np.ndarray:
        """Fixed-point iterations (network passes) per step."""
        return self.solution.counts["iterations"]

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


def rollout(net: ForceNetwork, cases: xr.Dataset | Sequence[xr.Dataset], *,
            mass: float | np.ndarray, known: Sequence[KnownComponent], mode: str = "lagged",
            scheme: str = "newmark", prescribed: str | np.ndarray | None = None,
            n_steps: int | None = None, check: bool = True, force: bool = False,
            reference_for_check: xr.Dataset | Sequence[xr.Dataset] | None = None,
            max_iter: int = 50, tol: float = 1e-9, corrections: int = 1,
            compiled: bool | None = None, progress: bool = False,
            amplitude: float | None = None) -> RolloutResult:
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
    amplitude : float, optional
        Reference max |z| of every case [m, rad] for the divergence watch (default: each
        case's own; give it when the cases are not references, e.g. a run from rest).
    """
    net._check_fitted()
    hs = [cases] if isinstance(cases, xr.Dataset) else list(cases)
    spec, nd, w, lead = net.spec_, net.n_dof_, net.spec_.span, net.spec_.lead
    dt = time_step(hs[0])
    eta, pre = _case_arrays(hs, spec, prescribed, known)
    n_steps = _n_steps(hs[0].sizes["time"], spec, n_steps)
    prediction = None
    if check:
        prediction = check_stability(
            net, hs if reference_for_check is None else reference_for_check, mass=mass,
            known=known, dt=dt, mode=mode, scheme=scheme, corrections=corrections)
        _refuse_unstable(prediction, mode, force)
    phys = BatchedPhysics(mass, known, nd)
    stepper = CoupledStepper(phys, spec, dt, mode, network_force(net), scheme, max_iter, tol,
                             corrections)
    start, kin = _start(phys, spec, hs)
    use_compiled = fast.supported(net.activation, phys.compiled_forces, mode, scheme) \
        if compiled is None else bool(compiled)
    k0 = w - 1
    sol = solve_coupled(
        stepper, pre, start.z, start.v, dt, progress=progress, a0=start.a, x0=start.x,
        window=start.buf, eta=eta, t=np.asarray(hs[0]["time"].values, float), start=k0,
        lead=lead, n_steps=n_steps, ref_amp=_reference_amplitude(kin["z"], amplitude),
        layers=folded_layers(net) if use_compiled else None)
    saw = _sawtooth(sol.a, kin["zddot"][:, k0:k0 + n_steps + 1])
    return RolloutResult(_histories(net, hs, sol, mass, mode, known), prediction, sol, saw)


def _reference_amplitude(z: np.ndarray, amplitude: float | None) -> np.ndarray:
    """Per case, the max |z| the divergence watch compares with [m, rad]: each reference's
    own (``z`` of shape (case, time, dof)) or the given ``amplitude``; never below 1e-12."""
    amp = (np.max(np.abs(z), axis=(1, 2)) if amplitude is None
           else np.full(len(z), float(amplitude)))
    return np.maximum(amp, 1e-12)


def _n_steps(n_total: int, spec: Any, n_steps: int | None) -> int:
    """Steps a rollout can take on cases of ``n_total`` samples (at most ``n_steps``)."""
    n_max = n_total - spec.span - spec.lead
    n_steps = n_max if n_steps is None else min(int(n_steps), n_max)
    if n_steps < 1:
        raise InputError(f"cases have {n_total} samples; the network window needs more than "
                         f"{spec.span}")
    return n_steps


def _refuse_unstable(prediction: stability.StabilityReport, mode: str, force: bool) -> None:
    """:class:`UnstablePartitionError` for a partition predicted unstable (a warning with
    ``force``)."""
    if prediction.stable:
        return
    msg = (f"hybrid {mode} rollout predicted unstable: spectral radius "
           f"{prediction.spectral_radius:.4f} > 1, |alpha_s|/(m+A_k) = "
           f"{prediction.added_mass_ratio:.3f}")
    if not force:
        raise UnstablePartitionError(msg)
    warnings.warn("UNSTABLE PARTITION: " + msg, RuntimeWarning, stacklevel=3)


def _start(phys: BatchedPhysics, spec: Any, hs: list[xr.Dataset]
           ) -> tuple[State, dict[str, np.ndarray]]:
    """The state at the end of the network's first window (sample ``span − 1``) of every
    case, and the cases' kinematics (n_cases, n_time, n_dof)."""
    w = spec.span
    chans = np.stack([channel_array(h, spec) for h in hs])  # (nc, nt, nch)
    k0 = w - 1
    kin = {k: np.stack([np.asarray(h[k].values, float) for h in hs])
           for k in ("z", "zdot", "zddot")}
    x0 = np.zeros((len(hs), phys.n_states))
    if phys.n_states:  # memory states consistent with the reference's past
        x0 = initial_states(phys, hs, k0)
    return State(kin["z"][:, k0], kin["zdot"][:, k0], kin["zddot"][:, k0], x0,
                 chans[:, k0::-1][:, :w] if k0 > 0 else chans[:, :1]), kin


def _sawtooth(acc: np.ndarray, a_ref: np.ndarray) -> np.ndarray:
    """Per case: rms of the second difference of z̈ over the reference rms z̈ (inf when
    not finite) — the period-2Δt mode of an unstable lagged coupling."""
    d2 = np.diff(acc, 2, axis=1)
    with np.errstate(invalid="ignore", over="ignore"):
        if d2.size and np.isfinite(d2).all():  # the usual case: one pass, no NaN masks
            ms = np.einsum("ijk,ijk->i", d2, d2) / (d2.shape[1] * d2.shape[2])
        else:
            ms = np.nanmean(d2 ** 2, axis=(1, 2))
        saw = np.sqrt(ms) / np.maximum(np.sqrt(np.mean(a_ref ** 2, axis=(1, 2))), 1e-300)
    return np.where(np.isfinite(saw), saw, np.inf)


def _histories(net: ForceNetwork, hs: list[xr.Dataset], sol: SolverResult,
               mass: float | np.ndarray, mode: str, known: Sequence[KnownComponent]
               ) -> list[xr.Dataset]:
    """One TimeHistory per case from the coupled solution (``F_known``, ``F_net``)."""
    # the same for every case: described once (describe() formats matrices, ~0.1 ms each)
    described, spec_dict = [c.describe() for c in known], net.spec_.to_dict()
    dt = time_step(hs[0])
    out = []
    for i, h in enumerate(hs):
        forces = {"F_known": sol.forces["F_known"][i], "F_net": sol.forces["F_net"][i]}
        out.append(make_history(sol.t, sol.z[i], sol.v[i], sol.a[i], forces=forces,
                                dof=list(h["dof"].values), mass=mass,
                                source=f"hybridwsi.surrogate.rollout ({mode})",
                                inputs={"mode": mode, "dt": dt, "n_steps": sol.counts["steps"],
                                        "known": list(described), "network": dict(spec_dict)},
                                check=False))
    return out
