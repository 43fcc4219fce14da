"""DualSPHysics floating-body output: ``FloatingInfo`` motion/force and ``FloatingAce`` files.

Formats ``dualsphysics-info`` (:func:`read_dualsphysics_floatinginfo`) and
``dualsphysics-ace`` (:func:`read_dualsphysics_floatingace`); heave only, SI units.

DualSPHysics writes each output at the first solver step on or after the output instant (and
``FloatingAce`` at every solver step), so its times are irregular by construction: a real
``FloatingAce`` file has steps from 0.00986 to 0.010136 s. Such jitter is resampled
automatically (cubic, onto the median step, :func:`hybridwsi.history.resample`; recorded in
``attrs["resampled"]``); steps further than :data:`OUTPUT_JITTER` from the median are gaps,
rejected unless ``resample=True`` like any irregular file
(:func:`hybridwsi.history.finalize_import`).
"""

from __future__ import annotations

import os
import re
import warnings

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.history import TextTable, finalize_import, is_uniform, make_history, split_header

#: relative deviation of a time step from the median step that still counts as DualSPHysics'
#: output jitter (one solver step at most; resampled automatically); larger ones are gaps
OUTPUT_JITTER = 0.5

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


def _require_alias(table: TextTable, aliases: tuple[str, ...], missing: str, what: str) -> str:
    """The column matching one of ``aliases``, or a one-line InputError naming ``missing``."""
    col = _find_alias(table, aliases)
    if col is None:
        raise InputError(f"{table.path.name}: no {missing} column for {what}; available "
                         f"columns: {', '.join(table.columns)}")
    return col


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
    resample: bool | None = None,
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
    resample : bool, optional
        None (default): resample when the irregularity is DualSPHysics' output jitter (see the
        module docstring), reject larger gaps; True: resample any irregular time; False:
        reject any irregular time.
    require_uniform : bool
        False returns an irregular file as sampled (no automatic resampling).
    """
    table = TextTable(path)
    rows = _select_mkbound(table, mkbound)
    what = "a DualSPHysics floating body"
    tcol = _require_alias(table, _DSPH_TIME, "time", what)
    zcol = _require_alias(table, _DSPH_Z, "heave or center.z", what)
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
    return _finalize(ds, resample, require_uniform)


def read_dualsphysics_floatingace(
    path: str | os.PathLike,
    mass: float | None = None,
    *,
    resample: bool | None = None,
    require_uniform: bool = True,
) -> xr.Dataset:
    """Heave acceleration (and ``F_tot = m zddot``) from DualSPHysics ``FloatingAce`` output.

    The file (``FloatingAce_mkbound_XX.csv``, header ``nstep;time [s];dt [s];predictor;
    acelin.x [m/s^2];acelin.y [m/s^2];acelin.z [m/s^2];aceang.x [rad/s^2];...``) is written
    at irregular solver steps. Rows whose ``predictor`` flag is true (``True``/``1``) are the
    predictor half of a predictor-corrector step and are dropped. ``resample`` and
    ``require_uniform`` as in :func:`read_dualsphysics_floatinginfo`.

    The file holds no displacement or velocity: the history has no ``z``/``zdot`` (this is
    stated in ``attrs["missing"]`` and in a :class:`UserWarning`); merge it with the
    ``FloatingInfo`` motion of the same run before running the diagnostic.
    """
    table = TextTable(path)
    tcol = _require_alias(table, _DSPH_TIME, "time", "DualSPHysics FloatingAce")
    acol = _require_alias(table, _DSPH_ZDDOT, "acelin.z", "DualSPHysics FloatingAce")
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
    return _finalize(ds, resample, require_uniform, require_z=False)


def _is_output_jitter(ds: xr.Dataset) -> bool:
    """Whether every time step [s] lies within :data:`OUTPUT_JITTER` of the median step."""
    steps = np.diff(np.asarray(ds["time"].values, dtype=float))
    median = float(np.median(steps))
    return bool(np.all(np.abs(steps - median) <= OUTPUT_JITTER * median))


def _finalize(ds: xr.Dataset, resample: bool | None, require_uniform: bool,
              require_z: bool = True) -> xr.Dataset:
    """:func:`finalize_import` with DualSPHysics' automatic resampling of output jitter."""
    auto = resample is None and require_uniform and not is_uniform(ds) and _is_output_jitter(ds)
    out = finalize_import(ds, resample_to_uniform=bool(resample) or auto,
                          require_uniform=require_uniform, require_z=require_z)
    if auto:
        out.attrs["resampled"] += " (automatic: DualSPHysics output times jitter)"
    return out


def _check_time_rows(table: TextTable, t: np.ndarray, rows: np.ndarray) -> None:
    """:meth:`TextTable.check_time` on a subset of rows, with the right line numbers."""
    full = table.line_numbers
    table.line_numbers = full[rows]
    try:
        table.check_time(t)
    finally:
        table.line_numbers = full
