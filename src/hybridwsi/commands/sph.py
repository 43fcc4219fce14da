"""``hybridwsi sph CASE``: run a PySPH numerical-wave-tank case into a TimeHistory NetCDF."""

from __future__ import annotations

import argparse

from hybridwsi.errors import InputError

HELP = "run an SPH wave-tank case (PySPH): hydrostatic, dam_break, waves2d, decay3d, regular3d"
DESCRIPTION = (
    "Run an SPH case with PySPH (optional extra hybridwsi[sph]) and write its TimeHistory "
    "(z, zdot, zddot, F_tot, probe elevations eta) to NetCDF. Checkpoints are written next to "
    "the output; --resume continues an interrupted run to the same result."
)
CASES = ("hydrostatic", "dam_break", "waves2d", "decay2d", "decay3d", "regular3d")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("case", choices=CASES, help="case to run")
    parser.add_argument("--dp", type=float, default=None, help="particle spacing [m]")
    parser.add_argument("--tf", type=float, default=None, help="final time [s]")
    parser.add_argument("--depth", type=float, default=None,
                        help="still-water depth [m] (cases with a depth; default the case's)")
    parser.add_argument("--out", default=None, help="output NetCDF (default sph_<case>.nc)")
    parser.add_argument("--resume", action="store_true",
                        help="continue from <out>.ckpt.npz when it exists")
    parser.add_argument("--checkpoint-every", type=float, default=300.0,
                        help="wall-clock seconds between checkpoints (default 300)")
    parser.add_argument("--openmp", action="store_true",
                        help="compile with OpenMP (threads from OMP_NUM_THREADS)")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")


def run(args: argparse.Namespace) -> int:
    try:
        import pysph  # noqa: F401
    except ImportError:
        raise InputError("PySPH is not installed; pip install 'hybridwsi[sph]'") from None
    from hybridwsi.sph import tank
    from hybridwsi.sph.run import run_case

    for name in ("dp", "tf", "depth"):
        v = getattr(args, name)
        if v is not None and not v > 0:
            raise InputError(f"--{name} must be positive, got {v}")
    case = tank.build(args.case, dp=args.dp, tf=args.tf, depth=args.depth)
    out = args.out or f"sph_{args.case}.nc"
    print(f"{case.name}: {case.n_particles} particles, dp = {case.dp} m, dt = {case.dt:.3g} s, "
          f"tf = {case.tf} s -> {out}")
    hist = run_case(case, out, resume=args.resume, checkpoint_every=args.checkpoint_every,
                    openmp=args.openmp, progress=not args.no_progress)
    print(f"wrote {out} ({hist.sizes['time']} samples)")
    return 0
