"""``hybridwsi reproduce``: Table 1, Fig. 1 and Fig. 2 of the paper into a results folder."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from hybridwsi.commands import _options as o
from hybridwsi.commands._options import require
from hybridwsi.errors import InputError
from hybridwsi.files import check_output_path
from hybridwsi.report.reproduce import run as reproduce

HELP = "reproduce the paper (Table 1, Fig. 1, Fig. 2) into a results folder"
DESCRIPTION = (
    "Runs BEM (Capytaine) → Cummins → regression/stability/reconstruction and the decay "
    "validation, and writes tables (Markdown, JSON), figures (PNG), NetCDF histories and "
    "report.md into --out. --quick uses a coarse mesh (about a minute); the default uses the "
    "paper's BEM configuration (6400 panels, 400 frequencies; cached after the first run)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    o.add_out(p, "results folder (default: results)", default="results", metavar="DIR")
    p.add_argument("--quick", action="store_true", help="coarse BEM mesh, for tests and a first look")
    p.add_argument("--no-decay", action="store_true", help="skip the decay validation (Fig. 1)")
    p.add_argument("--no-hybrid", action="store_true",
                   help="skip the outlook (component selection and hybrid-solver demo)")
    o.add_quiet(p)
    sph = p.add_mutually_exclusive_group()
    sph.add_argument("--recompute-sph", action="store_true",
                     help="run the SPH regular-wave case now for Table 1's SPH column (hours; "
                          "resumable: re-run the same command after an interruption)")
    sph.add_argument("--sph-history", default=None, metavar="FILE",
                     help="history for the SPH column: NetCDF/CSV/DualSPHysics FloatingInfo "
                          "(default: the one shipped with the package, if any)")
    p.add_argument("--sph-dp", type=o.positive_float, default=None, metavar="M",
                   help="particle spacing [m] of --recompute-sph (default: the case's)")
    p.add_argument("--sph-openmp", action="store_true",
                   help="compile the SPH kernels with OpenMP (threads from OMP_NUM_THREADS)")


def check_inputs(args: argparse.Namespace) -> None:
    """Check the paths before anything runs; the SPH history's content is checked by
    :func:`hybridwsi.report.reproduce.run` before its first expensive step."""
    out = check_output_path(args.out, [args.sph_history], kind="dir")
    if args.sph_history is not None:
        src = Path(os.path.realpath(Path(args.sph_history).expanduser()))  # loops do not raise
        if Path(os.path.realpath(out)) in src.parents:  # the results folder is replaced whole
            raise InputError(f"--sph-history {args.sph_history} lies inside the results folder "
                             f"{args.out}; move it out or choose another --out")
    if args.recompute_sph:
        require("pysph")


def run(args: argparse.Namespace) -> int:
    check_inputs(args)
    reproduce(args.out, quick=args.quick, progress=not args.quiet, decay=not args.no_decay,
              hybrid=not args.no_hybrid, recompute_sph=args.recompute_sph,
              sph_path=args.sph_history, sph_dp=args.sph_dp, sph_openmp=args.sph_openmp)
    return 0
