"""The TimeHistory data model: build, check and query one (no file I/O, no signal processing).

A TimeHistory is an :class:`xarray.Dataset` with

- coordinate ``time`` [s], strictly increasing and uniformly sampled;
- coordinate ``dof`` (str), degree-of-freedom names as in Capytaine (``"Heave"``, ``"Surge"``,
  ``"Pitch"``...); a 1-DOF history has ``dof = ["Heave"]``;
- variables ``z``, ``zdot``, ``zddot`` with dims ``(time, dof)``: m, m/s, m/s² for translations
  and rad, rad/s, rad/s² for rotations;
- any number of force components with dims ``(time, dof)``: N on translations, N m on
  rotations, each with ``attrs["role"] == "force"``; ``F_tot`` by convention is the total fluid
  + external force so that ``M zddot = F_tot`` (paper Eq. 2);
- optional ``mass`` with dims ``(dof, dof_j)`` (the rigid-body mass matrix: kg, kg m, kg m²);
- optional other variables (e.g. wave elevation ``eta(time, probe)`` [m]);
- ``attrs``: ``hybridwsi_version``, ``source`` (what made it), ``inputs`` (JSON of the inputs)
  and, for every kinematic variable that was estimated rather than given,
  ``attrs["estimated"]`` on that variable describing the method.

Units come from :mod:`hybridwsi.dofs`: every ``(time, dof)`` variable carries ``units`` (one
label, e.g. ``"m, rad"`` for Surge and Pitch) and ``units_per_dof`` (a JSON list in DOF order,
``["m", "rad"]``). See docs/DATA_MODEL.md.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi import dofs as _dofs
from hybridwsi._meta import version
from hybridwsi.errors import InputError
from hybridwsi.units import check_si
from hybridwsi.hydro.coefficients import pair_units_attr

KINEMATICS = ("z", "zdot", "zddot")
DEFAULT_DOF = ("Heave",)
#: relative spread of the time step tolerated before a history is called irregular
UNIFORM_RTOL = 1e-3


def units_attrs(quantity: str, dof: Sequence[str]) -> dict[str, str]:
    """``units`` and ``units_per_dof`` attributes of a ``(time, dof)`` variable.

    Parameters
    ----------
    quantity : str
        ``"z"``, ``"zdot"``, ``"zddot"`` or ``"force"``.
    dof : sequence of str
        The history's DOFs, in order.

    Returns
    -------
    dict
        ``{"units": "m, rad", "units_per_dof": '["m", "rad"]'}`` for a Surge–Pitch ``z``.
    """
    names = _dofs.check_dofs(list(dof))
    per = [_dofs.force_unit(d) if quantity == "force" else _dofs.motion_unit(d, quantity)
           for d in names]
    return {"units": _dofs.units_label(names, quantity), "units_per_dof": json.dumps(per)}


def units_per_dof(ds: xr.Dataset, name: str) -> list[str]:
    """Unit of variable ``name`` of a history per DOF (from ``units_per_dof``, else ``units``)."""
    attrs = ds[name].attrs
    if "units_per_dof" in attrs:
        return list(json.loads(attrs["units_per_dof"]))
    return [str(attrs.get("units", ""))] * ds.sizes["dof"]


def _mass_attrs(dof: Sequence[str]) -> dict[str, str]:
    return {"units": pair_units_attr("mass", list(dof))}


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


def _mass_matrix(mass: Any, nd: int) -> np.ndarray:
    """Scalar or (nd, nd) mass as a checked matrix (a scalar on every diagonal entry).

    Raises :class:`InputError` unless the mass is finite, positive on the diagonal and the
    matrix symmetric positive definite: a zero, negative or NaN mass has no physical meaning
    and would silently flip or blow up every acceleration it divides.
    """
    try:
        m = np.atleast_2d(np.asarray(mass, dtype=float))
    except (TypeError, ValueError):
        raise InputError(f"mass must be a number or a ({nd}, {nd}) matrix, got {mass!r}") from None
    m = np.eye(nd) * m[0, 0] if m.shape == (1, 1) else m
    check_mass(m, nd)
    return m


def check_mass(m: np.ndarray, nd: int) -> None:
    """Refuse a rigid-body mass matrix [kg, kg m, kg m²] that is not physical.

    Parameters
    ----------
    m : ndarray
        The matrix.
    nd : int
        Number of DOFs it must match.
    """
    if m.shape != (nd, nd):
        raise InputError(f"mass must be a scalar or a ({nd}, {nd}) matrix, got shape {m.shape}")
    shown = f"{m[0, 0]:g}" if nd == 1 else np.array2string(m, precision=4, separator=", ")
    shown = " ".join(shown.split())
    if not np.all(np.isfinite(m)):
        raise InputError(f"mass must be finite, got {shown}")
    if np.any(np.diag(m) <= 0):
        raise InputError(f"mass must be positive, got {shown} (a body needs a positive mass)")
    if not np.allclose(m, m.T, rtol=1e-9, atol=1e-12 * float(np.abs(m).max())):
        raise InputError(f"mass matrix must be symmetric, got {shown}")
    if nd > 1 and np.linalg.eigvalsh(m).min() <= 0:
        raise InputError(f"mass matrix must be positive definite, got {shown}")


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
        Displacement [m or rad per DOF], velocity [m/s or rad/s] and acceleration [m/s² or
        rad/s²]. ``zdot``/``zddot`` may be None; use
        :func:`hybridwsi.history.estimate_derivatives` to fill them from ``z``.
    forces : mapping of str to array_like, optional
        Force components [N on translations, N m on rotations], e.g.
        ``{"F_tot": ..., "F_hs": ...}``.
    dof : sequence of str
        Degree-of-freedom names (Capytaine's spelling, e.g. ``"Heave"``).
    mass : float or array, optional
        Rigid-body mass (scalar for 1 DOF [kg]) or mass matrix (n_dof, n_dof) [kg, kg m, kg m²].
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
        Units per DOF on every ``(time, dof)`` variable (``units``, ``units_per_dof``).
    """
    t = np.asarray(time, dtype=float)
    if t.ndim != 1:
        raise InputError(f"time must be one-dimensional, got shape {t.shape}")
    dof = list(_dofs.check_dofs(list(dof)))
    n, nd = t.size, len(dof)
    data_vars: dict[str, Any] = {}
    for name, values in (("z", z), ("zdot", zdot), ("zddot", zddot)):
        if values is None:
            continue
        data_vars[name] = (("time", "dof"), _as_2d(name, values, n, nd), units_attrs(name, dof))
    force_attrs = {**units_attrs("force", dof), "role": "force"} if forces else {}
    for name, values in (forces or {}).items():
        data_vars[name] = (("time", "dof"), _as_2d(name, values, n, nd), dict(force_attrs))
    if mass is not None:
        m = _mass_matrix(mass, nd)
        data_vars["mass"] = (("dof", "dof_j"), m, _mass_attrs(dof))
    coords: dict[str, Any] = {"time": ("time", t, {"units": "s"}), "dof": dof}
    if "mass" in data_vars:
        coords["dof_j"] = dof  # at construction: a later assign_coords costs a second merge
    data_vars.update(extra_vars or {})
    coords.update(extra_coords or {})
    ds = xr.Dataset(
        data_vars,
        coords=coords,
        attrs={
            "hybridwsi_version": version(),
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
    """Rigid-body mass matrix [kg, kg m, kg m²] of a history, or None when it carries none."""
    return None if "mass" not in ds else np.asarray(ds["mass"].values, dtype=float)


def set_mass(ds: xr.Dataset, mass: float | np.ndarray) -> xr.Dataset:
    """Return ``ds`` with its rigid-body mass set (scalar [kg] or (n_dof, n_dof) matrix)."""
    m = _mass_matrix(mass, ds.sizes["dof"])
    dof = [str(d) for d in ds["dof"].values]
    out = ds.drop_vars([v for v in ("mass",) if v in ds])
    out = out.assign_coords(dof_j=dof)
    out["mass"] = (("dof", "dof_j"), m, _mass_attrs(dof))
    return out


#: largest |value| of a kinematic or force variable: beyond it squares overflow float64
MAX_MAGNITUDE = 1e150


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
    and force variable finite (no NaN/inf) and shaped ``(time, dof)``; units SI
    (:func:`hybridwsi.units.check_si`: a file read without conversion is refused, not
    used at the wrong scale); ``mass``, when present, finite and positive definite.
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
    if require_uniform and not _steps_uniform(dt):
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
        peak = float(np.max(np.abs(var.values))) if var.size else 0.0
        if peak > MAX_MAGNITUDE:  # its squares (regression, energy, RMS) would overflow
            raise InputError(f"'{name}' reaches {peak:.3g} in SI units: its squares overflow "
                             f"(not a physical value; limit {MAX_MAGNITUDE:.0e})")
    if "mass" in ds:
        check_mass(np.atleast_2d(np.asarray(ds["mass"].values, dtype=float)), ds.sizes["dof"])
    check_si(ds)
    return ds


def check_compatible(histories: Sequence[xr.Dataset], *, rtol: float = UNIFORM_RTOL) -> None:
    """Refuse histories that cannot be pooled (training sets, sweeps): raise :class:`InputError`
    unless they share the DOFs, the time step [s] (within ``rtol``) and the mass matrix.

    Mixing records of different sampling or of bodies of different mass fits one model to
    different physics (a network trained on them predicts neither); histories without a mass
    are compatible with any.
    """
    hists = list(histories)
    if not hists:
        raise InputError("no histories given")
    ref = hists[0]
    ref_dof = [str(d) for d in ref["dof"].values]
    ref_dt = time_step(ref)
    ref_m = mass_matrix(ref)
    for k, h in enumerate(hists[1:], start=1):
        dof = [str(d) for d in h["dof"].values]
        if dof != ref_dof:
            raise InputError(f"history {k} has DOFs {dof}, history 0 has {ref_dof}")
        dt = time_step(h)
        if abs(dt - ref_dt) > rtol * ref_dt:
            raise InputError(f"history {k} has time step {dt:.6g} s, history 0 has "
                             f"{ref_dt:.6g} s: resample them to one step first")
        m = mass_matrix(h)
        if m is not None and ref_m is not None and not np.allclose(m, ref_m, rtol=1e-9):
            raise InputError(f"history {k} has mass {m.ravel().tolist()}, history 0 has "
                             f"{ref_m.ravel().tolist()} (different bodies cannot be pooled)")


def check_regressors(motion: Mapping[str, np.ndarray],
                     forces: Mapping[str, np.ndarray] | None = None) -> None:
    """Refuse data a least-squares fit on the motion cannot use (raise :class:`InputError`).

    Parameters
    ----------
    motion : mapping of str to ndarray, each (n, n_dof)
        The regressors (``z`` [m or rad], ``zdot``, ``zddot``).
    forces : mapping of str to ndarray, optional
        The regressed forces [N or N m].

    Every value must be finite and small enough that a sum of ``n`` squares stays finite
    (``|x| < sqrt(max float / n)``, about 1e150 for 1e5 samples: beyond it the normal
    equations overflow and the fit returns garbage with NaN); the motion must not be constant
    (zero variance in every column: nothing to regress on).
    """
    limit = None
    for name, values in {**motion, **(forces or {})}.items():
        v = np.asarray(values, dtype=float)
        if limit is None:
            limit = math.sqrt(np.finfo(float).max / max(v.shape[0], 1))
        if not np.all(np.isfinite(v)):
            raise InputError(f"'{name}' has NaN/inf values: nothing can be fitted to them")
        peak = float(np.abs(v).max()) if v.size else 0.0
        if peak > limit:
            raise InputError(
                f"'{name}' reaches {peak:.3g}: its squares overflow a float over "
                f"{v.shape[0]} samples; check its units (largest usable value {limit:.3g})"
            )
    spread = [np.ptp(np.asarray(v, dtype=float), axis=0) for v in motion.values()]
    if spread and all(np.all(s == 0) for s in spread):
        raise InputError("the motion is constant: nothing to regress (z, zdot, zddot never change)")


def select_dofs(hist: xr.Dataset, dofs: Sequence[str] | None,
                what: str = "the history") -> xr.Dataset:
    """Keep the DOFs ``dofs`` (in that order) of a TimeHistory; None keeps all.

    Per-DOF unit attributes are rewritten for the kept DOFs; (dof, dof_j) matrices are
    restricted to the kept rows and columns. A DOF the history lacks is an InputError naming
    ``what``.
    """
    if dofs is None:
        return hist
    have = [str(d) for d in hist["dof"].values]
    missing = [d for d in dofs if d not in have]
    if missing:
        raise InputError(f"{what} has no DOF {', '.join(missing)} (it has {', '.join(have)}); "
                         "choose --dofs among those")
    keep = [have.index(d) for d in dofs]
    out = hist.isel(dof=keep)
    if "dof_j" in out.dims:
        out = out.isel(dof_j=keep)
    for name in list(out.data_vars):
        attrs = out[name].attrs
        if "units_per_dof" in attrs and out[name].dims[-1:] == ("dof",):
            per = json.loads(attrs["units_per_dof"])
            if len(per) == len(have):
                per = [per[i] for i in keep]
                out[name] = out[name].assign_attrs(units_per_dof=json.dumps(per),
                                                   units=", ".join(dict.fromkeys(per)))
    return out


def _steps_uniform(steps: np.ndarray) -> bool:
    """Whether time steps [s] vary by at most ``UNIFORM_RTOL`` of their median."""
    return bool(steps.size and (steps.max() - steps.min()) <= UNIFORM_RTOL * np.median(steps))


def is_uniform(ds: xr.Dataset) -> bool:
    """Whether the time step varies by less than ``UNIFORM_RTOL`` (relative)."""
    return _steps_uniform(np.diff(np.asarray(ds["time"].values, dtype=float)))


def time_step(ds: xr.Dataset) -> float:
    """Mean sampling interval [s] of a (uniform) history."""
    t = np.asarray(ds["time"].values, dtype=float)
    return float((t[-1] - t[0]) / (t.size - 1))
