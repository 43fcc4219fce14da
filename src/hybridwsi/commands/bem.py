"""``hybridwsi bem``: Capytaine coefficients of a floating body (defaults: the paper's sphere;
``--case NAME|FILE`` a built-in case such as ``oc3_hywind`` or a case TOML file)."""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from hybridwsi.bodies import FloatingSphere, body_from_dict
from hybridwsi.casemodel import bem_arguments
from hybridwsi.cases import load_case
from hybridwsi.commands import _options as o
from hybridwsi.commands._options import check_allocation
from hybridwsi.dofs import coefficient_unit
from hybridwsi.errors import InputError
from hybridwsi.files import check_output_path
from hybridwsi.history import read_text_file, to_netcdf
from hybridwsi.hydro import bem
from hybridwsi.hydro import coefficients as co

HELP = "compute BEM coefficients (A, B, excitation, A_inf, C) of a floating body with Capytaine"
DESCRIPTION = (
    "Solve the radiation/diffraction problems of a floating body with Capytaine (symmetric mesh "
    "with lid where the body allows it, direct method) and write the coefficient NetCDF. "
    "Defaults reproduce the paper: a sphere R = 0.15 m, m = 7.06 kg, 6400 panels, 400 "
    "frequencies 0.1-40 rad/s, deep water. --case NAME|FILE takes the body and the [bem] table "
    "of a built-in case (e.g. oc3_hywind, paper_sphere) or of a case TOML file; --body takes "
    "any other body (a JSON "
    "description, hybridwsi.bodies.body_from_dict). Results are cached (~/.cache/hybridwsi/bem "
    "or $HYBRIDWSI_CACHE/bem), shipped results are used when the inputs match, and an "
    "interrupted run resumes where it stopped."
)
#: paper defaults of the options that --case replaces (None in the parser: to detect clashes)
SPHERE_DEFAULTS = {"radius": 0.15, "mass": 7.06, "omega_min": 0.1, "omega_max": 40.0,
                   "n_omega": 400, "depth": math.inf, "rho": 998.2, "g": 9.81,
                   "method": "direct"}
#: options that describe the problem (a case file gives all of them)
PROBLEM_OPTIONS = ("body", *SPHERE_DEFAULTS, "panels", "panel_size", "dofs")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    o.add_case(parser, "its body and [bem] table; not combined with the body, frequency and "
                       "mesh options")
    parser.add_argument("--quick", action="store_true",
                        help="with --case: the coarse [bem_quick] table instead of [bem]")
    parser.add_argument("--body", default=None,
                        help="body description: a JSON file or JSON text with a 'type' "
                             "(FloatingSphere, AxisymmetricBody, MeshBody, RigidAssembly); "
                             "replaces --radius/--mass/--rho/--g")
    parser.add_argument("--radius", type=o.positive_float, default=None,
                        help="sphere radius [m] (default 0.15)")
    o.add_mass(parser, "of the sphere (default 7.06)")
    parser.add_argument("--panels", type=o.positive_int, default=None, metavar="N",
                        help="approximate hull panel count (sphere default 6400)")
    parser.add_argument("--panel-size", type=o.positive_float, default=None, metavar="M",
                        help="hull panel size [m] (instead of --panels)")
    o.add_dofs(parser, "the DOFs to solve (default: the body's)")
    parser.add_argument("--omega-min", type=o.positive_float, default=None,
                        help="lowest frequency [rad/s] (default 0.1)")
    parser.add_argument("--omega-max", type=o.positive_float, default=None,
                        help="highest frequency [rad/s] (default 40)")
    parser.add_argument("--n-omega", type=o.positive_int, default=None,
                        help="number of log-spaced frequencies (default 400)")
    parser.add_argument("--depth", type=o.positive_float, default=None,
                        help="water depth [m] (default: infinite)")
    parser.add_argument("--rho", type=o.positive_float, default=None,
                        help="water density [kg/m^3] (default 998.2)")
    parser.add_argument("--g", type=o.positive_float, default=None,
                        help="gravity [m/s^2] (default 9.81)")
    parser.add_argument("--method", choices=("direct", "indirect"), default=None,
                        help="boundary-integral formulation of Capytaine (default direct)")
    o.add_out(parser, "output coefficient NetCDF (default coeffs.nc)", default="coeffs.nc",
              metavar="COEFFS.nc")
    parser.add_argument("--cache-dir", default=None, metavar="DIR",
                        help="cache folder (default ~/.cache/hybridwsi/bem or $HYBRIDWSI_CACHE/bem)")
    parser.add_argument("--no-cache", action="store_true", help="neither read nor write the cache")
    o.add_quiet(parser)
    parser.add_argument("--workers", type=o.positive_int, default=None,
                        help="worker processes (default: $HYBRIDWSI_BEM_JOBS, else all CPUs for "
                             "long sweeps)")


#: bytes per panel pair of Capytaine's dense influence matrices (S and K, complex128)
BYTES_PER_PANEL_PAIR = 2 * 16


def check_panels(n_panels: int | None, workers: int | None) -> None:
    """Refuse a mesh whose dense BEM matrices cannot fit in memory (before meshing)."""
    if n_panels is not None:
        check_allocation(BYTES_PER_PANEL_PAIR * float(n_panels) ** 2 * (workers or 1),
                         f"--panels {n_panels} (dense N x N influence matrices)",
                         "use fewer panels")


def read_body(spec: str):
    """A body from a JSON file or JSON text (:func:`hybridwsi.bodies.body_from_dict`)."""
    path = Path(spec).expanduser()
    looks_like_json = spec.lstrip().startswith(("{", "["))
    text = spec if looks_like_json else read_text_file(path)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"--body: {spec if looks_like_json else path} is not valid JSON "
                         f"({exc.msg} at line {exc.lineno})") from None
    if not isinstance(data, dict):
        raise InputError(f"--body must describe one body as a JSON object, got "
                         f"{type(data).__name__}")
    return body_from_dict(data)


def problem(args: argparse.Namespace) -> dict:
    """Keyword arguments of :func:`hybridwsi.hydro.bem.compute` from the options: a case's
    (:func:`hybridwsi.casemodel.bem_arguments`) or the body/frequency options (paper defaults)."""
    if args.case is not None:
        clash = [f"--{k.replace('_', '-')}" for k in PROBLEM_OPTIONS
                 if getattr(args, k) is not None]
        if clash:
            raise InputError(f"--case takes the body and BEM set-up from the case file; do not "
                             f"combine it with {', '.join(clash)}")
        case = load_case(args.case)
        try:
            return bem_arguments(case, "bem_quick" if args.quick else "bem")
        except InputError as exc:
            raise InputError(f"{case.label}: {exc}") from None
    if args.quick:
        raise InputError("--quick needs --case")
    opt = {k: SPHERE_DEFAULTS[k] if getattr(args, k) is None else getattr(args, k)
           for k in SPHERE_DEFAULTS}
    if not (0 < opt["omega_min"] < opt["omega_max"]) or opt["n_omega"] < 2:
        raise InputError("need 0 < --omega-min < --omega-max and --n-omega >= 2")
    if args.panels is not None and args.panel_size is not None:
        raise InputError("give --panels or --panel-size, not both")
    body = (read_body(args.body) if args.body is not None
            else FloatingSphere(radius=opt["radius"], mass=opt["mass"], rho=opt["rho"],
                                g=opt["g"]))
    return {"body": body,
            "omega": np.geomspace(opt["omega_min"], opt["omega_max"], opt["n_omega"]),
            "water_depth": opt["depth"], "n_panels": args.panels, "panel_size": args.panel_size,
            "dofs": args.dofs, "method": opt["method"]}


def run(args: argparse.Namespace) -> int:
    body_file = args.body if args.body and Path(args.body).expanduser().exists() else None
    case_file = args.case if args.case and Path(args.case).expanduser().is_file() else None
    check_output_path(args.out, [body_file, case_file])
    if args.cache_dir is not None and not args.no_cache:
        check_output_path(args.cache_dir, kind="dir")
    check_panels(args.panels, args.workers)
    start = time.perf_counter()
    ds = bem.compute(**problem(args), cache_dir=args.cache_dir, use_cache=not args.no_cache,
                     progress=not args.quiet, n_jobs=args.workers)
    wall = time.perf_counter() - start
    to_netcdf(ds, args.out)
    if not args.quiet:
        _print_summary(ds, wall, args.out)
    return 0


def _print_summary(ds, wall: float, out: str) -> None:
    w = co.omega(ds)
    print(f"panels: {ds.attrs['n_panels']} (+{ds.attrs['n_lid_panels']} lid), "
          f"frequencies: {w.size} ({w[0]:.3g}-{w[-1]:.3g} rad/s)")
    a_inf = co.matrix(ds, "added_mass_inf") if not np.isnan(ds["added_mass_inf"].values).any() \
        else np.full((len(co.dofs(ds)),) * 2, np.nan)
    mass, stiff = co.matrix(ds, "mass"), co.matrix(ds, "hydrostatic_stiffness")
    a_w = co.matrix_omega(ds, "added_mass")
    for k, dof in enumerate(co.dofs(ds)):
        mu, cu = coefficient_unit(dof, dof, "mass"), coefficient_unit(dof, dof, "stiffness")
        a, c = a_w[:, k, k], stiff[k, k]
        print(f"{dof}: A_inf = {a_inf[k, k]:.4f} {mu}   A(omega_max = {w[-1]:.3g}) = {a[-1]:.4f} "
              f"{mu}   C = {c:.2f} {cu}")
        # uncoupled undamped natural frequency: solve ω² (M + A(ω)) = C on the computed A(ω)
        resid = c - w**2 * (mass[k, k] + a)
        crossings = np.flatnonzero(np.diff(np.sign(resid)))
        if c > 0 and crossings.size:
            i = int(crossings[0])
            wn = w[i] - resid[i] * (w[i + 1] - w[i]) / (resid[i + 1] - resid[i])
            print(f"  natural frequency {wn:.4f} rad/s (Tn = {2 * np.pi / wn:.4f} s), "
                  f"A(omega_n) = {float(np.interp(wn, w, a)):.4f} {mu}")
    flags = ds.attrs.get("quality_flags", "[]")
    if flags != "[]":
        print(f"quality flags: {flags}")
    print(f"wall time {wall:.1f} s -> {out}")
