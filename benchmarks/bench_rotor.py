"""Benchmark: OC3-Hywind runs with the operating rotor against the same run with it parked.

One 3-DOF (Surge, Heave, Pitch) run of ``--duration`` seconds (default 3600: the baseline
sample then takes > 0.2 s) at dt 0.1 s:
linearised mooring, additional damping, radiation state space (fitted once, outside the
timing), NREL 5-MW rotor in turbulent wind (8 m/s, TI 0.1, Kaimal, rotor-averaged; at 18 m/s the
quasi-steady rotor leaves the pitch mode negatively damped and the hour does not finish). The
baseline, in the same process, is the run with the parked rotor (compiled RK4 loop); the
candidates are the quasi-steady rotor (its Numba kernel: the compiled loop) and the PI-controlled
rotor (three internal states: the NumPy loop). Timing: ``benchmarks/timing.py`` (samples of
>= 0.2 s, ``--repeat`` >= 5 rounds alternating baseline / candidates); prints per run the
median wall time, the median ratio to the baseline and its spread (min-max of the per-round
ratios), and the real-time factor.
Run: ``python benchmarks/bench_rotor.py``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from hybridwsi.cases import load_case
from hybridwsi.cummins import simulate
from hybridwsi.cummins.system import build_system
from hybridwsi.dofs import index
from hybridwsi.forces import Hydrostatic, additional_damping, rotor_from_case
from hybridwsi.hydro import coefficients as co
from hybridwsi.report.fowt import oc3_coefficients

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import REPEAT, Figure, compare, conditions  # noqa: E402

DOFS = ["Surge", "Heave", "Pitch"]


def runner(case: dict, coeffs, ss, rotor_spec: dict, duration: float):
    """A zero-argument function that does one run (from the mean-offset equilibrium)."""
    spec = {**case, "rotor": {**case["rotor"], **rotor_spec}}
    rotor = rotor_from_case(spec, DOFS)
    idx = index(DOFS)
    k = np.asarray(case["mooring"]["reference"]["K"])[np.ix_(idx, idx)]
    z0 = np.linalg.solve(co.matrix(coeffs, "hydrostatic_stiffness", DOFS) + k, rotor.mean_force())
    forces = [Hydrostatic(k), additional_damping(case, DOFS), rotor]
    return lambda: simulate(coeffs, dofs=DOFS, duration=duration, dt=0.1, z0=z0,
                            forces=forces, radiation_ss=ss)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=3600.0, help="simulated seconds per run")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    case = load_case("oc3_hywind")
    coeffs = oc3_coefficients(case)
    ss = build_system(coeffs, dofs=DOFS, radiation="statespace", dt=0.1).ss
    wind = dict(state="operating", wind_speed=8.0, turbulence_intensity=0.1, wind_seed=1)
    runs = {"parked": runner(case, coeffs, ss, {"state": "parked"}, args.duration),
            "quasi-steady": runner(case, coeffs, ss, {**wind, "controller": "quasi-steady"},
                                   args.duration),
            "pi": runner(case, coeffs, ss, {**wind, "controller": "pi"}, args.duration)}
    parked = runs.pop("parked")
    res = compare(Figure(parked, args.duration), {k: Figure(f, args.duration)
                                                  for k, f in runs.items()},
                  repeat=max(args.repeat, REPEAT), baseline_label="parked")
    print(f"{args.duration:g} s simulated, dt 0.1 s (times per simulated second)")
    for name, t in res.items():
        ratio = "" if t.ratios is None else f", / parked: {t.ratio_text()}"
        print(f"{name:13s} median {t.median * args.duration:7.3f} s per run "
              f"({1 / t.median:8.0f}x real time){ratio}")
    print(conditions(repeat=max(args.repeat, REPEAT)))
    base = res["parked"].median
    return 0 if math.isfinite(base) else 1


if __name__ == "__main__":
    raise SystemExit(main())
