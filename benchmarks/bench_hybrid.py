"""Hybrid rollout cost per step vs the pure Cummins state-space step (target <= 3x).

Everything is measured in this process on the same synthetic sphere-like body:

- baseline: ``cummins.simulate`` (linear, radiation state space) per time step, excluding its
  one-off set-up (state-space fit), measured as the difference of two durations;
- hybrid: ``surrogate.rollout`` (lagged, recommended partition: hydrostatics + A∞ + excitation
  known, a 32-unit network with an 11-tap ż window learns the radiation memory), per step, for
  a batch of 1 and of 32 cases (per case-step);
- hybrid-physics: the same stepper with the network replaced by its exact linear Jacobian in
  numpy, to separate the network's cost from the stepper's.

Run: ``python benchmarks/bench_hybrid.py`` (about a minute).
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
from hybridwsi.surrogate import rollout as ro
from hybridwsi.surrogate.demo import make_histories, partitions
from hybridwsi.surrogate.network import ForceNetwork

torch.set_num_threads(1)
DT = 0.02


def best_of(fn, n=3) -> float:
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    co = sh.coefficients()
    ss = cummins.build_system(co, dofs=["Heave"], mass=None, radiation="statespace", dt=DT).ss
    wave = waves.JONSWAP(hs=0.05, tp=0.8, seed=1)

    def cum(duration):
        return lambda: cummins.simulate(co, duration=duration, dt=DT, wave=wave, radiation_ss=ss)

    n_long, n_short = 20000, 2000
    base = (best_of(cum(n_long * DT)) - best_of(cum(n_short * DT))) / (n_long - n_short)

    train = make_histories(co, sh.M, range(2), hs=0.05, tp=0.8, duration=30.0, dt=DT)
    part = partitions(co)["recommended"]
    net = ForceNetwork(inputs=part["inputs"], hidden=(32,), window=11, stride=5, max_epochs=100,
                       lr=3e-3, batch_size=128).fit(train, "F_bb", known=part["known"])
    cases = make_histories(co, sh.M, range(100, 132), hs=0.05, tp=0.8, duration=n_long * DT, dt=DT)
    steps = n_long - net.spec_.span - 1

    def hyb(batch):
        return lambda: ro.rollout(net, cases[:batch], mass=sh.M, known=part["known"], check=False)

    t1 = best_of(hyb(1), 2) / steps
    t32 = best_of(hyb(32), 1) / steps / 32

    # network replaced by its (averaged) exact Jacobian: the stepper's own cost
    from hybridwsi.surrogate.features import build_features
    from hybridwsi.surrogate.linearise import feature_jacobian

    jac = feature_jacobian(net, build_features(train[0], net.spec_)[::10]).mean(0)
    orig = ro._torch_force
    ro._torch_force = lambda _net: (lambda x: x @ jac.T)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tphys = best_of(hyb(1), 2) / steps
    finally:
        ro._torch_force = orig

    print(f"pure Cummins state-space step     : {base * 1e6:8.2f} us/step (baseline)")
    print(f"hybrid rollout, 1 case            : {t1 * 1e6:8.2f} us/step  ratio {t1 / base:6.2f}x")
    print(f"hybrid rollout, 32 cases (batched): {t32 * 1e6:8.2f} us/case-step ratio {t32 / base:6.2f}x")
    print(f"hybrid stepper, numpy linear force: {tphys * 1e6:8.2f} us/step  ratio {tphys / base:6.2f}x")
    print(f"target <= 3x: 1 case {'met' if t1 / base <= 3 else 'NOT met'}, "
          f"32-case batch {'met' if t32 / base <= 3 else 'NOT met'}")


if __name__ == "__main__":
    main()
