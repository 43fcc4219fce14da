"""Hybrid rollout cost per step vs the pure Cummins state-space step.

Targets (issue 14): one case <= 3x and a 32-case batch <= 1.5x the Cummins step per case-step.
Everything is measured in this process on the same synthetic sphere-like body:

- baseline: ``cummins.simulate`` (linear, radiation state space) per time step, excluding its
  one-off set-up (state-space fit), measured as the difference of two durations;
- hybrid: ``surrogate.rollout`` (recommended partition: hydrostatics + A∞ + excitation known,
  a 32-unit network with an 11-tap ż window learns the radiation memory), per step, for a
  batch of 1 and of 32 cases (per case-step), in the ``lagged`` coupling (one network call per
  step) and the ``corrected`` one (two), with the compiled loop
  (:mod:`hybridwsi.surrogate.fast`, Numba) and with the NumPy stepper;
- hybrid-physics: the NumPy stepper with the network replaced by its exact linear Jacobian,
  to separate the network's cost from the stepper's.

Times are CPU times of this process (best of a few runs). Run: ``python
benchmarks/bench_hybrid.py`` (about a minute; the first run also compiles the Numba loop,
~10 s, cached afterwards).
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import synthetic_hydro as sh

from hybridwsi import cummins, waves
from hybridwsi.surrogate import fast
from hybridwsi.surrogate import rollout as ro
from hybridwsi.surrogate.demo import make_histories, partitions
from hybridwsi.surrogate.network import ForceNetwork

torch.set_num_threads(1)
DT = 0.02


def best_of(fn, n=3) -> float:
    """Shortest CPU time [s] of ``n`` calls (every part is single-threaded; CPU time is what
    a shared machine does not inflate, and equals the wall time on an idle one)."""
    times = []
    for _ in range(n):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return min(times)


def main() -> None:
    co = sh.coefficients()
    ss = cummins.build_system(co, dofs=["Heave"], mass=None, radiation="statespace", dt=DT).ss
    wave = waves.JONSWAP(hs=0.05, tp=0.8, seed=1)

    def cum(duration):
        return lambda: cummins.simulate(co, duration=duration, dt=DT, wave=wave, radiation_ss=ss)

    n_long, n_short = 20000, 2000
    base = (best_of(cum(n_long * DT)) - best_of(cum(n_short * DT))) / (n_long - n_short)

    train = make_histories(co, sh.M, range(2), hs=0.05, tp=0.8, duration=30.0, dt=DT,
                           radiation_ss=ss)
    part = partitions(co)["recommended"]
    net = ForceNetwork(inputs=part["inputs"], hidden=(32,), window=11, stride=5, max_epochs=100,
                       lr=3e-3, batch_size=128).fit(train, "F_bb", known=part["known"])
    cases = make_histories(co, sh.M, range(100, 132), hs=0.05, tp=0.8, duration=n_long * DT,
                           dt=DT, radiation_ss=ss)
    steps = n_long - net.spec_.span - 1

    def hyb(batch, mode="lagged", compiled=None, n_steps=None):
        return lambda: ro.rollout(net, cases[:batch], mass=sh.M, known=part["known"], mode=mode,
                                  check=False, compiled=compiled, n_steps=n_steps)

    rows = []  # (label, us per case-step)
    if fast.HAVE_NUMBA:
        hyb(1, "corrected", True, 100)()  # compile (or load the cache) outside the timing
        for mode in ("lagged", "corrected"):
            rows.append((f"hybrid {mode:9s} compiled, 1 case  ",
                         best_of(hyb(1, mode), 3) / steps))
            rows.append((f"hybrid {mode:9s} compiled, 32 cases",
                         best_of(hyb(32, mode), 2) / steps / 32))
    n_np = 4000  # the NumPy stepper is slower: fewer steps
    for mode in ("lagged", "corrected"):
        rows.append((f"hybrid {mode:9s} NumPy,    1 case  ",
                     best_of(hyb(1, mode, False, n_np), 2) / n_np))
        rows.append((f"hybrid {mode:9s} NumPy,    32 cases",
                     best_of(hyb(32, mode, False, n_np), 1) / n_np / 32))

    # network replaced by its (averaged) exact Jacobian: the NumPy stepper's own cost
    from hybridwsi.surrogate.features import build_features
    from hybridwsi.surrogate.linearise import feature_jacobian

    jac = feature_jacobian(net, build_features(train[0], net.spec_)[::10]).mean(0)
    orig = ro._torch_force
    ro._torch_force = lambda _net: (lambda x: x @ jac.T)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rows.append(("stepper lagged, linear force, 1 case ",
                         best_of(hyb(1, "lagged", False, n_np), 2) / n_np))
    finally:
        ro._torch_force = orig

    print(f"pure Cummins state-space step            : {base * 1e6:8.3f} us/step (baseline, 1x)")
    for label, t in rows:
        print(f"{label}: {t * 1e6:8.3f} us/case-step   ratio {t / base:7.2f}x")
    if fast.HAVE_NUMBA:
        one, batch = rows[0][1] / base, rows[1][1] / base
        print(f"target 1 case <= 3x (lagged, compiled)        : {one:5.2f}x "
              f"{'met' if one <= 3 else 'NOT met'}")
        print(f"target 32-case batch <= 1.5x (lagged, compiled): {batch:5.2f}x "
              f"{'met' if batch <= 1.5 else 'NOT met'}")
    else:
        print("Numba not installed: no compiled loop (pip install numba)")


if __name__ == "__main__":
    main()
