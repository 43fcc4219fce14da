"""``hybridwsi diagnose``: force-sensitivity regression and stability verdict for any history.

Reads a force/motion file (:func:`hybridwsi.importers.read_history`: NetCDF, CSV, DualSPHysics,
Kramer 2021), estimates missing velocity/acceleration from ``z`` (Savitzky–Golay by default,
stated in the warnings), regresses ``F_bb = F_force − Σ F_known`` on the motion
(:func:`hybridwsi.diagnostic.regression.regress`) and, when a mass is known, judges the stability
of the partition (:func:`hybridwsi.diagnostic.stability.assess`).

``--example`` runs on a built-in synthetic history (see :func:`example_history`) so that the
output can be seen without any file.
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi import __version__
from hybridwsi.commands import _options as o
from hybridwsi.commands._options import one_line, read_dofs
from hybridwsi.diagnostic.regression import regress
from hybridwsi.diagnostic.stability import CoupledStep, assess
from hybridwsi.errors import InputError
from hybridwsi.files import check_output_path, write_json
from hybridwsi.forces.linear import FROM_DATA, canonical_name, known_from, mass_from, parse_known
from hybridwsi.history import (estimate_derivatives, force_names, make_history, select_dofs,
                               split_header)
from hybridwsi.hydro.formats import read_coefficients

HELP = "regress a force history on the motion and judge the stability of the force partition"
DESCRIPTION = (
    "Fit F_bb = F - sum(known) ~ Fbar + alpha*zddot + beta*zdot + gamma*z (paper Eq. 5-7, with "
    "an intercept) on a force/motion history, report identifiability and, with a mass, the "
    "stability of the partition. FILE may be NetCDF, CSV (units in headers such as 'time [s]'), "
    "DualSPHysics FloatingInfo/FloatingAce CSV or a Kramer 2021 decay file. Missing zdot/zddot "
    "are estimated from z. Use --example to run on a built-in synthetic history."
)

#: the built-in example: the paper's sphere (m, A_inf, C) with a small linear damping
EXAMPLE = {
    "mass_kg": 7.06,
    "added_mass_inf_kg": 3.50,
    "stiffness_N_per_m": 692.2,
    "damping_Ns_per_m": 5.0,
    "periods_s": [0.6, 0.75, 1.1],
    "force_amplitudes_N": [4.0, 3.0, 5.0],
    "phases_rad": [0.0, 1.3, 2.1],
    "dt_s": 0.01,
    "duration_s": 60.0,
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", nargs="?", metavar="FILE", help="force/motion history file")
    parser.add_argument("--example", action="store_true",
                        help="run on a built-in synthetic multi-frequency forced oscillator")
    parser.add_argument("--force-column", default="F_tot", metavar="COL",
                        help="force variable/column to regress [N or N m] (default F_tot)")
    o.add_format(parser)
    o.add_columns(parser)
    o.add_eta(parser)
    o.add_dofs(parser, "the DOFs to diagnose (a CSV: the DOF names of its columns, default its "
               "'# dof:' line, else Heave; other files: a subset of theirs)")
    parser.add_argument("--known", action="append", default=[], metavar="NAME[=VALUE]",
                        help="known component removed from the force with its physical sign: "
                        "hydrostatic=C [N/m], added_mass_inf=A [kg] (alias added_mass), "
                        "linear_damping=B [N s/m] (alias damping), quadratic_damping=Bq; "
                        "'hydrostatic' and 'added_mass_inf' without a value take their "
                        "matrix from the history or from --coeffs (repeatable)")
    o.add_coeffs(parser, "supplies C, A_inf and the mass for the history's DOFs")
    o.add_mass(parser, "default the history's, else --coeffs'; enables the stability "
               "assessment")
    parser.add_argument("--fix-alpha", type=o.finite_float, metavar="A",
                        help="fix alpha [kg] (e.g. m + A_inf) and regress only beta, gamma")
    parser.add_argument("--force-accuracy", type=o.positive_float, default=0.01, metavar="EPS",
                        help="relative accuracy of the force (default 0.01, typical of CFD/SPH; "
                        "~2e-4 for Cummins histories): alpha and gamma count as identifiable only "
                        "when a larger force error is needed to move either by 10 %%")
    parser.add_argument("--target-dt", type=o.positive_float, metavar="S",
                        help="time step [s] of the coupled solver for the loosely coupled check "
                        "(not the history's sampling step)")
    parser.add_argument("--resample", action="store_true",
                        help="resample irregular time steps onto a uniform grid (cubic)")
    o.add_derivatives(parser, "default savgol", default="savgol")
    o.add_json(parser)
    o.add_quiet(parser)


def example_history() -> xr.Dataset:
    """The built-in example: steady state of a forced, damped sphere in heave.

    ``(m + A) z̈ + B ż + C z = F_exc(t)`` with the paper's m = 7.06 kg, A∞ = 3.50 kg,
    C = 692.2 N/m, a linear damping B = 5 N s/m and ``F_exc`` a sum of three sines (periods
    0.6, 0.75 and 1.1 s; see :data:`EXAMPLE`). The steady-state response is exact (complex
    amplitude ``F_k / (C − (m + A) ω_k² + i B ω_k)`` per harmonic), so z, ż, z̈ carry no
    integration or differentiation error. ``F_tot = m z̈`` is the total force (paper Eq. 2) and
    ``F_exc`` the excitation. With ``--known hydrostatic=692.2 --known added_mass_inf=3.5`` the
    regression of ``F_tot`` returns α = m + A, β = 0, γ = C (docs/THEORY.md §1, case 3); with no known
    component α = m, β = γ = 0 (case 1). Three frequencies make the split identifiable.
    """
    p = EXAMPLE
    m, a, b, c = (p["mass_kg"], p["added_mass_inf_kg"], p["damping_Ns_per_m"],
                  p["stiffness_N_per_m"])
    t = np.arange(0.0, p["duration_s"], p["dt_s"])
    z = np.zeros_like(t, dtype=complex)
    f_exc = np.zeros_like(t)
    zdd = np.zeros_like(t, dtype=complex)
    zd = np.zeros_like(t, dtype=complex)
    for period, amp, phase in zip(p["periods_s"], p["force_amplitudes_N"], p["phases_rad"]):
        w = 2 * np.pi / period
        fk = amp * np.exp(1j * phase)
        zk = fk / (c - (m + a) * w**2 + 1j * b * w) * np.exp(1j * w * t)
        z, zd, zdd = z + zk, zd + 1j * w * zk, zdd - w**2 * zk
        f_exc += np.real(fk * np.exp(1j * w * t))
    return make_history(
        t, z.real, zd.real, zdd.real, {"F_tot": m * zdd.real, "F_exc": f_exc},
        mass=m, source="hybridwsi diagnose --example", inputs=p,
    )


def _load(args: argparse.Namespace, notes: list[str]) -> tuple[xr.Dataset, dict[str, Any]]:
    """The history to diagnose and a description of where it came from."""
    if args.example:
        if args.file:
            raise InputError("give either FILE or --example, not both")
        return select_dofs(example_history(), args.dofs), {"file": None, "example": EXAMPLE}
    if not args.file:
        raise InputError("no input: give a history FILE (CSV, NetCDF, ...) or --example")
    mapping = {k: getattr(args, k) for k in ("time", "z", "zdot", "zddot", "eta")}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hist = read_dofs(args.file, args.dofs, format=args.format, mass=args.mass,
                         resample=args.resample, **mapping)
    notes += [str(w.message) for w in caught]
    info = {"file": str(Path(args.file)), "format": hist.attrs.get("format"),
            "columns": {k: v for k, v in mapping.items() if v is not None}}
    if "resampled" in hist.attrs:
        notes.append(f"time resampled: {hist.attrs['resampled']}")
    return hist, info


def _prepare(hist: xr.Dataset, args: argparse.Namespace, notes: list[str]) -> xr.Dataset:
    """Check that z and the force exist; estimate missing derivatives (noted)."""
    if "z" not in hist:
        missing = hist.attrs.get("missing", "z")
        raise InputError(f"the history has no displacement z (missing: {missing}); "
                         "the diagnostic needs z(t)")
    absent = [k for k in ("zdot", "zddot") if k not in hist]
    if absent:
        hist = estimate_derivatives(hist, method=args.derivatives, window=args.savgol_window)
        for k in absent:
            notes.append(f"{k} was not in the file: estimated from z by "
                         f"{hist[k].attrs['estimated']}")
    if args.force_column not in hist:
        base = split_header(args.force_column)[0]
        if base in hist and hist[base].attrs.get("role") == "force":
            args.force_column = base
        else:
            have = ", ".join(force_names(hist)) or "none"
            raise InputError(f"no force '{args.force_column}' in the history (force columns: "
                             f"{have}); choose one with --force-column")
    return hist


def _coefficients(args: argparse.Namespace) -> xr.Dataset | None:
    """The ``--coeffs`` Dataset, or None."""
    return read_coefficients(args.coeffs, assume_seawater=True) if args.coeffs else None


def _known(specs: list[str], hist: xr.Dataset | None, coeffs: xr.Dataset | None) -> list:
    """Components of ``--known``: ``NAME=VALUE`` as given, a bare ``NAME`` from the history's
    matrices or the coefficients (:func:`hybridwsi.forces.linear.known_from`). Without a
    history only the names are checked (fail fast) and the bare ones are left out."""
    out = []
    for spec in specs:
        if "=" in spec:
            out.append(parse_known(spec))
            continue
        name = canonical_name(spec)
        if name not in FROM_DATA:
            raise InputError(f"--known {name} needs a value ({name}=VALUE); only "
                             f"{', '.join(FROM_DATA)} can be read from a history or --coeffs")
        if hist is not None:
            out += known_from(hist, coeffs, [name])
    return out


def _stability(result: Any, hist: xr.Dataset, known: list, args: argparse.Namespace,
               notes: list[str], coeffs: xr.Dataset | None = None
               ) -> list[dict[str, Any]] | None:
    """Stability reports as dicts, or None without a mass."""
    mass = args.mass if args.mass is not None else mass_from(hist, coeffs)
    if mass is None:
        notes.append("no mass given (--mass): stability assessment skipped")
        return None

    m = np.asarray(mass, dtype=float)
    step = CoupledStep.from_components(float(m.ravel()[0]) if m.size == 1 else m, known, result,
                                       dt=args.target_dt, scheme="semi_implicit_euler")
    return [s.to_dict() for s in assess(step).settings]


def diagnose(args: argparse.Namespace) -> tuple[dict[str, Any], Any]:
    """Run the whole diagnosis: ``(JSON-ready dict, RegressionResult)``."""
    notes: list[str] = []
    _known(args.known, None, None)  # fail fast on a bad --known
    coeffs = _coefficients(args)
    hist, info = _load(args, notes)
    hist = _prepare(hist, args, notes)
    known = _known(args.known, hist, coeffs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = regress(hist, force=args.force_column, known=known, fix_alpha=args.fix_alpha,
                            force_accuracy=args.force_accuracy)
            stability = _stability(result, hist, known, args, notes, coeffs)
        except InputError:
            raise
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            raise InputError(f"the diagnostic failed on this history: {one_line(exc)}") from None
    notes += [str(w.message) for w in caught]
    out = result.to_dict()
    out["warnings"] = notes + list(out.get("warnings", []))
    out["stability"] = stability
    out["input"] = {**info, "force": args.force_column, "known": list(args.known),
                    "coeffs": args.coeffs, "dofs": [str(d) for d in hist["dof"].values],
                    "fix_alpha": args.fix_alpha, "dt": args.target_dt,
                    "n_samples": int(hist.sizes["time"]),
                    "estimated": {k: hist[k].attrs["estimated"]
                                  for k in ("zdot", "zddot") if "estimated" in hist[k].attrs}}
    out["hybridwsi_version"] = __version__
    return out, result


def _print(out: dict[str, Any], result: Any, notes_count: int) -> None:
    print(result.to_table())
    for w in out["warnings"][:notes_count]:
        print(f"note: {w}")
    for rep in out["stability"] or []:
        print(f"stability [{rep.get('setting', '?')}]: {rep.get('verdict', '?')} - "
              f"{rep.get('message', '')}")


def run(args: argparse.Namespace) -> int:
    if args.json:
        check_output_path(args.json, [args.file, args.coeffs])
    out, result = diagnose(args)
    n_notes = len(out["warnings"]) - len(result.warnings)
    if not args.quiet:
        _print(out, result, n_notes)
        if args.example and not args.known:
            print("try: hybridwsi diagnose --example --known hydrostatic=692.2 "
                  "--known added_mass_inf=3.5")
    if args.json:
        write_json(args.json, out)
        if not args.quiet:
            print(f"wrote {args.json}")
    return 0
