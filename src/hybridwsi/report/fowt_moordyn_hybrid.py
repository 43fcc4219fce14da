"""The hybrid on the MoorDyn-coupled OC3-Hywind reference (issue 29 items 5-6): the metrics of
``scripts/oc3_moordyn_hybrid.py`` and the report's table and spectra from the shipped results
``hybridwsi/data/oc3_moordyn_hybrid.{json,nc}`` (docs/OC3_HYWIND.md "The hybrid on the
MoorDyn-coupled reference"). Nothing here runs MoorDyn: the report reads the shipped file.

Metrics (per held-out sea, after the ramp; ``ref`` = the MoorDyn-coupled run):

- ``nrms``: RMS(x − x_ref) / RMS(x_ref) — the pipeline's convention
  (:func:`hybridwsi.surrogate.pipeline.nrms_per_dof`), the mean offset included;
- ``nrms_dynamic``: RMS(x − x_ref) / std(x_ref) — the same error over the fluctuation alone
  (the stricter number: the 13 m surge offset under the thrust does not dilute it);
- ``low_energy``: the energy of the surge spectrum below 0.1 rad/s (the slow drift, the
  surge resonance at 0.051 rad/s), model / reference − 1;
- the most loaded line: the line of the largest mean fairlead tension of the reference.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import scipy.optimize
import scipy.signal
import xarray as xr

from hybridwsi.hydro import coefficients as cf

__all__ = ["LOW_OMEGA", "MODELS", "linear_offset", "metrics", "psd", "series",
           "with_tensions"]

#: rad/s: the band of the slow-drift energy criterion (issue 29: "below 0.1 rad/s")
LOW_OMEGA = 0.1
#: the models of the table and the spectra, in this order
MODELS = ("linear", "table", "moordyn", "hybrid")
LABELS = {"linear": "linear", "table": "quasi-static (MoorPy table)",
          "moordyn": "MoorDyn-coupled reference", "hybrid": "hybrid"}
#: Welch segment [s]: 3.4 surge periods of 124 s in a 1800 s record, 5 segments (50 % overlap)
SEGMENT = 600.0
#: the excerpt of the time series shipped per sea [s after the ramp]
EXCERPT = 600.0


def linear_offset(model: Any, k_moor: np.ndarray) -> np.ndarray:
    """The equilibrium [m, rad] of the linear model under the case's mean forces (rotor):
    ``(C_hs + K_moor) q = F̄``."""
    comps = model.components()
    total = np.sum([np.asarray(c.mean_force(), float) for c in comps.values()
                    if callable(getattr(c, "mean_force", None))], axis=0)
    c_hs = cf.matrix(model.coeffs, "hydrostatic_stiffness", model.dofs)
    return np.linalg.solve(c_hs + k_moor, total)


def with_tensions(hist: xr.Dataset, mooring: Any) -> xr.Dataset:
    """``hist`` with the quasi-static line tensions ``T_fairlead``, ``T_anchor`` (time, line;
    N) of ``mooring`` (a table or quasi-static component) along its motion: the hybrid's and
    the linear model's tensions (neither carries line dynamics)."""
    values = np.asarray(mooring.line_tensions(hist), float)
    lines = np.arange(1, values.shape[1] + 1)
    return hist.assign_coords(line=lines).assign(
        T_fairlead=(("time", "line"), values[:, :, 0], {"units": "N"}),
        T_anchor=(("time", "line"), values[:, :, 1], {"units": "N"}))


# ------------------------------------------------------------------------------- series
def series(runs: Mapping[str, xr.Dataset], *, ramp: float) -> xr.Dataset:
    """Surge, heave, pitch and the most loaded line's fairlead tension of every model of
    :data:`MODELS` on the hybrid's time grid after ``ramp`` [s] (dims ``model``, ``time``).

    The most loaded line: the largest mean fairlead tension of the MoorDyn reference."""
    ref = runs["moordyn"]
    t = np.asarray(runs["hybrid"]["time"].values, float)
    t = t[t >= ramp]
    line = int(np.argmax(ref["T_fairlead"].sel(time=t, method="nearest").mean("time").values))
    data: dict[str, list[np.ndarray]] = {"surge": [], "heave": [], "pitch": [], "tension": []}
    for name in MODELS:
        h = runs[name].sel(time=t, method="nearest")
        for key, dof in (("surge", "Surge"), ("heave", "Heave"), ("pitch", "Pitch")):
            data[key].append(np.asarray(h["z"].sel(dof=dof).values, float))
        data["tension"].append(np.asarray(h["T_fairlead"].isel(line=line).values, float))
    units = {"surge": "m", "heave": "m", "pitch": "rad", "tension": "N"}
    ds = xr.Dataset({k: (("model", "time"), np.stack(v), {"units": units[k]})
                     for k, v in data.items()},
                    coords={"model": list(MODELS), "time": t})
    ds.attrs["most_loaded_line"] = line + 1
    return ds


def psd(x: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided spectrum of ``x`` about its mean, ``(ω [rad/s], S(ω) [x² s/rad])``
    (Welch, Hann windows of :data:`SEGMENT` s, 50 % overlap; ∫S dω = var(x))."""
    n = min(int(round(SEGMENT / dt)), len(x))
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
        out["errors"][name] = {k: {
            "nrms": float(np.sqrt(np.mean((x[k] - ref[k]) ** 2) / np.mean(ref[k] ** 2))),
            "nrms_dynamic": float(np.sqrt(np.mean((x[k] - ref[k]) ** 2)) / np.std(ref[k]))}
            for k in x}
        out["errors"][name]["low_energy"] = out["low_energy"][name] / low_ref - 1.0
    return out


def spectra(ds: xr.Dataset) -> xr.Dataset:
    """Surge and pitch spectra (:func:`psd`) of every model (dims ``model``, ``omega``)."""
    t = np.asarray(ds["time"].values, float)
    dt = float(np.median(np.diff(t)))
    out = {}
    for k in ("surge", "pitch"):
        rows = [psd(ds[k].sel(model=m).values, dt) for m in ds["model"].values]
        out[f"S_{k}"] = (("model", "omega"), np.stack([r[1] for r in rows]),
                         {"units": f"{ds[k].attrs['units']}^2 s/rad"})
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


def long_run(hyb: xr.Dataset, ref: xr.Dataset, *, ramp: float, wall: float) -> dict[str, Any]:
    """The 3-hour check: per DOF the hybrid's std and max |z − mean| per hour against the
    same-sea quasi-static run's, all finite."""
    t = np.asarray(hyb["time"].values, float)
    out: dict[str, Any] = {"duration": float(t[-1]), "finite": bool(np.all(np.isfinite(
        hyb["z"].values))), "wall_s": wall, "hours": []}
    for h0 in np.arange(0.0, t[-1] - 1.0, 3600.0):
        sel = (t >= max(h0, ramp)) & (t < h0 + 3600.0)
        row = {}
        for d in ("Surge", "Heave", "Pitch"):
            z = np.asarray(hyb["z"].sel(dof=d).values, float)[sel]
            zr = np.asarray(ref["z"].sel(dof=d).sel(time=t[sel], method="nearest").values,
                            float)
            row[d] = {"std": float(np.std(z)), "std_table": float(np.std(zr)),
                      "max_dev": float(np.max(np.abs(z - np.mean(z))))}
        out["hours"].append(row)
    return out
