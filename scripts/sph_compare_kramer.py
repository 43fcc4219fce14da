#!/usr/bin/env python
"""Compare SPH decay histories (hybridwsi sph decay3d) with Kramer et al. (2021).

    python scripts/sph_compare_kramer.py results/sph/decay3d_dp0.03.nc
    python scripts/sph_compare_kramer.py new.nc:"smooth body, D/10" old.nc:"lattice, D/10" \
        --png results/sph/decay3d_vs_kramer.png

Prints the comparison (periods, first extrema, RMS of z/H0 over 5 Te0) of each run as JSON.
With ``--table`` it also prints issue 15's measures (damped period and damping ratio fitted
over [0, 2.5 Te0], first trough, RMS over [0, 5 Te0]) of the runs beside the experiment and the
published codes, as a Markdown table; with ``--gci`` (three or more runs at different spacings)
also the observed order, extrapolated value and grid convergence index of those measures
and of the hold force before the release (when every run records it).
With ``--png`` it also draws the runs over the experiment
and saves the curves behind the figure next to it (same name, ``.nc``); ``--with-curves``
adds the runs of such an earlier ``.nc`` to the figure (not to the tables: a curve sampled
at the experiment's times is not the history the measures are fitted on), for runs whose
histories are gone or too large to keep:

    python scripts/sph_compare_kramer.py d14.nc:"SPH D/14" \
        --with-curves docs/figures/decay3d_vs_kramer.nc --png docs/figures/decay3d_vs_kramer.png
"""

import json
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi._meta import version
from hybridwsi.cli import Parser, run_script
from hybridwsi.errors import InputError
from hybridwsi.files import read_netcdf as read_dataset
from hybridwsi.history import read_netcdf, to_netcdf
from hybridwsi.importers.kramer import read_kramer_drop
from hybridwsi.report.validation import (CONVERGENCE_MEASURES, decay_convergence_table,
                                         decay_measures, decay_measures_published,
                                         decay_measures_table)
from hybridwsi.sph.decay import TE0, compare_decay, load_experiment


def main() -> None:
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", help="history NetCDF, optionally FILE:LABEL")
    ap.add_argument("--png", default=None, help="figure of the runs over the experiment")
    ap.add_argument("--table", action="store_true",
                    help="print the runs' damped fit, trough and RMS beside the published codes")
    ap.add_argument("--gci", action="store_true",
                    help="with runs at three or more spacings: the grid convergence index of "
                         "the --table measures (the three finest)")
    ap.add_argument("--with-curves", default=None, metavar="NC",
                    help="with --png: also draw the runs of an earlier comparison (the .nc that "
                         "--png wrote); in the figure only")
    a = ap.parse_args()
    if a.with_curves and not a.png:
        ap.error("--with-curves needs --png")
    if a.gci and len(a.runs) < 3:
        ap.error("--gci needs runs at three or more spacings")
    a.table = a.table or a.gci
    exp = load_experiment("01D")
    t = exp["t_over_Te0"].to_numpy()
    labels, curves, report, inputs = [], [], {}, {}
    measured = read_kramer_drop("01D", normalised=True) if a.table else None
    rows = decay_measures_published("01D", TE0, measured) if a.table else {}
    for spec in a.runs:
        path, _, label = spec.partition(":")
        hist = read_netcdf(path)
        z0 = float(hist["z"].values[0, 0])
        report[label or path] = compare_decay(hist, z0)
        zs = hist["z"].values[:, 0] / z0
        ts = hist["time"].values / TE0
        inside = (t >= ts[0]) & (t <= ts[-1])
        curves.append(np.where(inside, np.interp(t, ts, zs), np.nan))
        labels.append(label or Path(path).stem)
        inputs[labels[-1]] = json.loads(hist.attrs.get("inputs", "{}"))
        if a.table:
            rows[labels[-1]] = decay_measures(hist["time"].values, zs, TE0, measured)
            # the static force before the release [N], whose convergence issue 15 also asks
            rows[labels[-1]]["hold_force"] = float(hist["F_tot"].attrs.get("hold_mean", np.nan))
    print(json.dumps(report, indent=1))
    if a.table:
        print(decay_measures_table(rows, "01D"))
    if a.gci:
        by_dp = {float(inputs[lb]["dp"]): rows[lb] for lb in labels}
        if len(by_dp) != len(labels):
            raise InputError("--gci needs each run at its own spacing (two runs share a dp)")
        held = all(np.isfinite(r["hold_force"]) for r in by_dp.values())
        print(decay_convergence_table(
            by_dp, CONVERGENCE_MEASURES + (("hold_force",) if held else ())))
    if a.png:
        from hybridwsi.report.plots import save, sph_decay_figure

        runs = list(a.runs)
        if a.with_curves:
            runs += _add_earlier_curves(a.with_curves, t, labels, curves, report, inputs)
        ds = xr.Dataset(
            {"exp_mean": ("t", exp["x3_over_H0m_mean"].to_numpy()),
             "exp_ci95_lower": ("t", exp["ci95_lower"].to_numpy()),
             "exp_ci95_upper": ("t", exp["ci95_upper"].to_numpy()),
             "heave_over_H0": (("run", "t"), np.array(curves))},
            coords={"t": ("t", t, {"units": "1", "long_name": "t / Te0"}), "run": labels},
            attrs={"runs": json.dumps(runs), "comparison": json.dumps(report),
                   "run_inputs": json.dumps(inputs), "hybridwsi_version": version(),
                   "source": "scripts/sph_compare_kramer.py"})
        save(sph_decay_figure(ds), a.png)
        to_netcdf(ds, Path(a.png).with_suffix(".nc"))
        print(f"wrote {a.png} and {Path(a.png).with_suffix('.nc')}")


def _add_earlier_curves(path: str, t: np.ndarray, labels: list, curves: list, report: dict,
                        inputs: dict) -> list[str]:
    """Append the runs of an earlier comparison's figure data (``--png``'s ``.nc``) to this
    figure's; returns their run specs for the provenance."""
    old = read_dataset(path)
    if "heave_over_H0" not in old or "run" not in old.dims:
        raise InputError(f"{path}: not the figure data of sph_compare_kramer.py --png "
                         "(no heave_over_H0 per run)")
    if old.sizes["t"] != len(t) or not np.allclose(old["t"].values, t):
        raise InputError(f"{path}: its curves are not on the experiment's time grid")
    comparison = json.loads(old.attrs.get("comparison", "{}"))
    old_inputs = json.loads(old.attrs.get("run_inputs", "{}"))
    for run in (str(r) for r in old["run"].values):
        if run in labels:
            raise InputError(f"{path}: run {run!r} is also given on the command line")
        labels.append(run)
        curves.append(old["heave_over_H0"].sel(run=run).values)
        report[run], inputs[run] = comparison.get(run, {}), old_inputs.get(run, {})
    return [f"{spec} (from {path})" for spec in json.loads(old.attrs.get("runs", "[]"))]


if __name__ == "__main__":
    run_script(main)
