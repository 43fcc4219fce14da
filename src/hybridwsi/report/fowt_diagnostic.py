"""The stability diagnostic in several DOFs for OC3-Hywind (issue 13 item 7).

Reference histories: 3-DOF (surge, heave, pitch) Cummins runs of the spar in JONSWAP seas with
the radiation state space, the tabulated nonlinear MoorPy mooring, Morison drag with the Airy
wave kinematics and the additional linear damping (``[hybrid]`` of ``cases/oc3_hywind.toml``).

Partitions (the known part; the rest, ``F_bb = F_tot − Σ known``, is what a network would take):

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

For each, α, β, γ are regressed (matrix form, docs/THEORY.md §1–3b), identifiability is judged
per DOF and for the surge–pitch coupling at the stated force accuracies, and the lagged-coupling
verdict is the spectral radius of the one-step amplification matrix with the residual's α, β, γ
as the surrogate's (§4c; its added-mass part ρ((M + A_k)⁻¹ α)). The observed behaviour of the
partitions with linear known parts (1–3) is a lagged run of that very surrogate (α z̈_lag + β ż
+ γ z plus the reference remainder, so it reproduces the reference exactly when stable) from a
slightly perturbed start; the network partitions are observed with real networks
(:mod:`hybridwsi.report.fowt_hybrid`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.cummins import simulate
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
from hybridwsi.waves import JONSWAP

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
    hs, a_inf = known_from(hist, None, ["hydrostatic", "added_mass_inf"])
    a_diag = AddedMass(np.diag(np.diag(a_inf.value)))
    memory = RadiationMemory.from_history(hist)
    exc = PrescribedForce("F_exc")
    rest = [memory, damping, exc]
    return {
        "1": [],
        "2": [hs, mooring_linear],
        "3": [hs, mooring_linear, a_inf],
        "A_inf_to_network": [hs, mooring_linear, *rest],
        "A_inf_coupling_to_network": [hs, mooring_linear, a_diag, *rest],
        "recommended": [hs, mooring_linear, a_inf, *rest],
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


def diagnostic_markdown(diag: Mapping[str, Any], observed: Mapping[str, bool] | None = None
                        ) -> str:
    """The multi-DOF Table-1 analogue and the hand-over table."""
    observed = dict(observed or {})
    accs = list(diag["partitions"][0]["identifiable"])

    def ident(r: Mapping[str, Any], key: str) -> str:
        """Identifiable DOFs (or the coupling) at each stated accuracy, '/'-separated."""
        out = []
        for acc in accs:
            v = r["identifiable"][acc]
            out.append(("yes" if v[key] else "no") if key == "surge_pitch_coupling" else
                       (", ".join(d for d, ok in v["per_dof"].items() if ok) or "none"))
        return " / ".join(out)

    lines = ["### Diagnostic in several DOFs (surge, heave, pitch)", "",
             f"JONSWAP Hs {diag['history']['sea']['hs']} m, Tp {diag['history']['sea']['tp']} s, "
             f"{diag['history']['duration_s']:.0f} s, Δt {diag['history']['dt']} s; "
             f"ρ(M⁻¹A∞) = {diag['rho_M_inv_A_inf']:.3f} (surge alone A11/M11 = "
             f"{diag['added_mass_inf'][0][0] / diag['mass'][0][0]:.3f}).", "",
             "| partition | α diag [kg, kg, kg m²] | α surge–pitch [kg m] | γ diag [N/m, N/m, "
             f"N m/rad] | R² min | identifiable DOFs at {' / '.join(accs)} | surge–pitch "
             "coupling | ρ((M+A_k)⁻¹α) "
             "| lagged | observed |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in diag["partitions"]:
        a, g = np.asarray(r["alpha"]), np.asarray(r["gamma"])
        obs = r.get("observed", {}).get("observed_stable", observed.get(r["partition"]))
        obs_s = "—" if obs is None else ("stable" if obs else "unstable")
        lines.append(
            f"| {r['partition']} | {a[0, 0]:.4g}, {a[1, 1]:.4g}, {a[2, 2]:.4g} | "
            f"{a[0, 2]:.4g} / {a[2, 0]:.4g} | {g[0, 0]:.4g}, {g[1, 1]:.4g}, {g[2, 2]:.4g} | "
            f"{min(r['r2']):.4f} | {ident(r, 'per_dof')} | {ident(r, 'surge_pitch_coupling')} | "
            f"{r['added_mass_ratio']:.4f} | "
            f"{r['lagged_verdict']} | {obs_s} |")
    lines += ["", "| partition | left to the network | goes to | reason |", "|---|---|---|---|"]
    for r in diag["partitions"]:
        lines.append(f"| {r['partition']} | {r['left_to_network']} | {r['where']} | {r['reason']} |")
    return "\n".join(lines) + "\n"
