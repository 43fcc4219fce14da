"""Cylindrical members of a floating frame (columns, heave plates, pontoons, braces): the member
geometry (:class:`Member`) and its cut into strip elements for Morison's equation
(:func:`member_elements`, :func:`point_jacobians`).

A member is a straight circular cylinder between two end points [m] (global frame at rest, z
up from the still-water level) with a diameter [m] and a flag ``potential`` (part of the
potential-flow panel model, or a slender member for strip theory only). Case entries may carry
the Morison coefficients ``cd``, ``ca`` (transverse) and ``axial_cd`` (per end); the geometry
ignores them (:data:`COEFFICIENT_KEYS`), the elements carry them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridwsi.bodies.base import positive, vector3
from hybridwsi.errors import InputError

#: Morison coefficients a member entry may carry (forces/morison.py); not geometry
COEFFICIENT_KEYS = ("cd", "ca", "axial_cd", "axial_ca")
#: tolerance [m] for "same axis", "touching ends" and the symmetry checks
_GEOM_TOL = 1e-6
#: default element length [m] (the OpenFAST deck's MDivSize)
DEFAULT_ELEMENT_LENGTH = 1.0


@dataclass(frozen=True)
class Member:
    """A straight circular cylinder between two end points.

    Parameters
    ----------
    name : str
        Label (e.g. ``"pontoon_lower_1"``).
    ends : ((x, y, z), (x, y, z))
        End points of the axis, global frame at rest [m].
    diameter : float
        Outer diameter [m].
    potential : bool
        True: in the potential-flow (panel) model, must be vertical; False: slender member
        (strip theory only).
    """

    name: str
    ends: tuple[tuple[float, float, float], tuple[float, float, float]]
    diameter: float
    potential: bool = False

    def __post_init__(self) -> None:
        try:
            a, b = self.ends
        except (TypeError, ValueError):
            raise InputError(f"member {self.name!r}: ends must be two points [m]") from None
        a, b = vector3(f"member {self.name!r} end 1", a), vector3(f"member {self.name!r} end 2", b)
        if math.dist(a, b) <= _GEOM_TOL:
            raise InputError(f"member {self.name!r} has coincident ends")
        object.__setattr__(self, "name", str(self.name))
        object.__setattr__(self, "ends", (a, b))
        object.__setattr__(self, "diameter", positive(f"diameter of {self.name!r}", self.diameter))
        if not isinstance(self.potential, (bool, np.bool_)):
            raise InputError(f"member {self.name!r}: potential must be true or false")
        object.__setattr__(self, "potential", bool(self.potential))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Member:
        """A member from a case entry (Morison coefficient keys are dropped)."""
        if not isinstance(data, dict):
            raise InputError(f"a member must be a table, got {data!r}")
        geometry = {k: v for k, v in data.items() if k not in COEFFICIENT_KEYS}
        try:
            return cls(**geometry)
        except TypeError as exc:
            raise InputError(f"cannot build a member from {data}: {exc} (keys: name, ends, "
                             f"diameter, potential, and Morison {list(COEFFICIENT_KEYS)})") from None

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "ends": [list(p) for p in self.ends],
                "diameter": self.diameter, "potential": self.potential}

    @property
    def radius(self) -> float:
        return 0.5 * self.diameter

    @property
    def vertical(self) -> bool:
        (xa, ya, _), (xb, yb, _) = self.ends
        return math.hypot(xb - xa, yb - ya) <= _GEOM_TOL

    def submerged_axis(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The axis segment below z = 0 (two points [m]), or None when dry."""
        a, b = (np.asarray(p, dtype=float) for p in self.ends)
        if a[2] >= 0.0 and b[2] >= 0.0:
            return None
        if a[2] > b[2]:
            a, b = b, a
        if b[2] > 0.0:  # pierces the free surface: cut at z = 0
            b = a + (b - a) * (-a[2]) / (b[2] - a[2])
        return a, b



@dataclass(frozen=True)
class MemberElements:
    """Strip elements and axial end discs of the submerged parts of cylindrical members.

    Attributes
    ----------
    centre, tangent : ndarray, shape (n, 3)
        Element centres [m] (global frame at rest) and unit axis directions.
    length, diameter, cd, ca : ndarray, shape (n,)
        Element length [m], diameter [m], transverse drag and added-mass coefficients [-].
    inertia : ndarray of bool, shape (n,)
        Morison inertia (added mass and wave inertia) on this element: the members outside
        the potential-flow model (``potential = false``).
    end_centre, end_axis : ndarray, shape (m, 3)
        Centres [m] and unit normals of the end discs with an axial drag coefficient.
    end_area, end_cd : ndarray, shape (m,)
        Disc areas π D²/4 [m²] and axial drag coefficients [-].
    member : tuple of str
        Member name of each element.
    """

    centre: np.ndarray
    tangent: np.ndarray
    length: np.ndarray
    diameter: np.ndarray
    cd: np.ndarray
    ca: np.ndarray
    inertia: np.ndarray
    end_centre: np.ndarray
    end_axis: np.ndarray
    end_area: np.ndarray
    end_cd: np.ndarray
    member: tuple[str, ...]

    @property
    def volume(self) -> np.ndarray:
        """Element volumes π D²/4 l [m³]."""
        return 0.25 * math.pi * self.diameter**2 * self.length


def _coefficient(data: Mapping[str, Any], key: str, count: int) -> np.ndarray:
    """A member's Morison coefficient(s) ``key`` (default 0) as ``count`` finite values >= 0."""
    raw = data.get(key, 0.0)
    try:
        value = np.asarray(raw, dtype=float)
    except (TypeError, ValueError):
        value = np.array([np.nan])
    if value.ndim == 0:
        value = np.full(count, float(value))
    if value.shape != (count,) or not np.all(np.isfinite(value)) or np.any(value < 0):
        raise InputError(f"member {data.get('name')!r}: {key} must be {count} finite value(s) "
                         f">= 0, got {raw!r}")
    return value


def member_elements(members: Sequence[Mapping[str, Any]],
                    element_length: float = DEFAULT_ELEMENT_LENGTH) -> MemberElements:
    """Cut the submerged part of each member into equal elements of length <= ``element_length``.

    ``members``: case entries (``name``, ``ends``, ``diameter``, ``potential``; Morison ``cd``,
    ``ca`` transverse and ``axial_cd`` = [end 1, end 2], all default 0). Dry members and dry
    ends give nothing; a member cut by the free surface keeps its wet part.
    """
    if not (math.isfinite(element_length) and element_length > 0):
        raise InputError(f"Morison: element_length must be > 0 [m], got {element_length}")
    rows, ends = [], []
    for data in members:
        m = Member.from_dict(dict(data))
        cd, ca = _coefficient(data, "cd", 1)[0], _coefficient(data, "ca", 1)[0]
        axial = _coefficient(data, "axial_cd", 2)
        seg = m.submerged_axis()
        if seg is None:
            continue
        a, b = seg
        span = float(np.linalg.norm(b - a))
        n = max(1, math.ceil(span / element_length - 1e-9))
        t = (b - a) / span
        for k in range(n):
            rows.append(((a + (k + 0.5) / n * (b - a)), t, span / n, m.diameter, cd, ca,
                         not m.potential, m.name))
        axis = (np.asarray(m.ends[1]) - np.asarray(m.ends[0])) / math.dist(*m.ends)
        for k, end in enumerate(m.ends):
            if axial[k] > 0 and end[2] < 0:
                ends.append((np.asarray(end, float), axis, 0.25 * math.pi * m.diameter**2,
                             axial[k]))
    if not rows:
        raise InputError("Morison: no member is below the still-water level")
    col = list(zip(*rows))
    ecol = list(zip(*ends)) if ends else [np.zeros((0, 3)), np.zeros((0, 3)), (), ()]
    return MemberElements(
        centre=np.array(col[0]), tangent=np.array(col[1]), length=np.array(col[2]),
        diameter=np.array(col[3]), cd=np.array(col[4]), ca=np.array(col[5]),
        inertia=np.array(col[6], dtype=bool), member=tuple(col[7]),
        end_centre=np.array(ecol[0]).reshape(-1, 3), end_axis=np.array(ecol[1]).reshape(-1, 3),
        end_area=np.array(ecol[2], dtype=float), end_cd=np.array(ecol[3], dtype=float))


def point_jacobians(points: np.ndarray, reference_point: Sequence[float] = (0.0, 0.0, 0.0)
                    ) -> np.ndarray:
    """(n, 3, 6): velocity of each point per unit DOF rate, ``v = v_O + ω × r`` (small angles),
    ``r`` from the reference point O; its transpose maps a point force to forces and moments
    about O."""
    r = np.asarray(points, dtype=float) - np.asarray(reference_point, dtype=float)
    jac = np.zeros((r.shape[0], 3, 6))
    jac[:, 0, 0] = jac[:, 1, 1] = jac[:, 2, 2] = 1.0
    # ω × r = -r × ω: rows of -[r×]
    jac[:, 0, 4], jac[:, 0, 5] = r[:, 2], -r[:, 1]
    jac[:, 1, 3], jac[:, 1, 5] = -r[:, 2], r[:, 0]
    jac[:, 2, 3], jac[:, 2, 4] = r[:, 1], -r[:, 0]
    return jac
