"""Benchmark: the members' wave kinematics (``waves.AiryPoints``) as one complex
matrix-vector product per call against the direct sums of cosines and sines.

The OC4-DeepCwind semi's Morison elements (263 elements + 3 heave-plate discs, 1 m), a
JONSWAP sea (Hs 4 m, Tp 11 s, 200 components) at 30°, long-crested and spread (s = 5). The
baseline, in the same process, is the previous implementation: θ_ij = ω_j t + φ_ij on the
(points × components) grid, then Σ P cos θ, Σ Q sin θ and their ω-weighted sums (n × n_comp
cosines and sines per call); the candidate evaluates n_comp exponentials and one (3n × n_comp)
complex product. Timing: ``benchmarks/timing.py`` (samples of >= 0.2 s, baseline and
candidate alternated, ``--repeat`` rounds); prints the median ratio baseline/candidate with its
spread (min–max of the per-round ratios) and the largest difference. Also one ``MemberMorison.generalised_force`` call, where
the kinematics are most of the cost. Run: ``python benchmarks/bench_member_kinematics.py``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from hybridwsi.cases import load_case
from hybridwsi.forces import MemberMorison
from hybridwsi.waves import JONSWAP, AiryPoints, ramp_factor

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import REPEAT, Figure, compare, conditions  # noqa: E402


def trig_sums(kin: AiryPoints, t: float) -> tuple[np.ndarray, np.ndarray]:
    """The direct sums (the implementation before the complex product)."""
    theta = kin.omega * float(t) + kin.phase
    c, s = np.cos(theta), np.sin(theta)
    w = -np.sum(kin.vertical * s, axis=1)
    aw = -np.sum(kin.vertical * c * kin.omega, axis=1)
    pc, ps = kin.horizontal * c, -kin.horizontal * s * kin.omega
    f = float(ramp_factor(np.array([float(t)]), kin.ramp)[0]) if kin.ramp else 1.0
    return (np.column_stack([pc @ kin.direction, w]) * f,
            np.column_stack([ps @ kin.direction, aw]) * f)


def compare_calls(label: str, base, cand, times: np.ndarray, repeat: int) -> None:
    """Time ``base(t)`` and ``cand(t)`` over ``times`` (harness of ``benchmarks/timing.py``)."""
    res = compare(Figure(lambda: [base(t) for t in times], times.size),
                  {"candidate": Figure(lambda: [cand(t) for t in times], times.size)},
                  repeat=repeat)
    print(f"{label}: baseline {res['baseline'].median * 1e6:8.1f} us/call, candidate "
          f"{res['candidate'].median * 1e6:8.1f} us/call, speed-up "
          f"{res['candidate'].ratio_text(speedup=True)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=REPEAT + 2, help="alternating rounds")
    args = parser.parse_args()
    case = load_case("oc4_semi")
    times = np.linspace(0.0, 100.0, 37)
    for spread in (None, 5.0):
        sea = JONSWAP(hs=4.0, tp=11.0, seed=1, n_components=200,
                      direction=math.radians(30.0), spreading=spread)
        drag = MemberMorison.from_case(case, wave=sea, inertia=False)
        kin = drag._wave
        diff = max(float(np.abs(np.subtract(trig_sums(kin, t)[k],
                                            kin.velocity_acceleration(t)[k])).max())
                   for t in times[:5] for k in (0, 1))
        name = "long-crested" if spread is None else f"spread s={spread:g}"
        print(f"{name}: {kin.phase.shape[0]} points x {kin.omega.size} components, largest "
              f"difference {diff:.2e} m/s or m/s^2")
        compare_calls(f"  kinematics ({name})", lambda t: trig_sums(kin, t),
                lambda t: kin.velocity_acceleration(t), times, args.repeat)
        zdot = np.full(6, 0.01)
        cand = lambda t: drag.generalised_force(t, zdot)  # noqa: E731

        def base(t: float) -> None:
            kin.velocity_acceleration, saved = (lambda s: trig_sums(kin, s)), \
                kin.velocity_acceleration
            try:
                drag.generalised_force(t, zdot)
            finally:
                kin.velocity_acceleration = saved

        compare_calls(f"  MemberMorison.generalised_force ({name})", base, cand, times,
                      args.repeat)
    print(conditions(repeat=args.repeat))


if __name__ == "__main__":
    main()
