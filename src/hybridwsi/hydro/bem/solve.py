"""Solving the frequencies a plan still needs with Capytaine: chunks checkpointed into the
store, in this process or a pool of workers (joblib), with one BLAS thread; the finite-depth
low-kh frequencies re-solved with FinGreen3D."""

from __future__ import annotations

import contextlib
import json
import logging
import math
import os
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.bodies import Body
from hybridwsi.errors import InputError
from hybridwsi.files import to_netcdf
from hybridwsi.hydro.bem.cache import merge_store
from hybridwsi.hydro.bem.planning import Plan

#: the per-frequency coefficients a solve returns
COEFF_VARS = ("added_mass", "radiation_damping", "excitation_force")

def worker_count(n_jobs: int | None) -> int | None:
    """Worker count: the argument, else ``$HYBRIDWSI_BEM_JOBS``, else None (automatic)."""
    if n_jobs is None:
        n_jobs = os.environ.get("HYBRIDWSI_BEM_JOBS")
        if n_jobs is None:
            return None
    try:
        n = int(n_jobs)
    except (TypeError, ValueError):
        raise InputError(f"n_jobs must be a positive integer, got {n_jobs!r}") from None
    if n < 1:
        raise InputError(f"n_jobs must be a positive integer, got {n_jobs!r}")
    return n


def _auto_jobs(n_freq: int, mesh: Any) -> int:
    """Usable CPUs when the sweep is long enough to repay the workers' start-up (~3 s each):
    an estimated sequential time > 30 s, else 1.

    The estimate per frequency at 6400 hull panels is about 0.5 s on a rotation-symmetric
    mesh (growing like panels^1.5) and about 68 s on a plain mesh (dense solve, panels^2;
    ``benchmarks/bench_bem.py``); a mesh with other symmetries is costed as plain (an upper
    bound, which only makes the pool start sooner).
    """
    avail = os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else None
    cpus = max(1, len(avail) if avail else (os.cpu_count() or 1))
    scale = int(mesh.nb_faces) / 6400.0
    rotational = "RotationSymmetric" in type(mesh).__name__
    estimate = n_freq * (0.5 * scale**1.5 if rotational else 68.0 * scale**2)
    return cpus if estimate > 30.0 else 1


@contextlib.contextmanager
def blas_single_thread() -> Iterator[None]:
    """Limit BLAS to one thread (threadpoolctl), else warn unless OPENBLAS_NUM_THREADS is set."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        if os.environ.get("OPENBLAS_NUM_THREADS") != "1":
            warnings.warn("threadpoolctl is not installed: set OPENBLAS_NUM_THREADS=1 before "
                          "starting Python, multi-threaded BLAS slows Capytaine down a lot",
                          stacklevel=3)
        yield
        return
    with threadpool_limits(limits=1, user_api="blas"):
        yield


@contextlib.contextmanager
def quiet_capytaine() -> Iterator[None]:
    """Silence Capytaine's per-problem "Skipped ..." log lines: the frequencies it skips (low kh
    in finite depth) are re-solved or dropped below, with our own single warning."""
    logger = logging.getLogger("capytaine")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)


def solve_missing(p: Plan, todo: np.ndarray, store: xr.Dataset | None, store_path: Path | None,
                  *, progress: bool, chunk_size: int, n_jobs: int | None = None) -> xr.Dataset:
    """Solve ``todo`` frequencies chunk by chunk, checkpointing into ``store_path``.

    With ``n_jobs > 1`` the chunks go to a pool of worker processes (each builds the mesh and
    solver once); finished chunks are merged and checkpointed here, in completion order.
    (Capytaine's own ``n_jobs`` ships the solver with every frequency and was 3x slower here.)
    """
    from tqdm.auto import tqdm

    finite = todo[np.isfinite(todo) & (todo > 0)]
    limits = todo[~(np.isfinite(todo) & (todo > 0))]
    task = dict(body=p.body, dofs=p.dofs, directions=p.directions, depth=p.depth, mesh=p.mesh,
                method=p.method, symmetric=p.symmetric, lid=p.lid, low_kh=p.low_kh,
                low_mesh=p.low_kh_mesh)
    cbody, _ = _body_and_solver(p.body, p.dofs, p.mesh, p.symmetric, p.lid, p.method)
    _warn_mesh_resolution(cbody, finite, p.depth, p.body.g)
    n_jobs = _auto_jobs(finite.size, cbody.mesh) if n_jobs is None else n_jobs
    if n_jobs > 1:  # chunks small enough to keep every worker busy
        chunk_size = max(1, min(chunk_size, -(-finite.size // (2 * n_jobs))))
    chunks = [finite[i:i + chunk_size] for i in range(0, finite.size, chunk_size)]
    if limits.size:
        chunks.append(limits)  # radiation only; solved last so partial progress is visible first
    bar = tqdm(total=todo.size, unit="ω", desc="BEM", disable=not progress)

    def done(part: xr.Dataset) -> None:
        nonlocal store
        store = part if store is None else merge_store(store, part)
        if store_path is not None:
            to_netcdf(store, store_path)  # checkpoint: atomic
        bar.update(part.sizes["omega"])

    try:
        if n_jobs == 1 or len(chunks) == 1:
            for chunk in chunks:
                done(_solve_task(chunk, **task))
        else:
            import joblib

            # loky workers: reused for every chunk, one BLAS/OpenMP thread each, and (unlike
            # multiprocessing's spawn) safe in scripts without an ``if __name__`` guard
            with joblib.parallel_config(backend="loky", inner_max_num_threads=1):
                parts = joblib.Parallel(n_jobs=min(n_jobs, len(chunks)),
                                        return_as="generator_unordered")(
                    joblib.delayed(_solve_task)(chunk, **task) for chunk in chunks)
                for part in parts:
                    done(part)
    finally:
        bar.close()
    return store


_WORKER_CACHE: dict[str, Any] = {}


def _body_and_solver(body: Body, dofs: tuple, mesh: dict, symmetric: bool, lid: bool,
                     method: str):
    """Capytaine body and solver, built once per process and configuration (the parent's
    mesh-resolution check and a sequential sweep share them; each worker builds its own)."""
    import capytaine as cpt

    key = repr((body.to_json(), dofs, json.dumps(mesh, sort_keys=True), symmetric, lid, method))
    if key not in _WORKER_CACHE:
        _WORKER_CACHE.clear()  # one configuration at a time: meshes are large
        _WORKER_CACHE[key] = (body.capytaine_body(list(dofs), symmetric=symmetric, lid=lid,
                                                  **mesh),
                              cpt.BEMSolver(method=method))
    return _WORKER_CACHE[key]


def _solve_task(chunk: np.ndarray, *, body, dofs, directions, depth, mesh, method,
                symmetric, lid, low_kh, low_mesh) -> xr.Dataset:
    """Solve one chunk of frequencies (in this process or a worker)."""
    cbody, solver = _body_and_solver(body, tuple(dofs), mesh, symmetric, lid, method)
    with blas_single_thread(), warnings.catch_warnings(), quiet_capytaine():
        warnings.simplefilter("ignore", RuntimeWarning)  # NaN handled explicitly below
        part = solve_chunk(solver, cbody, chunk, directions=directions, depth=depth,
                            rho=body.rho, g=body.g)
        if math.isfinite(depth):
            part = _fix_low_kh(part, body, list(dofs), directions, depth, low_mesh, method,
                               symmetric, low_kh)
    return part


def solve_chunk(solver, cbody, omegas: np.ndarray, *, directions: np.ndarray, depth: float,
                 rho: float, g: float) -> xr.Dataset:
    """Solve radiation (and diffraction for finite ω > 0) problems at ``omegas``.

    Returns a Dataset with ``added_mass``, ``radiation_damping`` (omega, radiating_dof,
    influenced_dof) and ``excitation_force`` (omega, wave_direction, influenced_dof; NaN at the
    ω = 0 / ∞ limits, where diffraction is undefined).
    """
    omegas = np.asarray(omegas, dtype=float)
    dof_names = list(cbody.dofs)
    regular = bool(np.all(np.isfinite(omegas) & (omegas > 0)))
    coords = {"omega": omegas, "radiating_dof": dof_names, "water_depth": [depth],
              "rho": [rho], "g": [g]}
    if regular:
        coords["wave_direction"] = directions
    grid = xr.Dataset(coords=coords)
    raw = solver.fill_dataset(grid, cbody, hydrostatics=False, progress_bar=False,
                              _check_wavelength=False)
    out = xr.Dataset(coords={"omega": omegas, "radiating_dof": dof_names,
                             "influenced_dof": dof_names, "wave_direction": directions})
    for name in ("added_mass", "radiation_damping"):
        values = np.full((omegas.size, len(dof_names), len(dof_names)), np.nan)
        if name in raw:
            da = _str_dofs(_drop_scalar_dims(raw[name]))
            values = da.transpose("omega", "radiating_dof", "influenced_dof").values
        out[name] = (("omega", "radiating_dof", "influenced_dof"), np.asarray(values, float))
    exc = np.full((omegas.size, directions.size, len(dof_names)), np.nan + 0j)
    if regular and "excitation_force" in raw:
        da = _str_dofs(_drop_scalar_dims(raw["excitation_force"]))
        exc = da.transpose("omega", "wave_direction", "influenced_dof").values
    out["excitation_force"] = (("omega", "wave_direction", "influenced_dof"), exc)
    return out


def _drop_scalar_dims(da: xr.DataArray) -> xr.DataArray:
    """Drop Capytaine's length-1 parameter dimensions (rho, g, water_depth...)."""
    keep = ("omega", "radiating_dof", "influenced_dof", "wave_direction")
    return da.isel({d: 0 for d in da.dims if d not in keep}, drop=True)


def _str_dofs(da: xr.DataArray) -> xr.DataArray:
    """Capytaine returns categorical dof coordinates; plain strings serialise to NetCDF."""
    for dim in ("radiating_dof", "influenced_dof"):
        if dim in da.coords:
            da = da.assign_coords({dim: [str(v) for v in da[dim].values]})
    return da


def _fix_low_kh(part, body, dofs, directions, depth, mesh, method, symmetric,
                low_kh) -> xr.Dataset:
    """Re-solve NaN frequencies (finite depth, small kh) with FinGreen3D on the unlidded hull."""
    bad = np.isnan(part["added_mass"]).any(("radiating_dof", "influenced_dof")).values
    omegas = part["omega"].values[bad]
    if low_kh == "drop" or omegas.size == 0:
        return part
    import capytaine as cpt

    hull = body.capytaine_body(dofs, symmetric=symmetric, lid=False, **mesh)
    solver = cpt.BEMSolver(green_function=cpt.FinGreen3D(), method=method)
    directions = np.asarray(part["wave_direction"].values)
    for w in omegas:
        if not (math.isfinite(w) and w > 0):
            continue  # FinGreen3D has no ω = 0 / ∞ limit
        fixed = solve_chunk(solver, hull, np.array([w]), directions=directions, depth=depth,
                             rho=body.rho, g=body.g)
        for name in COEFF_VARS:
            part[name].loc[{"omega": w}] = fixed[name].sel(omega=w)
    return part


def _warn_mesh_resolution(cbody, omegas: np.ndarray, depth: float, g: float) -> None:
    """One warning (instead of Capytaine's per-problem log) when panels exceed λ/8."""
    if omegas.size == 0:
        return
    w = float(np.max(omegas))
    wavelength = 2 * math.pi * g / w**2  # deep-water value: shortest wave of the set
    if wavelength < cbody.minimal_computable_wavelength:
        warnings.warn(f"mesh is coarse for omega up to {w:.3g} rad/s: wavelength "
                      f"{wavelength:.3g} m < 8 x largest panel radius "
                      f"({cbody.minimal_computable_wavelength:.3g} m); high-frequency "
                      "coefficients may be inaccurate", stacklevel=4)
