"""Readers of third-party force/motion files into a TimeHistory (:mod:`hybridwsi.history`).

Formats (names used by :func:`detect_format`, :func:`read_history` and ``hybridwsi import
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
    [m/s^2];...``): :func:`read_dualsphysics_floatingace`
    (:mod:`~hybridwsi.importers.dualsphysics`).
``openfast``
    OpenFAST output, text ``.out`` or binary ``.outb`` (read with openfast-io, extra
    ``hybridwsi[openfast]``): platform DOFs, their rates and loads,
    :func:`read_openfast` (:mod:`~hybridwsi.importers.openfast`).

All readers return SI units, validate the result (:func:`hybridwsi.history.validate`) and treat
irregular sampling the same way: rejected with a clear message unless ``resample=True``
(cubic interpolation onto the median step, recorded in ``attrs["resampled"]``) or
``require_uniform=False`` (the history is returned as sampled, for inspection or plotting; the
diagnostic needs uniform sampling). The one exception is DualSPHysics output, whose times
jitter by a solver step by construction: it is resampled automatically when its steps stay
within :data:`~hybridwsi.importers.dualsphysics.OUTPUT_JITTER` of their median (and said so in
``attrs["resampled"]``); larger gaps are rejected like any other irregular file.
"""

from __future__ import annotations

import inspect
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.history import (KINEMATICS, NETCDF_MAGIC, TextTable, finalize_import, force_names,
                               read_csv, read_netcdf, set_mass)
from hybridwsi.importers.dualsphysics import (
    OUTPUT_JITTER,
    _key,
    read_dualsphysics_floatingace,
    read_dualsphysics_floatinginfo,
)
from hybridwsi.importers.elevation import read_elevation
from hybridwsi.importers.kramer import (
    KRAMER_DIAMETER,
    KRAMER_DROPS,
    KRAMER_MASS,
    KRAMER_TE0,
    kramer_data_dir,
    kramer_decay_file,
    kramer_drop_height,
    kramer_numerical_files,
    read_kramer_decay,
    read_kramer_drop,
    read_kramer_numerical,
)
from hybridwsi.importers.openfast import is_openfast_output, read_openfast

# --------------------------------------------------------------------------------------------
# Detection and dispatch
# --------------------------------------------------------------------------------------------

FORMATS = ("csv", "netcdf", "kramer", "kramer-numerical", "dualsphysics-info", "dualsphysics-ace",
           "openfast")
#: option names that mean the same thing to every reader (the CLI's --dofs and read_csv's dof)
_SYNONYMS = (("dof", "dofs"),)


def detect_format(path: str | os.PathLike) -> str:
    """Name of the file's format (one of :data:`FORMATS`), from its content.

    NetCDF is recognised by its magic bytes; OpenFAST output by its binary header (``.outb``)
    or its text header (:func:`~hybridwsi.importers.openfast.is_openfast_output`); text
    tables by their header: ``acelin.z`` with
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
    if is_openfast_output(path):
        return "openfast"
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
    "openfast": read_openfast,
}


def _require_units(ds, path) -> None:
    """A NetCDF history must say its units: a missing attribute would be read as SI silently."""
    names = ["time", *(k for k in KINEMATICS if k in ds.variables), *force_names(ds)]
    missing = [n for n in names if n in ds.variables and "units" not in ds.variables[n].attrs
               and "units_per_dof" not in ds.variables[n].attrs]
    if missing:
        raise InputError(f"{path}: variable(s) {', '.join(missing)} have no 'units' attribute; "
                         "add them (e.g. s, m, rad, N, N m) so that nothing is guessed")


def read_history(
    path: str | os.PathLike,
    *,
    format: str = "auto",
    mass: float | None = None,
    resample: bool = False,
    **options: Any,
) -> xr.Dataset:
    """Read a TimeHistory from any supported file (the one format dispatcher).

    Parameters
    ----------
    path : path-like
        NetCDF (written by :func:`hybridwsi.history.to_netcdf`), plain CSV/text
        (:func:`hybridwsi.history.read_csv`), DualSPHysics ``FloatingInfo``/``FloatingAce``
        CSV, Kramer et al. (2021) measured or numerical decay files, OpenFAST ``.out``/``.outb``.
    format : str
        ``"auto"`` (detected from the content by :func:`detect_format`) or one of
        :data:`FORMATS`.
    mass : float, optional
        Rigid-body mass [kg]; replaces the file's one when given.
    resample : bool
        Resample irregular sampling onto a uniform grid instead of rejecting it. False keeps
        the reader's own default (DualSPHysics files: resampled when their steps only jitter).
    **options
        Options of the chosen reader (e.g. ``time=``, ``z=``, ``forces=`` for CSV,
        ``drop_height=`` for Kramer files, ``mkbound=`` for DualSPHysics, ``dofs=`` for
        OpenFAST; ``dof`` and ``dofs`` are synonyms); None values are ignored, an option the
        reader does not take raises :class:`InputError`.

    Returns
    -------
    xarray.Dataset
        The validated TimeHistory, with ``attrs["format"]`` naming the format read.
    """
    fmt = detect_format(path) if format == "auto" else format
    if fmt not in FORMATS:
        raise InputError(f"unknown format '{format}' (choose auto, {', '.join(FORMATS)})")
    options = {k: v for k, v in options.items() if v is not None}
    if fmt == "netcdf":
        if options:
            raise InputError(f"option(s) {', '.join(options)} do not apply to NetCDF files")
        ds = read_netcdf(path)
        _require_units(ds, path)
        ds = finalize_import(ds, resample_to_uniform=resample, require_z="zddot" not in ds)
    else:
        reader = _READERS[fmt]
        params = inspect.signature(reader).parameters
        for a, b in (*_SYNONYMS, *((b, a) for a, b in _SYNONYMS)):
            if a in options and a not in params and b in params:
                options[b] = options.pop(a)
        bad = [k for k in options if k not in params]
        if bad:
            raise InputError(
                f"option(s) {', '.join(bad)} do not apply to {fmt} files "
                f"(it takes: {', '.join(p for p in params if p not in ('path', 'mass', 'resample'))})"
            )
        if "resample" in params and resample:
            options["resample"] = True  # else the reader's default (automatic for DualSPHysics)
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
    "KRAMER_DROPS",
    "KRAMER_MASS",
    "KRAMER_TE0",
    "OUTPUT_JITTER",
    "detect_format",
    "kramer_data_dir",
    "kramer_decay_file",
    "kramer_drop_height",
    "kramer_numerical_files",
    "read_dualsphysics_floatingace",
    "read_dualsphysics_floatinginfo",
    "read_elevation",
    "read_history",
    "read_kramer_decay",
    "read_kramer_drop",
    "read_kramer_numerical",
    "read_openfast",
]
