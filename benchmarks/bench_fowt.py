"""Benchmark: one hour of OC3-Hywind in a JONSWAP sea, 3 DOF (surge, heave, pitch).

The run: the shipped Capytaine coefficients, the radiation state space, the tabulated
nonlinear MoorPy mooring (``MooringForce``), Morison strip drag with the wave particle velocity
(``MorisonDrag``, 120 strips, Cd 0.6) and the additional linear damping, in a JONSWAP sea
(Hs 6 m, Tp 10 s, γ 3.3, 100 components), dt 0.1 s, RK4 (``cummins.simulate``'s stepping
solver: its Numba loop when Numba is installed, :mod:`hybridwsi.cummins.compiled`). Prints
simulated time / wall time (target ≥ 1000× real time). The radiation state space is fitted once
for the body (its time is printed; as ``hybridwsi.sweep`` does, every run reuses it) and the
Numba code is compiled (or loaded from its disk cache) by a short warm-up run, both outside
the timing; the ratio with the fit inside is printed too.
In the same process: the same run with the mooring as its linearised stiffness only and no
drag (still the stepping solver, since the stiffness is passed as a force component), and the
nonlinear run again on the NumPy loop (``solvers.COMPILED = False``; ``--no-numpy`` skips it)
with the largest difference between the two paths. Timing: ``benchmarks/timing.py``
(samples of >= 0.2 s, ``--repeat`` rounds alternating baseline and candidates, medians).
Run: ``python benchmarks/bench_fowt.py [--duration 3600] [--dt 0.1]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from hybridwsi.cases import load_case
from hybridwsi.cummins import build_system, simulate, solvers
from hybridwsi.hydro.irf import radiation_irf
from hybridwsi.forces import MooringForce, MorisonDrag
from hybridwsi.forces._compiled import HAVE_NUMBA
from hybridwsi.casemodel import linear_components
from hybridwsi.report.fowt import DOFS, oc3_coefficients
from hybridwsi.waves import JONSWAP

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import REPEAT, Figure, compare, conditions, sample  # noqa: E402


def _numpy_loop(run):
    """``run`` on the NumPy stepping loop (``solvers.COMPILED = False``)."""
    def numpy_run():
        solvers.COMPILED = False
        try:
            return run()
        finally:
            solvers.COMPILED = True
    return numpy_run


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=3600.0, help="simulated time [s]")
    parser.add_argument("--dt", type=float, default=0.1, help="time step [s]")
    parser.add_argument("--repeat", type=int, default=REPEAT, help="alternating rounds")
    parser.add_argument("--no-numpy", action="store_true", help="skip the NumPy-loop run")
    args = parser.parse_args(argv)

    case = load_case("oc3_hywind")
    coeffs = oc3_coefficients(case)
    wave = JONSWAP(hs=6.0, tp=10.0, gamma=3.3, seed=1, n_components=100)
    mooring = MooringForce.from_case(case, list(DOFS))
    linear = linear_components(case, DOFS, stiffness=mooring.table.stiffness())  # [−K z, B_add]
    drag = MorisonDrag.from_case(case, list(DOFS), wave=wave, ramp=60.0)
    ss = build_system(coeffs, dofs=DOFS, dt=args.dt).ss
    # the fit itself (an explicit kernel bypasses hydro.ss_cache, which keeps the fitted
    # model by content: a command run again on the same coefficients reads it instead)
    t_fit = sample(lambda: build_system(coeffs, dofs=DOFS, dt=args.dt,
                                        irf=radiation_irf(coeffs)))
    kw = dict(dofs=DOFS, duration=args.duration, dt=args.dt, wave=wave, ramp=60.0,
              radiation_ss=ss)

    def nonlinear():
        return simulate(coeffs, forces=[mooring, drag, linear[1]], **kw)

    def baseline():
        return simulate(coeffs, forces=linear, **kw)

    t0 = time.perf_counter()
    simulate(coeffs, forces=[mooring, drag, linear[1]], **dict(kw, duration=10 * args.dt))
    t_warm = time.perf_counter() - t0
    print(f"loop: {'Numba (compiled)' if HAVE_NUMBA and solvers.COMPILED else 'NumPy'}; "
          f"radiation fit (order {ss.order}) {t_fit:.2f} s, warm-up (compile or cache load) "
          f"{t_warm:.2f} s, both once per process")
    last = {}  # the last history of each run, for the statistics below

    def keep(name, run):
        return Figure(lambda: last.__setitem__(name, run()), args.duration)
    cands = {"nonlinear mooring + Morison drag": keep("nl", nonlinear)}
    if not args.no_numpy:
        cands["nonlinear, NumPy loop"] = keep("np", _numpy_loop(nonlinear))
    t = compare(keep("lin", baseline), cands, repeat=args.repeat, warmup=False,
                baseline_label="baseline: linear mooring only")
    wall_nl, wall_lin = (t[k].median * args.duration for k in (
        "nonlinear mooring + Morison drag", "baseline: linear mooring only"))
    hist_nl, hist_lin = last["nl"], last["lin"]
    runs = [(name, t[name].median * args.duration, last[key]) for name, key in (
        ("nonlinear mooring + Morison drag", "nl"), ("baseline: linear mooring only", "lin"),
        ("nonlinear, NumPy loop", "np")) if name in t]
    for name, wall, hist in runs:
        z = hist["z"].values
        print(f"{name:34s} {args.duration:.0f} s simulated in {wall:7.2f} s wall: "
              f"{args.duration / wall:7.0f}x real time; std surge {z[:, 0].std():.3f} m, "
              f"heave {z[:, 1].std():.3f} m, pitch {z[:, 2].std():.5f} rad")
    print(f"nonlinear with the radiation fit inside the timing: "
          f"{args.duration / (wall_nl + t_fit):.0f}x real time")
    diff = np.abs(hist_nl["z"].values - hist_lin["z"].values).max(axis=0)
    print("largest difference nonlinear - linear: " + ", ".join(
        f"{d} {v:.4g} {'rad' if d == 'Pitch' else 'm'}" for d, v in zip(DOFS, diff)))
    if not args.no_numpy:
        hist_np = last["np"]
        rel = max(np.abs(hist_nl[v].values - hist_np[v].values).max()
                  / np.abs(hist_np[v].values).max() for v in ("z", "zdot", "F_tot"))
        wall_np = t["nonlinear, NumPy loop"].median * args.duration
        print(f"Numba vs NumPy loop: {wall_np / wall_nl:.1f}x "
              f"faster (medians), largest difference {rel:.1e} of each variable's range "
              f"(z, zdot, F_tot)")
    print(f"cost of the nonlinear forces: "
          f"{t['nonlinear mooring + Morison drag'].ratio_text()} the linear baseline "
          f"(steps {int(args.duration / args.dt)}, dt {args.dt} s)")
    print(conditions(repeat=args.repeat))


if __name__ == "__main__":
    main()
