"""TimeHistory: the one labelled type that carries force/motion histories through the pipeline.

A TimeHistory is an :class:`xarray.Dataset` with

- coordinate ``time`` [s], strictly increasing and uniformly sampled;
- coordinate ``dof`` (str), degree-of-freedom names as in Capytaine (``"Heave"``, ``"Surge"``,
  ``"Pitch"``...); a 1-DOF history has ``dof = ["Heave"]``;
- variables ``z`` [m], ``zdot`` [m/s], ``zddot`` [m/s^2] with dims ``(time, dof)`` (rotations in
  rad, rad/s, rad/s^2);
- any number of force components with dims ``(time, dof)`` [N] (moments [N m]), each with
  ``attrs["role"] == "force"``; ``F_tot`` by convention is the total fluid + external force so
  that ``m zddot = F_tot`` (paper Eq. 2);
- optional ``mass`` with dims ``(dof, dof_j)`` [kg] (the rigid-body mass matrix);
- optional other variables (e.g. wave elevation ``eta(time, probe)`` [m]);
- ``attrs``: ``hybridwsi_version``, ``source`` (what made it), ``inputs`` (JSON of the inputs)
  and, for every kinematic variable that was estimated rather than given,
  ``attrs["estimated"]`` on that variable describing the method.

Use :func:`make_history` to build one and :func:`validate` to check one that came from
elsewhere. Readers and writers for CSV/NetCDF live in this module too.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError

KINEMATICS = ("z", "zdot", "zddot")
UNITS = {"z": "m", "zdot": "m/s", "zddot": "m/s^2", "time": "s"}
DEFAULT_DOF = ("Heave",)
#: relative spread of the time step tolerated before a history is called irregular
UNIFORM_RTOL = 1e-3


def _version() -> str:
    from hybridwsi import __version__

    return __version__


def _as_2d(name: str, values: Any, n_time: int, n_dof: int) -> np.ndarray:
    """Coerce a 1-D (1 DOF) or 2-D ``(time, dof)`` array-like, with clear errors."""
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"'{name}' is not numeric: {exc}") from None
    if arr.ndim == 1 and n_dof == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape != (n_time, n_dof):
        raise InputError(
            f"'{name}' has shape {arr.shape}; expected ({n_time},) or ({n_time}, {n_dof}) "
            f"to match time ({n_time} samples) and dof {n_dof}"
        )
    return arr


def make_history(
    time: Sequence[float] | np.ndarray,
    z: Any,
    zdot: Any | None = None,
    zddot: Any | None = None,
    forces: Mapping[str, Any] | None = None,
    *,
    dof: Sequence[str] = DEFAULT_DOF,
    mass: float | np.ndarray | None = None,
    source: str = "user",
    inputs: Mapping[str, Any] | None = None,
    check: bool = True,
) -> xr.Dataset:
    """Build a TimeHistory.

    Parameters
    ----------
    time : array_like, shape (n,)
        Sample times [s], strictly increasing and uniform.
    z, zdot, zddot : array_like, shape (n,) or (n, n_dof)
        Displacement [m], velocity [m/s] and acceleration [m/s^2]. ``zdot``/``zddot`` may be
        None; use :func:`estimate_derivatives` to fill them from ``z``.
    forces : mapping of str to array_like, optional
        Force components [N], e.g. ``{"F_tot": ..., "F_hs": ...}``.
    dof : sequence of str
        Degree-of-freedom names (Capytaine's spelling, e.g. ``"Heave"``).
    mass : float or array, optional
        Rigid-body mass [kg] (scalar for 1 DOF) or mass matrix (n_dof, n_dof).
    source : str
        What produced the history (stored in attrs).
    inputs : mapping, optional
        Inputs that produced it, stored as JSON in attrs for reproducibility.
    check : bool
        Run :func:`validate` on the result.

    Returns
    -------
    xarray.Dataset
    """
    t = np.asarray(time, dtype=float)
    if t.ndim != 1:
        raise InputError(f"time must be one-dimensional, got shape {t.shape}")
    dof = list(dof)
    n, nd = t.size, len(dof)
    data_vars: dict[str, Any] = {}
    for name, values in (("z", z), ("zdot", zdot), ("zddot", zddot)):
        if values is None:
            continue
        data_vars[name] = (("time", "dof"), _as_2d(name, values, n, nd), {"units": UNITS[name]})
    for name, values in (forces or {}).items():
        data_vars[name] = (
            ("time", "dof"),
            _as_2d(name, values, n, nd),
            {"units": "N", "role": "force"},
        )
    if mass is not None:
        m = np.atleast_2d(np.asarray(mass, dtype=float))
        if m.shape == (1, 1) and nd > 1:
            m = np.eye(nd) * m[0, 0]
        if m.shape != (nd, nd):
            raise InputError(f"mass must be a scalar or a ({nd}, {nd}) matrix, got {m.shape}")
        data_vars["mass"] = (("dof", "dof_j"), m, {"units": "kg"})
    ds = xr.Dataset(
        data_vars,
        coords={"time": ("time", t, {"units": "s"}), "dof": dof},
        attrs={
            "hybridwsi_version": _version(),
            "source": source,
            "inputs": json.dumps(dict(inputs or {}), default=str, sort_keys=True),
        },
    )
    if "mass" in ds:
        ds = ds.assign_coords(dof_j=dof)
    return validate(ds) if check else ds


def force_names(ds: xr.Dataset) -> list[str]:
    """Names of the force-component variables of a TimeHistory."""
    return [k for k, v in ds.data_vars.items() if v.attrs.get("role") == "force"]


def mass_matrix(ds: xr.Dataset) -> np.ndarray | None:
    """Rigid-body mass matrix [kg] of a history, or None when it does not carry one."""
    return None if "mass" not in ds else np.asarray(ds["mass"].values, dtype=float)


def validate(ds: xr.Dataset, *, min_samples: int = 8, require_uniform: bool = True) -> xr.Dataset:
    """Check a TimeHistory and return it unchanged, or raise :class:`InputError`.

    Checks: ``time`` present, finite, strictly increasing (no duplicates), uniform within
    ``UNIFORM_RTOL`` (unless ``require_uniform=False``), at least ``min_samples`` samples;
    ``z`` present; every kinematic and force variable finite (no NaN/inf) and shaped
    ``(time, dof)``.
    """
    if not isinstance(ds, xr.Dataset):
        raise InputError(f"expected an xarray.Dataset TimeHistory, got {type(ds).__name__}")
    if "time" not in ds.coords:
        raise InputError("history has no 'time' coordinate")
    t = np.asarray(ds["time"].values, dtype=float)
    if t.size < min_samples:
        raise InputError(f"history has {t.size} samples; at least {min_samples} are needed")
    if not np.all(np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise InputError(f"time has a non-finite value at row {i}")
    dt = np.diff(t)
    if np.any(dt == 0):
        i = int(np.flatnonzero(dt == 0)[0])
        raise InputError(f"time is duplicated at row {i + 1} (t = {t[i]:.6g} s)")
    if np.any(dt < 0):
        i = int(np.flatnonzero(dt < 0)[0])
        raise InputError(
            f"time is not sorted: row {i + 1} (t = {t[i + 1]:.6g} s) comes before "
            f"row {i} (t = {t[i]:.6g} s)"
        )
    if require_uniform:
        spread = (dt.max() - dt.min()) / np.median(dt)
        if spread > UNIFORM_RTOL:
            raise InputError(
                f"time is irregularly sampled (dt from {dt.min():.6g} to {dt.max():.6g} s); "
                "resample it first (hybridwsi.history.resample) or pass --resample"
            )
    if "dof" not in ds.dims:
        raise InputError("history has no 'dof' dimension")
    if "z" not in ds:
        raise InputError("history has no displacement variable 'z'")
    for name in [*KINEMATICS, *force_names(ds)]:
        if name not in ds:
            continue
        var = ds[name]
        if var.dims != ("time", "dof"):
            raise InputError(f"'{name}' has dims {var.dims}; expected ('time', 'dof')")
        bad = ~np.isfinite(var.values)
        if bad.any():
            i = int(np.flatnonzero(bad.any(axis=1))[0])
            raise InputError(
                f"'{name}' has {int(bad.sum())} NaN/inf value(s), first at row {i} "
                f"(t = {t[i]:.6g} s)"
            )
    return ds


def time_step(ds: xr.Dataset) -> float:
    """Mean sampling interval [s] of a (uniform) history."""
    t = np.asarray(ds["time"].values, dtype=float)
    return float((t[-1] - t[0]) / (t.size - 1))


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
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return path


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
        raise InputError(f"cannot read {path} as NetCDF: {exc}") from None
    for name in [n for n in ds.data_vars if str(n).endswith("__re")]:
        base = str(name)[: -len("__re")]
        if base + "__im" in ds:
            ds[base] = (ds[name] + 1j * ds[base + "__im"]).assign_attrs(ds[name].attrs)
            ds = ds.drop_vars([name, base + "__im"])
    return ds
