"""``hybridwsi import``: convert a third-party force/motion file into a TimeHistory file.

Any format of :mod:`hybridwsi.importers` (CSV, NetCDF, DualSPHysics FloatingInfo/FloatingAce,
Kramer 2021 measured/numerical decay) is read, validated and written as NetCDF (``.nc``) or as
CSV (``.csv``) with units in the header, atomically.
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

from hybridwsi.errors import InputError

HELP = "convert a force/motion file (CSV, DualSPHysics, Kramer 2021, NetCDF) to a TimeHistory"
DESCRIPTION = (
    "Read FILE (format detected from its content unless --format is given), validate it "
    "(sorted, uniform time, no NaN, SI units) and write it as a TimeHistory: NetCDF when OUT "
    "ends in .nc, CSV when it ends in .csv."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from hybridwsi.importers import FORMATS

    parser.add_argument("file", metavar="FILE", help="file to import")
    parser.add_argument("--out", required=True, metavar="HISTORY",
                        help="output TimeHistory (.nc NetCDF or .csv)")
    parser.add_argument("--format", default="auto", choices=("auto", *FORMATS),
                        help="input format (default: detected from the content)")
    for name, what in (("time", "time [s]"), ("z", "displacement [m]"),
                       ("zdot", "velocity [m/s]"), ("zddot", "acceleration [m/s^2]")):
        parser.add_argument(f"--{name}", metavar="COL", help=f"CSV column holding {what}")
    parser.add_argument("--force", action="append", metavar="COL", dest="forces",
                        help="CSV force column [N] to import (repeatable; default: every "
                        "other numeric column with a force unit or no unit)")
    parser.add_argument("--sep", help="CSV separator (default: detected; 'whitespace' allowed)")
    parser.add_argument("--dof", help="DOF name(s) of a CSV file, e.g. Pitch or Surge,Pitch "
                        "(default: the file's '# dof:' line, else Heave)")
    parser.add_argument("--mass", type=float, metavar="M", help="body mass [kg] to store")
    parser.add_argument("--drop-height", type=float, metavar="H",
                        help="Kramer 2021 measured files: drop height [m] (default from the "
                        "file name: 01D -> 0.03 m)")
    parser.add_argument("--mkbound", type=int, help="DualSPHysics: floating body to keep")
    parser.add_argument("--resample", action="store_true",
                        help="resample irregular time steps onto a uniform grid (cubic)")
    parser.add_argument("--estimate-derivatives", choices=("savgol", "spline"),
                        help="also fill missing zdot/zddot from z with this method")


def run(args: argparse.Namespace) -> int:
    from hybridwsi.history import estimate_derivatives, force_names, to_csv, to_netcdf
    from hybridwsi.importers import read_history

    out = Path(args.out)
    if out.suffix.lower() not in (".nc", ".csv"):
        raise InputError(f"--out must end in .nc (NetCDF) or .csv, got '{out.name}'")
    if args.mass is not None and not args.mass > 0:
        raise InputError(f"--mass must be a positive mass in kg, got {args.mass}")
    options = {"time": args.time, "z": args.z, "zdot": args.zdot, "zddot": args.zddot,
               "forces": args.forces, "sep": args.sep, "dof": args.dof,
               "drop_height": args.drop_height, "mkbound": args.mkbound}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hist = read_history(args.file, format=args.format, mass=args.mass,
                            resample=args.resample, **options)
    if args.estimate_derivatives:
        if "z" not in hist:
            raise InputError("cannot estimate derivatives: the history has no z")
        hist = estimate_derivatives(hist, method=args.estimate_derivatives)
    try:
        (to_csv if out.suffix.lower() == ".csv" else to_netcdf)(hist, out)
    except OSError as exc:
        raise InputError(f"cannot write {out}: {exc.strerror or exc}") from None
    t = hist["time"].values
    kin = [k for k in ("z", "zdot", "zddot") if k in hist]
    print(f"{args.file} ({hist.attrs.get('format')}) -> {out}: {t.size} samples, "
          f"t = {t[0]:.6g}..{t[-1]:.6g} s, dt = {(t[-1] - t[0]) / (t.size - 1):.6g} s")
    print(f"  kinematics: {', '.join(kin) or 'none'}; forces: "
          f"{', '.join(force_names(hist)) or 'none'}")
    for key in ("resampled", "missing"):
        if key in hist.attrs:
            print(f"  {key}: {hist.attrs[key]}")
    for k in ("zdot", "zddot"):
        if k in hist and "estimated" in hist[k].attrs:
            print(f"  {k} estimated: {hist[k].attrs['estimated']}")
    for w in caught:
        print(f"  note: {w.message}")
    return 0
