"""Benchmark: hybridwsi's BEM run (axisymmetric mesh, one BLAS thread) vs plain Capytaine on the
full (non-symmetric) mesh, both with the same panels, lid and direct method.

The baseline is timed on a few frequencies only (20-45 s and ~2 GB each at 6400 panels) and
extrapolated to the full frequency list; ours runs the full list (cache disabled). Both are
measured in the same process, ``--repeat`` rounds alternating them (``benchmarks/timing.py``:
medians, speed-up with its spread). Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bem.py            # paper set-up (~25 min)
    python benchmarks/bench_bem.py --panels 1600 --n-omega 40         # quick look
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import REPEAT, Figure, compare, conditions  # noqa: E402


def baseline_figure(body, omegas, resolution) -> Figure:
    """Capytaine on the full mesh (radiation + diffraction), per frequency."""
    import capytaine as cpt

    from hybridwsi.hydro.bem import blas_single_thread

    cbody = body.capytaine_body(("Heave",), resolution=resolution, symmetric=False, lid=True)
    solver = cpt.BEMSolver(method="direct")
    grid = xr.Dataset(coords={"omega": omegas, "radiating_dof": ["Heave"], "wave_direction": [0.0],
                              "water_depth": [np.inf], "rho": [body.rho], "g": [body.g]})

    def run() -> None:
        with blas_single_thread():
            solver.fill_dataset(grid, cbody, hydrostatics=False, progress_bar=False)
    return Figure(run, len(omegas))


def main() -> None:
    from hybridwsi.bodies import FloatingSphere
    from hybridwsi.hydro import bem

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--panels", type=int, default=6400)
    p.add_argument("--n-omega", type=int, default=400)
    p.add_argument("--n-baseline", type=int, default=2, help="frequencies timed for the baseline")
    p.add_argument("--repeat", type=int, default=REPEAT,
                   help="alternating rounds (each runs all three: about 5 min on the paper "
                        "set-up)")
    p.add_argument("--jobs", type=int, default=None,
                   help="hybridwsi worker processes (default: automatic, all CPUs here)")
    args = p.parse_args()

    body = FloatingSphere.paper()
    omega = np.geomspace(0.1, 40.0, args.n_omega)
    resolution = body.resolution_for(args.panels)

    last = {}
    n_solved = args.n_omega + 2  # + omega = 0, inf

    def ours(n_jobs):
        return lambda: last.update(ours=bem.compute(body, omega, n_panels=args.panels,
                                                    use_cache=False, progress=False,
                                                    n_jobs=n_jobs))
    sample = np.geomspace(1.0, 20.0, args.n_baseline)
    t = compare(baseline_figure(body, sample, resolution),
                {"ours": Figure(ours(args.jobs), n_solved),
                 "one process": Figure(ours(1), n_solved)},  # what the worker pool buys
                repeat=args.repeat, warmup=False, baseline_label="capytaine")
    ours = last["ours"]
    t_ours, t_one = t["ours"].median * n_solved, t["one process"].median * n_solved
    t_base = t["capytaine"].median
    t_base_total = t_base * args.n_omega
    print(f"mesh: {ours.attrs['n_panels']} hull + {ours.attrs['n_lid_panels']} lid panels, "
          f"{args.n_omega} frequencies (+ omega = 0, inf)")
    print(f"hybridwsi (axisymmetric): {t_ours:8.1f} s total, {t_ours / (args.n_omega + 2):.3f} s/omega")
    print(f"  same on one process   : {t_one:8.1f} s -> workers give {t_one / t_ours:.2f} x")
    print(f"capytaine full mesh     : {t_base:8.2f} s/omega (timed on {args.n_baseline}), "
          f"extrapolated {t_base_total:8.0f} s")
    print(f"speed-up (extrapolated) : {t['ours'].ratio_text(speedup=True)} per omega")
    print(f"A_inf = {float(ours['added_mass_inf'][0, 0]):.4f} kg")
    print(conditions(repeat=args.repeat))


if __name__ == "__main__":
    main()
