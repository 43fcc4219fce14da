"""The case-file schema: every table and key a case TOML may hold, checked recursively.

A case file is validated against :data:`CASE` before anything uses it
(:func:`validate`): unknown keys, missing required keys, wrong types, numbers out of range and
units that do not fit are refused with one line naming the file and the key, e.g.
``my_spar.toml: mooring.EA: expected a number [N], got 'stiff'``. The result is the case as
plain values in the units the schema states (:mod:`docs/CASES.md`):

- a number may be written as a TOML number (in the key's unit) or as a string ``"value unit"``
  (``water_depth = "1050 ft"``, ``line1_heading = "0.5 rad"``), converted with
  :func:`hybridwsi.units.convert_unit`; a unit of another quantity is refused;
- integers where the schema says integer, floats elsewhere (``320`` and ``320.0`` are one
  value, so they hash the same);
- DOF names spelled as :func:`hybridwsi.dofs.check_dofs` spells them (``surge`` -> ``Surge``);
- file paths (a mesh, a MoorDyn input, a force table) relative to the case file's folder,
  resolved to absolute paths; the file must exist, and its SHA-256 enters the case's hash
  instead of its path (:func:`canonical_hash`), so a case moved with its files keeps its hash;
- defaults of optional keys filled in inside the tables that are present, and the
  ``[forces]`` table always present and resolved (which component is on, which model).

The schema is data (:class:`Table`, :class:`Number`, ...): one place to add a key. This module
imports nothing above :mod:`hybridwsi.dofs` and :mod:`hybridwsi.units`.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hybridwsi.dofs import RIGID_DOFS, check_dofs, is_rotation
from hybridwsi.errors import InputError
from hybridwsi.units import convert_unit

#: marks an optional key without a default
MISSING: Any = object()
KeyPath = tuple[str | int, ...]


class Context:
    """What a check needs besides the value: the file (for messages and relative paths)
    and where the referenced files' hashes are collected."""

    def __init__(self, label: str, directory: Path) -> None:
        self.label = label
        self.directory = directory
        #: key path -> SHA-256 of every referenced file
        self.files: dict[KeyPath, str] = {}

    def fail(self, at: KeyPath, message: str) -> InputError:
        return InputError(f"{self.label}: {dotted(at) or 'top level'}: {message}")


def dotted(at: KeyPath) -> str:
    """``("body", "items", 2, "mass")`` -> ``"body.items[2].mass"``."""
    out = ""
    for part in at:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


# ---------------------------------------------------------------------------------- nodes
@dataclass(frozen=True, kw_only=True)
class Node:
    """A schema entry: ``check`` returns the normalised value or raises via ``ctx.fail``."""

    doc: str = ""
    required: bool = False
    default: Any = MISSING

    def check(self, value: Any, at: KeyPath, ctx: Context) -> Any:  # pragma: no cover
        raise NotImplementedError

    def kind(self) -> str:  # pragma: no cover - overridden
        """Short type description for messages and docs."""
        raise NotImplementedError


_VALUE_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf)\s*(.*?)\s*$")


@dataclass(frozen=True, kw_only=True)
class Number(Node):
    """A number in ``unit`` (``""``: a pure number; None: SI per DOF, numbers only).

    ``lo``/``hi`` bound it (``open_lo``: strictly above ``lo``); ``integer``: a whole number;
    ``allow_inf``: ``inf`` accepted (deep water).
    """

    unit: str | None = ""
    lo: float | None = None
    hi: float | None = None
    open_lo: bool = False
    integer: bool = False
    allow_inf: bool = False

    def kind(self) -> str:
        base = "an integer" if self.integer else "a number"
        return f"{base} [{self.unit}]" if self.unit else base

    def _parse(self, value: Any, at: KeyPath, ctx: Context) -> float:
        if isinstance(value, bool):
            raise ctx.fail(at, f"expected {self.kind()}, got {value!r}")
        if isinstance(value, (int, float)):
            return value
        if isinstance(value, str) and self.unit is not None and not self.integer:
            m = _VALUE_UNIT.match(value)
            if m and m.group(2):
                try:
                    return convert_unit(float(m.group(1)), m.group(2), self.unit)
                except InputError as exc:
                    raise ctx.fail(at, f"{exc} (write the value in {self.unit or 'no unit'})"
                                   ) from None
        raise ctx.fail(at, f"expected {self.kind()}, got {_shown(value)}")

    def check(self, value: Any, at: KeyPath, ctx: Context) -> float | int:
        x = self._parse(value, at, ctx)
        if isinstance(x, float) and math.isnan(x):
            raise ctx.fail(at, "is NaN")
        if math.isinf(x) and not self.allow_inf:
            raise ctx.fail(at, f"must be finite, got {x}")
        if self.integer:
            if isinstance(x, float) and not x.is_integer():
                raise ctx.fail(at, f"expected an integer, got {x}")
            x = int(x)
        else:
            x = float(x)
        if self.lo is not None and (x <= self.lo if self.open_lo else x < self.lo):
            raise ctx.fail(at, f"must be {'>' if self.open_lo else '>='} {self.lo:g}, got {x:g}")
        if self.hi is not None and x > self.hi:
            raise ctx.fail(at, f"must be <= {self.hi:g}, got {x:g}")
        return x


def positive(unit: str | None = "", doc: str = "", **kw: Any) -> Number:
    return Number(unit=unit, lo=0.0, open_lo=True, doc=doc, **kw)


def nonnegative(unit: str | None = "", doc: str = "", **kw: Any) -> Number:
    return Number(unit=unit, lo=0.0, doc=doc, **kw)


def integer(lo: int = 0, doc: str = "", **kw: Any) -> Number:
    return Number(integer=True, lo=lo, doc=doc, **kw)


@dataclass(frozen=True, kw_only=True)
class DofNumber(Number):
    """A number whose unit depends on the DOF that keys it (in a :class:`MapOf` of DOFs):
    ``linear`` on translations, ``rotational`` on rotations."""

    linear: str = ""
    rotational: str = ""

    def kind(self) -> str:
        return f"a number [{self.linear} or {self.rotational}]"

    def check(self, value: Any, at: KeyPath, ctx: Context) -> float:
        unit = self.rotational if is_rotation(str(at[-1])) else self.linear
        return Number(unit=unit, lo=self.lo, open_lo=self.open_lo).check(value, at, ctx)


@dataclass(frozen=True, kw_only=True)
class Boolean(Node):
    def kind(self) -> str:
        return "true or false"

    def check(self, value: Any, at: KeyPath, ctx: Context) -> bool:
        if not isinstance(value, bool):
            raise ctx.fail(at, f"expected true or false, got {_shown(value)}")
        return value


@dataclass(frozen=True, kw_only=True)
class Text(Node):
    choices: tuple[str, ...] | None = None

    def kind(self) -> str:
        return "one of " + ", ".join(map(repr, self.choices)) if self.choices else "a string"

    def check(self, value: Any, at: KeyPath, ctx: Context) -> str:
        if not isinstance(value, str):
            raise ctx.fail(at, f"expected {self.kind()}, got {_shown(value)}")
        if self.choices is not None and value not in self.choices:
            raise ctx.fail(at, f"expected {self.kind()}, got {value!r}")
        return value


@dataclass(frozen=True, kw_only=True)
class Dof(Node):
    """A DOF name (Surge ... Yaw, any case)."""

    def kind(self) -> str:
        return "a DOF name (Surge, Sway, Heave, Roll, Pitch, Yaw)"

    def check(self, value: Any, at: KeyPath, ctx: Context) -> str:
        if not isinstance(value, str):
            raise ctx.fail(at, f"expected {self.kind()}, got {_shown(value)}")
        try:
            return check_dofs([value])[0]
        except InputError:
            raise ctx.fail(at, f"expected {self.kind()}, got {value!r}") from None


@dataclass(frozen=True, kw_only=True)
class ListOf(Node):
    """A TOML array of ``item`` with an optional fixed ``length`` or bounds."""

    item: Node
    length: int | None = None
    min_length: int = 0
    unique: bool = False

    def kind(self) -> str:
        n = f"{self.length} " if self.length else ""
        if isinstance(self.item, Number):  # "a list of 3 numbers [m]"
            unit = f" [{self.item.unit}]" if self.item.unit else ""
            return f"a list of {n}{'integers' if self.item.integer else 'numbers'}{unit}"
        return f"a list of {n}entries, each {self.item.kind()}"

    def check(self, value: Any, at: KeyPath, ctx: Context) -> list[Any]:
        if not isinstance(value, list):
            raise ctx.fail(at, f"expected {self.kind()}, got {_shown(value)}")
        if self.length is not None and len(value) != self.length:
            raise ctx.fail(at, f"expected {self.length} entries, got {len(value)}")
        if len(value) < self.min_length:
            raise ctx.fail(at, f"expected at least {self.min_length} entries, got {len(value)}")
        out = [self.item.check(v, (*at, i), ctx) for i, v in enumerate(value)]
        if self.unique and len({json.dumps(v) for v in out}) != len(out):
            raise ctx.fail(at, "has repeated entries")
        return out


@dataclass(frozen=True, kw_only=True)
class Either(Node):
    """The first of ``options`` that accepts the value (e.g. a number or a list of them)."""

    options: tuple[Node, ...]

    def kind(self) -> str:
        return self.doc or " or ".join(o.kind() for o in self.options)

    def check(self, value: Any, at: KeyPath, ctx: Context) -> Any:
        errors = []
        for option in self.options:
            try:
                return option.check(value, at, ctx)
            except InputError as exc:
                errors.append(str(exc))
        # a value of the right shape: its own message; else name every accepted form
        shaped = [e for o, e in zip(self.options, errors)
                  if isinstance(o, ListOf) == isinstance(value, list)]
        if len(shaped) == 1:
            raise InputError(shaped[0])
        raise ctx.fail(at, f"expected {self.kind()}, got {_shown(value)}")


@dataclass(frozen=True, kw_only=True)
class FilePath(Node):
    """A file path relative to the case file's folder (absolute paths kept); must exist.

    ``shipped``: a package whose files a bare name may also mean when it is not beside the
    case file (a copy of a built-in case keeps finding the built-in case's MoorDyn input).
    """

    what: str = "file"
    shipped: str | None = None

    def kind(self) -> str:
        return f"a path to a {self.what}, relative to the case file"

    def check(self, value: Any, at: KeyPath, ctx: Context) -> str:
        if not isinstance(value, str) or not value.strip():
            raise ctx.fail(at, f"expected {self.kind()}, got {_shown(value)}")
        path = (ctx.directory / Path(value).expanduser()).resolve()
        if not path.is_file() and self.shipped and Path(value).name == value:
            from importlib import resources

            packaged = Path(str(resources.files(self.shipped) / value))
            path = packaged if packaged.is_file() else path
        if not path.is_file():
            raise ctx.fail(at, f"{self.what} {value!r} not found (looked for {path})")
        try:
            ctx.files[at] = hashlib.sha256(path.read_bytes()).hexdigest()
        except OSError as exc:
            raise ctx.fail(at, f"cannot read {path}: {exc.strerror or exc}") from None
        return str(path)


Check = Callable[[dict[str, Any], KeyPath, Context], None]


@dataclass(frozen=True, kw_only=True)
class Table(Node):
    """A TOML table with exactly the keys of ``fields`` (others refused).

    ``exclusive``: groups of keys of which at most one may be given; ``checks``: functions
    ``check(table, at, ctx)`` on the normalised table (relations between keys).
    """

    fields: Mapping[str, Node]
    exclusive: tuple[tuple[str, ...], ...] = ()
    checks: tuple[Check, ...] = ()

    def kind(self) -> str:
        return "a table"

    def check(self, value: Any, at: KeyPath, ctx: Context) -> dict[str, Any]:
        if not isinstance(value, Mapping):
            raise ctx.fail(at, f"expected a table, got {_shown(value)}")
        unknown = [k for k in value if k not in self.fields]
        if unknown:
            raise ctx.fail((*at, unknown[0]), f"unknown key (allowed in "
                           f"{'[' + dotted(at) + ']' if at else 'the top level'}: "
                           f"{', '.join(self.fields)})")
        for group in self.exclusive:
            given = [k for k in group if k in value]
            if len(given) > 1:
                raise ctx.fail(at, f"give at most one of {', '.join(group)} (got "
                                   f"{', '.join(given)})")
        out: dict[str, Any] = {}
        for key, node in self.fields.items():
            if key in value:
                out[key] = node.check(value[key], (*at, key), ctx)
            elif node.required:
                what = f" ({node.doc})" if node.doc else ""
                raise ctx.fail((*at, key), f"missing: {node.kind()}{what} is required")
            elif node.default is not MISSING:
                out[key] = node.default
        for check in self.checks:
            check(out, at, ctx)
        return out


@dataclass(frozen=True, kw_only=True)
class MapOf(Node):
    """A table whose keys are free names (``keys="name"``) or DOF names (``keys="dof"``,
    normalised to Capytaine's spelling), every value a ``value``."""

    value: Node
    keys: str = "name"

    def kind(self) -> str:
        return f"a table of {'DOF' if self.keys == 'dof' else 'name'} = value"

    def check(self, value: Any, at: KeyPath, ctx: Context) -> dict[str, Any]:
        if not isinstance(value, Mapping):
            raise ctx.fail(at, f"expected {self.kind()}, got {_shown(value)}")
        out: dict[str, Any] = {}
        for key, v in value.items():
            name = Dof().check(key, (*at, key), ctx) if self.keys == "dof" else key
            if name in out:
                raise ctx.fail((*at, key), f"{name} is given twice")
            out[name] = self.value.check(v, (*at, name), ctx)
        return out


@dataclass(frozen=True, kw_only=True)
class TableList(Node):
    """A TOML array of tables (``[[items]]`` or ``[{...}, {...}]``)."""

    table: Table

    def kind(self) -> str:
        return "an array of tables"

    def check(self, value: Any, at: KeyPath, ctx: Context) -> list[dict[str, Any]]:
        if not isinstance(value, list):
            raise ctx.fail(at, f"expected {self.kind()}, got {_shown(value)}")
        return [self.table.check(v, (*at, i), ctx) for i, v in enumerate(value)]


@dataclass(frozen=True, kw_only=True)
class OneOf(Node):
    """A table whose ``type`` key selects its schema among ``variants``; ``implicit``: the
    variant of a table without ``type``."""

    variants: Mapping[str, Table]
    implicit: str | None = None

    def kind(self) -> str:
        return f"a table with type = {' | '.join(map(repr, self.variants))}"

    def check(self, value: Any, at: KeyPath, ctx: Context) -> dict[str, Any]:
        if not isinstance(value, Mapping):
            raise ctx.fail(at, f"expected {self.kind()}, got {_shown(value)}")
        kind = value.get("type", self.implicit)
        if kind is None:
            raise ctx.fail((*at, "type"), f"missing: one of {', '.join(self.variants)}")
        if kind not in self.variants:
            raise ctx.fail((*at, "type"), f"expected one of {', '.join(map(repr, self.variants))}"
                                          f", got {_shown(kind)}")
        table = self.variants[kind]
        body = {k: v for k, v in value.items() if k != "type"}
        return {"type": kind, **table.check(body, at, ctx)}


# --------------------------------------------------------------------------- the schema
def _vec3(unit: str, doc: str = "", **kw: Any) -> ListOf:
    return ListOf(item=Number(unit=unit), length=3, doc=doc, **kw)


_INERTIA = Either(options=(ListOf(item=nonnegative("kg m^2"), length=3),
                           ListOf(item=ListOf(item=Number(unit="kg m^2"), length=3), length=3)),
                  doc="3 principal moments [kg m^2] (Ixx, Iyy, Izz) or the 3 x 3 tensor "
                      "about the CM")
_WATER = {"rho": positive("kg/m^3", "water density (default [environment] rho)"),
          "g": positive("m/s^2", "gravity (default [environment] g)")}
_MASS_PROPS = {"mass": positive("kg", "mass"), "cog": _vec3("m", "centre of mass"),
               "inertia": _INERTIA,
               "reference_point": _vec3("m", "DOF origin (default: the centre of mass)")}


def _profile_order(table: dict[str, Any], at: KeyPath, ctx: Context) -> None:
    rz = table.get("profile", [])
    if any(r < 0 for r, _ in rz):
        raise ctx.fail((*at, "profile"), "radii must be >= 0")
    if any(b[1] < a[1] for a, b in zip(rz, rz[1:])):
        raise ctx.fail((*at, "profile"), "z must not decrease from the keel up")


_SPHERE = Table(fields={
    "radius": positive("m", "sphere radius", required=True),
    "mass": positive("kg", "mass (default: floats at the draft)"),
    "draft": positive("m", "depth of the lowest point below the still-water level (default R)"),
    "center_of_mass": _vec3("m", "centre of mass relative to the sphere's centre"),
    "inertia": _INERTIA, **_WATER})
_AXISYMMETRIC = Table(fields={
    "profile": ListOf(item=ListOf(item=Number(unit="m"), length=2), min_length=2, required=True,
                      doc="(r, z) points from the keel centre up to above the waterline"),
    **_MASS_PROPS, **_WATER, "name": Text(doc="name of the Capytaine body")},
    checks=(_profile_order,))
_MESH = Table(fields={
    "mesh_file": FilePath(what="mesh file", required=True,
                          doc="any mesh Capytaine reads (GDF, STL, NEMOH .dat, ...)"),
    "file_format": Text(doc="Capytaine's format name when the extension does not tell it"),
    **_MASS_PROPS, **_WATER, "name": Text(doc="name of the Capytaine body")})
_MEMBER = Table(fields={
    "name": Text(required=True, doc="unique member name"),
    "ends": ListOf(item=_vec3("m"), length=2, required=True,
                   doc="end points of the member's axis (global frame at rest)"),
    "diameter": positive("m", "outer diameter", required=True),
    "potential": Boolean(default=False,
                         doc="in the potential-flow panel model (vertical columns only); "
                             "false: a slender member, strip theory only"),
    "cd": nonnegative("", "transverse drag coefficient (Morison, forces/morison.py)"),
    "ca": nonnegative("", "transverse added-mass coefficient (Morison inertia of the slender "
                          "members; 0 on potential-flow members)"),
    "axial_cd": ListOf(item=nonnegative(""), length=2,
                       doc="axial drag coefficients of the end discs [end 1, end 2] "
                           "(standard form 1/2 rho Cd A |w| w; heave plates)")},
    doc="a straight circular cylinder (bodies/members.py)")
_COLUMNS = Table(fields={
    "members": TableList(table=_MEMBER, required=True,
                         doc="the cylinders: vertical potential-flow members on one axis form "
                             "a column (panel model); the others are slender members"),
    "symmetry": integer(1, "order n of the layout's dihedral symmetry (mirror y = 0) the mesh "
                           "uses: one 2n-th is meshed (1: none)", default=1),
    **_MASS_PROPS, **_WATER, "name": Text(doc="name of the Capytaine body")},
    doc="vertical columns and slender members (bodies/columns.py ColumnsBody)")
_STRUCTURE = {"structure": Text(doc="the [[body.items]] entry whose mass properties are the "
                                    "hull's own")}
_ITEM = Table(fields={"name": Text(required=True), "mass": positive("kg", required=True),
                      "cm": _vec3("m", "centre of mass", required=True),
                      "inertia": _INERTIA})
_ASSEMBLY = Table(fields={
    "hull": OneOf(required=True, variants={
        name: Table(fields={**t.fields, **_STRUCTURE}, checks=t.checks)
        for name, t in (("sphere", _SPHERE), ("axisymmetric", _AXISYMMETRIC), ("mesh", _MESH),
                        ("columns", _COLUMNS))}),
    "items": TableList(table=_ITEM, doc="rigid mass items"),
    "reference_point": _vec3("m", "DOF origin (default: the assembly's centre of mass)"),
    "name": Text()})
#: the body variants (key ``type``; without it a sphere, the paper's files)
BODIES = {"sphere": _SPHERE, "axisymmetric": _AXISYMMETRIC, "mesh": _MESH,
          "columns": _COLUMNS, "rigid_assembly": _ASSEMBLY}


def _omega_order(table: dict[str, Any], at: KeyPath, ctx: Context) -> None:
    if "omega_min" in table and "omega_max" in table and table["omega_min"] >= table["omega_max"]:
        raise ctx.fail((*at, "omega_max"), f"must be above omega_min ({table['omega_min']:g})")


_BEM = Table(fields={
    "omega_min": positive("rad/s", "lowest frequency", required=True),
    "omega_max": positive("rad/s", "highest frequency", required=True),
    "n_omega": integer(2, "number of frequencies", required=True),
    "spacing": Text(choices=("geometric", "blend"), default="geometric"),
    "omega_blend": nonnegative("rad/s", "spacing proportional to omega + omega_blend"),
    "water_depth": positive("m", "default [environment] water_depth, else inf",
                            allow_inf=True),
    "panel_size": positive("m", "hull panel size"),
    "n_panels": integer(20, "approximate hull panel count"),
    "dofs": ListOf(item=Dof(), min_length=1, unique=True, doc="DOFs solved (default the body's)"),
    "wave_directions": ListOf(item=Number(unit="rad"), min_length=1,
                              doc="incident wave directions (default [0])"),
    "wave_directions_deg": ListOf(item=Number(unit="deg"), min_length=1, unique=True,
                                  doc="incident wave directions in degrees (converted with "
                                      "numpy.radians: the key of the shipped OC4 file)"),
    "method": Text(choices=("direct", "indirect")),
    "deep_water_kh": nonnegative("", "kh above which the deep-water Green function is used"),
    "low_kh": Text(choices=("fingreen", "drop")),
    "low_kh_panels": integer(20)},
    exclusive=(("panel_size", "n_panels"), ("wave_directions", "wave_directions_deg")),
    checks=(_omega_order,))

_SEA = Table(fields={"hs": positive("m", "significant wave height", required=True),
                     "tp": positive("s", "peak period", required=True),
                     "seed": integer(0, "seed of the random phases", required=True)},
             doc="a JONSWAP sea (gamma 3.3)")
_NETWORK_FIELDS: dict[str, Node] = {  # hybridwsi.surrogate.network.ForceNetwork's parameters
    "hidden": ListOf(item=integer(1), min_length=1, doc="hidden layer widths"),
    "activation": Text(doc="activation function (tanh, relu, ...)"),
    "window": integer(1, "taps per input"), "stride": integer(1, "samples between taps"),
    "lead": integer(0, "samples the wave elevation leads"), "lr": positive("", "learning rate"),
    "max_epochs": integer(1, "training epochs at most"),
    "patience": integer(1, "epochs without improvement before stopping"),
    "batch_size": integer(1, "mini-batch size [samples]"),
    "input_noise": nonnegative("", "input noise, x std of each input"),
    "seed": integer(0, "seed of the initialisation and batch order"),
    "val_fraction": Number(lo=0.0, hi=1.0, doc="validation share of the samples"),
    "weight_decay": nonnegative("", "Adam weight decay")}
_INPUTS = ListOf(item=Text(choices=("z", "zdot", "zddot", "eta")), min_length=1, unique=True,
                 doc="the network's input channels")
_HYBRID = Table(fields={
    "dofs": ListOf(item=Dof(), min_length=1, unique=True, doc="DOFs of the hybrid"),
    "dt": positive("s", "step of the reference runs and of the rollout"),
    "duration": positive("s", "length of each sea"),
    "quick_duration": positive("s", "the same with reproduce --quick"),
    "ramp": nonnegative("s", "excitation ramp"),
    "train": TableList(table=_SEA, doc="training seas"),
    "test": TableList(table=_SEA, doc="held-out seas"), "long": _SEA,
    "long_duration": positive("s", "length of the long sea"),
    "quick_long_duration": positive("s", "the same with reproduce --quick"),
    "force_accuracy": ListOf(item=positive(), min_length=1,
                             doc="relative force accuracies of the identifiability test"),
    "perturbation": positive("", "initial offset of the lagged runs, x std(z)"),
    "mode": Text(doc="coupling of the rollout (lagged, corrected, implicit)"),
    "known_linear_drag": Boolean(doc="the member drag linearised ([linear_drag]) is known: "
                                 "the network learns its departure from it"),
    "partitions": MapOf(value=Table(fields={"inputs": _INPUTS, **_NETWORK_FIELDS}),
                        doc="network settings per partition, over [hybrid.network]"),
    "network": Table(fields=_NETWORK_FIELDS, doc="network settings")},
    doc="the report's floating-wind hybrid (report/fowt_hybrid.py)")

_DOF_BOX = {d: nonnegative("rad" if is_rotation(d) else "m") for d in RIGID_DOFS}
_MOORING = Table(fields={
    "n_lines": integer(1, "number of lines, equally spaced", required=True),
    "line1_heading": Number(unit="deg", default=0.0, doc="direction of line 1 from +X"),
    "anchor_depth": positive("m", "anchor depth below the still-water level"),
    "anchor_radius": positive("m", "anchor distance from the centreline", required=True),
    "fairlead_depth": nonnegative("m", "fairlead depth below the SWL", required=True),
    "fairlead_radius": nonnegative("m", "fairlead distance from the centreline",
                                   required=True),
    "unstretched_length": positive("m", "line length", required=True),
    "diameter": positive("m", "nominal line diameter"),
    "mass_per_length": positive("kg/m", "line mass in air per length", required=True),
    "weight_in_water": positive("N/m", "apparent weight per length", required=True),
    "EA": positive("N", "extensional stiffness", required=True),
    "yaw_spring": nonnegative("N m/rad", "additional linear yaw stiffness", default=0.0),
    "moordyn_file": FilePath(what="MoorDyn input file", shipped="hybridwsi.cases",
                              doc="the MoorDyn v2 input of the same lines (forces/moordyn.py): "
                                  "a path relative to the case file, or the name of one "
                                  "shipped with the built-in cases"),
    "table": Table(fields={**_DOF_BOX, "spacing": positive("m", "grid step in (l_h, l_v)")},
                   doc="tabulation box of the interpolant: half-width per DOF"),
    "reference": Table(fields={
        "preload": ListOf(item=Number(unit=None), length=6, doc="F0 [N, N m]"),
        "K": ListOf(item=ListOf(item=Number(unit=None), length=6), length=6,
                    doc="-dF/dq [SI per DOF pair]"),
        "K11": Number(unit="N/m", doc="published surge (= sway) stiffness"),
        "K33": Number(unit="N/m", doc="published heave stiffness"),
        "K44": Number(unit="N m/rad", doc="published roll (= pitch) stiffness")},
        doc="published values, for tests")})

_ROTOR = Table(fields={
    "state": Text(choices=("parked", "thrust", "operating"), default="parked",
                  doc="parked: no force; thrust: a constant thrust and damping; operating: the "
                      "rotor in the wind below (docs/OC3_HYWIND.md, The rotor)"),
    "hub": _vec3("m", "rotor apex: where thrust and shaft torque act"),
    "thrust": Number(unit="N", doc="state thrust: mean thrust along +X"),
    "aero_damping": Number(unit="N s/m", default=0.0,
                           doc="state thrust: linear damping on the hub's fore-aft velocity"),
    "table": Text(doc="operating curve (NetCDF of scripts/rotor_table.py): a file shipped in "
                      "hybridwsi/data, or a path relative to the case file"),
    "shaft_tilt": Number(unit="deg", default=0.0, doc="shaft tilt: the thrust's direction"),
    "controller": Text(choices=("quasi-steady", "pi"), default="quasi-steady",
                       doc="quasi-steady: speed and pitch follow the operating curve at once; "
                           "pi: drivetrain + torque law + PI pitch (3 states)"),
    "torque_reaction": Boolean(default=True, doc="the shaft torque's moment on the nacelle"),
    "wind_speed": nonnegative("m/s", "mean hub-height wind"),
    "turbulence_intensity": nonnegative("", "sigma/U; 0: steady wind, > 0: Kaimal (IEC)",
                                        default=0.0),
    "wind_seed": integer(0, "seed of the turbulent wind's phases", default=0),
    "wind_period": positive("s", "the turbulent wind repeats after this", default=3600.0),
    "wind_dt": positive("s", "sample step of the turbulent wind", default=0.25),
    "rotor_averaged": Boolean(default=True, doc="disk-averaged wind (IEC coherence), else "
                                                "the hub point's"),
    "rotor_radius": positive("m", "radius of the disk average", default=63.0),
    "pi_gains": Text(choices=("oc3_detuned", "baseline"), default="oc3_detuned",
                     doc="controller pi: PI gains on generator speed (forces/controller.py)"),
    "pitch_kp": positive("s", "controller pi: proportional gain (overrides pi_gains)"),
    "pitch_ki": positive("", "controller pi: integral gain (overrides pi_gains)"),
    "pitch_theta_k": positive("deg", "controller pi: pitch where the gain halves",
                              default=6.302336),
    "torque_region3": Text(choices=("constant_torque", "constant_power"),
                           default="constant_torque",
                           doc="controller pi: generator torque above rated"),
    "drivetrain_inertia": positive("kg m^2", "controller pi: rotor-side inertia"),
    "speed_filter_hz": positive("Hz", "controller pi: generator-speed filter", default=0.25)},
    doc="forces/rotor.py")

#: mooring models: the MoorDyn lines, MoorPy solved at every call, MoorPy's interpolant
MOORING_MODELS = ("moordyn", "quasi-static", "table")
_FORCES = Table(fields={
    "hydrostatics": Text(choices=("linear", "nonlinear"), default="linear",
                         doc="-C z, or the exact wetted-volume force of the body"),
    "radiation": Text(choices=("statespace", "convolution", "none"), default="statespace"),
    "excitation": Boolean(default=True, doc="linear wave excitation from the BEM"),
    "mooring": Text(choices=(*MOORING_MODELS, "none"),
                    doc="default 'table' with a [mooring] table, else 'none'"),
    "morison": Boolean(doc="Morison drag; default on when [hydrodynamics] drag_cd > 0"),
    "rotor": Boolean(doc="the rotor of [rotor]; default on when the table is present"),
    "linear_damping": Boolean(doc="[hydrodynamics] additional_damping; default on when given"),
    "external_force": Boolean(doc="[external_force] table; default on when present"),
    "drift": Boolean(default=False,
                     doc="second-order slow drift of [drift] in the run's sea (Newman's "
                         "approximation, forces/drift.py); off unless switched on, so runs "
                         "without it keep their results")})

CASE = Table(fields={
    "name": Text(doc="default: the file name without .toml"),
    "dofs": ListOf(item=Dof(), min_length=1, unique=True, doc="the DOFs the case supports"),
    "default_dofs": ListOf(item=Dof(), min_length=1, unique=True,
                           doc="DOFs simulated when none are asked for"),
    "environment": Table(fields={
        "rho": positive("kg/m^3", "water density"), "g": positive("m/s^2", "gravity"),
        "water_depth": positive("m", "water depth (inf: deep water)", allow_inf=True)}),
    "body": OneOf(variants=BODIES, implicit="sphere", required=True),
    "bem": _BEM, "bem_quick": _BEM,
    "forces": _FORCES,
    "hydrodynamics": Table(fields={
        "displaced_volume": positive("m^3", "reference value (tests)"),
        "buoyancy": positive("N", "reference value rho g V0 (tests)"),
        "C33": Number(unit="N/m", doc="reference hydrostatic stiffness (tests)"),
        "C44": Number(unit="N m/rad", doc="reference, without the weight term (tests)"),
        "C55": Number(unit="N m/rad", doc="reference, without the weight term (tests)"),
        "drag_cd": nonnegative("", "Morison drag coefficient"),
        "morison_ca": nonnegative("", "Morison added-mass coefficient (recorded)"),
        "additional_damping": MapOf(keys="dof", value=DofNumber(
            linear="N s/m", rotational="N m s/rad", lo=0.0),
            doc="additional linear damping per DOF (the other DOFs 0)")}),
    "radiation": Table(fields={
        "t_max": positive("s", "length of the radiation kernel K(t)"),
        "dt": positive("s", "sampling step of K(t) for the fit"),
        "max_order": integer(1, "largest state-space order tried"),
        "tol": Number(lo=0.0, hi=1.0, open_lo=True, doc="relative time error of the fit"),
        "balance": Boolean(doc="fit every DOF's kernel scaled to peak 1"),
        "low_frequency": Text(choices=("auto", "zero", "free"),
                              doc="K̂(0) = 0 imposed (zero), left free, or chosen from the "
                                  "kernel's integral (auto, the default)")},
        doc="the radiation state-space fit (casemodel.radiation_ss); default: "
            "cummins.simulate's own"),
    "morison": Table(fields={"element_length": positive("m", "element length along the "
                                                        "members (default 1 m)")},
                     doc="Morison elements of the [[body.hull.members]] (forces/morison.py "
                         "MemberMorison)"),
    "linear_drag": MapOf(keys="dof", value=DofNumber(linear="m/s", rotational="rad/s", lo=0.0),
                         doc="velocity amplitudes of the Borgman-linearised member drag per "
                             "DOF (report/fowt_semi.py)"),
    "drag": Table(fields={"strip_length": positive("m", "strip length (default 1 m)"),
                          "n_strips": integer(1, "number of equal strips instead")},
                  exclusive=(("strip_length", "n_strips"),),
                  doc="Morison strips along the hull profile"),
    "mooring": _MOORING,
    "rotor": _ROTOR,
    "drift": Table(fields={
        "table": Text(required=True,
                      doc="mean drift coefficients (NetCDF of hydro.drift.drift_table): a file "
                          "shipped in hybridwsi/data, or a path relative to the case file"),
        "field": Text(choices=("combined", "far_field", "near_field"), default="combined",
                      doc="combined: far field on Surge/Sway/Yaw, near field on the others"),
        "panel_size": positive("m", "hull panel size of the solve behind the table"),
        "wave_directions": ListOf(item=Number(unit="rad"), min_length=1, unique=True,
                                  doc="wave directions solved"),
        "n_theta": integer(8, "Kochin-function angles over [0, 2 pi)"),
        "omega": ListOf(item=positive("rad/s"), min_length=2, unique=True,
                        doc="frequencies solved (scripts/oc3_drift.py)")},
        doc="second-order wave drift (hydro/drift.py, forces/drift.py SlowDriftForce)"),
    "external_force": Table(fields={"file": FilePath(
        what="force table", required=True,
        doc="CSV: 'time [s]' and F (one DOF) or F_<DOF> columns, units in the header")}),
    "force_accuracy": MapOf(value=Number(lo=0.0, hi=1.0, open_lo=True),
                            doc="relative accuracy of each generator's force"),
    "sweep": Table(fields={
        "duration": positive("s", "simulated time per sea"), "dt": positive("s", "time step"),
        "ramp": nonnegative("s", "excitation ramp; statistics start after it"),
        "dofs": ListOf(item=Dof(), min_length=1, unique=True, doc="DOFs simulated"),
        "gamma": Number(lo=1.0, doc="JONSWAP peak enhancement"),
        "wave_components": integer(1, "JONSWAP frequency components"),
        "wave_kinematics": Boolean(doc="Morison drag on the wave particle velocity")},
        doc="defaults of hybridwsi sweep --case (and of simulate --case)"),
    "simulation": Table(fields={"duration": positive("s", "simulated time"),
                                "dt": positive("s", "time step"),
                                "ramp": nonnegative("s", "excitation ramp"),
                                "wave_direction": Number(
                                    unit="deg", doc="wave propagation direction from +X"),
                                "spreading": positive(
                                    "", "cos-2s spreading exponent s of a JONSWAP sea")},
                        doc="defaults of hybridwsi simulate --case (over [sweep])"),
    "regular_waves": Table(fields={
        "period": Either(options=(positive("s"), ListOf(item=positive("s"), min_length=1)),
                         doc="wave period(s)"),
        "height": Either(options=(positive("m"), ListOf(item=positive("m"), min_length=1)),
                         doc="wave height(s)"),
        "duration": positive("s"), "dt": positive("s"), "ramp": nonnegative("s"),
        "headings_deg": ListOf(item=Number(unit="deg"), min_length=1,
                               doc="wave headings [deg] of the RAO check"),
        "window_start": nonnegative("s", "start of the regression window"),
        "steady_state_start": nonnegative("s", "start of the steady-state window")},
        doc="the case's regular seas (the paper's, the definition's)"),
    "reference_natural_frequencies": MapOf(value=positive("Hz"),
                                           doc="published natural frequencies (tests)"),
    "hybrid": _HYBRID,
    # reference data of the built-in cases (the paper's and the experiments' numbers)
    "paper_values": Table(fields={"added_mass_inf": Number(unit="kg"), "C": Number(unit="N/m"),
                                  "Te": positive("s")}, doc="as printed in the paper"),
    "paper_table1": MapOf(value=MapOf(value=Table(fields={
        "alpha": Number(unit="kg"), "beta": Number(unit="N s/m"),
        "gamma": Number(unit="N/m")})), doc="the paper's Table 1: generator -> case"),
    "sph_regular_waves": Table(fields={
        "dp": positive("m"), "depth": positive("m"), "tf": positive("s"), "hdx": positive(),
        "smooth_body": Boolean(), "gain": positive(), "symmetry": Text(), "packing": Text(),
        "alpha_body": nonnegative()}, doc="the shipped SPH run's set-up (sph/tank.py)"),
    "experiment": Table(fields={"water_depth": positive("m"), "Te0": positive("s"),
                                "rms_window": ListOf(item=nonnegative(), length=2,
                                                     doc="in units of Te0")},
                        doc="the decay experiment's parameters"),
    "drops": MapOf(value=positive("m"), doc="drop heights by name"),
})


# ------------------------------------------------------------------------- whole-case checks
def _check_dof_sets(case: dict[str, Any], ctx: Context) -> None:
    allowed = case.get("dofs")
    if allowed is None:
        return
    for at in (("default_dofs",), ("sweep", "dofs"), ("hybrid", "dofs"), ("bem", "dofs")):
        table = case.get(at[0]) if len(at) == 2 else case
        given = (table or {}).get(at[-1]) if isinstance(table, dict) else None
        extra = [d for d in given or () if d not in allowed]
        if extra:
            raise ctx.fail(at, f"{', '.join(extra)} not among the case's dofs "
                               f"({', '.join(allowed)})")


#: [forces] switch -> (what its data is, whether the case has it)
_NEEDS: dict[str, tuple[str, Callable[[dict[str, Any]], bool]]] = {
    "mooring": ("[mooring] table", lambda c: "mooring" in c),
    "morison": ("[hydrodynamics] drag_cd > 0 or members with cd",
                lambda c: c.get("hydrodynamics", {}).get("drag_cd", 0.0) > 0.0
                or any(m.get("cd", 0.0) > 0.0 or any(m.get("axial_cd", ()))
                       for m in _hull(c).get("members", ()))),
    "rotor": ("[rotor] table", lambda c: "rotor" in c),
    "linear_damping": ("[hydrodynamics] additional_damping",
                       lambda c: bool(c.get("hydrodynamics", {}).get("additional_damping"))),
    "external_force": ("[external_force] table", lambda c: "external_force" in c),
}


def _resolve_forces(case: dict[str, Any], ctx: Context) -> None:
    """Fill ``[forces]``: each switch's default from the data present; a switch on without
    its data is an error."""
    forces = dict(case.get("forces") or _FORCES.check({}, ("forces",), ctx))
    for key, (what, present) in _NEEDS.items():
        have = present(case)
        if key not in forces:
            forces[key] = ("table" if have else "none") if key == "mooring" else have
        on = forces[key] != "none" if key == "mooring" else forces[key]
        if on and not have:
            raise ctx.fail(("forces", key), f"is on but the case has no {what}")
    if forces["drift"] and "drift" not in case:
        raise ctx.fail(("forces", "drift"), "is on but the case has no [drift] table")
    if forces["mooring"] == "moordyn" and "moordyn_file" not in case["mooring"]:
        raise ctx.fail(("forces", "mooring"), "'moordyn' needs [mooring] moordyn_file (the "
                                              "MoorDyn v2 input)")
    if forces["hydrostatics"] == "nonlinear" and forces["radiation"] == "convolution":
        raise ctx.fail(("forces", "radiation"), "'convolution' works with linear hydrostatics "
                                                "only; use 'statespace'")
    case["forces"] = forces


def _hull(case: dict[str, Any]) -> dict[str, Any]:
    body = case.get("body", {})
    return body.get("hull", body)


def _check_morison_hull(case: dict[str, Any], ctx: Context) -> None:
    if not case["forces"]["morison"]:
        return
    if _hull(case).get("type") not in ("axisymmetric", "columns"):
        raise ctx.fail(("forces", "morison"), "Morison drag needs an axisymmetric (r, z) "
                                              "profile or a columns hull's members: [body] or "
                                              "[body.hull]")


# ------------------------------------------------------------------------- entry points
def validate(raw: Mapping[str, Any], label: str, directory: Path
             ) -> tuple[dict[str, Any], dict[KeyPath, str]]:
    """The normalised case and the SHA-256 of each file it references (by key path).

    Raises :class:`InputError` with one line ``"<label>: <key>: <problem>"``.
    """
    ctx = Context(label, directory)
    case = CASE.check(raw, (), ctx)
    _check_dof_sets(case, ctx)
    _resolve_forces(case, ctx)
    _check_morison_hull(case, ctx)
    return case, ctx.files


def canonical_hash(case: Mapping[str, Any], files: Mapping[KeyPath, str]) -> str:
    """SHA-256 of the normalised case with every file path replaced by the file's SHA-256:
    independent of the file's name, folder, layout, comments, key order and number
    spelling (``320`` = ``320.0`` = ``"320 m"``)."""
    data = json.loads(json.dumps(case))
    for at, digest in files.items():
        node = data
        for part in at[:-1]:
            node = node[part]
        node[at[-1]] = f"sha256:{digest}"
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=True)
    return hashlib.sha256(text.encode()).hexdigest()


def iter_nodes(node: Node = CASE, at: KeyPath = ()) -> Sequence[tuple[KeyPath, Node]]:
    """Every (key path, node) of the schema, depth first (docs and tests)."""
    out: list[tuple[KeyPath, Node]] = [(at, node)] if at else []
    children: Mapping[str, Node] = {}
    if isinstance(node, Table):
        children = node.fields
    elif isinstance(node, OneOf):
        children = {f"<{k}>": v for k, v in node.variants.items()}
    elif isinstance(node, (MapOf,)):
        children = {"<name>": node.value}
    elif isinstance(node, TableList):
        children = {"[]": node.table}
    for key, child in children.items():
        out += iter_nodes(child, (*at, key))
    return out


def _reference_rows(node: Node, at: KeyPath) -> list[tuple[str, str, str, str]]:
    """``(key, value, required/default, meaning)`` of ``node`` and everything below it."""
    need = "required" if node.required else (
        "" if node.default is MISSING else f"default `{json.dumps(node.default)}`")
    kind = node.kind()
    doc = "" if node.doc == kind else node.doc
    rows = [(dotted(at), kind.replace("|", "/"), need, doc.replace("|", "/"))]
    if isinstance(node, Table):
        for key, child in node.fields.items():
            rows += _reference_rows(child, (*at, key))
    elif isinstance(node, OneOf):
        for name, table in node.variants.items():
            rows.append((f'{dotted(at)}.type = "{name}"', "", "", ""))
            for key, child in table.fields.items():
                rows += _reference_rows(child, (*at, key))
    elif isinstance(node, MapOf):
        rows += _reference_rows(node.value, (*at, "<DOF>" if node.keys == "dof" else "<name>"))
    elif isinstance(node, TableList):
        for key, child in node.table.fields.items():
            rows += _reference_rows(child, (*at, 0, key))
    return rows


def markdown_reference() -> str:
    """The key reference of docs/CASES.md, generated from :data:`CASE` (a test keeps the
    document equal to it): the top-level keys, then one table per top-level table."""
    head = ["| key | value | | meaning |", "|---|---|---|---|"]
    scalars = [k for k, n in CASE.fields.items() if not isinstance(n, (Table, OneOf, MapOf))]
    out = ["#### top level", "", *head]
    for key in scalars:
        out += [f"| `{k}` | {v} | {n} | {d} |"
                for k, v, n, d in _reference_rows(CASE.fields[key], (key,))]
    for key, node in CASE.fields.items():
        if key in scalars:
            continue
        out += ["", f"#### `[{key}]`", "", *head]
        out += [f"| `{k}` | {v} | {n} | {d} |" for k, v, n, d in _reference_rows(node, (key,))]
    return "\n".join(out) + "\n"


__all__ = ["CASE", "BODIES", "MOORING_MODELS", "Context", "Node", "Number", "Table",
           "canonical_hash", "dotted", "validate", "iter_nodes", "markdown_reference"]
