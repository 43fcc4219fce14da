"""Print the nested leave-one-out selection of the Kramer network's training length (issue 32).

A thin caller of :func:`hybridwsi.surrogate.kramer.select_iterations`, which the study
(``hybridwsi reproduce``) runs inside every fold: for held-out drop H, each of H's two training
drops is trained alone and scored on the other every ``--every`` iterations, and the count with
the lowest mean inner score is used for H. The single-drop runs are shared by the folds, as in
the study. Nothing here is hard-coded into the pipeline.

Run: ``PYTHONPATH=src OMP_NUM_THREADS=1 python scripts/kramer_select.py [--iterations 80]
[--json out.json]`` (three single-drop trainings: about 90 s of CPU at 80 iterations).
"""

from __future__ import annotations

import dataclasses
import time
import warnings

import numpy as np

from hybridwsi.cli import Parser, run_script
from hybridwsi.history import write_json
from hybridwsi.surrogate import kramer as kh


def main() -> None:
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("--iterations", type=int, default=None,
                    help="longest training tried (default: the study's, 80; 40 with --quick)")
    ap.add_argument("--quick", action="store_true", help="the quick study's settings")
    ap.add_argument("--json", default=None, help="write the selections to this file")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    settings = kh.StudySettings.for_run(args.quick)
    if args.iterations is not None:
        settings = dataclasses.replace(settings, max_iterations=args.iterations)
    data = kh.KramerData.load()
    alone: dict[str, kh.AloneRun] = {}
    out = {}
    c0 = time.process_time()
    for held_out in kh.DROPS:
        train = [d for d in kh.DROPS if d != held_out]
        out[held_out] = kh.select_iterations(train, data, settings, alone)
    checkpoints = out[kh.DROPS[0]]["checkpoints"]
    print(f"inner validation RMS at {checkpoints} iterations "
          f"({time.process_time() - c0:.0f} s CPU)")
    print("held out | inner pairs | inner RMS | selected")
    for h, sel in out.items():
        print(f"{h} | {', '.join(sel['pairs'])} | {np.round(sel['inner_rms'], 4).tolist()} | "
              f"{sel['selected_iterations']}")
    if args.json:
        write_json(args.json, {"settings": dataclasses.asdict(settings), "selection": out})


if __name__ == "__main__":
    run_script(main)
