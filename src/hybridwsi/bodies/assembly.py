"""A rigid assembly: a hull body plus mass items (tower, nacelle, rotor, ballast…).

The items are rigidly fixed to the hull. The assembly is itself a :class:`Body`: its geometry,
hydrostatic integrals, meshes and exact heave volume are the hull's; its mass, centre of mass
and inertia are the sums over the hull and the items (parallel-axis theorem), so the gravity
term of the roll/pitch stiffness and the mass matrix use the whole structure.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridwsi.bodies.base import (Body, WaterplaneMoments, as_tuple_matrix, body_from_dict,
                                   inertia_matrix, parallel_axis, positive, vector3)
from hybridwsi.errors import InputError


@dataclass(frozen=True)
class MassItem:
    """A rigid mass fixed to the hull.

    Parameters
    ----------
    name : str
        Label (e.g. ``"tower"``).
    mass : float
        Mass [kg].
    cm : (3,) floats
        Its centre of mass in the global frame at rest [m].
    inertia_about_cm : (3,) or (3, 3) floats, optional
        Inertia about its own centre of mass [kg m^2]; default zero (a point mass).
    """

    name: str
    mass: float
    cm: tuple[float, float, float]
    inertia_about_cm: Any = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", str(self.name))
        object.__setattr__(self, "mass", positive(f"mass of {self.name}", self.mass))
        object.__setattr__(self, "cm", vector3(f"cm of {self.name}", self.cm))
        object.__setattr__(self, "inertia_about_cm", as_tuple_matrix(
            inertia_matrix(f"inertia_about_cm of {self.name}", self.inertia_about_cm)))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> MassItem:
        """Inverse of :meth:`to_dict`; also takes the case files' ``inertia`` key for
        ``inertia_about_cm``."""
        kwargs = dict(data)
        if "inertia" in kwargs:
            if "inertia_about_cm" in kwargs:
                raise InputError(f"mass item {kwargs.get('name')!r}: give inertia or "
                                 "inertia_about_cm, not both")
            kwargs["inertia_about_cm"] = kwargs.pop("inertia")
        try:
            return cls(**kwargs)
        except TypeError as exc:
            raise InputError(f"cannot build a MassItem from {data}: {exc}") from None

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "mass": self.mass, "cm": list(self.cm),
                "inertia_about_cm": [list(row) for row in self.inertia_about_cm]}


def combine(items: Sequence[MassItem]) -> tuple[float, np.ndarray, np.ndarray]:
    """Total mass [kg], centre of mass (3,) [m] and inertia about it (3, 3) [kg m^2]:
    ``I_G = sum_k [I_k + m_k (|d_k|² 1 - d_k d_kᵀ)]`` with ``d_k = c_k - G``."""
    masses = np.array([it.mass for it in items])
    centres = np.array([it.cm for it in items])
    total = float(masses.sum())
    g = masses @ centres / total
    inertia = sum(np.asarray(it.inertia_about_cm) + parallel_axis(it.mass, np.asarray(it.cm) - g)
                  for it in items)
    return total, g, inertia


@dataclass(frozen=True)
class RigidAssembly(Body):
    """A hull body with mass items rigidly attached; itself a :class:`Body`.

    Parameters
    ----------
    hull : Body
        The floating hull (geometry, hydrostatics, meshes, water properties). Its own mass,
        centre of mass and inertia count as one item (set them to the hull's structure).
    items : sequence of MassItem
        The other masses.
    reference_point : (3,) floats, optional
        DOF origin O [m]; default the assembly's centre of mass.
    name : str, optional
        Default: the hull's name.
    """

    hull: Body
    items: tuple[MassItem, ...] = ()
    reference_point: Any = None
    name: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.hull, Body):
            raise InputError(f"hull must be a hybridwsi.bodies.Body, got {type(self.hull).__name__}")
        items = tuple(it if isinstance(it, MassItem) else MassItem.from_dict(it)
                      for it in self.items)
        object.__setattr__(self, "items", items)
        ref = (tuple(float(v) for v in self.parts()[1]) if self.reference_point is None
               else vector3("reference_point", self.reference_point))
        object.__setattr__(self, "reference_point", ref)
        object.__setattr__(self, "name", self.hull.name if self.name is None else str(self.name))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> RigidAssembly:
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(hull=body_from_dict(data["hull"]),
                       items=tuple(MassItem.from_dict(it) for it in data.get("items", ())),
                       reference_point=data.get("reference_point"), name=data.get("name"))
        except (KeyError, TypeError) as exc:
            raise InputError(f"cannot build a RigidAssembly from {data}: {exc}") from None

    def to_dict(self) -> dict[str, Any]:
        return {"type": "RigidAssembly", "hull": self.hull.to_dict(),
                "items": [it.to_dict() for it in self.items],
                "reference_point": list(self.reference_point), "name": self.name}

    # ------------------------------------------------------------------ mass properties
    def parts(self) -> tuple[float, np.ndarray, np.ndarray]:
        """Total mass, centre of mass and inertia about it (hull and items, :func:`combine`)."""
        hull_item = MassItem("hull", self.hull.mass, self.hull.cog, self.hull.inertia_about_cog)
        return combine((hull_item, *self.items))

    @property
    def mass(self) -> float:  # type: ignore[override]
        return self.parts()[0]

    @property
    def cog(self) -> tuple[float, float, float]:
        return tuple(float(v) for v in self.parts()[1])

    @property
    def inertia_about_cog(self) -> np.ndarray:
        return self.parts()[2]

    # ------------------------------------------------------------------ the hull's
    @property
    def rho(self) -> float:  # type: ignore[override]
        return self.hull.rho

    @property
    def g(self) -> float:  # type: ignore[override]
        return self.hull.g

    @property
    def dofs(self) -> tuple[str, ...]:  # type: ignore[override]
        return self.hull.dofs

    @property
    def draft(self) -> float:
        return self.hull.draft

    @property
    def exact_restoring_dofs(self) -> tuple[str, ...]:
        return self.hull.exact_restoring_dofs

    def displaced_volume(self) -> float:
        return self.hull.displaced_volume()

    def center_of_buoyancy(self) -> np.ndarray:
        return self.hull.center_of_buoyancy()

    def waterplane_moments(self) -> WaterplaneMoments:
        return self.hull.waterplane_moments()

    def wetted_area(self) -> float:
        return self.hull.wetted_area()

    def submerged_volume(self, heave: float | np.ndarray) -> float | np.ndarray:
        return self.hull.submerged_volume(heave)

    def mesh_options(self, *args: Any, **options: Any) -> dict[str, Any]:
        return self.hull.mesh_options(*args, **options)

    def mesh_description(self, **options: Any) -> dict[str, Any]:
        return self.hull.mesh_description(**options)

    def mesh(self, *, symmetric: bool = True, lid: bool = True, **options: Any):
        return self.hull.mesh(symmetric=symmetric, lid=lid, **options)
