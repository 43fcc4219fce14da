"""Coefficient files users already hold → the coefficient Dataset, and WAMIT files back out.

:func:`read_coefficients` reads, by content (``format="auto"``) or by name:

- ``wamit``: ``ROOT.1`` with its siblings ``ROOT.3`` and ``ROOT.hst`` (OpenFAST HydroDyn's
  input; needs ρ, g and ULEN, :mod:`.wamit`);
- ``bemio``: a WEC-Sim BEMIO ``.h5`` (needs h5py, :mod:`.bemio`);
- ``capytaine``: a NetCDF written by Capytaine's ``export_dataset`` (:mod:`.capytaine_nc`);
- ``netcdf``: a coefficient NetCDF written by hybridwsi (``hybridwsi bem``/``coeffs``).

:func:`write_wamit` writes ``ROOT.1``, ``ROOT.3`` and ``ROOT.hst`` so that Capytaine results can
feed HydroDyn. All conventions are those of :mod:`hybridwsi.hydro.coefficients`.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.files import read_netcdf
from hybridwsi.hydro.formats import bemio, capytaine_nc, wamit
from hybridwsi.hydro.formats.common import SEAWATER

FORMATS = ("auto", "wamit", "bemio", "capytaine", "netcdf")
#: formats whose files carry ρ and g themselves
CARRY_RHO_G = ("bemio", "capytaine", "netcdf")

__all__ = ["FORMATS", "SEAWATER", "detect", "read_coefficients", "write_wamit"]


def detect(path: str | Path) -> str:
    """The format of ``path``: ``wamit``, ``bemio``, ``capytaine`` or ``netcdf``."""
    path = Path(path)
    if path.suffix.lower() in wamit.EXTENSIONS:
        return "wamit"
    if not path.is_file():
        raise InputError(f"file not found: {path}")
    with open(path, "rb") as f:
        head = f.read(8)
    if path.suffix.lower() in (".h5", ".hdf5"):
        if bemio.is_bemio(path):  # needs h5py: InputError naming the extra without it
            return "bemio"
        raise InputError(f"{path.name}: HDF5 file without BEMIO's simulation_parameters/"
                         f"body1 groups (not a WEC-Sim BEMIO file)")
    if head == bemio.HDF5_SIGNATURE and path.suffix.lower() != ".nc" and bemio.has_h5py() \
            and bemio.is_bemio(path):
        return "bemio"
    if head.startswith(b"CDF") or head == bemio.HDF5_SIGNATURE:
        return "netcdf"  # hybridwsi's or Capytaine's: told apart after opening
    raise InputError(f"{path.name}: unknown coefficient file format (expected a WAMIT .1, a "
                     f"BEMIO .h5 or a NetCDF from Capytaine or hybridwsi)")


def _netcdf(path: Path, fmt: str) -> xr.Dataset:
    ds = read_netcdf(path)
    if capytaine_nc.is_capytaine(ds) or fmt == "capytaine":
        return capytaine_nc.from_dataset(ds, path)
    for name in ("added_mass", "radiation_damping"):
        if name not in ds:
            raise InputError(f"{path.name}: no '{name}' (not a coefficient NetCDF)")
    if "radiating_dof" not in ds.coords:
        raise InputError(f"{path.name}: no 'radiating_dof' (not a coefficient NetCDF)")
    for name in ("added_mass", "radiation_damping", "excitation_force"):
        if name in ds and not np.all(np.isfinite(ds[name].values)):
            raise InputError(f"{path.name}: '{name}' contains NaN/inf")
    return ds


def read_coefficients(path: str | Path, *, rho: float | None = None, g: float | None = None,
                      ulen: float = 1.0, format: str = "auto", frequency_input: bool = False,
                      water_depth: float = math.inf,
                      assume_seawater: bool = False) -> xr.Dataset:
    """Read any supported coefficient file into the coefficient Dataset.

    Parameters
    ----------
    path : str or Path
        ``ROOT.1`` (WAMIT, siblings ``.3``/``.hst`` picked up), ``*.h5`` (BEMIO) or ``*.nc``.
    rho, g : float, optional
        Water density [kg/m³] and gravity [m/s²]; needed by WAMIT files only. Files that carry
        them (BEMIO, NetCDF) ignore these.
    ulen : float
        WAMIT length scale ULEN [m] (default 1).
    format : str
        ``auto`` (default) or one of ``wamit``, ``bemio``, ``capytaine``, ``netcdf``.
    frequency_input : bool
        WAMIT only: the first column is ω [rad/s] (``IPEROUT = 2``), not the period [s].
    water_depth : float
        WAMIT only: depth [m] recorded in the attrs (the numeric files do not hold it).
    assume_seawater : bool
        WAMIT only: without ``rho``/``g`` use seawater ρ = 1025 kg/m³ and g = 9.80665 m/s²
        and warn, instead of raising (what ``simulate``/``select --coeffs`` do).

    Raises
    ------
    InputError
        Unknown format, missing file or sibling, corrupt or truncated file, NaN, missing h5py,
        WAMIT without ρ/g.
    """
    if format not in FORMATS:
        raise InputError(f"unknown coefficient format {format!r}; choose from {list(FORMATS)}")
    path = Path(path)
    fmt = detect(path) if format == "auto" else format
    if fmt == "wamit":
        if (rho is None or g is None) and assume_seawater:
            rho = SEAWATER["rho"] if rho is None else rho
            g = SEAWATER["g"] if g is None else g
            warnings.warn(f"{path.name}: WAMIT files do not hold rho and g; assuming seawater "
                          f"rho = {rho} kg/m^3, g = {g} m/s^2", stacklevel=2)
        if rho is None or g is None:
            raise InputError(f"{path.name}: WAMIT files are nondimensional; give the water "
                             f"density and gravity of the WAMIT run (--rho, --g)")
        return wamit.read(path, rho=rho, g=g, ulen=ulen, frequency_input=frequency_input,
                          water_depth=water_depth)
    if not path.is_file():
        raise InputError(f"file not found: {path}")
    if fmt == "bemio":
        return bemio.read(path)
    return _netcdf(path, fmt)


def write_wamit(coeffs: xr.Dataset, root: str | Path, *, ulen: float = 1.0) -> list[Path]:
    """Write ``ROOT.1``, ``ROOT.3`` and ``ROOT.hst`` from coefficients (see :mod:`.wamit`)."""
    return wamit.write(coeffs, root, ulen=ulen)
