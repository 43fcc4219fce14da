"""Frequency-domain BEM coefficients with Capytaine, cached and resumable.

:func:`compute` returns the coefficient Dataset of ``docs/DATA_MODEL.md``: added mass A(ω),
radiation damping B(ω), excitation force (Froude–Krylov + diffraction), the limits A(∞) and
A(0), the hydrostatic stiffness and the rigid-body mass.

Any :class:`hybridwsi.bodies.Body` (the paper's sphere, a body of revolution from a profile,
a mesh file, a rigid assembly): the body supplies the Capytaine mesh (its symmetries and lid),
the DOF origin (``reference_point``, written to ``attrs``), the rigid-body mass matrix and the
hydrostatic stiffness. The mesh resolution is a panel size [m] (or a panel count) for every
body; the sphere also keeps its ``(n_theta, n_phi)`` resolution. :func:`plan` checks the
inputs and computes the cache keys without solving.

How the run is organised (and why):

- Frequencies are solved in chunks with ``capytaine.BEMSolver.fill_dataset``; after each chunk
  the solved frequencies are merged into a *store* NetCDF (atomic write) keyed by a SHA-256 of
  every input except the frequency list. A run that is interrupted, or a later run with more
  frequencies of the same configuration, solves only the frequencies that are missing.
  The finished result is also written under a key that includes the frequencies, so repeating
  the same call reads one file and solves nothing.
- Cache folder: ``cache_dir``, else ``$HYBRIDWSI_CACHE/bem``, else ``~/.cache/hybridwsi/bem``.
- BLAS is limited to one thread during the solve (threadpoolctl; else set
  ``OPENBLAS_NUM_THREADS=1`` yourself): multi-threaded OpenBLAS makes Capytaine's symmetric
  block products up to ~30x slower (docs/CAPYTAINE_NOTES.md pitfall 3).
- Default ``method="direct"``: it converges faster with the mesh (A(∞) within 0.01 % of the
  analytic hemisphere value at 6400 panels, pitfall 4).
- The ω = 0 and ω = ∞ limits are Capytaine radiation problems at ``omega=0`` and
  ``omega=np.inf``.
- Finite depth (pitfall 5): Capytaine's default Green function returns NaN for small kh. Those
  frequencies are re-solved with ``FinGreen3D`` on the hull *without* lid (FinGreen3D fails on
  panels lying in the free surface; irregular frequencies are far above these low
  frequencies); ``low_kh="drop"`` drops them instead. Frequencies still NaN are dropped with a
  warning and listed in ``attrs["dropped_omega"]``. A(0) is NaN in finite depth when no Green
  function can evaluate it (warned, flagged).
- Quality checks: NaN values and negative diagonal damping raise a ``UserWarning`` and are
  listed in ``attrs["quality_flags"]`` (JSON); never silent.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import math
import os
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi._meta import package_version, provenance, version
from hybridwsi.bodies import Body, FloatingSphere, check_dofs
from hybridwsi.dofs import force_unit
from hybridwsi.errors import InputError, SolverError
from hybridwsi.files import read_netcdf, to_netcdf
from hybridwsi.hydro.coefficients import pair_units_attr

#: number of frequencies solved between two checkpoints
CHUNK_SIZE = 10
#: default hull panel count (the paper's mesh)
DEFAULT_PANELS = 6400
#: relative tolerance below which a negative diagonal damping is treated as round-off
NEG_DAMPING_RTOL = 1e-6
COEFF_VARS = ("added_mass", "radiation_damping", "excitation_force")


# ---------------------------------------------------------------------------- configurations
def _paper_bem() -> dict[str, Any]:
    from hybridwsi.cases import load_case

    return load_case("paper_sphere")["bem"]


def paper_frequencies() -> np.ndarray:
    """The paper's frequencies [rad/s] (``cases/paper_sphere.toml`` [bem]: 400 log-spaced
    from 0.1 to 40 rad/s)."""
    cfg = _paper_bem()
    return np.geomspace(cfg["omega_min"], cfg["omega_max"], cfg["n_omega"])


def paper_configuration() -> dict[str, Any]:
    """The paper's BEM set-up as keyword arguments of :func:`compute`:
    ``compute(**paper_configuration())`` (R = 0.15 m sphere, m = 7.06 kg, 6400 panels with
    axial symmetry and lid, 400 frequencies 0.1–40 rad/s, infinite depth)."""
    cfg = _paper_bem()
    return {"body": FloatingSphere.paper(), "omega": paper_frequencies(),
            "n_panels": cfg["n_panels"], "water_depth": float(cfg["water_depth"]),
            "method": "direct"}


#: shipped result of ``compute(**paper_configuration())`` (see data/README.md)
PAPER_COEFFS = Path(__file__).resolve().parent.parent / "data" / "bem_paper_sphere.nc"


def paper_coefficients() -> xr.Dataset:
    """The paper configuration's coefficients as shipped with the package (no BEM run).

    Equal to ``compute(**paper_configuration())``; recompute with ``hybridwsi bem``.
    """
    if not PAPER_COEFFS.is_file():
        raise InputError(f"{PAPER_COEFFS} is missing; run `hybridwsi bem --out {PAPER_COEFFS}`")
    return read_netcdf(PAPER_COEFFS)


def _shipped(input_hash: str) -> xr.Dataset | None:
    """A coefficient file shipped in ``hybridwsi/data/bem_*.nc`` made with exactly these inputs
    (the hash of a whole plan or of one of its finite-depth/deep-water parts).

    The paper's configurations take minutes to solve; shipping their results (with the
    command that made them, data/README.md) makes ``hybridwsi reproduce`` fast on a fresh
    machine. A file is used only when its ``input_hash`` (all inputs and versions) matches.
    """
    for path in sorted(PAPER_COEFFS.parent.glob("bem_*.nc")):
        try:
            with xr.open_dataset(path) as f:
                if f.attrs.get("input_hash") != input_hash:
                    continue
        except (OSError, ValueError):
            continue
        return read_netcdf(path)
    return None


def default_cache_dir() -> Path:
    """``$HYBRIDWSI_CACHE/bem`` if that variable is set, else ``~/.cache/hybridwsi/bem``."""
    root = os.environ.get("HYBRIDWSI_CACHE")
    return Path(root).expanduser() / "bem" if root else Path.home() / ".cache" / "hybridwsi" / "bem"


# ---------------------------------------------------------------------------- public API
@dataclass(eq=False)
class Plan:
    """Everything :func:`compute` will do, decided before any solve (see :func:`plan`).

    ``mesh`` and ``low_kh_mesh`` are the body's canonical mesh options
    (:meth:`hybridwsi.bodies.Body.mesh_options`); ``config`` is every input but the frequencies
    (the key of the resumable store, hash ``config_hash``); ``input_hash`` the key of the
    result (``attrs["input_hash"]``). A finite-depth request solved in two parts has
    ``parts = (finite-depth part or None, deep-water part)`` and ``deep_water_kh``.
    """

    body: Body
    omega: np.ndarray
    depth: float
    dofs: tuple[str, ...]
    directions: np.ndarray
    mesh: dict[str, Any]
    low_kh_mesh: dict[str, Any]
    method: str
    symmetric: bool
    lid: bool
    low_kh: str
    include_inf: bool
    include_zero: bool
    config: dict[str, Any]
    config_hash: str
    input_hash: str
    parts: tuple[Plan | None, Plan] | None = None
    deep_water_kh: float | None = None


def plan(
    body: Body,
    omega: Sequence[float] | np.ndarray,
    *,
    water_depth: float = math.inf,
    dofs: Sequence[str] | None = None,
    wave_directions: Sequence[float] = (0.0,),
    panel_size: float | None = None,
    n_panels: int | None = None,
    resolution: tuple[int, int] | int | None = None,
    include_inf: bool = True,
    include_zero: bool = True,
    method: str = "direct",
    symmetric: bool = True,
    lid: bool = True,
    low_kh: str = "fingreen",
    low_kh_panels: int | None = 1600,
    deep_water_kh: float | None = 3.0,
) -> Plan:
    """Check the inputs of :func:`compute` and decide what it solves, without solving.

    Same parameters as :func:`compute` (those that change the result). ``plan(...).input_hash``
    is the ``attrs["input_hash"]`` that ``compute`` writes; the shipped coefficient files are
    used when one of them carries the hash of a plan (or of one of its ``parts``).
    """
    if not isinstance(body, Body):
        raise InputError(f"body must be a hybridwsi.bodies.Body, got {type(body).__name__}")
    omega = _check_omega(omega)
    dofs = check_dofs(body.dofs if dofs is None else dofs)
    directions = _check_directions(wave_directions)
    depth = _check_depth(water_depth, body)
    if method not in ("direct", "indirect"):
        raise InputError(f"method must be 'direct' or 'indirect', got {method!r}")
    if low_kh not in ("fingreen", "drop"):
        raise InputError(f"low_kh must be 'fingreen' or 'drop', got {low_kh!r}")
    # only the sphere knows a (n_theta, n_phi) resolution: other bodies refuse it
    sphere_only = {} if resolution is None else {"resolution": resolution}
    mesh = body.mesh_options(panel_size=panel_size, n_panels=n_panels, **sphere_only)
    if math.isfinite(depth) and deep_water_kh is not None:
        from hybridwsi.waves import dispersion_k

        deep = dispersion_k(omega, depth, body.g) * depth >= float(deep_water_kh)
        if deep.any():
            common = dict(dofs=dofs, wave_directions=directions, method=method,
                          symmetric=symmetric, lid=lid, deep_water_kh=None, **mesh)
            high = plan(body, omega[deep], water_depth=math.inf, include_inf=include_inf,
                        include_zero=False, **common)
            low = (plan(body, omega[~deep], water_depth=depth, include_inf=False,
                        include_zero=include_zero, low_kh=low_kh, low_kh_panels=low_kh_panels,
                        **common)
                   if (~deep).any() else None)
            joined = _sha256([None if low is None else low.input_hash, high.input_hash,
                              float(deep_water_kh)])
            return Plan(body=body, omega=omega, depth=depth, dofs=dofs, directions=directions,
                        mesh=mesh, low_kh_mesh=mesh, method=method, symmetric=symmetric,
                        lid=lid, low_kh=low_kh, include_inf=include_inf,
                        include_zero=include_zero, config={}, config_hash="",
                        input_hash=joined, parts=(low, high),
                        deep_water_kh=float(deep_water_kh))
    # FinGreen3D costs ~10 s per frequency on 6400 panels; the waves it is needed for (kh < 0.13,
    # wavelength > 40 body diameters in 0.9 m) are resolved by a much coarser hull
    low_mesh = mesh
    if math.isfinite(depth) and low_kh_panels is not None:
        try:
            coarse = body.mesh_options(n_panels=int(low_kh_panels))
        except InputError:  # a body whose panels are fixed (a mesh file)
            coarse = mesh
        if body.panel_count(**coarse) < body.panel_count(**mesh):
            low_mesh = coarse

    config = _configuration(body, depth, dofs, directions, mesh, method, symmetric, lid, low_kh)
    if math.isfinite(depth):  # deep water never calls the low-kh fallback: keep its hash
        for key, value in body.mesh_description(**low_mesh).items():
            if key != "kind":  # e.g. the sphere's "low_kh_resolution"
                config["solver"][f"low_kh_{key}"] = value
    input_hash = _sha256({**config, "omega": hashed_frequencies(omega), "include_inf": include_inf,
                          "include_zero": include_zero})
    return Plan(body=body, omega=omega, depth=depth, dofs=dofs, directions=directions,
                mesh=mesh, low_kh_mesh=low_mesh, method=method, symmetric=symmetric, lid=lid,
                low_kh=low_kh, include_inf=include_inf, include_zero=include_zero,
                config=config, config_hash=_sha256(config), input_hash=input_hash)


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
    water_depth : float
        Water depth [m]; ``inf`` for deep water.
    dofs : sequence of str, optional
        Rigid-body degrees of freedom (Capytaine names) about the body's reference point;
        default ``body.dofs`` (the sphere: heave).
    wave_directions : sequence of float
        Incident wave directions [rad] for the excitation force.
    panel_size : float, optional
        Target panel size [m] of the hull (and lid) mesh; for every body but a mesh file,
        whose panels are fixed.
    n_panels : int, optional
        Approximate number of hull panels instead of ``panel_size``.
    resolution : (n_theta, n_phi) or int, optional
        The sphere only: Capytaine ``mesh_sphere`` resolution (full sphere) or a panel count.
        Give at most one of ``panel_size``, ``n_panels``, ``resolution``; none: the body's
        default (the sphere: 6400 hull panels; others about 1000).
    include_inf, include_zero : bool
        Also solve the ω = ∞ / ω = 0 radiation limits (else the variables are NaN).
    method : {"direct", "indirect"}
        Capytaine boundary integral formulation.
    symmetric, lid : bool
        Keep the mesh's symmetries / add a waterplane lid (irregular frequencies).
    low_kh : {"fingreen", "drop"}
        Finite depth: re-solve NaN frequencies with FinGreen3D, or drop them.
    deep_water_kh : float or None
        Finite depth: frequencies with kh ≥ this value (waves that do not feel the bottom;
        tanh 3 = 0.995) and the ω → ∞ limit are solved in deep water. Capytaine's finite-depth
        Green function loses accuracy there (on the 6400-panel sphere in 0.9 m, B is 3 % low at
        12 rad/s and negative above 25 rad/s), while the bottom changes A by < 1 %. None: solve
        every frequency in finite depth.
    low_kh_panels : int or None
        Hull panels for the FinGreen3D re-solves (default 1600, used when coarser than the main
        mesh; None: the main mesh). Those frequencies have waves much longer than the body,
        where a coarse hull is converged.
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
                    use_cache=use_cache, chunk_size=int(chunk_size), n_jobs=_n_jobs(n_jobs))


#: relative excess of weight over buoyancy tolerated before a body is said to sink
SINK_RTOL = 0.01


def warn_if_sinks(body: Body, rtol: float = SINK_RTOL) -> bool:
    """Warn loudly (:class:`UserWarning`) when the body's weight m g [N] exceeds the buoyancy
    ρ g V [N] of its displaced volume at rest by more than ``rtol``: it sinks, so coefficients
    about this draft describe no equilibrium (usually a wrong mass). Returns whether it warned.

    A lighter body is not warned about: a moored floater (a spar, a TLP) carries the
    difference as mooring pretension.
    """
    weight = float(body.mass) * body.g
    buoyancy = body.rho * body.g * float(body.displaced_volume())
    if not weight > buoyancy * (1.0 + rtol):
        return False
    warnings.warn(
        f"THE BODY SINKS: {body.name} weighs m g = {weight:.4g} N but displaces only "
        f"rho g V = {buoyancy:.4g} N at rest (mass {float(body.mass):.4g} kg vs rho V = "
        f"{buoyancy / body.g:.4g} kg, {100 * (weight / buoyancy - 1):.3g} % too heavy); "
        "its coefficients describe no equilibrium: check the mass",
        UserWarning, stacklevel=3)
    return True


def _execute(p: Plan, *, cache_dir, progress: bool, use_cache: bool, chunk_size: int,
             n_jobs: int | None) -> xr.Dataset:
    """Run a :class:`Plan`: cached result, shipped file, or solve the missing frequencies."""
    run = dict(cache_dir=cache_dir, progress=progress, use_cache=use_cache,
               chunk_size=chunk_size, n_jobs=n_jobs)
    if p.parts is not None:
        # a result solved in two parts may be shipped as one file of the joined result
        whole = _shipped(p.input_hash) if use_cache else None
        if whole is not None:
            for flag in json.loads(whole.attrs.get("quality_flags", "[]")):
                warnings.warn(f"BEM coefficients (shipped): {flag}", stacklevel=3)
            return whole
        low, high = p.parts
        return _join_depths(None if low is None else _execute(low, **run), _execute(high, **run),
                            p.depth, p.deep_water_kh, p.input_hash)
    root = Path(cache_dir).expanduser() if cache_dir is not None else default_cache_dir()
    final_path = root / f"coeffs_{p.input_hash[:24]}.nc"
    store_path = root / f"store_{p.config_hash[:24]}.nc"

    if use_cache and not final_path.is_file():
        shipped = _shipped(p.input_hash)
        if shipped is not None:
            to_netcdf(shipped, final_path)  # seed the cache: later calls take the usual path
    if use_cache and final_path.is_file():
        cached = _read_cache(final_path)
        if cached is not None and cached.attrs.get("input_hash") == p.input_hash:
            for flag in json.loads(cached.attrs.get("quality_flags", "[]")):
                warnings.warn(f"BEM coefficients (cached): {flag}", stacklevel=3)
            return cached

    limits = [w for w, on in ((0.0, p.include_zero), (math.inf, p.include_inf)) if on]
    store = _read_cache(store_path) if use_cache and store_path.is_file() else None
    todo = _missing(np.concatenate([p.omega, limits]), store)
    if todo.size:
        store = _solve_missing(p, todo, store, store_path if use_cache else None,
                               progress=progress, chunk_size=chunk_size, n_jobs=n_jobs)
    ds = _assemble(store, p)
    if use_cache:
        to_netcdf(ds, final_path)
    return ds


# ---------------------------------------------------------------------------- input checks
def _check_omega(omega: Any) -> np.ndarray:
    try:
        w = np.atleast_1d(np.asarray(omega, dtype=float))
    except (TypeError, ValueError):
        raise InputError("omega must be a list of numbers [rad/s]") from None
    if w.ndim != 1 or w.size == 0:
        raise InputError(f"omega must be a non-empty 1-D list of frequencies, got shape {w.shape}")
    if not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise InputError("omega must be finite and > 0 rad/s (the 0 and inf limits are "
                         "include_zero/include_inf)")
    w = np.sort(w)
    if np.any(np.diff(w) <= 1e-12 * w[1:]):
        raise InputError("omega contains duplicated frequencies")
    return w


def _check_directions(directions: Any) -> np.ndarray:
    d = np.atleast_1d(np.asarray(directions, dtype=float))
    if d.ndim != 1 or d.size == 0 or not np.all(np.isfinite(d)):
        raise InputError("wave_directions must be a non-empty list of finite angles [rad]")
    if np.unique(d).size != d.size:
        raise InputError("wave_directions contains duplicates")
    return d


def _check_depth(depth: Any, body: Body) -> float:
    try:
        h = float(depth)
    except (TypeError, ValueError):
        raise InputError(f"water_depth must be a number or inf, got {depth!r}") from None
    if math.isnan(h) or h <= 0:
        raise InputError(f"water_depth must be > 0 (or inf), got {depth!r}")
    if math.isfinite(h) and h <= body.draft:
        raise InputError(f"water_depth {h} m must exceed the body draft {body.draft} m")
    return h


# ---------------------------------------------------------------------------- hashing/cache
def _configuration(body: Body, depth, dofs, directions, mesh: dict, method, symmetric, lid,
                   low_kh) -> dict[str, Any]:
    """Every input except the frequencies (key of the resumable store): the body's
    ``to_dict()`` and ``mesh_description()`` (for the paper's sphere exactly the keys of the
    sphere-only code, so the shipped coefficients stay valid)."""
    return {
        "body": body.to_dict(), "water_depth": depth if math.isfinite(depth) else "inf",
        "dofs": list(dofs), "wave_directions": directions.tolist(),
        "mesh": {**body.mesh_description(**mesh), "symmetric": symmetric, "lid": lid},
        "solver": {"method": method, "green_function": "Delhommeau", "low_kh": low_kh},
        "versions": provenance("capytaine"),
    }


def hashed_frequencies(omega: np.ndarray) -> list[float]:
    """The frequencies [rad/s] as the input hash sees them: 10 significant digits.

    ``np.geomspace`` differs in the last bit between CPUs (NumPy's SIMD ``log``/``exp``: 28 of
    the paper's 400 frequencies on an AMD EPYC against the machine that shipped the files), and
    a bit-exact key then misses the shipped coefficients and re-solves them."""
    return [float(f"{w:.10g}") for w in np.asarray(omega, dtype=float)]


def _sha256(obj: Any) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True).encode()).hexdigest()


def _read_cache(path: Path) -> xr.Dataset | None:
    """A cache file, or None (with a warning) when it cannot be read: it is then recomputed."""
    try:
        return read_netcdf(path)
    except InputError as exc:
        warnings.warn(f"ignoring unreadable BEM cache file ({exc})", stacklevel=3)
        return None


def _missing(wanted: np.ndarray, store: xr.Dataset | None) -> np.ndarray:
    """Frequencies (incl. 0/inf) of ``wanted`` not yet in ``store``."""
    if store is None:
        return wanted
    done = np.asarray(store["omega"].values, dtype=float)
    return np.array([w for w in wanted if not np.any(_same(done, w))], dtype=float)


def _same(a: np.ndarray, w: float) -> np.ndarray:
    return (a == w) | (np.isfinite(a) & np.isclose(a, w, rtol=1e-12, atol=0.0))


# ---------------------------------------------------------------------------- solving
def _n_jobs(n_jobs: int | None) -> int | None:
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
def _quiet_capytaine():
    """Silence Capytaine's per-problem "Skipped ..." log lines: the frequencies it skips (low kh
    in finite depth) are re-solved or dropped below, with our own single warning."""
    logger = logging.getLogger("capytaine")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)


def _solve_missing(p: Plan, todo, store, store_path, *, progress, chunk_size, n_jobs=None
                   ) -> xr.Dataset:
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
        store = part if store is None else _merge(store, part)
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
    with blas_single_thread(), warnings.catch_warnings(), _quiet_capytaine():
        warnings.simplefilter("ignore", RuntimeWarning)  # NaN handled explicitly below
        part = _solve_chunk(solver, cbody, chunk, directions=directions, depth=depth,
                            rho=body.rho, g=body.g)
        if math.isfinite(depth):
            part = _fix_low_kh(part, body, list(dofs), directions, depth, low_mesh, method,
                               symmetric, low_kh)
    return part


def _solve_chunk(solver, cbody, omegas: np.ndarray, *, directions: np.ndarray, depth: float,
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
        fixed = _solve_chunk(solver, hull, np.array([w]), directions=directions, depth=depth,
                             rho=body.rho, g=body.g)
        for name in COEFF_VARS:
            part[name].loc[{"omega": w}] = fixed[name].sel(omega=w)
    return part


def _merge(store: xr.Dataset, part: xr.Dataset) -> xr.Dataset:
    keep = ~np.isin(store["omega"].values, part["omega"].values)
    return xr.concat([store.isel(omega=keep), part], dim="omega").sortby("omega")


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


# ---------------------------------------------------------------------------- assembly
def _assemble(store: xr.Dataset, p: Plan) -> xr.Dataset:
    omega, dofs, body = p.omega, p.dofs, p.body
    w_store = store["omega"].values
    idx = [int(np.flatnonzero(_same(w_store, w))[0]) for w in omega]
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


def _join_depths(low: xr.Dataset | None, high: xr.Dataset, depth: float,
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
