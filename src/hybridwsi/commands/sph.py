"""``hybridwsi sph CASE``: run a PySPH numerical-wave-tank case into a TimeHistory NetCDF."""

from __future__ import annotations

import argparse

from hybridwsi.commands import _options as o
from hybridwsi.commands._options import require
from hybridwsi.files import check_output_path
from hybridwsi.sph import tank
from hybridwsi.sph.run import run_case


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
    parser.add_argument("--dp", type=o.positive_float, default=None, metavar="M",
                        help="particle spacing [m]")
    parser.add_argument("--tf", type=o.positive_float, default=None, metavar="S",
                        help="final time [s] of the SPH run")
    parser.add_argument("--depth", type=o.positive_float, default=None, metavar="M",
                        help="still-water depth [m] (cases with a depth; default the case's)")
    parser.add_argument("--hdx", type=o.positive_float, default=None,
                        help="smoothing length over spacing h/dp (body and wave cases)")
    parser.add_argument("--hold", type=o.nonnegative_float, default=None, metavar="S",
                        help="decay cases: seconds the body is held before release "
                             "(default 0.3, the longest hold with --relax; the history starts "
                             "at the release)")
    parser.add_argument("--sponge", type=o.nonnegative_float, default=None, metavar="M",
                        help="decay cases: width [m] of an absorbing layer along the side "
                             "walls (default 0: closed tank)")
    parser.add_argument("--gain", type=o.positive_float, default=None,
                        help="waves3d, regular3d: factor on the Biésel paddle stroke, from a "
                             "calibration in the empty flume (scripts/sph_wave_calibration.py)")
    parser.add_argument("--domain", choices=("quarter", "half", "full"), default=None,
                        help="decay3d, regular3d: the part of the symmetric tank simulated "
                             "(default: the case's, quarter for decay3d, half for regular3d)")
    parser.add_argument("--symmetry", choices=("mirror", "wall"), default=None,
                        help="3D cases: symmetry planes as mirror images of every particle "
                             "(default) or as free-slip walls (the old set-up, for comparison)")
    parser.add_argument("--lattice-body", action="store_true",
                        help="body cases: build the body from lattice points (staircase "
                             "surface) instead of smooth concentric shells, for comparison")
    parser.add_argument("--boundary", choices=("shepard", "mdbc"), default=None,
                        help="body cases: body-particle pressure by Shepard extrapolation "
                             "(default) or the first-order mDBC ghost node (docs/SPH_RUNS.md)")
    parser.add_argument("--packing", choices=("lattice", "packed"), default=None,
                        help="body cases: the fluid near the body relaxed to a body-fitted "
                             "packing with masses from the initial density (default; "
                             "hybridwsi.sph.packing) or the fluid lattice cut by the body (the "
                             "runs before issue 15; docs/SPH_RUNS.md)")
    parser.add_argument("--relax", type=o.nonnegative_float, default=None, metavar="R",
                        help="decay cases: damp the fluid while the body is held and release "
                             "once the rms fluid speed is below R·sqrt(g·depth) (default 1e-3; "
                             "0: an undamped hold of --hold seconds)")
    parser.add_argument("--alpha-wall", type=o.nonnegative_float, default=None, metavar="A",
                        help="decay cases, waves3d: artificial-viscosity coefficient between "
                             "the fluid and the solids (body, walls); default 0 for the decay "
                             "cases (docs/SPH_RUNS.md), the fluid's for waves3d")
    parser.add_argument("--alpha-body", type=o.nonnegative_float, default=None, metavar="A",
                        help="body cases: artificial-viscosity coefficient between the fluid "
                             "and the body alone (default: that of --alpha-wall; regular3d: "
                             "the fluid's)")
    o.add_out(parser, "output TimeHistory NetCDF (default sph_<case>.nc)", metavar="HIST.nc")
    parser.add_argument("--resume", action="store_true",
                        help="continue from <out>.ckpt.npz when it exists")
    parser.add_argument("--checkpoint-every", type=o.positive_float, default=300.0, metavar="S",
                        help="wall-clock seconds between checkpoints (default 300)")
    parser.add_argument("--openmp", action="store_true",
                        help="compile with OpenMP (threads from OMP_NUM_THREADS)")
    o.add_quiet(parser, alias="--no-progress")


def run(args: argparse.Namespace) -> int:
    require("pysph")

    out = args.out or f"sph_{args.case}.nc"
    check_output_path(out)
    case = tank.build(args.case, dp=args.dp, tf=args.tf, depth=args.depth, hdx=args.hdx,
                      t_release=args.hold, sponge=args.sponge, gain=args.gain,
                      domain=args.domain, symmetry=args.symmetry,
                      smooth_body=(False if args.lattice_body else None),
                      boundary=args.boundary, relax=args.relax, packing=args.packing,
                      alpha_wall=args.alpha_wall, alpha_body=args.alpha_body)
    if not args.quiet:
        print(f"{case.name}: {case.n_particles} particles, dp = {case.dp} m, dt = {case.dt:.3g} "
              f"s, tf = {case.tf} s -> {out}")
    hist = run_case(case, out, resume=args.resume, checkpoint_every=args.checkpoint_every,
                    openmp=args.openmp, progress=not args.quiet)
    if not args.quiet:
        print(f"wrote {out} ({hist.sizes['time']} samples)")
    return 0
