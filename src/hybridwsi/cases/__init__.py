"""The project's cases as data (TOML files beside this module).

``load_case("paper_sphere")`` returns the dict of ``paper_sphere.toml``: the floating sphere of
the paper, its BEM configuration, the regular-wave case (T = 0.75 s, H = 0.05 m) and the paper's
Table 1 values; ``load_case("kramer2021_decay")`` the decay experiment of Kramer et al. (2021);
``load_case("oc3_hywind")`` the OC3-Hywind spar with the NREL 5-MW turbine (docs/OC3_HYWIND.md);
``load_case("oc4_semi")`` the OC4-DeepCwind semi-submersible with the same turbine
(docs/OC4_SEMI.md).

From a case dict, :func:`body_from_case` builds its floating body and :func:`bem_arguments`
the keyword arguments of :func:`hybridwsi.hydro.bem.compute` (``[bem]`` or ``[bem_quick]``).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from importlib import resources
from typing import Any

import numpy as np

from hybridwsi.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, published as tomli (pyproject.toml dependency)
    import tomli as tomllib

#: keys of a case's ``[bem]`` table passed to :func:`hybridwsi.hydro.bem.compute` unchanged
BEM_KEYS = ("water_depth", "panel_size", "n_panels", "dofs", "method", "deep_water_kh",
            "low_kh", "low_kh_panels")


def available() -> list[str]:
    """Names of the built-in cases."""
    files = resources.files(__name__).iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".toml"))


def load_case(name: str) -> dict[str, Any]:
    """Load a built-in case by name (see :func:`available`)."""
    path = resources.files(__name__) / f"{name}.toml"
    if not path.is_file():
        raise InputError(f"unknown case '{name}' (available: {', '.join(available())})")
    return tomllib.loads(path.read_text())


# ---------------------------------------------------------------------------- case -> body
def body_from_case(case: Mapping[str, Any]):
    """The floating body (:class:`hybridwsi.bodies.Body`) of a case's ``[body]`` table.

    Two forms:

    - no ``type``: the keyword arguments of :class:`~hybridwsi.bodies.FloatingSphere`
      (``paper_sphere.toml``);
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
    from hybridwsi.bodies import FloatingSphere, body_from_dict

    spec = case.get("body") if isinstance(case, Mapping) else None
    if not isinstance(spec, Mapping):
        raise InputError("case has no [body] table")
    if "type" not in spec:
        try:
            return FloatingSphere(**spec)
        except TypeError as exc:
            raise InputError(f"[body] without a type is a FloatingSphere: {exc}") from None
    env = case.get("environment", {})
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


def wave_directions(degrees: Any, table: str = "bem") -> tuple[float, ...]:
    """Wave directions [rad] from a ``wave_directions_deg`` list [deg] (direction the waves
    travel to, from +X towards +Y)."""
    try:
        deg = np.atleast_1d(np.asarray(degrees, dtype=float))
    except (TypeError, ValueError):
        deg = np.array([np.nan])
    if deg.ndim != 1 or deg.size == 0 or not np.all(np.isfinite(deg)):
        raise InputError(f"[{table}] wave_directions_deg must be a list of angles [deg], "
                         f"got {degrees!r}")
    return tuple(float(v) for v in np.radians(deg))


def bem_arguments(case: Mapping[str, Any], table: str = "bem") -> dict[str, Any]:
    """Keyword arguments of :func:`hybridwsi.hydro.bem.compute` for a case:
    ``compute(**bem_arguments(case))``.

    Parameters
    ----------
    case : dict
        A case (:func:`load_case`).
    table : str
        ``"bem"`` (the shipped configuration) or ``"bem_quick"`` (coarse, for tests).

    Returns
    -------
    dict
        ``body`` (:func:`body_from_case`), ``omega`` (:func:`frequencies`), the table's
        entries among :data:`BEM_KEYS` (``water_depth`` defaults to the environment's, else
        infinite) and ``wave_directions`` [rad] from ``wave_directions_deg`` [deg] (absent:
        compute's default, head seas 0).
    """
    cfg = case.get(table)
    if not isinstance(cfg, Mapping):
        raise InputError(f"case {case.get('name', '?')!r} has no [{table}] table")
    unknown = set(cfg) - set(BEM_KEYS) - {"omega_min", "omega_max", "n_omega", "spacing",
                                          "omega_blend", "wave_directions_deg"}
    if unknown:
        raise InputError(f"[{table}] has unknown keys {sorted(unknown)}")
    args = {k: cfg[k] for k in BEM_KEYS if k in cfg}
    args.setdefault("water_depth", case.get("environment", {}).get("water_depth", math.inf))
    if "dofs" in args:
        args["dofs"] = tuple(args["dofs"])
    if "wave_directions_deg" in cfg:
        args["wave_directions"] = wave_directions(cfg["wave_directions_deg"], table)
    return {"body": body_from_case(case), "omega": frequencies(cfg), **args}

