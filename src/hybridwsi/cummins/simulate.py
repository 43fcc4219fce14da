"""``simulate`` and ``simulate_batch``: one Cummins run (or many) → TimeHistory Dataset.

    (M + A∞) z̈ + ∫_0^t K(t − τ) ż(τ) dτ + C z = F_exc(t) + Σ_k F_k(t, z, ż, x_k)

The history carries ``z, zdot, zddot`` and the forces ``F_hs`` (−C z, or the exact hydrostatic
force), ``F_rad_inf`` (−A∞ z̈), ``F_rad_mem`` (−∫K ż), ``F_exc`` (waves), ``F_ext`` (the sum of
the ``forces`` components) and ``F_tot`` = their sum, so that ``M z̈ = F_tot`` to round-off;
and the matrices ``mass``, ``added_mass_inf``, ``hydrostatic_stiffness`` as ``(dof, dof_j)``
variables (``M[i influenced, j radiating]``, units per DOF pair) so that the diagnostic reads
them from the history, plus the radiation state space in ``attrs["radiation_ss"]``.
Units per DOF: m / rad, N / N m (``attrs["units_per_dof"]``).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import scipy.linalg
import xarray as xr

from hybridwsi._meta import version as _version
from hybridwsi.cummins.forcing import (
    as_wave,
    elevation_attrs,
    excitation,
    split_components,
    time_forcing,
    time_grid,
)
from hybridwsi.cummins.result import SolverResult
from hybridwsi.cummins.solvers import CumminsIntegrator, integrator_for
from hybridwsi.cummins.system import CumminsSystem, build_system
from hybridwsi.errors import InputError, SolverError
from hybridwsi.forces import ExactHydrostatic, KnownComponent, summed_linear_coefficients
from hybridwsi.history import make_history, units_attrs
from hybridwsi.hydro.coefficients import pair_units_attr, unit_matrix
from hybridwsi.hydro.statespace import RadiationSS
from hybridwsi.waves import Wave

FORCES = ("F_tot", "F_hs", "F_rad_inf", "F_rad_mem", "F_exc", "F_ext")
#: the system matrices a history carries, with their attribute on CumminsSystem
MATRICES = {"mass": "mass", "added_mass_inf": "added_mass_inf",
            "hydrostatic_stiffness": "stiffness"}


def coeffs_hash(coeffs: xr.Dataset) -> str:
    """The coefficients' ``input_hash`` attribute, or a SHA-1 of their numerical content."""
    if coeffs.attrs.get("input_hash"):
        return str(coeffs.attrs["input_hash"])
    h = hashlib.sha1()
    for name in sorted(map(str, coeffs.data_vars)):
        h.update(name.encode())
        h.update(np.ascontiguousarray(coeffs[name].values).tobytes())
    return h.hexdigest()


def _vector(value: Any, n: int, name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float).reshape(-1)
    if arr.size == 1:
        arr = np.full(n, arr[0])
    if arr.size != n or not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be a finite scalar or a length-{n} vector")
    return arr


def simulate(coeffs: xr.Dataset, *, mass: float | np.ndarray | None = None, body: Any = None,
             dofs: Sequence[str] = ("Heave",), duration: float, dt: float,
             wave: Wave | Mapping | None = None, z0: float | Sequence[float] = 0.0,
             zdot0: float | Sequence[float] = 0.0, forces: Sequence[KnownComponent] = (),
             radiation: str = "statespace", nonlinear_hydrostatics: bool = False,
             ramp: float = 0.0, irf: xr.DataArray | None = None,
             radiation_ss: RadiationSS | None = None, ss_order: int | None = None,
             ss_tol: float = 0.005, irf_t_max: float | None = None, progress: bool = False
             ) -> xr.Dataset:
    """Integrate the Cummins equation and return a TimeHistory.

    Parameters
    ----------
    coeffs : xarray.Dataset
        Coefficient Dataset (``hydro.bem.compute`` or an imported file): ``added_mass_inf``,
        ``hydrostatic_stiffness``, ``radiation_damping`` (unless ``radiation="none"``),
        ``excitation_force`` (with waves), ``mass`` (unless ``mass`` is given).
    mass : float or ndarray, optional
        Rigid-body mass matrix (n, n) [kg, kg m, kg m²]; default ``coeffs["mass"]``.
    body : Body, optional
        The body, for ``nonlinear_hydrostatics`` (``restoring_force(q, dofs)`` and
        ``exact_restoring_dofs``, or ``buoyancy_force(z)`` for heave); recorded in ``inputs``.
    dofs : sequence of str
        Degrees of freedom (``Surge`` … ``Yaw``), any subset of the coefficients' DOFs.
    duration, dt : float
        Simulated time and output/integration step [s].
    wave : Wave or dict, optional
        Incident wave (:mod:`hybridwsi.waves`); its excitation force is ``F_exc``.
    z0, zdot0 : float or sequence
        Initial displacement [m, rad] and velocity [m/s, rad/s] per DOF.
    forces : sequence of KnownComponent
        Further forces on the right-hand side (``F_ext`` is their sum), e.g.
        :class:`~hybridwsi.forces.ConstantForce`, :class:`~hybridwsi.forces.PrescribedForce`
        ``.from_series``, :class:`~hybridwsi.forces.LinearDamping`,
        :class:`~hybridwsi.forces.QuadraticDamping`. Time-only ones keep the exact linear
        solver; a state-dependent one (or one with internal states) selects the RK4 solver
        (``radiation`` "statespace" or "none").
    radiation : {"statespace", "convolution", "none"}
        Memory-term evaluation (:mod:`hybridwsi.cummins.solvers`).
    nonlinear_hydrostatics : bool
        Exact hydrostatic force of ``body`` (:class:`~hybridwsi.forces.ExactHydrostatic`) on
        the DOFs the body can do exactly, linear ``−C z`` on the others (RK4 solver).
    ramp : float
        Duration [s] of the half-cosine ramp on the wave excitation.
    irf, radiation_ss, ss_order, ss_tol, irf_t_max
        Precomputed kernel K [N/m/s per DOF pair] or state-space model, and the fit's options
        (:func:`~hybridwsi.cummins.system.build_system`; default tolerance 0.5 %: a higher
        order costs almost nothing here and keeps the RAO error < 0.5 %).
    progress : bool
        Show a tqdm progress bar for the stepping solvers.

    Returns
    -------
    xarray.Dataset
        TimeHistory (see the module doc) with ``eta(time, probe)`` [m] when ``wave`` is given.
    """
    t = time_grid(duration, dt)
    wave = as_wave(wave)
    timed, stateful = split_components(forces)
    integ = integrator_for(radiation, state_forces=nonlinear_hydrostatics or bool(stateful))
    if nonlinear_hydrostatics and body is None:
        raise InputError("nonlinear_hydrostatics needs body= (a body with restoring_force(q, "
                         "dofs), or buoyancy_force(z), e.g. hybridwsi.bodies.FloatingSphere)")
    sys = build_system(coeffs, dofs=dofs, mass=mass, radiation=radiation, dt=dt, irf=irf,
                       radiation_ss=radiation_ss, ss_order=ss_order, ss_tol=ss_tol,
                       irf_t_max=irf_t_max)
    z0v, v0v = _vector(z0, sys.n, "z0"), _vector(zdot0, sys.n, "zdot0")
    f_exc, eta = excitation(wave, coeffs, t, sys.dofs, ramp)
    f_ext = time_forcing(timed, t, sys.n)
    options, extra_mass = _state_options(integ, sys, body if nonlinear_hydrostatics else None,
                                         stateful)
    u = _solver_forcing(integ, wave, coeffs, timed, t, sys, ramp, f_exc, f_ext)
    sol = integ.solve(sys, u, z0v, v0v, dt, progress=progress, **options).raise_on_failure()
    if "F_components" in sol.forces:  # the state-dependent components' force
        f_ext = f_ext + sol.forces["F_components"]
    inputs = _inputs(coeffs, sys, duration=duration, dt=dt, wave=wave, z0=z0v, zdot0=v0v,
                     forces=[c.describe() for c in (*timed, *stateful)], radiation=radiation,
                     ramp=ramp, nonlinear_hydrostatics=nonlinear_hydrostatics, body=body)
    return _history(sys, t, sol.z, sol.v, _restoring_force(sys, sol), sol.forces["F_rad_mem"],
                    f_exc, f_ext, eta, inputs, extra_mass)


def _state_options(integ: CumminsIntegrator, sys: CumminsSystem, body: Any,
                   stateful: Sequence[KnownComponent]
                   ) -> tuple[dict[str, Any], np.ndarray | None]:
    """Options of an integrator that takes state-dependent forces (``restoring``: the exact
    hydrostatic force of ``body`` when given, ``components``, ``meff``) and the components'
    acceleration coefficient (their ``ode_force`` leaves out ``−A_k z̈``), or ``({}, None)``."""
    if not integ.state_forces:
        return {}, None
    hs = ExactHydrostatic(body, sys.dofs, sys.stiffness) if body is not None else None
    extra_mass = summed_linear_coefficients(stateful, sys.n)[0] if stateful else None
    meff = sys.mass + sys.added_mass_inf
    if extra_mass is not None and np.any(extra_mass):
        meff = meff + extra_mass
    return {"restoring": None if hs is None else hs.restoring, "components": stateful,
            "meff": meff}, extra_mass


def _solver_forcing(integ: CumminsIntegrator, wave: Wave | None, coeffs: xr.Dataset,
                    timed: Sequence[KnownComponent], t: np.ndarray, sys: CumminsSystem,
                    ramp: float, f_exc: np.ndarray, f_ext: np.ndarray) -> np.ndarray:
    """The time-only force [N, N m] on the integrator's grid: the output grid (``f_exc +
    f_ext``), or the steps and their midpoints for RK4's stages (evaluated there)."""
    if not integ.half_steps:
        return f_exc + f_ext
    t_half = np.arange(2 * t.size - 1) * ((t[1] - t[0]) / 2)  # t[1] − t[0] is dt exactly
    u = excitation(wave, coeffs, t_half, sys.dofs, ramp)[0]
    u += time_forcing(timed, t_half, sys.n)
    return u


def _restoring_force(sys: CumminsSystem, sol: SolverResult) -> np.ndarray:
    """F_hs [N, N m]: the integrator's when it evaluated one, else the linear ``−C z``."""
    f_hs = sol.forces.get("F_hs")
    return -sol.z @ sys.stiffness.T if f_hs is None else f_hs


def _inputs(coeffs: xr.Dataset, sys: CumminsSystem, **kw: Any) -> dict[str, Any]:
    wave = kw.pop("wave")
    body = kw.pop("body")
    return {
        **{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in kw.items()},
        "coeffs_hash": coeffs_hash(coeffs),
        "dofs": sys.dofs,
        "wave": None if wave is None else wave.to_dict(),
        "body": None if body is None else repr(body),
        "radiation_ss": None if sys.ss is None else {
            "order": sys.ss.order, "fit_error": sys.ss.fit_error,
            "n_reflected": sys.ss.n_reflected},
        "kernel_length_s": None if sys.kernel is None else (sys.kernel.shape[0] - 1) * kw["dt"],
    }


def _forces(sys: CumminsSystem, z, v, f_hs, mem, f_exc, f_ext,
            extra_mass: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Force components and the acceleration from the equation of motion (last axis = DOF).

    ``extra_mass`` is the acceleration coefficient of the state-dependent components (their
    ``ode_force`` leaves out ``−A_k z̈``, added to ``F_ext`` here).
    """
    meff = sys.mass + sys.added_mass_inf
    has_extra = extra_mass is not None and np.any(extra_mass)
    if has_extra:
        meff = meff + extra_mass
    rhs = f_hs + mem  # in-place sums below: same order (same rounding), fewer temporaries
    rhs += f_exc
    rhs += f_ext
    rhs = np.moveaxis(rhs, -1, 0).reshape(sys.n, -1)
    if sys.n == 1:  # a scalar mass: the solve is a division (LAPACK's getrs is slow here)
        acc = rhs / meff[0, 0]
    else:  # LAPACK getrf/getrs as np.linalg.solve, without its copies of the right-hand side
        acc = scipy.linalg.lu_solve(scipy.linalg.lu_factor(meff), rhs, check_finite=False,
                                    overwrite_b=True)
    acc = np.moveaxis(acc.reshape(sys.n, *z.shape[:-1]), 0, -1)
    if has_extra:
        f_ext = f_ext - acc @ extra_mass.T
    f_inf = acc @ sys.added_mass_inf.T
    np.negative(f_inf, out=f_inf)
    tot = f_hs + f_inf
    tot += mem
    tot += f_exc
    tot += f_ext
    return {"zddot": acc, "F_hs": f_hs, "F_rad_inf": f_inf, "F_rad_mem": mem, "F_exc": f_exc,
            "F_ext": f_ext, "F_tot": tot}


def _matrix_vars(sys: CumminsSystem) -> dict[str, tuple]:
    """The system matrices as ``(dof, dof_j)`` variables with per-pair units."""
    out = {}
    for name, attr in MATRICES.items():
        out[name] = (("dof", "dof_j"), getattr(sys, attr),
                     {"units": pair_units_attr(name, sys.dofs),
                      "units_per_pair": json.dumps(unit_matrix(name, sys.dofs)),
                      "orientation": "[influenced dof, radiating dof_j]"})
    return out


def _set_dof_units(ds: xr.Dataset, dofs: Sequence[str]) -> None:
    """Per-DOF units (:func:`hybridwsi.history.units_attrs`) on a batch Dataset, in place
    (single runs get them from ``make_history``)."""
    for name in ("z", "zdot", "zddot", *FORCES):
        ds.variables[name].attrs.update(units_attrs("force" if name in FORCES else name, dofs))


def _history(sys, t, z, v, f_hs, mem, f_exc, f_ext, eta, inputs, extra_mass=None
             ) -> xr.Dataset:
    # validated here rather than by make_history: the time grid is ours (uniform) and the
    # forcing was checked on input, so only the solution itself can be non-finite
    if not all(np.all(np.isfinite(a)) for a in (z, v, mem, f_hs, f_ext)):
        raise SolverError("the Cummins solution is not finite (unstable system); check the "
                          "coefficients and the state-space fit")
    f = _forces(sys, z, v, f_hs, mem, f_exc, f_ext, extra_mass)
    acc = f.pop("zddot")
    extra = _matrix_vars(sys)
    del extra["mass"]  # make_history writes it (and the dof_j coordinate); units below
    coords = None
    if eta is not None:  # built with the Dataset: a later assignment costs an xarray merge
        extra["eta"] = (("time", "probe"), eta[:, None], elevation_attrs(inputs["ramp"]))
        coords = {"probe": ["origin"]}
    hist = make_history(t, z, v, acc, forces={k: f[k] for k in FORCES}, dof=sys.dofs,
                        mass=sys.mass, source="cummins", inputs=inputs, check=False,
                        extra_vars=extra, extra_coords=coords)
    hist.variables["mass"].attrs.update(_matrix_vars(sys)["mass"][2])
    if sys.ss is not None:
        hist.attrs["radiation_ss"] = json.dumps(sys.ss.to_dict())
    return hist


# --------------------------------------------------------------------------- batches
_CASE_KEYS = {"z0", "zdot0", "wave", "forces"}
_REGULAR_KEYS = {"period", "height", "phase"}
_JONSWAP_KEYS = {"hs", "tp", "gamma", "seed"}


def _cases_from_dataset(ds: xr.Dataset) -> list[dict[str, Any]]:
    """Rows of a parameter Dataset (dim ``case``) → case dicts."""
    if "case" not in ds.dims:
        raise InputError("a cases Dataset needs a 'case' dimension")
    names = set(map(str, ds.data_vars))
    unknown = names - _CASE_KEYS - _REGULAR_KEYS - _JONSWAP_KEYS
    if unknown:
        raise InputError(f"unknown case parameters {sorted(unknown)}")
    cases = []
    for i in range(ds.sizes["case"]):
        row = {k: ds[k].values[i].item() for k in names}
        case = {k: row[k] for k in ("z0", "zdot0") if k in row}
        if {"period", "height"} <= names:
            case["wave"] = {"type": "regular", **{k: row[k] for k in _REGULAR_KEYS if k in row}}
        elif {"hs", "tp"} <= names:
            case["wave"] = {"type": "jonswap",
                            **{k: row[k] for k in _JONSWAP_KEYS if k in row}}
            if "seed" in case["wave"]:
                case["wave"]["seed"] = int(case["wave"]["seed"])
        cases.append(case)
    return cases


def simulate_batch(
    coeffs: xr.Dataset,
    cases: Sequence[Mapping[str, Any]] | xr.Dataset,
    *,
    mass: float | np.ndarray | None = None,
    duration: float,
    dt: float,
    ramp: float = 0.0,
    dofs: Sequence[str] = ("Heave",),
    radiation: str = "statespace",
    irf: xr.DataArray | None = None,
    radiation_ss: RadiationSS | None = None,
    ss_order: int | None = None,
    ss_tol: float = 0.005,
    irf_t_max: float | None = None,
) -> xr.Dataset:
    """Many linear Cummins runs at once (one system, cases stacked as columns).

    Parameters
    ----------
    cases : list of dict or xarray.Dataset
        Each case may set ``z0``, ``zdot0``, ``wave`` (Wave or dict) and ``forces`` (time-only
        components: ``ConstantForce``, ``PrescribedForce.from_series``). A Dataset with
        dimension ``case`` may hold ``z0, zdot0`` and either ``period, height[, phase]``
        (regular) or ``hs, tp[, gamma, seed]`` (JONSWAP).
    other parameters
        As :func:`simulate` (linear only: ``radiation`` "statespace" or "none").

    Returns
    -------
    xarray.Dataset
        Variables ``z, zdot, zddot`` and the forces with dims ``(case, time, dof)``, ``eta``
        ``(case, time)`` when any case has waves; the matrices ``mass``, ``added_mass_inf``,
        ``hydrostatic_stiffness`` ``(dof, dof_j)``; attrs as a TimeHistory.
    """
    integ = integrator_for(radiation, batched=True)
    if isinstance(cases, xr.Dataset):
        cases = _cases_from_dataset(cases)
    cases = list(cases)
    if not cases:
        raise InputError("simulate_batch needs at least one case")
    t = time_grid(duration, dt)
    sys = build_system(coeffs, dofs=dofs, mass=mass, radiation=radiation, dt=dt, irf=irf,
                       radiation_ss=radiation_ss, ss_order=ss_order, ss_tol=ss_tol,
                       irf_t_max=irf_t_max)
    z0, v0, f_exc, f_ext, eta, described = _batch_inputs(coeffs, cases, sys, t, ramp)
    sol = integ.solve(sys, f_exc + f_ext, z0, v0, dt).raise_on_failure()
    z, v, mem = sol.z, sol.v, sol.forces["F_rad_mem"]
    forces = _forces(sys, z, v, -z @ sys.stiffness.T, mem, f_exc, f_ext)
    acc = forces.pop("zddot")
    inputs = _inputs(coeffs, sys, duration=duration, dt=dt, wave=None, z0=z0.T, zdot0=v0.T,
                     forces=[], radiation=radiation, ramp=ramp,
                     nonlinear_hydrostatics=False, body=None)
    inputs["cases"] = [{"z0": z0[c].tolist(), "zdot0": v0[c].tolist(), **described[c]}
                       for c in range(len(cases))]
    dims = ("case", "time", "dof")
    data = {"z": (dims, z), "zdot": (dims, v), "zddot": (dims, acc)}
    data.update({k: (dims, forces[k], {"role": "force"}) for k in FORCES})
    data.update(_matrix_vars(sys))
    if any(d["wave"] is not None for d in described):
        data["eta"] = (("case", "time"), eta, elevation_attrs(ramp))
    out = xr.Dataset(
        data,
        coords={"case": np.arange(len(cases)), "time": ("time", t, {"units": "s"}),
                "dof": sys.dofs, "dof_j": sys.dofs},
        attrs={"hybridwsi_version": _version(), "source": "cummins.simulate_batch",
               "inputs": json.dumps(inputs, default=str, sort_keys=True)},
    )
    _set_dof_units(out, sys.dofs)
    return out


def _batch_inputs(coeffs: xr.Dataset, cases: list[Mapping[str, Any]], sys: CumminsSystem,
                  t: np.ndarray, ramp: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                             list[dict[str, Any]]]:
    """Initial states (n_case, n), excitation and time-only forces (n_case, nt, n) [N, N m],
    η (n_case, nt) [m] and each case's description (wave dict, force names)."""
    n, nc = sys.n, len(cases)
    z0, v0 = np.zeros((nc, n)), np.zeros((nc, n))
    f_exc, f_ext = np.zeros((nc, t.size, n)), np.zeros((nc, t.size, n))
    eta = np.zeros((nc, t.size))
    described: list[dict[str, Any]] = []
    for c, case in enumerate(cases):
        unknown = set(case) - _CASE_KEYS
        if unknown:
            raise InputError(f"case {c}: unknown keys {sorted(unknown)} (use {sorted(_CASE_KEYS)})")
        z0[c] = _vector(case.get("z0", 0.0), n, f"case {c} z0")
        v0[c] = _vector(case.get("zdot0", 0.0), n, f"case {c} zdot0")
        wave = as_wave(case.get("wave"))
        if wave is not None:
            f_exc[c], eta[c] = excitation(wave, coeffs, t, sys.dofs, ramp)
        timed, stateful = split_components(case.get("forces"))
        if stateful:
            raise InputError(f"case {c}: simulate_batch is linear; state-dependent forces "
                             f"({', '.join(s.describe() for s in stateful)}) need simulate()")
        f_ext[c] = time_forcing(timed, t, n)
        described.append({"wave": None if wave is None else wave.to_dict(),
                          "forces": [s.describe() for s in timed]})
    return z0, v0, f_exc, f_ext, eta, described
