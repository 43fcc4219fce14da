"""Shared pieces of the coefficient-file readers: one Dataset builder, content hash, units.

Every reader (WAMIT, Capytaine NetCDF, BEMIO) turns its file into dimensional SI arrays in the
force-equation orientation ``M[ω, influenced i, radiating j]`` and Capytaine's excitation
convention ``F(t) = Re[F̂ a e^{−iωt}]``, then calls :func:`build`, which checks them and
stores them as the project's coefficient Dataset (``hybridwsi.hydro.coefficients``).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi import __version__
from hybridwsi.dofs import RIGID_DOFS, check_dofs, force_unit, is_rotation
from hybridwsi.errors import InputError
from hybridwsi.hydro.coefficients import PAIR, pair_units_attr

#: seawater ρ [kg/m³] and standard g [m/s²], assumed only where the caller asks for defaults
SEAWATER = {"rho": 1025.0, "g": 9.80665}


def n_rotations(i: str, j: str | None = None) -> int:
    """How many of the DOFs ``i`` (and ``j``) are rotations: the extra length powers in the
    WAMIT normalisation of a coefficient that couples them."""
    return int(is_rotation(i)) + (int(is_rotation(j)) if j is not None else 0)


def mode_dof(mode: int, where: str) -> str:
    """DOF name of a WAMIT/BEMIO mode index 1…6 (Surge…Yaw)."""
    if not 1 <= mode <= len(RIGID_DOFS):
        raise InputError(f"{where}: mode index {mode} is outside 1-6 (multi-body files and "
                         f"generalised modes are not supported)")
    return RIGID_DOFS[mode - 1]


def content_hash(paths: Iterable[Path], settings: dict[str, Any]) -> str:
    """SHA-256 of the input files' bytes and the settings used to read them."""
    h = hashlib.sha256()
    for p in paths:
        h.update(Path(p).name.encode())
        h.update(Path(p).read_bytes())
    h.update(json.dumps(settings, sort_keys=True, default=str).encode())
    return h.hexdigest()


def positive(value: float | None, name: str) -> float:
    """``value`` as a finite positive float, or InputError naming ``name``."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    if not (np.isfinite(v) and v > 0):
        raise InputError(f"{name} must be finite and positive, got {value!r}")
    return v


def excitation_units(dofs: Sequence[str]) -> str:
    """``units`` text of the excitation force per unit wave amplitude."""
    units = {f"{force_unit(d)}/m" for d in dofs}
    return units.pop() if len(units) == 1 else "N/m (translations), N m/m (rotations)"


def _finite(name: str, arr: np.ndarray | None, where: str) -> None:
    if arr is not None and not np.all(np.isfinite(arr)):
        raise InputError(f"{where}: '{name}' contains NaN/inf")


def _checked_frequencies(omega: np.ndarray, where: str) -> np.ndarray:
    """The frequencies [rad/s] as floats: a non-empty list of finite, positive, distinct
    values, else :class:`InputError` naming ``where``."""
    omega = np.asarray(omega, dtype=float)
    if omega.ndim != 1 or omega.size == 0:
        raise InputError(f"{where}: no finite frequency in the file")
    if not np.all(np.isfinite(omega) & (omega > 0)):
        raise InputError(f"{where}: frequencies must be finite and positive")
    srt = np.sort(omega)
    if np.any(np.diff(srt) == 0):
        raise InputError(f"{where}: repeated frequency {srt[1:][np.diff(srt) == 0][0]:.6g} rad/s")
    return omega


def _with_excitation(ds: xr.Dataset, excitation: np.ndarray, directions: np.ndarray | None,
                     order: np.ndarray, where: str) -> xr.Dataset:
    """``ds`` with the excitation force (n_ω, n_β, n) [N/m, N m/m] in frequency ``order`` and
    its wave directions [rad]."""
    exc = np.asarray(excitation, dtype=complex)
    directions = np.asarray(directions, dtype=float)
    shape = (ds.sizes["omega"], directions.size, ds.sizes["influenced_dof"])
    if exc.shape != shape:
        raise InputError(f"{where}: excitation has shape {exc.shape}, expected {shape}")
    _finite("excitation_force", exc, where)
    ds = ds.assign_coords(wave_direction=("wave_direction", directions, {"units": "rad"}))
    dofs = [str(d) for d in ds["influenced_dof"].values]
    ds["excitation_force"] = (("omega", "wave_direction", "influenced_dof"), exc[order], {
        "units": excitation_units(dofs),
        "description": "Froude-Krylov + diffraction per unit wave amplitude at the origin; "
                       "Capytaine's time convention F(t) = Re[F exp(-i omega t)]"})
    return ds


def build(
    *,
    omega: np.ndarray,
    dofs: Sequence[str],
    added_mass: np.ndarray,
    radiation_damping: np.ndarray,
    excitation: np.ndarray | None,
    directions: np.ndarray | None,
    added_mass_inf: np.ndarray | None,
    added_mass_zero: np.ndarray | None,
    hydrostatic_stiffness: np.ndarray | None,
    mass: np.ndarray | None,
    rho: float,
    g: float,
    water_depth: float,
    source: str,
    input_hash: str,
    where: str,
    attrs: dict[str, Any] | None = None,
) -> xr.Dataset:
    """Assemble the coefficient Dataset from dimensional arrays (sorted by ω on the way).

    Parameters
    ----------
    omega : (n_ω,) finite positive frequencies [rad/s].
    dofs : DOF names (Capytaine spelling), the order of the matrix axes.
    added_mass, radiation_damping : (n_ω, n, n) ``[ω, influenced, radiating]`` in kg, kg m,
        kg m² and N s/m, N s/rad, N m s/m, N m s/rad per DOF pair.
    excitation : (n_ω, n_β, n) complex, per unit wave amplitude (N/m, N m/m), Capytaine's
        convention ``F(t) = Re[F̂ a e^{−iωt}]``; ``None`` when the file has none.
    directions : (n_β,) wave directions [rad].
    added_mass_inf, added_mass_zero, hydrostatic_stiffness, mass : (n, n) ``[influenced,
        radiating]`` or ``None`` (stored as NaN for the A limits, omitted otherwise).
    rho, g, water_depth : kg/m³, m/s², m (``inf`` for deep water).
    source, input_hash : provenance (``input_hash`` is a content hash of the files).
    where : file name used in error messages.
    """
    dofs = list(check_dofs(list(dofs)))
    n = len(dofs)
    omega = _checked_frequencies(omega, where)
    order = np.argsort(omega)
    shapes = {"added_mass": (added_mass, (omega.size, n, n)),
              "radiation_damping": (radiation_damping, (omega.size, n, n))}
    for name, (arr, shape) in shapes.items():
        if np.shape(arr) != shape:
            raise InputError(f"{where}: '{name}' has shape {np.shape(arr)}, expected {shape}")
        _finite(name, arr, where)

    def pair_var(arr: np.ndarray) -> np.ndarray:  # [.., influenced, radiating] -> [.., rad, infl]
        return np.swapaxes(np.asarray(arr, dtype=float), -1, -2)

    ds = xr.Dataset(coords={"omega": ("omega", omega[order], {"units": "rad/s"}),
                            "radiating_dof": dofs, "influenced_dof": dofs})
    for name, arr in (("added_mass", added_mass), ("radiation_damping", radiation_damping)):
        ds[name] = (("omega", *PAIR), pair_var(np.asarray(arr)[order]),
                    {"units": pair_units_attr(name, dofs)})
    if excitation is not None:
        ds = _with_excitation(ds, excitation, directions, order, where)
    for name, arr, keep_nan in (("added_mass_inf", added_mass_inf, True),
                                ("added_mass_zero", added_mass_zero, True),
                                ("hydrostatic_stiffness", hydrostatic_stiffness, False),
                                ("mass", mass, False)):
        if arr is None and not keep_nan:
            continue
        val = np.full((n, n), np.nan) if arr is None else np.asarray(arr, dtype=float)
        if val.shape != (n, n):
            raise InputError(f"{where}: '{name}' has shape {val.shape}, expected {(n, n)}")
        if arr is not None:
            _finite(name, val, where)
        ds[name] = (PAIR, pair_var(val), {"units": pair_units_attr(name, dofs)})
    ds.attrs = {"source": source, "rho": float(rho), "g": float(g),
                "water_depth": float(water_depth), "input_hash": input_hash,
                "hybridwsi_version": __version__, **(attrs or {})}
    return ds
