"""``hybridwsi bem``: Capytaine coefficients of a floating sphere (defaults: the paper's set-up)."""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

HELP = "compute BEM coefficients (A, B, excitation, A_inf, C) of a floating sphere with Capytaine"
DESCRIPTION = (
    "Solve the radiation/diffraction problems of a floating sphere with Capytaine (axisymmetric "
    "mesh with lid, direct method) and write the coefficient NetCDF. Defaults reproduce the "
    "paper: R = 0.15 m, m = 7.06 kg, 6400 panels, 400 frequencies 0.1-40 rad/s, deep water. "
    "Results are cached (~/.cache/hybridwsi/bem or $HYBRIDWSI_CACHE/bem) and an interrupted "
    "run resumes where it stopped."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--radius", type=float, default=0.15, help="sphere radius [m]")
    parser.add_argument("--mass", type=float, default=7.06, help="body mass [kg]")
    parser.add_argument("--panels", type=int, default=6400, help="approximate hull panel count")
    parser.add_argument("--omega-min", type=float, default=0.1, help="lowest frequency [rad/s]")
    parser.add_argument("--omega-max", type=float, default=40.0, help="highest frequency [rad/s]")
    parser.add_argument("--n-omega", type=int, default=400, help="number of log-spaced frequencies")
    parser.add_argument("--depth", type=float, default=math.inf, help="water depth [m] (inf)")
    parser.add_argument("--rho", type=float, default=998.2, help="water density [kg/m^3]")
    parser.add_argument("--g", type=float, default=9.81, help="gravity [m/s^2]")
    parser.add_argument("--method", choices=("direct", "indirect"), default="direct")
    parser.add_argument("--out", default="coeffs.nc", help="output NetCDF file")
    parser.add_argument("--cache-dir", default=None, help="cache folder")
    parser.add_argument("--no-cache", action="store_true", help="neither read nor write the cache")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.add_argument("--jobs", type=int, default=None,
                        help="worker processes (default: $HYBRIDWSI_BEM_JOBS, else all CPUs for "
                             "long sweeps)")


def run(args: argparse.Namespace) -> int:
    from hybridwsi.bodies import FloatingSphere
    from hybridwsi.errors import InputError
    from hybridwsi.history import to_netcdf
    from hybridwsi.hydro import bem

    if not (0 < args.omega_min < args.omega_max) or args.n_omega < 2:
        raise InputError("need 0 < --omega-min < --omega-max and --n-omega >= 2")
    body = FloatingSphere(radius=args.radius, mass=args.mass, rho=args.rho, g=args.g)
    omega = np.geomspace(args.omega_min, args.omega_max, args.n_omega)
    start = time.perf_counter()
    ds = bem.compute(body, omega, water_depth=args.depth, n_panels=args.panels,
                     method=args.method, cache_dir=args.cache_dir, use_cache=not args.no_cache,
                     progress=not args.quiet, n_jobs=args.jobs)
    wall = time.perf_counter() - start
    to_netcdf(ds, args.out)
    _print_summary(ds, body, wall, args.out)
    return 0


def _print_summary(ds, body, wall: float, out: str) -> None:
    a_inf = float(ds["added_mass_inf"].values[0, 0])
    c = float(ds["hydrostatic_stiffness"].values[0, 0])
    # undamped natural frequency: solve ω² (m + A(ω)) = C on the computed A(ω)
    w = ds["omega"].values
    a = ds["added_mass"].values[:, 0, 0]
    resid = c - w**2 * (body.mass + a)
    i = int(np.flatnonzero(np.diff(np.sign(resid)))[0]) if np.any(np.diff(np.sign(resid))) else None
    print(f"panels: {ds.attrs['n_panels']} (+{ds.attrs['n_lid_panels']} lid), "
          f"frequencies: {w.size} ({w[0]:.3g}-{w[-1]:.3g} rad/s)")
    print(f"A_inf = {a_inf:.4f} kg   A(omega_max = {w[-1]:.3g}) = {a[-1]:.4f} kg   C = {c:.2f} N/m")
    if i is not None:
        wn = w[i] - resid[i] * (w[i + 1] - w[i]) / (resid[i + 1] - resid[i])
        an = float(np.interp(wn, w, a))
        print(f"natural frequency {wn:.4f} rad/s (Tn = {2 * np.pi / wn:.4f} s), A(omega_n) = {an:.4f} kg")
    flags = ds.attrs.get("quality_flags", "[]")
    if flags != "[]":
        print(f"quality flags: {flags}")
    print(f"wall time {wall:.1f} s -> {out}")
