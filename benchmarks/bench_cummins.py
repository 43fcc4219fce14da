"""Benchmark the Cummins solver: state space vs direct convolution, and batched ensembles.

Run: ``python benchmarks/bench_cummins.py [--panels 600] [--duration 600] [--cases 1000]``.

1. 10 min of simulated time at Δt = 0.01 s (regular waves, the paper's T = 0.75 s, H = 0.05 m)
   with ``radiation="convolution"`` (Newmark + trapezoidal memory integral, the reference) and
   ``radiation="statespace"`` (exact FOH discretisation, modal lfilter), both measured here in
   the same process; prints the speed-up and the RMS difference of z.
   Timing: ``benchmarks/timing.py`` (samples of >= 0.2 s, ``--repeat`` alternating rounds,
   median speed-up with its spread).
2. ``simulate_batch`` of N cases (decay drops and regular waves) vs one ``simulate`` run of the
   same length: cost per case and the ratio.

Coefficients: Capytaine on a coarse mesh of the paper's sphere (cached after the first run).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import REPEAT, Figure, compare, conditions, sample  # noqa: E402


def _coefficients(panels: int, n_omega: int):
    from hybridwsi.bodies import FloatingSphere
    from hybridwsi.hydro import bem
    from hybridwsi.hydro.irf import radiation_irf

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # coarse-mesh warnings at high ω
        co = bem.compute(FloatingSphere.paper(), np.geomspace(0.1, 40.0, n_omega),
                         n_panels=panels, progress=False)
        return co, radiation_irf(co)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--panels", type=int, default=600)
    p.add_argument("--n-omega", type=int, default=60)
    p.add_argument("--duration", type=float, default=600.0, help="simulated time [s]")
    p.add_argument("--dt", type=float, default=0.01)
    p.add_argument("--cases", type=int, default=1000)
    p.add_argument("--batch-duration", type=float, default=20.0)
    p.add_argument("--repeat", type=int, default=REPEAT, help="alternating rounds")
    args = p.parse_args()

    from hybridwsi import cummins
    from hybridwsi.cummins.solvers import solve_convolution, solve_linear
    from hybridwsi.hydro.statespace import fit_radiation_ss
    from hybridwsi.waves import Regular

    co, k = _coefficients(args.panels, args.n_omega)
    wave = Regular(0.75, 0.05)
    kw = dict(duration=args.duration, dt=args.dt, wave=wave, ramp=2.0, z0=0.01, irf=k)
    print(f"kernel: {k.sizes['time']} samples to t = {float(k.time[-1]):.2f} s; "
          f"{int(round(args.duration / args.dt))} steps of {args.dt} s")

    ss = fit_radiation_ss(k, tol=0.005, coeffs=co)
    t_fit = sample(lambda: fit_radiation_ss(k, tol=0.005, coeffs=co))
    run_ss = lambda: cummins.simulate(co, radiation_ss=ss, **kw)  # noqa: E731
    run_cv = lambda: cummins.simulate(co, radiation="convolution", **kw)  # noqa: E731
    h_ss, h_cv = run_ss(), run_cv()
    t = compare(Figure(run_cv), {"state space": Figure(run_ss)}, repeat=args.repeat,
                warmup=False, baseline_label="convolution")
    z_ss, z_cv = h_ss.z.values[:, 0], h_cv.z.values[:, 0]
    diff = np.linalg.norm(z_ss - z_cv) / np.linalg.norm(z_cv)
    t_ss, t_cv = t["state space"].median, t["convolution"].median
    print(f"state-space fit: order {ss.order}, {t_fit * 1e3:.1f} ms")
    print(f"end to end (forcing + solver + TimeHistory): convolution {t_cv:.3f} s, "
          f"state space {t_ss:.3f} s -> speed-up {t['state space'].ratio_text(speedup=True)} "
          f"(including the fit: {t_cv / (t_ss + t_fit):.1f}x); RMS diff of z {diff:.3%}")

    # integration only, same forcing array: the part the radiation method changes
    sys_ss = cummins.build_system(co, radiation_ss=ss)
    sys_cv = cummins.build_system(co, radiation="convolution", dt=args.dt, irf=k)
    u = h_ss.F_exc.values + h_ss.F_ext.values
    z0, v0 = np.array([0.01]), np.array([0.0])
    t = compare(Figure(lambda: solve_convolution(sys_cv, u, z0, v0, args.dt)),
                {"state space": Figure(lambda: solve_linear(sys_ss, u, z0, v0, args.dt))},
                repeat=args.repeat, baseline_label="convolution")
    print(f"integration only: convolution {t['convolution'].median:.3f} s, state space "
          f"{t['state space'].median * 1e3:.2f} ms -> speed-up "
          f"{t['state space'].ratio_text(speedup=True)} (target >= 100x, median)")

    rng = np.random.default_rng(0)
    cases = []
    for c in range(args.cases):
        if c % 2:
            cases.append({"z0": float(rng.uniform(-0.03, 0.03))})
        else:
            cases.append({"wave": Regular(float(rng.uniform(0.6, 1.5)),
                                          float(rng.uniform(0.01, 0.06)))})
    bkw = dict(duration=args.batch_duration, dt=args.dt, ramp=2.0, radiation_ss=ss)
    last = {}
    t = compare(Figure(lambda: cummins.simulate(co, **cases[0], **bkw)),
                {"batch": Figure(lambda: last.update(batch=cummins.simulate_batch(co, cases,
                                                                                  **bkw)),
                                 args.cases)},
                repeat=args.repeat, baseline_label="one simulate()")
    per_case, t_one = t["batch"].median, t["one simulate()"].median
    print(f"batch of {args.cases} cases x {args.batch_duration:g} s: "
          f"{per_case * args.cases:.2f} s ({per_case * 1e3:.2f} ms/case) vs one simulate(): "
          f"{t_one * 1e3:.1f} ms -> {t['batch'].ratio_text(speedup=True)} cheaper per case")
    assert np.all(np.isfinite(last["batch"].z.values))
    print(conditions(repeat=args.repeat))

if __name__ == "__main__":
    main()
