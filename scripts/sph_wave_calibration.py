#!/usr/bin/env python
"""Calibrate the paddle stroke of ``regular3d`` in its empty flume, as a laboratory does.

At coarse particle spacing the SPH wave loses height on its way from the paddle to the body
(numerical damping; ``docs/SPH_RUNS.md``). This runs the flume without the body (``waves3d``,
or its 2D section ``waves2d`` with ``--dim 2``, minutes instead of an hour) at the spacing of
the production run, measures the steady wave height where the body will be (two wavelengths
from the paddle) and sets

    gain = H_target / H_measured(x_body),

then runs the flume again with that gain (``--iterations`` times, correcting it each time:
the loss grows with the wave's steepness) and reports the height reached.
Resumable: the runs are checkpointed next to their NetCDF files.

    OMP_NUM_THREADS=2 python scripts/sph_wave_calibration.py --dim 2 --dp 0.025 --iterations 2 \\
        --out results/sph_calibration

Writes <out>/calibration.json (appended per run) and prints the gain to pass as
``hybridwsi sph regular3d --gain G``.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from hybridwsi.cli import Parser, run_script
from hybridwsi.history import atomic_write
from hybridwsi.sph import tank, wavemaker
from hybridwsi.sph.run import run_case


def flume(dim: int, dp: float, hdx: float, alpha: float, tf: float, gain: float):
    """``regular3d``'s flume without the body (same depth, period, height, length, g)."""
    T, H, d = 0.75, 0.05, 0.45
    lam = 2 * math.pi / wavemaker.wavenumber(T, d, tank.KRAMER_G)
    probes = (lam, 1.5 * lam, 2.0 * lam)
    if dim == 3:
        return tank.waves3d(dp=dp, depth=d, period=T, height=H, tf=tf, hdx=hdx, alpha=alpha,
                            probes=probes, gain=gain)
    return tank.waves2d(dp=dp, depth=d, period=T, height=H, length=4 * lam, tf=tf,
                        probes=probes, alpha=alpha, hdx=hdx, gain=gain)


def measure(dim: int, dp: float, hdx: float, alpha: float, tf: float, gain: float,
            out: Path, openmp: bool) -> dict:
    case = flume(dim, dp, hdx, alpha, tf, gain)
    hist = run_case(case, out / f"flume{dim}d_dp{dp:g}_gain{gain:.4f}.nc", resume=True,
                    openmp=openmp)
    inp = case.inputs
    g = tank.KRAMER_G if dim == 3 else tank.G
    waves = wavemaker.probe_waves(hist["time"].values, hist["eta"].values,
                                  hist["probe_x"].values, inp["period"], inp["depth"],
                                  inp["t_ramp"], g)
    lam = inp["wavelength"]
    for w in waves:
        w["x_over_wavelength"] = round(w["x"] / lam, 3)
        w["H_err"] = w["H"] / inp["height"] - 1
    return {"dim": dim, "dp": dp, "hdx": hdx, "alpha": alpha, "tf": tf, "gain": gain,
            "n_particles": case.n_particles, "target_H": inp["height"], "probes": waves}


def main() -> None:
    ap = Parser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--dim", type=int, choices=(2, 3), default=3)
    ap.add_argument("--dp", type=float, default=0.0375, help="particle spacing [m]")
    ap.add_argument("--hdx", type=float, default=tank.BODY_HDX)
    ap.add_argument("--alpha", type=float, default=tank.BODY_ALPHA)
    ap.add_argument("--tf", type=float, default=8.0, help="simulated time [s]")
    ap.add_argument("--iterations", type=int, default=1,
                    help="re-runs with the corrected gain after the first run (default 1)")
    ap.add_argument("--openmp", action="store_true")
    ap.add_argument("--out", default="results/sph_calibration")
    a = ap.parse_args()
    if a.iterations < 0:
        ap.error(f"--iterations must be 0 or more, got {a.iterations}")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    log = out / "calibration.json"
    runs = json.loads(log.read_text()) if log.is_file() else []

    def record(res: dict) -> None:
        runs.append(res)
        atomic_write(log, lambda tmp: Path(tmp).write_text(json.dumps(runs, indent=1)))
        print(json.dumps(res, indent=1))

    args = (a.dim, a.dp, a.hdx, a.alpha, a.tf)
    gain = 1.0
    # the loss grows with the wave's steepness, so one correction undershoots a little:
    # iterate gain <- gain H_target / H(x_body)
    for _ in range(1 + a.iterations):
        res = measure(*args, gain, out, a.openmp)
        res["calibrated_gain"] = round(gain * res["target_H"] / res["probes"][-1]["H"], 4)
        record(res)
        gain = res["calibrated_gain"]
    print(f"gain = {gain:.4f}  (hybridwsi sph regular3d --dp {a.dp:g} --gain {gain:.4f})")

if __name__ == "__main__":
    run_script(main)
