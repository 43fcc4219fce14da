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


def _floats(text: str) -> list[float]:
    from hybridwsi.errors import InputError

    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InputError(f"expected comma-separated numbers, got '{text}'") from None


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--hs", required=True, help="significant wave heights [m], comma-separated")
    p.add_argument("--tp", required=True, help="peak periods [s], comma-separated")
    p.add_argument("--seeds", type=int, default=1, help="random seeds per (Hs, Tp) (default 1)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--duration", type=float, default=60.0, help="simulated time per case [s]")
    p.add_argument("--dt", type=float, default=0.01, help="time step [s]")
    p.add_argument("--coeffs", help="BEM coefficient NetCDF (default: the paper sphere, cached)")
    p.add_argument("--nonlinear-hydrostatics", action="store_true",
                   help="exact sphere buoyancy instead of -C z")
    p.add_argument("--ramp", type=float, default=2.0, help="wave ramp duration [s]")
    p.add_argument("--scheduler", help="Dask scheduler address (tcp://host:8786)")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    p.add_argument("--resume", action="store_true", help="continue a previous sweep in OUT")


def run(args: argparse.Namespace) -> int:
    from hybridwsi.sweep import SweepConfig, case_grid, run_sweep

    cases = case_grid(_floats(args.hs), _floats(args.tp), args.seeds)
    cfg = SweepConfig(duration=args.duration, dt=args.dt, coeffs=args.coeffs,
                      nonlinear_hydrostatics=args.nonlinear_hydrostatics, ramp=args.ramp)
    store = run_sweep(cases, args.out, cfg, scheduler=args.scheduler, n_workers=args.workers,
                      resume=args.resume)
    print(f"{len(cases)} cases -> {store}")
    return 0
