"""Importers of third-party force/motion files into a TimeHistory (:mod:`hybridwsi.history`).

Formats (names used by :func:`detect_format`, :func:`read_any` and ``hybridwsi import
--format``):

``netcdf``
    A TimeHistory written by :func:`hybridwsi.history.to_netcdf`.
``csv``
    Any delimited text table, read by :func:`hybridwsi.history.read_csv`.
``kramer``
    Kramer et al. (2021) floating-sphere heave decay, measured mean of 4 repetitions with its
    95 % confidence band (``*_CI95_Normalized_every5th.csv``): :func:`read_kramer_decay`.
``kramer-numerical``
    The blind-comparison results of the same paper (``numerical/<CODE>_<DROP>.csv``, columns
    ``t_s,x3_m``): :func:`read_kramer_numerical`.
``dualsphysics-info``
    DualSPHysics floating-body motion/force CSV (``FloatingInfo`` tool or ``FloatingMotion``
    output; ``;``-separated, ``time [s];fvel.z [m/s];center.z [m];heave [m];face.z [m/s^2];
    fluidforcelin.z [N]...``): :func:`read_dualsphysics_floatinginfo`.
``dualsphysics-ace``
    DualSPHysics ``FloatingAce_mkbound_XX.csv`` (``nstep;time [s];dt [s];predictor;acelin.x
    [m/s^2];...``): :func:`read_dualsphysics_floatingace`.

All readers return SI units, validate the result (:func:`hybridwsi.history.validate`) and treat
irregular sampling the same way: rejected with a clear message unless ``resample=True``
(cubic interpolation onto the median step, recorded in ``attrs["resampled"]``) or
``require_uniform=False`` (the history is returned as sampled, for inspection or plotting; the
diagnostic needs uniform sampling).
"""

from __future__ import annotations

import inspect
import os
import re
import warnings
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.history import (
    NETCDF_MAGIC,
    TextTable,
    finalize_import,
    make_history,
    read_csv,
    read_netcdf,
    set_mass,
    split_header,
)

#: Kramer et al. (2021): sphere diameter [m] and undamped natural period Te0 [s] (README)
KRAMER_DIAMETER = 0.300
KRAMER_TE0 = 0.7561
KRAMER_MASS = 7.056
_KRAMER_DIRNAME = "kramer2021_sphere_decay"


# --------------------------------------------------------------------------------------------
# Kramer et al. (2021) sphere decay
# --------------------------------------------------------------------------------------------


def kramer_data_dir() -> Path:
    """Folder holding the Kramer et al. (2021) decay data.

    Looked up in order: the environment variable ``HYBRIDWSI_KRAMER_DIR``; the shared copy
    ``../shared/data/kramer2021_sphere_decay`` next to the repository root; the copy packaged in
    ``hybridwsi/data/kramer2021_sphere_decay`` (always installed with the package).
    """
    env = os.environ.get("HYBRIDWSI_KRAMER_DIR")
    if env:
        path = Path(env)
        if not path.is_dir():
            raise InputError(f"HYBRIDWSI_KRAMER_DIR={env} is not a folder")
        return path
    repo_root = Path(__file__).resolve().parents[2]  # src/hybridwsi/importers.py -> repo
    shared = repo_root.parent / "shared" / "data" / _KRAMER_DIRNAME
    if shared.is_dir():
        return shared
    packaged = Path(str(resources.files("hybridwsi") / "data" / _KRAMER_DIRNAME))
    if packaged.is_dir():
        return packaged
    raise InputError(  # pragma: no cover - the packaged copy ships with hybridwsi
        "Kramer 2021 data not found: set HYBRIDWSI_KRAMER_DIR to the folder holding "
        "01D_CI95_Normalized_every5th.csv"
    )


def _kramer_drop_height(path: Path, drop_height: float | None) -> float:
    """Drop height [m]: given, or from the ``01D``/``03D``/``05D`` tag in the file name."""
    if drop_height is not None:
        if not np.isfinite(drop_height) or drop_height <= 0:
            raise InputError(f"drop height must be a positive length in m, got {drop_height}")
        return float(drop_height)
    m = re.search(r"(?<![0-9])0?([0-9])D(?![a-zA-Z])", path.stem)
    if not m:
        raise InputError(
            f"cannot tell the drop height from the name {path.name} (expected 01D/03D/05D); "
            "pass drop_height (--drop-height) in m"
        )
    return int(m.group(1)) / 10 * KRAMER_DIAMETER


def read_kramer_decay(
    path: str | os.PathLike,
    drop_height: float | None = None,
    te0: float = KRAMER_TE0,
    *,
    mass: float | None = KRAMER_MASS,
) -> xr.Dataset:
    """Measured heave decay of Kramer et al. (2021) as a TimeHistory.

    Parameters
    ----------
    path : path-like
        ``01D_CI95_Normalized_every5th.csv`` (or 03D/05D), columns ``t_over_Te0,
        x3_over_H0m_mean, ci95_lower, ci95_upper[, t_s_derived]``.
    drop_height : float, optional
        Drop height H0 [m] that un-normalises x3; default from the file name: 01D -> 0.1 D =
        0.03 m, 03D -> 0.09 m, 05D -> 0.15 m (D = 0.300 m).
    te0 : float
        Natural period Te0 [s] that un-normalises time (0.7561 s, see the data README).
    mass : float, optional
        Sphere mass [kg] stored in the history (7.056 kg); None to leave it out.

    Returns
    -------
    xarray.Dataset
        ``time`` = t/Te0 x te0 [s] (t = 0 at release; the held phase t < 0 is kept),
        ``z`` = x3/H0 x drop_height [m], and ``ci95_lower``/``ci95_upper`` [m] as extra
        ``(time, dof)`` variables. No velocity, acceleration or force is measured.
    """
    table = TextTable(path)
    h0 = _kramer_drop_height(table.path, drop_height)
    if not np.isfinite(te0) or te0 <= 0:
        raise InputError(f"te0 must be a positive period in s, got {te0}")
    t = table.numeric(table.require("t_over_Te0")) * te0
    table.check_time(t)
    z = table.numeric(table.require("x3_over_H0m_mean")) * h0
    ds = make_history(
        t, z, dof=["Heave"], mass=mass, source=f"kramer2021:{table.path.name}",
        inputs={"file": str(table.path), "drop_height_m": h0, "te0_s": te0},
        check=False,
    )
    for name in ("ci95_lower", "ci95_upper"):
        col = table.find(name)
        if col is not None:
            ds[name] = (("time", "dof"), table.numeric(col)[:, None] * h0,
                        {"units": "m", "description": "95 % confidence bound of the mean z"})
    ds["z"].attrs["description"] = "heave from equilibrium, positive up (mean of 4 repetitions)"
    ds.attrs["reference"] = "Kramer et al. (2021), Energies 14(2):269, doi:10.3390/en14020269"
    return finalize_import(ds)


def read_kramer_numerical(
    path: str | os.PathLike,
    *,
    resample: bool = False,
    require_uniform: bool = True,
    mass: float | None = KRAMER_MASS,
) -> xr.Dataset:
    """One of the blind-comparison results of Kramer et al. (2021) as a TimeHistory.

    Parameters
    ----------
    path : path-like
        ``numerical/<CODE>_<DROP>.csv`` with columns ``t_s,x3_m`` (time [s], heave [m]).
    resample : bool
        Several codes (LPF1-3, the RANS ones) were saved with an adaptive step, so their kept
        rows are only approximately 0.01 s apart. ``resample=True`` interpolates them (cubic)
        onto the median step.
    require_uniform : bool
        With False, an irregular file is returned as sampled (for plotting/comparison).
        Otherwise (the default) an irregular file raises :class:`InputError`, because the
        diagnostic's derivative estimation needs a uniform step.
    mass : float, optional
        Sphere mass [kg] stored in the history (7.056 kg); None to leave it out.
    """
    table = TextTable(path)
    t = table.numeric(table.require("t_s"), "time")
    table.check_time(t)
    z = table.numeric(table.require("x3_m"), "length")
    code = table.path.stem
    ds = make_history(
        t, z, dof=["Heave"], mass=mass, source=f"kramer2021-numerical:{code}",
        inputs={"file": str(table.path), "code": code.split("_")[0]}, check=False,
    )
    ds["z"].attrs["description"] = "heave x3 from equilibrium as computed by the code"
    return finalize_import(ds, resample_to_uniform=resample, require_uniform=require_uniform)


# --------------------------------------------------------------------------------------------
# DualSPHysics
# --------------------------------------------------------------------------------------------

# Column aliases, compared after :func:`_key` (lower case, no unit, no spaces/underscores).
_DSPH_TIME = ("time", "t")
_DSPH_Z = ("heave", "center.z", "fcenter.z", "centre.z", "pos.z")
_DSPH_ZDOT = ("fvel.z", "vel.z", "velz", "linvel.z", "fvellin.z")
_DSPH_ZDDOT = ("face.z", "acelin.z", "fvelace.z", "ace.z", "acez", "linace.z")
_DSPH_FORCE = ("fluidforcelin.z", "fluidforce.z", "ffluid.z", "fluidf.z", "forcelin.z", "force.z")
_DSPH_MK = ("mkbound", "mk")


def _key(header: str) -> str:
    base, _ = split_header(header)
    return re.sub(r"[\s_]", "", base.lower())


def _find_alias(table: TextTable, aliases: tuple[str, ...]) -> str | None:
    keys = {_key(c): c for c in table.columns}
    return next((keys[a.replace("_", "")] for a in aliases if a.replace("_", "") in keys), None)


def _si(table: TextTable, col: str, quantity: str, rows: np.ndarray) -> np.ndarray:
    return table.numeric(col, quantity)[rows]


def _select_mkbound(table: TextTable, mkbound: int | None) -> np.ndarray:
    """Row indices of the requested floating body (all rows when the file holds one)."""
    rows = np.arange(table.n_rows)
    col = _find_alias(table, _DSPH_MK)
    if col is None:
        tag = re.search(r"mk(?:bound)?_?(\d+)", table.path.stem, re.IGNORECASE)
        if mkbound is not None and tag and int(tag.group(1)) != mkbound:
            raise InputError(f"{table.path.name} holds mkbound {tag.group(1)}, not {mkbound}")
        return rows
    mk = table.numeric(col).astype(int)
    present = sorted(set(mk.tolist()))
    if mkbound is None:
        if len(present) > 1:
            raise InputError(
                f"{table.path.name} holds several floating bodies (mkbound {present}); "
                "choose one with mkbound (--mkbound)"
            )
        return rows
    if mkbound not in present:
        raise InputError(f"{table.path.name} has no mkbound {mkbound} (has {present})")
    return rows[mk == mkbound]


def read_dualsphysics_floatinginfo(
    path: str | os.PathLike,
    mkbound: int | None = None,
    mass: float | None = None,
    *,
    resample: bool = False,
    require_uniform: bool = True,
) -> xr.Dataset:
    """Heave motion and fluid force of a DualSPHysics floating body.

    Parameters
    ----------
    path : path-like
        CSV written by DualSPHysics' ``FloatingInfo`` tool (``-savemotion``) or its
        ``FloatingMotion``/``FloatingInfo`` output: ``;`` (or ``,``) separated, units in
        brackets, trailing separators allowed. Recognised heave columns (any case, units
        converted): time ``time [s]``; ``z`` from ``heave [m]`` (displacement from the initial
        position) or else ``center.z [m]`` minus its first value; ``zdot`` from ``fvel.z
        [m/s]``; ``zddot`` from ``face.z [m/s^2]`` (or ``acelin.z``); the fluid force from
        ``fluidforcelin.z [N]`` (or ``fluidforce.z``). Only time and a z column are required.
    mkbound : int, optional
        Body to keep when the file has an ``mkbound`` column with several bodies.
    mass : float, optional
        Body mass [kg]. When given (and ``face.z`` is present) ``F_tot = m zddot`` is added, the
        total force consistent with the motion (paper Eq. 2). ``F_fluid`` is the fluid force
        alone (pressure + viscous, including buoyancy but not gravity).
    resample, require_uniform : bool
        See the module docstring (DualSPHysics saves at the first step after each output
        instant, so its times are slightly irregular).
    """
    table = TextTable(path)
    rows = _select_mkbound(table, mkbound)
    tcol = _find_alias(table, _DSPH_TIME)
    zcol = _find_alias(table, _DSPH_Z)
    if tcol is None or zcol is None:
        missing = "time" if tcol is None else "heave or center.z"
        raise InputError(
            f"{table.path.name}: no {missing} column for a DualSPHysics floating body; "
            f"available columns: {', '.join(table.columns)}"
        )
    t = _si(table, tcol, "time", rows)
    _check_time_rows(table, t, rows)
    z = _si(table, zcol, "length", rows)
    z_note = f"from '{zcol}'"
    if _key(zcol) != "heave":
        z, z_note = z - z[0], f"'{zcol}' minus its initial value"
    vcol, acol, fcol = (_find_alias(table, a) for a in (_DSPH_ZDOT, _DSPH_ZDDOT, _DSPH_FORCE))
    zdot = _si(table, vcol, "velocity", rows) if vcol else None
    zddot = _si(table, acol, "acceleration", rows) if acol else None
    forces = {"F_fluid": _si(table, fcol, "force", rows)} if fcol else {}
    if mass is not None and zddot is not None:
        forces["F_tot"] = float(mass) * zddot
    ds = make_history(
        t, z, zdot, zddot, forces, dof=["Heave"], mass=mass,
        source=f"dualsphysics-floatinginfo:{table.path.name}",
        inputs={"file": str(table.path), "mkbound": mkbound,
                "columns": {"time": tcol, "z": zcol, "zdot": vcol, "zddot": acol, "F_fluid": fcol}},
        check=False,
    )
    ds["z"].attrs["description"] = f"heave displacement [m], {z_note}"
    if "F_fluid" in ds:
        ds["F_fluid"].attrs["description"] = f"fluid force from '{fcol}' (no gravity)"
    if "F_tot" in ds:
        ds["F_tot"].attrs["description"] = "mass x zddot (total force, paper Eq. 2)"
    return finalize_import(ds, resample_to_uniform=resample, require_uniform=require_uniform)


def read_dualsphysics_floatingace(
    path: str | os.PathLike,
    mass: float | None = None,
    *,
    resample: bool = False,
    require_uniform: bool = True,
) -> xr.Dataset:
    """Heave acceleration (and ``F_tot = m zddot``) from DualSPHysics ``FloatingAce`` output.

    The file (``FloatingAce_mkbound_XX.csv``, header ``nstep;time [s];dt [s];predictor;
    acelin.x [m/s^2];acelin.y [m/s^2];acelin.z [m/s^2];aceang.x [rad/s^2];...``) is written
    at irregular solver steps. Rows whose ``predictor`` flag is true (``True``/``1``) are the
    predictor half of a predictor-corrector step and are dropped.

    The file holds no displacement or velocity: the history has no ``z``/``zdot`` (this is
    stated in ``attrs["missing"]`` and in a :class:`UserWarning`); merge it with the
    ``FloatingInfo`` motion of the same run before running the diagnostic.
    """
    table = TextTable(path)
    tcol = _find_alias(table, _DSPH_TIME)
    acol = _find_alias(table, _DSPH_ZDDOT)
    if tcol is None or acol is None:
        missing = "time" if tcol is None else "acelin.z"
        raise InputError(
            f"{table.path.name}: no {missing} column for DualSPHysics FloatingAce; available "
            f"columns: {', '.join(table.columns)}"
        )
    rows = np.arange(table.n_rows)
    pcol = _find_alias(table, ("predictor",))
    n_pred = 0
    if pcol is not None:
        flags = [str(c).strip().lower() for c in table.cells[pcol]]
        unknown = sorted({f for f in flags if f not in ("true", "false", "1", "0")})
        if unknown:
            raise InputError(f"{table.path.name}: predictor flag '{unknown[0]}' is not True/False")
        corrector = np.array([f in ("false", "0") for f in flags])
        n_pred = int((~corrector).sum())
        rows = rows[corrector]
    t = _si(table, tcol, "time", rows)
    _check_time_rows(table, t, rows)
    zddot = _si(table, acol, "acceleration", rows)
    forces = {"F_tot": float(mass) * zddot} if mass is not None else {}
    missing = "z and zdot (FloatingAce files hold accelerations only)"
    ds = make_history(
        t, None, None, zddot, forces, dof=["Heave"], mass=mass,
        source=f"dualsphysics-floatingace:{table.path.name}",
        inputs={"file": str(table.path), "predictor_rows_dropped": n_pred,
                "columns": {"time": tcol, "zddot": acol}},
        check=False,
    )
    ds.attrs["missing"] = missing
    if "F_tot" in ds:
        ds["F_tot"].attrs["description"] = "mass x zddot (total force, paper Eq. 2)"
    warnings.warn(f"{table.path.name}: no displacement: the history lacks {missing}", UserWarning,
                  stacklevel=2)
    return finalize_import(ds, resample_to_uniform=resample, require_uniform=require_uniform,
                           require_z=False)


def _check_time_rows(table: TextTable, t: np.ndarray, rows: np.ndarray) -> None:
    """:meth:`TextTable.check_time` on a subset of rows, with the right line numbers."""
    full = table.line_numbers
    table.line_numbers = full[rows]
    try:
        table.check_time(t)
    finally:
        table.line_numbers = full


# --------------------------------------------------------------------------------------------
# Detection and dispatch
# --------------------------------------------------------------------------------------------

FORMATS = ("csv", "netcdf", "kramer", "kramer-numerical", "dualsphysics-info", "dualsphysics-ace")


def detect_format(path: str | os.PathLike) -> str:
    """Name of the file's format (one of :data:`FORMATS`), from its content.

    NetCDF is recognised by its magic bytes; text tables by their header: ``acelin.z`` with
    ``predictor``/``nstep`` -> ``dualsphysics-ace``; DualSPHysics floating columns (``fvel.*``,
    ``center.*``, ``face.*``, ``fluidforcelin.*``) -> ``dualsphysics-info``;
    ``x3_over_H0m_mean`` -> ``kramer``; exactly ``t_s,x3_m`` -> ``kramer-numerical``; any
    other text table -> ``csv``. Missing, empty or binary files raise :class:`InputError`.
    """
    path = Path(path)
    if path.is_file():
        with open(path, "rb") as f:
            if f.read(8).startswith(NETCDF_MAGIC):
                return "netcdf"
    if path.suffix.lower() in (".nc", ".nc4", ".netcdf", ".cdf"):
        if not path.is_file():
            raise InputError(f"file not found: {path}")
        return "netcdf"
    table = TextTable(path)  # raises on missing/empty/binary
    keys = {_key(c) for c in table.columns}
    if "acelin.z" in keys and keys & {"predictor", "nstep"}:
        return "dualsphysics-ace"
    if any(k.split(".")[0] in ("fvel", "center", "fcenter", "face", "fluidforcelin") for k in keys):
        return "dualsphysics-info"
    if "x3overh0mmean" in keys:
        return "kramer"
    if keys == {"ts", "x3m"}:
        return "kramer-numerical"
    return "csv"


_READERS: dict[str, Callable[..., xr.Dataset]] = {
    "csv": read_csv,
    "kramer": read_kramer_decay,
    "kramer-numerical": read_kramer_numerical,
    "dualsphysics-info": read_dualsphysics_floatinginfo,
    "dualsphysics-ace": read_dualsphysics_floatingace,
}


def read_any(
    path: str | os.PathLike,
    *,
    format: str = "auto",
    mass: float | None = None,
    resample: bool = False,
    **options: Any,
) -> xr.Dataset:
    """Implementation of :func:`hybridwsi.history.read_history` (see there)."""
    fmt = detect_format(path) if format == "auto" else format
    if fmt not in FORMATS:
        raise InputError(f"unknown format '{format}' (choose auto, {', '.join(FORMATS)})")
    options = {k: v for k, v in options.items() if v is not None}
    if fmt == "netcdf":
        if options:
            raise InputError(f"option(s) {', '.join(options)} do not apply to NetCDF files")
        ds = read_netcdf(path)
        ds = finalize_import(ds, resample_to_uniform=resample, require_z="zddot" not in ds)
    else:
        reader = _READERS[fmt]
        params = inspect.signature(reader).parameters
        bad = [k for k in options if k not in params]
        if bad:
            raise InputError(
                f"option(s) {', '.join(bad)} do not apply to {fmt} files "
                f"(it takes: {', '.join(p for p in params if p not in ('path', 'mass', 'resample'))})"
            )
        if "resample" in params:
            options["resample"] = resample
        if "mass" in params and mass is not None:
            options["mass"] = mass
        ds = reader(path, **options)
        if resample and "resample" not in params:
            ds = finalize_import(ds, resample_to_uniform=True, require_z="z" in ds)
    if mass is not None:
        ds = set_mass(ds, mass)
    ds.attrs["format"] = fmt
    return ds


__all__ = [
    "FORMATS",
    "KRAMER_DIAMETER",
    "KRAMER_MASS",
    "KRAMER_TE0",
    "detect_format",
    "kramer_data_dir",
    "read_any",
    "read_dualsphysics_floatingace",
    "read_dualsphysics_floatinginfo",
    "read_kramer_decay",
    "read_kramer_numerical",
]
