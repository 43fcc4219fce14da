"""The BEM entry point: :func:`compute` plans, then takes the result from the cache or the
shipped files, or solves the missing frequencies and assembles them."""

from __future__ import annotations

import json
import math
import os
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.bodies import Body
from hybridwsi.errors import InputError
from hybridwsi.files import to_netcdf
from hybridwsi.hydro.bem.assembly import assemble, join_depths
from hybridwsi.hydro.bem.cache import default_cache_dir, missing, read_cache, shipped
from hybridwsi.hydro.bem.planning import Plan, plan, warn_if_sinks
from hybridwsi.hydro.bem.solve import solve_missing, worker_count

#: number of frequencies solved between two checkpoints
CHUNK_SIZE = 10


def compute(
    body: Body,
    omega: Sequence[float] | np.ndarray,
    *,
    cache_dir: str | os.PathLike | None = None,
    progress: bool = True,
    use_cache: bool = True,
    chunk_size: int = CHUNK_SIZE,
    n_jobs: int | None = None,
    **options: Any,
) -> xr.Dataset:
    """Linear hydrodynamic coefficients of ``body`` from Capytaine (see module docstring).

    Parameters
    ----------
    body : hybridwsi.bodies.Body
        Any floating body (sphere, axisymmetric profile, mesh file, assembly); its ``rho``,
        ``g``, reference point (DOF origin), mass properties and hydrostatics are used.
    omega : array_like
        Wave frequencies [rad/s], finite and > 0 (sorted on output; duplicates rejected).
    **options
        The keyword arguments of :func:`plan` (what is solved; they enter the cache key):
        ``water_depth``, ``dofs``, ``wave_directions``, ``panel_size``, ``n_panels``,
        ``resolution``, ``include_inf``, ``include_zero``, ``method``, ``symmetric``, ``lid``,
        ``low_kh``, ``deep_water_kh``, ``low_kh_panels``.
    cache_dir : path, optional
        Cache folder (default :func:`default_cache_dir`).
    progress : bool
        Show a tqdm progress bar over frequencies.
    use_cache : bool
        Read and write the cache (False: solve everything, write nothing).
    chunk_size : int
        Frequencies per checkpoint.
    n_jobs : int, optional
        Worker processes solving chunks of frequencies in parallel (one BLAS thread each).
        Default: ``$HYBRIDWSI_BEM_JOBS``, else the usable CPU count for sweeps estimated to take
        over 30 s and 1 below (starting a worker costs ~3 s). Capytaine's Green function runs
        on one core, so two workers cut the paper configuration from 170 s to 122 s here.
        Results and cache key do not depend on it.

    Returns
    -------
    xarray.Dataset
        Coefficients as in ``docs/DATA_MODEL.md`` (matrices about ``attrs["reference_point"]``,
        units per DOF pair); ``attrs["input_hash"]`` identifies the inputs,
        ``attrs["quality_flags"]`` lists problems found (JSON list, empty when clean).
    """
    if int(chunk_size) < 1:
        raise InputError(f"chunk_size must be >= 1, got {chunk_size}")
    the_plan = plan(body, omega, **options)  # checks the body first
    warn_if_sinks(body)
    return _execute(the_plan, cache_dir=cache_dir, progress=progress,
                    use_cache=use_cache, chunk_size=int(chunk_size), n_jobs=worker_count(n_jobs))



def _execute(p: Plan, *, cache_dir: str | os.PathLike | None, progress: bool, use_cache: bool,
             chunk_size: int, n_jobs: int | None) -> xr.Dataset:
    """Run a :class:`Plan`: cached result, shipped file, or solve the missing frequencies."""
    run = dict(cache_dir=cache_dir, progress=progress, use_cache=use_cache,
               chunk_size=chunk_size, n_jobs=n_jobs)
    if p.parts is not None:
        # a result solved in two parts may be shipped as one file of the joined result
        whole = shipped(p.input_hash) if use_cache else None
        if whole is not None:
            _warn_flags(whole, "shipped", stacklevel=4)
            return whole
        low, high = p.parts
        return join_depths(None if low is None else _execute(low, **run), _execute(high, **run),
                           p.depth, p.deep_water_kh, p.input_hash)
    root = Path(cache_dir).expanduser() if cache_dir is not None else default_cache_dir()
    final_path = root / f"coeffs_{p.input_hash[:24]}.nc"
    store_path = root / f"store_{p.config_hash[:24]}.nc"
    cached = _cached_result(p, final_path) if use_cache else None
    if cached is not None:
        return cached
    limits = [w for w, on in ((0.0, p.include_zero), (math.inf, p.include_inf)) if on]
    store = read_cache(store_path) if use_cache and store_path.is_file() else None
    todo = missing(np.concatenate([p.omega, limits]), store)
    if todo.size:
        store = solve_missing(p, todo, store, store_path if use_cache else None,
                              progress=progress, chunk_size=chunk_size, n_jobs=n_jobs)
    ds = assemble(store, p)
    if use_cache:
        to_netcdf(ds, final_path)
    return ds


def _cached_result(p: Plan, final_path: Path) -> xr.Dataset | None:
    """The finished result of ``p`` from the cache file ``final_path`` (seeded first from a
    shipped file of the same inputs, so later calls take the usual path), or None."""
    if not final_path.is_file():
        ship = shipped(p.input_hash)
        if ship is not None:
            to_netcdf(ship, final_path)
    if not final_path.is_file():
        return None
    cached = read_cache(final_path)
    if cached is None or cached.attrs.get("input_hash") != p.input_hash:
        return None
    _warn_flags(cached, "cached", stacklevel=5)
    return cached


def _warn_flags(ds: xr.Dataset, origin: str, stacklevel: int) -> None:
    """The quality flags of a result read from a file, warned again (they were at its solve);
    ``stacklevel`` points at the caller of :func:`compute`."""
    for flag in json.loads(ds.attrs.get("quality_flags", "[]")):
        warnings.warn(f"BEM coefficients ({origin}): {flag}", stacklevel=stacklevel)
