"""A body from any mesh file Capytaine reads, with user-given mass properties.

The file (``cpt.load_mesh``: GDF/WAMIT, Nemoh ``.mar``, HydroStar ``.hst``, HAMS ``.pnl``,
Capytaine NetCDF, and STL/OBJ/MSH… when meshio or trimesh is installed) holds the hull at rest
in the global frame (z up from the still-water level); parts above z = 0 are clipped off.
Its panels are the BEM panels: there is no panel size to choose.

Hydrostatics come from Capytaine's mesh integrals on the immersed hull (volume, centre of
buoyancy, waterplane integrals); the gravity term and the reference point enter through
:meth:`hybridwsi.bodies.base.Body.hydrostatic_stiffness`, as for every body. The lid is
Capytaine's ``generate_lid`` at z = 0.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from hybridwsi.bodies.base import (Body, WaterplaneMoments, as_tuple_matrix, inertia_matrix,
                                   positive, vector3)
from hybridwsi.errors import InputError


@dataclass(frozen=True)
class MeshBody(Body):
    """A floating body whose wetted hull is read from a mesh file.

    Parameters
    ----------
    mesh_file : str or path
        Mesh file readable by ``capytaine.load_mesh`` (module docstring).
    mass : float
        Mass [kg].
    cog : (3,) floats
        Centre of mass G in the global frame [m].
    inertia : (3,) or (3, 3) floats, optional
        Inertia about G [kg m^2]; default zero (give it for rotational DOFs).
    reference_point : (3,) floats, optional
        DOF origin O [m]; default the centre of mass.
    rho, g : float
        Water density [kg/m^3] (default 1025) and gravity [m/s^2].
    name : str, optional
        Name of the Capytaine body; default the file name without extension.
    file_format : str, optional
        Format hint for ``load_mesh`` when the extension does not tell it.
    """

    mesh_file: Any
    mass: float
    cog: tuple[float, float, float]
    inertia: Any = None
    reference_point: Any = None
    rho: float = 1025.0
    g: float = 9.81
    name: str | None = None
    file_format: str | None = None

    def __post_init__(self) -> None:
        path = Path(self.mesh_file).expanduser()
        if not path.is_file():
            raise InputError(f"mesh file {path} not found")
        cog = vector3("cog", self.cog)
        ref = cog if self.reference_point is None else vector3("reference_point", self.reference_point)
        for name, value in (("mesh_file", str(path)), ("mass", positive("mass", self.mass)),
                            ("cog", cog), ("reference_point", ref),
                            ("inertia", as_tuple_matrix(inertia_matrix("inertia", self.inertia))),
                            ("rho", positive("rho", self.rho)), ("g", positive("g", self.g)),
                            ("name", path.stem if self.name is None else str(self.name))):
            object.__setattr__(self, name, value)
        if self.hull.nb_faces == 0:
            raise InputError(f"mesh {path} has no panels below the still-water level z = 0")
        if not self.hull.waterplane_area > 0:
            raise InputError(f"mesh {path} does not pierce the free surface (no waterplane)")

    # ------------------------------------------------------------------ description
    def to_dict(self) -> dict[str, Any]:
        return {"type": "MeshBody", "mesh_file": self.mesh_file, "mass": self.mass,
                "cog": list(self.cog), "inertia": [list(row) for row in self.inertia],
                "reference_point": list(self.reference_point), "rho": self.rho, "g": self.g,
                "name": self.name, "file_format": self.file_format}

    @property
    def inertia_about_cog(self) -> np.ndarray:
        return np.asarray(self.inertia, dtype=float)

    # ------------------------------------------------------------------ the mesh
    @cached_property
    def hull(self):
        """The immersed part of the file's mesh (a Capytaine mesh, symmetries kept)."""
        import capytaine as cpt

        try:
            mesh = cpt.load_mesh(self.mesh_file, file_format=self.file_format)
        except (OSError, ValueError, TypeError, IndexError) as exc:
            raise InputError(f"cannot read mesh {self.mesh_file}: {exc}") from None
        return mesh.immersed_part()

    @cached_property
    def file_sha256(self) -> str:
        """SHA-256 of the mesh file (the BEM cache key changes when the file does)."""
        return hashlib.sha256(Path(self.mesh_file).read_bytes()).hexdigest()

    def mesh_options(self, panel_size: float | None = None, n_panels: int | None = None,
                     **options: Any) -> dict[str, Any]:
        """No options: the file's panels are the BEM panels."""
        if panel_size is not None or n_panels is not None or options:
            raise InputError(f"the mesh file {self.mesh_file} sets the panels; panel_size and "
                             "n_panels do not apply to a MeshBody")
        return {}

    def mesh_description(self, **options: Any) -> dict[str, Any]:
        self.mesh_options(**options)
        return {"kind": "mesh_file", "file": Path(self.mesh_file).name,
                "sha256": self.file_sha256, "n_faces": int(self.hull.nb_faces)}

    def mesh(self, *, symmetric: bool = True, lid: bool = True, **options: Any):
        """Capytaine ``(hull, lid or None)``; ``symmetric=False`` merges the file's symmetries."""
        self.mesh_options(**options)
        hull = self.hull if symmetric else self.hull.merged()
        lid_mesh = None
        if lid:
            lid_mesh = hull.generate_lid(z=0.0)
            lid_mesh = None if lid_mesh.nb_faces == 0 else lid_mesh.with_normal_vector_going_down()
        return hull, lid_mesh

    # ------------------------------------------------------------------ hydrostatics
    @property
    def draft(self) -> float:
        return -float(self.hull.vertices[:, 2].min())

    def displaced_volume(self) -> float:
        return float(self.hull.volume)

    def center_of_buoyancy(self) -> np.ndarray:
        return np.asarray(self.hull.center_of_buoyancy, dtype=float)

    def waterplane_moments(self) -> WaterplaneMoments:
        quad = self.hull.quadrature_points[0]
        x, y = quad[:, :, 0], quad[:, :, 1]
        wp = self.hull.waterplane_integral
        return WaterplaneMoments(area=float(wp(np.ones_like(x))), sx=float(wp(x)),
                                 sy=float(wp(y)), sxx=float(wp(x**2)), syy=float(wp(y**2)),
                                 sxy=float(wp(x * y)))

    def wetted_area(self) -> float:
        return float(self.hull.wet_surface_area)
