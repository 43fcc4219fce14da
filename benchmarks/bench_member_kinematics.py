"""Benchmark: the members' wave kinematics (``waves.AiryPoints``) as one complex
matrix-vector product per call against the direct sums of cosines and sines.

The OC4-DeepCwind semi's Morison elements (263 elements + 3 heave-plate discs, 1 m), a
JONSWAP sea (Hs 4 m, Tp 11 s, 200 components) at 30°, long-crested and spread (s = 5). The
baseline, in the same process, is the previous implementation: θ_ij = ω_j t + φ_ij on the
(points × components) grid, then Σ P cos θ, Σ Q sin θ and their ω-weighted sums (n × n_comp
cosines and sines per call); the candidate evaluates n_comp exponentials and one (3n × n_comp)
complex product. Samples of >= 0.2 s, baseline and candidate alternated, ``--repeat`` pairs
(>= 5); prints the median ratio baseline/candidate with its spread (min–max of the per-pair
ratios) and the largest difference. Also one ``MemberMorison.generalised_force`` call, where
the kinematics are most of the cost. Run: ``python benchmarks/bench_member_kinematics.py``.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from hybridwsi.cases import load_case
from hybridwsi.forces import MemberMorison
from hybridwsi.waves import JONSWAP, AiryPoints, ramp_factor


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


def _sample(fn, times: np.ndarray, min_time: float = 0.2) -> float:
    """Seconds per call over at least ``min_time`` s."""
    calls, start = 0, time.perf_counter()
    while True:
        for t in times:
            fn(t)
        calls += times.size
        elapsed = time.perf_counter() - start
        if elapsed >= min_time:
            return elapsed / calls


def compare(label: str, base, cand, times: np.ndarray, repeat: int) -> None:
    ratios, tb, tc = [], [], []
    for _ in range(repeat):
        b, c = _sample(base, times), _sample(cand, times)
        tb.append(b)
        tc.append(c)
        ratios.append(b / c)
    print(f"{label}: baseline {np.median(tb) * 1e6:8.1f} us/call, candidate "
          f"{np.median(tc) * 1e6:8.1f} us/call, ratio median {np.median(ratios):.2f}x "
          f"(min {min(ratios):.2f}, max {max(ratios):.2f}, {repeat} pairs)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
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
        compare(f"  kinematics ({name})", lambda t: trig_sums(kin, t),
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

        compare(f"  MemberMorison.generalised_force ({name})", base, cand, times, args.repeat)


if __name__ == "__main__":
    main()
