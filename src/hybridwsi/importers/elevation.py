"""A wave-elevation record η(t) from a file: the input of ``simulate --wave-elevation``.

Three kinds of file, told apart by their content:

- a text table (CSV, ``;``, tab or whitespace separated): a ``time`` column [s, or the unit
  in its header] and the elevation column, ``eta`` by default [m, or the length unit in its
  header, e.g. ``eta [mm]``];
- NetCDF: a variable ``eta`` (or the one named) with dimension ``time`` and at most one other
  dimension (the probe; the first probe, or the probe named by ``column``), ``units``
  attributes honoured (a TimeHistory written by ``hybridwsi simulate`` is one);
- OpenFAST output (``.out``/``.outb``): the channel ``Wave1Elev`` by default.

The time must be sorted and uniform (resample it first otherwise), the values finite.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from hybridwsi.errors import InputError
from hybridwsi.files import read_netcdf
from hybridwsi.history import NETCDF_MAGIC, TextTable, split_header, unit_factor
from hybridwsi.importers.openfast import is_openfast_output, read_channels

#: the elevation column or variable looked for when none is named
DEFAULT_COLUMN = "eta"
#: the OpenFAST channel looked for when none is named
OPENFAST_CHANNEL = "Wave1Elev"


def _from_table(path: Path, column: str | None) -> tuple[np.ndarray, np.ndarray, str]:
    table = TextTable(path)
    t = table.numeric(table.require("time", "time column"), "time")
    table.check_time(t)
    col = table.require(column or DEFAULT_COLUMN, "wave-elevation column")
    return t, table.numeric(col, "length"), col


def _from_netcdf(path: Path, column: str | None) -> tuple[np.ndarray, np.ndarray, str]:
    ds = read_netcdf(path)
    name = column if column is not None and column in ds.variables else DEFAULT_COLUMN
    if name not in ds.variables:
        raise InputError(f"{path.name}: no wave-elevation variable '{column or name}' "
                         f"(variables: {', '.join(map(str, ds.data_vars)) or 'none'})")
    var = ds[name]
    if "time" not in var.dims or var.ndim > 2:
        raise InputError(f"{path.name}: '{name}' must have dimension time and at most one "
                         f"probe dimension, has {var.dims}")
    if var.ndim == 2:
        probe = next(d for d in var.dims if d != "time")
        labels = [str(p) for p in ds[probe].values] if probe in ds.coords else []
        pick = labels.index(column) if column in labels else 0
        var = var.isel({probe: pick}).transpose("time")
    t = np.asarray(ds["time"].values, dtype=float)
    t = t * unit_factor(ds["time"].attrs.get("units"), "time", "time")
    return t, np.asarray(var.values, dtype=float) * unit_factor(
        var.attrs.get("units"), "length", name), name


def _from_openfast(path: Path, column: str | None) -> tuple[np.ndarray, np.ndarray, str]:
    ch = read_channels(path)
    name = column or OPENFAST_CHANNEL
    found = ch.find([name])
    if found is None:
        raise InputError(f"{path.name}: no wave-elevation channel '{name}'")
    return ch.si(0, 1.0, "time"), ch.si(*found, "length"), ch.names[found[0]]


def read_elevation(path: str | os.PathLike, column: str | None = None
                   ) -> tuple[np.ndarray, np.ndarray, str]:
    """``(time [s], eta [m], description)`` of a wave-elevation record (module docstring).

    Raises :class:`InputError` (one line) for a missing file or column, a unit that is not a
    length, NaN/inf, unsorted, repeated or irregular time, or fewer than 8 samples.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"wave-elevation file not found: {path}")
    with open(path, "rb") as f:
        netcdf = f.read(8).startswith(NETCDF_MAGIC)
    reader = (_from_netcdf if netcdf else _from_openfast if is_openfast_output(path)
              else _from_table)
    t, eta, name = reader(path, column)
    if t.size < 8:
        raise InputError(f"{path.name}: {t.size} samples; a wave-elevation record needs >= 8")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(eta))):
        raise InputError(f"{path.name}: the wave elevation '{name}' holds NaN or inf")
    steps = np.diff(t)
    if np.any(steps <= 0):
        raise InputError(f"{path.name}: time is not strictly increasing")
    if np.ptp(steps) > 1e-6 * np.median(steps):
        raise InputError(f"{path.name}: time is not uniformly sampled (steps "
                         f"{steps.min():.6g}-{steps.max():.6g} s); resample the record first")
    return t, eta, f"{path.name}:{split_header(name)[0]}"
