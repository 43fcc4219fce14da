"""``hybridwsi simulate``: a Cummins time-domain run (paper Eq. 9) → TimeHistory NetCDF.

Two set-ups: a case (``--case NAME|FILE``: its body's coefficients and every force component of
the case, :mod:`hybridwsi.casemodel`), or bare coefficients (``--coeffs FILE``, or the paper
sphere computed on the fly with ``--panels N``). Waves: regular, JONSWAP, or a recorded wave
elevation whose excitation force comes from the coefficients' transfer function
(``--wave-elevation FILE``, :class:`hybridwsi.waves.ElevationRecord`).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi import cummins, waves
from hybridwsi.bodies import FloatingSphere
from hybridwsi.casemodel import CaseModel, elevation_wave, force_table
from hybridwsi.cases import is_builtin, load_case
from hybridwsi.commands import _options as o
from hybridwsi.commands.bem import check_panels
from hybridwsi.errors import InputError
from hybridwsi.files import check_output_path
from hybridwsi.history import to_netcdf
from hybridwsi.hydro import bem
from hybridwsi.hydro.formats import read_coefficients

HELP = "time-domain Cummins simulation of a case or of coefficients (decay, waves, forces)"
DESCRIPTION = (
    "Integrate (m + A_inf) z'' + int K z' + C z = F_exc + sum F_k. --case NAME|FILE (a built-in "
    "case or a case TOML file, docs/CASES.md) takes the body's coefficients and every force "
    "component of the case (mooring, Morison drag, rotor, linear damping, force table); "
    "--coeffs FILE takes coefficients alone (--panels N: the paper's sphere computed on the "
    "fly). Waves: --regular, --jonswap or --wave-elevation FILE (a recorded elevation at the "
    "reference point; its excitation force from the coefficients' transfer function). Writes "
    "a TimeHistory NetCDF with z, zdot, zddot, the forces F_tot, F_hs, F_rad_inf, F_rad_mem, "
    "F_exc, F_ext, each case component separately (F_mooring, F_morison, F_rotor, F_damping, "
    "F_external, F_drift), the line tensions T_fairlead, T_anchor and eta. --rotor, "
    "--wind-speed, --turbulence-intensity, --wind-seed and --slow-drift replace the case's "
    "rotor and slow-drift settings; a run with a mean force (rotor thrust, drift) starts from "
    "its static offset."
)
#: defaults without a case (a case's [simulation], then [sweep] table replaces them)
DEFAULTS = {"duration": 30.0, "dt": 0.01, "gamma": 3.3, "wave_components": 200}


def add_arguments(p: argparse.ArgumentParser) -> None:
    o.add_case(p, "its coefficients ([bem] table; shipped or cached when the inputs match), "
                  "default DOFs and every force component")
    p.add_argument("--quick", action="store_true",
                   help="with --case: the coarse [bem_quick] coefficients (tests)")
    o.add_coeffs(p, "the body's coefficients (with --case: instead of the case's own)")
    p.add_argument("--panels", type=o.positive_int, metavar="N",
                   help="compute coefficients of the paper's sphere with ~N panels (>= 20)")
    p.add_argument("--n-omega", type=o.positive_int, default=120,
                   help="log-spaced frequencies 0.1-40 rad/s with --panels (default 120)")
    o.add_dofs(p, "the DOFs to simulate (default: the case's default DOFs, else Heave)")
    o.add_mass(p, "default from the coefficients (not with --case: its body gives the mass)")
    p.add_argument("--decay", type=o.finite_floats, metavar="Z0[,Z0...]", default=(0.0,),
                   help="initial displacement [m or rad]: one value for every simulated DOF, "
                        "or one per DOF (free decay)")
    sea = p.add_mutually_exclusive_group()
    sea.add_argument("--regular", nargs=2, type=o.positive_float, metavar=("T", "H"),
                     help="regular wave: period [s] and height [m]")
    sea.add_argument("--jonswap", nargs=2, type=o.positive_float, metavar=("HS", "TP"),
                     help="JONSWAP sea: Hs [m] and Tp [s]")
    sea.add_argument("--wave-elevation", metavar="FILE",
                     help="recorded wave elevation at the reference point: CSV (time, eta "
                          "columns; units in the header), NetCDF (eta) or OpenFAST "
                          "(Wave1Elev); its excitation force from the coefficients' transfer "
                          "function; time 0 is the first sample")
    o.add_eta(p)
    p.add_argument("--wave-direction", type=o.finite_float, default=None, metavar="DEG",
                   help="wave propagation direction [deg] from +X, the mean direction of a "
                        "spread sea (default: the case's [simulation], else 0); a heading "
                        "the coefficients hold, or one their body's symmetry or two stored "
                        "headings around it give. The wind blows along +X (the rotor faces "
                        "it), so this is the wave heading relative to the wind")
    p.add_argument("--spreading", type=o.positive_float, default=None, metavar="S",
                   help="JONSWAP short-crested: exponent s of the cos-2s spreading function "
                        "(wind sea 5-15, swell >= 25; default: the case's [simulation], else "
                        "long-crested)")
    p.add_argument("--jonswap-gamma", type=o.positive_float, default=None, metavar="GAMMA",
                   help="JONSWAP peak-enhancement factor (default 3.3, or the case's [sweep])")
    p.add_argument("--wave-components", type=o.positive_int, default=None, metavar="N",
                   help="JONSWAP frequency components over (0.5, 4) x the peak frequency "
                        "(default 200, or the case's [sweep]); the sea repeats after "
                        "2 pi / d_omega")
    p.add_argument("--seed", type=o.nonnegative_int, default=0,
                   help="random seed of the JONSWAP wave phases (default 0)")
    p.add_argument("--ramp", type=o.nonnegative_float, default=None,
                   help="excitation ramp [s] (default: the case's, else 2 wave periods with "
                        "regular/JONSWAP waves, 0 otherwise)")
    o.add_mooring(p)
    o.add_rotor(p)
    p.add_argument("--no-wave-kinematics", dest="wave_kinematics", action="store_false",
                   default=True,
                   help="with --case: Morison drag on the body velocity alone, without the "
                        "wave particle velocity")
    p.add_argument("--external-force", metavar="FILE",
                   help="external force: CSV/text table with a 'time [s]' column and a force column "
                        "named F, F_ext or force (one DOF) or F_<DOF> (unit in the header, e.g. "
                        "'F_ext [kN]'; default N); interpolated linearly, must cover the run")
    p.add_argument("--duration", type=o.positive_float, default=None,
                   help="simulated time [s] (default: the case's, the record's length with "
                        "--wave-elevation, else 30)")
    p.add_argument("--dt", type=o.positive_float, default=None,
                   help="time step [s] of the run (default: the case's, else 0.01)")
    p.add_argument("--radiation", choices=("statespace", "convolution", "none"), default=None,
                   help="memory-term evaluation (default: the case's [forces], else statespace)")
    p.add_argument("--nonlinear-hydrostatics", action="store_true",
                   help="exact hydrostatic force of the body (heave of the sphere: spherical "
                        "cap) instead of -C z on the DOFs the body can do exactly")
    p.add_argument("--network", metavar="MODEL",
                   help="with --case: run the hybrid solver of a model folder (hybridwsi hybrid "
                        "--case ... --out MODEL): the known components of its partition plus "
                        "its network force; refused when the case's hash, the DOFs or --dt "
                        "differ from its certificate. Writes F_network, F_known and the "
                        "per-step flag outside_envelope (network inputs outside the training "
                        "envelope; warns above 1 %%)")
    o.add_out(p, "output TimeHistory NetCDF", required=True, metavar="HIST.nc")
    o.add_quiet(p)


# ------------------------------------------------------------------------------ set-up
def _coefficients(args: argparse.Namespace) -> xr.Dataset:
    """Coefficients without a case: ``--coeffs`` or the paper sphere at ``--panels``."""
    if args.coeffs:
        return read_coefficients(args.coeffs, assume_seawater=True)
    if args.panels is None:
        raise InputError("give --case NAME|FILE, --coeffs FILE or --panels N")
    if args.panels < 20 or args.n_omega < 10:
        raise InputError("--panels must be >= 20 and --n-omega >= 10")
    check_panels(args.panels, None)
    return bem.compute(FloatingSphere.paper(), np.geomspace(0.1, 40.0, args.n_omega),
                       n_panels=args.panels, progress=not args.quiet)


def _body(coeffs: xr.Dataset) -> FloatingSphere:
    """The body the coefficients were computed for (attrs["body"]), or the paper's sphere."""
    raw = coeffs.attrs.get("body")
    return FloatingSphere.from_dict(json.loads(raw)) if raw else FloatingSphere.paper()


def _case_defaults(case: Any) -> dict[str, Any]:
    """Run defaults of a case: [simulation] over [sweep] over :data:`DEFAULTS`."""
    sweep, sim = case.get("sweep", {}), case.get("simulation", {})
    out = dict(DEFAULTS)
    for key, name in (("duration", "duration"), ("dt", "dt"), ("ramp", "ramp"),
                      ("gamma", "gamma"), ("wave_components", "wave_components"),
                      ("wave_direction", "wave_direction"), ("spreading", "spreading")):
        value = sim.get(key, sweep.get(name))
        if value is not None:
            out[key] = value
    return out


def _check_sources(args: argparse.Namespace) -> None:
    if args.case is not None:
        clash = [name for name, given in (("--panels", args.panels is not None),
                                          ("--mass", args.mass is not None)) if given]
        if clash:
            raise InputError(f"--case takes the body (its mass, its coefficients) from the case "
                             f"file; do not combine it with {', '.join(clash)}")
        return
    if args.coeffs and args.panels is not None:
        raise InputError("give --coeffs or --panels, not both")
    for name, given in (("--quick", args.quick), ("--mooring", args.mooring is not None),
                        ("--no-wave-kinematics", not args.wave_kinematics),
                        ("--rotor/--wind-*/--slow-drift", bool(o.case_overrides(args)))):
        if given:
            raise InputError(f"{name} needs --case")
    if args.network:
        raise InputError("--network needs --case (the case the model was trained for)")


def _wave(args: argparse.Namespace, coeffs: xr.Dataset, defaults: dict[str, Any]
          ) -> waves.Wave | None:
    direction = math.radians(args.wave_direction if args.wave_direction is not None
                             else defaults.get("wave_direction", 0.0))
    spreading = args.spreading if args.spreading is not None else defaults.get("spreading")
    if args.spreading is not None and not args.jonswap:
        raise InputError("--spreading spreads a JONSWAP sea: give --jonswap HS TP")
    if args.regular:
        return waves.Regular(period=args.regular[0], height=args.regular[1],
                             direction=direction)
    if args.jonswap:
        gamma = args.jonswap_gamma if args.jonswap_gamma is not None else defaults["gamma"]
        n = (args.wave_components if args.wave_components is not None
             else defaults["wave_components"])
        return waves.JONSWAP(hs=args.jonswap[0], tp=args.jonswap[1], gamma=gamma,
                             seed=args.seed, n_components=n, direction=direction,
                             spreading=spreading)
    if args.wave_elevation:
        return elevation_wave(coeffs, args.wave_elevation, args.eta, direction)
    if args.eta is not None:
        raise InputError("--eta names the column of a --wave-elevation file")
    return None


def _timing(args: argparse.Namespace, wave: waves.Wave | None, defaults: dict[str, Any]
            ) -> tuple[float, float, float]:
    """``(duration, dt, ramp)`` [s] from the options, the record and the defaults."""
    record = isinstance(wave, waves.ElevationRecord)
    duration = args.duration if args.duration is not None else (
        wave.duration if record else defaults["duration"])
    dt = args.dt if args.dt is not None else wave.dt if record else defaults["dt"]
    if record and duration > wave.duration * (1 + 1e-9):
        raise InputError(f"--duration {duration:g} s is longer than the wave-elevation record "
                         f"({wave.duration:g} s)")
    if duration <= dt:
        raise InputError(f"--duration ({duration} s) must be longer than --dt ({dt} s)")
    ramp = args.ramp if args.ramp is not None else defaults.get("ramp")
    if ramp is None:
        period = args.regular[0] if args.regular else args.jonswap[1] if args.jonswap else 0.0
        ramp = 2.0 * period
    return duration, dt, ramp


def _check_decay(z0: tuple[float, ...], dofs: tuple[str, ...]) -> None:
    if len(z0) not in (1, len(dofs)):
        raise InputError(f"--decay takes one value or one per DOF ({len(dofs)}: "
                         f"{', '.join(dofs)}), got {len(z0)}")


# ------------------------------------------------------------------------------ the run
def _run_case(args: argparse.Namespace) -> xr.Dataset:
    case = load_case(args.case)
    defaults = _case_defaults(case)
    model = CaseModel.build(case, dofs=args.dofs, coeffs=args.coeffs, mooring=args.mooring,
                            quick=args.quick, progress=not args.quiet,
                            overrides=o.case_overrides(args))
    wave = _wave(args, model.coeffs, defaults)
    duration, dt, ramp = _timing(args, wave, defaults)
    o.check_steps(duration, dt, len(model.dofs))
    _check_decay(args.decay, model.dofs)
    extra = ({"external_force": force_table(args.external_force, model.dofs)}
             if args.external_force else None)
    return model.simulate(
        duration=duration, dt=dt, wave=wave, z0=args.decay, ramp=ramp,
        wave_kinematics=args.wave_kinematics, progress=not args.quiet, extra=extra,
        radiation=args.radiation,
        hydrostatics="nonlinear" if args.nonlinear_hydrostatics else None)


#: options the hybrid solver does not take (its forces are the model's partition), by dest
NOT_WITH_NETWORK = {"external_force": "--external-force", "mooring": "--mooring",
                    "radiation": "--radiation", "nonlinear_hydrostatics":
                    "--nonlinear-hydrostatics"}


def _run_network(args: argparse.Namespace) -> xr.Dataset:
    """``--network MODEL``: the hybrid solver of a certified model folder on this sea."""
    o.require("torch")
    from hybridwsi.surrogate.certified import CertifiedModel

    clash = [flag for dest, flag in NOT_WITH_NETWORK.items() if getattr(args, dest)]
    clash += ["--rotor/--wind-*/--slow-drift"] if o.case_overrides(args) else []
    clash += ["--decay"] if any(args.decay) else []
    if clash:
        raise InputError(f"--network runs the model's partition from rest; do not combine it "
                         f"with {', '.join(clash)}")
    net = CertifiedModel.load(args.network)  # an altered folder is refused here
    case = load_case(args.case)
    dofs = args.dofs or tuple(net.doc["dofs"])
    net.check_run(case.sha256, case.label, dofs, args.dt if args.dt is not None
                  else float(net.doc["dt"]))  # before the coefficients are computed
    model = CaseModel.build(case, dofs=dofs, coeffs=args.coeffs, quick=args.quick,
                            progress=not args.quiet, dt=float(net.doc["dt"]))
    defaults = _case_defaults(case)
    wave = _wave(args, model.coeffs, defaults)
    duration, dt, ramp = _timing(args, wave, {**defaults, "dt": float(net.doc["dt"])})
    o.check_steps(duration, dt, len(model.dofs))
    return net.simulate(model, wave, duration=duration, dt=dt, ramp=ramp,
                        progress=not args.quiet)


def _run_coefficients(args: argparse.Namespace) -> xr.Dataset:
    coeffs = _coefficients(args)
    dofs = args.dofs or ("Heave",)
    _check_decay(args.decay, dofs)
    wave = _wave(args, coeffs, DEFAULTS)
    duration, dt, ramp = _timing(args, wave, DEFAULTS)
    o.check_steps(duration, dt, len(dofs))
    external = [force_table(args.external_force, dofs)] if args.external_force else []
    return cummins.simulate(
        coeffs, mass=args.mass, dofs=dofs, duration=duration, dt=dt, wave=wave,
        z0=args.decay, forces=external, radiation=args.radiation or "statespace",
        nonlinear_hydrostatics=args.nonlinear_hydrostatics,
        body=_body(coeffs) if args.nonlinear_hydrostatics else None, ramp=ramp,
        progress=not args.quiet)


def _summary(hist: xr.Dataset, path: Path) -> None:
    dofs = [str(d) for d in hist["dof"].values]
    t = hist["time"].values
    dt = (t[-1] - t[0]) / (t.size - 1)
    print(f"{t.size} samples, dt = {dt:g} s, DOFs {', '.join(dofs)}")
    units = json.loads(hist["z"].attrs.get("units_per_dof", "[]")) or [""] * len(dofs)
    z = hist["z"].values
    print("  " + "; ".join(f"{d}: max |z| {np.max(np.abs(z[:, j])):.4g} {u}, final "
                           f"{z[-1, j]:.4g}" for j, (d, u) in enumerate(zip(dofs, units))))
    comps = [str(k) for k in hist.data_vars if hist[k].attrs.get("component")]
    if comps:
        print(f"  force components: {', '.join(comps)}")
    if "T_fairlead" in hist:
        top = hist["T_fairlead"].max("time").values
        print("  max fairlead tension per line: "
              + ", ".join(f"{v / 1e3:.6g} kN" for v in top))
    if "radiation_ss" in hist.attrs:
        ss = json.loads(hist.attrs["radiation_ss"])
        fe = ss["fit_error"]
        print(f"  radiation state space: order {ss['order']}, fit error time "
              f"{fe['time']:.2%}, frequency {fe['frequency']:.2%}")
    print(f"-> {path}")


def run(args: argparse.Namespace) -> int:
    _check_sources(args)
    inputs = [args.coeffs, args.external_force, args.wave_elevation, args.network,
              None if args.case is None or is_builtin(args.case) else args.case]
    check_output_path(args.out, inputs)
    if args.network:
        hist = _run_network(args)
    else:
        hist = _run_case(args) if args.case is not None else _run_coefficients(args)
    path = to_netcdf(hist, args.out)
    if not args.quiet:
        _summary(hist, path)
    return 0 if np.all(np.isfinite(hist["z"].values[-1])) else 1
