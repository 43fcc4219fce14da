"""The hybrid on the MoorDyn-coupled OC3-Hywind reference in 6 DOFs (issue 29 items 5-6): the
set-up (seas, winds, the two partitions, the tension head, the runs) and the metrics of
``scripts/oc3_moordyn_hybrid.py``
and ``benchmarks/bench_mooring.py --hybrid``, and the report's table and spectra from the
shipped results ``hybridwsi/data/oc3_moordyn_hybrid.{json,nc}`` (docs/OC3_HYWIND.md "The
hybrid on the MoorDyn-coupled reference"). The report's path runs no MoorDyn: it reads the
shipped files.

Metrics (per held-out sea, after the ramp; ``ref`` = the MoorDyn-coupled run):

- ``nrms``: RMS(x − x_ref) / RMS(x_ref) — the pipeline's convention
  (:func:`hybridwsi.history.nrms_per_dof`), the mean offset included;
- ``nrms_dynamic``: RMS(x − x_ref) / std(x_ref) — the same error over the fluctuation's size
  (the stricter number: the 13 m surge offset under the thrust does not dilute it);
- ``fluctuation``: RMS((x − x̄) − (x_ref − x̄_ref)) / std(x_ref) — the error of the
  fluctuation alone (the mean's bias left out): for the tension, what the line dynamics and
  the tension head are judged by;
- ``low_energy``: the energy of the surge spectrum below 0.1 rad/s (the slow drift, the
  surge resonance at 0.051 rad/s), model / reference − 1;
- the most loaded line: the line of the largest mean fairlead tension of the reference.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import json
import time
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import scipy.signal
import xarray as xr

from hybridwsi.casemodel import CaseModel, linear_components
from hybridwsi.cummins.forcing import excitation
from hybridwsi.diagnostic.partition import build_candidates
from hybridwsi.files import DATA, read_netcdf
from hybridwsi.forces.external import PrescribedForce
from hybridwsi.forces.linear import LinearDamping, mass_from
from hybridwsi.history import make_history
from hybridwsi.hydro import coefficients as cf
from hybridwsi.report.plots import save
from hybridwsi.surrogate.network import ForceNetwork
from hybridwsi.surrogate.pipeline import HybridPipeline
from hybridwsi.waves import JONSWAP

__all__ = ["HEAD", "HELD", "LOW_OMEGA", "MODELS", "NETWORKS", "PARTITIONS", "SHIPPED", "TRAIN",
           "case_model", "errors", "fit_tension_head", "head_tensions", "hybrid_case",
           "known_part", "linear_offset", "load_shipped", "long_run", "metrics", "prepared",
           "psd", "report_section", "run_hybrid", "series", "simulate", "spectra",
           "spectra_figure", "stored", "tension_dynamics", "with_quasi_static",
           "with_tensions"]

#: the results of scripts/oc3_moordyn_hybrid.py (``.json`` and ``.nc``) and its network
#: (``.pt`` and ``.json``, :meth:`ForceNetwork.load`)
SHIPPED = DATA / "oc3_moordyn_hybrid"
NETWORKS = {"hybrid": DATA / "oc3_moordyn_hybrid_network",
            "hybrid_lin": DATA / "oc3_moordyn_hybrid_lin_network"}
#: the tension head (:func:`fit_tension_head`), shared by both hybrids
HEAD = DATA / "oc3_moordyn_hybrid_tension_head"

#: rad/s: the band of the slow-drift energy criterion (issue 29: "below 0.1 rad/s")
LOW_OMEGA = 0.1
#: the models of the table and the spectra, in this order
MODELS = ("linear", "table", "moordyn", "hybrid", "hybrid_lin")
LABELS = {"linear": "linear", "table": "quasi-static (MoorPy table)",
          "moordyn": "MoorDyn-coupled reference",
          "hybrid": "hybrid (quasi-static mooring + rotor known)",
          "hybrid_lin": "hybrid (linear known part)"}
#: units of the series
UNITS = {"surge": "m", "sway": "m", "heave": "m", "roll": "rad", "pitch": "rad", "yaw": "rad",
         "tension": "N", "tension_qs": "N"}
#: resolution of the shipped series per unit (stored as scaled int32: 0.1 mm, 1 µrad, 1 N;
#: the metrics are computed on the series at this resolution, :func:`stored`)
RESOLUTION = {"m": 1e-4, "rad": 1e-6, "N": 1.0}
#: Welch segment [s]: 3.4 surge periods of 124 s in a 1800 s record, 5 segments (50 % overlap)
SEGMENT = 600.0
#: rad/s: marked on the spectra (surge, heave and pitch natural frequencies of the linear
#: system, docs/OC3_HYWIND.md "Natural frequencies")
MARKS = {0.0506: ("surge (at rest)", "center"), 0.2038: ("heave", "right"),
         0.2123: ("pitch", "left")}
#: Welch segment of the figure [s]: finer in ω (0.0052 rad/s) to show the slow-drift band
FIGURE_SEGMENT = 1200.0


# ------------------------------------------------------------------------------- the set-up
DOFS = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
DT = 0.1
RAMP = 60.0
TI = 0.1
#: the known part of the partition besides the case's components (diagnostic candidates)
CANDIDATES = ("hydrostatic", "added_mass_inf", "radiation_memory", "excitation")
#: seas: Hs [m], Tp [s], wave seed, mean hub wind [m/s], wind seed. Training winds 7-9 m/s
#: (below rated: region 2, positive aerodynamic damping); held-out seas AND winds between them
TRAIN = {"train1": (4.0, 10.0, 1, 7.0, 1), "train2": (6.0, 12.0, 2, 9.0, 2),
         "train3": (5.0, 11.0, 3, 8.0, 3)}
HELD = {"held1": (4.5, 10.5, 101, 8.5, 101), "held2": (5.5, 11.5, 102, 7.5, 102)}
LONG = {"long": (5.0, 11.0, 201, 8.0, 201)}
#: the coupling of the network (the case's [hybrid] mode)
MODE = "corrected"
#: the inputs of the force network and of the tension head
INPUTS = ("z", "zdot", "eta")
#: the two partitions (model name -> what the network learns; docs/OC3_HYWIND.md):
#: ``hybrid`` the diagnostic's recommendation, the quasi-static mooring and the rotor in the
#: ODE (nonlinear components with Numba kernels, evaluated inside the compiled loop);
#: ``hybrid_lin`` everything known linear (the mooring linearised about rest, the rotor's wind
#: force as a time series and its aerodynamic damping at the mean wind)
PARTITIONS = {
    "hybrid": "MoorDyn - quasi-static mooring + slow drift + drag",
    "hybrid_lin": "MoorDyn + K z (its linearisation about rest removed) + slow drift + drag + "
                  "the rotor's force beyond F(U(t)) - B_aero zdot",
}


def case_model(sea: tuple, mooring: str, *, linear: bool = False) -> CaseModel:
    """The OC3 model of one sea's wind: operating rotor, turbulent wind, slow drift, drag
    (``linear``: no drag, no drift: the mooring is added as its linearisation)."""
    _, _, _, wind, wseed = sea
    forces = {"drift": not linear, "morison": not linear, **({"mooring": "none"} if linear
                                                              else {})}
    return CaseModel.build("oc3_hywind", dofs=DOFS, dt=DT, mooring=None if linear else mooring,
                           overrides={
                               "rotor": {"state": "operating", "wind_speed": wind,
                                         "turbulence_intensity": TI, "wind_seed": wseed},
                               "forces": forces})


def jonswap(sea: tuple) -> JONSWAP:
    """The JONSWAP sea of ``(Hs [m], Tp [s], seed, ...)`` (γ 3.3, 200 components)."""
    hs, tp, seed = sea[:3]
    return JONSWAP(hs=hs, tp=tp, seed=seed)


def simulate(kind: str, sea: tuple, duration: float) -> xr.Dataset:
    """One run: ``moordyn`` (the reference), ``table`` (quasi-static mooring, else the same),
    ``linear`` (linearised mooring, no drag, no drift, the same rotor and wind)."""
    if kind != "linear":
        return case_model(sea, kind).simulate(duration=duration, dt=DT, wave=jonswap(sea),
                                              ramp=RAMP)
    model = case_model(sea, "none", linear=True)
    lin = linear_components(model.case, DOFS)
    z0 = linear_offset(model, lin[0].linear_coefficients(len(DOFS))[2])
    return model.simulate(duration=duration, dt=DT, wave=jonswap(sea), ramp=RAMP,
                          extra={"linear_mooring": lin[0]}, from_offset=False, z0=z0)


def known_part(hist: xr.Dataset, model: CaseModel, partition: str, *, rotor: bool,
               comps: dict | None = None) -> list:
    """The known components of ``partition`` (:data:`PARTITIONS`) on ``hist``: the
    candidates, the additional damping and the mooring (``hybrid``: the quasi-static
    tabulated one; ``hybrid_lin``: linearised about rest, −K z) and, with ``rotor``, the rotor
    of ``model``'s wind (``hybrid``: the operating rotor itself; ``hybrid_lin``: its force in
    the wind alone, ``F_rotor_wind`` of the history, and its damping at the mean wind).
    ``comps``: ``model.components()`` when the caller has built them (each build reads the
    rotor table)."""
    comps = model.components() if comps is None else comps
    known = [*build_candidates(hist, model.coeffs, CANDIDATES).values(),
             comps["linear_damping"]]
    if partition == "hybrid":
        return known + [comps["mooring"]] + ([comps["rotor"]] if rotor else [])
    known.append(linear_components(model.case, DOFS)[0])
    if rotor:
        known += [PrescribedForce("F_rotor_wind"),
                  LinearDamping(comps["rotor"].linear_coefficients(len(DOFS))[1])]
    return known


def prepared(hist: xr.Dataset, model: CaseModel, comps: dict | None = None) -> xr.Dataset:
    """The history with the radiation state space its ``radiation_memory`` candidate reads,
    ``F_rotor_wind`` (the rotor's force in the wind with the hub at rest; time only) and, for
    a reference run, the forces the residual of each partition is taken of when its rotor
    model is known: ``F_hybrid = F_tot − F_rotor`` (the recorded rotor force) and
    ``F_hybrid_lin = F_tot − (F_rotor_wind − B_aero ż)`` — each history its own wind
    (``comps`` as in :func:`known_part`)."""
    rotor = (model.components() if comps is None else comps)["rotor"]
    t = np.asarray(hist["time"].values, float)
    still = np.zeros((t.size, len(DOFS)))
    f_wind = np.asarray(rotor.ode_force(t, still, still, np.zeros(0)), float)  # hub at rest
    new = {"F_rotor_wind": f_wind}
    if "F_rotor" in hist:
        b = rotor.linear_coefficients(len(DOFS))[1]
        f_tot = np.asarray(hist["F_tot"].values, float)
        new["F_hybrid"] = f_tot - np.asarray(hist["F_rotor"].values, float)
        new["F_hybrid_lin"] = f_tot - f_wind + np.asarray(hist["zdot"].values, float) @ b.T
    hist = hist.assign({k: (("time", "dof"), v, {"units": "N, N m"}) for k, v in new.items()})
    hist.attrs["radiation_ss"] = json.dumps(model.radiation_ss.to_dict())
    return hist


def hybrid_case(sea: tuple, duration: float, network: ForceNetwork, model: CaseModel
                ) -> xr.Dataset:
    """What the hybrid needs to run in ``sea`` without a reference run (``model``: the
    sea's :func:`case_model` with the table mooring, built once like the network): the time
    grid (the network's η lead beyond ``duration``), the excitation and η, the case's mass,
    and as the initial state the static offset under the rotor's mean force (the reference
    starts from it with the drift's mean too: a transient of the slow drift's mean)."""
    wave = jonswap(sea)
    comps = model.components()
    offset = model.mean_offset({"mooring": comps["mooring"], "rotor": comps["rotor"]})
    t = np.arange(int(round(duration / DT)) + 1 + network.spec_.lead) * DT
    f_exc, eta = excitation(wave, model.coeffs, t, list(DOFS), RAMP)
    z = np.broadcast_to(offset, (t.size, len(DOFS))).copy()
    zero = np.zeros_like(z)
    return make_history(t, z, zero, zero, forces={"F_exc": f_exc}, dof=list(DOFS),
                        mass=mass_from(None, model.coeffs, list(DOFS)), check=False,
                        extra_vars={"eta": (("time", "probe"), eta[:, None], {"units": "m"})})


def run_hybrid(network: ForceNetwork, ref: xr.Dataset, model: CaseModel, partition: str, *,
               corrections: int, head: ForceNetwork | None = None
               ) -> tuple[xr.Dataset, float]:
    """The hybrid ``partition`` on ``ref``'s sea and ``model``'s wind (``ref``'s first window
    as the initial state; ``ref`` a reference run or :func:`hybrid_case`) and its wall time
    [s] (the wind's rotor force, the known components and the rollout), with the line
    tensions along its motion (:func:`with_tensions`: quasi-static, plus the tension
    ``head``'s line dynamics when given)."""
    start = time.perf_counter()
    comps = model.components()  # once: each build reads the rotor table
    h = prepared(ref, model, comps)
    run = HybridPipeline.from_network(network, known_part(h, model, partition, rotor=True,
                                                          comps=comps),
                                      mass=h["mass"].values, dt=DT, mode=MODE,
                                      corrections=corrections)
    hyb = run.rollout([h]).histories[0]
    wall = time.perf_counter() - start
    return with_tensions(hyb, comps["mooring"], head, h), wall


def linear_offset(model: Any, k_moor: np.ndarray) -> np.ndarray:
    """The equilibrium [m, rad] of the linear model under the case's mean forces (rotor):
    ``(C_hs + K_moor) q = F̄``."""
    comps = model.components()
    total = np.sum([np.asarray(c.mean_force(), float) for c in comps.values()
                    if callable(getattr(c, "mean_force", None))], axis=0)
    c_hs = cf.matrix(model.coeffs, "hydrostatic_stiffness", model.dofs)
    return np.linalg.solve(c_hs + k_moor, total)


def with_tensions(hist: xr.Dataset, mooring: Any, head: ForceNetwork | None = None,
                  wave: xr.Dataset | None = None) -> xr.Dataset:
    """``hist`` with the line tensions ``T_fairlead``, ``T_anchor`` (time, line; N) along its
    motion: the quasi-static ones of ``mooring`` (a table or quasi-static component; the
    linear model's, which carries no line dynamics) and, with the tension ``head``, plus the
    head's line dynamics (:func:`head_tensions`; η from ``wave``, the run's case) — the
    hybrid's. The quasi-static ones are also kept (:func:`with_quasi_static`)."""
    qs = np.asarray(mooring.line_tensions(hist), float)
    total = qs if head is None else qs + head_tensions(head, hist, wave)
    return _assign_tensions(_assign_tensions(hist, total, ""), qs, "_qs")


def with_quasi_static(hist: xr.Dataset, mooring: Any) -> xr.Dataset:
    """``hist`` (a MoorDyn-coupled run: its recorded tensions kept) with the quasi-static
    tensions of ``mooring`` along its motion, ``T_fairlead_qs``, ``T_anchor_qs`` [N]."""
    return _assign_tensions(hist, np.asarray(mooring.line_tensions(hist), float), "_qs")


def _assign_tensions(hist: xr.Dataset, values: np.ndarray, suffix: str) -> xr.Dataset:
    """``T_fairlead<suffix>``, ``T_anchor<suffix>`` from ``values`` (n_time, n_lines, 2)."""
    lines = np.arange(1, values.shape[1] + 1)
    return hist.assign_coords(line=lines).assign(
        {f"{k}{suffix}": (("time", "line"), values[:, :, i], {"units": "N"})
         for i, k in enumerate(("T_fairlead", "T_anchor"))})


# ------------------------------------------------------------------------------- tensions
def tension_dynamics(hist: xr.Dataset, mooring: Any) -> np.ndarray:
    """What the line dynamics add to the tensions of a MoorDyn-coupled run: recorded minus
    quasi-static along its motion, (n_time, 2 n_lines) [N] (fairleads, then anchors): the
    tension head's target."""
    qs = np.asarray(mooring.line_tensions(hist), float)
    rec = np.stack([hist["T_fairlead"].values, hist["T_anchor"].values], axis=-1)
    return (rec - qs).transpose(0, 2, 1).reshape(len(qs), -1)


def fit_tension_head(histories: list[xr.Dataset], mooring: Any,
                     settings: Mapping[str, Any]) -> ForceNetwork:
    """The tension head: a :class:`ForceNetwork` of the force network's ``settings`` (the same
    inputs, window, taps and η lead) trained on :func:`tension_dynamics` of the prepared
    reference ``histories``. An output only: it never feeds back into the ODE."""
    targets = [tension_dynamics(h, mooring) for h in histories]
    return ForceNetwork(**settings).fit(histories, targets, n_out=targets[0].shape[1])


def head_tensions(head: ForceNetwork, hist: xr.Dataset, wave: xr.Dataset) -> np.ndarray:
    """The head's line dynamics along ``hist``'s motion, (n_time, n_lines, 2) [N]: its
    features from ``hist``'s z, ż and the elevation η of ``wave`` (the run's case, which
    reaches the head's lead beyond ``hist``'s end); 0 where the window is not full yet."""
    t = np.asarray(hist["time"].values, float)
    lead = head.spec_.lead
    t_ext = t[0] + DT * np.arange(t.size + lead)
    eta_all = np.asarray(wave["eta"].values, float).reshape(wave.sizes["time"], -1)
    eta = np.stack([np.interp(t_ext, wave["time"].values, e) for e in eta_all.T], axis=1)
    pad = lambda v: np.pad(np.asarray(hist[v].values, float), ((0, lead), (0, 0)),  # noqa: E731
                           mode="edge")
    ds = xr.Dataset({"z": (("time", "dof"), pad("z")), "zdot": (("time", "dof"), pad("zdot")),
                     "zddot": (("time", "dof"), pad("zddot")),
                     "eta": (("time", "probe"), eta)},
                    coords={"time": t_ext, "dof": hist["dof"].values})
    out = np.nan_to_num(head.predict(ds)[:t.size])
    return out.reshape(t.size, 2, -1).transpose(0, 2, 1)


# ------------------------------------------------------------------------------- series
def series(runs: Mapping[str, xr.Dataset], *, ramp: float,
           models: tuple[str, ...] = MODELS) -> xr.Dataset:
    """The six DOFs, the most loaded line's fairlead tension (each model's: the hybrids' with
    the tension head) and its quasi-static tension along each model's motion (``tension_qs``)
    of every model of ``models`` on the ``hybrid`` run's time grid after ``ramp`` [s] (dims
    ``model``, ``time``).

    The most loaded line: the largest mean fairlead tension of the MoorDyn reference."""
    ref = runs["moordyn"]
    t = np.asarray(runs["hybrid"]["time"].values, float)
    t = t[t >= ramp]
    line = int(np.argmax(ref["T_fairlead"].sel(time=t, method="nearest").mean("time").values))
    data: dict[str, list[np.ndarray]] = {k: [] for k in UNITS}
    for name in models:
        h = runs[name].sel(time=t, method="nearest")
        for dof in DOFS:
            data[dof.lower()].append(np.asarray(h["z"].sel(dof=dof).values, float))
        for key, var in (("tension", "T_fairlead"), ("tension_qs", "T_fairlead_qs")):
            data[key].append(np.asarray(h[var if var in h else "T_fairlead"].isel(line=line)
                                        .values, float))
    ds = xr.Dataset({k: (("model", "time"), np.stack(v), {"units": UNITS[k]})
                     for k, v in data.items()},
                    coords={"model": list(models), "time": t})
    ds.attrs["most_loaded_line"] = line + 1
    return ds


def stored(ds: xr.Dataset) -> xr.Dataset:
    """:func:`series` at the shipped resolution (:data:`RESOLUTION`): what the metrics are
    computed on, so that the file gives them again exactly."""
    out = ds.copy()
    for k in UNITS:
        res = RESOLUTION[UNITS[k]]
        out[k] = out[k].copy(data=np.round(out[k].values / res) * res)
    return out


def psd(x: np.ndarray, dt: float, segment: float = SEGMENT) -> tuple[np.ndarray, np.ndarray]:
    """One-sided spectrum of ``x`` about its mean, ``(ω [rad/s], S(ω) [x² s/rad])``
    (Welch, Hann windows of ``segment`` [s], 50 % overlap; ∫S dω = var(x))."""
    n = min(int(round(segment / dt)), len(x))
    f, s = scipy.signal.welch(np.asarray(x, float) - np.mean(x), fs=1.0 / dt, nperseg=n)
    return 2.0 * np.pi * f, s / (2.0 * np.pi)


def band_energy(x: np.ndarray, dt: float, omega_max: float = LOW_OMEGA) -> float:
    """∫ S(ω) dω over 0 < ω ≤ ``omega_max`` [x²] (:func:`psd`, rectangle rule)."""
    w, s = psd(x, dt)
    keep = (w > 0) & (w <= omega_max)
    return float(np.sum(s[keep]) * (w[1] - w[0]))


def _stats(x: np.ndarray) -> dict[str, float]:
    return {"mean": float(np.mean(x)), "std": float(np.std(x)),
            "rms": float(np.sqrt(np.mean(x ** 2))), "max": float(np.max(x)),
            "max_abs": float(np.max(np.abs(x)))}


def errors(x: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    """``x`` against ``ref`` (module doc): ``nrms`` (over RMS(ref)), ``nrms_dynamic`` (the same
    error over std(ref)) and ``fluctuation`` — the error of the fluctuation alone,
    RMS((x − x̄) − (ref − ref̄)) / std(ref) (the mean's bias left out)."""
    e = x - ref
    return {"nrms": float(np.sqrt(np.mean(e ** 2) / np.mean(ref ** 2))),
            "nrms_dynamic": float(np.sqrt(np.mean(e ** 2)) / np.std(ref)),
            "fluctuation": float(np.std(e) / np.std(ref))}


def metrics(ds: xr.Dataset) -> dict[str, Any]:
    """Statistics per model and the errors against the MoorDyn reference (module doc) from a
    :func:`series` Dataset (recomputed by the test from the shipped file)."""
    t = np.asarray(ds["time"].values, float)
    dt = float(np.median(np.diff(t)))
    out: dict[str, Any] = {"stats": {}, "errors": {}, "low_energy": {},
                           "most_loaded_line": int(ds.attrs["most_loaded_line"])}
    ref = {k: np.asarray(ds[k].sel(model="moordyn").values, float) for k in ds.data_vars}
    low_ref = band_energy(ref["surge"], dt)
    for name in MODELS:
        x = {k: np.asarray(ds[k].sel(model=name).values, float) for k in ds.data_vars}
        out["stats"][name] = {k: _stats(v) for k, v in x.items()}
        out["low_energy"][name] = band_energy(x["surge"], dt)
        if name == "moordyn":
            continue
        out["errors"][name] = {k: errors(x[k], ref[k]) for k in x}
        # the quasi-static tension along the model's motion against the reference's own
        out["errors"][name]["tension_qs"] = errors(x["tension_qs"], ref["tension"])
        out["errors"][name]["low_energy"] = out["low_energy"][name] / low_ref - 1.0
    # the reference's own quasi-static tension: what the line dynamics add to it
    out["line_dynamics"] = errors(ref["tension_qs"], ref["tension"])
    return out


def spectra(ds: xr.Dataset, segment: float = SEGMENT) -> xr.Dataset:
    """Surge and pitch spectra (:func:`psd`) of every model (dims ``model``, ``omega``)."""
    t = np.asarray(ds["time"].values, float)
    dt = float(np.median(np.diff(t)))
    out = {}
    for k in ("surge", "pitch"):
        rows = [psd(ds[k].sel(model=m).values, dt, segment) for m in ds["model"].values]
        out[f"S_{k}"] = (("model", "omega"), np.stack([r[1] for r in rows]),
                         {"units": f"{UNITS[k]}^2 s/rad"})
    return xr.Dataset(out, coords={"model": ds["model"].values, "omega": rows[0][0]})


# ------------------------------------------------------------------------------- the run
def prediction(pipe: Any) -> dict[str, Any]:
    """The pipeline's stability prediction at its Δt (without the rotor's aerodynamic
    damping, which only adds damping below rated: conservative)."""
    p = pipe.stability_
    finite = lambda v: float(v) if v is not None and np.isfinite(v) else None  # noqa: E731
    return {"stable": bool(p.stable), "spectral_radius": finite(p.spectral_radius),
            "max_stable_dt": finite(p.max_stable_dt),
            "added_mass_ratio": finite(p.added_mass_ratio), "dt": pipe.dt_,
            "mode": pipe.mode, "corrections": int(pipe.corrections_)}


def long_run(hyb: xr.Dataset, ref: xr.Dataset, table: xr.Dataset, *, ramp: float,
             wall: float) -> dict[str, Any]:
    """The 3-hour check of a hybrid against the MoorDyn-coupled reference ``ref`` of the same
    sea and wind (and the quasi-static run ``table``): per hour and per DOF (and the most
    loaded line's fairlead tension) the std and the max |x − mean| of each; over the whole
    run after ``ramp`` the errors (:func:`errors`) and the surge energy below
    :data:`LOW_OMEGA` (model / reference − 1); all finite."""
    t = np.asarray(hyb["time"].values, float)
    runs = {"hybrid": hyb, "moordyn": ref, "table": table}
    one = series(runs, ramp=ramp, models=tuple(runs))
    out: dict[str, Any] = {"duration": float(t[-1]), "finite": bool(np.all(np.isfinite(
        hyb["z"].values))), "wall_s": wall, "most_loaded_line": one.attrs["most_loaded_line"],
        "hours": []}
    tt = np.asarray(one["time"].values, float)
    keys = [d.lower() for d in DOFS] + ["tension"]
    for h0 in np.arange(0.0, t[-1] - 1.0, 3600.0):
        sel = (tt >= h0) & (tt < h0 + 3600.0)
        row = {}
        for k in keys:
            x = {m: np.asarray(one[k].sel(model=m).values, float)[sel] for m in runs}
            row[k] = {"std": float(np.std(x["hybrid"])), "std_ref": float(np.std(x["moordyn"])),
                      "std_table": float(np.std(x["table"])),
                      "max_dev": float(np.max(np.abs(x["hybrid"] - np.mean(x["hybrid"])))),
                      "max_dev_ref": float(np.max(np.abs(x["moordyn"]
                                                         - np.mean(x["moordyn"]))))}
        out["hours"].append(row)
    x = {k: {m: np.asarray(one[k].sel(model=m).values, float) for m in runs} for k in keys}
    out["errors"] = {k: {m: errors(x[k][m], x[k]["moordyn"]) for m in ("hybrid", "table")}
                     for k in keys}
    dt = float(np.median(np.diff(tt)))
    low = {m: band_energy(x["surge"][m], dt) for m in runs}
    out["low_energy"] = {m: low[m] / low["moordyn"] - 1.0 for m in ("hybrid", "table")}
    return out


# ------------------------------------------------------------------------------- the report
def load_shipped(stem: Path = SHIPPED) -> tuple[dict[str, Any], xr.Dataset]:
    """The shipped metrics (JSON) and held-out series (NetCDF, dims ``sea``, ``model``,
    ``time``)."""
    return (json.loads(Path(stem).with_suffix(".json").read_text()),
            read_netcdf(Path(stem).with_suffix(".nc")))


def sea_series(ds: xr.Dataset, sea: str) -> xr.Dataset:
    """One held-out sea of the shipped series as :func:`series` returned it."""
    one = ds.sel(sea=sea).drop_vars(["sea", "most_loaded_line"])
    one.attrs["most_loaded_line"] = int(ds["most_loaded_line"].sel(sea=sea))
    return one


def table_markdown(res: Mapping[str, Any], sea: str) -> list[str]:
    """RMS and max of surge, pitch and the most loaded line's fairlead tension per model, and
    the hybrid's errors, for one held-out sea (Markdown lines)."""
    m = res["held_out"][sea]
    s = res["held_out_seas"][sea]
    lines = [f"Held-out sea {sea}: JONSWAP Hs {s['hs']:g} m, Tp {s['tp']:g} s (seed "
             f"{s['seed']}), wind {s['wind_speed']:g} m/s TI {res['turbulence_intensity']:g} "
             f"(seed {s['wind_seed']}); after the {res['ramp']:g} s ramp. Most loaded line: "
             f"{m['most_loaded_line']}.", "",
             "| model | surge RMS / max [m] | pitch RMS / max [deg] | T_fairlead RMS / max [kN] "
             "| surge energy < 0.1 rad/s [m²] |", "|---|---|---|---|---|"]
    for name in MODELS:
        st = m["stats"][name]
        lines.append(
            f"| {LABELS[name]} | {st['surge']['rms']:.2f} / {st['surge']['max_abs']:.2f} | "
            f"{np.degrees(st['pitch']['rms']):.2f} / {np.degrees(st['pitch']['max_abs']):.2f} | "
            f"{st['tension']['rms'] / 1e3:.1f} / {st['tension']['max'] / 1e3:.1f} | "
            f"{m['low_energy'][name]:.3g} |")
    lines += ["", "| vs the MoorDyn reference | surge | pitch | T_fairlead | T_fairlead "
              "quasi-static along the motion | low-frequency surge energy |",
              "|---|---|---|---|---|---|"]
    for name in (n for n in MODELS if n != "moordyn"):
        e = m["errors"][name]
        def cell(k: str, e: Mapping[str, Any] = e) -> str:
            return f"{100 * e[k]['nrms']:.2f} % ({100 * e[k]['fluctuation']:.1f} %)"

        lines.append(f"| {LABELS[name]} | {cell('surge')} | {cell('pitch')} | "
                     f"{cell('tension')} | {cell('tension_qs')} | "
                     f"{100 * e['low_energy']:+.1f} % |")
    lines += ["", "Errors: RMS(x − x_ref)/RMS(x_ref) (in brackets: the fluctuation's, "
              "RMS((x − x̄) − (x_ref − x̄_ref))/std(x_ref)). The hybrids' T_fairlead: the "
              "quasi-static tension along their motion plus the tension head; next column "
              "without the head. The reference's own quasi-static tension misses "
              f"{100 * m['line_dynamics']['fluctuation']:.0f} % of its fluctuation.", "",
              "Other DOFs (fluctuation error of the hybrids): "
              + "; ".join(f"{LABELS[k]}: " + ", ".join(
                  f"{d.lower()} {100 * m['errors'][k][d.lower()]['fluctuation']:.1f} %"
                  for d in DOFS if d not in ("Surge", "Pitch")) for k in PARTITIONS) + "."]
    return lines


def long_lines(res: Mapping[str, Any]) -> list[str]:
    """The stability prediction and the 3-hour run of each hybrid against the 3-hour
    MoorDyn-coupled reference (Markdown lines)."""
    lines = []
    for k in PARTITIONS:
        pred, long = res["prediction"][k], res["long"][k]
        ratio = [h[d]["std"] / h[d]["std_ref"] for h in long["hours"] for d in ("surge", "pitch")]
        e = long["errors"]
        lines.append(
            f"{LABELS[k]}: predicted {'stable' if pred['stable'] else 'UNSTABLE'} (spectral "
            f"radius {pred['spectral_radius']:.6f} at Δt {pred['dt']:g} s); its "
            f"{long['duration'] / 3600:.1f}-hour run is "
            f"{'finite' if long['finite'] else 'NOT finite'} and against the {long['duration'] / 3600:.1f}-hour MoorDyn-coupled reference of "
            f"the same sea and wind: RMS error surge {100 * e['surge']['hybrid']['nrms']:.2f} %, "
            f"pitch {100 * e['pitch']['hybrid']['nrms']:.2f} %, fairlead tension "
            f"{100 * e['tension']['hybrid']['nrms']:.2f} % (fluctuation "
            f"{100 * e['tension']['hybrid']['fluctuation']:.1f} %), surge energy below "
            f"{LOW_OMEGA:g} rad/s {100 * long['low_energy']['hybrid']:+.1f} %; hourly std of "
            f"surge and pitch {min(ratio):.3f}–{max(ratio):.3f} × the reference's.")
    return lines


def spectra_figure(ds: xr.Dataset, sea: str, tp: float) -> plt.Figure:
    """Log-log surge and pitch spectra of every model on one axis per DOF, with the
    natural frequencies and the wave peak marked."""
    sp = spectra(sea_series(ds, sea), FIGURE_SEGMENT)
    keep = (sp["omega"].values > 0) & (sp["omega"].values <= 2.0)
    w = sp["omega"].values[keep]
    fig, axes = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    styles = {"linear": ":", "table": "--", "moordyn": "-", "hybrid": "-.", "hybrid_lin": ":"}
    for ax, key, unit in ((axes[0], "surge", "m² s/rad"), (axes[1], "pitch", "rad² s/rad")):
        top = 0.0
        for name in sp["model"].values:
            y = sp[f"S_{key}"].sel(model=name).values[keep]
            ax.loglog(w, y, styles[str(name)], lw=1.2, label=LABELS[str(name)])
            top = max(top, float(y.max()))
        ax.set_ylim(top * 1e-6, top * 3.0)
        marks = {**MARKS, 2.0 * np.pi / tp: ("wave peak", "center")}
        for omega, (label, align) in marks.items():
            ax.axvline(omega, color="0.6", lw=0.8)
            ax.text(omega, 1.02, label, transform=ax.get_xaxis_transform(), fontsize=7,
                    ha=align)
        ax.axvspan(w[0], LOW_OMEGA, color="0.92", zorder=0, label="ω < 0.1 rad/s")
        ax.set_ylabel(f"S_{key} [{unit}]")
        ax.grid(alpha=0.3, which="both")
    axes[1].legend(fontsize=8, loc="lower left")  # the pitch panel has room there
    axes[-1].set_xlim(w[0], 2.0)
    axes[-1].set_xlabel("ω [rad/s]")
    fig.tight_layout()
    return fig


def report_section(folder: Path, stem: Path = SHIPPED) -> str:
    """The report's design-fidelity hybrid: the table and ``folder/moordyn_hybrid_spectra.png``
    of the first held-out sea, a line per other sea, from the shipped results (no MoorDyn)."""
    res, ds = load_shipped(stem)
    seas = list(res["held_out"])
    first = seas[0]
    fig = spectra_figure(ds, first, res["held_out_seas"][first]["tp"])
    save(fig, Path(folder) / "moordyn_hybrid_spectra.png")
    lines = ["### The hybrid on the MoorDyn-coupled reference (design fidelity)", "",
             "Reference: 6-DOF Cummins + MoorDyn (a coupled 6-DOF body) + slow drift (Newman) "
             "+ Morison drag + the operating NREL 5-MW rotor in turbulent wind, JONSWAP seas "
             f"({res['duration']:g} s each). Two hybrids, each a network (inputs z, ż, η) "
             f"trained on {len(res['train_seas'])} seas and winds through the hybrid pipeline: "
             + "; ".join(f"{LABELS[k]}: the network learns {v}" for k, v in PARTITIONS.items())
             + ". Both hybrids' fairlead tensions: the quasi-static ones along their motion "
             "plus a tension head (a second network on the same features, trained on MoorDyn's "
             "tension minus the quasi-static one; an output, not fed back into the ODE). "
             "Shipped results (`hybridwsi/data/oc3_moordyn_hybrid.json/.nc`, "
             "`scripts/oc3_moordyn_hybrid.py`).", "", *table_markdown(res, first), ""]
    for sea in seas[1:]:
        for k in PARTITIONS:
            e = res["held_out"][sea]["errors"][k]
            lines.append(f"Held-out sea {sea}, {LABELS[k]}: surge {100 * e['surge']['nrms']:.2f} "
                         f"%, pitch {100 * e['pitch']['nrms']:.2f} %, fairlead tension "
                         f"{100 * e['tension']['nrms']:.2f} % (fluctuation "
                         f"{100 * e['tension']['fluctuation']:.1f} %; quasi-static "
                         f"{100 * e['tension_qs']['fluctuation']:.1f} %), low-frequency surge "
                         f"energy {100 * e['low_energy']:+.1f} %.")
    lines += ["", *long_lines(res), "", "![spectra](fowt/moordyn_hybrid_spectra.png)", ""]
    return "\n".join(lines)
