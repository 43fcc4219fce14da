"""``hybridwsi sph CASE``: run a PySPH numerical-wave-tank case into a TimeHistory NetCDF."""

from __future__ import annotations

import argparse

from hybridwsi.errors import InputError

HELP = ("run an SPH wave-tank case (PySPH): hydrostatic, dam_break, waves2d, waves3d, decay3d, "
        "regular3d")
DESCRIPTION = (
    "Run an SPH case with PySPH (optional extra hybridwsi[sph]) and write its TimeHistory "
    "(z, zdot, zddot, F_tot, probe elevations eta) to NetCDF. Checkpoints are written next to "
    "the output; --resume continues an interrupted run to the same result."
)
CASES = ("hydrostatic", "dam_break", "waves2d", "waves3d", "decay2d", "decay3d", "regular3d")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("case", choices=CASES, help="case to run")
    parser.add_argument("--dp", type=float, default=None, help="particle spacing [m]")
    parser.add_argument("--tf", type=float, default=None, help="final time [s]")
    parser.add_argument("--depth", type=float, default=None,
                        help="still-water depth [m] (cases with a depth; default the case's)")
    parser.add_argument("--hdx", type=float, default=None,
                        help="smoothing length over spacing h/dp (body and wave cases)")
    parser.add_argument("--hold", type=float, default=None,
                        help="decay cases: seconds the body is held before release "
                             "(default 0.3; the history starts at the release)")
    parser.add_argument("--sponge", type=float, default=None,
                        help="decay cases: width [m] of an absorbing layer along the side "
                             "walls (default 0: closed tank)")
    parser.add_argument("--gain", type=float, default=None,
                        help="waves3d, regular3d: factor on the Biésel paddle stroke, from a "
                             "calibration in the empty flume (scripts/sph_wave_calibration.py)")
    parser.add_argument("--lattice-body", action="store_true",
                        help="body cases: build the body from lattice points (staircase "
                             "surface) instead of smooth concentric shells, for comparison")
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

    for name in ("dp", "tf", "depth", "hdx"):
        v = getattr(args, name)
        if v is not None and not v > 0:
            raise InputError(f"--{name} must be positive, got {v}")
    if args.sponge is not None and not args.sponge >= 0:
        raise InputError(f"--sponge must be a non-negative width in m, got {args.sponge}")
    if args.hold is not None and not args.hold >= 0:
        raise InputError(f"--hold must be a non-negative time in s, got {args.hold}")
    case = tank.build(args.case, dp=args.dp, tf=args.tf, depth=args.depth, hdx=args.hdx,
                      t_release=args.hold, sponge=args.sponge, gain=args.gain,
                      smooth_body=(False if args.lattice_body else None))
    out = args.out or f"sph_{args.case}.nc"
    print(f"{case.name}: {case.n_particles} particles, dp = {case.dp} m, dt = {case.dt:.3g} s, "
          f"tf = {case.tf} s -> {out}")
    hist = run_case(case, out, resume=args.resume, checkpoint_every=args.checkpoint_every,
                    openmp=args.openmp, progress=not args.no_progress)
    print(f"wrote {out} ({hist.sizes['time']} samples)")
    return 0
