"""The diagnostic on OC3-Hywind's design-fidelity components (issue 29 item 4).

Which of the new force components — MoorDyn's mooring, the slow drift, the operating rotor —
can be handed to a network coupled one step lagged, and which must stay in the ODE?

1. **Probe.** Each component's force on a prescribed broadband motion in all six DOFs
   (:func:`probe_motion`: a sum of sinusoids per DOF over 0.03–1 rad/s, the slow-drift,
   heave/pitch and wave bands, at the offset of the components' mean forces), so every DOF
   is excited and the regression is identifiable: MoorDyn driven along it
   (``MoorDynForce.force``), the rotor and the drift evaluated on it.
2. **Regress** (:func:`hybridwsi.diagnostic.regression.regress`) ``F_k ≈ α z̈ + β ż + γ z +
   c``: α of MoorDyn is minus the lines' added mass, β minus their damping, γ minus their
   stiffness (compare with MoorPy's / the definition's K); β of the rotor is minus the
   aerodynamic damping ``dT/dU j jᵀ``; the drift depends on the wave, not the motion (R² ≈ 0).
3. **Predict** with the one assessment (:func:`hybridwsi.diagnostic.stability.assess`): the
   step with the rigid mass, the known part (A∞, hydrostatics, additional damping, the other
   components' linearisation; no radiation damping — conservative) and the component's α, β,
   γ as the learned part, coupled lagged at the solver's Δt: learnable lagged if stable.
4. **Observe** (:func:`observe`): free decays of the case from its mean offset with the
   component in the ODE and coupled one step lagged (:class:`~hybridwsi.forces.lagged.
   LaggedComponent`; MoorDyn is coupled that way already), at the solver's Δt.

``python scripts/oc3_components.py`` runs it and prints the tables of docs/OC3_HYWIND.md.
"""

from __future__ import annotations

import dataclasses
import json
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.casemodel import CaseModel, component_variable
from hybridwsi.diagnostic import stability
from hybridwsi.diagnostic.regression import regress
from hybridwsi.forces import Hydrostatic, KnownComponent, LinearDamping, additional_damping
from hybridwsi.forces.linear import known_from
from hybridwsi.forces.mooring import MooringForce
from hybridwsi.history import make_history
from hybridwsi.hydro import coefficients as cf

#: RMS of the probe motion per DOF [m, rad]: the order of the motions of a 3-hour storm sea
PROBE_RMS = {"Surge": 2.0, "Sway": 1.0, "Heave": 0.3, "Roll": 0.01, "Pitch": 0.015,
             "Yaw": 0.02}
#: frequency band of the probe motion [rad/s]: slow drift (surge 0.05), heave/pitch (0.2),
#: waves (0.4-1)
PROBE_BAND = (0.03, 1.0)
#: relative accuracy of the components' forces (computed, not measured)
FORCE_ACCURACY = 1e-6
#: a decay is observed stable when the kicked DOF's last-third RMS about the offset is below
#: this times its first-third RMS
DECAY_LIMIT = 1.0


def probe_motion(t: np.ndarray, dofs: Sequence[str], *, rms: Mapping[str, float] | None = None,
                 band: tuple[float, float] = PROBE_BAND, n_lines: int = 12, seed: int = 0
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A broadband motion ``(z, ż, z̈)`` [m, rad; per s; per s²], shape (n_time, n_dof): per
    DOF ``n_lines`` sinusoids log-spaced over ``band`` [rad/s], each DOF's lines interleaved
    with the others' (no two DOFs share a frequency, so they are not collinear), random phases
    (``seed``), scaled to ``rms`` (default :data:`PROBE_RMS`)."""
    rms = {**PROBE_RMS, **(rms or {})}
    t = np.asarray(t, dtype=float)
    n = len(dofs)
    omega = np.geomspace(band[0], band[1], n_lines * n).reshape(n_lines, n).T  # (n_dof, lines)
    phase = np.random.default_rng(seed).uniform(0.0, 2 * np.pi, omega.shape)
    amp = np.array([rms[d] for d in dofs])[:, None] * np.sqrt(2.0 / n_lines)
    arg = omega[None] * t[:, None, None] + phase[None]  # (time, dof, line)
    z = np.sum(amp * np.sin(arg), axis=2)
    zd = np.sum(amp * omega * np.cos(arg), axis=2)
    zdd = -np.sum(amp * omega ** 2 * np.sin(arg), axis=2)
    return z, zd, zdd


def probe_history(model: CaseModel, components: Mapping[str, KnownComponent], *,
                  duration: float, dt: float, seed: int = 0,
                  rms: Mapping[str, float] | None = None) -> xr.Dataset:
    """The probe motion (:func:`probe_motion`, ``rms`` [m, rad] per DOF over
    :data:`PROBE_RMS`) about the components' mean offset as a TimeHistory, with each
    component's force on it (:func:`~hybridwsi.casemodel.component_variable`: ``F_mooring``,
    ``F_rotor``, ``F_drift``, ...) and the rigid mass and A∞, C of the case."""
    t = np.arange(0.0, duration + 0.5 * dt, dt)
    z, zd, zdd = probe_motion(t, model.dofs, seed=seed, rms=rms)
    z = z + model.mean_offset(components)
    mass = cf.matrix(model.coeffs, "mass", model.dofs)
    hist = make_history(t, z, zd, zdd, dof=list(model.dofs), mass=mass, source="probe")
    hist = hist.assign(
        added_mass_inf=(("dof", "dof_j"), cf.matrix(model.coeffs, "added_mass_inf", model.dofs)),
        hydrostatic_stiffness=(("dof", "dof_j"),
                               cf.matrix(model.coeffs, "hydrostatic_stiffness", model.dofs)))
    forces = {component_variable(k): (("time", "dof"), np.asarray(c.force(hist), dtype=float))
              for k, c in components.items()}
    return hist.assign(forces)


def known_part(model: CaseModel, hist: xr.Dataset, components: Mapping[str, KnownComponent],
               learned: str) -> list[KnownComponent]:
    """The known part when ``learned`` goes to a network: A∞ and hydrostatics of the history,
    the case's additional damping, the mooring's yaw spring, every other component's
    linearisation (C = its stiffness, B = its damping)."""
    known = known_from(hist, None, ["hydrostatic", "added_mass_inf"])
    if learned == "mooring":
        known += _yaw_spring(model)
    if model.case["forces"]["linear_damping"]:
        known.append(additional_damping(model.case, model.dofs))
    for name, comp in components.items():
        if name in (learned, "linear_damping"):
            continue
        _, b, c = comp.linear_coefficients(len(model.dofs))
        known.append(Hydrostatic(c))
        if np.any(b):
            known.append(LinearDamping(b))
    return known


def _yaw_spring(model: CaseModel) -> list[KnownComponent]:
    """The definition's linear yaw spring (``[mooring] yaw_spring``) on the DOFs: a linear
    component that stays in the ODE whatever the mooring model (none without yaw)."""
    k = float(model.case.get("mooring", {}).get("yaw_spring", 0.0))
    if not k or "Yaw" not in model.dofs:
        return []
    c = np.zeros((len(model.dofs), len(model.dofs)))
    c[model.dofs.index("Yaw"), model.dofs.index("Yaw")] = k
    return [Hydrostatic(c)]


def _regression(model: CaseModel, hist: xr.Dataset, name: str) -> Any:
    """``regress`` of the component's force; the mooring's without the yaw spring."""
    spring = _yaw_spring(model) if name == "mooring" else []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return regress(hist, component_variable(name), spring, force_accuracy=FORCE_ACCURACY)


def predict(model: CaseModel, hist: xr.Dataset, components: Mapping[str, KnownComponent],
            name: str, *, dt: float, scheme: str = "newmark") -> dict[str, Any]:
    """Regression of one component's force on the probe and the verdict of :func:`assess` on
    the step that learns it lagged at ``dt`` [s] (module docstring, steps 2-3)."""
    reg = _regression(model, hist, name)
    known = known_part(model, hist, components, name)
    mass = np.asarray(hist["mass"].values, dtype=float)
    rep = stability.assess(stability.CoupledStep.from_components(
        mass, known, reg, dt=dt, scheme=scheme, mode="lagged"))
    lagged = rep.loosely_coupled
    return {
        "component": name, "describe": components[name].describe(), "dofs": list(model.dofs),
        "alpha": reg.alpha, "beta": reg.beta, "gamma": reg.gamma, "r2": reg.r2,
        "units": reg.units(), "added_mass_ratio": rep.added_mass_ratio,
        "continuous": rep.continuous.verdict, "lagged": lagged.verdict,
        "spectral_radius": lagged.spectral_radius, "max_stable_dt": lagged.max_stable_dt,
        "message": lagged.message, "learnable_lagged": bool(rep.stable and
                                                             rep.continuous_stable)}


def hold_rk4_map(step: stability.CoupledStep, dt: float | None = None) -> np.ndarray:
    """One-step map (3n×3n, state ``[z, ż, z̈]``) of the case's own coupling of a stepped
    component: RK4 on ``(m + A_k) z̈ = −B_k ż − C_k z + f`` with the learned force ``f = α z̈_k
    + β ż_k + γ z_k`` evaluated at the step's start and held over the step (how the Cummins
    solver couples MoorDyn); ``z̈`` carried is the end-of-step acceleration under that hold.
    Passed to :func:`~hybridwsi.diagnostic.stability.assess` as ``step_map``. A numerical
    kernel (column by column, as ``stability.amplification_matrix``)."""
    dt = step.dt if dt is None else float(dt)
    n = step.n_dof
    inv = np.linalg.inv(step.inertia)

    def accel(z: np.ndarray, v: np.ndarray, f: np.ndarray) -> np.ndarray:
        return inv @ (f - step.known_damping @ v - step.known_stiffness @ z)

    g = np.empty((3 * n, 3 * n))
    for k in range(3 * n):
        s = np.zeros(3 * n)
        s[k] = 1.0
        z, v, a = s[:n], s[n:2 * n], s[2 * n:]
        f = step.alpha @ a + step.beta @ v + step.gamma @ z
        k1z, k1v = v, accel(z, v, f)
        k2z, k2v = v + 0.5 * dt * k1v, accel(z + 0.5 * dt * k1z, v + 0.5 * dt * k1v, f)
        k3z, k3v = v + 0.5 * dt * k2v, accel(z + 0.5 * dt * k2z, v + 0.5 * dt * k2v, f)
        k4z, k4v = v + dt * k3v, accel(z + dt * k3z, v + dt * k3v, f)
        z1 = z + dt / 6 * (k1z + 2 * k2z + 2 * k3z + k4z)
        v1 = v + dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        g[:, k] = np.concatenate([z1, v1, accel(z1, v1, f)])
    return g


def hold_rk4_limit(step: stability.CoupledStep, dts: Sequence[float] = tuple(
        np.geomspace(0.01, 5.0, 120))) -> float:
    """Largest Δt [s] of ``dts`` below which :func:`hold_rk4_map` has spectral radius ≤ 1 (+
    ``stability.RHO_TOL``) at every tested step (inf: all of them)."""
    last = float("inf")
    for dt in dts:
        rho = float(np.max(np.abs(np.linalg.eigvals(hold_rk4_map(step, dt)))))
        if rho > 1.0 + stability.RHO_TOL:
            return last if last != float("inf") else 0.0
        last = float(dt)
    return float("inf")


def predict_coupling(model: CaseModel, hist: xr.Dataset,
                     components: Mapping[str, KnownComponent], name: str, *, dt: float
                     ) -> dict[str, Any]:
    """The component (MoorDyn) coupled by the case's solver one step lagged — RK4 with its
    force held from the step's start (:func:`hold_rk4_map`) — judged by ``assess`` with that
    step map at ``dt`` [s], and the largest stable Δt of the same map."""
    reg = _regression(model, hist, name)
    mass = np.asarray(hist["mass"].values, dtype=float)
    step = stability.CoupledStep.from_components(
        mass, known_part(model, hist, components, name), reg, dt=dt, mode="lagged")
    rep = stability.assess(step, step_map=hold_rk4_map(step))
    return {"component": name, "dt": dt, "spectral_radius": rep.spectral_radius,
            "stable": rep.stable, "max_stable_dt": hold_rk4_limit(step),
            "added_mass_ratio": rep.added_mass_ratio}


def ode_limit(model: CaseModel, hist: xr.Dataset, components: Mapping[str, KnownComponent]
              ) -> float:
    """Largest stable RK4 Δt [s] of the linear ODE alone (known part of the mooring's step
    with its quasi-static stiffness, nothing lagged; no radiation memory): what limits Δt
    before any coupling does."""
    mass = np.asarray(hist["mass"].values, dtype=float)
    known = known_part(model, hist, components, "none")
    return hold_rk4_limit(stability.CoupledStep.from_components(mass, known, None, dt=0.1))


def _decay_ratio(hist: xr.Dataset, dof: str, offset: float) -> float:
    """RMS of ``z − offset`` of ``dof`` over the last third over that of the first third."""
    y = hist["z"].sel(dof=dof).values - offset
    k = y.size // 3
    first, last = np.sqrt(np.mean(y[:k] ** 2)), np.sqrt(np.mean(y[-k:] ** 2))
    return float(last / first) if np.isfinite(last) else float("inf")


def observe(model: CaseModel, name: str, *, kick: Mapping[str, float], duration: float,
            dt: float, wave: Any = None, ramp: float = 0.0) -> dict[str, Any]:
    """Runs from the mean offset plus ``kick`` [m, rad per DOF] with ``name`` in the ODE and
    coupled one step lagged (MoorDyn: its own coupling, a hold of the step's start, against
    the tabulated quasi-static mooring in the ODE). In calm water (free decays) observed
    stable when every kicked DOF decays (:data:`DECAY_LIMIT`); in a sea (``wave``, the slow
    drift) also the lagged run's largest difference from the run in the ODE over the latter's
    largest motion about the offset, per DOF."""
    z0 = np.array([kick.get(d, 0.0) for d in model.dofs])
    in_ode = model
    if name == "mooring" and model.mooring == "moordyn":  # MoorDyn is lagged by its coupling
        table = MooringForce.from_case(model.case, model.dofs).table
        in_ode = dataclasses.replace(model, mooring="table", mooring_table=table)
    runs = {}
    for label, run, lagged in (("in_ode", in_ode, ()), ("lagged", model, (name,))):
        try:
            hist = run.simulate(duration=duration, dt=dt, z0=z0, lagged=lagged, wave=wave,
                                ramp=ramp)
        except Exception as exc:  # noqa: BLE001 — a blow-up is an observation, not a bug
            runs[label] = {"stable": False, "error": str(exc).splitlines()[0]}
            continue
        offset = np.array(list(json.loads(hist.attrs["mean_offset"]).values()))
        ratios = {d: _decay_ratio(hist, d, offset[model.dofs.index(d)]) for d in kick}
        runs[label] = {"decay_ratio": ratios, "z": hist["z"].values,
                       "stable": bool(np.all(np.isfinite(hist["z"].values)) and (
                           wave is not None or all(r < DECAY_LIMIT for r in ratios.values())))}
    if "z" in runs["in_ode"] and "z" in runs["lagged"]:
        ref, lag = runs["in_ode"]["z"], runs["lagged"]["z"]
        size = np.maximum(np.max(np.abs(ref - ref[0]), axis=0), 1e-12)
        runs["difference"] = dict(zip(model.dofs, (np.max(np.abs(lag - ref), axis=0)
                                                   / size).tolist()))
    for run in runs.values():
        if isinstance(run, dict):
            run.pop("z", None)
    return runs
