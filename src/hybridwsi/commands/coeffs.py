"""``hybridwsi coeffs``: convert coefficient files (WAMIT, BEMIO, Capytaine) ↔ coefficient NetCDF."""

from __future__ import annotations

import argparse
import math

from hybridwsi.commands import _options as o
from hybridwsi.errors import InputError
from hybridwsi.files import check_output_path
from hybridwsi.history import to_netcdf
from hybridwsi.hydro import coefficients as cf
from hybridwsi.hydro.formats import CARRY_RHO_G, detect, read_coefficients, write_wamit

HELP = "convert coefficient files: WAMIT .1/.3/.hst, BEMIO .h5, Capytaine NetCDF -> NetCDF, or -> WAMIT"
DESCRIPTION = (
    "Read hydrodynamic coefficients a user already holds into hybridwsi's coefficient NetCDF "
    "(Capytaine's names and conventions; usable by simulate/select --coeffs), or write WAMIT "
    ".1/.3/.hst files for OpenFAST HydroDyn (--to wamit). INPUT: a WAMIT .1 (its .3 and .hst "
    "siblings are picked up; needs --rho and --g), a WEC-Sim BEMIO .h5, a NetCDF written by "
    "Capytaine's export_dataset, or a hybridwsi coefficient NetCDF."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", metavar="INPUT",
                   help="coefficient file: ROOT.1 (WAMIT), FILE.h5 (BEMIO) or FILE.nc")
    o.add_out(p, "output: COEFFS.nc, or DIR/ROOT with --to wamit (writes ROOT.1, ROOT.3, "
              "ROOT.hst)", required=True)
    p.add_argument("--to", choices=("netcdf", "wamit"), default="netcdf",
                   help="output format (default netcdf)")
    p.add_argument("--format", choices=("auto", "wamit", "bemio", "capytaine", "netcdf"),
                   default="auto", help="input format (default: detected from the file)")
    p.add_argument("--rho", type=o.positive_float, default=None,
                   help="water density [kg/m^3] of the WAMIT run (WAMIT input only; other "
                        "files carry it)")
    p.add_argument("--g", type=o.positive_float, default=None,
                   help="gravity [m/s^2] of the WAMIT run (WAMIT input only)")
    p.add_argument("--ulen", type=o.positive_float, default=1.0,
                   help="WAMIT length scale ULEN [m] for reading and writing WAMIT (default 1)")
    p.add_argument("--frequency-input", action="store_true",
                   help="WAMIT input lists omega [rad/s] in the first column (IPEROUT=2), "
                        "not the period [s]")
    p.add_argument("--depth", type=o.positive_float, default=math.inf,
                   help="water depth [m] to record for WAMIT input (default: infinite)")
    o.add_quiet(p)


#: the files ``--to wamit`` writes next to DIR/ROOT
WAMIT_SUFFIXES = (".1", ".3", ".hst")


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse outputs that are inputs (a WAMIT input's siblings included) before reading."""
    from pathlib import Path

    src = Path(args.input)
    siblings = [src.with_suffix(sfx) for sfx in WAMIT_SUFFIXES] if src.suffix == ".1" else []
    inputs = [src, *(p for p in siblings if p.exists())]
    if args.to == "wamit":
        root = Path(args.out)
        for sfx in WAMIT_SUFFIXES:
            check_output_path(root.with_name(root.name + sfx), inputs)
    else:
        check_output_path(args.out, inputs)


def run(args: argparse.Namespace) -> int:
    _check_outputs(args)
    fmt = detect(args.input) if args.format == "auto" else args.format
    say = (lambda *a: None) if args.quiet else print
    if fmt in CARRY_RHO_G:
        for name in ("rho", "g"):
            if getattr(args, name) is not None:
                say(f"note: --{name} ignored: {args.input} carries its own {name}")
    coeffs = read_coefficients(args.input, rho=args.rho, g=args.g, ulen=args.ulen, format=fmt,
                               frequency_input=args.frequency_input, water_depth=args.depth)
    w = cf.omega(coeffs)
    say(f"{coeffs.attrs.get('source', fmt)}: DOFs {', '.join(cf.dofs(coeffs))}; {w.size} frequencies "
          f"{w[0]:.4g}-{w[-1]:.4g} rad/s; rho = {coeffs.attrs['rho']:g} kg/m^3, "
          f"g = {coeffs.attrs['g']:g} m/s^2")
    for name in ("added_mass_inf", "added_mass_zero", "hydrostatic_stiffness", "mass"):
        try:
            cf.matrix(coeffs, name)
        except InputError:  # absent, or NaN (limit not in the file)
            say(f"note: the input has no {name}")
    if args.to == "wamit":
        paths = write_wamit(coeffs, args.out, ulen=args.ulen)
        say("-> " + ", ".join(str(p) for p in paths))
    else:
        say(f"-> {to_netcdf(coeffs, args.out)}")
    return 0
