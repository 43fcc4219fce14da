"""``hybridwsi coeffs``: convert coefficient files (WAMIT, BEMIO, Capytaine) ↔ coefficient NetCDF."""

from __future__ import annotations

import argparse
import math

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
    p.add_argument("--out", required=True, metavar="PATH",
                   help="output: COEFFS.nc, or DIR/ROOT with --to wamit (writes ROOT.1, "
                        "ROOT.3, ROOT.hst)")
    p.add_argument("--to", choices=("netcdf", "wamit"), default="netcdf",
                   help="output format (default netcdf)")
    p.add_argument("--format", choices=("auto", "wamit", "bemio", "capytaine", "netcdf"),
                   default="auto", help="input format (default: detected from the file)")
    p.add_argument("--rho", type=float, default=None,
                   help="water density [kg/m^3] of the WAMIT run (WAMIT input only; other "
                        "files carry it)")
    p.add_argument("--g", type=float, default=None,
                   help="gravity [m/s^2] of the WAMIT run (WAMIT input only)")
    p.add_argument("--ulen", type=float, default=1.0,
                   help="WAMIT length scale ULEN [m] for reading and writing WAMIT (default 1)")
    p.add_argument("--frequency-input", action="store_true",
                   help="WAMIT input lists omega [rad/s] in the first column (IPEROUT=2), "
                        "not the period [s]")
    p.add_argument("--depth", type=float, default=math.inf,
                   help="water depth [m] to record for WAMIT input (default inf)")


def run(args: argparse.Namespace) -> int:
    from hybridwsi.errors import InputError
    from hybridwsi.history import to_netcdf
    from hybridwsi.hydro import coefficients as cf
    from hybridwsi.hydro.formats import CARRY_RHO_G, detect, read_coefficients, write_wamit

    fmt = detect(args.input) if args.format == "auto" else args.format
    if fmt in CARRY_RHO_G:
        for name in ("rho", "g"):
            if getattr(args, name) is not None:
                print(f"note: --{name} ignored: {args.input} carries its own {name}")
    coeffs = read_coefficients(args.input, rho=args.rho, g=args.g, ulen=args.ulen, format=fmt,
                               frequency_input=args.frequency_input, water_depth=args.depth)
    w = cf.omega(coeffs)
    print(f"{coeffs.attrs.get('source', fmt)}: DOFs {', '.join(cf.dofs(coeffs))}; {w.size} frequencies "
          f"{w[0]:.4g}-{w[-1]:.4g} rad/s; rho = {coeffs.attrs['rho']:g} kg/m^3, "
          f"g = {coeffs.attrs['g']:g} m/s^2")
    for name in ("added_mass_inf", "added_mass_zero", "hydrostatic_stiffness", "mass"):
        try:
            cf.matrix(coeffs, name)
        except InputError:  # absent, or NaN (limit not in the file)
            print(f"note: the input has no {name}")
    if args.to == "wamit":
        paths = write_wamit(coeffs, args.out, ulen=args.ulen)
        print("-> " + ", ".join(str(p) for p in paths))
    else:
        print(f"-> {to_netcdf(coeffs, args.out)}")
    return 0
