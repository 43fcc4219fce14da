"""Units of TimeHistory data: the one table every reader converts with (CSV headers, NetCDF
``units`` attributes), and the conversion of a whole history to SI.

Known units (case-insensitive; spellings normalised by :func:`normalise_unit`):

- length m, mm, cm, km, in, ft; time s, ms, min, h; angle rad, deg;
- force N, kN, MN; moment (force × length) N m, kN m, MN m (also ``Nm``, ``N.m``, ``N*m``);
- velocity and acceleration composed of those: ``mm/s``, ``ft/s^2``, ``deg/s``, ``m s-2``...

Anything else raises :class:`~hybridwsi.errors.InputError` naming the variable and the unit:
a unit that cannot be converted is never read as SI.
"""

from __future__ import annotations

import json
import math
import re
from functools import lru_cache

import numpy as np
import xarray as xr

from hybridwsi import dofs as _dofs
from hybridwsi.errors import InputError

_LENGTH = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "km": 1e3, "in": 0.0254, "ft": 0.3048}
_TIME = {"s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0}
_ANGLE = {"rad": 1.0, "deg": math.pi / 180}
_FORCE = {"n": 1.0, "kn": 1e3, "mn": 1e6}
#: word spellings -> the symbols above (per token, after lower-casing)
_ALIASES = {
    "sec": "s", "secs": "s", "second": "s", "seconds": "s", "hr": "h", "hour": "h", "hours": "h",
    "minute": "min", "minutes": "min", "mins": "min", "millisecond": "ms", "milliseconds": "ms",
    "meter": "m", "meters": "m", "metre": "m", "metres": "m", "millimeter": "mm",
    "millimeters": "mm", "millimetre": "mm", "millimetres": "mm", "inch": "in", "inches": "in",
    "foot": "ft", "feet": "ft", "degree": "deg", "degrees": "deg", "radian": "rad",
    "radians": "rad", "newton": "n", "newtons": "n",
}


def _composed(num: dict[str, float], den: dict[str, float], power: int) -> dict[str, float]:
    suffix = "" if power == 1 else f"^{power}"
    return {f"{a}/{b}{suffix}": fa / fb**power for a, fa in num.items() for b, fb in den.items()}


#: quantity -> canonical unit spelling (lower case) -> factor to SI
UNIT_FACTORS: dict[str, dict[str, float]] = {
    "time": dict(_TIME),
    "length": dict(_LENGTH),
    "velocity": _composed(_LENGTH, _TIME, 1),
    "acceleration": _composed(_LENGTH, _TIME, 2),
    "force": dict(_FORCE),
    "angle": dict(_ANGLE),
    "angular_velocity": _composed(_ANGLE, _TIME, 1),
    "angular_acceleration": _composed(_ANGLE, _TIME, 2),
    "moment": {f"{f} {l}": ff * fl for f, ff in _FORCE.items() for l, fl in _LENGTH.items()},
    "mass": {"kg": 1.0, "g": 1e-3, "t": 1e3},
}
#: the SI unit of each quantity (what a converted variable's ``units`` says)
SI_UNITS = {"time": "s", "length": "m", "velocity": "m/s", "acceleration": "m/s^2",
            "force": "N", "angle": "rad", "angular_velocity": "rad/s",
            "angular_acceleration": "rad/s^2", "moment": "N m", "mass": "kg"}
#: labels that mean "no unit"
_DIMENSIONLESS = {"", "1", "-", "none", "dimensionless"}


def quantity_of(role: str, dof: str = "Heave") -> str:
    """Physical quantity of a TimeHistory role (``time``, ``z``, ``zdot``, ``zddot``, ``force``)
    on ``dof`` (rotations take angles and moments, :func:`hybridwsi.dofs.is_rotation`)."""
    rot = _dofs.is_rotation(dof)
    return {
        "time": "time",
        "z": "angle" if rot else "length",
        "zdot": "angular_velocity" if rot else "velocity",
        "zddot": "angular_acceleration" if rot else "acceleration",
        "force": "moment" if rot else "force",
    }[role]


@lru_cache(maxsize=512)
def normalise_unit(unit: str) -> str:
    """Canonical spelling of a unit: ``"M S^-2"`` -> ``"m/s^2"``, ``"kN.m"`` -> ``"kn m"``,
    ``"meters/second"`` -> ``"m/s"``, ``"m/s²"`` -> ``"m/s^2"``. Unknown units are returned
    lower-cased (and then not found in :data:`UNIT_FACTORS`)."""
    u = unit.strip()
    if re.fullmatch(r"mN(\s*[.*·]?\s*m)?", u):
        return "millinewton"  # lower-casing would read it as MN: refuse rather than guess
    u = u.lower().replace("**", "^").replace("²", "^2").replace("·", " ").replace("⋅", " ")
    u = re.sub(r"\s*/\s*", "/", re.sub(r"\s+", " ", u))
    u = "".join(_ALIASES.get(tok, tok) for tok in re.split(r"([/ ^*.\-])", u))
    # "m s^-2", "m.s-1", "m*s^-1" -> "m/s^2", "m/s"
    m = re.fullmatch(r"(.+?)[ .*]([a-z]+)\^?-([12])", u)
    if m:
        u = f"{m.group(1)}/{m.group(2)}" + ("^2" if m.group(3) == "2" else "")
    m = re.fullmatch(r"(.+?)/([a-z]+)\^?2", u)  # "m/s2" -> "m/s^2"
    if m:
        u = f"{m.group(1)}/{m.group(2)}^2"
    m = re.fullmatch(r"((?:k|m)?n)\s*[.*]?\s*(m|mm|cm|km|in|ft)", u)  # "kNm", "N.m" -> "kn m"
    if m:
        u = f"{m.group(1)} {m.group(2)}"
    return u


def unit_factor(unit: str | None, quantity: str, column: str) -> float:
    """Factor converting ``unit`` to SI for ``quantity``; no unit means SI already.

    Parameters
    ----------
    unit : str or None
        As written (``"mm"``, ``"kN m"``, ``"deg/s^2"``...).
    quantity : str
        A key of :data:`UNIT_FACTORS` (see :func:`quantity_of`).
    column : str
        Name of the column or variable, for the error message.
    """
    if unit is None or unit.strip() == "":
        return 1.0
    table = UNIT_FACTORS[quantity]
    key = normalise_unit(unit)
    if key not in table:
        raise InputError(
            f"column '{column}' has unit '{unit}', not a {quantity.replace('_', ' ')} unit "
            f"hybridwsi knows (accepted: {', '.join(list(table)[:12])}"
            f"{', ...' if len(table) > 12 else ''})"
        )
    return table[key]


def quantity_of_unit(unit: str) -> str | None:
    """The quantity a unit measures (``"mm/s"`` -> ``"velocity"``), None when unknown."""
    key = normalise_unit(unit)
    return next((q for q, table in UNIT_FACTORS.items() if key in table), None)


# --------------------------------------------------------------------------------------------
# A whole history in SI
# --------------------------------------------------------------------------------------------


def _per_dof_units(attrs: dict, n_dof: int, name: str) -> list[str | None]:
    """Unit of a ``(time, dof)`` variable per DOF, from ``units_per_dof`` or ``units``."""
    if "units_per_dof" in attrs:
        try:
            per = json.loads(attrs["units_per_dof"])
        except (TypeError, ValueError):
            raise InputError(f"'{name}' has an unreadable units_per_dof attribute") from None
        if not isinstance(per, list) or len(per) != n_dof:
            raise InputError(f"'{name}' units_per_dof {attrs['units_per_dof']!r} does not "
                             f"list one unit per DOF ({n_dof})")
        per = [None if u is None else str(u) for u in per]
        if "units" in attrs:  # the CF attribute must name the same units as our per-DOF list
            listed = {normalise_unit(p.strip()) for p in str(attrs["units"]).split(",")}
            if listed != {normalise_unit(u) for u in per if u is not None}:
                raise InputError(f"'{name}' has units '{attrs['units']}' but units_per_dof "
                                 f"{attrs['units_per_dof']}: the two disagree")
        return per
    units = attrs.get("units")
    if units is None:
        return [None] * n_dof
    parts = [p.strip() for p in str(units).split(",")]
    if len(parts) == n_dof:
        return parts
    if len(parts) == 1:
        return parts * n_dof
    # units_label lists each distinct unit once ("m, rad" for Surge, Sway, Pitch): ambiguous
    raise InputError(f"'{name}' has units '{units}' for {n_dof} DOFs: give units_per_dof "
                     "(a JSON list, one unit per DOF)")


def _role(ds: xr.Dataset, name: str) -> str | None:
    if name in ("z", "zdot", "zddot"):
        return name
    return "force" if ds.variables[name].attrs.get("role") == "force" else None


def _time_factor(var: xr.Variable) -> float:
    units = var.attrs.get("units")
    if units is None:
        return 1.0
    unit = str(units).split(" since ")[0]  # CF "seconds since 2000-01-01": offsets in seconds
    return unit_factor(unit, "time", "time")


def history_factors(ds: xr.Dataset) -> dict[str, float | np.ndarray]:
    """SI factor of every variable/coordinate of a history that carries units.

    Returns ``{name: factor}`` (an array per DOF for ``(time, dof)`` variables); raises
    :class:`InputError` for a unit that does not fit the variable (``z`` in ``furlong``, a
    rotation's ``z`` in ``m``). Variables that are neither kinematics, forces, time nor mass
    are converted when their unit is known, and left as they are otherwise.
    """
    out: dict[str, float | np.ndarray] = {}
    if "time" in ds.variables and not np.issubdtype(ds["time"].dtype, np.datetime64):
        out["time"] = _time_factor(ds.variables["time"])
    dof = [str(d) for d in ds["dof"].values] if "dof" in ds.coords else []
    for name, var in ds.variables.items():
        name = str(name)
        if name == "time" or name in ("dof", "dof_j"):
            continue
        role = _role(ds, name) if name in ds.data_vars else None
        if role is not None and var.dims == ("time", "dof"):
            units = _per_dof_units(var.attrs, len(dof), name)
            out[name] = np.array([
                unit_factor(u, quantity_of(role, d), f"{name}" + (f" on {d}" if len(dof) > 1 else ""))
                for u, d in zip(units, dof)])
        elif name == "mass":
            units = var.attrs.get("units")
            if len(dof) == 1 and units is not None:
                out[name] = unit_factor(str(units), "mass", name)
        elif "units" in var.attrs and not str(var.attrs["units"]).strip().lower() in _DIMENSIONLESS:
            q = quantity_of_unit(str(var.attrs["units"]))
            if q is not None and "," not in str(var.attrs["units"]):
                out[name] = UNIT_FACTORS[q][normalise_unit(str(var.attrs["units"]))]
    return out


def _si_label(quantity_by_dof: list[str]) -> dict[str, str]:
    per = [SI_UNITS[q] for q in quantity_by_dof]
    return {"units": ", ".join(dict.fromkeys(per)), "units_per_dof": json.dumps(per)}


def to_si(ds: xr.Dataset) -> xr.Dataset:
    """A history with every variable and coordinate carrying units converted to SI.

    ``time`` in ms/min/h (or CF ``"<unit> since <date>"``, or decoded as dates) becomes
    seconds; ``z``/``zdot``/``zddot`` and force components per DOF (``units_per_dof`` or
    ``units``) become m, m/s, m/s² (rad, rad/s, rad/s² on rotations) and N (N m); a 1-DOF
    ``mass`` becomes kg; other variables with a known unit (``eta`` in mm) are converted too.
    Their ``units`` attributes then name the SI unit. Unknown units raise
    :class:`InputError` (one line naming the variable and the unit). Returns ``ds`` itself
    when everything is SI already.
    """
    if "time" in ds.coords and np.issubdtype(ds["time"].dtype, np.datetime64):
        t = ds["time"].values
        seconds = (t - t[0]) / np.timedelta64(1, "s")
        ds = ds.assign_coords(time=("time", seconds.astype(float), {"units": "s"}))
    factors = history_factors(ds)
    dof = [str(d) for d in ds["dof"].values] if "dof" in ds.coords else []
    changed = {k: f for k, f in factors.items() if np.any(np.asarray(f) != 1.0)}
    relabel = [k for k in factors if k in ds.data_vars and _role(ds, k) is not None]
    if not changed and all(_is_si_label(ds, k, dof) for k in relabel):
        return ds
    out = ds.copy()
    for name, f in changed.items():
        var = out.variables[name]
        attrs = dict(var.attrs)
        values = np.asarray(var.values, dtype=float) * f  # per DOF: broadcasts on the last axis
        if name == "time":
            out = out.assign_coords(time=("time", values, {**attrs, "units": "s"}))
            continue
        if name not in relabel:
            q = "mass" if name == "mass" else quantity_of_unit(str(attrs["units"]))
            attrs["units"] = SI_UNITS[q]  # type: ignore[index]
        out[name] = (var.dims, values, attrs)
    for name in relabel:
        role = _role(out, name)
        out[name].attrs.update(_si_label([quantity_of(role, d) for d in dof]))  # type: ignore[arg-type]
    return out


def _is_si_label(ds: xr.Dataset, name: str, dof: list[str]) -> bool:
    role = _role(ds, name)
    want = _si_label([quantity_of(role, d) for d in dof])  # type: ignore[arg-type]
    attrs = ds.variables[name].attrs
    return attrs.get("units_per_dof", want["units_per_dof"]) == want["units_per_dof"] and (
        "units_per_dof" in attrs or attrs.get("units") in (None, want["units"]))


def check_si(ds: xr.Dataset) -> None:
    """Raise :class:`InputError` when a variable of a history is not in SI (or has an unknown
    unit): what :func:`hybridwsi.history.validate` checks so that a file read without
    conversion (``read_netcdf``) is never used with the wrong scale."""
    if "time" in ds.coords and np.issubdtype(ds["time"].dtype, np.datetime64):
        raise InputError("time holds dates, not seconds: read the file with "
                         "hybridwsi.importers.read_history (converts units)")
    for name, f in history_factors(ds).items():
        if np.any(np.asarray(f) != 1.0):
            unit = ds.variables[name].attrs.get("units_per_dof") or ds.variables[name].attrs.get("units")
            raise InputError(
                f"'{name}' is in {unit}, not SI: read the file with "
                "hybridwsi.importers.read_history or convert with hybridwsi.history.to_si"
            )


# --------------------------------------------------------------------------------------------
# Units of parameters (case files): a general product/quotient of SI-derived tokens
# --------------------------------------------------------------------------------------------

#: base dimensions of :func:`parse_unit`: mass, length, time and plane angle (kept apart from
#: a pure number so that N m and N m/rad are not confused)
BASE_DIMENSIONS = ("kg", "m", "s", "rad")
#: unit token -> (factor to the base units, exponents of :data:`BASE_DIMENSIONS`);
#: case-sensitive (``MN`` mega-newton, ``m`` metre)
UNIT_TOKENS: dict[str, tuple[float, tuple[int, int, int, int]]] = {
    "kg": (1.0, (1, 0, 0, 0)), "g": (1e-3, (1, 0, 0, 0)), "t": (1e3, (1, 0, 0, 0)),
    **{u: (f, (0, 1, 0, 0)) for u, f in _LENGTH.items()},
    **{u: (f, (0, 0, 1, 0)) for u, f in _TIME.items()},
    "N": (1.0, (1, 1, -2, 0)), "kN": (1e3, (1, 1, -2, 0)), "MN": (1e6, (1, 1, -2, 0)),
    "Pa": (1.0, (1, -1, -2, 0)), "kPa": (1e3, (1, -1, -2, 0)), "MPa": (1e6, (1, -1, -2, 0)),
    "GPa": (1e9, (1, -1, -2, 0)),
    "rad": (1.0, (0, 0, 0, 1)), "deg": (math.pi / 180.0, (0, 0, 0, 1)),
    "Hz": (1.0, (0, 0, -1, 0)),
}
_DIMENSIONLESS_UNITS = {"", "1", "-"}
_TERM = re.compile(r"^([A-Za-z]+)(?:(?:\^|\*\*)?(-?\d+)|([²³]))?$")


def _unit_terms(text: str, sign: int, out: list[tuple[float, tuple[int, ...]]]) -> None:
    for term in re.split(r"[\s*·.]+", text.strip()):
        if not term:
            continue
        m = _TERM.match(term)
        if m is None or m.group(1) not in UNIT_TOKENS:
            raise InputError(f"unknown unit {term!r} (known: {', '.join(UNIT_TOKENS)})")
        power = int(m.group(2)) if m.group(2) else {"²": 2, "³": 3}.get(m.group(3) or "", 1)
        factor, dims = UNIT_TOKENS[m.group(1)]
        out.append((factor ** (sign * power), tuple(sign * power * d for d in dims)))


@lru_cache(maxsize=512)
def parse_unit(text: str) -> tuple[float, tuple[int, ...]]:
    """``(factor to base units, exponents over BASE_DIMENSIONS)`` of a unit expression.

    Products of the tokens of :data:`UNIT_TOKENS` separated by spaces, ``*``, ``·`` or ``.``,
    with integer powers (``m^2``, ``m**2``, ``m²``, ``s^-2``) and one ``/`` after which every
    term is in the denominator: ``"kg/m^3"``, ``"N s/m"``, ``"N m s/rad"``, ``"kg m^2"``.
    ``""``, ``"1"`` and ``"-"`` are dimensionless. Raises :class:`InputError` for anything else.
    """
    if text.strip() in _DIMENSIONLESS_UNITS:
        return 1.0, (0, 0, 0, 0)
    num, slash, den = text.partition("/")
    if "/" in den:
        raise InputError(f"unit {text!r}: write at most one '/' (e.g. 'm/s^2', 'N s/m')")
    terms: list[tuple[float, tuple[int, ...]]] = []
    _unit_terms(num, 1, terms)
    if slash:
        if not den.strip():
            raise InputError(f"unit {text!r} has nothing after '/'")
        _unit_terms(den, -1, terms)
    factor, dims = 1.0, (0, 0, 0, 0)
    for f, d in terms:
        factor *= f
        dims = tuple(a + b for a, b in zip(dims, d))
    return factor, dims


def convert_unit(value: float, unit: str, to: str) -> float:
    """``value`` in ``unit`` expressed in ``to`` (:func:`parse_unit` expressions), or an
    :class:`InputError` when the two measure different quantities (``"320 s"`` as a depth)."""
    f_from, d_from = parse_unit(unit)
    f_to, d_to = parse_unit(to)
    if d_from != d_to:
        raise InputError(f"unit '{unit}' is not a unit of {to or 'a pure number'}")
    return value * f_from / f_to
