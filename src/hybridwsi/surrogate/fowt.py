"""The floating-wind hybrid study of OC3-Hywind: multi-DOF diagnostic, networks, rollouts.

Issue 13 items 7–8 (docs/OC3_HYWIND.md); the report's tables and files are
:mod:`hybridwsi.report.fowt_hybrid`.

**Reference histories**: 3-DOF (surge, heave, pitch) Cummins runs of the spar in JONSWAP seas
with the radiation state space, the tabulated nonlinear MoorPy mooring, Morison drag with the
Airy wave kinematics and the additional linear damping (``[hybrid]`` of
``cases/oc3_hywind.toml``).

**Partitions** (the known part; the rest, ``F_bb = F_tot − Σ known``, is what a network would
take):

- ``1`` F_tot: nothing known;
- ``2`` F_tot − F_hs − F_moor,lin: hydrostatics and the mooring *linearised* at q = 0 (MoorPy's
  K, Eq. 5-1; the mooring's nonlinearity stays in F_bb);
- ``3`` also − F_A∞ (the whole 3×3 A∞ matrix);
- ``A_inf_to_network``: C, K, radiation memory, additional damping and the excitation known,
  A∞ left to the network (with the drag and the mooring nonlinearity);
- ``A_inf_coupling_to_network``: the same with the diagonal of A∞ known, only its surge–pitch
  coupling left to the network;
- ``recommended``: C, K, A∞, radiation memory, additional damping, excitation known; the
  network takes Morison drag + (tabulated mooring − its linearisation).

**Diagnostic** (:func:`diagnostic`): for each partition α, β, γ are regressed (matrix form,
docs/THEORY.md §1–3b), identifiability is judged per DOF and for the surge–pitch coupling at
the stated force accuracies, and the lagged-coupling verdict is the spectral radius of the
one-step amplification matrix with the residual's α, β, γ as the surrogate's (§4c; its
added-mass part ρ((M + A_k)⁻¹ α)). The observed behaviour of the partitions with linear known
parts (1–3) is a lagged run of that very surrogate (α z̈_lag + β ż + γ z plus the reference
remainder, so it reproduces the reference exactly when stable) from a slightly perturbed start.

**Hybrid** (:func:`run_partition`, :func:`long_run`, :func:`run_study`): a
:class:`~hybridwsi.surrogate.network.ForceNetwork` learns each network partition's residual
from irregular seas (the ``[hybrid] train`` seas);
:func:`~hybridwsi.surrogate.rollout.check_stability` (the network's linearisation in the very
step map of the rollout) predicts stability before each rollout; the held-out seas
(``[hybrid] test``) give the rollout error per DOF (% of the reference's RMS); each partition is
rolled out both ``lagged`` (the diagnostic's setting) and in the configured mode
(``corrected``); the recommended partition then runs the ``long`` sea (3 hours). That case is a
linear Cummins run of the same sea (it supplies the time grid, ``eta``, ``F_exc`` and the
initial window; a nonlinear reference of that length would cost more than the rollout): the
check there is stability (bounded, no drift), and the hybrid's RMS motion is reported beside
the linear one. torch (the optional ``ml`` extra) is imported where the networks are.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.cummins import build_system, simulate
from hybridwsi.diagnostic import stability
from hybridwsi.diagnostic.integrators import LaggedIntegrator
from hybridwsi.diagnostic.regression import regress
from hybridwsi.forces import (
    AddedMass,
    KnownComponent,
    MooringForce,
    RadiationMemory,
    black_box_force,
    summed_linear_coefficients,
)
from hybridwsi.forces.external import PrescribedForce
from hybridwsi.forces.linear import known_from
from hybridwsi.forces.morison import MorisonDrag
from hybridwsi.history import nrms_percent
from hybridwsi.waves import JONSWAP

from hybridwsi.surrogate.network import ForceNetwork  # torch itself is loaded when used
from hybridwsi.surrogate.pipeline import predict_stability
from hybridwsi.surrogate.rollout import RolloutResult, rollout

#: growth of the lagged run's error over its initial perturbation that counts as "blew up"
GROWTH_LIMIT = 1e3
#: what each partition leaves to the network, for the tables
RESIDUAL = {
    "1": "everything (inertia, hydrostatics, mooring, radiation, drag, excitation)",
    "2": "A∞, radiation memory, drag, mooring nonlinearity, damping, excitation",
    "3": "radiation memory, drag, mooring nonlinearity, damping, excitation",
    "A_inf_to_network": "A∞ (3×3), drag, mooring nonlinearity",
    "A_inf_coupling_to_network": "A∞ surge–pitch coupling, drag, mooring nonlinearity",
    "recommended": "Morison drag + (tabulated mooring − K q)",
}


# ------------------------------------------------------------------------- reference data
def hybrid_settings(case: Mapping[str, Any], quick: bool = False) -> dict[str, Any]:
    """The ``[hybrid]`` table with the ``quick`` durations applied."""
    cfg = dict(case["hybrid"])
    net = dict(cfg["network"])
    if quick:
        cfg["duration"], cfg["long_duration"] = cfg["quick_duration"], cfg["quick_long_duration"]
    net["hidden"] = tuple(net["hidden"])
    cfg["network"] = net
    return cfg


def sea(spec: Mapping[str, Any]) -> JONSWAP:
    """A JONSWAP sea from ``{hs [m], tp [s], seed}``."""
    return JONSWAP(hs=float(spec["hs"]), tp=float(spec["tp"]), seed=int(spec["seed"]))


def irregular_history(coeffs: xr.Dataset, case: Mapping[str, Any], mooring: MooringForce,
                      damping: KnownComponent, spec: Mapping[str, Any], *, dofs: Sequence[str],
                      duration: float, dt: float, ramp: float, radiation_ss: Any = None
                      ) -> xr.Dataset:
    """One nonlinear Cummins run in a JONSWAP sea: radiation state space, tabulated mooring
    (F(q) − F0), Morison drag with the wave's particle velocity, additional linear damping.

    ``F_ext`` of the history is the sum of those three components [N, N m].
    """
    wave = sea(spec)
    drag = MorisonDrag.from_case(case, dofs, wave=wave, ramp=ramp)
    return simulate(coeffs, dofs=dofs, duration=duration, dt=dt, wave=wave, ramp=ramp,
                    forces=[mooring, drag, damping], radiation_ss=radiation_ss)


# ------------------------------------------------------------------------------ partitions
def partitions(hist: xr.Dataset, mooring_linear: KnownComponent, damping: KnownComponent
               ) -> dict[str, list[KnownComponent]]:
    """The known components of each partition (module docstring), matrices from ``hist``."""
    hs, added_mass_inf = known_from(hist, None, ["hydrostatic", "added_mass_inf"])
    a_diag = AddedMass(np.diag(np.diag(added_mass_inf.value)))
    memory = RadiationMemory.from_history(hist)
    exc = PrescribedForce("F_exc")
    rest = [memory, damping, exc]
    return {
        "1": [],
        "2": [hs, mooring_linear],
        "3": [hs, mooring_linear, added_mass_inf],
        "A_inf_to_network": [hs, mooring_linear, *rest],
        "A_inf_coupling_to_network": [hs, mooring_linear, a_diag, *rest],
        "recommended": [hs, mooring_linear, added_mass_inf, *rest],
    }


def expected_coefficients(hist: xr.Dataset, known: Sequence[KnownComponent]
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Newton's exact α, β, γ = (M + A_k, B_k, C_k) when the known part is purely linear and
    time-invariant (docs/THEORY.md §1): then F_bb ≡ (M + A_k) z̈ + B_k ż + C_k z; else None."""
    if any(k.time_only or k.n_states for k in known):
        return None
    n = hist.sizes["dof"]
    a_k, b_k, c_k = summed_linear_coefficients(list(known), n)
    return rigid_mass(hist) + a_k, b_k, c_k


def rigid_mass(hist: xr.Dataset) -> np.ndarray:
    """The rigid-body mass matrix M [kg, kg m, kg m²] the history carries."""
    return np.asarray(hist["mass"].values, dtype=float)


# ------------------------------------------------------------------------- observed (1–3)
def lagged_linear_run(hist: xr.Dataset, known: Sequence[KnownComponent], reg: Any, *,
                      perturbation: float, scheme: str = "newmark") -> dict[str, Any]:
    """Run the lagged coupling with the regressed surrogate and report the error growth.

    The surrogate is ``F_s = α z̈_lag + β ż + γ z + r(t)`` with the remainder
    ``r = F_bb,ref − (α z̈ + β ż + γ z)_ref`` (so on the reference it is F_bb exactly); the
    known part must be linear (``A_k, B_k, C_k``). Start: the reference plus ``perturbation`` ×
    std(z) on every DOF. Observed unstable: the error grows by more than :data:`GROWTH_LIMIT`
    (or goes non-finite).
    """
    z_r, v_r, a_r = (np.asarray(hist[k].values, float) for k in ("z", "zdot", "zddot"))
    t = np.asarray(hist["time"].values, float)
    n = z_r.shape[1]
    m = rigid_mass(hist)
    a_k, b_k, c_k = summed_linear_coefficients(list(known), n)
    f_bb = black_box_force(hist, "F_tot", list(known))
    remainder = f_bb - a_r @ reg.alpha.T - v_r @ reg.beta.T - z_r @ reg.gamma.T
    dt = float(t[1] - t[0])
    integ = LaggedIntegrator(scheme, dt, m + a_k, b_k, c_k)
    dz0 = perturbation * z_r.std(axis=0)
    z, v, a = z_r[0] + dz0, v_r[0].copy(), a_r[0].copy()
    err = np.empty(len(t))
    err[0] = 1.0
    scale = np.maximum(np.abs(dz0), 1e-300)
    for k in range(len(t) - 1):
        f = a @ reg.alpha.T + v @ reg.beta.T + z @ reg.gamma.T + remainder[k + 1]
        z, v, a = integ.step(z, v, a, f)
        e = float(np.max(np.abs(z - z_r[k + 1]) / scale))
        err[k + 1] = e
        if not math.isfinite(e) or e > GROWTH_LIMIT:
            err[k + 2:] = np.nan
            break
    grown = float(np.nanmax(err))
    return {"scheme": scheme, "dt": dt, "perturbation_x_std": perturbation,
            "max_error_growth": grown if math.isfinite(grown) else None,
            "final_error_growth": float(err[-1]) if math.isfinite(err[-1]) else None,
            "observed_stable": bool(math.isfinite(grown) and grown <= GROWTH_LIMIT)}


# ------------------------------------------------------------------------------ regression
def coupling_identifiable(reg: Any, accuracy: float, i: int, j: int) -> bool:
    """The coupling entries (i, j) and (j, i) of α and γ move by 10 % only under a force error
    larger than ``accuracy`` (docs/THEORY.md §3b)."""
    eps = [reg.force_error_terms[t][a, b] for t in ("alpha", "gamma") for a, b in ((i, j), (j, i))]
    return bool(min(eps) > accuracy)


def partition_entry(name: str, hist: xr.Dataset, known: Sequence[KnownComponent],
                    accuracies: Sequence[float], *, dt: float, perturbation: float,
                    scheme: str = "newmark") -> dict[str, Any]:
    """Regression, identifiability, lagged verdict (and, for linear known parts, the observed
    lagged run) of one partition."""
    dofs = [str(d) for d in hist["dof"].values]
    i_s, i_p = dofs.index("Surge"), dofs.index("Pitch")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        regs = [regress(hist, "F_tot", list(known), force_accuracy=acc) for acc in accuracies]
    reg = regs[0]
    rep = stability.assess(stability.CoupledStep.from_components(
        rigid_mass(hist), list(known), reg, dt=dt, scheme=scheme))
    lag, ratio = rep.loosely_coupled, rep.added_mass_ratio
    out: dict[str, Any] = {
        "partition": name,
        "known": [k.describe() for k in known],
        "left_to_network": RESIDUAL[name],
        "dofs": dofs,
        "alpha": reg.alpha.tolist(), "beta": reg.beta.tolist(), "gamma": reg.gamma.tolist(),
        "units": reg.units(),
        "r2": reg.r2.tolist(),
        "condition_number": float(reg.condition_number),
        "force_error_10pct": reg.force_error_10pct.tolist(),
        "identifiable": {f"{acc:g}": {"per_dof": dict(zip(dofs, map(bool, r.identifiable_dof))),
                                      "surge_pitch_coupling": coupling_identifiable(
                                          r, acc, i_s, i_p)}
                         for acc, r in zip(accuracies, regs)},
        "added_mass_ratio": ratio,
        "spectral_radius": lag.spectral_radius,
        "lagged_verdict": lag.verdict,
        "lagged_message": lag.message,
        "predicted_stable": bool(lag.verdict == "stable"),
    }
    exact = expected_coefficients(hist, known)
    if exact is not None:
        out["newton"] = {k: v.tolist() for k, v in zip(("alpha", "beta", "gamma"), exact)}
        out["observed"] = lagged_linear_run(hist, known, reg, perturbation=perturbation,
                                            scheme=scheme)
    return out


def verdict_line(entry: Mapping[str, Any]) -> tuple[str, str]:
    """(where it goes, one-line reason) for the hand-over table."""
    ratio, rho = entry["added_mass_ratio"], entry["spectral_radius"]
    if entry["predicted_stable"]:
        return ("network", f"lagged step map stable: ρ = {rho:.4f}, ρ((M+A_k)⁻¹α) = "
                           f"{ratio:.3f} < 1")
    if abs(ratio - 1.0) < 1e-3:
        return ("ODE", f"F_bb is the body's own inertia (α = M + A_k, ρ((M+A_k)⁻¹α) = "
                       f"{ratio:.4f}): a lagged network would carry the left-hand side")
    if ratio >= 1.0:
        return ("ODE", f"added-mass instability: ρ((M+A_k)⁻¹α) = {ratio:.3f} ≥ 1 at every Δt")
    return ("ODE", f"lagged step map unstable at this Δt: ρ = {rho:.4f}")


def diagnostic(histories: Sequence[xr.Dataset], mooring_linear: KnownComponent,
               damping: KnownComponent, cfg: Mapping[str, Any]) -> dict[str, Any]:
    """Item 7 on the first training history (JSON-ready): one entry per partition."""
    hist = histories[0]
    parts = partitions(hist, mooring_linear, damping)
    rows = [partition_entry(name, hist, known, cfg["force_accuracy"], dt=float(cfg["dt"]),
                            perturbation=float(cfg["perturbation"]))
            for name, known in parts.items()]
    for r in rows:
        r["where"], r["reason"] = verdict_line(r)
    return {"history": {"sea": cfg["train"][0], "duration_s": float(hist["time"][-1]),
                        "dt": float(cfg["dt"]), "dofs": list(cfg["dofs"])},
            "mass": rigid_mass(hist).tolist(),
            "added_mass_inf": np.asarray(hist["added_mass_inf"].values).tolist(),
            "rho_M_inv_A_inf": stability.added_mass_ratio(
                rigid_mass(hist), np.zeros_like(rigid_mass(hist)),
                np.asarray(hist["added_mass_inf"].values)),
            "partitions": rows}


# ------------------------------------------------------------------------------ hybrid
#: rollout error [% of the reference RMS, any DOF] above which a run that did not blow up still
#: counts as unstable: a growing mode held bounded only by the network's saturation (an
#: uncorrelated response of the right size would give ~141 %)
DIVERGED_PERCENT = 100.0


def checked_rollout(net: ForceNetwork, cases: Sequence[xr.Dataset],
                    reference: xr.Dataset | Sequence[xr.Dataset], *, mass: np.ndarray,
                    known: Sequence[KnownComponent], mode: str, stride: int = 5
                    ) -> tuple[Any, int, RolloutResult]:
    """Predict the coupling's stability, then roll it out, unstable or not.

    The pipeline's :func:`~hybridwsi.surrogate.pipeline.predict_stability` on ``reference``
    (every ``stride``-th state; in ``corrected`` mode with the corrections the network's
    added-mass ratio calls for), then :func:`~hybridwsi.surrogate.rollout.rollout` of
    ``cases`` (a partition predicted unstable runs too: the study observes what it does).

    Returns
    -------
    prediction : StabilityReport
    corrections : int
        Predictor-corrector passes (1 outside ``corrected``).
    result : RolloutResult
    """
    refs = [reference] if isinstance(reference, xr.Dataset) else list(reference)
    pred, n_corr = predict_stability(net, refs, mass=mass, known=known, mode=mode,
                                     stride=stride)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # unstable ones run on purpose
        res = rollout(net, list(cases), mass=mass, known=known, mode=mode, corrections=n_corr,
                      check=False)
    return pred, n_corr, res


def run_partition(name: str, known: Sequence[KnownComponent], net_kw: Mapping[str, Any],
                  train: Sequence[xr.Dataset], test: Sequence[xr.Dataset], mass: np.ndarray,
                  mode: str) -> tuple[dict[str, Any], ForceNetwork, RolloutResult]:
    """Train the partition's network (``net_kw``: ForceNetwork settings with ``inputs``),
    predict, roll out (lagged and ``mode``) on the held-out seas.

    Returns the JSON entry, the network and the ``mode`` rollout (for the figure).
    """
    t0 = time.time()
    net = ForceNetwork(**{**net_kw, "inputs": tuple(net_kw["inputs"])}).fit(
        list(train), "F_bb", known=list(known))
    entry: dict[str, Any] = {"partition": name,
                             "network": {k: (list(v) if isinstance(v, tuple) else v)
                                         for k, v in net_kw.items()},
                             "known": [k.describe() for k in known],
                             "left_to_network": RESIDUAL[name],
                             "train_s": time.time() - t0,
                             "r2_held_out": float(np.mean([net.score(h, "F_bb", known=list(known))
                                                           for h in test]))}
    res_mode = None
    for m in dict.fromkeys(("lagged", mode)):
        pred, n_corr, res = checked_rollout(net, list(test), train, mass=mass, known=known,
                                            mode=m)
        entry[m] = {"corrections": n_corr if m == "corrected" else 0,
                    "spectral_radius": pred.spectral_radius,
                    "added_mass_ratio": pred.added_mass_ratio,
                    "alpha_s": np.asarray(pred.alpha_s).tolist(),
                    "predicted_stable": bool(pred.stable),
                    "blew_up": res.blew_up.tolist(),
                    "rollout_error_percent_rms": [dict(zip(_dofs(h), nrms_percent(r, h)))
                                                  for r, h in zip(res.histories, test)]}
        worst = max(max(c.values()) for c in entry[m]["rollout_error_percent_rms"])
        entry[m]["observed_stable"] = bool(not res.blew_up.any() and worst <= DIVERGED_PERCENT)
        entry[m]["agree"] = entry[m]["predicted_stable"] == entry[m]["observed_stable"]
        if m == mode:
            res_mode = res
    return entry, net, res_mode


def _dofs(hist: xr.Dataset) -> list[str]:
    """The history's DOF names."""
    return [str(d) for d in hist["dof"].values]


def long_run(net: ForceNetwork, known: Sequence[KnownComponent], case_hist: xr.Dataset,
             mass: np.ndarray, mode: str) -> dict[str, Any]:
    """The recommended partition over the long sea: predicted, blown up, RMS per DOF, drift.

    The prediction is linearised on every 20th state of the long sea; ``wall_s`` [s] times the
    prediction and the rollout.
    """
    t0 = time.time()
    pred, _, res = checked_rollout(net, [case_hist], case_hist, mass=mass, known=known,
                                   mode=mode, stride=20)
    wall = time.time() - t0
    h = res.histories[0]
    z = h["z"].values
    dofs = _dofs(h)
    tail = z[-len(z) // 10:]
    return {"duration_s": float(h["time"][-1] - h["time"][0]), "wall_s": wall,
            "predicted_stable": bool(pred.stable), "spectral_radius": pred.spectral_radius,
            "blew_up": bool(res.blew_up[0]),
            "rms_hybrid": dict(zip(dofs, np.sqrt(np.mean(z ** 2, axis=0)).tolist())),
            "rms_linear_reference": dict(zip(dofs, np.sqrt(np.mean(
                case_hist["z"].values ** 2, axis=0)).tolist())),
            "max_abs_hybrid": dict(zip(dofs, np.abs(z).max(axis=0).tolist())),
            "mean_last_10pct": dict(zip(dofs, tail.mean(axis=0).tolist()))}


@dataclass
class FowtHybridStudy:
    """What :func:`run_study` computed (JSON-ready dicts; non-finite numbers as they came).

    Attributes
    ----------
    settings : dict
        :func:`hybrid_settings` of the run.
    diagnostic : dict
        :func:`diagnostic` on the first training sea.
    hybrid : dict
        ``settings``, ``partitions`` (one :func:`run_partition` entry each), ``long_run``
        (:func:`long_run` with its ``sea``) and ``all_agree`` (every prediction as observed).
    shown : RolloutResult
        The recommended partition's rollout in the configured mode on the held-out seas.
    test : list of TimeHistory
        The held-out seas' reference histories.
    """

    settings: dict[str, Any]
    diagnostic: dict[str, Any]
    hybrid: dict[str, Any]
    shown: Any
    test: list[xr.Dataset]


def run_study(case: Mapping[str, Any], coeffs: xr.Dataset, mooring_linear: KnownComponent,
              damping: KnownComponent, *, quick: bool = False,
              log: Callable[[str], None] = lambda m: None) -> FowtHybridStudy:
    """Items 7 and 8: reference seas, the diagnostic, a network per partition, the long sea.

    ``mooring_linear`` is −K q on ``[hybrid] dofs`` (MoorPy's K), ``damping`` the additional
    linear damping (:func:`hybridwsi.casemodel.linear_components`); ``quick`` uses the
    ``[hybrid]`` quick durations.
    """
    import torch

    torch.set_num_threads(1)  # tiny networks on a shared machine
    cfg = hybrid_settings(case, quick)
    dofs, dt = list(cfg["dofs"]), float(cfg["dt"])
    mooring = MooringForce.from_case(case, dofs)
    ss = build_system(coeffs, dofs=dofs, dt=dt).ss  # one fit for every sea

    def histories(seas: Sequence[Mapping[str, Any]]) -> list[xr.Dataset]:
        return [irregular_history(coeffs, case, mooring, damping, s, dofs=dofs,
                                  duration=cfg["duration"], dt=dt, ramp=cfg["ramp"],
                                  radiation_ss=ss) for s in seas]

    train, test = histories(cfg["train"]), histories(cfg["test"])
    log("irregular-sea references")
    diag = diagnostic(train, mooring_linear, damping, cfg)
    log("diagnostic")

    mass = rigid_mass(train[0])
    parts = partitions(train[0], mooring_linear, damping)
    entries, nets, shown = [], {}, None
    for name, own in cfg["partitions"].items():
        entry, net, res = run_partition(name, parts[name], {**cfg["network"], **own}, train,
                                        test, mass, cfg["mode"])
        entries.append(entry)
        nets[name] = net
        if name == "recommended":
            shown = res
        log(f"hybrid {name}")
    hyb: dict[str, Any] = {
        "settings": {k: cfg[k] for k in ("dofs", "dt", "duration", "ramp", "train", "test",
                                         "mode")}
        | {"network": {**cfg["network"], "hidden": list(cfg["network"]["hidden"])}},
        "partitions": entries}
    # the long case: linear Cummins (linearised mooring, additional damping) of the same sea
    long_hist = simulate(coeffs, dofs=dofs, duration=float(cfg["long_duration"]), dt=dt,
                         wave=sea(cfg["long"]), ramp=cfg["ramp"], radiation_ss=ss,
                         forces=[mooring_linear, damping])
    hyb["long_run"] = {"sea": cfg["long"], **long_run(nets["recommended"],
                                                      parts["recommended"], long_hist, mass,
                                                      cfg["mode"])}
    hyb["all_agree"] = all(p[m]["agree"] for p in entries for m in ("lagged", cfg["mode"]))
    log("the long run")
    return FowtHybridStudy(cfg, diag, hyb, shown, test)
