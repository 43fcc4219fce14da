"""Benchmark: vectorised Morison strip drag against a plain-Python loop over the strips.

Times :meth:`hybridwsi.forces.morison.MorisonDrag.ode_force` for the OC3-Hywind spar (the
case's 120 strips, Cd 0.6) on one state and on a batch of 32 states, in two set-ups:
Surge/Heave/Pitch in still water (the 3-DOF head-sea model) and all 6 DOFs with the Airy
velocity of a JONSWAP sea (100 components, 30° off the x axis). The baseline, measured in the
same process, is the same formula written as a Python loop over strips (and wave components,
their cosines computed once per state), one state at a time, as one would write it without
NumPy. The Numba kernel the compiled RK4 loop calls (``MorisonDrag.compiled_force``) is timed
on single states too (called from Python, so the call overhead is included). Timing:
``benchmarks/timing.py`` (samples of >= 0.2 s, ``--repeat`` rounds alternating baseline and
candidates, median speed-up with its spread); also prints the largest difference.
Run: ``python benchmarks/bench_morison.py``.
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
from pathlib import Path

import numpy as np

from hybridwsi.cases import load_case
from hybridwsi.forces.morison import MorisonDrag
from hybridwsi.waves import JONSWAP

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import REPEAT, Figure, compare, conditions  # noqa: E402


def loop_baseline(drag: MorisonDrag):
    """The drag as a plain-Python function of (t, rates): loops over strips and components."""
    strips = [(float(c), list(map(float, jx)), list(map(float, jy)))
              for c, jx, jy in zip(drag.coef, drag._jx, drag._jy)]
    wave = drag._wave
    comps, prof = [], []
    if wave is not None:
        comps = list(zip(wave.omega.tolist(), wave.phase.tolist()))
        prof = wave.profile.tolist()
        cb, sb = wave.cos_beta, wave.sin_beta
    n = len(drag.dofs)

    def force(t: float, v: list[float]) -> list[float]:
        out = [0.0] * n
        phasors = [math.cos(w * t + ph) for w, ph in comps]  # once per state, not per strip
        for k, (c, jx, jy) in enumerate(strips):
            ux = -sum(jx[i] * v[i] for i in range(n))
            uy = -sum(jy[i] * v[i] for i in range(n))
            if comps:
                u = sum(p * cph for p, cph in zip(prof[k], phasors))
                ux += u * cb
                uy += u * sb
            s = c * math.hypot(ux, uy)
            for i in range(n):
                out[i] += s * (ux * jx[i] + uy * jy[i])
        return out

    return force


def run(label: str, drag: MorisonDrag, states: np.ndarray, repeat: int) -> None:
    base = loop_baseline(drag)
    rows = [s.tolist() for s in states]
    it = itertools.cycle(range(len(rows)))
    n = len(rows)
    figures = {
        "vectorised, single state": Figure(lambda: drag.ode_force(1.7, None, states[next(it)],
                                                                  None)),
        f"vectorised, batch of {n}, per state": Figure(
            lambda: drag.ode_force(1.7, None, states, None), n)}
    kern = drag.compiled_force(states.shape[1])  # None without Numba
    if kern is not None:
        out, zero = np.empty(states.shape[1]), np.zeros(states.shape[1])
        times = itertools.count(1.7, 0.05)  # distinct t: no cached wave speed
        figures["Numba kernel (compiled loop), single"] = Figure(
            lambda: kern.kernel(next(times), zero, states[next(it)], out, kern.fdata,
                                kern.idata))
    res = compare(Figure(lambda: base(1.7, rows[next(it)])), figures, repeat=repeat,
                  baseline_label="Python loop over strips, per state")
    ref = np.array([base(1.7, r) for r in rows])
    got = drag.ode_force(1.7, None, states, None)
    err = np.abs(got - ref).max() / np.abs(ref).max()
    print(f"{label}")
    for name, t in res.items():
        ratio = "(baseline)" if t.ratios is None else f"speed-up {t.ratio_text(speedup=True)}"
        print(f"  {name:38s}: {t.median * 1e6:9.2f} us   {ratio}")
    print(f"  max |difference| / max |force|        : {err:.1e}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=REPEAT, help="alternating rounds")
    parser.add_argument("--batch", type=int, default=32, help="states per batch call")
    args = parser.parse_args()

    case = load_case("oc3_hywind")
    rng = np.random.default_rng(0)
    still = MorisonDrag.from_case(case)  # Surge, Heave, Pitch; no wave kinematics
    print(f"{still.describe()}")
    scale3 = np.array([1.0, 0.5, 0.02])  # m/s, m/s, rad/s
    run("3 DOF, still water", still, rng.normal(size=(args.batch, 3)) * scale3, args.repeat)
    sea = JONSWAP(hs=6.0, tp=12.0, gamma=3.3, seed=1, n_components=100, direction=math.pi / 6)
    waves = MorisonDrag.from_case(case, case["dofs"], wave=sea)
    scale6 = np.array([1.0, 1.0, 0.5, 0.02, 0.02, 0.05])
    run("6 DOF, JONSWAP wave kinematics (100 components)", waves,
        rng.normal(size=(args.batch, 6)) * scale6, args.repeat)
    print(conditions(repeat=args.repeat))


if __name__ == "__main__":
    main()
