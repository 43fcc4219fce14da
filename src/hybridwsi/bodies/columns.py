"""A floating body of vertical circular columns (in the panel model) and slender members
(strip theory): semi-submersibles such as the OC4-DeepCwind platform.

The body is a list of cylindrical :class:`Member` s, each a straight circular cylinder between
two end points [m] (global frame at rest, z up from the still-water level) with a diameter [m]
and a flag ``potential``:

- ``potential = True``: the member is part of the potential-flow (BEM) model. Such members must
  be vertical; those sharing an axis (x, y) and touching end to end form one *column*, a body
  of revolution about its own axis with a stepped (r, z) profile (e.g. an offset column of
  12 m diameter on a 24 m base column, the heave plate). Every column must pierce the
  waterline. The columns are meshed (panels) and give the exact frusta hydrostatics of
  :mod:`hybridwsi.bodies.axisymmetric`, each about its own axis.
- ``potential = False``: a slender member (pontoon, brace) left to Morison's equation
  (:mod:`hybridwsi.forces.morison`), not meshed. It still displaces water, so its submerged
  part enters the hydrostatics: volume ``π R² l`` (``l`` the submerged axis length; exact for
  a cylinder cut obliquely by the free surface), centroid at the middle of the submerged axis
  and, where it pierces the free surface, an elliptical waterplane (semi-axes ``R`` and
  ``R / cos φ``, φ the inclination from vertical). Overlaps with the columns at the joints
  (a member end touching a column wall) are neglected.

Member entries may carry Morison coefficients (``cd``, ``ca``, ``axial_cd``, ``axial_ca``): the
body ignores them (they are read by the Morison component), so changing a drag coefficient does
not change the body or its BEM cache key.

Mesh: quadrilateral panels on each column (triangles at the keel centre), clipped at z = 0
by construction, outward normals, conforming at the steps (one angular division per column, set
by its largest radius), and a waterplane lid of concentric rings (normals down). With
``symmetry = n >= 2`` the layout must have the dihedral symmetry of order n with a mirror plane
y = 0: one column on the z axis (optional) and n columns that are rotations by 360°/n of one
column on the negative x axis; then only one 2n-th of the hull is meshed and Capytaine's
``RotationSymmetricMesh(ReflectionSymmetricMesh(...), n)`` carries the rest (the BEM cost drops
roughly by the group order, 2n). ``symmetry = 1``: the full mesh.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridwsi.bodies.axisymmetric import _check_profile, _clip, _volume
from hybridwsi.bodies.base import (Body, WaterplaneMoments, as_tuple_matrix, inertia_matrix,
                                   positive, vector3)
from hybridwsi.bodies.members import _GEOM_TOL, Member
from hybridwsi.errors import InputError



@dataclass(frozen=True)
class Column:
    """A vertical body of revolution about the axis ``(x, y)`` with an (r, z) ``profile`` [m]
    (keel centre first, :class:`hybridwsi.bodies.AxisymmetricBody` conventions)."""

    axis: tuple[float, float]
    profile: tuple[tuple[float, float], ...]

    @property
    def immersed(self) -> np.ndarray:
        return _clip(np.asarray(self.profile), 0.0)

    @property
    def waterline_radius(self) -> float:
        return float(self.immersed[-1, 0])


def columns_from_members(members: Sequence[Member]) -> tuple[Column, ...]:
    """Group the potential-flow members into columns (same axis, end to end).

    Raises
    ------
    InputError
        A potential member that is not vertical, overlapping or disjoint pieces on one axis,
        or a column that does not pierce the waterline.
    """
    groups: dict[tuple[float, float], list[tuple[float, float, float]]] = {}
    for m in members:
        if not m.potential:
            continue
        if not m.vertical:
            raise InputError(f"member {m.name!r}: potential-flow members must be vertical "
                             "(columns); leave inclined members to strip theory (potential = false)")
        (x, y, za), (_, _, zb) = m.ends
        key = next((k for k in groups if math.hypot(k[0] - x, k[1] - y) <= _GEOM_TOL), (x, y))
        groups.setdefault(key, []).append((min(za, zb), max(za, zb), m.radius))
    columns = []
    for (x, y), pieces in groups.items():
        pieces.sort()
        points = [(0.0, pieces[0][0])]
        for k, (z0, z1, r) in enumerate(pieces):
            if k and abs(z0 - pieces[k - 1][1]) > _GEOM_TOL:
                raise InputError(f"the potential members on the axis ({x:g}, {y:g}) must touch "
                                 f"end to end (gap or overlap at z = {z0:g} m)")
            points += [(r, z0), (r, z1)]
        rz = np.array(points)
        keep = np.ones(len(rz), bool)
        keep[1:] = np.any(np.abs(np.diff(rz, axis=0)) > 0, axis=1)  # repeated points
        # points inside a straight wall (same radius before and after) carry no geometry
        columns.append(Column((float(x), float(y)), tuple(map(tuple, rz[keep].tolist()))))
    for col in columns:
        try:
            _check_profile(col.profile)
        except InputError as exc:
            raise InputError(f"column on the axis {col.axis}: {exc}") from None
    return tuple(columns)


@dataclass(frozen=True)
class ColumnsBody(Body):
    """Vertical columns (panel model) and slender members (strip theory); module docstring.

    Parameters
    ----------
    members : sequence of Member or dict
        The cylinders (:class:`Member`; dicts as in a case file).
    mass : float
        Mass [kg] of the structure (with ballast).
    cog : (3,) floats
        Centre of mass G [m].
    inertia : (3,) or (3, 3) floats, optional
        Inertia about G [kg m^2].
    reference_point : (3,) floats, optional
        DOF origin O [m]; default (0, 0, 0), the SWL on the z axis.
    rho, g : float
        Water density [kg/m^3] and gravity [m/s^2].
    name : str
        Name of the Capytaine body.
    symmetry : int
        Order n of the layout's dihedral symmetry used by the mesh (1: none).
    """

    members: Any
    mass: float
    cog: tuple[float, float, float]
    inertia: Any = None
    reference_point: Any = (0.0, 0.0, 0.0)
    rho: float = 1025.0
    g: float = 9.81
    name: str = "columns"
    symmetry: int = 1

    def __post_init__(self) -> None:
        members = tuple(m if isinstance(m, Member) else Member.from_dict(dict(m))
                        for m in self.members)
        if not any(m.potential for m in members):
            raise InputError("a ColumnsBody needs at least one potential-flow column")
        names = [m.name for m in members]
        if len(set(names)) != len(names):
            raise InputError(f"member names must be unique, got {names}")
        if int(self.symmetry) != self.symmetry or self.symmetry < 1:
            raise InputError(f"symmetry must be a positive integer, got {self.symmetry!r}")
        for name, value in (("members", members), ("mass", positive("mass", self.mass)),
                            ("cog", vector3("cog", self.cog)),
                            ("inertia", as_tuple_matrix(inertia_matrix("inertia", self.inertia))),
                            ("reference_point", vector3("reference_point", self.reference_point)),
                            ("rho", positive("rho", self.rho)), ("g", positive("g", self.g)),
                            ("name", str(self.name)), ("symmetry", int(self.symmetry))):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "_columns", columns_from_members(members))
        if self.symmetry > 1:
            _fundamental_columns(self.columns, self.symmetry)  # raises if the layout lacks it

    # ------------------------------------------------------------------ description
    def to_dict(self) -> dict[str, Any]:
        return {"type": "ColumnsBody", "members": [m.to_dict() for m in self.members],
                "mass": self.mass, "cog": list(self.cog),
                "inertia": [list(row) for row in self.inertia],
                "reference_point": list(self.reference_point), "rho": self.rho, "g": self.g,
                "name": self.name, "symmetry": self.symmetry}

    @property
    def columns(self) -> tuple[Column, ...]:
        """The potential-flow columns (:func:`columns_from_members`)."""
        return self._columns  # type: ignore[attr-defined]

    @property
    def slender_members(self) -> tuple[Member, ...]:
        """Members left to strip theory (``potential = False``)."""
        return tuple(m for m in self.members if not m.potential)

    @property
    def inertia_about_cog(self) -> np.ndarray:
        return np.asarray(self.inertia, dtype=float)

    # ------------------------------------------------------------------ hydrostatics
    @property
    def draft(self) -> float:
        lowest = min(min(p[2] for p in m.ends) for m in self.members)
        return -float(lowest)

    def volume_parts(self) -> dict[str, tuple[float, np.ndarray]]:
        """Submerged volume [m^3] and its centroid (3,) [m] per column and slender member
        (keys ``"column (x, y)"`` and member names); dry members are absent."""
        parts = {}
        for col in self.columns:
            vol, moment = _volume(col.immersed)
            parts[f"column ({col.axis[0]:g}, {col.axis[1]:g})"] = (
                vol, np.array([col.axis[0], col.axis[1], moment / vol]))
        for m in self.slender_members:
            seg = m.submerged_axis()
            if seg is not None:
                a, b = seg
                parts[m.name] = (math.pi * m.radius**2 * float(np.linalg.norm(b - a)),
                                 0.5 * (a + b))
        return parts

    def displaced_volume(self) -> float:
        return float(sum(v for v, _ in self.volume_parts().values()))

    def center_of_buoyancy(self) -> np.ndarray:
        parts = self.volume_parts().values()
        return sum(v * c for v, c in parts) / sum(v for v, _ in parts)

    def waterplane_moments(self) -> WaterplaneMoments:
        """Sum over the columns' circles and the piercing members' ellipses."""
        total = np.zeros(6)  # area, sx, sy, sxx, syy, sxy
        for col in self.columns:
            a = col.waterline_radius
            total += _patch(math.pi * a**2, col.axis, np.eye(2) * math.pi * a**4 / 4)
        for m in self.slender_members:
            (pa, pb) = (np.asarray(p, dtype=float) for p in m.ends)
            if (pa[2] < 0.0) == (pb[2] < 0.0) or pa[2] == pb[2]:
                continue  # does not pierce (or lies in) the free surface
            d = pb - pa
            cross = pa + d * (-pa[2]) / d[2]
            cos_phi = abs(d[2]) / float(np.linalg.norm(d))
            r = m.radius
            area = math.pi * r**2 / cos_phi
            horiz = d[:2] / max(float(np.hypot(*d[:2])), 1e-300)
            u = horiz if np.hypot(*d[:2]) > 0 else np.array([1.0, 0.0])
            v = np.array([-u[1], u[0]])
            own = area / 4 * ((r / cos_phi) ** 2 * np.outer(u, u) + r**2 * np.outer(v, v))
            total += _patch(area, cross[:2], own)
        return WaterplaneMoments(*map(float, total))

    def wetted_area(self) -> float:
        """Wetted area of the columns [m^2] (the meshed surface)."""
        area = 0.0
        for col in self.columns:
            rz = col.immersed
            dr, dz = np.diff(rz[:, 0]), np.diff(rz[:, 1])
            area += float(np.sum(math.pi * (rz[:-1, 0] + rz[1:, 0]) * np.hypot(dr, dz)))
        return area

    # ------------------------------------------------------------------ meshes
    def mesh_description(self, **options: Any) -> dict[str, Any]:
        h = self.mesh_options(**options)["panel_size"]
        return {"kind": "columns", "panel_size": h, "symmetry": self.symmetry,
                "n_hull_panels": int(sum(len(f) for _, f in self._hull_parts(h)) *
                                     (2 * self.symmetry if self.symmetry > 1 else 1))}

    def _hull_parts(self, h: float, lid: bool = False) -> list[tuple[np.ndarray, list]]:
        """(vertices, faces) of each column patch of the meshed region (the fundamental
        2n-th with symmetry, else everything); the lid discs with ``lid``."""
        parts = []
        n = self.symmetry
        for col, (t0, t1) in _meshed_sectors(self.columns, n):
            rz = np.array([[0.0, 0.0], [col.waterline_radius, 0.0]]) if lid else col.immersed
            # one angular division per column, from its largest radius (conforming steps)
            r_max = float(np.max(col.immersed[:, 0]))
            per_turn = max(8, 4 * math.ceil(math.pi * r_max / (2 * h) - 1e-9))
            if n > 1:  # a whole number of divisions per mirror sector (2n per turn)
                per_turn = 2 * n * math.ceil(per_turn / (2 * n))
            n_theta = max(1, round(per_turn * (t1 - t0) / (2 * math.pi)))
            parts.append(_revolution(col.axis, _profile_points(rz, h), t0, t1, n_theta))
        return parts

    def mesh(self, *, symmetric: bool = True, lid: bool = True, **options: Any):
        """Capytaine ``(hull, lid or None)``; ``options``: ``panel_size`` [m] or ``n_panels``.

        With ``symmetry > 1`` and ``symmetric``: ``RotationSymmetricMesh`` of a
        ``ReflectionSymmetricMesh`` (module docstring); else plain meshes.
        """
        import capytaine as cpt

        h = self.mesh_options(**options)["panel_size"]

        def assemble(parts, name):
            verts, faces, offset = [], [], 0
            for v, f in parts:
                verts.append(v)
                faces += [[i + offset for i in face] for face in f]
                offset += len(v)
            # built clean (no degenerate panels; the copies of an axis point are harmless):
            # Capytaine's per-panel cleaning loop would cost seconds on 10 000 panels
            mesh = cpt.Mesh(np.concatenate(verts), faces, name=name, auto_clean=False)
            if self.symmetry > 1:
                half = cpt.ReflectionSymmetricMesh(half=mesh, plane="xOz", name=name)
                mesh = cpt.RotationSymmetricMesh(wedge=half, n=self.symmetry, name=name)
                if not symmetric:
                    mesh = mesh.merged()
            return mesh

        hull = assemble(self._hull_parts(h), self.name)
        lid_mesh = None
        if lid:
            lid_mesh = assemble(self._hull_parts(h, lid=True), f"{self.name}_lid")
            lid_mesh = lid_mesh.with_normal_vector_going_down()
        return hull, lid_mesh


# ---------------------------------------------------------------------------- geometry helpers
def _patch(area: float, centre: Sequence[float], own: np.ndarray) -> np.ndarray:
    """(area, sx, sy, sxx, syy, sxy) of a waterplane patch with centroid ``centre`` and
    second moments ``own`` (2x2) about it."""
    x, y = float(centre[0]), float(centre[1])
    return np.array([area, area * x, area * y, own[0, 0] + area * x * x,
                     own[1, 1] + area * y * y, own[0, 1] + area * x * y])


def _profile_points(rz: np.ndarray, h: float) -> np.ndarray:
    """Profile points at spacing <= ``h`` [m] along every segment."""
    pts = [rz[:1]]
    for p, q in zip(rz[:-1], rz[1:]):
        n = max(1, math.ceil(math.hypot(*(q - p)) / h - 1e-9))
        pts.append(p + np.outer(np.arange(1, n + 1) / n, q - p))
    return np.concatenate(pts)


def _revolution(axis: Sequence[float], rz: np.ndarray, t0: float, t1: float, n_theta: int
                ) -> tuple[np.ndarray, list[list[int]]]:
    """Panels of the surface of revolution of ``rz`` about the vertical ``axis`` for angles
    ``t0 -> t1`` [rad] in ``n_theta`` steps. Face order (i, j), (i, j+1), (i+1, j+1), (i+1, j)
    gives normals pointing out of a solid whose profile runs from the keel centre up (the
    side the profile turns to the right of); a point at r = 0 is shared (triangles)."""
    theta = np.linspace(t0, t1, n_theta + 1)
    n_p, n_t = len(rz), n_theta + 1
    verts = np.empty((n_p, n_t, 3))
    verts[..., 0] = axis[0] + rz[:, :1] * np.cos(theta)
    verts[..., 1] = axis[1] + rz[:, :1] * np.sin(theta)
    verts[..., 2] = rz[:, 1:2]
    index = np.arange(n_p * n_t).reshape(n_p, n_t)
    faces = []
    for i in range(n_p - 1):
        for j in range(n_theta):
            a, b, c, d = index[i, j], index[i, j + 1], index[i + 1, j + 1], index[i + 1, j]
            if rz[i, 0] == 0.0:
                faces.append([a, c, d, d])  # fan around the axis point (b coincides with a)
            elif rz[i + 1, 0] == 0.0:
                faces.append([a, b, c, c])
            else:
                faces.append([a, b, c, d])
    return verts.reshape(-1, 3), faces


def _fundamental_columns(columns: Sequence[Column], n: int
                         ) -> tuple[Column | None, Column]:
    """The central column (or None) and the column on the negative x axis of a layout with
    the dihedral symmetry of order ``n`` (mirror y = 0); InputError otherwise."""
    central = [c for c in columns if math.hypot(*c.axis) <= _GEOM_TOL]
    outer = [c for c in columns if math.hypot(*c.axis) > _GEOM_TOL]
    base = [c for c in outer if abs(c.axis[1]) <= _GEOM_TOL and c.axis[0] < 0]
    if len(central) > 1 or len(base) != 1 or len(outer) != n:
        raise InputError(f"symmetry = {n} needs at most one column on the z axis and {n} outer "
                         f"columns, one of them on the negative x axis (got {len(central)} "
                         f"central, {len(outer)} outer)")
    ref = base[0]
    rho = -ref.axis[0]
    for k in range(n):
        phi = math.pi + 2 * math.pi * k / n
        target = (rho * math.cos(phi), rho * math.sin(phi))
        match = [c for c in outer if math.dist(c.axis, target) <= 1e-4 * max(rho, 1.0)]
        if len(match) != 1 or not np.allclose(match[0].profile, ref.profile, atol=_GEOM_TOL):
            raise InputError(f"symmetry = {n}: no column identical to the one at "
                             f"{ref.axis} at the rotated position ({target[0]:.6g}, "
                             f"{target[1]:.6g}) m")
    return (central[0] if central else None), ref


def _meshed_sectors(columns: Sequence[Column], n: int) -> list[tuple[Column, tuple[float, float]]]:
    """Each column to mesh with its angular range about its own axis [rad]: everything for
    ``n = 1``; else the fundamental region (central column for π − π/n ... π, the column on
    the negative x axis for 0 ... π, i.e. its y >= 0 half)."""
    if n == 1:
        return [(c, (0.0, 2 * math.pi)) for c in columns]
    central, ref = _fundamental_columns(columns, n)
    parts = [] if central is None else [(central, (math.pi - math.pi / n, math.pi))]
    return parts + [(ref, (0.0, math.pi))]
