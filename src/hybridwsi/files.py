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
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError

#: first bytes of NetCDF classic/64-bit and NetCDF-4 (HDF5) files
NETCDF_MAGIC = (b"CDF\x01", b"CDF\x02", b"CDF\x05", b"\x89HDF\r\n\x1a\n")


def cache_dir(kind: str) -> Path:
    """The cache folder of ``kind`` ("bem", "moordyn", "radiation_ss"):
    ``$HYBRIDWSI_CACHE/<kind>`` if that variable is set, else ``~/.cache/hybridwsi/<kind>``."""
    root = os.environ.get("HYBRIDWSI_CACHE")
    return (Path(root).expanduser() if root else Path.home() / ".cache" / "hybridwsi") / kind


def _atomic_target(path: str | os.PathLike) -> tuple[Path, str]:
    """The file to replace and a temporary file beside it. A symbolic link is written
    through: its target is replaced (in the target's folder), the link stays a link."""
    path = Path(path)
    if path.is_symlink():
        path = Path(os.path.realpath(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    return path, tmp


def atomic_write(path: str | os.PathLike, writer) -> Path:
    """Call ``writer(tmp_path)`` then rename the temporary file onto ``path``.

    A crash or Ctrl-C while writing never leaves a half-written ``path`` behind. When
    ``path`` is a symbolic link, the file it points to is written (the link is kept).
    Returns ``path`` as given.
    """
    given = Path(path)
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
    return given


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


#: folder of the files shipped with the package (coefficients, force tables)
DATA = Path(__file__).resolve().parent / "data"


def data_path(name: str | os.PathLike, folder: Path | None = None, what: str = "file") -> Path:
    """Where a table named in a case lives: an absolute path, a path relative to ``folder``
    (the case file's), to the working directory, or the name of a file shipped in
    ``hybridwsi/data``; InputError naming ``what`` and the places looked at otherwise."""
    path = Path(name).expanduser()
    candidates = [path] if path.is_absolute() else (
        ([folder / path] if folder is not None else []) + [Path.cwd() / path, DATA / path])
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    raise InputError(f"{what} not found: {name} (looked for "
                     f"{', '.join(str(c) for c in candidates)})")


def _nearest_existing(path: Path) -> Path:
    """``path`` itself or its closest ancestor that exists (the folder a write would create from)."""
    for candidate in (path, *path.parents):
        if os.path.lexists(candidate):
            return candidate
    return Path(path.anchor or ".")


def _same_file(a: Path, b: str | os.PathLike) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:  # either side missing, a dangling link or a loop: not the same existing file
        return Path(os.path.abspath(a)) == Path(os.path.abspath(b))


def check_output_path(
    out: str | os.PathLike,
    inputs: Sequence[str | os.PathLike | None] = (),
    *,
    kind: str = "file",
    products: Sequence[str] = (),
) -> Path:
    """Refuse an output path before any work is done; return it as a Path.

    Refused: an output that is one of ``inputs`` (the same file after resolving links,
    :func:`os.path.samefile`); an existing path that is not a regular file (``kind="file"``:
    a device such as /dev/full, a folder, a dangling link or a symlink loop) or not a folder
    (``kind="dir"``); a path below an existing non-folder; a parent folder that is not
    writable. With ``kind="dir"``, ``products`` are the file names the command writes inside
    the folder; each is checked the same way (e.g. a history named ``report.json`` in it).

    Parameters
    ----------
    out : path-like
        The output file or folder.
    inputs : sequence of path-like or None
        Files the command reads (None entries are skipped).
    kind : {"file", "dir"}
        What ``out`` must be.
    products : sequence of str
        With ``kind="dir"``: names of the files written inside ``out``.

    Raises
    ------
    InputError
        With a one-line message naming the option value and what is wrong.
    """
    if kind not in ("file", "dir"):
        raise ValueError(f"kind must be 'file' or 'dir', got {kind!r}")
    path = Path(out).expanduser()
    if str(out) == "":
        raise InputError("the output path is empty")
    given = [p for p in inputs if p is not None]
    targets = [path] if kind == "file" else [path / name for name in products]
    for target in targets:
        for src in given:
            if _same_file(target, src):
                raise InputError(f"output {target} is the input {src}: choose another output path "
                                 "(an input is never overwritten)")
        if kind == "dir" and os.path.lexists(target) and not target.is_file():
            raise InputError(f"output {target} exists and is not a regular file")
    if os.path.lexists(path):
        if kind == "file" and not path.is_file():
            what = "a folder" if path.is_dir() else "not a regular file"
            raise InputError(f"output {path} exists and is {what}: give a file path")
        if kind == "dir" and not path.is_dir():
            raise InputError(f"output {path} exists and is not a folder: give a folder path")
    base = _nearest_existing(path.parent if kind == "file" or not path.is_dir() else path)
    if not base.is_dir():
        raise InputError(f"cannot write {path}: {base} is not a folder")
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(f"cannot write {path}: folder {base} is not writable")
    return path
