"""The project's cases as data: TOML files, built in (beside this module) or the user's own.

``load_case("paper_sphere")`` returns the validated content of ``paper_sphere.toml``: the
floating sphere of the paper, its BEM configuration, the regular-wave case (T = 0.75 s,
H = 0.05 m) and the paper's Table 1 values; ``load_case("kramer2021_decay")`` the decay
experiment of Kramer et al. (2021); ``load_case("oc3_hywind")`` the OC3-Hywind spar with the
NREL 5-MW turbine (docs/OC3_HYWIND.md); ``load_case("path/to/my_spar.toml")`` a user's case
file. Every case is checked against one schema (:mod:`hybridwsi.cases.schema`,
docs/CASES.md); paths inside a case file are relative to it.

From a case, :func:`body_from_case` builds its floating body and :func:`bem_arguments`
the keyword arguments of :func:`hybridwsi.hydro.bem.compute` (``[bem]`` or ``[bem_quick]``).
The force components of a case are built above the force layer, in
:mod:`hybridwsi.casemodel`; this package is data only.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from hybridwsi.bodies import FloatingSphere, body_from_dict
from hybridwsi.cases.schema import MOORING_MODELS, canonical_hash, validate
from hybridwsi.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, published as tomli (pyproject.toml dependency)
    import tomli as tomllib

#: keys of a case's ``[bem]`` table passed to :func:`hybridwsi.hydro.bem.compute` unchanged
BEM_KEYS = ("water_depth", "panel_size", "n_panels", "dofs", "method", "deep_water_kh",
            "low_kh", "low_kh_panels", "wave_directions")


class Case(dict):
    """A validated case: its content as plain values (:func:`load_case`), plus where it came
    from.

    Attributes
    ----------
    name : str
        The ``name`` entry, else the file name without ``.toml``.
    path : Path or None
        The case file (None for a case built from a dict without a file).
    directory : Path
        The folder relative paths in the case are taken from.
    sha256 : str
        Canonical content hash (:func:`hybridwsi.cases.schema.canonical_hash`): the same for
        a copy under another name or folder, different for any change of a value or of a
        referenced file. Computed once, at loading; edit a copy with :func:`from_dict`.
    """

    def __init__(self, data: Mapping[str, Any], *, name: str, path: Path | None,
                 directory: Path, sha256: str) -> None:
        super().__init__(data)
        self.name = name
        self.path = path
        self.directory = directory
        self.sha256 = sha256

    @property
    def label(self) -> str:
        """How messages name the case: its file, else its name."""
        return str(self.path) if self.path is not None else f"case {self.name!r}"


def available() -> list[str]:
    """Names of the built-in cases."""
    files = resources.files(__name__).iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".toml"))


def _builtin(name: str) -> Path | None:
    path = Path(str(resources.files(__name__))) / f"{name}.toml"
    return path if path.is_file() and os.sep not in name and "/" not in name else None


def is_builtin(case: str | os.PathLike) -> bool:
    """Whether ``case`` names a built-in case (not a file)."""
    text = os.fspath(case)
    return not text.endswith(".toml") and _builtin(text) is not None


def case_path(case: str | os.PathLike) -> Path:
    """The file of a case given as a built-in name or a path to a TOML file."""
    text = os.fspath(case)
    builtin = _builtin(text) if not text.endswith(".toml") else None
    if builtin is not None:
        return builtin
    path = Path(text).expanduser()
    if path.is_file():
        return path
    if text.endswith(".toml") or os.sep in text or "/" in text:
        raise InputError(f"case file {text} not found")
    raise InputError(f"unknown case '{text}': not a built-in case ({', '.join(available())}) "
                     "and no such file")


def _label(case: str | os.PathLike, path: Path) -> str:
    return path.name if path.parent == Path(str(resources.files(__name__))) else os.fspath(case)


def raw_case(case: str | os.PathLike) -> dict[str, Any]:
    """The TOML content of a case file as written (not validated): to edit and check again
    with :func:`from_dict`."""
    path = case_path(case)
    label = _label(case, path)
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as exc:
        raise InputError(f"{label}: cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise InputError(f"{label}: not a UTF-8 text file (a case is a TOML file)") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{label}: not valid TOML: {exc}") from None


def load_case(case: str | os.PathLike) -> Case:
    """A case by built-in name (see :func:`available`) or path to a TOML file, validated.

    Raises
    ------
    InputError
        One line naming the file and the key: not found, not TOML, unknown key, missing or
        malformed value, wrong unit (:mod:`hybridwsi.cases.schema`).
    """
    if isinstance(case, Case):
        return case
    path = case_path(case)
    return from_dict(raw_case(case), label=_label(case, path), path=path.resolve())


def from_dict(raw: Mapping[str, Any], *, label: str = "case",
              path: str | os.PathLike | None = None,
              directory: str | os.PathLike | None = None) -> Case:
    """A case from its TOML content as a dict (validated like a file; relative paths from
    ``directory``, default the folder of ``path``, else the working directory)."""
    path = None if path is None else Path(path)
    folder = Path(directory) if directory is not None else (
        path.parent if path is not None else Path.cwd())
    content, files = validate(raw, label, folder)
    name = content.get("name") or (path.stem if path is not None else label)
    return Case(content, name=str(name), path=path, directory=folder,
                sha256=canonical_hash(content, files))


def mooring_model(case: Mapping[str, Any], override: str | None = None) -> str:
    """The case's mooring model (``[forces] mooring``: moordyn, quasi-static, table or none),
    or ``override`` (the command line's ``--mooring``) when given; an override needs the
    case's ``[mooring]`` table."""
    model = case.get("forces", {}).get("mooring", "table" if "mooring" in case else "none")
    if override is None or override == model:
        return model
    if override not in MOORING_MODELS:
        raise InputError(f"mooring model must be one of {', '.join(MOORING_MODELS)}, got "
                         f"{override!r}")
    if "mooring" not in case:
        raise InputError(f"--mooring {override}: the case has no [mooring] table")
    return override


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
        A case (:func:`load_case`).
    table : str
        ``"bem"`` (the shipped configuration) or ``"bem_quick"`` (coarse, for tests).

    Returns
    -------
    dict
        ``body`` (:func:`body_from_case`), ``omega`` (:func:`frequencies`) and the table's
        entries among :data:`BEM_KEYS` (``water_depth`` defaults to the environment's, else
        infinite).
    """
    cfg = case.get(table)
    if not isinstance(cfg, Mapping):
        raise InputError(f"case {case.get('name', '?')!r} has no [{table}] table")
    unknown = set(cfg) - set(BEM_KEYS) - {"omega_min", "omega_max", "n_omega", "spacing",
                                          "omega_blend"}
    if unknown:
        raise InputError(f"[{table}] has unknown keys {sorted(unknown)}")
    args = {k: cfg[k] for k in BEM_KEYS if k in cfg}
    args.setdefault("water_depth", case.get("environment", {}).get("water_depth", math.inf))
    if "dofs" in args:
        args["dofs"] = tuple(args["dofs"])
    return {"body": body_from_case(case), "omega": frequencies(cfg), **args}

