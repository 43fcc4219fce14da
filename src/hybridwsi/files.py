"""Atomic file writers and the NetCDF round trip of TimeHistories and coefficient Datasets.

Every result file is written to a temporary file in the target folder and renamed into place,
so a crash or Ctrl-C never leaves a half-written file. JSON is strict (numpy values converted,
inf/NaN written as null); complex variables are split into ``name__re``/``name__im`` for
NetCDF and joined again on reading.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError

#: first bytes of NetCDF classic/64-bit and NetCDF-4 (HDF5) files
NETCDF_MAGIC = (b"CDF\x01", b"CDF\x02", b"CDF\x05", b"\x89HDF\r\n\x1a\n")


def _atomic_target(path: str | os.PathLike) -> tuple[Path, str]:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    return path, tmp


def atomic_write(path: str | os.PathLike, writer) -> Path:
    """Call ``writer(tmp_path)`` then rename the temporary file onto ``path``.

    A crash or Ctrl-C while writing never leaves a half-written ``path`` behind.
    """
    path, tmp = _atomic_target(path)
    try:
        writer(tmp)
        # mkstemp creates 0600; give the result the permissions a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return path


def _jsonable(obj: Any) -> Any:
    """Plain-Python, strictly valid JSON values: numpy → lists/floats, inf/NaN → None."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    if obj is None or isinstance(obj, (str, int, float, bool)):
        return obj
    return str(obj)


def write_json(path: str | os.PathLike, obj: Any, *, indent: int = 2) -> Path:
    """Write ``obj`` as strict JSON (numpy values converted, inf/NaN as null), atomically."""
    text = json.dumps(_jsonable(obj), indent=indent, allow_nan=False) + "\n"
    try:
        return atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))
    except OSError as exc:
        raise InputError(f"cannot write {path}: {exc.strerror or exc}") from None


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write a text file atomically."""
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def to_netcdf(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write a Dataset (history or coefficients) to NetCDF atomically (complex values split)."""
    out = ds.copy()
    for name in list(out.data_vars):
        if np.iscomplexobj(out[name].values):
            attrs = dict(out[name].attrs)
            out[name + "__re"] = out[name].real.assign_attrs(attrs)
            out[name + "__im"] = out[name].imag.assign_attrs(attrs)
            out = out.drop_vars(name)
    return atomic_write(path, lambda tmp: out.to_netcdf(tmp))


def read_netcdf(path: str | os.PathLike) -> xr.Dataset:
    """Read a NetCDF written by :func:`to_netcdf` (complex values re-joined), fully loaded."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"file not found: {path}")
    try:
        with xr.open_dataset(path) as f:
            ds = f.load()
    except Exception as exc:  # netCDF4/h5py raise many types on corrupt files
        # netCDF4 reports a non-NetCDF file as "[Errno 22] Invalid argument": say what it means
        reason = getattr(exc, "strerror", None) or str(exc)
        raise InputError(
            f"cannot read {path} as NetCDF: not a NetCDF/HDF5 file or corrupt ({reason})"
        ) from None
    for name in [n for n in ds.data_vars if str(n).endswith("__re")]:
        base = str(name)[: -len("__re")]
        if base + "__im" in ds:
            ds[base] = (ds[name] + 1j * ds[base + "__im"]).assign_attrs(ds[name].attrs)
            ds = ds.drop_vars([name, base + "__im"])
    return ds
