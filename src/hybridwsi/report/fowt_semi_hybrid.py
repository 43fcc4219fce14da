"""The OC4-DeepCwind semi's hybrid (issue 30 item 5): the one hybrid pipeline in oblique seas.

The "high-fidelity" reference is the case's full six-DOF model (:meth:`hybridwsi.casemodel.
CaseModel.simulate`: radiation state space, MoorPy's tabulated mooring F(q) − F0, every
member's Morison drag on the relative velocity with the Airy kinematics of the sea) in
long-crested JONSWAP seas travelling towards 30°. The partition is the 6×6 diagnostic's
``recommended`` one (:data:`hybridwsi.report.fowt_semi.SEMI_RESIDUAL`): hydrostatics, A∞,
radiation memory and excitation known (:data:`SEMI_HYBRID_PARTITION`), plus the case's linear
models (:func:`hybridwsi.surrogate.certified.case_linear`): the mooring linearised about rest
(−K q) and, with ``[hybrid] known_linear_drag``, the member drag's Borgman linearisation
(−B_lin ż), so the network learns :data:`LEFT_TO_NETWORK`. Training, certificate and held-out
errors are :func:`hybridwsi.surrogate.certified.train_model` (the ``hybridwsi hybrid --case``
path, network settings of the case's ``[hybrid.network]``); the held-out seas are rolled out
with the same pipeline from the reference's first window (no training loop here).

Predicted stability: the certificate's spectral radius ρ of the rollout's step map with the
network's trajectory-averaged Jacobian (:func:`hybridwsi.surrogate.rollout.check_stability`):
a perturbation grows or decays at σ = ln ρ / Δt. Observed: what ρ predicts, the growth of a
perturbation — the same rollout again from a first window offset by 1 % of std(z) per DOF,
the difference of the two runs (:func:`perturbation_rate`) — and the blow-up flag; the growth
of the error against the reference (RMS over the second half over the first) is recorded too,
but it is dominated by the forced mismatch, not by the free modes the certificate is about.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
import time
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from hybridwsi.casemodel import CaseModel
from hybridwsi.dofs import RIGID_DOFS, motion_unit
from hybridwsi.forces import summed_linear_coefficients
from hybridwsi.history import nrms_per_dof
from hybridwsi.surrogate.certified import CertifiedModel, case_linear, prepare_histories, \
    train_model
from hybridwsi.surrogate.network import target_force
from hybridwsi.surrogate.pipeline import HybridPipeline
from hybridwsi.waves import JONSWAP

#: known candidates of the diagnostic's recommended partition (the case's linearised mooring
#: is known besides them: :func:`case_linear`)
SEMI_HYBRID_PARTITION = "hydrostatic+added_mass_inf+radiation_memory+excitation"
#: what the network learns with the case's ``[hybrid] known_linear_drag``
LEFT_TO_NETWORK = "(member drag − (−B_lin ż)) + (tabulated mooring − (−K q))"
#: JONSWAP seas (γ 3.3): Hs [m], Tp [s], seed, heading [deg] (travelling towards)
SEMI_HYBRID_TRAIN = ({"hs": 4.0, "tp": 11.0, "seed": 1, "heading_deg": 30.0},
                     {"hs": 6.0, "tp": 12.0, "seed": 2, "heading_deg": 30.0})
#: held out: another Hs/Tp/seed at the training heading, and the same sea at 45° (the network
#: sees the elevation at the reference point only, not the heading)
SEMI_HYBRID_TEST = ({"hs": 5.0, "tp": 11.5, "seed": 3, "heading_deg": 30.0},
                    {"hs": 5.0, "tp": 11.5, "seed": 3, "heading_deg": 45.0})
#: frequency components of each sea (as the diagnostic's sea; Tp ≥ 10.1 s keeps them inside
#: the BEM's 2.5 rad/s)
N_COMPONENTS = 100
#: below this frequency [Hz] the motion is the slow drift of the surge, sway and yaw modes
#: (0.0088, 0.0088, 0.0126 Hz), above it the wave-frequency response (seas from 0.043 Hz)
LOW_FREQUENCY_HZ = 0.03
#: initial offset of the perturbed twin run, × std(z) per DOF: small enough for the network's
#: linear response, large enough to stay far above round-off over the run
PERTURBATION = 0.01


def semi_sea(spec: Mapping[str, Any]) -> JONSWAP:
    """The JONSWAP sea of ``{hs [m], tp [s], seed, heading_deg [deg]}``."""
    return JONSWAP(hs=float(spec["hs"]), tp=float(spec["tp"]), seed=int(spec["seed"]),
                   n_components=N_COMPONENTS, direction=math.radians(spec["heading_deg"]))


def sea_label(spec: Mapping[str, Any]) -> str:
    """``Hs 4 m, Tp 11 s, seed 1, 30°``."""
    return (f"Hs {spec['hs']:g} m, Tp {spec['tp']:g} s, seed {spec['seed']}, "
            f"{spec['heading_deg']:g}°")


def semi_case_model(system: Any, case: Any, dt: float) -> CaseModel:
    """The case's model on the report's coefficients and radiation state space (``system``,
    :class:`hybridwsi.report.fowt_semi.SemiSystem`: the same ``[bem]`` and ``[radiation]``
    fit, made once for the whole section instead of once per run)."""
    model = CaseModel.build(case, coeffs=system.coeffs)
    return dataclasses.replace(model, dt=float(dt), radiation_ss=system.radiation_ss)


def band_errors(hyb: xr.Dataset, ref: xr.Dataset, split_hz: float = LOW_FREQUENCY_HZ
                ) -> dict[str, np.ndarray]:
    """Per DOF, over the hybrid's times: RMS of the error below / above ``split_hz`` [Hz] and
    of the reference below it, each over the reference's RMS; the error's growth (RMS over
    the second half / over the first half)."""
    t = np.asarray(hyb["time"].values, float)
    z = np.asarray(hyb["z"].values, float)
    z_ref = np.asarray(ref["z"].sel(time=t, method="nearest").values, float)
    err = z - z_ref
    low = np.fft.rfftfreq(t.size, t[1] - t[0]) < split_hz

    def lowpass(x: np.ndarray) -> np.ndarray:
        spec = np.fft.rfft(x - x.mean(0), axis=0)
        return np.fft.irfft(spec * low[:, None], n=t.size, axis=0) + x.mean(0)

    def rms(x: np.ndarray) -> np.ndarray:
        return np.sqrt(np.mean(x ** 2, axis=0))

    scale = np.maximum(rms(z_ref), 1e-300)
    half = t.size // 2
    return {"low": rms(lowpass(err)) / scale, "wave": rms(err - lowpass(err)) / scale,
            "reference_low": rms(lowpass(z_ref)) / scale,
            "growth": rms(err[half:]) / np.maximum(rms(err[:half]), 1e-300)}


def drag_damping(model: CaseModel, hist: xr.Dataset, spec: Mapping[str, Any], ramp: float,
                 stride: int = 25) -> np.ndarray:
    """Trajectory-averaged ∂F_drag/∂ż (6×6) [N s/m ... N m s/rad] of the members' Morison
    drag along ``hist`` in its sea (central differences at every ``stride``-th sample): the
    damping the network's lag-0 β_s should approach."""
    drag = model.components(wave=semi_sea(spec), ramp=ramp)["morison"]
    t, v = np.asarray(hist["time"].values, float), np.asarray(hist["zdot"].values, float)
    steps = np.where(np.arange(6) < 3, 1e-4, 1e-6)  # m/s, rad/s
    out = []
    for k in range(int(ramp / (t[1] - t[0])), t.size, stride):
        cols = [(drag.ode_force(t[k], None, v[k] + e, None)
                 - drag.ode_force(t[k], None, v[k] - e, None)) / (2 * h)
                for e, h in zip(np.diag(steps), steps)]
        out.append(np.column_stack(cols))
    return np.mean(out, axis=0)


def train_semi_hybrid(model: CaseModel, train: Sequence[xr.Dataset], network: Mapping[str, Any],
                      mode: str = "lagged", folder: Path | None = None) -> CertifiedModel:
    """Train and certify the network of :data:`SEMI_HYBRID_PARTITION` on ``train`` (the
    predicted-unstable case accepted and recorded), saved into ``folder`` (a model folder of
    ``hybridwsi simulate --network``; default a temporary one, only to hash its content)."""
    pipe = HybridPipeline(SEMI_HYBRID_PARTITION, mode=mode, network=dict(network),
                          known_extra=case_linear(model), allow_unstable=True)
    names = [f"training sea {i + 1}" for i in range(len(train))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the partition predicted unstable: recorded
        cm = train_model(train, names, model, pipeline=pipe)
    if folder is None:
        with tempfile.TemporaryDirectory() as tmp:
            cm.save(tmp)
    else:
        cm.save(folder)
    return cm


def perturbed(case: xr.Dataset, span: int) -> tuple[xr.Dataset, np.ndarray]:
    """``case`` with the motion of the network's first window (``span`` samples) offset by
    :data:`PERTURBATION` × std(z) per DOF, and that offset [m, rad]."""
    z = np.asarray(case["z"].values, float).copy()
    dz = PERTURBATION * np.maximum(z.std(0), 1e-12)
    z[:span] += dz
    return case.assign(z=(("time", "dof"), z, dict(case["z"].attrs))), dz


def perturbation_rate(base: xr.Dataset, twin: xr.Dataset, dz: np.ndarray) -> float:
    """Observed growth rate σ [1/s] of a perturbation of the hybrid: the difference of the
    perturbed twin's motion from the run's, per DOF over its initial offset ``dz``, RMS over
    the last quarter of the run against the third (where the least damped mode dominates),
    ln(ratio) / (T/4). What the certificate's spectral radius predicts (σ = ln ρ / Δt)."""
    d = (np.asarray(twin["z"].values, float) - np.asarray(base["z"].values, float)) / dz
    n = d.shape[0] // 4
    if n < 2 or not np.all(np.isfinite(d)):
        return math.inf
    t = np.asarray(base["time"].values, float)
    r3, r4 = (float(np.sqrt(np.mean(d[k * n:(k + 1) * n] ** 2))) for k in (2, 3))
    return math.log(max(r4, 1e-300) / max(r3, 1e-300)) / (t[4 * n - 1] - t[3 * n - 1])


def held_out(cm: CertifiedModel, model: CaseModel, refs: Sequence[xr.Dataset],
             specs: Sequence[Mapping[str, Any]]) -> tuple[list[dict[str, Any]], list]:
    """Roll the certified pipeline out in each held-out sea (its reference's time grid,
    ``F_exc``, ``eta`` and first window), and again from a perturbed first window
    (:func:`perturbed`): per sea the RMS error per DOF, by band, its growth, the blow-up flag
    and the perturbation's observed growth rate (:func:`perturbation_rate`); and the hybrid
    histories. Observed stable: no blow-up, finite errors, the perturbation not growing."""
    cases = prepare_histories(refs, [sea_label(s) for s in specs], model)
    span = cm.pipeline.network_.spec_.span
    twins, offsets = zip(*(perturbed(c, span) for c in cases))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = cm.pipeline.rollout([*cases, *twins])
    hybs, twin_runs = res.histories[:len(cases)], res.histories[len(cases):]
    rows = []
    for spec, hyb, twin, dz, ref, blew in zip(specs, hybs, twin_runs, offsets, refs,
                                              res.blew_up):
        bands = band_errors(hyb, ref)
        total = nrms_per_dof(hyb, ref)
        sigma = perturbation_rate(hyb, twin, dz)
        row = {"sea": dict(spec), "blew_up": bool(blew),
               "nrms_z": dict(zip(RIGID_DOFS, total.tolist())),
               **{f"nrms_z_{k}": dict(zip(RIGID_DOFS, v.tolist())) for k, v in bands.items()},
               "perturbation_rate": sigma}
        row["observed_stable"] = bool(not blew and np.all(np.isfinite(total)) and sigma <= 0.0)
        rows.append(row)
    return rows, list(hybs)


def run_semi_hybrid(system: Any, case: Any, folder: Path, *, quick: bool = False,
                    log: Any = lambda msg: None) -> tuple[dict[str, Any], Any]:
    """The section's hybrid: references, training, held-out rollouts, evidence. Returns the
    JSON document (``hybrid.json``) and the rollout figure with its data."""
    import torch  # deferred: the optional dependency of the hybrid

    torch.set_num_threads(1)  # a small network on a shared machine: threads only contend
    cfg = dict(case["hybrid"])
    dt, ramp = float(cfg["dt"]), float(cfg["ramp"])
    duration = float(cfg["quick_duration"] if quick else cfg["duration"])
    model = semi_case_model(system, case, dt)
    t0 = time.time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the radiation fit's known tolerance warning
        refs = [model.simulate(duration=duration, dt=dt, wave=semi_sea(s), ramp=ramp)
                for s in (*SEMI_HYBRID_TRAIN, *SEMI_HYBRID_TEST)]
    train, test = refs[:len(SEMI_HYBRID_TRAIN)], refs[len(SEMI_HYBRID_TRAIN):]
    t_ref = time.time() - t0
    log(f"hybrid references ({t_ref:.0f} s)")
    net = {**cfg["network"], "hidden": tuple(cfg["network"]["hidden"])}
    t0 = time.time()
    cm = train_semi_hybrid(model, train, net, cfg.get("mode", "lagged"),
                           folder / "hybrid_model")
    t_train = time.time() - t0
    rows, hybs = held_out(cm, model, test, SEMI_HYBRID_TEST)
    log(f"hybrid trained and rolled out ({t_train:.0f} s)")
    doc = semi_hybrid_doc(cm, rows, model, train[0], duration=duration, dt=dt, ramp=ramp)
    doc["wall_s"] = {"references": t_ref, "train_certify_rollout": t_train}
    fig = semi_hybrid_figure(hybs[0], test[0], SEMI_HYBRID_TEST[0])
    return doc, fig


def semi_hybrid_doc(cm: CertifiedModel, rows: list[dict[str, Any]], model: CaseModel,
                    first: xr.Dataset, *, duration: float, dt: float, ramp: float
                    ) -> dict[str, Any]:
    """``hybrid.json``: settings, partition (known components and what the network learns),
    certificate, training and held-out errors, the drag-damping evidence."""
    doc, cert = cm.doc, cm.doc["certificate"]
    known = cm.pipeline.known_
    residual = target_force(first, "F_bb", known=known, force="F_tot")
    # what the network should learn: the drag's and the mooring's departures from the case's
    # linear models of them (−B ż, −K q)
    _, b_lin, c_lin = summed_linear_coefficients(case_linear(model), 6)
    learned = (np.asarray(first["F_morison"].values, float)
               + np.asarray(first["F_mooring"].values, float)
               + np.asarray(first["z"].values, float) @ c_lin.T
               + np.asarray(first["zdot"].values, float) @ b_lin.T)
    beta_net = np.diag(np.asarray(cert["network"]["beta"]))
    beta_drag = np.diag(drag_damping(model, first, SEMI_HYBRID_TRAIN[0], ramp))
    return {
        "settings": {"dt": dt, "duration_s": duration, "ramp_s": ramp,
                     "n_components": N_COMPONENTS, "train": list(SEMI_HYBRID_TRAIN),
                     "test": list(SEMI_HYBRID_TEST), "mode": doc["coupling"]["mode"],
                     "network": doc["features"]["network"]},
        "partition": {"candidates": list(doc["partition"]["known"]),
                      "known": doc["partition"]["components"],
                      "network_inputs": doc["partition"]["network_inputs"],
                      "left_to_network": LEFT_TO_NETWORK if b_lin.any() else
                      "member drag + (tabulated mooring − (−K q))",
                      "residual_is_drag_plus_mooring_nonlinearity": float(
                          np.max(np.abs(residual - learned)) / np.max(np.abs(learned)))},
        "certificate": {k: cert[k] for k in ("dt", "spectral_radius", "added_mass_ratio",
                                            "max_stable_dt", "stable")},
        "predicted_stable": bool(cert["stable"]),
        # the predicted growth of the error over a half run: exp(σ T/2), σ = ln ρ / Δt
        "predicted_growth_half_run": float(np.exp(
            math.log(max(cert["spectral_radius"], 1e-300)) / dt * duration / 2)),
        "predicted_rate": math.log(max(cert["spectral_radius"], 1e-300)) / dt,
        "observed_rate": max(r["perturbation_rate"] for r in rows),
        "training_held_out": doc["held_out"],
        "held_out": rows,
        "observed_stable": all(r["observed_stable"] for r in rows),
        "agree": bool(cert["stable"]) == all(r["observed_stable"] for r in rows),
        "damping_evidence": {
            "dofs": list(RIGID_DOFS), "network_beta_diag": beta_net.tolist(),
            "known_drag_diag": np.diag(b_lin).tolist(),
            "drag_beta_diag": beta_drag.tolist(),
            # the diagnostic's linear regression of the same residual (certificate)
            "regression_beta_diag": np.diag(np.asarray(cert["diagnostic"]["beta"])).tolist()},
    }


def semi_hybrid_figure(hyb: xr.Dataset, ref: xr.Dataset, spec: Mapping[str, Any]
                       ) -> tuple[Any, xr.Dataset]:
    """The held-out rollout on the reference's axes, one panel per DOF [m or rad] against
    time [s], and the data behind it."""
    t = np.asarray(hyb["time"].values, float)
    z_ref = np.asarray(ref["z"].sel(time=t, method="nearest").values, float)
    z = np.asarray(hyb["z"].values, float)
    fig, axes = plt.subplots(3, 2, figsize=(10, 8), sharex=True)
    for i, (ax, dof) in enumerate(zip(axes.T.ravel(), RIGID_DOFS)):
        ax.plot(t, z_ref[:, i], "k-", lw=1.0, label="reference (case model)")
        ax.plot(t, z[:, i], "r--", lw=0.8, label="hybrid (network in the loop)")
        ax.set_ylabel(f"{dof} [{motion_unit(dof)}]")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle(f"OC4 semi hybrid, held-out sea {sea_label(spec)}", fontsize=9)
    fig.tight_layout()
    ds = xr.Dataset({"z_reference": (("time", "dof"), z_ref), "z_hybrid": (("time", "dof"), z)},
                    coords={"time": t, "dof": list(RIGID_DOFS)},
                    attrs={"sea": sea_label(spec), "units": ", ".join(
                        f"{d}: {motion_unit(d)}" for d in RIGID_DOFS)})
    return fig, ds


def semi_hybrid_markdown(doc: Mapping[str, Any]) -> str:
    """The hybrid table of the semi's report section."""
    cert, s = doc["certificate"], doc["settings"]
    verdict = "stable" if doc["predicted_stable"] else "unstable"
    lines = [
        f"Hybrid through the one pipeline (`train_model`, partition `{SEMI_HYBRID_PARTITION}` "
        f"+ the case's linear models: the network learns {doc['partition']['left_to_network']} "
        f"from z, ż, η), {len(s['train'])} training seas of {s['duration_s']:.0f} s at 30°, "
        f"Δt {s['dt']:g} s, {s['mode']}; predicted {verdict} (spectral radius "
        f"{cert['spectral_radius']:.5f}, a perturbation's rate σ = ln ρ/Δt = "
        f"{doc['predicted_rate']:.2e} 1/s, |α_s|/(M+A_k) = {cert['added_mass_ratio']:.3f}); "
        f"observed: a perturbation's rate {doc['observed_rate']:.2e} 1/s (the rollout again "
        "from a first window offset by 1 % of std(z), the two runs' difference over the last "
        "quarter against the third); the prediction "
        f"{'agrees' if doc['agree'] else 'does not agree'} with the observation. "
        "Error = RMS(z_hybrid − z_ref) / RMS(z_ref) per DOF [%] (below "
        f"{LOW_FREQUENCY_HZ:g} Hz / above it); growth = error RMS second half / first half.",
        "", "| sea | observed | " + " | ".join(RIGID_DOFS)
        + " | growth (max) | perturbation σ [1/s] |", "|---" * 10 + "|"]
    for i, e in enumerate(doc["training_held_out"]["nrms_z"]):
        lines.append(f"| training sea {i + 1}, last 20 % | – | "
                     + " | ".join(f"{100 * e[d]:.1f}" for d in RIGID_DOFS) + " | – | – |")
    for r in doc["held_out"]:
        obs = "blew up" if r["blew_up"] else ("stable" if r["observed_stable"] else "diverged")
        cells = [f"{100 * r['nrms_z'][d]:.1f} ({100 * r['nrms_z_low'][d]:.1f} / "
                 f"{100 * r['nrms_z_wave'][d]:.1f})" for d in RIGID_DOFS]
        lines.append(f"| held out: {sea_label(r['sea'])} | {obs} | " + " | ".join(cells)
                     + f" | {max(r['nrms_z_growth'].values()):.2f} | "
                     f"{r['perturbation_rate']:.2e} |")
    ev = doc["damping_evidence"]
    lines += ["", "Damping of the coupled step, known B_lin − network's lag-0 β_s, against the "
              "drag's own −∂F/∂ż averaged along training sea 1 (diagonal; N s/m, N m s/rad): "
              + ", ".join(f"{d} {k - b:.3g} / {-g:.3g}" for d, k, b, g in zip(
                  ev["dofs"], ev["known_drag_diag"], ev["network_beta_diag"],
                  ev["drag_beta_diag"])) + ".",
              "", "![hybrid rollout](fowt_semi/hybrid_rollout.png)", ""]
    return "\n".join(lines)
