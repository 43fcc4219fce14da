"""The coefficient Dataset of a plan from the solved store: the plan's frequencies, the
ω = 0 / ∞ limits, the body's mass and hydrostatics, units, quality flags and provenance; and
the join of a finite-depth part with its deep-water part."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import xarray as xr

from hybridwsi._meta import package_version, version
from hybridwsi.bodies import Body
from hybridwsi.dofs import force_unit
from hybridwsi.errors import SolverError
from hybridwsi.hydro.bem.cache import same_frequency
from hybridwsi.hydro.bem.planning import Plan
from hybridwsi.hydro.bem.solve import COEFF_VARS
from hybridwsi.hydro.coefficients import pair_units_attr

#: relative tolerance below which a negative diagonal damping is treated as round-off
NEG_DAMPING_RTOL = 1e-6


def assemble(store: xr.Dataset, p: Plan) -> xr.Dataset:
    """The coefficient Dataset of plan ``p`` (``docs/DATA_MODEL.md``) from the ``store`` of
    solved frequencies: NaN frequencies dropped and flagged, the limits, the body's matrices,
    units, quality flags (each also warned) and the inputs in ``attrs``."""
    omega, dofs, body = p.omega, p.dofs, p.body
    w_store = store["omega"].values
    idx = [int(np.flatnonzero(same_frequency(w_store, w))[0]) for w in omega]
    ds = store.isel(omega=idx).assign_coords(omega=omega)
    flags: list[str] = []
    nan_w = ds["omega"].values[np.isnan(ds["added_mass"]).any(("radiating_dof", "influenced_dof")).values]
    if nan_w.size:
        flags.append(f"dropped {nan_w.size} frequencies with NaN coefficients "
                     f"({nan_w.min():.3g}-{nan_w.max():.3g} rad/s)")
        ds = ds.sel(omega=~np.isin(ds["omega"].values, nan_w))
        if ds.sizes["omega"] == 0:
            raise SolverError("the BEM returned NaN at every frequency")

    def limit(w: float, on: bool) -> np.ndarray:
        hit = np.flatnonzero(w_store == w)
        if not on or hit.size == 0:
            return np.full((len(dofs), len(dofs)), np.nan)
        return store["added_mass"].isel(omega=int(hit[0])).values

    a_inf, a_zero = limit(math.inf, p.include_inf), limit(0.0, p.include_zero)
    for name, val, on in (("added_mass_inf", a_inf, p.include_inf),
                          ("added_mass_zero", a_zero, p.include_zero)):
        if on and np.isnan(val).any():
            flags.append(f"{name} is NaN (not computable for this water depth/Green function)")

    pair = ("radiating_dof", "influenced_dof")
    cbody = body.capytaine_body(dofs, lid=p.lid, **p.mesh)
    ds["added_mass_inf"] = (pair, a_inf)
    ds["added_mass_zero"] = (pair, a_zero)
    # the body returns force-equation matrices M[influenced, radiating]: stored transposed
    ds["hydrostatic_stiffness"] = (pair, body.hydrostatic_stiffness(dofs).T)
    ds["hydrostatic_stiffness_mesh"] = (pair, _capytaine_stiffness(cbody, body))
    ds["mass"] = (pair, body.mass_matrix(dofs).T)
    _annotate(ds, dofs)
    flags += _quality_flags(ds)
    for f in flags:
        warnings.warn(f"BEM coefficients: {f}", stacklevel=4)
    n_lid = 0 if cbody.lid_mesh is None else int(cbody.lid_mesh.nb_faces)
    ds.attrs = {
        "source": "hybridwsi.hydro.bem.compute (Capytaine)",
        "rho": body.rho, "g": body.g, "water_depth": p.depth,
        "body": body.to_json(), "n_panels": int(cbody.mesh.nb_faces), "n_lid_panels": n_lid,
        "mesh": json.dumps(p.config["mesh"], sort_keys=True),
        "reference_point": [float(v) for v in body.reference_point],
        "method": p.method, "symmetric": int(p.symmetric), "lid": int(p.lid),
        "low_kh": p.low_kh,
        "input_hash": p.input_hash, "inputs": json.dumps(p.config, sort_keys=True),
        "hybridwsi_version": version(), "capytaine_version": package_version("capytaine"),
        "quality_flags": json.dumps(flags),
        "dropped_omega": json.dumps([float(w) for w in nan_w]),
    }
    return ds


def _annotate(ds: xr.Dataset, dofs: tuple[str, ...]) -> None:
    """Units and descriptions of the coefficient variables, in place."""
    for name in ("added_mass", "radiation_damping", "added_mass_inf", "added_mass_zero",
                 "hydrostatic_stiffness", "hydrostatic_stiffness_mesh", "mass"):
        kind = "hydrostatic_stiffness" if name == "hydrostatic_stiffness_mesh" else name
        ds[name].attrs["units"] = pair_units_attr(kind, dofs)
    exc_units = sorted({f"{force_unit(d)}/m" for d in dofs})
    ds["excitation_force"].attrs["units"] = (
        exc_units[0] if len(exc_units) == 1
        else "per DOF (N/m for translations, N m/m for rotations)")
    ds["excitation_force"].attrs["description"] = (
        "Froude-Krylov + diffraction per unit wave amplitude at the origin; Capytaine's time "
        "convention F(t) = Re[F exp(-i omega t)]")
    ds["hydrostatic_stiffness"].attrs["description"] = (
        "analytic where the geometry allows, about the reference point, including the weight "
        "term -m g (z_G - z_O) in roll and pitch (hybridwsi.bodies.base)")
    ds["hydrostatic_stiffness_mesh"].attrs["description"] = (
        "Capytaine compute_hydrostatic_stiffness on the mesh (with the body's mass and centre "
        "of mass)")
    ds["mass"].attrs["description"] = "rigid-body mass matrix about the reference point"
    ds["omega"].attrs["units"] = "rad/s"
    ds["wave_direction"].attrs["units"] = "rad"


def join_depths(low: xr.Dataset | None, high: xr.Dataset, depth: float,
                 deep_kh: float, input_hash: str) -> xr.Dataset:
    """Finite-depth coefficients below kh = ``deep_kh`` joined with deep-water ones above."""
    per_omega = ("added_mass", "radiation_damping", "excitation_force")
    if low is None:
        ds = high.copy()
    else:
        ds = low.copy()
        for name in per_omega:
            ds = ds.drop_vars(name)
        ds = ds.drop_dims("omega") if "omega" in ds.dims else ds
        joined = xr.concat([low[list(per_omega)], high[list(per_omega)]], dim="omega")
        ds = xr.merge([joined, ds], combine_attrs="override")
        ds["added_mass_inf"] = high["added_mass_inf"]
    flags = (json.loads(low.attrs.get("quality_flags", "[]")) if low is not None else []) + \
        json.loads(high.attrs.get("quality_flags", "[]"))
    ds.attrs.update(
        water_depth=depth, deep_water_kh=deep_kh,
        deep_water_above_omega=float(high["omega"].values.min()),
        input_hash=input_hash,
        quality_flags=json.dumps(flags),
        note=(f"finite depth {depth} m below kh = {deep_kh}; deep water above "
              f"(omega >= {float(high['omega'].values.min()):.4g} rad/s) and for A_inf"),
    )
    return ds


def _quality_flags(ds: xr.Dataset) -> list[str]:
    flags = []
    for name in COEFF_VARS:
        n = int(np.isnan(ds[name].values).sum())
        if n:
            flags.append(f"{name} has {n} NaN value(s)")
    b = ds["radiation_damping"].values
    diag = np.diagonal(b, axis1=1, axis2=2)
    scale = np.nanmax(np.abs(diag)) if np.isfinite(diag).any() else 0.0
    neg = diag < -NEG_DAMPING_RTOL * scale
    if neg.any():
        w = ds["omega"].values[neg.any(axis=1)]
        flags.append(f"negative diagonal radiation damping at {w.size} frequencies "
                     f"({w.min():.3g}-{w.max():.3g} rad/s), min {diag.min():.3g} N s/m")
    return flags


def _capytaine_stiffness(cbody, body: Body) -> np.ndarray:
    """Capytaine's mesh-integrated hydrostatic stiffness (works on the symmetric mesh), stored
    as (radiating_dof, influenced_dof)."""
    c = cbody.compute_hydrostatic_stiffness(rho=body.rho, g=body.g)
    return np.asarray(c.transpose("radiating_dof", "influenced_dof").values, dtype=float)
