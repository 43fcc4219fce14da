"""``hybridwsi select``: rank force partitions for a hybrid solver (docs/THEORY.md §5)."""

from __future__ import annotations

import argparse

from hybridwsi import __version__
from hybridwsi.commands import _options as o
from hybridwsi.commands._options import read_dofs
from hybridwsi.diagnostic.partition import select_partition, table_to_json
from hybridwsi.files import check_output_path, write_json
from hybridwsi.hydro.formats import read_coefficients

HELP = "rank force partitions (known physics vs surrogate) by stability and reconstruction error"
DESCRIPTION = (
    "For every combination of candidate known components (hydrostatics, A_inf, radiation "
    "memory, linear/quadratic damping, excitation) regress the residual force of FILE, check "
    "stability settings (a)-(c) at the target time step, reconstruct the motion and rank the "
    "partitions (feasible first, then spectral radius + reconstruction error)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", help="TimeHistory NetCDF (e.g. from 'hybridwsi simulate')")
    o.add_coeffs(p, "of the history's DOFs or more (hydrostatic_stiffness, added_mass_inf, "
                 "radiation_damping, mass)")
    o.add_dofs(p, "the DOFs of the history to use (default: all of them)")
    p.add_argument("--target-dt", type=o.positive_float, metavar="S",
                   help="time step [s] of the target hybrid solver (default: the history's)")
    o.add_mass(p, "default the history's, else the coefficients'")
    p.add_argument("--candidates", help="comma-separated candidate names: hydrostatic, "
                   "added_mass_inf, radiation_memory, linear_damping, quadratic_damping, "
                   "excitation (default: all available)")
    p.add_argument("--quadratic-drag", type=o.positive_float, metavar="BQ",
                   help="Bq [N s^2/m^2] of the quadratic candidate")
    p.add_argument("--no-reconstruct", action="store_true", help="skip the reconstructions (fast)")
    o.add_json(p)
    o.add_quiet(p)


def run(args: argparse.Namespace) -> int:
    import pandas as pd

    if args.json:
        check_output_path(args.json, [args.file, args.coeffs])
    hist = read_dofs(args.file, args.dofs, format="netcdf")
    coeffs = read_coefficients(args.coeffs, assume_seawater=True) if args.coeffs else None
    cands = [c.strip() for c in args.candidates.split(",")] if args.candidates else None
    table = select_partition(hist, coeffs, cands, dt=args.target_dt, mass=args.mass,
                             quadratic_drag=args.quadratic_drag,
                             reconstruct_each=not args.no_reconstruct)
    cols = ["rank", "partition", "alpha", "beta", "gamma", "surrogate_verdict",
            "loosely_coupled_verdict", "spectral_radius", "recon_nrms", "feasible", "score"]
    if not args.quiet:
        with pd.option_context("display.width", 200, "display.max_columns", 20,
                               "display.max_colwidth", 60):
            print(table[cols].to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    if args.json:
        doc = {"hybridwsi_version": __version__, "inputs": {"file": args.file,
               "coeffs": args.coeffs, "dofs": [str(d) for d in hist["dof"].values],
               "dt": table.attrs["dt"], "candidates": cands},
               **table_to_json(table)}
        write_json(args.json, doc)
    return 0
