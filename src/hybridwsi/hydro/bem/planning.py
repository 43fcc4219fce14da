"""What a BEM run solves, decided before any solve: the checked inputs, the body's mesh
options, the low-kh and deep-water split, and the cache keys (:class:`Plan`, :func:`plan`);
also the paper's configuration and the sinking-body check."""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridwsi._meta import provenance
from hybridwsi.bodies import Body, FloatingSphere, check_dofs
from hybridwsi.cases import load_case
from hybridwsi.errors import InputError
from hybridwsi.waves import dispersion_k

#: default hull panel count (the paper's mesh)
DEFAULT_PANELS = 6400


# ---------------------------------------------------------------------------- configurations
def _paper_bem() -> dict[str, Any]:
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

    ``plan(...).input_hash`` is the ``attrs["input_hash"]`` that ``compute`` writes; the
    shipped coefficient files are used when one of them carries the hash of a plan (or of one
    of its ``parts``). ``body`` and ``omega`` as :func:`compute`.

    Parameters
    ----------
    water_depth : float
        Water depth [m]; ``inf`` for deep water.
    dofs : sequence of str, optional
        Rigid-body degrees of freedom (Capytaine names) about the body's reference point;
        default ``body.dofs`` (the sphere: heave).
    wave_directions : sequence of float
        Incident wave directions [rad] for the excitation force.
    panel_size : float, optional
        Target panel size [m] of the hull (and lid) mesh (not for a mesh file).
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
        tanh 3 = 0.995) and the ω → ∞ limit are solved in deep water (why: ``_deep_water``).
        None: solve every frequency in finite depth.
    low_kh_panels : int or None
        Hull panels for the FinGreen3D re-solves (default 1600, used when coarser than the main
        mesh; None: the main mesh).
    """
    omega, dofs, directions, depth = _check_inputs(body, omega, dofs, wave_directions,
                                                   water_depth, method, low_kh)
    # only the sphere knows a (n_theta, n_phi) resolution: other bodies refuse it
    sphere_only = {} if resolution is None else {"resolution": resolution}
    mesh = body.mesh_options(panel_size=panel_size, n_panels=n_panels, **sphere_only)
    deep = _deep_water(omega, depth, body.g, deep_water_kh)
    if deep.any():
        return _plan_in_two_parts(
            body, omega, deep, depth=depth, deep_water_kh=float(deep_water_kh), dofs=dofs,
            directions=directions, mesh=mesh, method=method, symmetric=symmetric, lid=lid,
            include_inf=include_inf, include_zero=include_zero, low_kh=low_kh,
            low_kh_panels=low_kh_panels)
    low_mesh = _low_kh_mesh(body, mesh, depth, low_kh_panels)
    config = _configuration(body, depth, dofs, directions, mesh, method, symmetric, lid, low_kh,
                            low_mesh)
    input_hash = json_sha256({**config, "omega": hashed_frequencies(omega),
                              "include_inf": include_inf, "include_zero": include_zero})
    return Plan(body=body, omega=omega, depth=depth, dofs=dofs, directions=directions,
                mesh=mesh, low_kh_mesh=low_mesh, method=method, symmetric=symmetric, lid=lid,
                low_kh=low_kh, include_inf=include_inf, include_zero=include_zero,
                config=config, config_hash=json_sha256(config), input_hash=input_hash)


def _deep_water(omega: np.ndarray, depth: float, g: float,
                deep_water_kh: float | None) -> np.ndarray:
    """Which frequencies [rad/s] a finite-depth plan solves in deep water (kh >= the
    threshold); none in deep water or without a threshold.

    Capytaine's finite-depth Green function loses accuracy at large kh (on the 6400-panel
    sphere in 0.9 m, B is 3 % low at 12 rad/s and negative above 25 rad/s), while the bottom
    changes A by < 1 % there.
    """
    if not math.isfinite(depth) or deep_water_kh is None:
        return np.zeros(omega.shape, dtype=bool)
    return dispersion_k(omega, depth, g) * depth >= float(deep_water_kh)


def _plan_in_two_parts(body: Body, omega: np.ndarray, deep: np.ndarray, *, depth: float,
                       deep_water_kh: float, dofs: tuple[str, ...], directions: np.ndarray,
                       mesh: dict[str, Any], method: str, symmetric: bool, lid: bool,
                       include_inf: bool, include_zero: bool, low_kh: str,
                       low_kh_panels: int | None) -> Plan:
    """A finite-depth plan whose ``deep`` frequencies (kh >= ``deep_water_kh``) and ω = ∞
    limit are solved in deep water, the others in ``depth`` [m] (see :func:`plan`)."""
    common = dict(dofs=dofs, wave_directions=directions, method=method, symmetric=symmetric,
                  lid=lid, deep_water_kh=None, **mesh)
    high = plan(body, omega[deep], water_depth=math.inf, include_inf=include_inf,
                include_zero=False, **common)
    low = (plan(body, omega[~deep], water_depth=depth, include_inf=False,
                include_zero=include_zero, low_kh=low_kh, low_kh_panels=low_kh_panels,
                **common)
           if (~deep).any() else None)
    joined = json_sha256([None if low is None else low.input_hash, high.input_hash,
                          deep_water_kh])
    return Plan(body=body, omega=omega, depth=depth, dofs=dofs, directions=directions,
                mesh=mesh, low_kh_mesh=mesh, method=method, symmetric=symmetric, lid=lid,
                low_kh=low_kh, include_inf=include_inf, include_zero=include_zero, config={},
                config_hash="", input_hash=joined, parts=(low, high),
                deep_water_kh=deep_water_kh)


def _low_kh_mesh(body: Body, mesh: dict[str, Any], depth: float,
                 low_kh_panels: int | None) -> dict[str, Any]:
    """Mesh options of the FinGreen3D re-solves: ``low_kh_panels`` hull panels when coarser
    than ``mesh`` (finite depth only).

    FinGreen3D costs ~10 s per frequency on 6400 panels; the waves it is needed for (kh < 0.13,
    wavelength > 40 body diameters in 0.9 m) are much longer than the body, where a much
    coarser hull is converged.
    """
    if not math.isfinite(depth) or low_kh_panels is None:
        return mesh
    try:
        coarse = body.mesh_options(n_panels=int(low_kh_panels))
    except InputError:  # a body whose panels are fixed (a mesh file)
        return mesh
    return coarse if body.panel_count(**coarse) < body.panel_count(**mesh) else mesh


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

# ---------------------------------------------------------------------------- input checks
def _check_inputs(body: Any, omega: Any, dofs: Sequence[str] | None, wave_directions: Any,
                  water_depth: Any, method: str, low_kh: str
                  ) -> tuple[np.ndarray, tuple[str, ...], np.ndarray, float]:
    """The checked frequencies [rad/s], DOFs, wave directions [rad] and depth [m] of
    :func:`plan`; :class:`InputError` on the first bad one."""
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
    return omega, dofs, directions, depth


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
def _configuration(body: Body, depth: float, dofs: tuple[str, ...], directions: np.ndarray,
                   mesh: dict[str, Any], method: str, symmetric: bool, lid: bool, low_kh: str,
                   low_mesh: dict[str, Any]) -> dict[str, Any]:
    """Every input except the frequencies (key of the resumable store): the body's
    ``to_dict()`` and ``mesh_description()`` (for the paper's sphere exactly the keys of the
    sphere-only code, so the shipped coefficients stay valid)."""
    config = {
        "body": body.to_dict(), "water_depth": depth if math.isfinite(depth) else "inf",
        "dofs": list(dofs), "wave_directions": directions.tolist(),
        "mesh": {**body.mesh_description(**mesh), "symmetric": symmetric, "lid": lid},
        "solver": {"method": method, "green_function": "Delhommeau", "low_kh": low_kh},
        "versions": provenance("capytaine"),
    }
    if math.isfinite(depth):  # deep water never calls the low-kh fallback: keep its hash
        for key, value in body.mesh_description(**low_mesh).items():
            if key != "kind":  # e.g. the sphere's "low_kh_resolution"
                config["solver"][f"low_kh_{key}"] = value
    return config


def hashed_frequencies(omega: np.ndarray) -> list[float]:
    """The frequencies [rad/s] as the input hash sees them: 10 significant digits.

    ``np.geomspace`` differs in the last bit between CPUs (NumPy's SIMD ``log``/``exp``: 28 of
    the paper's 400 frequencies on an AMD EPYC against the machine that shipped the files), and
    a bit-exact key then misses the shipped coefficients and re-solves them."""
    return [float(f"{w:.10g}") for w in np.asarray(omega, dtype=float)]


def json_sha256(obj: Any) -> str:
    """SHA-256 of ``obj`` as sorted-key JSON: the cache keys of the BEM and the drift solves."""
    return hashlib.sha256(json.dumps(obj, sort_keys=True).encode()).hexdigest()


