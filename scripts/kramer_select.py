"""Nested leave-one-out selection of the network's multi-step training length (issue 14).

For the Kramer hybrid (``hybridwsi.report.kramer_hybrid``) the one free choice of the network
is how many L-BFGS iterations of multi-step training on the measured heave it gets (more
iterations fit the training drops better and extrapolate in amplitude worse). It is chosen
here without the held-out drop: each drop A is fitted *alone* (its own release lead from the
structured fit on A, the one-step network on A's F_bb, then multi-step training on A's heave)
and scored every 10 iterations on each other drop B. For held-out drop H, the inner
validation is the mean over the two ordered pairs (A → B, B → A) with A, B ≠ H; H's own curve
is never looked at for H.

Run: ``PYTHONPATH=src OMP_NUM_THREADS=1 python scripts/kramer_select.py [--iterations 80]``
(about 7 min wall on the loaded machine). Prints the inner validation table and the selected
count.
"""

from __future__ import annotations

import json
import time
import warnings

import numpy as np

from hybridwsi.cli import Parser, run_script
from hybridwsi.importers.kramer import read_kramer_drop
from hybridwsi.report import kramer_hybrid as kh


def main() -> None:
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("--iterations", type=int, default=80)
    ap.add_argument("--json", default=None, help="write the curves to this file")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    setup = kh.kramer_setup()
    measured = {d: kh.measured_history(d, setup) for d in kh.DROPS}
    exp = {d: read_kramer_drop(d, normalised=True) for d in kh.DROPS}
    curves = {d: (exp[d]["time"].values, exp[d]["z"].values[:, 0]) for d in kh.DROPS}
    single: dict[str, dict] = {}
    for a in kh.DROPS:
        t0 = time.perf_counter()
        _, lead, _ = kh.fit_output_error(setup, {a: curves[a]}, np.zeros(len(kh.STRUCTURED_TERMS)),
                                         kh.STRUCTURED_FREE, dt=kh.FIT_DT[False], fit_lead=True)
        net = kh.fit_network([measured[a]])
        info = kh.train_network_on_heave(net, setup, {a: curves[a]}, lead,
                                         iterations=args.iterations,
                                         validation={b: curves[b] for b in kh.DROPS if b != a})
        single[a] = info
        print(f"trained on {a} alone (lead {1e3 * lead:.1f} ms, {time.perf_counter() - t0:.0f} s):",
              {b: np.round(v, 4).tolist() for b, v in info["validation_rms"].items()}, flush=True)
    checkpoints = single[kh.DROPS[0]]["checkpoints"]
    out = {"checkpoints": checkpoints, "single": single, "selected": {}}
    print("\nheld out | inner pairs | inner validation RMS at", checkpoints, "| selected")
    for h in kh.DROPS:
        a, b = [d for d in kh.DROPS if d != h]
        inner = 0.5 * (np.array(single[a]["validation_rms"][b])
                       + np.array(single[b]["validation_rms"][a]))
        k = int(checkpoints[int(np.argmin(inner))])
        out["selected"][h] = k
        print(f"{h} | {a}->{b}, {b}->{a} | {np.round(inner, 4).tolist()} | {k}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    run_script(main)
