"""Options shared by the commands: one name, one meaning, one validation (docs/CLI.md).

Every command builds its shared options with the ``add_*`` helpers below, so that ``--dofs``,
``--out``, ``--quiet``, ``--coeffs``, ``--mass`` … are spelled, documented and checked the
same way everywhere. Numeric options use the argparse types of this module (:func:`positive_float`
…), which refuse NaN, ±inf and out-of-range values while the command line is parsed, so a bad
value is one ``error:`` line before any work starts.

Also here: :func:`require` (an optional dependency → one line naming the extra to install),
:func:`check_allocation` (refuse a run whose arrays cannot fit in memory before allocating) and
:func:`read_dofs` (read a history and keep its DOFs ``--dofs``, with ``history.select_dofs``).
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import re
from collections.abc import Callable, Sequence
from typing import Any

from hybridwsi.dofs import check_dofs
from hybridwsi.errors import InputError
from hybridwsi.history import select_dofs
from hybridwsi.importers import FORMATS, detect_format, read_history



def one_line(text: str) -> str:
    """``text`` with every run of whitespace (newlines included) collapsed to one space."""
    return " ".join(str(text).split())


# ----------------------------------------------------------------------------- value types


def _number(text: str, cast: Callable[[str], Any], kind: str) -> Any:
    try:
        value = cast(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(f"expected {kind}, got {text!r}") from None
    if isinstance(value, float) and not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def finite_float(text: str) -> float:
    """argparse type: a finite float (NaN and ±inf refused)."""
    return _number(text, float, "a number")


def positive_float(text: str) -> float:
    """argparse type: a finite float > 0."""
    value = finite_float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be positive, got {text!r}")
    return value


def nonnegative_float(text: str) -> float:
    """argparse type: a finite float >= 0."""
    value = finite_float(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return value


def fraction(text: str) -> float:
    """argparse type: a float strictly between 0 and 1."""
    value = finite_float(text)
    if not 0 < value < 1:
        raise argparse.ArgumentTypeError(f"must be between 0 and 1 (exclusive), got {text!r}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    value = _number(text, int, "an integer")
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return value


def nonnegative_int(text: str) -> int:
    """argparse type: an integer >= 0."""
    value = _number(text, int, "an integer")
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be an integer >= 0, got {text!r}")
    return value


def _list(item: Callable[[str], Any]) -> Callable[[str], tuple]:
    def parse(text: str) -> tuple:
        parts = [p.strip() for p in text.split(",") if p.strip()]
        if not parts:
            raise argparse.ArgumentTypeError(f"expected a comma-separated list, got {text!r}")
        return tuple(item(p) for p in parts)

    parse.__name__ = f"{item.__name__}_list"
    return parse


#: argparse type: comma-separated finite numbers, e.g. ``5,0,0.02``
finite_floats = _list(finite_float)
#: argparse type: comma-separated positive numbers, e.g. ``0.05,0.1``
positive_floats = _list(positive_float)
#: argparse type: comma-separated positive integers, e.g. ``32,32``
positive_ints = _list(positive_int)


def dof_names(text: str) -> tuple[str, ...]:
    """argparse type: comma-separated DOF names (:func:`hybridwsi.dofs.check_dofs`)."""
    try:
        return check_dofs(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


#: a Dask scheduler address: scheme://host[:port] (tcp, tls, ucx, inproc, ws, wss)
_SCHEDULER = re.compile(r"^(tcp|tls|ucx|inproc|ws|wss)://[^\s/]+(:\d{1,5})?/?$")


def scheduler_address(text: str) -> str:
    """argparse type: a Dask scheduler address such as ``tcp://host:8786``."""
    if not _SCHEDULER.match(text):
        raise argparse.ArgumentTypeError(
            f"expected a Dask scheduler address such as tcp://host:8786, got {text!r}")
    return text


# ------------------------------------------------------------------------- shared options


def add_dofs(p: argparse.ArgumentParser, help: str, default: Sequence[str] | None = None
             ) -> None:
    """``--dofs Surge,Pitch``: the degrees of freedom the command works on."""
    p.add_argument("--dofs", type=dof_names, default=None if default is None else tuple(default),
                   metavar="DOF[,DOF...]",
                   help=f"comma-separated DOFs (Surge, Sway, Heave, Roll, Pitch, Yaw): {help}")


def add_out(p: argparse.ArgumentParser, help: str, *, required: bool = False,
            default: str | None = None, metavar: str = "PATH") -> None:
    """``--out PATH``: where the command writes its result (refused if it is an input)."""
    p.add_argument("--out", required=required, default=default, metavar=metavar, help=help)


def add_case(p: argparse.ArgumentParser, help: str) -> None:
    """``--case NAME|FILE``: a built-in case or a case TOML file (docs/CASES.md)."""
    p.add_argument("--case", default=None, metavar="NAME|FILE",
                   help=f"a built-in case (oc3_hywind, paper_sphere, kramer2021_decay) or a case "
                        f"TOML file (docs/CASES.md): {help}")


#: ``--mooring`` choices (hybridwsi.cases.schema.MOORING_MODELS)
MOORING_MODELS = ("moordyn", "quasi-static", "table")


def add_mooring(p: argparse.ArgumentParser) -> None:
    """``--mooring MODEL``: the mooring model instead of the case's ``[forces] mooring``."""
    p.add_argument("--mooring", choices=MOORING_MODELS, default=None,
                   help="with --case: the mooring model instead of the case's: moordyn (line "
                        "dynamics), quasi-static (MoorPy solved every step) or table (MoorPy's "
                        "interpolant, the default of a case with [mooring])")


#: rotor states of ``--rotor`` (:mod:`hybridwsi.forces.rotor` STATES; the case schema's)
ROTOR_STATES = ("parked", "thrust", "operating")


def add_rotor(p: argparse.ArgumentParser) -> None:
    """``--rotor``, ``--wind-speed``, ``--turbulence-intensity``, ``--wind-seed`` and
    ``--slow-drift``/``--no-slow-drift``: the case's ``[rotor]`` and ``[forces] drift`` entries
    replaced for this run (:func:`case_overrides`)."""
    p.add_argument("--rotor", choices=ROTOR_STATES, default=None,
                   help="with --case: the rotor state instead of the case's [rotor] state: "
                        "parked (no aerodynamic force), thrust (the case's constant thrust), "
                        "operating (the rotor in the wind of --wind-speed)")
    p.add_argument("--wind-speed", type=positive_float, default=None, metavar="U",
                   help="with --case: mean hub-height wind [m/s] of the operating rotor "
                        "(implies --rotor operating)")
    p.add_argument("--turbulence-intensity", type=nonnegative_float, default=None,
                   metavar="TI", help="with --case: sigma/U of the hub-height wind (0: steady, "
                                      "> 0: seeded Kaimal turbulence; implies --rotor operating)")
    p.add_argument("--wind-seed", type=nonnegative_int, default=None, metavar="N",
                   help="with --case: random seed of the turbulent wind's phases (implies "
                        "--rotor operating)")
    p.add_argument("--slow-drift", action=argparse.BooleanOptionalAction, default=None,
                   help="with --case: the second-order slow-drift force of the case's [drift] "
                        "table in the run's sea (Newman's approximation, F_drift) on or off, "
                        "instead of the case's [forces] drift")


#: option name -> [rotor] key of :func:`case_overrides`
WIND_OPTIONS = {"wind_speed": "wind_speed", "turbulence_intensity": "turbulence_intensity",
                "wind_seed": "wind_seed"}


def case_overrides(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """The case entries the options of :func:`add_rotor` replace, ``{table: {key: value}}``
    (:func:`hybridwsi.cases.with_values`); empty when none is given. A wind option implies the
    operating rotor; with ``--rotor parked`` or ``thrust`` it is refused."""
    rotor = {key: getattr(args, opt) for opt, key in WIND_OPTIONS.items()
             if getattr(args, opt, None) is not None}
    state = getattr(args, "rotor", None)
    if rotor and state not in (None, "operating"):
        given = ", ".join("--" + k.replace("_", "-") for k in rotor)
        raise InputError(f"{given} set the wind of the operating rotor; not with --rotor {state}")
    if state is not None or rotor:
        rotor["state"] = state or "operating"
    out: dict[str, dict[str, Any]] = {}
    if rotor:
        out["rotor"] = rotor
    forces = {"rotor": True} if rotor.get("state", "parked") != "parked" else {}
    if getattr(args, "slow_drift", None) is not None:
        forces["drift"] = bool(args.slow_drift)
    if forces:
        out["forces"] = forces
    return out


def add_eta(p: argparse.ArgumentParser) -> None:
    """``--eta COL``: the wave-elevation column/channel of a CSV or OpenFAST file."""
    p.add_argument("--eta", metavar="COL", default=None,
                   help="wave-elevation column [m, or the length unit of its header] of a "
                        "CSV, or channel of an OpenFAST file (e.g. Wave1Elev); read as "
                        "eta(time, probe). Default: a CSV column named eta; OpenFAST: every "
                        "Wave<n>Elev")


def add_json(p: argparse.ArgumentParser) -> None:
    """``--json FILE``: also write the printed results as JSON."""
    p.add_argument("--json", metavar="FILE", default=None,
                   help="also write the results as JSON to FILE (atomically)")


def add_quiet(p: argparse.ArgumentParser, *, alias: str | None = None) -> None:
    """``--quiet``: no progress bars and no summary; errors are still printed."""
    p.add_argument("--quiet", action="store_true",
                   help="print nothing but errors (no progress bar, no summary)")
    if alias:  # deprecated spelling kept working, hidden from --help
        p.add_argument(alias, dest="quiet", action="store_true", help=argparse.SUPPRESS)


def add_coeffs(p: argparse.ArgumentParser, help: str, *, group: Any = None) -> None:
    """``--coeffs FILE``: a coefficient file (NetCDF, Capytaine NetCDF, BEMIO .h5, WAMIT .1)."""
    (group or p).add_argument(
        "--coeffs", metavar="FILE", default=None,
        help="coefficient file: NetCDF (hybridwsi bem/coeffs, Capytaine), BEMIO .h5 or WAMIT "
             f"ROOT.1 (seawater rho, g assumed); {help}")


def add_mass(p: argparse.ArgumentParser, help: str, default: float | None = None) -> None:
    """``--mass M``: the rigid-body mass [kg] (positive, finite)."""
    p.add_argument("--mass", type=positive_float, default=default, metavar="KG",
                   help=f"rigid-body mass [kg]: {help}")


def add_columns(p: argparse.ArgumentParser) -> None:
    """``--time/--z/--zdot/--zddot COL``: the CSV columns of the kinematics."""
    for name, what in (("time", "time [s]"), ("z", "displacement [m or rad]"),
                       ("zdot", "velocity [m/s or rad/s]"),
                       ("zddot", "acceleration [m/s^2 or rad/s^2]")):
        p.add_argument(f"--{name}", metavar="COL", help=f"CSV column holding {what}")


def add_format(p: argparse.ArgumentParser) -> None:
    """``--format``: the input history format (default detected from the content)."""
    p.add_argument("--format", default="auto", choices=("auto", *FORMATS),
                   help="input format (default: detected from the content)")


def add_derivatives(p: argparse.ArgumentParser, help: str, default: str | None) -> None:
    """``--derivatives`` and ``--savgol-window``: estimation of missing zdot/zddot from z."""
    p.add_argument("--derivatives", choices=("savgol", "spline"), default=default,
                   help=f"method estimating missing zdot/zddot from z: {help}")
    p.add_argument("--savgol-window", type=positive_int, default=None, metavar="N",
                   help="Savitzky-Golay window [samples] of --derivatives savgol (default: "
                        "chosen from the data)")


# --------------------------------------------------------------------- optional extras

#: top-level module of an optional dependency -> the extra of pyproject.toml that installs it
EXTRAS = {"torch": "ml", "dask": "sweep", "distributed": "sweep", "zarr": "sweep",
          "pysph": "sph", "h5py": "bemio", "moorpy": "mooring"}


def missing_dependency(module: str | None) -> str | None:
    """The one-line message for a missing optional module, or None if it is not optional."""
    top = (module or "").split(".")[0]
    if top not in EXTRAS:
        return None
    return f"{top} is not installed; install it with: pip install 'hybridwsi[{EXTRAS[top]}]'"


def require(*modules: str) -> None:
    """Import optional dependencies up front; raise InputError naming the extra to install."""
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError:
            raise InputError(missing_dependency(name) or f"{name} is not installed") from None


# ------------------------------------------------------------------------- resources

#: fraction of the physical memory one run may plan to allocate
MEMORY_FRACTION = 0.5


def memory_bytes() -> int:
    """Physical memory of the machine [bytes] (0 when the OS does not say)."""
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 0


def check_allocation(n_bytes: float, what: str, fix: str) -> None:
    """Refuse a run whose estimated arrays exceed half the memory, before allocating them."""
    limit = MEMORY_FRACTION * memory_bytes()
    if limit and not n_bytes <= limit:
        raise InputError(f"{what} needs about {n_bytes / 2**30:.3g} GiB, more than "
                         f"{limit / 2**30:.3g} GiB (half the memory); {fix}")


#: float64 (time, dof) arrays a time-domain run holds per step: z, zdot, zddot, 7 force
#: components, the half-step excitation, solver states and the NetCDF copy (an upper bound)
ARRAYS_PER_STEP = 32


def check_steps(duration: float, dt: float, n_dof: int) -> int:
    """Number of time steps of a run; refuse one whose arrays cannot fit in memory."""
    n = duration / dt + 1
    check_allocation(n * n_dof * ARRAYS_PER_STEP * 8,
                     f"--duration {duration:g} s at --dt {dt:g} s ({n:.3g} steps)",
                     "increase --dt or shorten --duration")
    return int(n)


# ------------------------------------------------------------------------- histories


def read_dofs(path: str, dofs: Sequence[str] | None, *, format: str = "auto",
              **options: Any) -> Any:
    """:func:`hybridwsi.importers.read_history` with ``--dofs``.

    For a plain CSV, ``dofs`` names the DOFs of its columns (the reader's ``dof``); for the
    formats that name their DOFs (NetCDF, DualSPHysics, Kramer) it selects a subset of them.
    """
    if dofs is None:
        return read_history(path, format=format, **options)
    fmt = detect_format(path) if format == "auto" else format
    if fmt == "csv":
        return read_history(path, format=fmt, dof=list(dofs), **options)
    return select_dofs(read_history(path, format=fmt, **options), dofs, what=str(path))
