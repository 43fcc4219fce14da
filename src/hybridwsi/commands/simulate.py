"""``hybridwsi simulate``: a Cummins time-domain run (paper Eq. 9) → TimeHistory NetCDF."""

from __future__ import annotations

import argparse
import math

HELP = "time-domain Cummins simulation (decay, regular or JONSWAP waves, external force)"
DESCRIPTION = (
    "Integrate (m + A_inf) z'' + int K z' + C z = F_exc + F_ext with coefficients from a NetCDF "
    "(hybridwsi bem) or computed on the fly for the paper's sphere (--panels N). Writes a "
    "TimeHistory NetCDF with z, zdot, zddot and the force components F_tot, F_hs, F_rad_inf, "
    "F_rad_mem, F_exc, F_ext (and eta with waves)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    from hybridwsi.commands import _options as o

    src = p.add_mutually_exclusive_group(required=True)
    o.add_coeffs(p, "the body's coefficients", group=src)
    src.add_argument("--panels", type=o.positive_int, metavar="N",
                     help="compute coefficients of the paper's sphere with ~N panels (>= 20)")
    p.add_argument("--n-omega", type=o.positive_int, default=120,
                   help="log-spaced frequencies 0.1-40 rad/s with --panels (default 120)")
    o.add_dofs(p, "the DOFs to simulate (default Heave)", default=("Heave",))
    o.add_mass(p, "default from the coefficients")
    p.add_argument("--decay", type=o.finite_float, metavar="Z0", default=0.0,
                   help="initial displacement [m or rad] of every simulated DOF (free decay)")
    waves = p.add_mutually_exclusive_group()
    waves.add_argument("--regular", nargs=2, type=o.positive_float, metavar=("T", "H"),
                       help="regular wave: period [s] and height [m]")
    waves.add_argument("--jonswap", nargs=2, type=o.positive_float, metavar=("HS", "TP"),
                       help="JONSWAP sea: Hs [m] and Tp [s]")
    p.add_argument("--jonswap-gamma", type=o.positive_float, default=3.3,
                   help="JONSWAP peak-enhancement factor (default 3.3)")
    p.add_argument("--seed", type=o.nonnegative_int, default=0,
                   help="random seed of the JONSWAP wave phases (default 0)")
    p.add_argument("--ramp", type=o.nonnegative_float, default=None,
                   help="excitation ramp [s] (default: 2 wave periods with waves, else 0)")
    p.add_argument("--external-force", metavar="FILE",
                   help="external force: CSV/text table with a 'time [s]' column and a force column "
                        "named F, F_ext or force (unit in the header, e.g. 'F_ext [kN]'; "
                        "default N); interpolated linearly, must cover the run")
    p.add_argument("--duration", type=o.positive_float, default=30.0,
                   help="simulated time [s] (default 30)")
    p.add_argument("--dt", type=o.positive_float, default=0.01,
                   help="time step [s] of the run (default 0.01)")
    p.add_argument("--radiation", choices=("statespace", "convolution", "none"),
                   default="statespace", help="memory-term evaluation (default statespace)")
    p.add_argument("--nonlinear-hydrostatics", action="store_true",
                   help="exact hydrostatic force of the body (heave of the sphere: spherical "
                        "cap) instead of -C z on the DOFs the body can do exactly")
    o.add_out(p, "output TimeHistory NetCDF", required=True, metavar="HIST.nc")
    o.add_quiet(p)


def _coefficients(args: argparse.Namespace):
    import numpy as np

    from hybridwsi.bodies import FloatingSphere
    from hybridwsi.errors import InputError
    from hybridwsi.hydro.formats import read_coefficients

    if args.coeffs:
        return read_coefficients(args.coeffs, assume_seawater=True)
    if args.panels < 20 or args.n_omega < 10:
        raise InputError("--panels must be >= 20 and --n-omega >= 10")
    from hybridwsi.commands.bem import check_panels
    from hybridwsi.hydro import bem

    check_panels(args.panels, None)
    return bem.compute(FloatingSphere.paper(), np.geomspace(0.1, 40.0, args.n_omega),
                       n_panels=args.panels, progress=not args.quiet)


def _body(coeffs):
    """The body the coefficients were computed for (attrs["body"]), or the paper's sphere."""
    import json

    from hybridwsi.bodies import FloatingSphere

    raw = coeffs.attrs.get("body")
    return FloatingSphere.from_dict(json.loads(raw)) if raw else FloatingSphere.paper()


#: accepted names of the force column of an ``--external-force`` file with one DOF
#: (case-insensitive, unit allowed); with several DOFs the columns are ``F_<DOF>``
FORCE_COLUMNS = ("F", "F_ext", "force")


def _force_csv(path: str, dofs: tuple[str, ...] = ("Heave",)):
    """``PrescribedForce.from_series`` from a text table with a ``time`` column [s] and, for
    one DOF, a force column named ``F``, ``F_ext`` or ``force``; for several DOFs one column
    ``F_<DOF>`` per DOF the force acts on (absent ones are zero). Units come from the header
    (e.g. ``F_ext [kN]``; N by default, N m for a rotation DOF)."""
    import numpy as np

    from hybridwsi.errors import InputError
    from hybridwsi.forces import PrescribedForce
    from hybridwsi.history import TextTable, quantity_of

    table = TextTable(path)
    t = table.numeric(table.require("time"), "time")
    table.check_time(t, min_samples=2)
    if len(dofs) == 1:
        found = {c for c in (table.find(name) for name in FORCE_COLUMNS) if c is not None}
        if len(found) != 1:
            what = "no force column" if not found else f"several force columns {sorted(found)}"
            raise InputError(f"{table.path.name}: {what}; name one column "
                             f"{' or '.join(FORCE_COLUMNS)} (columns: {', '.join(table.columns)})")
        columns = {dofs[0]: found.pop()}
    else:
        columns = {d: c for d in dofs if (c := table.find(f"F_{d}")) is not None}
        if not columns:
            raise InputError(f"{table.path.name}: no force column for the DOFs {', '.join(dofs)}; "
                             f"name them F_<DOF>, e.g. F_{dofs[0]} (columns: "
                             f"{', '.join(table.columns)})")
    values = np.zeros((t.size, len(dofs)))
    for k, d in enumerate(dofs):
        if d in columns:
            values[:, k] = table.numeric(columns[d], quantity_of("force", d))
    return PrescribedForce.from_series(t, values if len(dofs) > 1 else values[:, 0],
                                       name=f"{table.path.name}:{','.join(columns.values())}")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from hybridwsi import cummins, waves
    from hybridwsi.commands._options import check_steps
    from hybridwsi.errors import InputError
    from hybridwsi.files import check_output_path
    from hybridwsi.history import to_netcdf

    check_output_path(args.out, [args.coeffs, args.external_force])
    if args.duration <= args.dt:
        raise InputError(f"--duration ({args.duration} s) must be longer than --dt ({args.dt} s)")
    check_steps(args.duration, args.dt, len(args.dofs))
    external = [_force_csv(args.external_force, args.dofs)] if args.external_force else []
    coeffs = _coefficients(args)
    wave = None
    if args.regular:
        wave = waves.Regular(period=args.regular[0], height=args.regular[1])
    elif args.jonswap:
        wave = waves.JONSWAP(hs=args.jonswap[0], tp=args.jonswap[1], gamma=args.jonswap_gamma,
                             seed=args.seed)
    ramp = args.ramp
    if ramp is None:
        ramp = 0.0 if wave is None else 2.0 * (args.regular[0] if args.regular else args.jonswap[1])
    hist = cummins.simulate(
        coeffs, mass=args.mass, dofs=args.dofs, duration=args.duration, dt=args.dt, wave=wave,
        z0=args.decay, forces=external,
        radiation=args.radiation, nonlinear_hydrostatics=args.nonlinear_hydrostatics,
        body=_body(coeffs) if args.nonlinear_hydrostatics else None, ramp=ramp,
        progress=not args.quiet,
    )
    path = to_netcdf(hist, args.out)
    z = hist["z"].values[:, 0]
    if not args.quiet:
        print(f"{hist.sizes['time']} samples, dt = {args.dt} s, radiation = {args.radiation}"
              f", max |z| = {np.max(np.abs(z)):.4g} m, final z = {z[-1]:.4g} m")
        if "radiation_ss" in hist.attrs:
            import json

            ss = json.loads(hist.attrs["radiation_ss"])
            fe = ss["fit_error"]
            print(f"radiation state space: order {ss['order']}, fit error time "
                  f"{fe['time']:.2%}, frequency {fe['frequency']:.2%}")
        print(f"-> {path}")
    return 0 if math.isfinite(float(z[-1])) else 1
