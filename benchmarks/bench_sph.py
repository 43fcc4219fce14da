"""Particle updates per second of the hybridwsi SPH tank vs PySPH's stock WCSPH scheme.

Both are measured in this process on the same particle positions (our case's fluid and wall
particles), with OpenMP on ``OMP_NUM_THREADS`` threads (default 2). The ratio ours/stock is
what to compare between machines; absolute rates depend on the load. Timing:
``benchmarks/timing.py`` (samples of >= 0.2 s of whole steps, ``--repeat`` rounds alternating
stock and ours, median rates and the ratio's spread; the load average is printed).
OpenMP threads sleep at barriers (``OMP_WAIT_POLICY=passive``, set by ``hybridwsi.sph.run``
unless given): spinning threads made the 2-thread rate 2-7x lower whenever another job held a core.

    OMP_NUM_THREADS=2 python benchmarks/bench_sph.py [--skip3d] [--repeat 5]

The first run compiles 4 kernel sets (about a minute each); later runs use PySPH's cache.
Measured rates before and after the engine-speed work (issue 15 item 9): docs/SPH_RUNS.md,
section "Engine speed".
"""

from __future__ import annotations

import argparse
import itertools
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "2")
sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import REPEAT, Figure, compare, conditions  # noqa: E402

#: recorded before/after of the engine-speed work, 2D case, particle-updates/s, best of 5 x 40
#: steps, load average 2.8-3.0 (docs/SPH_RUNS.md, "Engine speed")
RECORDED = ("recorded 2D (main 2012cb3 -> now, load 2.8-3.0): 1 thread 9.1-9.4e5 -> 1.04-1.06e6; "
            "2 threads spinning median 1.7-1.8e5, passive 9.0-9.4e5 -> 0.99-1.02e6")


def _stepper(solver, n_particles: int, dt: float) -> Figure:
    """One integrator step per call (after a warm-up step: the first neighbour build), per
    particle update."""
    integ = solver.integrator
    integ.initial_acceleration(0.0, dt)
    integ.step(0.0, dt)
    k = itertools.count(1)
    return Figure(lambda: integ.step(next(k) * dt, dt), n_particles)


def ours(case) -> Figure:
    from hybridwsi.sph.run import make_solver

    return _stepper(make_solver(case, openmp=True), case.n_particles, case.dt)


def stock(case) -> Figure:
    """PySPH's WCSPHScheme (dynamic boundary, Tait, Monaghan AV, XSPH) on the same points."""
    from compyle.config import get_config
    from pysph.base.kernels import WendlandQuintic
    from pysph.base.nnps import LinkedListNNPS
    from pysph.base.utils import get_particle_array_wcsph
    from pysph.sph.scheme import WCSPHScheme

    get_config().use_openmp = True
    f, w = case.fluid, case.wall
    xyz = ("x", "y", "z")[: case.dim]
    fluid = get_particle_array_wcsph(name="fluid", **{k: f.get(k) for k in xyz}, h=case.h,
                                     m=f.get("m"), rho=f.get("rho"))
    bnd = get_particle_array_wcsph(name="boundary", **{k: w.get(k) for k in xyz}, h=case.h,
                                   m=w.get("m"), rho=case.rho0)
    g = dict(zip(("gx", "gy", "gz"), case.gvec))
    scheme = WCSPHScheme(["fluid"], ["boundary"], dim=case.dim, rho0=case.rho0, c0=case.c0,
                         h0=case.h, hdx=case.hdx, alpha=case.alpha, hg_correction=True, **g)
    scheme.setup_properties([fluid, bnd])
    kernel = WendlandQuintic(dim=case.dim)
    scheme.configure_solver(kernel=kernel, dt=case.dt, tf=1.0)
    solver = scheme.get_solver()
    solver.set_disable_output(True)
    solver.set_parallel_manager(None)
    nnps = LinkedListNNPS(dim=case.dim, particles=[fluid, bnd], radius_scale=kernel.radius_scale,
                          fixed_h=True)
    solver.setup(particles=[fluid, bnd], equations=scheme.get_equations(), nnps=nnps,
                 kernel=kernel, fixed_h=True)
    return _stepper(solver, case.n_particles, case.dt)


def main() -> None:
    from hybridwsi.sph import tank

    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--skip3d", action="store_true")
    ap.add_argument("--repeat", type=int, default=REPEAT, help="alternating rounds")
    a = ap.parse_args()
    cases = [("2D hydrostatic tank 2.5 m x 1 m, dp = 0.01 m",
              tank.hydrostatic(dp=0.01, depth=1.0, length=2.5, init="hydrostatic"))]
    if not a.skip3d:
        cases.append(("3D sphere decay, quarter domain 1.2 x 1.2 x 0.9 m, dp = 0.025 m",
                      # the lattice start, fixed hold and wall viscosity of the README's
                      # recorded rate
                      tank.decay3d(dp=0.025, packing="lattice", relax=0.0, alpha_wall=None)))
    import hybridwsi.sph.run  # noqa: F401 - sets OMP_WAIT_POLICY before OpenMP loads

    print(f"OMP_NUM_THREADS={os.environ['OMP_NUM_THREADS']} "
          f"OMP_WAIT_POLICY={os.environ.get('OMP_WAIT_POLICY')}")
    for desc, case in cases:
        t = compare(stock(case), {"ours": ours(case)}, repeat=a.repeat, warmup=False,
                    baseline_label="stock")
        print(f"{desc}: {case.n_particles} particles ({case.fluid.get_number_of_particles()} "
              f"fluid)")
        print(f"  hybridwsi tank (Adami walls, density diffusion, body coupling): "
              f"{1 / t['ours'].median:.3g} particle-updates/s (median)")
        print(f"  PySPH stock WCSPHScheme (dynamic boundary):                    "
              f"{1 / t['stock'].median:.3g} particle-updates/s (median)")
        print(f"  ratio ours / stock (rates) = {t['ours'].ratio_text(speedup=True)}")
    print(conditions(repeat=a.repeat))
    print(RECORDED)

if __name__ == "__main__":
    main()
