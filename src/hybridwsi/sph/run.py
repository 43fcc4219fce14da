"""Driver of the SPH wave tank: equations, time loop, progress, checkpoints, resume, output.

``run_case(case, out)`` advances a :class:`~hybridwsi.sph.tank.SPHCase` with PySPH's PEC
integrator at a fixed time step, samples the body and probes every ``case.output_dt`` and
returns (and atomically writes) a TimeHistory. Checkpoints hold every particle property and
constant plus the samples so far; a resumed run continues bit-for-bit where the interrupted
one stopped (fixed dt, accelerations restored, no re-evaluation at restart).
"""

from __future__ import annotations

import json
import os
import time as _time
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError, SolverError
from hybridwsi.history import atomic_write, make_history, to_netcdf
from hybridwsi.sph.mdbc import body_boundary_post
from hybridwsi.sph.symmetry import mirror_domain, n_real, reflect_crossers, remove_ghosts
from hybridwsi.sph.tank import SPHCase, free_surface

CHECKPOINT_VERSION = 2  # 2: real particles only (no mirror ghosts)

# OpenMP threads that wait at the end of a parallel loop sleep instead of spinning. On a shared
# machine a spinning thread holds a core the other thread (or another job) needs; every
# parallel loop then waits for a descheduled thread: the 2D benchmark with 2 threads ran
# 1.5e5 particle-updates/s spinning against 1.0e6 sleeping while another job used one core
# (docs/SPH_RUNS.md, "Engine speed"). libgomp reads it when PySPH first loads it, so this
# must run before ``pysph.base.nnps`` is imported; a value the user set is kept.
os.environ.setdefault("OMP_WAIT_POLICY", "passive")


def make_equations(case: SPHCase) -> list:
    """The equation groups shared by all cases (parameter values differ, code does not).

    Groups are named: PySPH otherwise numbers them with a process-wide counter that ends up in
    the generated source, so a second case in the same process would be recompiled (~1 min).
    """
    from pysph.sph.basic_equations import XSPHCorrection
    from pysph.sph.equation import Group
    from pysph.sph.wc.basic import TaitEOS

    from hybridwsi.sph.equations import (
        AdvectionVelocity,
        BodyForceReduce,
        DampingZone,
        FluidRates,
        GravityRamp,
        HoldRelaxation,
        WallForce,
        WallPressureAdami,
    )

    gx, gy, gz = case.gvec
    grav = {"gx": gx, "gy": gy, "gz": gz, "t_ramp": case.t_ramp}
    x0, x1, sigma = case.damping
    alpha_wall = case.alpha if case.alpha_wall is None else case.alpha_wall
    alpha_body = alpha_wall if case.alpha_body is None else case.alpha_body
    return [
        Group(equations=[TaitEOS("fluid", None, rho0=case.rho0, c0=case.c0, gamma=case.gamma)],
              real=False, name="eos"),
        # mDBC: the body particles' density is then overwritten from their mirror nodes
        Group(equations=[WallPressureAdami("wall", ["fluid"], rho0=case.rho0, c0=case.c0,
                                           gamma=case.gamma, **grav)], real=False,
              name="wall_bc", post=body_boundary_post(case) if case.boundary == "mdbc"
              else None),
        Group(equations=[
            # continuity + density diffusion + momentum in one pass per source array
            FluidRates("fluid", ["fluid"], c0=case.c0, alpha=case.alpha, delta=case.delta,
                       rho0=case.rho0, **grav),
            # fluid-solid pairs take their own viscosity and no density diffusion
            FluidRates("fluid", ["wall"], c0=case.c0, alpha=alpha_wall, delta=0.0,
                       rho0=case.rho0, alpha_body=alpha_body, **grav),
            GravityRamp("fluid", None, **grav),
            HoldRelaxation("fluid", None),
            DampingZone("fluid", None, x0=x0, x1=x1, sigma_max=sigma,
                        radial=int(case.damping_radial), dim=case.dim),
            # the integrator moves particles with (ax, ay, az): XSPH, or the velocity itself
            XSPHCorrection("fluid", ["fluid"], eps=case.xsph_eps) if case.xsph_eps
            else AdvectionVelocity("fluid", None),
            WallForce("wall", ["fluid"], alpha=alpha_body),  # on the body's particles only
        ], name="rates"),
        Group(equations=[BodyForceReduce("wall", None)], name="body"),
    ]


def make_solver(case: SPHCase, openmp: bool = False):
    """Compile (or load from PySPH's cache) and set up a PySPH Solver for ``case``."""
    from compyle.config import get_config
    from pysph.base.kernels import WendlandQuintic
    from pysph.base.nnps import LinkedListNNPS
    from pysph.solver.solver import Solver
    from pysph.sph.integrator import PECIntegrator
    from pysph.sph.integrator_step import WCSPHStep

    from hybridwsi.sph.equations import WallStep

    get_config().use_openmp = bool(openmp)
    kernel = WendlandQuintic(dim=case.dim)
    integrator = PECIntegrator(fluid=WCSPHStep(), wall=WallStep())
    solver = Solver(dim=case.dim, integrator=integrator, kernel=kernel, dt=case.dt, tf=case.tf)
    solver.set_disable_output(True)
    solver.set_parallel_manager(None)  # serial run (what Application does without MPI)
    particles = [case.fluid, case.wall]
    # mirror ghosts within two kernel supports of each symmetry plane (see symmetry.py)
    domain = mirror_domain(case.mirror, 2.0 * kernel.radius_scale * case.h)
    nnps = LinkedListNNPS(dim=case.dim, particles=particles, radius_scale=kernel.radius_scale,
                          fixed_h=True, domain=domain)
    solver.setup(particles=particles, equations=make_equations(case), nnps=nnps,
                 kernel=kernel, fixed_h=True)
    if case.mirror:
        def keep_on_real_side(t: float, dt: float, stage: int) -> None:
            # after the corrector only (the predictor's x0, u0 must stay consistent); the
            # ghosts were made before the move, so make them again if anything moved
            if stage == 2 and reflect_crossers(case.fluid, case.mirror):
                nnps.update_domain()

        solver.add_post_stage_callback(keep_on_real_side)
    return solver


# --------------------------------------------------------------------------- sampling
def _sample(case: SPHCase, t: float) -> dict[str, Any]:
    b = case.wall.body
    row: dict[str, Any] = {"time": t, "z": b[0], "zdot": b[1], "zddot": b[2],
                           "F_tot": b[6], "F_fluid": b[5]}
    row["eta"] = [free_surface(case.fluid, x, case.dp, case.dim, y) - case.depth
                  for x, y in case.probes]
    for name, fn in case.monitors.items():
        row[name] = fn(case.fluid, case.wall)
    return row


def _rows_to_arrays(rows: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    if not rows:
        return {}
    return {k: np.asarray([r[k] for r in rows], dtype=float) for k in rows[0]}


def _arrays_to_rows(arrs: dict[str, np.ndarray]) -> list[dict[str, Any]]:
    if not arrs:
        return []
    n = len(arrs["time"])
    return [{k: (v[i].tolist() if v.ndim > 1 else float(v[i])) for k, v in arrs.items()}
            for i in range(n)]


def history_from_rows(case: SPHCase, rows: list[dict[str, Any]]) -> xr.Dataset:
    """Build the TimeHistory (z, zdot, zddot, F_tot, F_fluid, eta(time, probe), monitors)."""
    a = _rows_to_arrays(rows)
    hold_force = None
    if case.t_release > 0.0 and a:
        # the hold phase is the set-up, not the record: keep its mean static force [N]
        # (second half, after the start-up transient) and start the history at the release
        t = a["time"]
        late_hold = (t >= 0.5 * case.t_release) & (t < case.t_release - 1e-9)
        if np.any(late_hold):
            hold_force = float(np.mean(a["F_tot"][late_hold]))
        keep = t >= case.t_release - 1e-9
        a = {k: v[keep] for k, v in a.items()}
        a["time"] = a["time"] - case.t_release
    if case.body_mass is None:
        # no floating body: the body constants hold placeholders, report zeros
        for k in ("z", "zdot", "zddot", "F_tot", "F_fluid"):
            a[k] = np.zeros_like(a["time"])
    import pysph

    inputs = dict(case.inputs, dt=case.dt, c0=case.c0, h=case.h, alpha=case.alpha,
                  t_release_actual=case.t_release,
                  delta=case.delta, n_particles=case.n_particles, engine="PySPH",
                  engine_version=pysph.__version__)
    ds = make_history(a["time"], a["z"], a["zdot"], a["zddot"],
                      forces={"F_tot": a["F_tot"], "F_fluid": a["F_fluid"]},
                      dof=["Heave"], mass=case.body_mass, source=f"hybridwsi.sph:{case.name}",
                      inputs=inputs, check=len(a["time"]) >= 8)
    ds["zddot"].attrs["note"] = "body acceleration at the last force evaluation (mid-step)"
    if hold_force is not None:
        ds["F_tot"].attrs["hold_mean"] = hold_force
        ds["F_tot"].attrs["hold_note"] = (
            "mean F_tot [N] over the second half of the hold before release; the exact "
            "hydrostatic value is the restoring force at the release height")
    if case.body_mass is None:
        ds.attrs["note"] = "no floating body in this case: z, zdot, zddot, forces are zero"
    if case.probes:
        ds["eta"] = (("time", "probe"), np.atleast_2d(a["eta"]).reshape(len(a["time"]), -1),
                     {"units": "m", "long_name": "free-surface elevation at probes"})
        ds = ds.assign_coords(probe_x=("probe", [p[0] for p in case.probes], {"units": "m"}))
    for name in case.monitors:
        ds[name] = ("time", a[name], {"long_name": name})
    return ds


# --------------------------------------------------------------------------- checkpoints
def _inputs_key(case: SPHCase) -> str:
    return json.dumps(case.inputs, sort_keys=True, default=str)


def write_checkpoint(path: Path, case: SPHCase, count: int, rows: list[dict[str, Any]]) -> None:
    """Atomically save every particle property/constant, the step count and the samples."""
    data: dict[str, np.ndarray] = {"_count": np.array(count), "_version": np.array(
        CHECKPOINT_VERSION), "_inputs": np.array(_inputs_key(case))}
    for pa in (case.fluid, case.wall):
        name = pa.name
        n = n_real(pa)  # mirror ghosts are remade from the real particles on resume
        for prop in pa.properties:
            data[f"{name}/p/{prop}"] = pa.get(prop)[:n * pa.stride.get(prop, 1)]
        for const in pa.constants:
            data[f"{name}/c/{const}"] = np.array(getattr(pa, const))
    for k, v in _rows_to_arrays(rows).items():
        data[f"rows/{k}"] = v

    def writer(tmp: str) -> None:
        with open(tmp, "wb") as fh:
            np.savez(fh, **data)

    atomic_write(path, writer)


def read_checkpoint(path: Path, case: SPHCase) -> tuple[int, list[dict[str, Any]]]:
    """Load a checkpoint into ``case``'s arrays; return (step count, samples so far).

    Mirror ghosts are removed first; the caller remakes them (``nnps.update_domain()``)."""
    try:
        with np.load(path, allow_pickle=False) as f:
            data = {k: f[k] for k in f.files}
    except Exception as exc:  # noqa: BLE001 - zip/npz errors come in many types
        raise InputError(f"cannot read checkpoint {path}: {exc}") from None
    if str(data["_inputs"]) != _inputs_key(case):
        raise InputError(f"checkpoint {path} was written for other inputs; delete it or "
                         "run with the same options")
    remove_ghosts(case.fluid, case.wall)
    for pa in (case.fluid, case.wall):
        n = pa.get_number_of_particles()
        for prop in pa.properties:
            arr = data[f"{pa.name}/p/{prop}"]
            if arr.shape[0] != n:
                raise InputError(f"checkpoint {path} has {arr.shape[0]} '{pa.name}' "
                                 f"particles, the case has {n}")
            getattr(pa, prop)[:] = arr
        for const in pa.constants:
            key = f"{pa.name}/c/{const}"
            if key in data:  # checkpoints from before the relaxation have no ``relax``
                getattr(pa, const)[:] = data[key]
    rows = _arrays_to_rows({k[5:]: v for k, v in data.items() if k.startswith("rows/")})
    return int(data["_count"]), rows


# --------------------------------------------------------------------------- relaxation
def fluid_urms(fluid: Any) -> float:
    """Root-mean-square speed [m/s] of the real fluid particles."""
    n = n_real(fluid)
    return float(np.sqrt(np.mean(fluid.u[:n] ** 2 + fluid.v[:n] ** 2 + fluid.w[:n] ** 2)))


def _set_release(case: SPHCase, t_release: float, tf_after: float) -> None:
    """Release the body (and end the fluid's relaxation) at ``t_release`` [s], an output
    sample; the run then lasts ``tf_after`` [s] beyond it. As at construction, the body is
    free from the force evaluation half a step before the release sample."""
    from hybridwsi.sph.equations import B_TREL

    case.t_release = t_release
    case.tf = tf_after + t_release
    case.wall.body[B_TREL] = t_release - 0.75 * case.dt
    case.fluid.relax[1] = t_release


# --------------------------------------------------------------------------- driver
def _start(case: SPHCase, solver: Any, ckpt: Path | None, relaxing: bool, tf_after: float
           ) -> tuple[int, list[dict]]:
    """Steps done and samples so far: restored from the checkpoint ``ckpt`` when it exists,
    else a fresh start (the first sample at t = 0, PEC's initial accelerations)."""
    dt = case.dt
    if ckpt is not None and ckpt.is_file():
        count, rows = read_checkpoint(ckpt, case)
        solver.nnps.update_domain()  # the mirror ghosts of the restored particles
        if relaxing:  # the release time the interrupted run had chosen (body[B_TREL])
            _set_release(case, round((case.wall.body[16] + 0.75 * dt) / dt) * dt, tf_after)
        return count, rows
    if relaxing:
        case.fluid.relax[:] = [case.relax_sigma, case.t_release]
    # PEC uses the accelerations of the previous evaluation in its predictor
    solver.integrator.initial_acceleration(0.0, dt)
    return 0, [_sample(case, 0.0)]


def run_case(case: SPHCase, out: str | os.PathLike | None = None, *,
             checkpoint: str | os.PathLike | None = None, checkpoint_every: float = 120.0,
             resume: bool = False, progress: bool = True, openmp: bool = False,
             stop_after_steps: int | None = None) -> xr.Dataset:
    """Run an SPH case and return its TimeHistory.

    Parameters
    ----------
    case : SPHCase
        From :func:`hybridwsi.sph.tank.build`.
    out : path, optional
        NetCDF file written atomically at the end.
    checkpoint : path, optional
        Checkpoint file (default ``<out>.ckpt.npz`` when ``out`` is given).
    checkpoint_every : float
        Wall-clock interval between checkpoints [s].
    resume : bool
        Continue from the checkpoint when it exists.
    progress : bool
        Show a tqdm progress bar (simulated time).
    openmp : bool
        Compile with OpenMP (threads from ``OMP_NUM_THREADS``).
    stop_after_steps : int, optional
        Stop (after writing a checkpoint) once this many steps are done; for tests of resume.
        The returned history then holds the samples so far and ``out`` is not written.
    """
    from tqdm.auto import tqdm

    dt = case.dt
    nsub = max(1, round(case.output_dt / dt))
    if checkpoint is None and out is not None:
        checkpoint = Path(str(out) + ".ckpt.npz")
    ckpt = Path(checkpoint) if checkpoint is not None else None
    solver = make_solver(case, openmp=openmp)
    integ = solver.integrator
    relaxing = case.relax_urms > 0.0 and case.t_release > 0.0
    tf_after = case.tf - case.t_release
    count, rows = _start(case, solver, ckpt if resume else None, relaxing, tf_after)
    n_total = round(case.tf / dt)
    last_ckpt = _time.monotonic()
    bar = tqdm(total=n_total, initial=count, disable=not progress, unit="step",
               desc=f"SPH {case.name} ({case.n_particles} particles)", mininterval=1.0)
    try:
        while count < n_total:
            if stop_after_steps is not None and count >= stop_after_steps:
                break
            integ.step(count * dt, dt)
            count += 1
            if count % nsub == 0:
                rows.append(_sample(case, count * dt))
                if not np.isfinite(rows[-1]["F_tot"]) or not np.all(np.isfinite(case.fluid.rho)):
                    raise SolverError(f"SPH run {case.name} diverged at t = {count * dt:.4g} s")
                # not before one acoustic period: the fluid starts at rest and its jitter
                # (~5e-3 sqrt(g d) undamped) builds up over the first one
                if (relaxing and case.relax_tmin <= count * dt < case.fluid.relax[1] - 0.5 * dt
                        and fluid_urms(case.fluid) < case.relax_urms):
                    # at rest: release at the next sample (PEC's release needs a step ahead)
                    _set_release(case, (count + nsub) * dt, tf_after)
                    n_total = round(case.tf / dt)
                    bar.total = n_total
            bar.update(1)
            if ckpt is not None and _time.monotonic() - last_ckpt > checkpoint_every:
                write_checkpoint(ckpt, case, count, rows)
                last_ckpt = _time.monotonic()
    except KeyboardInterrupt:
        if ckpt is not None:
            write_checkpoint(ckpt, case, count, rows)
        raise
    finally:
        bar.close()
    if ckpt is not None:
        write_checkpoint(ckpt, case, count, rows)
    hist = history_from_rows(case, rows)
    if out is not None and count >= n_total:
        to_netcdf(hist, out)
    return hist
