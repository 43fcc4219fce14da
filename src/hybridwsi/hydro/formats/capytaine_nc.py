"""NetCDF written by Capytaine (``cpt.assemble_dataset`` or ``BEMSolver.fill_dataset``, then
``cpt.export_dataset(path, ds)``) → the coefficient Dataset.

What Capytaine 3 writes (``capytaine.io.xarray.save_dataset_as_netcdf``): complex variables
split along a ``complex`` dimension with labels ``re``/``im``; ``added_mass`` and
``radiation_damping`` as ``(omega, influenced_dof, radiating_dof)``; ``diffraction_force``,
``Froude_Krylov_force`` and (when both exist) ``excitation_force`` as ``(omega,
wave_direction, influenced_dof)``; ``rho``, ``g``, ``water_depth`` as scalar coordinates (or
dimensions when several values were solved); ``omega = 0`` and ``omega = inf`` rows when they
were asked for; with hydrostatics, ``hydrostatic_stiffness`` and ``inertia_matrix``
(``influenced_dof``, ``radiating_dof``). A run listed by period (or wavenumber…) has that as
its dimension and ``omega`` as a coordinate along it. Capytaine's time convention is already
the project's (``Re[F̂ e^{−iωt}]``): no conjugation.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.hydro.formats.common import build, content_hash

FREQ_DIMS = ("omega", "period", "freq", "wavenumber", "wavelength")


def is_capytaine(ds: xr.Dataset) -> bool:
    """True for a Dataset written by Capytaine (not by hybridwsi)."""
    return "capytaine_version" in ds.attrs and "hybridwsi_version" not in ds.attrs


def _merge_complex(ds: xr.Dataset) -> xr.Dataset:
    if "complex" not in ds.dims:
        return ds
    labels = [str(v) for v in ds["complex"].values]
    if sorted(labels) != ["im", "re"]:
        raise InputError(f"Capytaine NetCDF: 'complex' labels are {labels}, expected re/im")
    for name in [n for n in ds.data_vars if "complex" in ds[n].dims]:
        da = ds[name]
        ds[name] = da.sel(complex="re", drop=True) + 1j * da.sel(complex="im", drop=True)
    return ds.drop_vars("complex")


def _squeeze(ds: xr.Dataset, where: str) -> xr.Dataset:
    """Drop the size-1 parameter dims (rho, g, water_depth, forward_speed…); refuse sweeps."""
    keep = {"omega", "wave_direction", "radiating_dof", "influenced_dof", "space_coordinate"}
    for dim in [d for d in ds.dims if d not in keep]:
        if ds.sizes[dim] != 1:
            raise InputError(f"{where}: Capytaine dataset sweeps '{dim}' ({ds.sizes[dim]} "
                             f"values); select one value first (ds.sel({dim}=...))")
        ds = ds.isel({dim: 0})
    return ds


def _scalar(ds: xr.Dataset, name: str, where: str) -> float:
    if name not in ds.variables:
        raise InputError(f"{where}: Capytaine dataset has no '{name}'")
    return float(np.asarray(ds[name].values).reshape(-1)[0])


def _pair(da: xr.DataArray, dofs: list[str], lead: tuple[str, ...] = ()) -> np.ndarray:
    """``[…, influenced, radiating]`` values for ``dofs`` (labels, not positions)."""
    da = da.sel(influenced_dof=dofs, radiating_dof=dofs)
    return np.asarray(da.transpose(*lead, "influenced_dof", "radiating_dof").values, dtype=float)


def from_dataset(raw: xr.Dataset, path: Path) -> xr.Dataset:
    """Map a loaded Capytaine Dataset (``path`` for messages and the hash) to ours."""
    where = path.name
    ds = _merge_complex(raw)
    if "omega" not in ds.dims:
        dim = next((d for d in FREQ_DIMS if d in ds.dims), None)
        if dim is None or "omega" not in ds.coords:
            raise InputError(f"{where}: Capytaine dataset has no frequency dimension")
        ds = ds.swap_dims({dim: "omega"})
    ds = _squeeze(ds, where)
    for name in ("added_mass", "radiation_damping"):
        if name not in ds:
            raise InputError(f"{where}: Capytaine dataset has no '{name}'")
    if "forward_speed" in ds.variables and _scalar(ds, "forward_speed", where) != 0.0:
        raise InputError(f"{where}: forward speed is not supported")
    dofs = [str(d) for d in ds["radiating_dof"].values]
    if sorted(dofs) != sorted(str(d) for d in ds["influenced_dof"].values):
        raise InputError(f"{where}: radiating and influenced DOFs differ")
    w_all = np.asarray(ds["omega"].values, dtype=float)
    regular = np.isfinite(w_all) & (w_all > 0)

    def limit(w: float) -> np.ndarray | None:
        hit = np.flatnonzero(w_all == w)
        return _pair(ds["added_mass"].isel(omega=int(hit[0])), dofs) if hit.size else None

    reg = ds.isel(omega=np.flatnonzero(regular))
    exc = None
    if "excitation_force" in reg:
        exc_da = reg["excitation_force"]
    elif "diffraction_force" in reg and "Froude_Krylov_force" in reg:
        exc_da = reg["diffraction_force"] + reg["Froude_Krylov_force"]
    else:
        exc_da = None
    if exc_da is not None:
        exc_da = exc_da.sel(influenced_dof=dofs).transpose("omega", "wave_direction",
                                                           "influenced_dof")
        exc = np.asarray(exc_da.values, dtype=complex)
    stiff = _pair(ds["hydrostatic_stiffness"], dofs) if "hydrostatic_stiffness" in ds else None
    mass = _pair(ds["inertia_matrix"], dofs) if "inertia_matrix" in ds else None
    rho, g = _scalar(ds, "rho", where), _scalar(ds, "g", where)
    depth = _scalar(ds, "water_depth", where) if "water_depth" in ds.variables else math.inf
    return build(
        omega=w_all[regular], dofs=dofs,
        added_mass=_pair(reg["added_mass"], dofs, ("omega",)),
        radiation_damping=_pair(reg["radiation_damping"], dofs, ("omega",)),
        excitation=exc,
        directions=None if exc is None else np.asarray(reg["wave_direction"].values, float),
        added_mass_inf=limit(math.inf), added_mass_zero=limit(0.0),
        hydrostatic_stiffness=stiff, mass=mass, rho=rho, g=g, water_depth=depth,
        source=f"Capytaine NetCDF {where}", input_hash=content_hash([path], {}), where=where,
        attrs={"capytaine_version": str(raw.attrs.get("capytaine_version", ""))})
