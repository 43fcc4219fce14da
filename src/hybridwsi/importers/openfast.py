"""OpenFAST output files (``.out`` text, ``.outb`` binary) as a TimeHistory: format ``openfast``.

The files are parsed by NREL's ``openfast-io`` (:mod:`openfast_io.FAST_output_reader`,
optional extra ``hybridwsi[openfast]``); this module maps their channels onto the
TimeHistory's DOFs in SI units, taking each channel's unit from the file's unit row.

Channels (names case-insensitive; a leading ``-`` in a name, OpenFAST's sign flip, is undone):

- displacement ``z``: ElastoDyn ``PtfmSurge``, ``PtfmSway``, ``PtfmHeave`` (m) and
  ``PtfmRoll``, ``PtfmPitch``, ``PtfmYaw`` (deg -> rad); else ``PtfmTDxi``/``PtfmRDxi``...;
  else HydroDyn's platform reference point ``PRPSurge``... (m, rad);
- velocity ``zdot``: ``PtfmTVxi``, ``PtfmTVyi``, ``PtfmTVzi`` (m/s), ``PtfmRVxi``,
  ``PtfmRVyi``, ``PtfmRVzi`` (deg/s -> rad/s), the time derivatives of the platform DOFs in
  ElastoDyn (inertial frame ``i``; the tilted-frame ``...t`` channels are not); else
  ``PRPTVxi``...;
- acceleration ``zddot``: ``PtfmTAxi``... (m/s^2), ``PtfmRAxi``... (deg/s^2 -> rad/s^2); else
  ``PRPTAxi``...;
- forces [N, N m] on the selected DOFs (a force is kept only when its channel exists for every
  selected DOF): ``F_hydro`` = HydroDyn ``HydroFxi``...``HydroMzi`` (total hydrodynamic load at
  the platform reference point); ``F_platform`` = ElastoDyn ``PtfmFxi``...``PtfmMzi``
  (external load on the platform: hydrodynamic + mooring, kN -> N); HydroDyn's WAMIT body 1
  parts ``F_exc`` (``B1WvsFxi``..., wave excitation), ``F_hs`` (``B1HdSFxi``..., hydrostatics
  including the buoyancy rho g V0 in heave), ``F_rad_mem`` (``B1RdtFxi``..., radiation
  memory) and ``F_add`` (``B1AddFxi``..., HydroDyn's additional preload, stiffness and damping);
  ``F_tot = M zddot`` when a mass is given and the accelerations are in the file;
- other variables: ``T_fairlead(time, line)`` and ``T_anchor(time, line)`` [N] from the
  mooring module's ``FAIRTEN<n>``/``ANCHTEN<n>`` (the names every mooring model of hybridwsi
  records), ``eta(time, probe)`` [m] from ``Wave<n>Elev`` (every probe; ``eta="Wave2Elev"``:
  that channel alone, any length channel may be named).

Velocities or accelerations not in the file (for some selected DOF) are estimated from ``z``
(:func:`hybridwsi.history.estimate_derivatives`) and say so in ``attrs["estimated"]``.
"""

from __future__ import annotations

import os
import re
import struct
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi import dofs as _dofs
from hybridwsi.errors import InputError
from hybridwsi.history import (
    UNIFORM_RTOL,
    estimate_derivatives,
    finalize_import,
    is_uniform,
    make_history,
    quantity_of,
    unit_factor,
    units_attrs,
)

#: OpenFAST's binary file identifiers (FileFmtID_WithTime ... FileFmtID_ChanLen_In)
BINARY_FILE_IDS = (1, 2, 3, 4)
#: rows of the text header: names on line 7, units on line 8 (openfast-io's layout)
_TEXT_HEADER_LINES = 8
_NAME_LINE, _UNIT_LINE = 6, 7
_AXIS = {"Surge": "x", "Sway": "y", "Heave": "z", "Roll": "x", "Pitch": "y", "Yaw": "z"}

#: force variable -> (channel pattern, description); {L} is F (translation) or M (rotation)
FORCE_CHANNELS: dict[str, tuple[str, str]] = {
    "F_hydro": ("Hydro{L}{a}i", "HydroDyn total hydrodynamic load at the platform reference "
                "point"),
    "F_platform": ("Ptfm{L}{a}i", "ElastoDyn external platform load (hydrodynamic + mooring) "
                   "at the platform reference point"),
    "F_exc": ("B1Wvs{L}{a}i", "HydroDyn wave excitation on WAMIT body 1"),
    "F_hs": ("B1HdS{L}{a}i", "HydroDyn hydrostatic load on WAMIT body 1 (with the buoyancy "
             "rho g V0 in heave)"),
    "F_rad_mem": ("B1Rdt{L}{a}i", "HydroDyn radiation memory load on WAMIT body 1"),
    "F_add": ("B1Add{L}{a}i", "HydroDyn additional preload, stiffness and damping on WAMIT "
              "body 1"),
}
#: numbered channels kept as extra variables: variable -> (name regex, dim, quantity, units)
SERIES_CHANNELS: dict[str, tuple[str, str, str, str]] = {
    "T_fairlead": (r"FAIRTEN(\d+)", "line", "force", "N"),
    "T_anchor": (r"ANCHTEN(\d+)", "line", "force", "N"),
    "eta": (r"WAVE(\d+)ELEV", "probe", "length", "m"),
}


def motion_channels(role: str, dof: str) -> tuple[str, ...]:
    """OpenFAST channels holding kinematic ``role`` (``z``, ``zdot``, ``zddot``) of ``dof``,
    in order of preference (ElastoDyn platform DOF first, HydroDyn's PRP last)."""
    kind = "R" if _dofs.is_rotation(dof) else "T"
    a = _AXIS[_dofs.check_dofs([dof])[0]]
    if role == "z":
        return (f"Ptfm{dof}", f"Ptfm{kind}D{a}i", f"PRP{dof}")
    letter = {"zdot": "V", "zddot": "A"}[role]
    return (f"Ptfm{kind}{letter}{a}i", f"PRP{kind}{letter}{a}i")


@dataclass
class OpenFASTChannels:
    """The channels of one OpenFAST output file, as read by openfast-io.

    Attributes
    ----------
    path : Path
    description : str
        The file's description line.
    names, units : list of str
        Channel names and units (without parentheses), ``names[0]`` the time.
    data : ndarray, shape (n_time, n_channels)
        Values in the file's units.
    """

    path: Path
    description: str
    names: list[str]
    units: list[str]
    data: np.ndarray

    @cached_property
    def lookup(self) -> dict[str, tuple[int, float]]:
        """``{NAME: (column, sign)}``: upper-case names without OpenFAST's ``-`` sign flip,
        whose sign is -1 (the first column of a name wins)."""
        out: dict[str, tuple[int, float]] = {}
        for j, name in enumerate(self.names):
            out.setdefault(name.upper().lstrip("-"), (j, -1.0 if name.startswith("-") else 1.0))
        return out

    def find(self, candidates: Sequence[str]) -> tuple[int, float] | None:
        """Column and sign of the first of ``candidates`` present (case-insensitive)."""
        return next((self.lookup[c.upper()] for c in candidates if c.upper() in self.lookup),
                    None)

    def si(self, column: int, sign: float, quantity: str) -> np.ndarray:
        """Column ``column`` times ``sign`` in SI units (its unit from the unit row)."""
        name, unit = self.names[column], self.units[column]
        # OpenFAST spells moments N-m, kN-m; hybridwsi's table has "N m"
        unit = re.sub(r"(?<=[A-Za-z])-(?=[A-Za-z])", " ", unit)
        try:
            factor = unit_factor(unit, quantity, name)
        except InputError as exc:
            raise InputError(f"{self.path.name}: {exc}") from None
        return sign * factor * self.data[:, column]


# --------------------------------------------------------------------------------------------
# Recognising and reading the files
# --------------------------------------------------------------------------------------------


def _text_header(path: Path) -> list[str] | None:
    """The first lines of a text file (None for a binary one)."""
    with open(path, "rb") as f:
        head = f.read(65536)
    if b"\x00" in head:
        return None
    return head.decode("latin-1").splitlines()[:_TEXT_HEADER_LINES]


def _binary_header(path: Path) -> tuple[int, int, int] | None:
    """``(file id, number of channels, number of time steps)`` of an OpenFAST binary file,
    or None when the first bytes do not fit the format."""
    with open(path, "rb") as f:
        head = f.read(12)
    if len(head) < 10:
        return None
    (file_id,) = struct.unpack("<h", head[:2])
    if file_id not in BINARY_FILE_IDS:
        return None
    offset = 4 if file_id == 4 else 2  # FileFmtID_ChanLen_In stores the name length first
    if len(head) < offset + 8:
        return None
    n_chan, n_time = struct.unpack("<ii", head[offset:offset + 8])
    return file_id, n_chan, n_time


def _looks_like_text_output(lines: list[str]) -> bool:
    """Names on line 7 starting with ``Time`` and a unit row of ``(unit)`` cells on line 8."""
    if len(lines) < _TEXT_HEADER_LINES:
        return False
    names, units = lines[_NAME_LINE].split(), lines[_UNIT_LINE].split()
    return bool(names) and names[0].lower() == "time" and len(units) == len(names) and all(
        u.startswith("(") and u.endswith(")") for u in units)


def is_openfast_output(path: str | os.PathLike) -> bool:
    """Whether ``path`` is an OpenFAST output file: a ``.outb`` binary, or a text file with
    OpenFAST's header (channel names on line 7 from ``Time``, ``(unit)`` cells on line 8)."""
    path = Path(path)
    if not path.is_file():
        return False
    lines = _text_header(path)
    if lines is None:
        return path.suffix.lower() in (".outb", ".out") and _binary_header(path) is not None
    return _looks_like_text_output(lines)


def _openfast_io():
    try:
        from openfast_io import FAST_output_reader
    except ImportError:
        raise InputError("reading OpenFAST output needs openfast-io: "
                         "pip install 'hybridwsi[openfast]'") from None
    return FAST_output_reader


def _first_ragged_line(path: Path, width: int) -> str:
    """``line N has K fields`` for the first data row whose width is not ``width``."""
    with open(path, encoding="latin-1") as f:
        for i, line in enumerate(f, start=1):
            if i > _TEXT_HEADER_LINES and len(line.split()) != width:
                return f"line {i} has {len(line.split())} fields, not {width}"
    return "rows of unequal length"


def read_channels(path: str | os.PathLike) -> OpenFASTChannels:
    """All channels of an OpenFAST ``.out``/``.outb`` file (binary recognised by content).

    Raises :class:`InputError` (one line) for a missing, empty, truncated or malformed file,
    or when openfast-io is not installed.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"file not found: {path}")
    if path.stat().st_size == 0:
        raise InputError(f"{path.name} is empty")
    reader = _openfast_io()
    lines = _text_header(path)
    if lines is None:
        header = _binary_header(path)
        if header is None:
            raise InputError(f"{path.name}: not an OpenFAST binary output file (file id not "
                             f"in {BINARY_FILE_IDS})")
        file_id, n_chan, n_time = header
        width = 8 if file_id == 3 else 2  # uncompressed float64, else int16
        if n_chan <= 0 or n_time <= 0 or n_chan * n_time * width > path.stat().st_size:
            raise InputError(f"{path.name}: truncated or corrupt OpenFAST binary file (header "
                             f"says {n_chan} channels x {n_time} steps)")
        try:
            data, info, _ = reader.load_binary_output(str(path))
        except Exception as exc:  # openfast-io raises bare Exception/struct.error on short files
            raise InputError(f"{path.name}: truncated or corrupt OpenFAST binary file "
                             f"({type(exc).__name__}: {str(exc)[:80]})") from None
    else:
        if not _looks_like_text_output(lines):
            raise InputError(f"{path.name}: not an OpenFAST text output (expected channel names "
                             "from 'Time' on line 7 and '(unit)' cells on line 8)")
        n_names = len(lines[_NAME_LINE].split())
        try:
            data, info = reader.load_ascii_output(str(path))
        except ValueError as exc:
            if "convert" in str(exc):  # numpy: could not convert string to float: 'x'
                raise InputError(f"{path.name}: non-numeric value in the data "
                                 f"({str(exc)[:60]})") from None
            raise InputError(f"{path.name}: {_first_ragged_line(path, n_names)} (truncated "
                             "file?)") from None
    data = np.asarray(data, dtype=float)
    names, units = list(info["attribute_names"]), list(info["attribute_units"])
    if data.ndim != 2 or data.shape[0] == 0:
        raise InputError(f"{path.name}: no data rows after the header")
    if data.shape[1] != len(names) or len(units) != len(names):
        raise InputError(f"{path.name}: {len(names)} channel names, {len(units)} units and "
                         f"{data.shape[1]} values per row do not match")
    if names[0].lower() != "time":
        raise InputError(f"{path.name}: the first channel is '{names[0]}', not Time")
    return OpenFASTChannels(path, str(info.get("description", "")), names, units, data)


# --------------------------------------------------------------------------------------------
# Channels -> TimeHistory
# --------------------------------------------------------------------------------------------


def _role(ch: OpenFASTChannels, role: str, dofs: Sequence[str]
          ) -> tuple[np.ndarray | None, list[str], list[str]]:
    """``(values (time, dof) or None, channels used, DOFs without a channel)`` of a role."""
    cols, used, missing = [], [], []
    for d in dofs:
        found = ch.find(motion_channels(role, d))
        if found is None:
            missing.append(d)
            continue
        cols.append(ch.si(*found, quantity_of(role, d)))
        used.append(ch.names[found[0]])
    return (np.column_stack(cols) if not missing else None), used, missing


def _forces(ch: OpenFASTChannels, dofs: Sequence[str]
            ) -> tuple[dict[str, np.ndarray], dict[str, list[str]], list[str]]:
    """Force variables present for every DOF, their channels, and notes on partial ones."""
    values, used, notes = {}, {}, []
    for var, (pattern, _) in FORCE_CHANNELS.items():
        names = [pattern.format(L="M" if _dofs.is_rotation(d) else "F", a=_AXIS[d]) for d in dofs]
        found = [ch.find([n]) for n in names]
        if all(f is None for f in found):
            continue
        absent = [n for n, f in zip(names, found) if f is None]
        if absent:
            notes.append(f"{var} left out: {', '.join(absent)} not in the file")
            continue
        values[var] = np.column_stack([ch.si(*f, quantity_of("force", d))
                                       for f, d in zip(found, dofs)])
        used[var] = [ch.names[f[0]] for f in found]
    return values, used, notes


def _series(ch: OpenFASTChannels, eta: str | None = None) -> dict[str, tuple]:
    """Numbered channels (fairlead tensions, wave elevations) as extra variables; ``eta``:
    the one channel read as the wave elevation instead of every ``Wave<n>Elev``."""
    out = {}
    if eta is not None:
        found = ch.find([eta])
        if found is None:
            raise InputError(f"{ch.path.name}: no wave-elevation channel '{eta}' (channels: "
                             f"{', '.join(ch.names[:12])}{' ...' if len(ch.names) > 12 else ''})")
        out["eta"] = ((("time", "probe"), ch.si(*found, "length")[:, None],
                       {"units": "m", "channels": ch.names[found[0]]}),
                      ("probe", [ch.names[found[0]]]))
    for var, (regex, dim, quantity, units) in SERIES_CHANNELS.items():
        if var in out:
            continue
        hits = sorted((int(m.group(1)), col) for key, col in ch.lookup.items()
                      if (m := re.fullmatch(regex, key)))
        if hits:
            values = np.column_stack([ch.si(*col, quantity) for _, col in hits])
            attrs = {"units": units, "channels": ", ".join(ch.names[c[0]] for _, c in hits)}
            out[var] = ((("time", dim), values, attrs), (dim, [k for k, _ in hits]))
    return out


def _mass_force(mass: float | np.ndarray, zddot: np.ndarray, dofs: Sequence[str]
                ) -> np.ndarray | None:
    """``F_tot = M zddot`` [N, N m], or None when a scalar mass meets a rotational DOF."""
    m = np.atleast_2d(np.asarray(mass, dtype=float))
    if m.shape == (1, 1):
        if any(_dofs.is_rotation(d) for d in dofs):
            return None
        m = np.eye(len(dofs)) * m[0, 0]
    if m.shape != (len(dofs), len(dofs)):
        raise InputError(f"mass must be a scalar or a ({len(dofs)}, {len(dofs)}) matrix for "
                         f"DOFs {list(dofs)}, got shape {m.shape}")
    return zddot @ m.T


def _snap_time(t: np.ndarray) -> tuple[np.ndarray, str | None]:
    """A uniform grid rounded to its printed decimals -> the exact grid (else ``t`` unchanged).

    OpenFAST prints time with a fixed number of decimals, so an output step such as 0.00625 s
    reads back as alternating 0.0062/0.0063 s steps. The grid keeps the first time and takes
    the least-squares step through it; it replaces ``t`` when every sample lies within one
    printed unit of it.
    """
    steps = np.diff(t)
    if t.size < 3 or np.ptp(steps) <= UNIFORM_RTOL * np.median(steps):
        return t, None
    quantum = next((10.0 ** -d for d in range(1, 10)
                    if np.all(np.abs(t * 10.0**d - np.round(t * 10.0**d)) < 1e-6)), None)
    if quantum is None:
        return t, None
    k = np.arange(t.size)
    dt = float(np.dot(k, t - t[0]) / np.dot(k, k))
    grid = t[0] + dt * k
    shift = float(np.max(np.abs(t - grid)))
    if shift == 0.0 or shift > quantum:
        return t, None
    return grid, (f"time printed to {quantum:g} s: replaced by the uniform grid "
                  f"t0 + k*{dt:.9g} s (largest shift {shift:.3g} s)")


def _estimate(ds: xr.Dataset, role: str, reason: str, notes: list[str]) -> xr.Dataset:
    """``ds`` with ``role`` estimated from ``z`` (constant DOFs get an exact zero); the method
    and ``reason`` go to the variable's ``attrs["estimated"]``, a failure to ``notes``."""
    if not is_uniform(ds):
        notes.append(f"{role} not in the file and not estimated: the time is irregular")
        return ds
    dofs = [str(d) for d in ds["dof"].values]
    z = ds["z"].values
    moving = [j for j in range(len(dofs)) if np.ptp(z[:, j]) > 0]
    values = np.zeros_like(z)
    desc = "zero (constant z)"
    if moving:
        sub = make_history(ds["time"].values, z[:, moving], dof=[dofs[j] for j in moving],
                           check=False)
        est = estimate_derivatives(sub)[role]
        values[:, moving] = est.values
        desc = est.attrs["estimated"]
        if len(moving) < len(dofs):
            desc += "; zero for constant " + ", ".join(d for j, d in enumerate(dofs)
                                                      if j not in moving)
    out = ds.copy()
    out[role] = (("time", "dof"), values, {**units_attrs(role, dofs),
                                             "estimated": f"{desc} ({reason})"})
    return out


def _platform_dofs(ch: OpenFASTChannels, dofs: str | Sequence[str] | None) -> list[str]:
    """The DOFs asked for, or every DOF whose displacement channel is in the file."""
    if dofs is None:
        dofs = [d for d in _dofs.RIGID_DOFS if ch.find(motion_channels("z", d)) is not None]
        if not dofs:
            raise InputError(f"{ch.path.name}: no platform displacement channel (PtfmSurge ... "
                             "PtfmYaw or PRPSurge ...); channels: "
                             f"{', '.join(ch.names[:12])}{' ...' if len(ch.names) > 12 else ''}")
    return list(_dofs.check_dofs(dofs))


def _motion(ch: OpenFASTChannels, dofs: list[str]
            ) -> tuple[dict[str, np.ndarray], dict[str, list[str]], dict[str, list[str]]]:
    """Displacement (required), velocity and acceleration of ``dofs`` in SI by role, the
    channels read per role, and the channels missing per derivative (estimated later)."""
    z, z_used, z_missing = _role(ch, "z", dofs)
    if z is None:
        raise InputError(f"{ch.path.name}: no displacement channel for {', '.join(z_missing)} "
                         f"(looked for {', '.join(motion_channels('z', z_missing[0]))})")
    kin = {"z": z}
    used = {"z": z_used}
    missing: dict[str, list[str]] = {}
    for role in ("zdot", "zddot"):
        values, cols, absent = _role(ch, role, dofs)
        if values is not None:
            kin[role], used[role] = values, cols
        else:
            missing[role] = [motion_channels(role, d)[0] for d in absent]
    return kin, used, missing


def _describe_forces(ds: xr.Dataset, force_used: dict[str, list[str]]) -> None:
    """Each force variable's description: what it is and the channels it sums, in place."""
    for var, (_, desc) in FORCE_CHANNELS.items():
        if var in ds:
            ds[var].attrs["description"] = f"{desc} ({', '.join(force_used[var])})"
    if "F_tot" in ds:
        ds["F_tot"].attrs["description"] = "mass matrix x zddot (total force on the rigid platform)"


def read_openfast(
    path: str | os.PathLike,
    dofs: str | Sequence[str] | None = None,
    mass: float | np.ndarray | None = None,
    *,
    resample: bool = False,
    require_uniform: bool = True,
    eta: str | None = None,
) -> xr.Dataset:
    """Platform motion and loads of an OpenFAST run (``.out`` or ``.outb``) as a TimeHistory.

    Parameters
    ----------
    path : path-like
        OpenFAST output: text ``.out`` (tab/space separated, names on line 7, ``(unit)`` row on
        line 8) or binary ``.outb`` (any FileFmtID 1-4); read with openfast-io.
    dofs : str or sequence of str, optional
        DOFs to keep (``"Surge,Heave,Pitch"``); each needs its displacement channel. Default:
        every DOF whose displacement is in the file, in Surge...Yaw order.
    mass : float or array, optional
        Rigid-body mass [kg] (translations only) or (n_dof, n_dof) matrix [kg, kg m, kg m²]
        about the platform reference point. With the accelerations in the file,
        ``F_tot = M zddot`` is added (the total external force on a rigid platform).
    resample, require_uniform : bool
        Irregular time (variable-step output): see :mod:`hybridwsi.importers`.
    eta : str, optional
        The channel of the wave elevation (e.g. ``"Wave1Elev"``, unit from the file); default
        every ``Wave<n>Elev`` channel, one probe each.

    Returns
    -------
    xarray.Dataset
        ``z`` [m, rad], ``zdot``, ``zddot`` (from the file or estimated, ``attrs["estimated"]``
        saying how and which channels were missing), forces [N, N m] (see the module
        docstring). Loads left out and similar remarks are in ``attrs["notes"]`` and raised as
        :class:`UserWarning` (the commands print them as notes).
    """
    ch = read_channels(path)
    t = ch.si(0, 1.0, "time")
    t, time_note = _snap_time(t)
    dofs = _platform_dofs(ch, dofs)
    kin, used, missing = _motion(ch, dofs)
    forces, force_used, notes = _forces(ch, dofs)
    if mass is not None and "zddot" in kin:
        f_tot = _mass_force(mass, kin["zddot"], dofs)
        if f_tot is None:
            notes.append("F_tot not formed: a scalar mass does not apply to rotations; give "
                         "the mass matrix")
        else:
            forces["F_tot"] = f_tot
    series = _series(ch, eta)
    ds = make_history(
        t, kin["z"], kin.get("zdot"), kin.get("zddot"), forces, dof=dofs, mass=mass,
        source=f"openfast:{ch.path.name}",
        inputs={"file": str(ch.path), "description": ch.description,
                "channels": {**used, **force_used}},
        check=False,
        extra_vars={k: v[0] for k, v in series.items()},
        extra_coords={v[1][0]: v[1][1] for v in series.values()},
    )
    _describe_forces(ds, force_used)
    if time_note:
        ds.attrs["time_regridded"] = time_note
    ds = finalize_import(ds, resample_to_uniform=resample, require_uniform=require_uniform)
    for role, channels in missing.items():
        ds = _estimate(ds, role, f"{', '.join(channels)} not in the file", notes)
    if notes:
        ds.attrs["notes"] = "; ".join(notes)
        for note in notes:
            warnings.warn(f"{ch.path.name}: {note}", UserWarning, stacklevel=2)
    return ds
