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
    extra_vars: Mapping[str, tuple] | None = None,
    extra_coords: Mapping[str, Any] | None = None,
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
    extra_vars, extra_coords : mapping, optional
        Further variables ``{name: (dims, values, attrs)}`` and their coordinates, e.g. the
        wave elevation ``eta(time, probe)`` [m]; stored as given.

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
    coords: dict[str, Any] = {"time": ("time", t, {"units": "s"}), "dof": dof}
    if "mass" in data_vars:
        coords["dof_j"] = dof  # at construction: a later assign_coords costs a second merge
    data_vars.update(extra_vars or {})
    coords.update(extra_coords or {})
    ds = xr.Dataset(
        data_vars,
        coords=coords,
        attrs={
            "hybridwsi_version": _version(),
            "source": source,
            "inputs": json.dumps(dict(inputs or {}), default=str, sort_keys=True),
        },
    )
    return validate(ds) if check else ds


def force_names(ds: xr.Dataset) -> list[str]:
    """Names of the force-component variables of a TimeHistory."""
    # ds.variables: no DataArray per variable (validation runs on every simulated history)
    return [k for k in ds.data_vars if ds.variables[k].attrs.get("role") == "force"]


def mass_matrix(ds: xr.Dataset) -> np.ndarray | None:
    """Rigid-body mass matrix [kg] of a history, or None when it does not carry one."""
    return None if "mass" not in ds else np.asarray(ds["mass"].values, dtype=float)


def validate(
    ds: xr.Dataset,
    *,
    min_samples: int = 8,
    require_uniform: bool = True,
    require_z: bool = True,
) -> xr.Dataset:
    """Check a TimeHistory and return it unchanged, or raise :class:`InputError`.

    Checks: ``time`` present, finite, strictly increasing (no duplicates), uniform within
    ``UNIFORM_RTOL`` (unless ``require_uniform=False``), at least ``min_samples`` samples;
    ``z`` present (unless ``require_z=False``, for acceleration-only imports); every kinematic
    and force variable finite (no NaN/inf) and shaped ``(time, dof)``.
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
    if require_z and "z" not in ds:
        raise InputError("history has no displacement variable 'z'")
    for name in [*KINEMATICS, *force_names(ds)]:
        if name not in ds:
            continue
        var = ds.variables[name]
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


# --------------------------------------------------------------------------------------------
# Derivative estimation
# --------------------------------------------------------------------------------------------

#: cumulative share of the displacement power that defines the signal band (the rest is noise)
SIGNAL_POWER_SHARE = 0.999


def _signal_band(z: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Welch spectrum of ``z`` inside its signal band.

    Returns the angular frequencies [rad/s] and the power per bin [m^2] of the band holding
    ``SIGNAL_POWER_SHARE`` of the (linearly detrended) power, and the dominant period [s].
    """
    from scipy.signal import welch

    f, p = welch(z, fs=1.0 / dt, nperseg=min(z.size, 1024), detrend="linear")
    f, p = f[1:], p[1:] * (f[1] - f[0])  # drop the mean; PSD -> power per bin
    if p.sum() <= 0:
        raise InputError("z is constant: its derivatives cannot be estimated")
    k = int(np.searchsorted(np.cumsum(p), SIGNAL_POWER_SHARE * p.sum())) + 1
    return 2 * np.pi * f[:k], p[:k], float(1.0 / f[int(np.argmax(p))])


def _noise_std(z: np.ndarray) -> float:
    """Robust white-noise level [m]: MAD of the 4th difference (variance 70 sigma^2)."""
    d4 = np.diff(z, 4)
    return float(1.4826 * np.median(np.abs(d4 - np.median(d4))) / np.sqrt(70.0))


def savgol_window(z: np.ndarray, dt: float, polyorder: int = 3, deriv: int = 2) -> int:
    """Savitzky–Golay window length [samples] that balances truncation error and noise.

    For each odd window up to one dominant period, the predicted mean-square error of the
    ``deriv``-th derivative is the filter's exact frequency-response error summed over the
    signal band of ``z`` (Welch spectrum), plus the white-noise level (from the 4th difference
    of ``z``) times the squared norm of the filter coefficients. The window with the smallest
    predicted error is returned. Clean, finely sampled data thus get short windows; noisy data
    get longer ones, never more than a dominant period.
    """
    from scipy.signal import savgol_coeffs

    omega, power, period = _signal_band(z, dt)
    sigma2 = _noise_std(z) ** 2
    w_min = polyorder + 1 + (polyorder % 2)  # smallest odd window > polyorder
    w_max = min(z.size - (1 - z.size % 2), max(w_min, int(period / dt) | 1))
    best, best_err = w_min, np.inf
    for w in range(w_min, w_max + 1, 2):
        c = savgol_coeffs(w, polyorder, deriv=deriv, delta=dt, use="dot")
        lag = (np.arange(w) - w // 2) * dt
        if deriv == 1:
            resp = np.sin(np.outer(omega, lag)) @ c / omega
        else:
            resp = np.cos(np.outer(omega, lag)) @ c / -(omega**2)
        err = np.sum(power * omega ** (2 * deriv) * (resp - 1.0) ** 2) + sigma2 * np.sum(c**2)
        if err < best_err:
            best, best_err = w, err
    return best


def _savgol(z: np.ndarray, dt: float, deriv: int, window: int | None, polyorder: int):
    from scipy.signal import savgol_filter

    w = savgol_window(z, dt, polyorder, deriv) if window is None else int(window)
    if w % 2 == 0 or w <= polyorder or w > z.size:
        raise InputError(
            f"Savitzky-Golay window must be odd, > polyorder ({polyorder}) and <= the number "
            f"of samples ({z.size}); got {w}"
        )
    est = savgol_filter(z, w, polyorder, deriv=deriv, delta=dt, mode="interp")
    return est, f"savgol(window={w}, polyorder={polyorder}, deriv={deriv}, dt={dt:.6g})"


def estimate_derivatives(
    ds: xr.Dataset,
    method: str = "savgol",
    window: int | None = None,
    polyorder: int = 3,
    overwrite: bool = False,
    lam: float | None = None,
) -> xr.Dataset:
    """Fill missing ``zdot`` [m/s] and ``zddot`` [m/s^2] from ``z`` [m].

    Parameters
    ----------
    ds : xarray.Dataset
        A uniformly sampled TimeHistory with ``z``.
    method : {"savgol", "spline"}
        ``"savgol"``: :func:`scipy.signal.savgol_filter` with ``deriv=1/2`` and ``delta=dt``
        (local least-squares polynomial of degree ``polyorder``; at the ends the polynomial of
        the first/last window is differentiated). When ``window`` is None it is chosen per
        derivative and per DOF by :func:`savgol_window` from ``dt``, the spectrum of ``z``
        (dominant period and signal band) and its noise level.
        ``"spline"``: :func:`scipy.interpolate.make_smoothing_spline` (cubic smoothing spline,
        smoothing ``lam`` chosen by generalised cross-validation when None), differentiated
        analytically. It is a natural spline, so ``zddot`` is biased towards 0 at both ends.
    window : int, optional
        Savitzky–Golay window length [samples], odd, > ``polyorder``.
    polyorder : int
        Savitzky–Golay polynomial degree. With a symmetric window an odd degree ``p`` gives
        the same interior second derivative as ``p - 1``.
    overwrite : bool
        Re-estimate variables that are already present.
    lam : float, optional
        Smoothing parameter of ``method="spline"``.

    Returns
    -------
    xarray.Dataset
        A copy with the estimated variables added; each carries ``attrs["estimated"]``
        describing the method (e.g. ``"savgol(window=9, polyorder=3, deriv=2, dt=0.01)"``).
    """
    if method not in ("savgol", "spline"):
        raise InputError(f"unknown derivative method '{method}' (choose savgol or spline)")
    validate(ds)
    targets = [(name, d) for name, d in (("zdot", 1), ("zddot", 2)) if overwrite or name not in ds]
    if not targets:
        return ds
    dt = time_step(ds)
    t = np.asarray(ds["time"].values, dtype=float)
    z = np.asarray(ds["z"].values, dtype=float)
    out = ds.copy()
    for name, deriv in targets:
        cols, notes = [], []
        for j in range(z.shape[1]):
            if method == "savgol":
                est, note = _savgol(z[:, j], dt, deriv, window, polyorder)
            else:
                est, note = _spline(t, z[:, j], deriv, lam)
            cols.append(est)
            notes.append(note)
        desc = notes[0] if len(set(notes)) == 1 else "; ".join(
            f"{d}: {n}" for d, n in zip(ds["dof"].values, notes)
        )
        out[name] = (("time", "dof"), np.column_stack(cols), {"units": UNITS[name], "estimated": desc})
    return out


def _spline(t: np.ndarray, z: np.ndarray, deriv: int, lam: float | None):
    from scipy.interpolate import make_smoothing_spline

    try:
        spl = make_smoothing_spline(t, z, lam=lam)
    except ValueError as exc:
        raise InputError(f"smoothing spline failed: {exc}") from None
    return spl.derivative(deriv)(t), f"smoothing_spline(lam={'GCV' if lam is None else lam}, deriv={deriv})"


# --------------------------------------------------------------------------------------------
# Resampling
# --------------------------------------------------------------------------------------------

_INTERPOLATORS = ("cubic", "linear", "pchip", "akima")


def resample(ds: xr.Dataset, dt: float | None = None, method: str = "cubic") -> xr.Dataset:
    """Interpolate an irregularly sampled history onto a uniform grid.

    Parameters
    ----------
    ds : xarray.Dataset
        History with strictly increasing (possibly irregular) ``time`` [s].
    dt : float, optional
        New time step [s]; default the median of the original steps.
    method : {"cubic", "linear", "pchip", "akima"}
        :class:`scipy.interpolate.CubicSpline` (not-a-knot), :func:`numpy.interp`,
        :class:`~scipy.interpolate.PchipInterpolator` or
        :class:`~scipy.interpolate.Akima1DInterpolator`.

    Returns
    -------
    xarray.Dataset
        Every variable along ``time`` interpolated on ``t0 + k dt`` (k = 0, 1, ... up to the
        last original time); ``attrs["resampled"]`` records the method and the original grid.
    """
    from scipy import interpolate

    if method not in _INTERPOLATORS:
        raise InputError(f"unknown resampling method '{method}' (choose {', '.join(_INTERPOLATORS)})")
    validate(ds, require_uniform=False, require_z=False)
    t = np.asarray(ds["time"].values, dtype=float)
    steps = np.diff(t)
    dt = float(np.median(steps)) if dt is None else float(dt)
    if not np.isfinite(dt) or dt <= 0:
        raise InputError(f"resampling step must be a positive number of seconds, got {dt}")
    n_new = int(np.floor((t[-1] - t[0]) / dt * (1 + 1e-12))) + 1
    t_new = t[0] + dt * np.arange(n_new)

    def interp(y: np.ndarray) -> np.ndarray:
        if method == "linear":
            return np.apply_along_axis(lambda c: np.interp(t_new, t, c), 0, y)
        cls = {"cubic": interpolate.CubicSpline, "pchip": interpolate.PchipInterpolator,
               "akima": interpolate.Akima1DInterpolator}[method]
        return cls(t, y, axis=0)(t_new)

    data_vars = {}
    for name, var in ds.data_vars.items():
        if "time" not in var.dims:
            data_vars[name] = var
            continue
        moved = var.transpose("time", ...)
        values = interp(np.asarray(moved.values, dtype=float))
        data_vars[name] = (moved.dims, values, dict(var.attrs))
    coords = {k: v for k, v in ds.coords.items() if "time" not in v.dims}
    coords["time"] = ("time", t_new, dict(ds["time"].attrs))
    out = xr.Dataset(data_vars, coords=coords, attrs=dict(ds.attrs))
    out.attrs["resampled"] = (
        f"{method}(dt={dt:.6g}) from {t.size} samples with dt {steps.min():.6g}..{steps.max():.6g} s"
    )
    return out


def is_uniform(ds: xr.Dataset) -> bool:
    """Whether the time step varies by less than ``UNIFORM_RTOL`` (relative)."""
    steps = np.diff(np.asarray(ds["time"].values, dtype=float))
    return bool(steps.size and (steps.max() - steps.min()) <= UNIFORM_RTOL * np.median(steps))


def finalize_import(
    ds: xr.Dataset,
    *,
    resample_to_uniform: bool = False,
    require_uniform: bool = True,
    require_z: bool = True,
) -> xr.Dataset:
    """Validate a freshly imported history; resample it first when asked and irregular.

    Used by every ``read_*`` function so that irregular sampling is handled the same way:
    rejected with a clear message unless ``resample_to_uniform`` (or ``require_uniform=False``).
    """
    validate(ds, require_uniform=False, require_z=require_z)
    if resample_to_uniform and not is_uniform(ds):
        ds = resample(ds)
    return validate(ds, require_uniform=require_uniform, require_z=require_z)


# --------------------------------------------------------------------------------------------
# Text tables (CSV, semicolon, whitespace) with units in the headers
# --------------------------------------------------------------------------------------------

#: quantity -> accepted unit spellings (lower case) -> factor to SI
UNIT_FACTORS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "sec": 1.0, "ms": 1e-3},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3},
    "velocity": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3},
    "acceleration": {"m/s^2": 1.0, "m/s2": 1.0, "m/s**2": 1.0, "m/s²": 1.0, "mm/s^2": 1e-3,
                     "mm/s2": 1e-3},
    "force": {"n": 1.0, "kn": 1e3},
    "angle": {"rad": 1.0, "deg": np.pi / 180},
    "angular_velocity": {"rad/s": 1.0, "deg/s": np.pi / 180},
    "angular_acceleration": {"rad/s^2": 1.0, "rad/s2": 1.0, "deg/s^2": np.pi / 180,
                             "deg/s2": np.pi / 180},
    "moment": {"nm": 1.0, "n m": 1.0, "n.m": 1.0, "n*m": 1.0, "knm": 1e3},
}
_ROTATIONS = {"roll", "pitch", "yaw"}


def quantity_of(role: str, dof: str = "Heave") -> str:
    """Physical quantity of a TimeHistory role (``time``, ``z``, ``zdot``, ``zddot``, ``force``)."""
    rot = dof.lower() in _ROTATIONS
    return {
        "time": "time",
        "z": "angle" if rot else "length",
        "zdot": "angular_velocity" if rot else "velocity",
        "zddot": "angular_acceleration" if rot else "acceleration",
        "force": "moment" if rot else "force",
    }[role]


def split_header(header: str) -> tuple[str, str | None]:
    """``"time [s]"`` -> ``("time", "s")``; also ``"z (mm)"``; no unit -> ``(header, None)``."""
    import re

    m = re.match(r"^\s*(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]\s*$", header)
    return (m.group(1), m.group(2)) if m else (header.strip(), None)


def unit_factor(unit: str | None, quantity: str, column: str) -> float:
    """Factor converting ``unit`` to SI for ``quantity``; no unit means SI already."""
    if unit is None or unit == "":
        return 1.0
    table = UNIT_FACTORS[quantity]
    key = unit.strip().lower()
    if key not in table:
        raise InputError(
            f"column '{column}' has unit '{unit}', not a {quantity.replace('_', ' ')} unit "
            f"hybridwsi knows (accepted: {', '.join(table)})"
        )
    return table[key]


class TextTable:
    """A delimited text table read as strings, with file line numbers for error messages.

    Attributes
    ----------
    path : Path
    columns : list of str
        Header cells as written (e.g. ``"time [s]"``); empty trailing columns removed.
    meta : dict
        ``key: value`` pairs from ``# key: value`` comment lines before the header.
    sep : str
        The separator used (``","``, ``";"``, ``"\\t"`` or ``"whitespace"``).
    """

    def __init__(self, path: str | os.PathLike, sep: str | None = None) -> None:
        self.path = Path(path)
        text = read_text_file(self.path)
        self._lines = text.splitlines()
        self.meta: dict[str, str] = {}
        header_idx = None
        for i, line in enumerate(self._lines):
            s = line.strip()
            if not s:
                continue
            if s.startswith("#"):
                key, colon, value = s.lstrip("#").partition(":")
                if colon and header_idx is None:
                    self.meta[key.strip()] = value.strip()
                continue
            header_idx = i
            break
        if header_idx is None:
            raise InputError(f"{self.path.name}: no header line and no data (only comments)")
        self.sep = sep or detect_separator(self._lines[header_idx])
        self._header_idx = header_idx
        self.columns, self.cells, self.line_numbers = self._parse(header_idx)

    def _split(self, line: str) -> list[str]:
        line = line.split("#", 1)[0]
        if self.sep == "whitespace":
            return line.split()
        return [c.strip() for c in line.split(self.sep)]

    def _parse(self, header_idx: int):
        header = self._split(self._lines[header_idx])
        rows, linenos = [], []
        for i in range(header_idx + 1, len(self._lines)):
            s = self._lines[i].strip()
            if not s or s.startswith("#"):
                continue
            rows.append(self._split(self._lines[i]))
            linenos.append(i + 1)
        # trailing separators (DualSPHysics writes "a;b;") give empty header cells: drop them
        keep = [j for j, h in enumerate(header) if h != ""]
        width = len(header)
        for row, ln in zip(rows, linenos):
            if any(c != "" for c in row[width:]):
                raise InputError(
                    f"{self.path.name}: line {ln} has {len(row)} fields but the header has "
                    f"{len(keep)} columns (mismatched lengths)"
                )
        for j in range(width):
            if j not in keep and any(len(r) > j and r[j] != "" for r in rows):
                raise InputError(f"{self.path.name}: column {j + 1} has data but no header name")
        columns = [header[j] for j in keep]
        if len(set(columns)) != len(columns):
            dup = next(c for c in columns if columns.count(c) > 1)
            raise InputError(f"{self.path.name}: column name '{dup}' appears twice in the header")
        cells: dict[str, list[str | None]] = {c: [] for c in columns}
        for row in rows:
            for j, c in zip(keep, columns):
                cells[c].append(row[j] if j < len(row) else None)  # None: row too short
        return columns, cells, np.asarray(linenos, dtype=int)

    @property
    def n_rows(self) -> int:
        return int(self.line_numbers.size)

    def find(self, name: str) -> str | None:
        """Column whose full header or unit-less name matches ``name`` (case-insensitive)."""
        want = name.strip().lower()
        for c in self.columns:
            if c.lower() == want:
                return c
        for c in self.columns:
            if split_header(c)[0].lower() == want:
                return c
        return None

    def require(self, name: str, what: str = "column") -> str:
        col = self.find(name)
        if col is None:
            raise InputError(
                f"{what} '{name}' not found in {self.path.name}; available columns: "
                f"{', '.join(self.columns)}"
            )
        return col

    def numeric(self, column: str, quantity: str | None = None, scale: float = 1.0) -> np.ndarray:
        """Column as floats in SI (unit from the header), or a one-line InputError."""
        raw = self.cells[column]
        try:
            factor = 1.0 if quantity is None else unit_factor(split_header(column)[1], quantity, column)
        except InputError as exc:
            raise InputError(f"{self.path.name}: {exc}") from None
        try:  # fast path: every cell a finite number
            out = np.asarray(raw, dtype=float)
            if np.all(np.isfinite(out)):
                return out * factor * scale
        except (TypeError, ValueError):
            out = np.empty(len(raw))
        width = len(self.columns)
        for i, cell in enumerate(raw):
            ln = self.line_numbers[i]
            if cell is None:
                raise InputError(
                    f"{self.path.name}: line {ln} has fewer fields than the header's {width} "
                    f"columns (mismatched lengths; '{column}' is missing)"
                )
            try:
                out[i] = float(cell)
            except ValueError:
                if cell == "":
                    raise InputError(
                        f"{self.path.name}: empty cell in column '{column}' at line {ln}"
                    ) from None
                raise InputError(
                    f"{self.path.name}: non-numeric value '{cell[:30]}' in column '{column}' "
                    f"at line {ln}"
                ) from None
            if not np.isfinite(out[i]):
                what = "NaN" if np.isnan(out[i]) else "infinite"
                raise InputError(
                    f"{self.path.name}: {what} value '{cell}' in column '{column}' at line {ln}"
                )
        return out * factor * scale

    def is_numeric(self, column: str) -> bool:
        """Whether at least one cell of the column parses as a number."""
        for cell in self.cells[column]:
            try:
                float(cell)  # type: ignore[arg-type]
                return True
            except (TypeError, ValueError):
                continue
        return False

    def check_time(self, t: np.ndarray, min_samples: int = 8) -> None:
        """Sorted, no duplicates, enough samples; messages give file line numbers."""
        name = self.path.name
        if t.size < min_samples:
            raise InputError(f"{name}: {t.size} data rows; at least {min_samples} are needed")
        steps = np.diff(t)
        if np.any(steps == 0):
            i = int(np.flatnonzero(steps == 0)[0]) + 1
            raise InputError(
                f"{name}: time {t[i]:.6g} s is duplicated at line {self.line_numbers[i]}"
            )
        if np.any(steps < 0):
            i = int(np.flatnonzero(steps < 0)[0]) + 1
            raise InputError(
                f"{name}: time is not sorted: line {self.line_numbers[i]} (t = {t[i]:.6g} s) "
                f"comes after line {self.line_numbers[i - 1]} (t = {t[i - 1]:.6g} s)"
            )


def detect_separator(header_line: str) -> str:
    """``";"``, ``","``, ``"\\t"`` or ``"whitespace"``, from the header line."""
    for sep in (";", ",", "\t"):
        if sep in header_line:
            return sep
    return "whitespace"


#: first bytes of NetCDF classic/64-bit and NetCDF-4 (HDF5) files
NETCDF_MAGIC = (b"CDF\x01", b"CDF\x02", b"CDF\x05", b"\x89HDF\r\n\x1a\n")


def read_text_file(path: Path) -> str:
    """The file's text, or a one-line InputError (missing, empty, binary, undecodable)."""
    if not path.exists():
        raise InputError(f"file not found: {path}")
    if not path.is_file():
        raise InputError(f"not a regular file: {path}")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror or exc}") from None
    if not data.strip():
        raise InputError(f"{path.name} is empty")
    if data.startswith(NETCDF_MAGIC):
        raise InputError(f"{path.name} is a NetCDF file, not a text table (use read_history)")
    if b"\x00" in data[:65536]:
        raise InputError(f"{path.name} is a binary file, not a CSV/text table")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        try:
            text = data.decode("latin-1")
        except UnicodeDecodeError:  # pragma: no cover - latin-1 decodes every byte
            raise InputError(f"{path.name} is not a text file") from None
        # binary garbage decodes as latin-1 too: insist on mostly printable text
        printable = sum(ch.isprintable() or ch in "\r\n\t" for ch in text[:4096])
        if printable < 0.95 * min(len(text), 4096):
            raise InputError(f"{path.name} is a binary file, not a CSV/text table") from None
        return text


# --------------------------------------------------------------------------------------------
# CSV read/write and the format-dispatching reader
# --------------------------------------------------------------------------------------------


def read_csv(
    path: str | os.PathLike,
    *,
    time: str = "time",
    z: str | None = "z",
    zdot: str | None = None,
    zddot: str | None = None,
    forces: Sequence[str] | Mapping[str, str] | str | None = None,
    sep: str | None = None,
    dof: str = "Heave",
    mass: float | None = None,
    resample: bool = False,
) -> xr.Dataset:
    """Read a one-DOF TimeHistory from a delimited text file.

    Parameters
    ----------
    path : path-like
        Text table: one header line, ``#`` comments (anywhere; ``# key: value`` lines before
        the header are read as metadata, e.g. ``# mass [kg]: 7.06`` as written by
        :func:`to_csv`), separator ``,``/``;``/tab/whitespace (auto-detected from the header
        unless ``sep`` is given; trailing separators are tolerated).
    time, z, zdot, zddot : str
        Column names, matched case-insensitively against the full header cell or its unit-less
        name (``"time"`` matches ``"time [s]"``). ``zdot``/``zddot`` default to columns named
        ``zdot``/``zddot`` when present, else they are left out (see
        :func:`estimate_derivatives`).
    forces : str, sequence of str or mapping {variable: column}, optional
        Force columns [N]. None: every other numeric column whose unit is a force unit or absent
        becomes a force component named after its unit-less header; columns with other known
        units (m, m/s, ...) are kept as extra ``(time, dof)`` variables; wholly non-numeric
        columns are skipped.
    sep : str, optional
        Separator override (``","``, ``";"``, ``"\\t"`` or ``"whitespace"``).
    dof : str
        Name of the degree of freedom (``"Heave"``; rotations take angle units).
    mass : float, optional
        Rigid-body mass [kg] (else the ``# mass [kg]:`` metadata line, if any).
    resample : bool
        Interpolate irregular sampling onto a uniform grid (:func:`resample`, cubic) instead
        of rejecting it.

    Units in headers (``[unit]`` or ``(unit)``) are converted to SI: time s/ms, length m/cm/mm,
    force N/kN, ...; an unknown unit raises :class:`InputError`.
    """
    table = TextTable(path, sep)
    name = table.path.name
    cols: dict[str, str] = {"time": table.require(time, "time column")}
    if z is not None:
        cols["z"] = table.require(z, "displacement column")
    for role, given in (("zdot", zdot), ("zddot", zddot)):
        if given is not None:
            cols[role] = table.require(given, f"{role} column")
        elif table.find(role) is not None:
            cols[role] = table.find(role)  # type: ignore[assignment]
    t = table.numeric(cols["time"], "time")
    table.check_time(t)
    kin = {r: table.numeric(c, quantity_of(r, dof)) for r, c in cols.items() if r != "time"}
    force_cols, extra_cols = _force_columns(table, forces, set(cols.values()))
    force_data = {v: table.numeric(c, quantity_of("force", dof)) for v, c in force_cols.items()}
    if mass is None and "mass [kg]" in table.meta:
        mass = _meta_float(table, "mass [kg]")
    ds = make_history(
        t, kin.get("z"), kin.get("zdot"), kin.get("zddot"), force_data, dof=[dof], mass=mass,
        source=table.meta.get("source", f"csv:{name}"),
        inputs={"file": str(table.path), "columns": {**cols, **force_cols}, "sep": table.sep},
        check=False,
    )
    for var, col in extra_cols.items():
        unit = split_header(col)[1]
        ds[var] = (("time", "dof"), table.numeric(col)[:, None], {"units": unit or ""})
    for role in ("zdot", "zddot"):
        note = table.meta.get(f"estimated.{role}")
        if note and role in ds:
            ds[role].attrs["estimated"] = note
    return finalize_import(ds, resample_to_uniform=resample, require_z=z is not None)


def _meta_float(table: TextTable, key: str) -> float:
    try:
        return float(table.meta[key])
    except ValueError:
        raise InputError(f"{table.path.name}: metadata '{key}' is not a number") from None


def _force_columns(
    table: TextTable, forces: Sequence[str] | Mapping[str, str] | str | None, used: set[str]
) -> tuple[dict[str, str], dict[str, str]]:
    """``({variable: column} of forces, {variable: column} of extra variables)``."""
    if forces is not None:
        if isinstance(forces, str):
            forces = [forces]
        mapping = dict(forces) if isinstance(forces, Mapping) else {f: f for f in forces}
        return {_var_name(v): table.require(c, "force column") for v, c in mapping.items()}, {}
    out: dict[str, str] = {}
    extra: dict[str, str] = {}
    for col in table.columns:
        if col in used or not table.is_numeric(col):
            continue
        base, unit = split_header(col)
        if unit is None or unit.strip().lower() in UNIT_FACTORS["force"]:
            out[_var_name(base)] = col
        else:
            extra[_var_name(base)] = col
    return out, extra


def _var_name(name: str) -> str:
    """A NetCDF-safe variable name (``/`` is not allowed)."""
    return name.strip().replace("/", "_") or "unnamed"


def to_csv(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write a one-DOF TimeHistory as CSV atomically (read back by :func:`read_csv`).

    The header line carries units (``time [s],z [m],...``); ``#`` lines before it carry the
    version, source, DOF, mass, inputs and estimation notes. Values are written with 17
    significant digits so that a round trip is exact.
    """
    if ds.sizes.get("dof", 1) != 1:
        raise InputError("CSV export holds one DOF; write multi-DOF histories with to_netcdf")
    names = [n for n in ds.data_vars if ds[n].dims == ("time", "dof")]
    t = np.asarray(ds["time"].values, dtype=float)
    header = ["time [s]"] + [f"{n} [{ds[n].attrs.get('units', '')}]".replace(" []", "") for n in names]
    meta = [
        "hybridwsi TimeHistory",
        f"hybridwsi_version: {_version()}",
        f"source: {ds.attrs.get('source', 'unknown')}",
        f"dof: {ds['dof'].values[0]}",
    ]
    if "mass" in ds:
        meta.append(f"mass [kg]: {float(np.asarray(ds['mass'].values).ravel()[0])!r}")
    for n in ("zdot", "zddot"):
        if n in ds and "estimated" in ds[n].attrs:
            meta.append(f"estimated.{n}: {ds[n].attrs['estimated']}")
    meta.append(f"inputs: {ds.attrs.get('inputs', '{}')}")
    data = np.column_stack([t] + [np.asarray(ds[n].values, dtype=float)[:, 0] for n in names])

    def writer(tmp: str) -> None:
        with open(tmp, "w", encoding="utf-8") as f:
            f.writelines(f"# {line}\n" for line in meta)
            f.write(",".join(header) + "\n")
            np.savetxt(f, data, delimiter=",", fmt="%.17g")

    return atomic_write(path, writer)


def read_history(
    path: str | os.PathLike,
    *,
    format: str = "auto",
    mass: float | None = None,
    resample: bool = False,
    **mapping: Any,
) -> xr.Dataset:
    """Read a TimeHistory from any supported file.

    Parameters
    ----------
    path : path-like
        NetCDF (written by :func:`to_netcdf`), plain CSV/text (:func:`read_csv`), DualSPHysics
        ``FloatingInfo``/``FloatingAce`` CSV, Kramer et al. (2021) measured or numerical decay
        files (:mod:`hybridwsi.importers`).
    format : str
        ``"auto"`` (detected from the content by :func:`hybridwsi.importers.detect_format`) or
        one of :data:`hybridwsi.importers.FORMATS`.
    mass : float, optional
        Rigid-body mass [kg]; replaces the file's one when given.
    resample : bool
        Resample irregular sampling onto a uniform grid instead of rejecting it.
    **mapping
        Options of the chosen reader (e.g. ``time=``, ``z=``, ``forces=`` for CSV,
        ``drop_height=`` for Kramer files, ``mkbound=`` for DualSPHysics); None values are
        ignored, an option the reader does not take raises :class:`InputError`.
    """
    from hybridwsi import importers

    return importers.read_any(path, format=format, mass=mass, resample=resample, **mapping)


def set_mass(ds: xr.Dataset, mass: float | np.ndarray) -> xr.Dataset:
    """Return ``ds`` with its rigid-body mass [kg] set (scalar or (n_dof, n_dof) matrix)."""
    nd = ds.sizes["dof"]
    try:
        m = np.atleast_2d(np.asarray(mass, dtype=float))
    except (TypeError, ValueError):
        raise InputError(f"mass must be a number, got {mass!r}") from None
    if m.shape == (1, 1):
        m = np.eye(nd) * m[0, 0]
    if m.shape != (nd, nd) or not np.all(np.isfinite(m)) or np.any(np.diag(m) <= 0):
        raise InputError(f"mass must be a positive scalar or a ({nd}, {nd}) matrix, got {mass!r}")
    out = ds.drop_vars([v for v in ("mass",) if v in ds])
    out = out.assign_coords(dof_j=list(ds["dof"].values))
    out["mass"] = (("dof", "dof_j"), m, {"units": "kg"})
    return out
