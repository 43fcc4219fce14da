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

Runners are plain top-level functions ``runner(case: dict, config: dict) -> TimeHistory`` so
that they pickle to workers; :func:`cummins_case` is the default.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import os
import shutil
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi._meta import version
from hybridwsi.errors import InputError, SolverError
from hybridwsi.history import atomic_write, check_compatible, read_netcdf, to_netcdf

Runner = Callable[[dict, dict], xr.Dataset]
PARTS = "parts"
STORE = "sweep.zarr"
MANIFEST = "manifest.json"
#: prefix of the temporary folders a store is built in
PARTIAL_PREFIX = ".sweep."


@dataclass
class SweepConfig:
    """What every case shares.

    Parameters
    ----------
    duration, dt : float
        Simulated time and time step [s].
    coeffs : str or None
        NetCDF of BEM coefficients (``hydro.bem.compute`` output); None = the paper sphere's
        shipped coefficients (:func:`load_coefficients`).
    mass : float or None
        Rigid-body mass [kg]; None = the coefficients' ``mass``.
    nonlinear_hydrostatics : bool
        Exact wetted-volume restoring force of the paper sphere instead of ``-C z`` (so the
        residual ``F_tot - (-C z)`` is not linear in the motion).
    ramp : float
        Half-cosine ramp [s] of the wave excitation.
    """

    duration: float = 60.0
    dt: float = 0.01
    coeffs: str | None = None
    mass: float | None = None
    nonlinear_hydrostatics: bool = False
    ramp: float = 2.0

    def check(self) -> None:
        if not (self.duration > 0 and self.dt > 0 and self.dt < self.duration):
            raise InputError(f"need 0 < dt < duration, got dt={self.dt}, duration={self.duration}")
        if self.ramp < 0:
            raise InputError(f"ramp must be >= 0 s, got {self.ramp}")
        if self.coeffs is not None and not Path(self.coeffs).is_file():
            raise InputError(f"coefficient file not found: {self.coeffs}")


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


# ------------------------------------------------------------------------ default runner
def load_coefficients(path: str | os.PathLike | None = None) -> xr.Dataset:
    """The coefficients a sweep runs with: the NetCDF at ``path``, or with None the paper
    sphere's, as shipped with the package (``hydro.bem.paper_coefficients``; no BEM run)."""
    if path:
        return read_netcdf(path)
    from hybridwsi.hydro import bem

    return bem.paper_coefficients()


def cummins_case(case: dict, config: dict) -> xr.Dataset:
    """One irregular-sea Cummins run (JONSWAP Hs, Tp, seed) -> TimeHistory with ``eta``."""
    from hybridwsi import bodies, cummins, waves

    coeffs = config.get("_coeffs")
    if coeffs is None:
        coeffs = load_coefficients(config.get("coeffs"))
    nonlinear = bool(config.get("nonlinear_hydrostatics", False))
    return cummins.simulate(
        coeffs, mass=config.get("mass"), duration=float(config["duration"]),
        dt=float(config["dt"]), ramp=float(config.get("ramp", 0.0)),
        wave=waves.JONSWAP(hs=case["hs"], tp=case["tp"], seed=int(case["seed"])),
        nonlinear_hydrostatics=nonlinear, radiation_ss=config.get("_radiation_ss"),
        body=bodies.FloatingSphere.paper() if nonlinear else None,
    )


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
            return Client(scheduler, timeout="10s"), None
        except OSError as exc:
            raise InputError(f"cannot connect to the Dask scheduler {scheduler}: {exc}") from None
    cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=40)
    return Client(cluster), cluster


def _file_digest(path: str | os.PathLike) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def settings(config: SweepConfig, runner: Runner | None = None) -> dict:
    """What every case of a sweep shares, as plain values: the configuration, the SHA-256 of
    the coefficient file's content (a file replaced in place changes the set-up) and the
    runner's qualified name. The case list is not part of it (a grid may be extended)."""
    runner = cummins_case if runner is None else runner
    cfg = asdict(config)
    if config.coeffs:  # the same file from another working directory is the same set-up
        cfg["coeffs"] = str(Path(config.coeffs).resolve())
    cfg["coeffs_sha256"] = _file_digest(config.coeffs) if config.coeffs else None
    cfg["runner"] = f"{getattr(runner, '__module__', '?')}.{getattr(runner, '__qualname__', runner)}"
    return cfg


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
    runner: Runner = cummins_case,
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
        Shared settings (duration, dt, coefficients, nonlinearity).
    runner : callable
        ``runner(case, config_dict) -> TimeHistory``, picklable.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``); default a LocalCluster of
        ``n_workers`` processes with one thread each.
    resume : bool
        Skip cases already written; with False an existing non-empty ``parts/`` is an error
        (delete it or pass ``resume=True``). Resuming with settings other than those in the
        manifest (:func:`settings_hash`) is an error too.

    Returns
    -------
    Path
        The consolidated Zarr store (or the parts folder when ``consolidate_store=False``).
    """
    from tqdm.auto import tqdm

    config = config or SweepConfig()
    config.check()
    out = Path(out)
    ids = [c["case_id"] for c in cases]
    if len(set(ids)) != len(ids):
        raise InputError("case ids are not unique")
    done = finished_cases(out)
    if done and not resume:
        raise InputError(f"{out / PARTS} already holds {len(done)} finished case(s); "
                         "pass --resume to continue that sweep or choose a new --out")
    current = settings(config, runner)
    if done:
        check_resume(out, current)
    todo = [c for c in cases if c["case_id"] not in done]
    (out / PARTS).mkdir(parents=True, exist_ok=True)
    for stale in (out / PARTS).glob(".*.tmp"):  # half-written parts of a killed run
        stale.unlink(missing_ok=True)
    clean_partials(out)
    _write_manifest(out, cases, current, status="running")
    cfg = asdict(config)
    failures: list[str] = []
    if todo:
        client, cluster = _client(scheduler, n_workers)
        try:
            if runner is cummins_case:  # load/compute and fit once, ship to the workers
                from hybridwsi import cummins

                cfg["_coeffs"] = load_coefficients(cfg.get("coeffs"))
                import inspect

                # the fit simulate() itself would make (same tolerance), done once
                tol = inspect.signature(cummins.simulate).parameters["ss_tol"].default
                cfg["_radiation_ss"] = cummins.build_system(
                    cfg["_coeffs"], mass=config.mass, radiation="statespace", dt=config.dt,
                    ss_tol=tol).ss
            cfg_f = client.scatter(cfg, broadcast=True)
            futures = [client.submit(run_one, c, cfg_f, str(out), runner, key=f"case-{c['case_id']}",
                                     pure=False) for c in todo]
            from distributed import as_completed

            bar = tqdm(total=len(cases), initial=len(cases) - len(todo), desc="sweep",
                       unit="case", disable=not progress)
            for fut in as_completed(futures):
                try:
                    fut.result()
                except Exception as exc:  # keep going; report all failed cases at the end
                    failures.append(f"{fut.key}: {type(exc).__name__}: {exc}")
                bar.update(1)
            bar.close()
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    if failures:
        raise SolverError(f"{len(failures)} case(s) failed (re-run with --resume to retry): "
                          + "; ".join(failures[:3]))
    if not consolidate_store:
        return out / PARTS
    path = consolidate(out, ids)
    _write_manifest(out, cases, current, status="complete")
    return path


def _write_manifest(out: Path, cases: Sequence[dict], current: dict, status: str) -> None:
    config = {k: v for k, v in current.items() if k not in ("coeffs_sha256", "runner")}
    meta = {"hybridwsi_version": version(), "status": status, "config": config,
            "settings": current, "settings_hash": _digest(current),
            "n_cases": len(cases), "cases": list(cases)}
    text = json.dumps(meta, indent=1, default=str)
    atomic_write(out / MANIFEST, lambda tmp: Path(tmp).write_text(text))


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
