"""``hybridwsi select``: rank force partitions for a hybrid solver (docs/THEORY.md §5)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from hybridwsi.errors import InputError

HELP = "rank force partitions (known physics vs surrogate) by stability and reconstruction error"
DESCRIPTION = (
    "For every combination of candidate known components (hydrostatics, A_inf, radiation "
    "memory, linear/quadratic damping, excitation) regress the residual force of FILE, check "
    "stability settings (a)-(c) at the target time step, reconstruct the motion and rank the "
    "partitions (feasible first, then spectral radius + reconstruction error)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", help="TimeHistory NetCDF (e.g. from 'hybridwsi simulate')")
    p.add_argument("--coeffs", help="coefficient file of the history's DOFs or more "
                   "(hydrostatic_stiffness, added_mass_inf, radiation_damping, mass): NetCDF, "
                   "BEMIO .h5 or WAMIT ROOT.1 (seawater rho, g assumed)")
    p.add_argument("--dt", type=float, help="target hybrid time step [s] (default: the file's)")
    p.add_argument("--mass", type=float, help="rigid-body mass [kg] (default: the history's, else "
                   "the coefficients')")
    p.add_argument("--candidates", help="comma-separated candidate names: hydrostatic, "
                   "added_mass_inf, radiation_memory, linear_damping, quadratic_damping, "
                   "excitation (default: all available)")
    p.add_argument("--quadratic-drag", type=float, help="Bq [N s^2/m^2] of the quadratic candidate")
    p.add_argument("--no-reconstruct", action="store_true", help="skip the reconstructions (fast)")
    p.add_argument("--json", dest="json_out", help="write the table as JSON here")


def run(args: argparse.Namespace) -> int:
    import pandas as pd

    from hybridwsi.diagnostic.partition import select_partition, table_to_json
    from hybridwsi.history import atomic_write, read_netcdf
    from hybridwsi.hydro.formats import read_coefficients

    hist = read_netcdf(args.file)
    coeffs = read_coefficients(args.coeffs, assume_seawater=True) if args.coeffs else None
    cands = [c.strip() for c in args.candidates.split(",")] if args.candidates else None
    if args.dt is not None and not args.dt > 0:
        raise InputError(f"--dt must be positive, got {args.dt}")
    table = select_partition(hist, coeffs, cands, dt=args.dt, mass=args.mass,
                             quadratic_drag=args.quadratic_drag,
                             reconstruct_each=not args.no_reconstruct)
    cols = ["rank", "partition", "alpha", "beta", "gamma", "surrogate_verdict",
            "loosely_coupled_verdict", "spectral_radius", "recon_nrms", "feasible", "score"]
    with pd.option_context("display.width", 200, "display.max_columns", 20,
                           "display.max_colwidth", 60):
        print(table[cols].to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    if args.json_out:
        from hybridwsi import __version__

        doc = {"hybridwsi_version": __version__, "inputs": {"file": args.file,
               "coeffs": args.coeffs, "dt": table.attrs["dt"], "candidates": cands},
               **table_to_json(table)}
        text = json.dumps(doc, indent=1, default=str)
        atomic_write(Path(args.json_out), lambda tmp: Path(tmp).write_text(text))
    return 0
