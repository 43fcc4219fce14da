"""A case, built: its body, coefficients and force components, and its Cummins runs.

The one place where a case (:mod:`hybridwsi.cases`: a built-in name or the user's TOML file)
becomes objects: its body (:func:`body_from_case`), its BEM set-up (:func:`bem_arguments`) and
coefficients (:func:`case_coefficients`), and the components of its time-domain model;
``bem``, ``simulate``, ``sweep`` and the report all come here. The ODE (paper Eq. 9) is

    (M + A∞) z̈ + ∫K ż + C z = F_exc(t) + Σ_k F_k

with the hydrostatics (``[forces] hydrostatics``: −C z or the body's exact wetted volume), the
radiation (``[forces] radiation``) and the excitation of the BEM coefficients in
:func:`hybridwsi.cummins.simulate`, and the case's components ``F_k`` (:func:`case_components`):

==================  ====================  ==================================================
component           TimeHistory variable  from
==================  ====================  ==================================================
``mooring``         ``F_mooring``         ``[mooring]``; model ``[forces] mooring`` or
                                          ``--mooring``: ``table`` (MoorPy's interpolant),
                                          ``quasi-static`` (MoorPy every call), ``moordyn``
``morison``         ``F_morison``         ``[hydrodynamics] drag_cd``, ``[drag]``, the hull;
                                          a ``columns`` hull: its members' drag
``rotor``           ``F_rotor``           ``[rotor]`` (``state``, ``wind_speed``,
                                          ``turbulence_intensity``; ``--rotor``,
                                          ``--wind-speed``, ...)
``drift``           ``F_drift``           ``[drift]`` when ``[forces] drift`` is on and the run
                                          has a sea: Newman's slow drift
``linear_damping``  ``F_damping``         ``[hydrodynamics] additional_damping``
``external_force``  ``F_external``        ``[external_force] file`` (a force table)
==================  ====================  ==================================================

:meth:`CaseModel.simulate` records every component separately (N or N m per DOF, their sum is
the history's ``F_ext``), the wave elevation ``eta`` and, for a mooring component that says
them (:class:`~hybridwsi.forces.mooring.LineTensions`), the line tensions ``T_fairlead`` and
``T_anchor`` (dims ``time``, ``line``; N). A run starts from the static equilibrium under the
components' mean forces (the rotor's thrust, the slow drift's mean: :meth:`CaseModel.
mean_offset`), recorded in ``attrs["mean_offset"]``.

Everything a Dask sweep's seas share (coefficients, radiation state space, mooring table) is
in one picklable :class:`CaseModel`, built once on the client (:meth:`CaseModel.build`).
"""

from __future__ import annotations

import importlib
import inspect
import json
import math
import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import scipy.optimize
import xarray as xr

from hybridwsi import cummins
from hybridwsi.bodies import FloatingSphere, body_from_dict
from hybridwsi.cases import Case, load_case, mooring_model, with_values
from hybridwsi.cummins.forcing import elevation_attrs
from hybridwsi.dofs import RIGID_DOFS, check_dofs, index
from hybridwsi.errors import InputError, SolverError
from hybridwsi.forces import (
    Hydrostatic,
    KnownComponent,
    LinearDamping,
    MooringForce,
    MemberMorison,
    MooringSystem,
    MorisonDrag,
    PrescribedForce,
    additional_damping,
    rotor_from_case,
)
from hybridwsi.forces.drift import SlowDriftForce
from hybridwsi.forces.lagged import LaggedComponent
from hybridwsi.forces.mooring import LineTensions, MooringTable, QuasiStaticMooring
from hybridwsi.history import TextTable, quantity_of, units_attrs
from hybridwsi.hydro import bem
from hybridwsi.hydro import coefficients as cf
from hybridwsi.hydro.formats import read_coefficients
from hybridwsi.hydro.irf import radiation_irf
from hybridwsi.hydro.ss_cache import cached_radiation_ss
from hybridwsi.hydro.statespace import RadiationSS, fit_radiation_ss
from hybridwsi.hydro.strip import case_elements, with_slender_members
from hybridwsi.importers import read_elevation
from hybridwsi.waves import ElevationRecord, Wave, ramp_factor

#: component name -> TimeHistory variable of its force
COMPONENT_VARIABLES = {"mooring": "F_mooring", "morison": "F_morison", "rotor": "F_rotor",
                       "linear_damping": "F_damping", "external_force": "F_external",
                       "drift": "F_drift"}
#: the module m1-moordyn's MoorDyn component lives in (``MoorDynForce.from_case``)
MOORDYN_MODULE = "hybridwsi.forces.moordyn"
#: largest share of a wave-elevation record's variance above the BEM frequencies accepted
MAX_VARIANCE_OUTSIDE = 0.01
#: accepted names of the force column of a force table with one DOF (case-insensitive, unit
#: allowed); with several DOFs the columns are ``F_<DOF>``
FORCE_COLUMNS = ("F", "F_ext", "force")


#: keys of a case's ``[bem]`` table passed to :func:`hybridwsi.hydro.bem.compute` unchanged
BEM_KEYS = ("water_depth", "panel_size", "n_panels", "dofs", "method", "deep_water_kh",
            "low_kh", "low_kh_panels", "wave_directions")


# ---------------------------------------------------------------------------- case -> body
def body_from_case(case: Mapping[str, Any]):
    """The floating body (:class:`hybridwsi.bodies.Body`) of a case's ``[body]`` table.

    Two forms:

    - ``type = "sphere"`` (or no ``type``): the keyword arguments of
      :class:`~hybridwsi.bodies.FloatingSphere` (``paper_sphere.toml``);
    - a ``type`` (:func:`hybridwsi.bodies.body_from_dict`; e.g. ``"rigid_assembly"`` with a
      ``[body.hull]`` table of ``type = "axisymmetric"`` and a ``profile``, ``[[body.items]]``
      with ``name``, ``mass`` [kg], ``cm`` [m], ``inertia`` [kg m^2] about the item's CM, and a
      ``reference_point`` [m]). ``hull.structure`` names the item whose mass properties are the
      hull's own (hull geometry and its structural mass are one rigid part); that item leaves
      the list so nothing is counted twice.

    Bodies take ``rho`` and ``g`` from ``[environment]`` unless they give their own, and the
    case's ``name`` unless they give one.

    Raises
    ------
    InputError
        A missing or malformed entry.
    """
    spec = case.get("body") if isinstance(case, Mapping) else None
    if not isinstance(spec, Mapping):
        raise InputError("case has no [body] table")
    env = case.get("environment", {})
    if spec.get("type", "sphere") == "sphere":
        try:
            return FloatingSphere(**_with_water({k: v for k, v in spec.items() if k != "type"},
                                                env))
        except TypeError as exc:
            raise InputError(f"[body] of type sphere: {exc}") from None
    spec = {**spec, "name": spec.get("name", case.get("name"))}
    if "hull" in spec:
        spec["hull"], spec["items"] = _hull_and_items(spec["hull"], spec.get("items", []), env)
    else:
        spec = _with_water(spec, env)
    return body_from_dict(spec)


def _with_water(spec: Mapping[str, Any], env: Mapping[str, Any]) -> dict[str, Any]:
    """``spec`` with the environment's ``rho`` and ``g`` where it has none."""
    return {**{k: env[k] for k in ("rho", "g") if k in env}, **spec}


def _hull_and_items(hull: Any, items: Any, env: Mapping[str, Any]
                    ) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The hull dict (with water and its structure item's mass properties) and the items."""
    if not isinstance(hull, Mapping) or not isinstance(items, list):
        raise InputError("[body.hull] must be a table and [[body.items]] a list of tables")
    hull = _with_water(hull, env)
    if hull.get("type") == "sphere":
        hull["type"] = "FloatingSphere"
    structure = hull.pop("structure", None)
    if structure is None:
        return hull, list(items)
    own = [it for it in items if isinstance(it, Mapping) and it.get("name") == structure]
    if len(own) != 1:
        raise InputError(f"[body.hull] structure = {structure!r} must name exactly one of "
                         "[[body.items]]")
    item = own[0]
    try:
        hull.update(mass=item["mass"], cog=item["cm"], inertia=item.get("inertia"))
    except KeyError as exc:
        raise InputError(f"mass item {structure!r} has no {exc}") from None
    return hull, [it for it in items if it is not item]


# ---------------------------------------------------------------------------- case -> BEM
def frequencies(cfg: Mapping[str, Any]) -> np.ndarray:
    """Wave frequencies [rad/s] of a ``[bem]`` table.

    ``omega_min``, ``omega_max`` [rad/s] and ``n_omega``; ``spacing``:

    - ``"geometric"`` (default): log-spaced (the paper's sphere);
    - ``"blend"``: spacing proportional to ``omega + omega_blend``, i.e.
      ``omega_k = (omega_min + c) (q^k) - c`` with ``c = omega_blend`` [rad/s]: nearly uniform
      well below ``c`` (where the coefficients barely change: long waves), geometric well above.

    Raises
    ------
    InputError
        Missing keys, ``0 < omega_min < omega_max`` violated, fewer than 2 frequencies or an
        unknown spacing.
    """
    try:
        lo, hi, n = float(cfg["omega_min"]), float(cfg["omega_max"]), int(cfg["n_omega"])
    except KeyError as exc:
        raise InputError(f"[bem] needs {exc}") from None
    except (TypeError, ValueError):
        raise InputError("[bem] omega_min, omega_max must be numbers, n_omega an integer") from None
    if not (0 < lo < hi < math.inf) or n < 2:
        raise InputError(f"[bem] needs 0 < omega_min < omega_max and n_omega >= 2, got "
                         f"{lo}, {hi}, {n}")
    spacing = cfg.get("spacing", "geometric")
    if spacing == "geometric":
        return np.geomspace(lo, hi, n)
    if spacing == "blend":
        c = float(cfg.get("omega_blend", 0.0))
        if not (math.isfinite(c) and c >= 0):
            raise InputError(f"[bem] omega_blend must be >= 0 rad/s, got {c}")
        w = np.geomspace(lo + c, hi + c, n) - c
        w[[0, -1]] = lo, hi  # exact ends (round-off of the shift)
        return w
    raise InputError(f"[bem] spacing must be 'geometric' or 'blend', got {spacing!r}")


def bem_arguments(case: Mapping[str, Any], table: str = "bem") -> dict[str, Any]:
    """Keyword arguments of :func:`hybridwsi.hydro.bem.compute` for a case:
    ``compute(**bem_arguments(case))``.

    Parameters
    ----------
    case : dict
        A case (:func:`hybridwsi.cases.load_case`: its tables checked by the schema).
    table : str
        ``"bem"`` (the shipped configuration) or ``"bem_quick"`` (coarse, for tests).

    Returns
    -------
    dict
        ``body`` (:func:`body_from_case`), ``omega`` (:func:`frequencies`) and the table's
        entries among :data:`BEM_KEYS` (``water_depth`` defaults to the environment's, else
        infinite; ``wave_directions`` [rad] also from ``wave_directions_deg`` [deg]).
    """
    cfg = case.get(table)
    if not isinstance(cfg, Mapping):
        raise InputError(f"case {case.get('name', '?')!r} has no [{table}] table")
    args = {k: cfg[k] for k in BEM_KEYS if k in cfg}
    args.setdefault("water_depth", case.get("environment", {}).get("water_depth", math.inf))
    if "dofs" in args:
        args["dofs"] = tuple(args["dofs"])
    if "wave_directions_deg" in cfg:  # numpy's degrees-to-radians: the shipped files' key
        args["wave_directions"] = tuple(float(v) for v in np.radians(cfg["wave_directions_deg"]))
    return {"body": body_from_case(case), "omega": frequencies(cfg), **args}


# ------------------------------------------------------------------------------ pieces
def radiation_ss(coeffs: xr.Dataset, dofs: Sequence[str], mass: Any, dt: float,
                 fit: Mapping[str, Any] | None = None) -> RadiationSS:
    """The radiation state space ``cummins.simulate`` would fit itself (same tolerance),
    fitted once and reused (a sweep ships it to its workers).

    ``fit``: a case's ``[radiation]`` table instead (``t_max`` [s] and ``dt`` [s] of the
    kernel, ``max_order``, ``tol``, ``balance``, ``low_frequency``: :func:`hybridwsi.hydro.statespace.
    fit_radiation_ss` with every DOF weighed alike), for multi-DOF kernels the default fit
    does not capture (the OC4 semi: docs/OC4_SEMI.md)."""
    if fit:
        kw = {k: fit[k] for k in ("t_max", "dt") if k in fit}
        opts = {k: fit[k] for k in ("tol", "max_order", "balance", "low_frequency")
                if k in fit}
        dofs = list(dofs)
        return cached_radiation_ss(  # fitted once per content (the OC4 semi's takes 3 s)
            coeffs, ("case", dofs, sorted(kw.items()), sorted(opts.items())),
            lambda: fit_radiation_ss(radiation_irf(coeffs, **kw).sel(
                radiating_dof=dofs, influenced_dof=dofs), coeffs=coeffs, **opts))
    tol = inspect.signature(cummins.simulate).parameters["ss_tol"].default
    return cummins.build_system(coeffs, dofs=dofs, mass=mass, radiation="statespace", dt=dt,
                                ss_tol=tol).ss


def case_coefficients(case: Case, *, coeffs: str | os.PathLike | xr.Dataset | None = None,
                      quick: bool = False, cache_dir: str | os.PathLike | None = None,
                      progress: bool = False) -> xr.Dataset:
    """The coefficients of a case: ``coeffs`` (a file or a Dataset) when given, else the BEM
    solution of its ``[bem]`` table (``quick``: ``[bem_quick]``), ``compute(**bem_arguments
    (case))``, which is the shipped file without solving when the inputs match (OC3-Hywind:
    ``bem_oc3_hywind.nc``), else cached, else solved by Capytaine."""
    if isinstance(coeffs, xr.Dataset):
        return coeffs
    if coeffs is not None:
        return read_coefficients(coeffs, assume_seawater=True)
    table = "bem_quick" if quick else "bem"
    try:
        args = bem_arguments(case, table)
    except InputError as exc:
        raise InputError(f"{case.label}: {exc}") from None
    with warnings.catch_warnings():  # Capytaine's chatter on loading
        warnings.simplefilter("ignore")
        coeffs = bem.compute(**args, cache_dir=cache_dir, progress=progress)
    if has_members(case):  # the slender members' Morison inertia (hydro/strip.py)
        coeffs = with_slender_members(coeffs, case_elements(case))
    return coeffs


def has_members(case: Mapping[str, Any]) -> bool:
    """Whether the case's hull is a frame of members (``type = "columns"``): its slender
    members' inertia belongs to the coefficients, its drag to ``MemberMorison``."""
    body = case.get("body", {})
    return body.get("hull", body).get("type") == "columns"


def force_table(path: str | os.PathLike, dofs: Sequence[str] = ("Heave",)) -> PrescribedForce:
    """A tabulated external force: ``PrescribedForce.from_series`` of a text table with a
    ``time`` column [s] and, for one DOF, a force column named ``F``, ``F_ext`` or ``force``;
    for several DOFs one column ``F_<DOF>`` per DOF the force acts on (absent ones are zero).
    Units come from the header (e.g. ``F_ext [kN]``; N by default, N m on a rotation)."""
    table = TextTable(path)
    t = table.numeric(table.require("time"), "time")
    table.check_time(t, min_samples=2)
    if len(dofs) == 1:
        found = {c for c in (table.find(name) for name in FORCE_COLUMNS) if c is not None}
        if len(found) != 1:
            what = "no force column" if not found else f"several force columns {sorted(found)}"
            raise InputError(f"{table.path.name}: {what}; name one column "
                             f"{' or '.join(FORCE_COLUMNS)} (columns: {', '.join(table.columns)})")
        columns = {dofs[0]: found.pop()}
    else:
        columns = {d: c for d in dofs if (c := table.find(f"F_{d}")) is not None}
        if not columns:
            raise InputError(f"{table.path.name}: no force column for the DOFs {', '.join(dofs)}; "
                             f"name them F_<DOF>, e.g. F_{dofs[0]} (columns: "
                             f"{', '.join(table.columns)})")
    values = np.zeros((t.size, len(dofs)))
    for k, d in enumerate(dofs):
        if d in columns:
            values[:, k] = table.numeric(columns[d], quantity_of("force", d))
    return PrescribedForce.from_series(t, values if len(dofs) > 1 else values[:, 0],
                                       name=f"{table.path.name}:{','.join(columns.values())}")


def moordyn_component(case: Case, dofs: Sequence[str], dt: float | None) -> KnownComponent:
    """The MoorDyn-coupled mooring (``hybridwsi.forces.moordyn.MoorDynForce.from_case``)."""
    if dt is None:
        raise InputError("the MoorDyn mooring needs the solver's time step (dt)")
    try:  # the component is optional until its module is part of the package
        module = importlib.import_module(MOORDYN_MODULE)
    except ModuleNotFoundError as exc:
        if exc.name != MOORDYN_MODULE:
            raise
        raise InputError("--mooring moordyn: the MoorDyn mooring component "
                         f"({MOORDYN_MODULE}) is not available in this version of hybridwsi; "
                         "use --mooring table or quasi-static") from None
    return module.MoorDynForce.from_case(case, dofs, dt=dt, case_dir=case.directory)


def mooring_component(case: Case, dofs: Sequence[str], model: str, *,
                      table: MooringTable | None = None, dt: float | None = None
                      ) -> KnownComponent:
    """The case's mooring on ``dofs`` as ``model`` (table, quasi-static or moordyn);
    ``table``: an interpolant already built (else tabulated here, ~1 s of MoorPy)."""
    if model == "table":
        return MooringForce(table, dofs) if table is not None else MooringForce.from_case(
            case, dofs)
    if model == "quasi-static":
        return QuasiStaticMooring.from_case(case, dofs)
    if model == "moordyn":
        return moordyn_component(case, dofs, dt)
    raise InputError(f"unknown mooring model {model!r}")


def case_components(case: Case, dofs: Sequence[str], *, wave: Wave | None = None,
                    ramp: float = 0.0, mooring: str | None = None,
                    mooring_table: MooringTable | None = None, dt: float | None = None,
                    sea: Wave | None = None) -> dict[str, KnownComponent]:
    """The force components of a case on ``dofs``, by name (:data:`COMPONENT_VARIABLES`), as
    switched on by its ``[forces]`` table.

    ``wave``: the Morison drag's wave particle velocity (ramped like the excitation over
    ``ramp`` [s]); None: the drag on the body velocity alone. ``mooring``: the model
    (:func:`hybridwsi.cases.mooring_model`, default the case's); ``mooring_table``: the table
    model's interpolant if built already; ``dt``: the solver's step (MoorDyn); ``sea``: the
    run's sea, which drives the slow drift (default ``wave``; no sea, no drift).
    """
    on = case["forces"]
    model = mooring_model(case, mooring)
    out: dict[str, KnownComponent] = {}
    if model != "none":
        out["mooring"] = mooring_component(case, dofs, model, table=mooring_table, dt=dt)
    if on["morison"]:
        out["morison"] = (
            MemberMorison.from_case(case, dofs, wave=wave, ramp=ramp, inertia=False)
            if has_members(case) else MorisonDrag.from_case(case, dofs, wave=wave, ramp=ramp))
    if on["rotor"]:
        out["rotor"] = rotor_from_case(case, dofs)
    if on["linear_damping"]:
        out["linear_damping"] = additional_damping(case, dofs)
    if on["external_force"]:
        out["external_force"] = force_table(case["external_force"]["file"], dofs)
    sea = sea if sea is not None else wave
    if on.get("drift") and sea is not None:
        out["drift"] = SlowDriftForce.from_case(case, dofs, wave=sea, ramp=ramp)
    return out


def linear_components(case: Case, dofs: Sequence[str], *, stiffness: np.ndarray | None = None
                      ) -> list[KnownComponent]:
    """The case's mooring and additional damping linearised about rest, in this order: the
    mooring as ``−K z`` (``stiffness`` a 6×6 K = −∂F/∂q [SI per DOF pair], default MoorPy's
    at q = 0 with the yaw spring) and the additional linear damping; each only if the case
    has it. The linear system of the report's decays and RAOs (docs/OC3_HYWIND.md)."""
    out: list[KnownComponent] = []
    idx = index(dofs)
    if "mooring" in case:
        k6 = MooringSystem.from_case(case).stiffness() if stiffness is None else stiffness
        out.append(Hydrostatic(np.asarray(k6, dtype=float)[np.ix_(idx, idx)]))
    if case["forces"]["linear_damping"]:
        out.append(additional_damping(case, dofs))
    return out


def linearised_member_drag(case: Case, amplitudes: Mapping[str, float] | None = None
                           ) -> np.ndarray:
    """Σ over DOFs of the Borgman-linearised member drag for a harmonic motion of that DOF
    alone at its velocity amplitude (``[linear_drag]`` of the case, [m/s, rad/s]): a 6×6
    damping matrix [N s/m, N s/rad, N m s/m, N m s/rad] (rows = force DOF)."""
    amps = dict(case.get("linear_drag", {}) if amplitudes is None else amplitudes)
    if not amps:
        raise InputError("no velocity amplitudes for the drag linearisation ([linear_drag])")
    drag = MemberMorison.from_case(case, RIGID_DOFS, inertia=False)
    total = np.zeros((6, 6))
    for dof, value in amps.items():
        a = np.zeros(6)
        a[RIGID_DOFS.index(dof)] = float(value)
        total += drag.linearise_at(a).linear_coefficients(6)[1]
    return total


def known_linear_drag(case: Case, dofs: Sequence[str]) -> list[KnownComponent]:
    """The case's member drag linearised (:func:`linearised_member_drag`) as a known damping
    of a hybrid, when its ``[hybrid] known_linear_drag`` is on (else nothing): the network then
    learns the drag's departure from it, and the coupled step keeps the physical damping of
    the slow modes whatever sign the network's ∂F/∂ż takes (docs/OC4_SEMI.md, "The damping
    the network learns")."""
    if not case.get("hybrid", {}).get("known_linear_drag", False):
        return []
    idx = index(dofs)
    return [LinearDamping(linearised_member_drag(case)[np.ix_(idx, idx)])]


def elevation_wave(coeffs: xr.Dataset, path: str | os.PathLike, column: str | None = None,
                   direction: float = 0.0) -> ElevationRecord:
    """A wave-elevation record file (:func:`hybridwsi.importers.read_elevation`) as the wave
    of a run: its Fourier components up to the coefficients' highest frequency (below their
    lowest one the transfer function is held). Refused when more than
    :data:`MAX_VARIANCE_OUTSIDE` of η's variance lies above it."""
    t, eta, source = read_elevation(path, column)
    return record_wave(coeffs, t, eta, source=source, direction=direction)


def record_wave(coeffs: xr.Dataset, t: np.ndarray, eta: np.ndarray, *, source: str = "",
                direction: float = 0.0) -> ElevationRecord:
    """A wave elevation record η(t) [s, m] as the wave of a run or of a history's excitation
    (:func:`elevation_wave` without the file; ``hybridwsi hybrid`` on histories with η but
    no ``F_exc``), refused as there when too much of its variance lies above the
    coefficients' frequencies."""
    omega_max = float(np.max(coeffs["omega"].values))
    wave = ElevationRecord(t, eta, omega_max=omega_max, source=source, direction=direction)
    if wave.variance_outside > MAX_VARIANCE_OUTSIDE:
        raise InputError(
            f"{source}: {wave.variance_outside:.1%} of the wave elevation's variance lies "
            f"above the coefficients' highest frequency {omega_max:.4g} rad/s; low-pass "
            "filter the record or compute coefficients to higher frequencies")
    return wave


def _force_variable(comp: KnownComponent, name: str, hist: xr.Dataset) -> tuple:
    dofs = [str(d) for d in hist["dof"].values]
    values = np.asarray(comp.force(hist), dtype=float)
    attrs = {**units_attrs("force", dofs), "role": "force", "component": name,
             "description": comp.describe()}
    return ("time", "dof"), values, attrs


def _tension_variables(comp: LineTensions, hist: xr.Dataset) -> dict[str, tuple]:
    values = np.asarray(comp.line_tensions(hist), dtype=float)
    if values.shape != (hist.sizes["time"], comp.n_lines, 2):
        raise InputError(f"line tensions of shape {values.shape}; expected "
                         f"({hist.sizes['time']}, {comp.n_lines}, 2)")
    where = {"T_fairlead": ("fairlead", 0), "T_anchor": ("anchor", 1)}
    return {var: (("time", "line"), values[:, :, k],
                  {"units": "N", "long_name": f"line tension at the {end}"})
            for var, (end, k) in where.items()}


def component_variable(name: str) -> str:
    """The TimeHistory variable of a component: :data:`COMPONENT_VARIABLES`, else ``F_<name>``
    (a network component named ``network`` is recorded as ``F_network``)."""
    return COMPONENT_VARIABLES.get(name, name if name.startswith("F_") else f"F_{name}")


def record_components(hist: xr.Dataset, components: Mapping[str, KnownComponent]
                      ) -> xr.Dataset:
    """``hist`` with each component's force (:func:`component_variable`) and the mooring's
    line tensions (``T_fairlead``, ``T_anchor``, coordinate ``line`` = 1…n) added.

    ``attrs["components_residual"]``: the largest ``|Σ F_k − F_ext|`` over the largest
    ``|F_ext|``; round-off when every component's ``force`` on the history is what entered the
    ODE (a warning says so when it exceeds 1e-6).
    """
    new = {component_variable(name): _force_variable(comp, name, hist)
           for name, comp in components.items()}
    coords = {}
    for comp in components.values():
        if isinstance(comp, LineTensions):
            new.update(_tension_variables(comp, hist))
            coords["line"] = np.arange(1, comp.n_lines + 1)
    out = hist.assign_coords(coords).assign(new)
    if components and "F_ext" in hist:
        total = sum(v[1] for k, v in new.items() if k.startswith("F_"))
        scale = max(float(np.max(np.abs(hist["F_ext"].values))), 1e-300)
        residual = float(np.max(np.abs(total - hist["F_ext"].values))) / scale
        out.attrs["components_residual"] = residual
        if residual > 1e-6:
            warnings.warn(f"the force components differ from F_ext by {residual:.2g} of its "
                          "largest value: some component's force on the history is not what "
                          "the ODE integrated", UserWarning, stacklevel=2)
    return out


# ------------------------------------------------------------------------------ the model
@dataclass
class CaseModel:
    """A case with its DOFs, coefficients and mooring model, ready to simulate.

    Build it with :meth:`build`. Picklable: a sweep ships it to its workers once.

    Attributes
    ----------
    case : Case
        The validated case (:func:`hybridwsi.cases.load_case`).
    dofs : tuple of str
        The DOFs simulated.
    coeffs : xarray.Dataset
        The BEM coefficients.
    mooring : str
        The mooring model: ``table``, ``quasi-static``, ``moordyn`` or ``none``.
    mooring_table : MooringTable or None
        The interpolant of the ``table`` model, built once.
    dt : float or None
        The time step the radiation state space was fitted for.
    radiation_ss : RadiationSS or None
        That fit (None: fitted by each run).
    """

    case: Case
    dofs: tuple[str, ...]
    coeffs: xr.Dataset
    mooring: str
    mooring_table: MooringTable | None = None
    dt: float | None = None
    radiation_ss: RadiationSS | None = field(default=None, repr=False)

    @classmethod
    def build(cls, case: str | os.PathLike | Case, *, dofs: Sequence[str] | str | None = None,
              coeffs: str | os.PathLike | xr.Dataset | None = None, mooring: str | None = None,
              dt: float | None = None, quick: bool = False,
              cache_dir: str | os.PathLike | None = None, progress: bool = False,
              overrides: Mapping[str, Mapping[str, Any]] | None = None) -> CaseModel:
        """Load the case, get its coefficients and build what every run shares.

        Parameters
        ----------
        case : str, path or Case
            A built-in name or a TOML file (:func:`hybridwsi.cases.load_case`).
        dofs : sequence of str, optional
            Default: the case's ``default_dofs``, else the coefficients' DOFs.
        coeffs : path or Dataset, optional
            Coefficients instead of the case's ``[bem]`` solution.
        mooring : str, optional
            Mooring model overriding the case's (``--mooring``).
        dt : float, optional
            Time step [s]: fits the radiation state space once for it.
        quick : bool
            The coarse ``[bem_quick]`` table (tests).
        overrides : mapping, optional
            Entries of the case's tables replaced (:func:`hybridwsi.cases.with_values`; the
            command line's ``--rotor``, ``--wind-speed``, ``--slow-drift``, ...:
            :func:`hybridwsi.commands._options.case_overrides`).
        """
        case = with_values(load_case(case), overrides or {})
        coeffs = case_coefficients(case, coeffs=coeffs, quick=quick, cache_dir=cache_dir,
                                   progress=progress)
        have = cf.dofs(coeffs)
        dofs = check_dofs(dofs if dofs is not None else case.get("default_dofs") or have)
        missing = [d for d in dofs if d not in have]
        if missing:
            raise InputError(f"the coefficients of case {case.name!r} have no DOF "
                             f"{', '.join(missing)} (they have {', '.join(have)})")
        model = mooring_model(case, mooring)
        table = MooringForce.from_case(case, dofs).table if model == "table" else None
        ss = None
        if dt is not None and case["forces"]["radiation"] == "statespace":
            ss = radiation_ss(coeffs, dofs, None, dt, case.get("radiation"))
        return cls(case, dofs, coeffs, model, table, dt, ss)

    def state_space(self, dt: float) -> RadiationSS | None:
        """The radiation state space of a run at ``dt`` [s]: the one built with the model
        when fitted for that step, or when the case's ``[radiation]`` table fits it (its
        kernel sampling is the table's, whatever the run's step: the same fit, ~20 s on the
        OC4 semi, is not repeated); a new fit of that table otherwise; None (the run fits its
        own) without the table."""
        if self.radiation_ss is not None and (self.case.get("radiation") or (
                self.dt is not None and math.isclose(self.dt, dt))):
            return self.radiation_ss
        if self.case.get("radiation"):
            return radiation_ss(self.coeffs, self.dofs, None, dt, self.case["radiation"])
        return None

    @cached_property
    def body(self) -> Any:
        """The case's body (:func:`body_from_case`)."""
        try:
            return body_from_case(self.case)
        except InputError as exc:
            raise InputError(f"{self.case.label}: body: {exc}") from None

    def components(self, *, wave: Wave | None = None, ramp: float = 0.0,
                   dt: float | None = None, sea: Wave | None = None
                   ) -> dict[str, KnownComponent]:
        """:func:`case_components` of this model (its DOFs, mooring model and table)."""
        return case_components(self.case, self.dofs, wave=wave, ramp=ramp,
                               mooring=self.mooring, mooring_table=self.mooring_table,
                               dt=dt if dt is not None else self.dt, sea=sea)

    def mean_offset(self, components: Mapping[str, KnownComponent]) -> np.ndarray:
        """The static equilibrium [m, rad per DOF] under the components' mean forces.

        Solves ``Σ_k F̄_k + F_moor(q) − C q = 0`` for ``q``: ``F̄_k`` the ``mean_force()`` of
        every component that has one (the rotor's thrust and torque at the mean wind, the slow
        drift's realisation mean), ``C`` the coefficients' hydrostatic stiffness (linear, also
        for a run with nonlinear hydrostatics), ``F_moor`` the mooring's static force: the
        ``table`` or ``quasi-static`` component itself, MoorPy's tabulated interpolant for
        MoorDyn (whose statics agree with MoorPy's within 1 %: docs/OC3_HYWIND.md). Zero when no
        component has a mean force, so a parked run starts at rest as before.

        Raises
        ------
        SolverError
            No equilibrium found (e.g. a thrust larger than the mooring can hold).
        """
        n = len(self.dofs)
        means = [np.asarray(c.mean_force(), dtype=float).reshape(n)
                 for c in components.values() if callable(getattr(c, "mean_force", None))]
        total = np.sum(means, axis=0) if means else np.zeros(n)
        if not np.any(total):
            return np.zeros(n)
        stiffness = cf.matrix(self.coeffs, "hydrostatic_stiffness", self.dofs)
        mooring = components.get("mooring")
        if self.mooring == "moordyn":  # MoorPy's smooth interpolant (its solve is noisy)
            mooring = MooringForce.from_case(self.case, self.dofs)
        still, empty = np.zeros(n), np.zeros(0)

        def residual(q: np.ndarray) -> np.ndarray:
            f = total - stiffness @ q
            return f if mooring is None else f + mooring.ode_force(0.0, q, still, empty)

        k = stiffness + (0.0 if mooring is None else mooring.linear_coefficients(n)[2])
        first = np.linalg.lstsq(k, total, rcond=None)[0]
        sol = scipy.optimize.root(residual, first, method="hybr")
        scale = max(float(np.max(np.abs(total))), 1.0)
        if not sol.success or float(np.max(np.abs(residual(sol.x)))) > 1e-6 * scale:
            raise SolverError(f"{self.case.label}: no static equilibrium under the mean forces "
                              f"{np.array2string(total, precision=4)} N, N m ({sol.message})")
        return sol.x

    def settings(self) -> dict[str, Any]:
        """The set-up as plain values (a sweep's settings hash): the case's content hash, the
        coefficients' hash, the DOFs, the mooring model and table hash, every component."""
        forces = self.case["forces"]
        comps = ([] if self.mooring == "moordyn" else
                 [c.describe() for c in self.components().values()])
        return {"dofs": list(self.dofs), "case_sha256": self.case.sha256,
                "coeffs_hash": cummins.coeffs_hash(self.coeffs), "forces": comps,
                "models": {**forces, "mooring": self.mooring},
                "mooring_table": None if self.mooring_table is None
                else self.mooring_table.dataset.attrs.get("input_hash")}

    def _with(self, comps: dict[str, KnownComponent], extra: Mapping[str, KnownComponent],
              lagged: Sequence[str]) -> dict[str, KnownComponent]:
        """``comps`` plus ``extra`` (a name given twice is refused), the ``lagged`` ones
        wrapped in :class:`~hybridwsi.forces.lagged.LaggedComponent` (a stepped component,
        MoorDyn, is lagged by its own coupling already)."""
        for name, comp in extra.items():
            if name in comps:
                raise InputError(f"{self.case.label} has its own {name} component; give it "
                                 "once")
            comps[name] = comp
        for name in lagged:
            if name not in comps:
                raise InputError(f"no component {name!r} to lag (have {', '.join(comps)})")
            if not comps[name].stepped:
                comps[name] = LaggedComponent(comps[name])
        return comps

    def simulate(self, *, duration: float, dt: float, wave: Wave | None = None,
                 z0: float | Sequence[float] = 0.0, zdot0: float | Sequence[float] = 0.0,
                 ramp: float = 0.0, wave_kinematics: bool = True, progress: bool = False,
                 extra: Mapping[str, KnownComponent] | None = None,
                 radiation: str | None = None, hydrostatics: str | None = None,
                 from_offset: bool = True, lagged: Sequence[str] = ()) -> xr.Dataset:
        """One Cummins run of the case → TimeHistory with every component recorded.

        Parameters
        ----------
        duration, dt : float
            Simulated time and step [s].
        wave : Wave, optional
            Regular, JONSWAP or a recorded elevation (:func:`elevation_wave`).
        z0, zdot0 : float or sequence
            Initial displacement [m, rad] and velocity per DOF (a decay), about the mean
            offset when ``from_offset``.
        ramp : float
            Half-cosine ramp [s] of the excitation and of the drag's wave velocity.
        wave_kinematics : bool
            The Morison drag sees the wave particle velocity.
        extra : mapping of name to KnownComponent, optional
            Components besides the case's, recorded as :func:`component_variable` of their
            name: ``{"external_force": force_table(...)}`` (``simulate --external-force``;
            not with a case that has its own), ``{"network": ...}`` (``F_network``).
        radiation, hydrostatics : str, optional
            Instead of the case's ``[forces]`` models (``statespace``/``convolution``/``none``;
            ``linear``/``nonlinear``).
        from_offset : bool
            Start from the static equilibrium under the mean forces (:meth:`mean_offset`: the
            operating rotor's thrust, the slow drift's mean), so the run does not begin with a
            surge transient of the slow mode (~125 s period on OC3); False: from rest.
        lagged : sequence of str
            Components (by name) coupled one step lagged, their force held over each step
            from its start (:class:`~hybridwsi.forces.lagged.LaggedComponent`; MoorDyn is
            coupled so already): what a loosely coupled code or a lagged network does.

        Returns
        -------
        xarray.Dataset
            :func:`hybridwsi.cummins.simulate`'s history plus :func:`record_components`;
            ``attrs["case"]``: the case's name, file, content hash and models.
        """
        forces = {**self.case["forces"], "mooring": self.mooring,
                  **({"radiation": radiation} if radiation else {}),
                  **({"hydrostatics": hydrostatics} if hydrostatics else {})}
        comps = self.components(wave=wave if wave_kinematics else None, ramp=ramp, dt=dt,
                                sea=wave)
        comps = self._with(comps, extra or {}, lagged)
        n = len(self.dofs)
        offset = self.mean_offset(comps) if from_offset else np.zeros(n)
        z0 = offset + np.broadcast_to(np.asarray(z0, dtype=float), (n,))
        nonlinear = forces["hydrostatics"] == "nonlinear"
        excite = wave if forces["excitation"] else None
        ss = self.state_space(dt) if forces["radiation"] == "statespace" else None
        hist = cummins.simulate(
            self.coeffs, dofs=self.dofs, duration=duration, dt=dt, wave=excite, z0=z0,
            zdot0=zdot0, forces=list(comps.values()), radiation=forces["radiation"],
            nonlinear_hydrostatics=nonlinear, body=self.body if nonlinear else None, ramp=ramp,
            radiation_ss=ss, progress=progress)
        if wave is not None and excite is None:  # the elevation without its excitation
            t = hist["time"].values  # ramped as the drag's wave velocity is
            hist = hist.assign(eta=(("time", "probe"),
                                    (wave.elevation(t) * ramp_factor(t, ramp))[:, None],
                                    elevation_attrs(ramp)))
            hist = hist.assign_coords(probe=["origin"])
        hist = record_components(hist, comps)
        hist.attrs["mean_offset"] = json.dumps(dict(zip(self.dofs, offset.tolist())))
        hist.attrs["case"] = json.dumps({
            "name": self.case.name, "file": None if self.case.path is None
            else str(self.case.path), "sha256": self.case.sha256,
            "models": forces, "wave_kinematics": bool(wave_kinematics and wave is not None)})
        return hist
