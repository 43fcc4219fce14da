"""``hybridwsi sweep``: many Cummins runs in irregular seas on Dask, resumable."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from hybridwsi.commands import _options as o
from hybridwsi.commands._options import case_overrides, check_steps, require, scheduler_address
from hybridwsi.errors import InputError
from hybridwsi.files import check_output_path
from hybridwsi.hydro import coefficients as cf
from hybridwsi.hydro.formats import read_coefficients
from hybridwsi.sweep import MANIFEST, SPHERE_DOFS, SYNCHRONOUS, SweepConfig, case_grid, run_sweep

HELP = "run a grid of irregular-sea Cummins cases on Dask into one Zarr store (resumable)"
DESCRIPTION = (
    "Hs x Tp x seeds JONSWAP cases, each simulated on a Dask worker (LocalCluster of "
    "--workers processes by default, or --scheduler ADDRESS) and written atomically to "
    "OUT/parts/<case>.nc; then consolidated into OUT/sweep.zarr with a 'case' dimension, and "
    "OUT/manifest.json (inputs, versions, settings hash, per-case motion statistics). "
    "Default: the paper sphere in heave. --case NAME|FILE (a built-in case such as oc3_hywind, "
    "or a case TOML file) simulates that case: its coefficients, DOFs, force components "
    "(mooring, Morison drag, additional damping, rotor), each recorded in the parts, and the "
    "defaults of its [sweep] table. Re-run with --resume after an interruption: finished "
    "cases are skipped."
)

#: the sphere sweep's defaults (a case's [sweep] table replaces them)
SPHERE_DEFAULTS = {"duration": 60.0, "dt": 0.01, "ramp": 2.0}


def _scheduler(text: str) -> str:
    """argparse type: a Dask scheduler address, or ``synchronous`` (in this process)."""
    return text if text == SYNCHRONOUS else scheduler_address(text)


def add_arguments(p: argparse.ArgumentParser) -> None:
    o.add_case(p, "its body's coefficients ([bem] table, shipped when the inputs match), "
                  "DOFs, force components and [sweep] defaults; default: the paper sphere in "
                  "heave")
    o.add_mooring(p)
    o.add_rotor(p)
    p.add_argument("--hs", required=True, type=o.wave_heights, metavar="HS[,HS...]",
                   help="significant wave heights [m], comma-separated")
    p.add_argument("--tp", required=True, type=o.positive_floats, metavar="TP[,TP...]",
                   help="peak periods [s], comma-separated")
    p.add_argument("--seeds", type=o.positive_int, default=1, metavar="N",
                   help="random wave-phase seeds 0..N-1 per (Hs, Tp) (default 1)")
    p.add_argument("--jonswap-gamma", type=o.positive_float, default=None, metavar="GAMMA",
                   help="JONSWAP peak-enhancement factor (default 3.3, or the case's)")
    p.add_argument("--wave-components", type=o.positive_int, default=None, metavar="N",
                   help="JONSWAP frequency components over (0.5, 4) x the peak frequency "
                        "(default 200, or the case's); the sea repeats after 2 pi / d_omega")
    p.add_argument("--no-wave-kinematics", dest="wave_kinematics", action="store_false",
                   default=None,
                   help="with --case: Morison drag on the body velocity alone, without the "
                        "wave particle velocity")
    o.add_out(p, "output folder (parts/, sweep.zarr, manifest.json)", required=True,
              metavar="DIR")
    p.add_argument("--duration", type=o.positive_float, default=None,
                   help="simulated time per case [s] (default 60, or the case's)")
    p.add_argument("--dt", type=o.positive_float, default=None,
                   help="time step [s] of each run (default 0.01, or the case's)")
    o.add_coeffs(p, "default: the paper sphere's shipped coefficients, or the case's")
    o.add_dofs(p, "the DOFs to simulate (default: the case's default DOFs; the sphere sweep "
                  "does Heave only)")
    o.add_mass(p, "default from the coefficients (sphere only; a case's body gives its mass)")
    p.add_argument("--nonlinear-hydrostatics", action="store_true",
                   help="exact sphere buoyancy instead of -C z (sphere only)")
    p.add_argument("--ramp", type=o.nonnegative_float, default=None,
                   help="wave ramp duration [s] (default 2, or the case's); the statistics "
                        "in the manifest start after it")
    p.add_argument("--scheduler", type=_scheduler, metavar="ADDRESS",
                   help="Dask scheduler address (tcp://host:8786), or 'synchronous' to run "
                        "the cases one by one in this process (default a LocalCluster)")
    p.add_argument("--workers", type=o.positive_int, default=2,
                   help="worker processes of the LocalCluster (default 2)")
    p.add_argument("--resume", action="store_true", help="continue a previous sweep in OUT")
    o.add_quiet(p)


#: what a wave-excited Cummins run reads from the coefficients
NEEDED = ("added_mass_inf", "hydrostatic_stiffness", "radiation_damping", "excitation_force")


def check_coefficients(coeffs, *, mass_given: bool) -> None:
    """Refuse coefficients that lack what every case needs (before any case starts)."""
    needed = NEEDED if mass_given else (*NEEDED, "mass")
    missing = [n for n in needed if not cf.has(coeffs, n)]
    if missing:
        raise InputError(f"the coefficients have no {', '.join(missing)}; a sweep needs "
                         f"{', '.join(needed)}")
    for name in ("added_mass_inf", "hydrostatic_stiffness") + (() if mass_given else ("mass",)):
        cf.matrix(coeffs, name)  # raises on NaN or a malformed matrix


def config_from(args: argparse.Namespace):
    """The :class:`~hybridwsi.sweep.SweepConfig` of the options: a case's ``[sweep]`` defaults
    (``--case``) or the sphere's, overridden by the options given."""
    given = {"duration": args.duration, "dt": args.dt, "ramp": args.ramp, "dofs": args.dofs,
             "gamma": args.jonswap_gamma, "wave_components": args.wave_components,
             "wave_kinematics": args.wave_kinematics, "coeffs": args.coeffs, "mass": args.mass,
             "mooring": args.mooring, "overrides": case_overrides(args) or None,
             "nonlinear_hydrostatics": args.nonlinear_hydrostatics or None}
    if args.case is not None:
        cfg = SweepConfig.for_case(args.case, **given)
    else:
        cfg = SweepConfig(**{**SPHERE_DEFAULTS, **{k: v for k, v in given.items()
                                                   if v is not None}})
    cfg.check()  # one line before the Dask cluster starts
    return cfg


#: cases whose statistics are printed (all are in manifest.json)
PRINTED_CASES = 20


def print_statistics(manifest: dict) -> None:
    """One line per case: std and max |.| of every DOF after the ramp, and 4 std(eta)."""
    rows = list(manifest.get("statistics", {}).get("cases", {}).items())
    if rows:
        window = manifest["statistics"]["window_s"]
        print(f"motion statistics over {window[0]:g}-{window[1]:g} s (manifest.json):")
    for cid, row in rows[:PRINTED_CASES]:
        parts = [f"{d} std {v['std']:.4g} max|.| {max(abs(v['min']), abs(v['max'])):.4g} "
                 f"{v['unit']}" for d, v in row.items() if d != "eta" and not d.startswith("T_")]
        if "eta" in row:
            parts.append(f"4 std(eta) {row['eta']['hs_4std']:.3g} m")
        if "T_fairlead" in row:
            top = max(v["max"] for v in row["T_fairlead"].values())
            parts.append(f"max fairlead tension {top / 1e3:.5g} kN")
        print(f"  {cid}: " + "; ".join(parts))
    if len(rows) > PRINTED_CASES:
        print(f"  ... and {len(rows) - PRINTED_CASES} more cases in manifest.json")


def run(args: argparse.Namespace) -> int:


    if args.scheduler == SYNCHRONOUS:  # no Dask workers, but the store is Zarr
        require("zarr")
    else:
        require("distributed", "zarr")
    check_output_path(args.out, [args.coeffs], kind="dir", products=(MANIFEST,))
    cfg = config_from(args)
    if cfg.duration <= cfg.dt:
        raise InputError(f"--duration ({cfg.duration} s) must be longer than --dt ({cfg.dt} s)")
    check_steps(cfg.duration, cfg.dt, len(cfg.dofs or SPHERE_DOFS))
    if args.coeffs:  # a bad file is refused here, before the Dask cluster starts
        check_coefficients(read_coefficients(args.coeffs, assume_seawater=True),
                           mass_given=args.mass is not None)
    cases = case_grid(args.hs, args.tp, args.seeds)
    store = run_sweep(cases, args.out, cfg, scheduler=args.scheduler, n_workers=args.workers,
                      resume=args.resume, progress=not args.quiet)
    if not args.quiet:
        print(f"{len(cases)} cases -> {store}")

        print_statistics(json.loads((Path(args.out) / MANIFEST).read_text()))
    return 0
