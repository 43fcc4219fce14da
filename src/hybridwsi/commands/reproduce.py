"""``hybridwsi reproduce``: Table 1, Fig. 1 and Fig. 2 of the paper into a results folder."""

from __future__ import annotations

import argparse

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


def run(args: argparse.Namespace) -> int:
    from hybridwsi.reproduce import run as reproduce

    reproduce(args.out, quick=args.quick, progress=not args.quiet, decay=not args.no_decay,
              hybrid=not args.no_hybrid)
    return 0
