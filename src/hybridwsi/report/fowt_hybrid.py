"""The report's floating-wind hybrid (OC3-Hywind, issue 13 items 7–8): tables, figure, files.

The study (reference seas, the multi-DOF diagnostic, a network per partition, stability
predicted and observed, the 3-hour sea) is :func:`hybridwsi.surrogate.fowt.run_study`;
:func:`run_fowt_hybrid` runs it and writes ``diagnostic.json``, ``hybrid.json`` and
``hybrid_rollout.png/.nc``, and returns the report's Markdown (:func:`diagnostic_markdown`,
:func:`hybrid_markdown`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from hybridwsi.dofs import motion_unit
from hybridwsi.forces import KnownComponent
from hybridwsi.report.plots import save
from hybridwsi.surrogate.fowt import DIVERGED_PERCENT, run_study


def json_safe(value: Any) -> Any:
    """``value`` with non-finite floats as None and tuples as lists (strict JSON)."""
    if isinstance(value, Mapping):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if np.isfinite(value) else None
    if isinstance(value, (np.integer, np.bool_)):
        return value.item()
    return value


def rollout_figure(hybrid: xr.Dataset, ref: xr.Dataset, title: str
                   ) -> tuple[plt.Figure, xr.Dataset]:
    """Held-out rollout against the reference, one panel per DOF (units per DOF)."""
    dofs = [str(d) for d in hybrid["dof"].values]
    t = hybrid["time"].values
    z_ref = ref["z"].sel(time=t, method="nearest").values
    fig, axes = plt.subplots(len(dofs), 1, figsize=(8, 7), sharex=True)
    for i, (ax, dof) in enumerate(zip(axes, dofs)):
        ax.plot(t, z_ref[:, i], "k-", lw=1.2, label="reference (nonlinear Cummins)")
        ax.plot(t, hybrid["z"].values[:, i], "r--", lw=1, label="hybrid (network in the loop)")
        ax.set_ylabel(f"{dof} [{motion_unit(dof)}]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[0].set_title(title, fontsize=9)
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    ds = xr.Dataset({"z_reference": (("time", "dof"), z_ref),
                     "z_hybrid": (("time", "dof"), hybrid["z"].values)},
                    coords={"time": t, "dof": dofs},
                    attrs={"title": title,
                           "units": ", ".join(f"{d}: {motion_unit(d)}" for d in dofs)})
    return fig, ds


def _observed(e: Mapping[str, Any]) -> str:
    """'stable', 'blew up' or 'diverged' (error > DIVERGED_PERCENT) for one rollout entry."""
    if any(e["blew_up"]):
        return "blew up"
    return "stable" if e["observed_stable"] else "diverged"


def hybrid_markdown(hyb: Mapping[str, Any]) -> str:
    """The hybrid table."""
    mode = hyb["settings"]["mode"]
    lines = ["### Hybrid (network in the loop), held-out seas", "",
             f"Networks {hyb['settings']['network']['hidden']} ({mode} rollouts, Δt "
             f"{hyb['settings']['dt']} s); error = RMS(z_hybrid − z_ref) in % of RMS z_ref, "
             "worst held-out sea; observed unstable = blew up (|z| > 20× the reference or a "
             f"saw-tooth z̈), or diverged (error > {DIVERGED_PERCENT:g} % on a DOF).", "",
             "| partition | coupling | ρ((M+A_k)⁻¹α_s) | spectral radius | predicted | observed "
             "| surge % | heave % | pitch % |", "|---|---|---|---|---|---|---|---|---|"]
    for p in hyb["partitions"]:
        for m in dict.fromkeys(("lagged", mode)):
            e = p[m]
            worst = {d: max(c[d] for c in e["rollout_error_percent_rms"])
                     for d in e["rollout_error_percent_rms"][0]}
            lines.append(
                f"| {p['partition']} | "
                f"{m}{' ×' + str(e['corrections']) if e['corrections'] else ''}"
                f" | {e['added_mass_ratio']:.3f} | {e['spectral_radius']:.4f} | "
                f"{'stable' if e['predicted_stable'] else 'unstable'} | "
                f"{_observed(e)} | "
                + " | ".join(f"{worst[d]:.3g}" for d in ("Surge", "Heave", "Pitch")) + " |")
    lr = hyb.get("long_run")
    if lr:
        lines += ["", f"Recommended partition over a {lr['duration_s'] / 3600:.2f}-hour sea: "
                  f"predicted {'stable' if lr['predicted_stable'] else 'unstable'}, "
                  f"{'blew up' if lr['blew_up'] else 'stable'}; RMS surge/heave/pitch "
                  f"{lr['rms_hybrid']['Surge']:.3g} m / {lr['rms_hybrid']['Heave']:.3g} m / "
                  f"{lr['rms_hybrid']['Pitch']:.3g} rad (linear Cummins "
                  f"{lr['rms_linear_reference']['Surge']:.3g} / "
                  f"{lr['rms_linear_reference']['Heave']:.3g} / "
                  f"{lr['rms_linear_reference']['Pitch']:.3g}); prediction and rollout "
                  f"{lr['wall_s']:.1f} s."]
    return "\n".join(lines) + "\n"


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
        lines.append(f"| {r['partition']} | {r['left_to_network']} | {r['where']} | "
                     f"{r['reason']} |")
    return "\n".join(lines) + "\n"


def run_fowt_hybrid(folder: Path, case: Mapping[str, Any], coeffs: xr.Dataset,
                    mooring_linear: KnownComponent, damping: KnownComponent, *,
                    write_json: Callable[[Path, Any], None], quick: bool = False,
                    log: Callable[[str], None] = lambda m: None) -> str:
    """Items 7 and 8: write ``diagnostic.json``, ``hybrid.json`` (with ``write_json``;
    non-finite numbers as null), ``hybrid_rollout.png/.nc`` into ``folder`` and return the
    Markdown tables.

    ``mooring_linear`` is −K q on ``[hybrid] dofs`` (MoorPy's K), ``damping`` the additional
    linear damping (:func:`hybridwsi.casemodel.linear_components`).
    """
    study = run_study(case, coeffs, mooring_linear, damping, quick=quick, log=log)
    write_json(folder / "diagnostic.json", json_safe(study.diagnostic))
    write_json(folder / "hybrid.json", json_safe(study.hybrid))
    log("diagnostic.json, hybrid.json")

    first = study.settings["test"][0]
    fig, ds = rollout_figure(study.shown.histories[0], study.test[0],
                             f"OC3-Hywind recommended hybrid, held-out sea Hs "
                             f"{first['hs']} m, Tp {first['tp']} s")
    save(fig, folder / "hybrid_rollout.png")
    ds.to_netcdf(folder / "hybrid_rollout.nc")
    entries = study.hybrid["partitions"]
    observed = {p["partition"]: p["lagged"]["observed_stable"] for p in entries}
    return (diagnostic_markdown(study.diagnostic, observed) + "\n"
            + hybrid_markdown(study.hybrid) + "\n"
            + "![hybrid rollout](fowt/hybrid_rollout.png)\n")
