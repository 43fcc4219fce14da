"""``hybridwsi import``: convert a third-party force/motion file into a TimeHistory file.

Any format of :mod:`hybridwsi.importers` (CSV, NetCDF, DualSPHysics FloatingInfo/FloatingAce,
Kramer 2021 measured/numerical decay) is read, validated and written as NetCDF (``.nc``) or as
CSV (``.csv``) with units in the header, atomically.
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

from hybridwsi.commands import _options as o
from hybridwsi.commands._options import read_dofs
from hybridwsi.errors import InputError
from hybridwsi.files import check_output_path
from hybridwsi.history import estimate_derivatives, force_names, to_csv, to_netcdf

HELP = "convert a force/motion file (CSV, DualSPHysics, Kramer 2021, NetCDF) to a TimeHistory"
DESCRIPTION = (
    "Read FILE (format detected from its content unless --format is given), validate it "
    "(sorted, uniform time, no NaN, SI units) and write it as a TimeHistory: NetCDF when OUT "
    "ends in .nc, CSV when it ends in .csv."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", metavar="FILE", help="file to import")
    o.add_out(parser, "output TimeHistory (.nc NetCDF or .csv)", required=True,
              metavar="HISTORY")
    o.add_format(parser)
    o.add_columns(parser)
    o.add_eta(parser)
    parser.add_argument("--force-column", action="append", metavar="COL", dest="forces",
                        help="CSV force column [N or N m] to import (repeatable; default: every "
                        "other numeric column with a force unit or no unit)")
    parser.add_argument("--sep", help="CSV separator (default: detected; 'whitespace' allowed)")
    o.add_dofs(parser, "the DOF names of a CSV's columns, e.g. Pitch or Surge,Pitch (default "
               "the file's '# dof:' line, else Heave); other files: a subset of theirs")
    o.add_mass(parser, "stored in the history (default: the file's, if any)")
    parser.add_argument("--drop-height", type=o.positive_float, metavar="H",
                        help="Kramer 2021 measured files: drop height [m] (default from the "
                        "file name: 01D -> 0.03 m)")
    parser.add_argument("--mkbound", type=o.nonnegative_int,
                        help="DualSPHysics: MkBound number of the floating body to keep")
    parser.add_argument("--resample", action="store_true",
                        help="resample irregular time steps onto a uniform grid (cubic)")
    o.add_derivatives(parser, "fill missing zdot/zddot with this method (default: leave "
                      "them out)", default=None)
    o.add_quiet(parser)


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if out.suffix.lower() not in (".nc", ".csv"):
        raise InputError(f"--out must end in .nc (NetCDF) or .csv, got '{out.name}'")
    check_output_path(out, [args.file])
    options = {"time": args.time, "z": args.z, "zdot": args.zdot, "zddot": args.zddot,
               "forces": args.forces, "sep": args.sep, "drop_height": args.drop_height,
               "mkbound": args.mkbound, "eta": args.eta}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hist = read_dofs(args.file, args.dofs, format=args.format, mass=args.mass,
                         resample=args.resample, **options)
    if args.derivatives:
        if "z" not in hist:
            raise InputError("cannot estimate derivatives: the history has no z")
        hist = estimate_derivatives(hist, method=args.derivatives, window=args.savgol_window)
    try:
        (to_csv if out.suffix.lower() == ".csv" else to_netcdf)(hist, out)
    except OSError as exc:
        raise InputError(f"cannot write {out}: {exc.strerror or exc}") from None
    if args.quiet:
        return 0
    t = hist["time"].values
    kin = [k for k in ("z", "zdot", "zddot") if k in hist]
    print(f"{args.file} ({hist.attrs.get('format')}) -> {out}: {t.size} samples, "
          f"t = {t[0]:.6g}..{t[-1]:.6g} s, dt = {(t[-1] - t[0]) / (t.size - 1):.6g} s")
    print(f"  kinematics: {', '.join(kin) or 'none'}; forces: "
          f"{', '.join(force_names(hist)) or 'none'}"
          + (f"; wave elevation: {', '.join(map(str, hist['probe'].values))}"
             if "eta" in hist else ""))
    for key in ("resampled", "missing"):
        if key in hist.attrs:
            print(f"  {key}: {hist.attrs[key]}")
    for k in ("zdot", "zddot"):
        if k in hist and "estimated" in hist[k].attrs:
            print(f"  {k} estimated: {hist[k].attrs['estimated']}")
    for w in caught:
        print(f"  note: {w.message}")
    return 0
