"""``hybridwsi sweep``: many Cummins runs in irregular seas on Dask, resumable."""

from __future__ import annotations

import argparse

HELP = "run a grid of irregular-sea Cummins cases on Dask into one Zarr store (resumable)"
DESCRIPTION = (
    "Hs x Tp x seeds JONSWAP cases, each simulated on a Dask worker (LocalCluster of "
    "--workers processes by default, or --scheduler ADDRESS) and written atomically to "
    "OUT/parts/<case>.nc; then consolidated into OUT/sweep.zarr with a 'case' dimension. "
    "Re-run with --resume after an interruption: finished cases are skipped."
)

#: the DOFs the sweep's Cummins runner simulates (hybridwsi.sweep.cummins_case)
SWEEP_DOFS = ("Heave",)


def add_arguments(p: argparse.ArgumentParser) -> None:
    from hybridwsi.commands import _options as o

    p.add_argument("--hs", required=True, type=o.positive_floats, metavar="HS[,HS...]",
                   help="significant wave heights [m], comma-separated")
    p.add_argument("--tp", required=True, type=o.positive_floats, metavar="TP[,TP...]",
                   help="peak periods [s], comma-separated")
    p.add_argument("--seeds", type=o.positive_int, default=1, metavar="N",
                   help="random wave-phase seeds 0..N-1 per (Hs, Tp) (default 1)")
    o.add_out(p, "output folder (parts/, sweep.zarr, manifest.json)", required=True,
              metavar="DIR")
    p.add_argument("--duration", type=o.positive_float, default=60.0,
                   help="simulated time per case [s] (default 60)")
    p.add_argument("--dt", type=o.positive_float, default=0.01,
                   help="time step [s] of each run (default 0.01)")
    o.add_coeffs(p, "default: the paper sphere's shipped coefficients")
    o.add_dofs(p, "the DOFs to simulate (the sweep runner does Heave only)",
               default=SWEEP_DOFS)
    o.add_mass(p, "default from the coefficients")
    p.add_argument("--nonlinear-hydrostatics", action="store_true",
                   help="exact sphere buoyancy instead of -C z")
    p.add_argument("--ramp", type=o.nonnegative_float, default=2.0,
                   help="wave ramp duration [s] (default 2)")
    p.add_argument("--scheduler", type=o.scheduler_address, metavar="ADDRESS",
                   help="Dask scheduler address (tcp://host:8786; default a LocalCluster)")
    p.add_argument("--workers", type=o.positive_int, default=2,
                   help="worker processes of the LocalCluster (default 2)")
    p.add_argument("--resume", action="store_true", help="continue a previous sweep in OUT")
    o.add_quiet(p)


#: what a wave-excited Cummins run reads from the coefficients
NEEDED = ("added_mass_inf", "hydrostatic_stiffness", "radiation_damping", "excitation_force")


def check_coefficients(coeffs, *, mass_given: bool) -> None:
    """Refuse coefficients that lack what every case needs (before any case starts)."""
    from hybridwsi.errors import InputError
    from hybridwsi.hydro import coefficients as cf

    needed = NEEDED if mass_given else (*NEEDED, "mass")
    missing = [n for n in needed if not cf.has(coeffs, n)]
    if missing:
        raise InputError(f"the coefficients have no {', '.join(missing)}; a sweep needs "
                         f"{', '.join(needed)}")
    for name in ("added_mass_inf", "hydrostatic_stiffness") + (() if mass_given else ("mass",)):
        cf.matrix(coeffs, name)  # raises on NaN or a malformed matrix


def run(args: argparse.Namespace) -> int:
    from hybridwsi.commands._options import check_steps, require
    from hybridwsi.errors import InputError
    from hybridwsi.files import check_output_path
    from hybridwsi.hydro.formats import read_coefficients
    from hybridwsi.sweep import MANIFEST, SweepConfig, case_grid, run_sweep

    require("distributed", "zarr")
    if tuple(args.dofs) != SWEEP_DOFS:
        raise InputError(f"sweep simulates {', '.join(SWEEP_DOFS)} only; use 'hybridwsi "
                         "simulate --dofs' for other DOFs")
    check_output_path(args.out, [args.coeffs], kind="dir", products=(MANIFEST,))
    if args.duration <= args.dt:
        raise InputError(f"--duration ({args.duration} s) must be longer than --dt ({args.dt} s)")
    check_steps(args.duration, args.dt, len(args.dofs))
    if args.coeffs:  # a bad file is refused here, before the Dask cluster starts
        check_coefficients(read_coefficients(args.coeffs, assume_seawater=True),
                           mass_given=args.mass is not None)
    cases = case_grid(args.hs, args.tp, args.seeds)
    cfg = SweepConfig(duration=args.duration, dt=args.dt, coeffs=args.coeffs, mass=args.mass,
                      nonlinear_hydrostatics=args.nonlinear_hydrostatics, ramp=args.ramp)
    store = run_sweep(cases, args.out, cfg, scheduler=args.scheduler, n_workers=args.workers,
                      resume=args.resume, progress=not args.quiet)
    if not args.quiet:
        print(f"{len(cases)} cases -> {store}")
    return 0
