"""Parameter sweeps of Cummins runs on Dask (``dask.distributed``), resumable.

A sweep is a grid of cases (significant wave height Hs [m] x peak period Tp [s] x seed).
Each case runs on a Dask worker and writes its own NetCDF part ``parts/<case_id>.nc``
atomically, so a killed sweep resumes by skipping the cases whose part exists. When every
case is done the parts are consolidated into one chunked Zarr store ``sweep.zarr`` with a
``case`` dimension (one chunk per case) plus ``manifest.json`` (inputs, version, case table).

The manifest records, from the start, a hash of the settings every case shares
(:func:`settings_hash`: the :class:`SweepConfig`, the content of the coefficient file and the
runner); resuming with other settings is refused, so a store never mixes cases of two set-ups.
The store is built in a temporary ``.sweep.*`` folder and renamed into place; such folders
left by a run killed while consolidating are removed when the next run starts.

Two set-ups:

- the paper sphere (no ``case``): heave only, the shipped or given coefficients, optionally the
  exact sphere buoyancy (:func:`cummins_case`);
- a case, built-in or a TOML file (``SweepConfig.for_case("oc3_hywind")``; :func:`case_sea`):
  the case's coefficients (its ``[bem]`` table; the shipped file when the inputs match), DOFs
  (default the case's ``default_dofs``) and force components, each recorded in the history
  with the line tensions (:mod:`hybridwsi.casemodel`: the mooring as the case's model or
  ``mooring``, Morison drag with the wave particle velocity, additional linear damping,
  rotor), defaults from the case's ``[sweep]`` table. Everything the seas share
  (coefficients, radiation state-space fit, mooring table) is one
  :class:`~hybridwsi.casemodel.CaseModel` built ONCE on the client (:func:`case_setup`) and
  shipped to the workers (OC3: 0.43 MB, of which the table 0.31 MB, pickled and unpickled in
  ~3 ms; tabulating costs 0.6-1.2 s of MoorPy solves).

Runners are plain top-level functions ``runner(case: dict, config: dict) -> TimeHistory`` so
that they pickle to workers; :func:`default_runner` picks one from the configuration. The
manifest also holds per-case motion statistics (:func:`sea_statistics`: mean, std, min, max per
DOF after the ramp, 4 std(eta), the line tensions' mean, std and max per line) and the library
versions.
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import json
import logging
import math
import os
import pickle
import shutil
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi import bodies, cummins, waves
from hybridwsi._meta import version
from hybridwsi.casemodel import CaseModel, case_coefficients, radiation_ss
from hybridwsi.cases import case_path, is_builtin, load_case
from hybridwsi.dofs import check_dofs, motion_unit
from hybridwsi.errors import InputError, SolverError
from hybridwsi.history import atomic_write, check_compatible, read_netcdf, to_netcdf
from hybridwsi.hydro import bem

Runner = Callable[[dict, dict], xr.Dataset]
PARTS = "parts"
STORE = "sweep.zarr"
MANIFEST = "manifest.json"
#: prefix of the temporary folders a store is built in
PARTIAL_PREFIX = ".sweep."
#: ``run_sweep(scheduler=...)`` value that runs the cases in this process, without Dask
SYNCHRONOUS = "synchronous"
#: how long to try reaching a ``--scheduler`` before refusing it
CONNECT_TIMEOUT = "10s"


@dataclass
class SweepConfig:
    """What every case shares.

    Parameters
    ----------
    duration, dt : float
        Simulated time and time step [s].
    coeffs : str or None
        NetCDF of BEM coefficients (``hydro.bem.compute`` output); None = the paper sphere's
        shipped coefficients (:func:`load_coefficients`), or with ``case`` the case's own.
    mass : float or None
        Rigid-body mass [kg]; None = the coefficients' ``mass`` (sphere only).
    nonlinear_hydrostatics : bool
        Exact wetted-volume restoring force of the paper sphere instead of ``-C z`` (so the
        residual ``F_tot - (-C z)`` is not linear in the motion); sphere only.
    ramp : float
        Half-cosine ramp [s] of the wave excitation (and of the drag's wave velocity).
    case : str or None
        A case: a built-in name (``hybridwsi.cases``, e.g. ``"oc3_hywind"``) or a TOML file;
        its coefficients, DOFs and force components (:mod:`hybridwsi.casemodel`); None = the
        paper sphere.
    dofs : tuple of str or None
        DOFs to simulate; None = the case's ``default_dofs`` (sphere: Heave, the only choice).
    gamma : float or None
        JONSWAP peak enhancement γ; None = 3.3 (:class:`hybridwsi.waves.JONSWAP`).
    wave_components : int or None
        Number of JONSWAP components; None = 200. The sea repeats after 2π/Δω
        (Δω = 3.5 ωp / n: ~570 s at Tp 10 s with 200).
    wave_kinematics : bool or None
        With ``case``: the Morison drag sees the wave particle velocity (None = yes).
    mooring : str or None
        With ``case``: the mooring model (``table``, ``quasi-static``, ``moordyn``) instead of
        the case's ``[forces] mooring``.
    overrides : dict or None
        With ``case``: entries of its tables replaced, ``{table: {key: value}}``
        (:func:`hybridwsi.cases.with_values`; ``--rotor``, ``--wind-speed``,
        ``--turbulence-intensity``, ``--wind-seed``, ``--slow-drift``).

    The fields from ``case`` on are left out of :func:`settings` while None, so a sphere sweep
    started by an earlier version keeps its settings hash and can be resumed.
    """

    duration: float = 60.0
    dt: float = 0.01
    coeffs: str | None = None
    mass: float | None = None
    nonlinear_hydrostatics: bool = False
    ramp: float = 2.0
    case: str | None = None
    dofs: tuple[str, ...] | None = None
    gamma: float | None = None
    wave_components: int | None = None
    wave_kinematics: bool | None = None
    mooring: str | None = None
    overrides: dict | None = None

    def __post_init__(self) -> None:
        if self.dofs is not None:  # one spelling, a tuple (a TOML list or "surge,pitch")
            self.dofs = check_dofs(self.dofs)

    @classmethod
    def for_case(cls, name: str, **options: Any) -> SweepConfig:
        """The configuration of a case (a built-in name or a TOML file): its ``[sweep]``
        table (:data:`CASE_SWEEP_KEYS`, checked by the case schema) and ``default_dofs``,
        overridden by the ``options`` that are not None."""
        spec = load_case(name)
        table = spec.get("sweep", {})
        given = {k: v for k, v in options.items() if v is not None}
        merged = {**table, **given}
        if merged.get("dofs") is None and spec.get("default_dofs"):
            merged["dofs"] = spec["default_dofs"]
        return cls(case=name, **merged)

    def check(self) -> None:
        if not (self.duration > 0 and self.dt > 0 and self.dt < self.duration):
            raise InputError(f"need 0 < dt < duration, got dt={self.dt}, duration={self.duration}")
        if self.ramp < 0:
            raise InputError(f"ramp must be >= 0 s, got {self.ramp}")
        if self.coeffs is not None and not Path(self.coeffs).is_file():
            raise InputError(f"coefficient file not found: {self.coeffs}")
        if self.gamma is not None and not (math.isfinite(self.gamma) and self.gamma >= 1):
            raise InputError(f"JONSWAP gamma must be >= 1, got {self.gamma}")
        if self.wave_components is not None and not int(self.wave_components) >= 1:
            raise InputError(f"wave_components must be >= 1, got {self.wave_components}")
        if self.case is None:
            if self.dofs is not None and tuple(self.dofs) != SPHERE_DOFS:
                raise InputError(f"the sphere sweep simulates {', '.join(SPHERE_DOFS)} only; "
                                 "use a case (--case) or 'hybridwsi simulate --dofs'")
            if self.wave_kinematics is not None:
                raise InputError("wave kinematics belong to a case's Morison drag (--case)")
            if self.mooring is not None:
                raise InputError("a mooring model (--mooring) needs a case with a mooring "
                                 "(--case)")
            if self.overrides:
                raise InputError("--rotor, --wind-speed, --turbulence-intensity, --wind-seed "
                                 "and --slow-drift change a case (--case)")
            return
        if self.mass is not None:
            raise InputError("a case's body gives its mass matrix; do not give a mass with it")
        if self.nonlinear_hydrostatics:
            raise InputError("nonlinear hydrostatics are the paper sphere's (no case)")


#: the DOFs of the sphere sweep (:func:`cummins_case`)
SPHERE_DOFS = ("Heave",)
#: keys a case's ``[sweep]`` table may set (defaults of :meth:`SweepConfig.for_case`)
CASE_SWEEP_KEYS = ("duration", "dt", "ramp", "dofs", "gamma", "wave_components",
                   "wave_kinematics")
#: SweepConfig fields left out of the settings while None (added with cases)
_OPTIONAL_FIELDS = ("case", "dofs", "gamma", "wave_components", "wave_kinematics", "mooring",
                    "overrides")


def case_grid(hs: Sequence[float], tp: Sequence[float], seeds: int | Sequence[int]) -> list[dict]:
    """The cases of a Hs x Tp x seed grid, each ``{"case_id", "hs", "tp", "seed"}``.

    ``case_id`` is derived from the values (not the position), so adding grid points later does
    not rename finished cases.
    """
    hs, tp = [float(h) for h in hs], [float(t) for t in tp]
    seed_list = list(range(int(seeds))) if np.ndim(seeds) == 0 else [int(s) for s in seeds]
    if not hs or not tp or not seed_list:
        raise InputError("a sweep needs at least one Hs, one Tp and one seed")
    if min(hs) <= 0 or min(tp) <= 0:
        raise InputError("Hs and Tp must be positive")
    return [
        {"case_id": f"hs{h:.4g}_tp{t:.4g}_s{s}", "hs": h, "tp": t, "seed": s}
        for h, t, s in itertools.product(hs, tp, seed_list)
    ]


# ------------------------------------------------------------------------------- runners
def load_coefficients(path: str | os.PathLike | None = None) -> xr.Dataset:
    """The coefficients a sweep runs with: the NetCDF at ``path``, or with None the paper
    sphere's, as shipped with the package (``hydro.bem.paper_coefficients``; no BEM run)."""
    if path:
        return read_netcdf(path)
    return bem.paper_coefficients()


def sea(case: dict, config: dict) -> Any:
    """The JONSWAP sea of one case (Hs, Tp, seed) with the configuration's γ and components."""
    options = {k: config[key] for k, key in (("gamma", "gamma"), ("n_components",
               "wave_components")) if config.get(key) is not None}
    return waves.JONSWAP(hs=case["hs"], tp=case["tp"], seed=int(case["seed"]), **options)


def cummins_case(case: dict, config: dict) -> xr.Dataset:
    """One irregular-sea Cummins run of the paper sphere (JONSWAP Hs, Tp, seed) -> TimeHistory
    with ``eta``."""
    coeffs = config.get("_coeffs")
    if coeffs is None:
        coeffs = load_coefficients(config.get("coeffs"))
    nonlinear = bool(config.get("nonlinear_hydrostatics", False))
    return cummins.simulate(
        coeffs, mass=config.get("mass"), duration=float(config["duration"]),
        dt=float(config["dt"]), ramp=float(config.get("ramp", 0.0)), wave=sea(case, config),
        nonlinear_hydrostatics=nonlinear, radiation_ss=config.get("_radiation_ss"),
        body=bodies.FloatingSphere.paper() if nonlinear else None,
    )


def sweep_coefficients(manifest: dict) -> xr.Dataset:
    """The coefficients a sweep ran with, from its ``manifest.json`` (parsed): the file it
    was given, else its case's (:func:`~hybridwsi.casemodel.case_coefficients`), else the
    paper sphere's."""
    cfg = manifest.get("config", {})
    if cfg.get("coeffs"):
        return load_coefficients(cfg["coeffs"])
    if cfg.get("case"):
        return case_coefficients(load_case(cfg["case"]))
    return load_coefficients()


def case_setup(config: SweepConfig) -> dict:
    """What every sea of a case sweep shares, built once (on the client) and shipped:
    ``{"_model": CaseModel}`` (coefficients, DOFs, mooring model and table, radiation state
    space fitted for the sweep's dt)."""
    return {"_model": CaseModel.build(str(config.case), dofs=config.dofs, coeffs=config.coeffs,
                                      mooring=config.mooring, dt=config.dt,
                                      overrides=config.overrides)}


def _public(config: dict) -> SweepConfig:
    """The :class:`SweepConfig` of a worker's config dict (the shipped ``_`` entries dropped)."""
    return SweepConfig(**{k: v for k, v in config.items() if not k.startswith("_")})


def case_sea(case: dict, config: dict) -> xr.Dataset:
    """One irregular-sea Cummins run of a case -> TimeHistory with ``eta``, every force
    component and the line tensions (:meth:`hybridwsi.casemodel.CaseModel.simulate`).

    The shared model comes from ``config`` (:func:`case_setup`, shipped by :func:`run_sweep`)
    or is built here when absent.
    """
    shared = config if "_model" in config else case_setup(_public(config))
    return shared["_model"].simulate(
        duration=float(config["duration"]), dt=float(config["dt"]), wave=sea(case, config),
        ramp=float(config.get("ramp", 0.0)),
        wave_kinematics=config.get("wave_kinematics") is not False)  # None: yes


def default_runner(config: SweepConfig) -> Runner:
    """:func:`case_sea` for a case, else :func:`cummins_case` (the paper sphere)."""
    return case_sea if config.case else cummins_case


def shared_objects(config: SweepConfig, runner: Runner) -> dict:
    """The objects the default runners would otherwise rebuild per case (coefficients,
    radiation state space, mooring table), built once; {} for another runner."""
    if runner is case_sea:
        return case_setup(config)
    if runner is cummins_case:
        coeffs = load_coefficients(config.coeffs)
        return {"_coeffs": coeffs,
                "_radiation_ss": radiation_ss(coeffs, SPHERE_DOFS, config.mass, config.dt)}
    return {}


# ------------------------------------------------------------------------- worker side
def _part_path(out: Path, case_id: str) -> Path:
    return out / PARTS / f"{case_id}.nc"


def run_one(case: dict, config: dict, out: str, runner: Runner) -> dict:
    """Run one case and write its part atomically (worker entry point)."""
    path = _part_path(Path(out), case["case_id"])
    if path.is_file():
        return {"case_id": case["case_id"], "status": "skipped"}
    hist = runner(case, config)
    hist = hist.assign_attrs(case=json.dumps(case), hybridwsi_version=version())
    to_netcdf(hist, path)
    return {"case_id": case["case_id"], "status": "done"}


# ------------------------------------------------------------------------- client side
def _client(scheduler: str | None, n_workers: int):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError("sweeps need Dask: pip install 'hybridwsi[sweep]'") from None
    if scheduler:
        try:
            return Client(scheduler, timeout=CONNECT_TIMEOUT), None
        except OSError as exc:
            raise InputError(f"cannot connect to the Dask scheduler {scheduler}: {exc}") from None
    # CRITICAL only: a failing case is reported once, as a line of the final error, not
    # as the worker's "Compute Failed" traceback on the console
    cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=logging.CRITICAL)
    return Client(cluster), cluster


def _file_digest(path: str | os.PathLike) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def settings(config: SweepConfig, runner: Runner | None = None, shared: dict | None = None
             ) -> dict:
    """What every case of a sweep shares, as plain values: the configuration, the SHA-256 of
    the coefficient file's content (a file replaced in place changes the set-up) and the
    runner's qualified name. The case list is not part of it (a grid may be extended).

    With a case also (:func:`case_settings`): the SHA-256 of the case's content, the
    coefficients' input hash, the DOFs simulated, every force component (its description) and
    the mooring model and table's input hash. ``shared``: :func:`case_setup` of ``config`` if
    already built (else built here, ~3 s for OC3-Hywind).
    """
    runner = default_runner(config) if runner is None else runner
    cfg = asdict(config)
    for key in _OPTIONAL_FIELDS:  # absent while unset: the settings of sphere sweeps as before
        if cfg[key] is None:
            del cfg[key]
    if config.coeffs:  # the same file from another working directory is the same set-up
        cfg["coeffs"] = str(Path(config.coeffs).resolve())
    if config.case and not is_builtin(config.case):  # a user's file, from any folder
        cfg["case"] = str(case_path(config.case).resolve())
    cfg["coeffs_sha256"] = _file_digest(config.coeffs) if config.coeffs else None
    cfg["runner"] = f"{getattr(runner, '__module__', '?')}.{getattr(runner, '__qualname__', runner)}"
    if config.case:
        cfg.update(case_settings(case_setup(config) if shared is None else shared))
    return cfg


def case_settings(shared: dict) -> dict:
    """The set-up of a case sweep as plain values (:meth:`CaseModel.settings` of
    :func:`case_setup`)."""
    return shared["_model"].settings()


def _digest(current: dict) -> str:
    return hashlib.sha256(json.dumps(current, sort_keys=True, default=str).encode()).hexdigest()


def settings_hash(config: SweepConfig, runner: Runner | None = None) -> str:
    """SHA-256 of :func:`settings` (stored in the manifest, compared on resume)."""
    return _digest(settings(config, runner))


def check_resume(out: str | os.PathLike, current: dict) -> None:
    """Refuse to resume a sweep in ``out`` whose manifest records other settings.

    ``current`` is :func:`settings` of the run about to start. Raises :class:`InputError` (one
    line naming the settings that differ) when ``out`` holds finished parts and its manifest
    is missing, unreadable, older than settings hashes, or records different settings.
    """
    out = Path(out)
    try:
        meta = json.loads((out / MANIFEST).read_text())
        stored = meta["settings"]
        stored_hash = meta["settings_hash"]
    except (OSError, ValueError, KeyError, TypeError):
        raise InputError(f"{out} holds finished cases but no readable manifest with their "
                         "settings: cannot resume safely; choose a new --out") from None
    if stored_hash != _digest(current):
        diff = [k for k in sorted(set(stored) | set(current)) if stored.get(k) != current.get(k)]
        shown = ", ".join(f"{k} {stored.get(k)!r} -> {current.get(k)!r}" for k in diff[:4])
        raise InputError(f"cannot resume the sweep in {out}: its settings differ ({shown or 'hash'}"
                         "); use the same settings or a new --out")


def clean_partials(out: str | os.PathLike) -> int:
    """Remove ``.sweep.*`` folders a killed consolidation left in ``out``; return how many."""
    out = Path(out)
    stale = [p for p in out.glob(PARTIAL_PREFIX + "*") if p.is_dir()] if out.is_dir() else []
    for p in stale:
        shutil.rmtree(p, ignore_errors=True)
    return len(stale)


def finished_cases(out: str | os.PathLike) -> set[str]:
    """Case ids whose part file exists in ``out/parts``."""
    d = Path(out) / PARTS
    return {p.stem for p in d.glob("*.nc")} if d.is_dir() else set()


def run_sweep(
    cases: Sequence[dict],
    out: str | os.PathLike,
    config: SweepConfig | None = None,
    *,
    runner: Runner | None = None,
    scheduler: str | None = None,
    n_workers: int = 2,
    resume: bool = True,
    progress: bool = True,
    consolidate_store: bool = True,
) -> Path:
    """Run every case on Dask, one atomic part per case, then consolidate.

    Parameters
    ----------
    cases : sequence of dict
        From :func:`case_grid` (each needs a unique ``case_id``).
    out : path
        Output folder (``parts/``, ``sweep.zarr``, ``manifest.json``).
    config : SweepConfig
        Shared settings (duration, dt, coefficients, case, DOFs, sea options).
    runner : callable, optional
        ``runner(case, config_dict) -> TimeHistory``, picklable; default
        :func:`default_runner` (the sphere's :func:`cummins_case` or a case's :func:`case_sea`).
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``); ``"synchronous"`` runs the
        cases one after the other in this process (no Dask; for debugging and tests); default
        a LocalCluster of ``n_workers`` processes with one thread each.
    resume : bool
        Skip cases already written; with False an existing non-empty ``parts/`` is an error
        (delete it or pass ``resume=True``). Resuming with settings other than those in the
        manifest (:func:`settings_hash`) is an error too.

    Returns
    -------
    Path
        The consolidated Zarr store (or the parts folder when ``consolidate_store=False``).
    """
    config = config or SweepConfig()
    config.check()
    runner = default_runner(config) if runner is None else runner
    out = Path(out)
    ids = [c["case_id"] for c in cases]
    if len(set(ids)) != len(ids):
        raise InputError("case ids are not unique")
    done = finished_cases(out)
    if done and not resume:
        raise InputError(f"{out / PARTS} already holds {len(done)} finished case(s); "
                         "pass --resume to continue that sweep or choose a new --out")
    # a case's shared objects enter its settings, so they are built before the resume check
    shared = shared_objects(config, runner) if config.case else None
    current = settings(config, runner, shared)
    if done:
        check_resume(out, current)
    todo = [c for c in cases if c["case_id"] not in done]
    # folders this run creates (``out`` and missing parents): removed if no case finishes
    fresh = [p for p in (out, *out.parents) if not p.exists()]
    # the Dask client first: an unreachable scheduler is one line with nothing written
    with _connected(scheduler if todo else SYNCHRONOUS, n_workers) as client:
        _start(out, cases, current)
        try:
            failures = _run_cases(todo, config, shared, out, runner, client, len(cases),
                                  progress)
        except BaseException:
            _forget_empty(out, fresh)
            raise
    if failures:
        if _forget_empty(out, fresh):
            raise SolverError("every case failed, nothing was written: " + "; ".join(
                failures[:3]))
        raise SolverError(f"{len(failures)} case(s) failed (re-run with --resume to retry): "
                          + "; ".join(failures[:3]))
    if not consolidate_store:
        return out / PARTS
    path = consolidate(out, ids)
    _write_manifest(out, cases, current, status="complete",
                    statistics=sea_statistics(open_sweep(path), start=config.ramp))
    return path


def _start(out: Path, cases: Sequence[dict], current: dict) -> None:
    """``parts/`` ready (half-written parts and stores of a killed run removed) and the
    manifest written with status "running"."""
    (out / PARTS).mkdir(parents=True, exist_ok=True)
    for stale in (out / PARTS).glob(".*.tmp"):
        stale.unlink(missing_ok=True)
    clean_partials(out)
    _write_manifest(out, cases, current, status="running")


def _forget_empty(out: Path, fresh: Sequence[Path]) -> bool:
    """Remove what a sweep that finished no case wrote (its "running" manifest, the empty
    ``parts/``, the ``fresh`` folders this run created, deepest first); True if it did. A
    sweep with finished parts keeps them and its manifest, for ``--resume``."""
    if finished_cases(out):
        return False
    (out / MANIFEST).unlink(missing_ok=True)
    for folder in (out / PARTS, *fresh):
        try:
            folder.rmdir()  # only when empty: never a file someone else put there
        except OSError:
            pass
    return True


@contextlib.contextmanager
def _connected(scheduler: str | None, n_workers: int):
    """The Dask client of :func:`_client` (``None`` for ``"synchronous"``), closed after."""
    if scheduler == SYNCHRONOUS:
        yield None
        return
    client, cluster = _client(scheduler, n_workers)
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


@contextlib.contextmanager
def _progress(total: int, initial: int, progress: bool):
    """A tqdm bar over cases, cleared from the console when the run fails (so the error
    line that follows stands alone)."""
    from tqdm.auto import tqdm

    bar = tqdm(total=total, initial=initial, desc="sweep", unit="case", disable=not progress)
    try:
        yield bar
    except BaseException:
        bar.leave = False
        raise
    finally:
        bar.close()


def _run_cases(todo: Sequence[dict], config: SweepConfig, shared: dict | None, out: Path,
               runner: Runner, client: Any, n_total: int, progress: bool) -> list[str]:
    """Run ``todo`` on ``client`` (``None``: in this process); return the failures as
    one-line texts (the other cases still run)."""
    failures: list[str] = []
    if not todo:
        return failures
    # load/compute and fit once, ship to the workers
    shared = shared_objects(config, runner) if shared is None else shared
    cfg = {**asdict(config), **shared}
    with _progress(n_total, n_total - len(todo), progress) as bar:
        if client is None:
            # run on what a worker would receive: unpickled arrays are contiguous copies, and
            # BLAS rounds a strided view (e.g. the state-space matrices) differently at
            # 1e-16, so this keeps the in-process numbers bit-identical to the workers'
            cfg = pickle.loads(pickle.dumps(cfg))
            for c in todo:
                try:
                    run_one(c, cfg, str(out), runner)
                except Exception as exc:  # keep going; report all failed cases at the end
                    failures.append(f"case-{c['case_id']}: {type(exc).__name__}: {exc}")
                bar.update(1)
            bar.leave = not failures  # the error line that follows stands alone
            return failures
        from distributed import as_completed

        cfg_f = client.scatter(cfg, broadcast=True)
        futures = [client.submit(run_one, c, cfg_f, str(out), runner, key=f"case-{c['case_id']}",
                                 pure=False) for c in todo]
        for fut in as_completed(futures):
            try:
                fut.result()
            except Exception as exc:  # keep going; report all failed cases at the end
                failures.append(f"{fut.key}: {type(exc).__name__}: {exc}")
            bar.update(1)
        bar.leave = not failures  # the error line that follows stands alone
    return failures


def sea_statistics(sweep: xr.Dataset, start: float = 0.0) -> dict:
    """Per-case motion statistics of a consolidated sweep, from ``start`` [s] on (after the
    ramp, so the start-up transient of the excitation is left out).

    Returns
    -------
    dict
        ``{"window_s": [start, end], "cases": {case_id: {dof: {"mean", "std", "min", "max",
        "unit"}, "eta": {"std", "hs_4std"}, "T_fairlead": {line: {"mean", "std", "max"}},
        "T_anchor": ...}}}`` in m or rad per DOF, N per line; ``hs_4std`` = 4 std(η) [m], the
        significant wave height the sea actually had at the wave probe.
    """
    t = sweep["time"].values
    keep = t >= start - 1e-9 * max(1.0, abs(start))
    if not keep.any():
        raise InputError(f"no samples after {start} s to summarise")
    z = sweep["z"].isel(time=np.flatnonzero(keep))
    stats = {name: getattr(z, name)("time").transpose("case", "dof").values
             for name in ("mean", "std", "min", "max")}
    eta = None
    if "eta" in sweep:
        e = sweep["eta"].isel(time=np.flatnonzero(keep))
        eta = e.std("time").transpose("case", ...).values.reshape(e.sizes["case"], -1)[:, 0]
    dofs = [str(d) for d in sweep["dof"].values]
    tensions = {var: _line_statistics(sweep[var].isel(time=np.flatnonzero(keep)))
                for var in ("T_fairlead", "T_anchor") if var in sweep}
    cases = {}
    for i, cid in enumerate(str(c) for c in sweep["case"].values):
        row: dict[str, Any] = {
            d: {**{k: float(v[i, j]) for k, v in stats.items()}, "unit": motion_unit(d)}
            for j, d in enumerate(dofs)}
        if eta is not None:
            row["eta"] = {"std": float(eta[i]), "hs_4std": float(4.0 * eta[i]), "unit": "m"}
        row.update({var: values[i] for var, values in tensions.items()})
        cases[cid] = row
    return {"window_s": [float(t[keep][0]), float(t[-1])], "cases": cases}


def _line_statistics(tension: xr.DataArray) -> list[dict[str, Any]]:
    """Per case: ``{line: {"mean", "std", "max", "unit"}}`` of a tension [N]."""
    stats = {name: getattr(tension, name)("time").transpose("case", "line").values
             for name in ("mean", "std", "max")}
    lines = [str(v) for v in tension["line"].values]
    return [{line: {**{k: float(v[i, j]) for k, v in stats.items()}, "unit": "N"}
             for j, line in enumerate(lines)} for i in range(tension.sizes["case"])]


def _write_manifest(out: Path, cases: Sequence[dict], current: dict, status: str,
                    statistics: dict | None = None) -> None:
    config = {k: v for k, v in current.items() if k not in ("coeffs_sha256", "runner")}
    inputs = {k: current[k] for k in ("case", "case_sha256", "coeffs", "coeffs_sha256",
                                      "coeffs_hash", "dofs", "forces", "models",
                                      "mooring_table") if k in current}
    meta = {"hybridwsi_version": version(), "versions": library_versions(), "status": status,
            "inputs": inputs, "config": config, "settings": current,
            "settings_hash": _digest(current), "n_cases": len(cases), "cases": list(cases)}
    if statistics is not None:
        meta["statistics"] = statistics
    text = json.dumps(meta, indent=1, default=str)
    atomic_write(out / MANIFEST, lambda tmp: Path(tmp).write_text(text))


def library_versions() -> dict[str, str | None]:
    """Versions of the libraries a sweep's numbers depend on (None: not installed)."""
    from importlib import metadata

    out: dict[str, str | None] = {"hybridwsi": version()}
    for name in ("numpy", "scipy", "xarray", "dask", "distributed", "zarr", "moorpy",
                 "capytaine"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def consolidate(out: str | os.PathLike, case_ids: Sequence[str] | None = None) -> Path:
    """Concatenate the parts along a ``case`` dimension into ``out/sweep.zarr`` (atomic).

    Histories must share the time axis and variables. The store is written to a temporary
    folder and renamed into place, so a crash never leaves a half store.
    """
    out = Path(out)
    clean_partials(out)
    ids = sorted(finished_cases(out)) if case_ids is None else list(case_ids)
    missing = [c for c in ids if not _part_path(out, c).is_file()]
    if missing:
        raise InputError(f"{len(missing)} case(s) not finished yet (e.g. {missing[0]}); resume the sweep")
    parts, cases = [], []
    for cid in ids:
        ds = read_netcdf(_part_path(out, cid))
        cases.append(json.loads(ds.attrs.get("case", json.dumps({"case_id": cid}))))
        parts.append(ds.drop_attrs() if hasattr(ds, "drop_attrs") else ds)
    check_compatible(parts)  # one dt, one body: a store is one set-up
    try:
        big = xr.concat(parts, dim="case", data_vars="all", coords="minimal",
                        compat="override", join="exact")
    except ValueError as exc:
        raise InputError(f"sweep parts do not share a time axis: {exc}") from None
    big = big.assign_coords(case=ids)
    for key in ("hs", "tp", "seed"):
        if all(key in c for c in cases):
            big = big.assign_coords({key: ("case", [c[key] for c in cases])})
    big.attrs = {"hybridwsi_version": version(), "source": "hybridwsi.sweep",
                 "inputs": json.dumps({"cases": cases}, default=str)}
    big = big.chunk({"case": 1})
    target = out / STORE
    tmp = Path(tempfile.mkdtemp(prefix=PARTIAL_PREFIX, dir=out))
    try:
        big.to_zarr(tmp / STORE, mode="w", consolidated=True, zarr_format=2)
        if target.exists():  # move the old store aside (renames only: never no store + no new)
            os.replace(target, tmp / "previous")
        os.replace(tmp / STORE, target)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return target


def open_sweep(path: str | os.PathLike) -> xr.Dataset:
    """Open a consolidated sweep (folder or ``sweep.zarr``) lazily."""
    path = Path(path)
    store = path / STORE if (path / STORE).exists() else path
    if not store.exists():
        raise InputError(f"no sweep store at {store}")
    return xr.open_zarr(store, consolidated=True)


def case_history(sweep: xr.Dataset, case: str | int) -> xr.Dataset:
    """One case of a sweep as a plain TimeHistory (loaded)."""
    sel = sweep.isel(case=case) if isinstance(case, int) else sweep.sel(case=case)
    ds = sel.load()
    return ds.drop_vars([c for c in ("case", "hs", "tp", "seed") if c in ds.coords])
