"""``hybridwsi reproduce``: Table 1, Fig. 1 and Fig. 2 of the paper into a results folder."""

from __future__ import annotations

import argparse
from pathlib import Path

HELP = "reproduce the paper (Table 1, Fig. 1, Fig. 2) into a results folder"
DESCRIPTION = (
    "Runs BEM (Capytaine) → Cummins → regression/stability/reconstruction and the decay "
    "validation, and writes tables (Markdown, JSON), figures (PNG), NetCDF histories and "
    "report.md into --out. --quick uses a coarse mesh (about a minute); the default uses the "
    "paper's BEM configuration (6400 panels, 400 frequencies; cached after the first run)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", default="results", help="results folder (default: results)")
    p.add_argument("--quick", action="store_true", help="coarse BEM mesh, for tests and a first look")
    p.add_argument("--no-decay", action="store_true", help="skip the decay validation (Fig. 1)")
    p.add_argument("--no-hybrid", action="store_true",
                   help="skip the outlook (component selection and hybrid-solver demo)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    sph = p.add_mutually_exclusive_group()
    sph.add_argument("--recompute-sph", action="store_true",
                     help="run the SPH regular-wave case now for Table 1's SPH column (hours; "
                          "resumable: re-run the same command after an interruption)")
    sph.add_argument("--sph-history", default=None, metavar="FILE",
                     help="history for the SPH column: NetCDF/CSV/DualSPHysics FloatingInfo "
                          "(default: the one shipped with the package, if any)")
    p.add_argument("--sph-dp", type=float, default=None,
                   help="particle spacing [m] of --recompute-sph (default: the case's)")
    p.add_argument("--sph-openmp", action="store_true",
                   help="compile the SPH kernels with OpenMP (threads from OMP_NUM_THREADS)")


def run(args: argparse.Namespace) -> int:
    from hybridwsi.errors import InputError
    from hybridwsi.report.reproduce import run as reproduce

    if args.sph_dp is not None and not args.sph_dp > 0:
        raise InputError(f"--sph-dp must be positive, got {args.sph_dp}")
    if args.sph_history is not None and not Path(args.sph_history).is_file():
        raise InputError(f"--sph-history: no such file {args.sph_history}")
    reproduce(args.out, quick=args.quick, progress=not args.quiet, decay=not args.no_decay,
              hybrid=not args.no_hybrid, recompute_sph=args.recompute_sph,
              sph_path=args.sph_history, sph_dp=args.sph_dp, sph_openmp=args.sph_openmp)
    return 0
