"""The 3-DOF hybrid of OC3-Hywind (issue 13 item 8) and the fowt report's items 7–8.

A :class:`~hybridwsi.surrogate.network.ForceNetwork` learns each network partition's residual of
:mod:`hybridwsi.report.fowt_diagnostic` (surge, heave, pitch) from irregular seas (the
``[hybrid] train`` seas); :func:`~hybridwsi.surrogate.rollout.check_stability` (the network's
linearisation in the very step map of the rollout) predicts stability before each rollout; the
held-out seas (``[hybrid] test``) give the rollout error per DOF (% of the reference's RMS);
each partition is rolled out both ``lagged`` (the diagnostic's setting) and in the configured
mode (``corrected``); the recommended partition then runs the ``long`` sea (3 hours).

The 3-hour case is a linear Cummins run of the same sea (it supplies the time grid, ``eta``,
``F_exc`` and the initial window; a nonlinear reference of that length would cost more than
the rollout): the check there is stability (bounded, no drift), and the hybrid's RMS motion is
reported beside the linear one.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from hybridwsi.cummins import build_system, simulate
from hybridwsi.dofs import motion_unit
from hybridwsi.forces import KnownComponent, MooringForce
from hybridwsi.report import fowt_diagnostic as fd
from hybridwsi.report.plots import save
from hybridwsi.surrogate.network import ForceNetwork
from hybridwsi.surrogate.rollout import check_stability, corrections_for, rollout

#: rollout error [% of the reference RMS, any DOF] above which a run that did not blow up still
#: counts as unstable: a growing mode held bounded only by the network's saturation (an
#: uncorrelated response of the right size would give ~141 %)
DIVERGED_PERCENT = 100.0

def nrms_percent(hist: xr.Dataset, ref: xr.Dataset) -> list[float]:
    """RMS of (hybrid − reference) z per DOF over the hybrid's times, in % of the reference's
    RMS z on those times (inf when the hybrid is not finite)."""
    t = hist["time"].values
    z_ref = ref["z"].sel(time=t, method="nearest").values
    z = hist["z"].values
    if not np.all(np.isfinite(z)):
        return [float("inf")] * z.shape[1]
    err = np.sqrt(np.mean((z - z_ref) ** 2, axis=0))
    return (100.0 * err / np.sqrt(np.mean(z_ref ** 2, axis=0))).tolist()


def run_partition(name: str, known: Sequence[KnownComponent], net_kw: Mapping[str, Any],
                  train: Sequence[xr.Dataset], test: Sequence[xr.Dataset], mass: np.ndarray,
                  mode: str) -> tuple[dict[str, Any], ForceNetwork, Any]:
    """Train the partition's network (``net_kw``: ForceNetwork settings with ``inputs``),
    predict, roll out (lagged and ``mode``) on the held-out seas.

    Returns the JSON entry, the network and the ``mode`` rollout (for the figure).
    """
    t0 = time.time()
    net = ForceNetwork(**{**net_kw, "inputs": tuple(net_kw["inputs"])}).fit(list(train), "F_bb", known=list(known))
    entry: dict[str, Any] = {"partition": name, "network": {k: (list(v) if isinstance(v, tuple) else v)
                                         for k, v in net_kw.items()},
                             "known": [k.describe() for k in known],
                             "left_to_network": fd.RESIDUAL[name],
                             "train_s": time.time() - t0,
                             "r2_held_out": float(np.mean([net.score(h, "F_bb", known=list(known))
                                                           for h in test]))}
    res_mode = None
    for m in dict.fromkeys(("lagged", mode)):
        pred = check_stability(net, train, mass=mass, known=known, mode=m)
        n_corr = corrections_for(pred.added_mass_ratio) if m == "corrected" else 1
        if n_corr != 1:
            pred = check_stability(net, train, mass=mass, known=known, mode=m,
                                   corrections=n_corr)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # unstable ones run on purpose
            res = rollout(net, list(test), mass=mass, known=known, mode=m, corrections=n_corr,
                          check=False)
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
    """The recommended partition over the long sea: predicted, blown up, RMS per DOF, drift."""
    pred = check_stability(net, case_hist, mass=mass, known=known, mode=mode, stride=20)
    n_corr = corrections_for(pred.added_mass_ratio) if mode == "corrected" else 1
    t0 = time.time()
    res = rollout(net, [case_hist], mass=mass, known=known, mode=mode, corrections=n_corr,
                  check=False)
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
    dofs = _dofs(hybrid)
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
                f"| {p['partition']} | {m}{' ×' + str(e['corrections']) if e['corrections'] else ''}"
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
                  f"{lr['rms_linear_reference']['Pitch']:.3g}); rollout {lr['wall_s']:.1f} s."]
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
    import torch

    torch.set_num_threads(1)  # tiny networks on a shared machine
    cfg = fd.hybrid_settings(case, quick)
    dofs, dt = list(cfg["dofs"]), float(cfg["dt"])
    mooring = MooringForce.from_case(case, dofs)
    ss = build_system(coeffs, dofs=dofs, dt=dt).ss  # one fit for every sea

    def histories(seas: Sequence[Mapping[str, Any]]) -> list[xr.Dataset]:
        return [fd.irregular_history(coeffs, case, mooring, damping, s, dofs=dofs,
                                     duration=cfg["duration"], dt=dt, ramp=cfg["ramp"],
                                     radiation_ss=ss) for s in seas]

    train, test = histories(cfg["train"]), histories(cfg["test"])
    log("irregular-sea references")
    diag = fd.diagnostic(train, mooring_linear, damping, cfg)
    write_json(folder / "diagnostic.json", json_safe(diag))
    log("diagnostic.json")

    mass = fd.rigid_mass(train[0])
    parts = fd.partitions(train[0], mooring_linear, damping)
    entries, nets, shown = [], {}, None
    for name, own in cfg["partitions"].items():
        entry, net, res = run_partition(name, parts[name], {**cfg["network"], **own}, train,
                                        test, mass, cfg["mode"])
        entries.append(entry)
        nets[name] = net
        if name == "recommended":
            shown = res
        log(f"hybrid {name}")
    hyb: dict[str, Any] = {"settings": {k: cfg[k] for k in ("dofs", "dt", "duration", "ramp",
                                                           "train", "test", "mode")}
                           | {"network": {**cfg["network"], "hidden": list(cfg["network"]["hidden"])}},
                           "partitions": entries}
    # the long case: linear Cummins (linearised mooring, additional damping) of the same sea
    long_hist = simulate(coeffs, dofs=dofs, duration=float(cfg["long_duration"]), dt=dt,
                         wave=fd.sea(cfg["long"]), ramp=cfg["ramp"], radiation_ss=ss,
                         forces=[mooring_linear, damping])
    hyb["long_run"] = {"sea": cfg["long"], **long_run(nets["recommended"],
                                                      parts["recommended"], long_hist, mass,
                                                      cfg["mode"])}
    hyb["all_agree"] = all(p[m]["agree"] for p in entries for m in ("lagged", cfg["mode"]))
    write_json(folder / "hybrid.json", json_safe(hyb))
    log("hybrid.json and the long run")

    fig, ds = rollout_figure(shown.histories[0], test[0],
                             f"OC3-Hywind recommended hybrid, held-out sea Hs "
                             f"{cfg['test'][0]['hs']} m, Tp {cfg['test'][0]['tp']} s")
    save(fig, folder / "hybrid_rollout.png")
    ds.to_netcdf(folder / "hybrid_rollout.nc")
    observed = {p["partition"]: p["lagged"]["observed_stable"] for p in entries}
    return (fd.diagnostic_markdown(diag, observed) + "\n" + hybrid_markdown(hyb) + "\n"
            + "![hybrid rollout](fowt/hybrid_rollout.png)\n")
