"""Benchmark: force regression with HAC uncertainty on 1e6 samples (target < 1 s).

Prints the time of :func:`hybridwsi.diagnostic.regress` (SVD fit, HAC covariance, spectrum of
z) and its ratio to a baseline measured in the same process: a plain ``numpy.linalg.lstsq`` fit
of ``[1, z̈, ż, z]`` without any uncertainty. Timing: ``benchmarks/timing.py`` (samples of >= 0.2 s, 5 alternating
rounds, median ratio with its spread). Run: ``python benchmarks/bench_regression.py``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from hybridwsi.diagnostic import regress
from hybridwsi.history import make_history

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import REPEAT, Figure, compare, conditions  # noqa: E402


def _data(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    ws, amps, phs = (3.1, 5.7, 8.4), (0.02, 0.012, 0.008), (0.3, 1.1, 2.0)
    z = sum(a * np.sin(w * t + p) for a, w, p in zip(amps, ws, phs))
    zd = sum(a * w * np.cos(w * t + p) for a, w, p in zip(amps, ws, phs))
    zdd = sum(-a * w**2 * np.sin(w * t + p) for a, w, p in zip(amps, ws, phs))
    f = 1.5 + 10.56 * zdd + 0.3 * zd + 692.2 * z + rng.normal(0, 0.2, n)
    return make_history(t, z, zd, zdd, forces={"F_tot": f}), (t, z, zd, zdd, f)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000, help="number of samples")
    parser.add_argument("--repeat", type=int, default=REPEAT, help="alternating rounds")
    args = parser.parse_args()
    hist, (_, z, zd, zdd, f) = _data(args.n)

    def baseline() -> None:
        x = np.column_stack([np.ones_like(z), zdd, zd, z])
        np.linalg.lstsq(x, f, rcond=None)

    res = regress(hist)
    t = compare(Figure(baseline), {"regress": Figure(lambda: regress(hist))},
                repeat=args.repeat)
    t_reg = t["regress"].median
    print(f"samples                      : {args.n}")
    print(f"baseline numpy lstsq (no SE) : {t['baseline'].time_text(1.0, 's')}")
    print(f"regress with HAC (lag {res.hac_lags:>3d})   : {t['regress'].time_text(1.0, 's')}")
    print(f"ratio regress / baseline     : {t['regress'].ratio_text()}")
    print(f"target < 1 s                 : {'met' if t_reg < 1.0 else 'NOT met'} (median)")
    print(f"alpha, beta, gamma = {res.alpha[0, 0]:.4f}, {res.beta[0, 0]:.4f}, "
          f"{res.gamma[0, 0]:.3f} (truth 10.56, 0.3, 692.2)")
    print(conditions(repeat=args.repeat))


if __name__ == "__main__":
    main()
