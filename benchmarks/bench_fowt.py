"""Benchmark: one hour of OC3-Hywind in a JONSWAP sea, 3 DOF (surge, heave, pitch).

The run: the shipped Capytaine coefficients, the radiation state space, the tabulated
nonlinear MoorPy mooring (``MooringForce``), Morison strip drag with the wave particle velocity
(``MorisonDrag``, 120 strips, Cd 0.6) and the additional linear damping, in a JONSWAP sea
(Hs 6 m, Tp 10 s, γ 3.3, 100 components), dt 0.1 s, RK4 (``cummins.simulate``'s stepping
solver). Prints simulated time / wall time (target ≥ 1000× real time). Baseline in the same
process: the same run with the mooring as its linearised stiffness only and no drag (still the
stepping solver, since the stiffness is passed as a force component). Best of ``--repeat``.
Run: ``python benchmarks/bench_fowt.py [--duration 3600] [--dt 0.1]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hybridwsi.cases import load_case
from hybridwsi.cummins import simulate
from hybridwsi.forces import MooringForce, MorisonDrag
from hybridwsi.report.fowt import DOFS, linear_forces, oc3_coefficients
from hybridwsi.waves import JONSWAP


def _best_wall(run, repeat: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = run()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=3600.0, help="simulated time [s]")
    parser.add_argument("--dt", type=float, default=0.1, help="time step [s]")
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args(argv)

    case = load_case("oc3_hywind")
    coeffs = oc3_coefficients(case)
    wave = JONSWAP(hs=6.0, tp=10.0, gamma=3.3, seed=1, n_components=100)
    mooring = MooringForce.from_case(case, list(DOFS))
    linear = linear_forces(case, mooring.table.stiffness())  # [−K z, B_add]
    drag = MorisonDrag.from_case(case, list(DOFS), wave=wave, ramp=60.0)
    kw = dict(dofs=DOFS, duration=args.duration, dt=args.dt, wave=wave, ramp=60.0)

    def nonlinear():
        return simulate(coeffs, forces=[mooring, drag, linear[1]], **kw)

    def baseline():
        return simulate(coeffs, forces=linear, **kw)

    wall_nl, hist_nl = _best_wall(nonlinear, args.repeat)
    wall_lin, hist_lin = _best_wall(baseline, args.repeat)
    for name, wall, hist in (("nonlinear mooring + Morison drag", wall_nl, hist_nl),
                             ("baseline: linear mooring only", wall_lin, hist_lin)):
        z = hist["z"].values
        print(f"{name:34s} {args.duration:.0f} s simulated in {wall:7.2f} s wall: "
              f"{args.duration / wall:7.0f}x real time; std surge {z[:, 0].std():.3f} m, "
              f"heave {z[:, 1].std():.3f} m, pitch {z[:, 2].std():.5f} rad")
    diff = np.abs(hist_nl["z"].values - hist_lin["z"].values).max(axis=0)
    print("largest difference nonlinear - linear: " + ", ".join(
        f"{d} {v:.4g} {'rad' if d == 'Pitch' else 'm'}" for d, v in zip(DOFS, diff)))
    print(f"cost of the nonlinear forces: {wall_nl / wall_lin:.2f}x the linear baseline "
          f"(steps {int(args.duration / args.dt)}, dt {args.dt} s)")


if __name__ == "__main__":
    main()
