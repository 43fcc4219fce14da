"""Benchmark: hybridwsi's BEM run (axisymmetric mesh, one BLAS thread) vs plain Capytaine on the
full (non-symmetric) mesh, both with the same panels, lid and direct method.

The baseline is timed on a few frequencies only (20-45 s and ~2 GB each at 6400 panels) and
extrapolated to the full frequency list; ours runs the full list (cache disabled). Both are
measured in the same process. Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bem.py            # paper set-up (~8-10 min)
    python benchmarks/bench_bem.py --panels 1600 --n-omega 40         # quick look
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import xarray as xr


def baseline_per_omega(body, omegas, resolution) -> float:
    """Mean wall time [s] per frequency (radiation + diffraction) of Capytaine, full mesh."""
    import capytaine as cpt

    from hybridwsi.hydro.bem import blas_single_thread

    cbody = body.capytaine_body(("Heave",), resolution=resolution, symmetric=False, lid=True)
    solver = cpt.BEMSolver(method="direct")
    grid = xr.Dataset(coords={"omega": omegas, "radiating_dof": ["Heave"], "wave_direction": [0.0],
                              "water_depth": [np.inf], "rho": [body.rho], "g": [body.g]})
    with blas_single_thread():
        start = time.perf_counter()
        solver.fill_dataset(grid, cbody, hydrostatics=False, progress_bar=False)
        return (time.perf_counter() - start) / len(omegas)


def main() -> None:
    from hybridwsi.bodies import FloatingSphere
    from hybridwsi.hydro import bem

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--panels", type=int, default=6400)
    p.add_argument("--n-omega", type=int, default=400)
    p.add_argument("--n-baseline", type=int, default=2, help="frequencies timed for the baseline")
    p.add_argument("--jobs", type=int, default=None,
                   help="hybridwsi worker processes (default: automatic, all CPUs here)")
    args = p.parse_args()

    body = FloatingSphere.paper()
    omega = np.geomspace(0.1, 40.0, args.n_omega)
    resolution = body.resolution_for(args.panels)

    start = time.perf_counter()
    ours = bem.compute(body, omega, n_panels=args.panels, use_cache=False, progress=True,
                       n_jobs=args.jobs)
    t_ours = time.perf_counter() - start
    # the same sweep on one process: what the worker pool buys
    start = time.perf_counter()
    bem.compute(body, omega, n_panels=args.panels, use_cache=False, progress=True, n_jobs=1)
    t_one = time.perf_counter() - start

    sample = np.geomspace(1.0, 20.0, args.n_baseline)
    t_base = baseline_per_omega(body, sample, resolution)
    t_base_total = t_base * args.n_omega

    print(f"mesh: {ours.attrs['n_panels']} hull + {ours.attrs['n_lid_panels']} lid panels, "
          f"{args.n_omega} frequencies (+ omega = 0, inf)")
    print(f"hybridwsi (axisymmetric): {t_ours:8.1f} s total, {t_ours / (args.n_omega + 2):.3f} s/omega")
    print(f"  same on one process   : {t_one:8.1f} s -> workers give {t_one / t_ours:.2f} x")
    print(f"capytaine full mesh     : {t_base:8.2f} s/omega (timed on {args.n_baseline}), "
          f"extrapolated {t_base_total:8.0f} s")
    print(f"speed-up (extrapolated) : {t_base_total / t_ours:8.1f} x")
    print(f"A_inf = {float(ours['added_mass_inf'][0, 0]):.4f} kg")


if __name__ == "__main__":
    main()
