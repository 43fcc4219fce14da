"""Benchmark: the tabulated mooring interpolant against a MoorPy solve per evaluation (target ≥ 100×).

Times :meth:`hybridwsi.forces.mooring.MooringTable.force6` (the OC3-Hywind mooring, default box)
on one state and on a batch of 32 states (its Numba kernel when Numba is installed; the NumPy
float path, the fallback without Numba, is timed too), and two MoorPy baselines measured in
the same process, :meth:`MooringSystem.force6` (MoorPy placing the body and statically solving
its three catenary lines) per state:

- from random states of the box, each solve started from the previous, unrelated state;
- along a smooth time-loop path (0.1 s steps), each solve warm-started from the previous
  step's, MoorPy's fastest use. This is the fair per-evaluation baseline for the time loop
  (the interpolant replaces MoorPy inside the ODE, where consecutive states are close); the
  random-state one is what a single isolated evaluation costs.

Best of ``--repeat`` runs each, so a loaded machine slows both sides alike. Also prints the
largest interpolation error on the benchmark states, relative to each DOF's force scale.
Run: ``python benchmarks/bench_mooring.py`` (needs ``hybridwsi[mooring]``).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hybridwsi.cases import load_case
from hybridwsi.forces._compiled import HAVE_NUMBA
from hybridwsi.forces.mooring import MooringSystem


def _best_per_call(fn, calls: int, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - t0) / calls)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=2000, help="interpolant calls per run")
    parser.add_argument("--repeat", type=int, default=5, help="best of this many runs")
    parser.add_argument("--batch", type=int, default=32, help="states per batch call")
    args = parser.parse_args()

    case = load_case("oc3_hywind")
    system = MooringSystem.from_case(case)
    import hybridwsi.forces._compiled  # noqa: F401  loads (or compiles) the kernels untimed
    t0 = time.perf_counter()
    table = system.tabulate()
    t_build = time.perf_counter() - t0
    half = np.array(list(table.ranges.values()))
    states = np.random.default_rng(0).uniform(-1.0, 1.0, (args.batch, 6)) * half
    # a time-loop trajectory: half the box, periods 20-125 s, 0.1 s steps (MoorPy warm-starts
    # each catenary from the previous solve, its fastest use)
    t = np.arange(20_000)[:, None] * 0.1
    path = 0.5 * half * np.sin(2 * np.pi * t / np.array([125, 110, 31, 29, 29, 8.3]) + 0.3)
    cycle, walk = iter(np.tile(states, (10_000, 1))), iter(path)

    t_random = _best_per_call(lambda: system.force6(next(cycle)), 64, args.repeat)
    t_moorpy = _best_per_call(lambda: system.force6(next(walk)), 200, args.repeat)
    t_single = _best_per_call(lambda: table.force6(next(cycle)), args.calls, args.repeat)
    t_batch = _best_per_call(lambda: table.force6(states), args.calls // 10, args.repeat)
    t_numpy = _best_per_call(lambda: table._force6_scalar(next(cycle)), args.calls // 4,
                             args.repeat)
    exact = np.array([system.force6(q) for q in states])
    scale = np.abs(exact - system.preload()).max(axis=0)
    error = np.abs(table.force6(states) - exact).max(axis=0) / scale

    print(f"table {table.dataset.sizes['l_h']} x {table.dataset.sizes['l_v']} "
          f"(l_h x l_v), built in {t_build:.2f} s; evaluation "
          f"{'Numba kernel' if HAVE_NUMBA else 'NumPy (no Numba)'}")
    print(f"MoorPy solve, random states  : {t_random * 1e6:9.1f} us   (interpolant single: "
          f"ratio {t_random / t_single:.0f}x)")
    print(f"MoorPy solve along a path    : {t_moorpy * 1e6:9.1f} us   (baseline below)")
    print(f"interpolant, single state    : {t_single * 1e6:9.1f} us   ratio {t_moorpy / t_single:6.0f}x")
    print(f"interpolant, batch of {args.batch:<3d}    : {t_batch * 1e6:9.1f} us   "
          f"{t_batch / args.batch * 1e6:.1f} us/state, ratio {args.batch * t_moorpy / t_batch:6.0f}x")
    print(f"interpolant, single, NumPy   : {t_numpy * 1e6:9.1f} us   ratio {t_moorpy / t_numpy:6.0f}x "
          f"(the fallback without Numba)")
    print(f"target >= 100x               : single {'met' if t_moorpy / t_single >= 100 else 'NOT met'}, "
          f"batch {'met' if args.batch * t_moorpy / t_batch >= 100 else 'NOT met'}")
    print("max error / force scale per DOF: " + ", ".join(f"{e:.1e}" for e in error))


if __name__ == "__main__":
    main()
