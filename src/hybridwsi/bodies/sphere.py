"""The paper's body: a rigid sphere floating in the free surface.

Coordinates as every body (:mod:`hybridwsi.bodies.base`): ``z`` up, origin on the undisturbed
free surface above the sphere's centre (a half-submerged sphere has its centre at the origin).
The reference point (DOF origin) is the centre of mass, so the paper's BEM inputs, and with
them the cache keys of the shipped coefficients, are those of the sphere-only code.

Capytaine is imported lazily (only by :meth:`FloatingSphere.mesh`) so that importing this
module stays cheap. The lid of the axisymmetric mesh is built from profile points, because
``generate_lid()`` returns an empty lid on a ``RotationSymmetricMesh`` (docs/CAPYTAINE_NOTES.md
pitfall 1).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from hybridwsi.bodies.base import (HORIZONTAL_AND_HEAVE, Body, WaterplaneMoments,
                                   as_tuple_matrix, check_panel_count, disc_lid, inertia_matrix,
                                   positive, vector3)
from hybridwsi.cases import load_case
from hybridwsi.errors import InputError


def cap_volume(depth: float | np.ndarray, radius: float) -> float | np.ndarray:
    """Volume [m^3] of a spherical cap of height ``depth`` [m] cut from a sphere of ``radius``."""
    d = np.asarray(depth, dtype=float)
    vol = math.pi * d**2 * (3.0 * radius - d) / 3.0
    return float(vol) if vol.ndim == 0 else vol


@dataclass(frozen=True)
class FloatingSphere(Body):
    """A rigid sphere floating in the free surface.

    Parameters
    ----------
    radius : float
        Sphere radius R [m].
    mass : float, optional
        Body mass m [kg]. Default: the displaced mass ``rho * V_sub(draft)``, i.e. the body
        floats in equilibrium at ``draft``.
    draft : float, optional
        Submerged depth of the lowest point below the still-water level [m], in (0, 2R).
        Default: R (half submerged, centre in the free surface).
    center_of_mass : (3,) floats
        Centre of mass relative to the sphere's centre [m] (e.g. ``(0, 0, -0.0348)``).
    inertia : (3,) or (3, 3) floats, optional
        Rotational inertia about the centre of mass [kg m^2] (diagonal Ixx, Iyy, Izz or full).
        Default: a uniform solid sphere, ``0.4 m R^2`` on the diagonal.
    rho : float
        Water density [kg/m^3].
    g : float
        Gravitational acceleration [m/s^2].

    Notes
    -----
    The reference point is the centre of mass; default DOFs ``("Heave",)``; the mesh
    resolution is Capytaine's ``mesh_sphere`` ``(n_theta, n_phi)``, given directly, as a hull
    panel count or as a panel size (:meth:`mesh_options`).
    """

    radius: float = 0.15
    mass: float | None = None
    draft: float | None = None
    center_of_mass: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: Any = None
    rho: float = 998.2
    g: float = 9.81

    # not dataclass fields: they stay out of to_dict() and so out of the BEM cache keys
    name = "sphere"
    dofs = ("Heave",)
    default_panels = 6400

    def __post_init__(self) -> None:
        r = positive("radius", self.radius)
        draft = r if self.draft is None else positive("draft", self.draft)
        if not draft < 2.0 * r:
            raise InputError(f"draft {draft} m must be smaller than the diameter {2 * r} m")
        rho, g = positive("rho", self.rho), positive("g", self.g)
        mass = rho * cap_volume(draft, r) if self.mass is None else positive("mass", self.mass)
        cog = vector3("center_of_mass", self.center_of_mass)
        inertia = (np.eye(3) * 0.4 * mass * r**2 if self.inertia is None  # uniform solid sphere
                   else inertia_matrix("inertia", self.inertia))
        # frozen dataclass: normalised values are written once here
        for name, value in (("radius", r), ("draft", draft), ("mass", mass), ("rho", rho), ("g", g),
                            ("center_of_mass", cog)):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "inertia", as_tuple_matrix(inertia))

    # ------------------------------------------------------------------ presets
    @classmethod
    def paper(cls) -> FloatingSphere:
        """The paper's sphere (``cases/paper_sphere.toml`` [body]: R = 0.15 m, m = 7.06 kg,
        half submerged, rho = 998.2, g = 9.81)."""
        return cls.from_dict(load_case("paper_sphere")["body"])

    @classmethod
    def kramer2021(cls) -> FloatingSphere:
        """Kramer et al. (2021) decay-test sphere: D = 0.300 m, m = 7.056 kg, CoG 34.8 mm below
        the centre, Ixx = Iyy = 0.098252, Izz = 0.073052 kg m^2, rho = 998.2, g = 9.82."""
        return cls(radius=0.15, mass=7.056, center_of_mass=(0.0, 0.0, -0.0348),
                   inertia=(0.098252, 0.098252, 0.073052), rho=998.2, g=9.82)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able description (used for hashing and NetCDF attrs)."""
        d = asdict(self)
        d["center_of_mass"] = list(self.center_of_mass)
        d["inertia"] = [list(row) for row in self.inertia]
        return {"type": "FloatingSphere", **d}

    # ------------------------------------------------------------------ geometry
    @property
    def center(self) -> tuple[float, float, float]:
        """Sphere centre in the global frame [m] (z = R - draft)."""
        return (0.0, 0.0, self.radius - self.draft)

    @property
    def cog(self) -> tuple[float, float, float]:
        """Centre of mass in the global frame [m]."""
        return tuple(c + o for c, o in zip(self.center, self.center_of_mass))

    @property
    def inertia_about_cog(self) -> np.ndarray:
        """Inertia tensor about the centre of mass [kg m^2]."""
        return np.asarray(self.inertia, dtype=float)

    @property
    def reference_point(self) -> tuple[float, float, float]:
        """The centre of mass [m] (the paper's DOF origin)."""
        return self.cog

    @property
    def waterplane_radius(self) -> float:
        """Radius of the waterplane circle [m]."""
        zc = self.radius - self.draft
        return math.sqrt(self.radius**2 - zc**2)

    def waterplane_moments(self) -> WaterplaneMoments:
        """Waterplane circle of radius a: area pi a^2, second moments pi a^4 / 4."""
        a = self.waterplane_radius
        return WaterplaneMoments(area=math.pi * a**2, sxx=math.pi * a**4 / 4,
                                 syy=math.pi * a**4 / 4)

    def displaced_volume(self) -> float:
        """Submerged volume at rest [m^3] (spherical cap of height ``draft``)."""
        return cap_volume(self.draft, self.radius)

    def center_of_buoyancy(self) -> np.ndarray:
        """Centre of buoyancy in the global frame [m] (on the vertical axis, z < 0)."""
        d, r = self.draft, self.radius
        # centroid of a cap of height d, measured from the sphere centre: 3(2R - d)^2 / (4(3R - d))
        return np.array([0.0, 0.0, self.center[2] - 3.0 * (2.0 * r - d) ** 2 / (4.0 * (3.0 * r - d))])

    def wetted_area(self) -> float:
        """Area of the wetted spherical cap, 2 pi R draft [m^2]."""
        return 2.0 * math.pi * self.radius * self.draft

    # ------------------------------------------------------------------ exact hydrostatics
    @property
    def exact_restoring_dofs(self) -> tuple[str, ...]:
        return HORIZONTAL_AND_HEAVE

    def submerged_volume(self, heave: float | np.ndarray) -> float | np.ndarray:
        """Spherical-cap volume [m^3] below the still-water level after a heave ``heave`` [m].

        Valid while the sphere is partly submerged: ``draft - 2R <= heave <= draft``.

        Raises
        ------
        InputError
            If any ``heave`` is outside that range or not finite.
        """
        zz = np.asarray(heave, dtype=float)
        lo, hi = self.draft - 2.0 * self.radius, self.draft
        if not np.all(np.isfinite(zz)) or np.any(zz < lo - 1e-12) or np.any(zz > hi + 1e-12):
            bad = zz[~(np.isfinite(zz) & (zz >= lo - 1e-12) & (zz <= hi + 1e-12))].ravel()[0]
            raise InputError(
                f"heave displacement z = {bad:.6g} m is outside [{lo:.6g}, {hi:.6g}] m where the "
                "sphere is partly submerged; the spherical-cap buoyancy is not defined there"
            )
        return cap_volume(np.clip(self.draft - zz, 0.0, 2.0 * self.radius), self.radius)

    def buoyancy_force(self, z: float | np.ndarray) -> float | np.ndarray:
        """Exact (nonlinear) net vertical hydrostatic force [N] at heave displacement ``z`` [m].

        ``F(z) = rho g V_sub(draft - z) - m g`` with the spherical-cap volume, so
        ``F(0) = rho g V_sub - m g`` (zero for a body in equilibrium) and ``dF/dz(0) = -C_33``.
        Valid while the sphere is partly submerged: ``draft - 2R <= z <= draft``
        (``|z| <= R`` for a half-submerged sphere); :class:`InputError` outside.
        """
        return super().buoyancy_force(z)

    # ------------------------------------------------------------------ meshes
    def mesh_options(self, panel_size: float | None = None, n_panels: int | None = None,
                     resolution: tuple[int, int] | int | None = None) -> dict[str, Any]:
        """Canonical mesh options ``{"resolution": (n_theta, n_phi)}`` from at most one of a
        panel size [m], a hull panel count or a resolution (default 6400 hull panels)."""
        given = [v is not None for v in (panel_size, n_panels, resolution)]
        if sum(given) > 1:
            raise InputError("give one of panel_size, n_panels and resolution for the sphere mesh")
        if panel_size is not None:
            # square-ish panels: pi R / (2k) along the meridian and around the equator
            k = max(2, math.ceil(math.pi * self.radius / (2.0 * positive("panel_size", panel_size))))
            return {"resolution": (2 * k, 4 * k)}
        return {"resolution": self.panel_resolution(n_panels if resolution is None else resolution)}

    def mesh_description(self, **options: Any) -> dict[str, Any]:
        """``{"kind": "mesh_sphere", "resolution": [n_theta, n_phi]}`` (the paper's cache key)."""
        return {"kind": "mesh_sphere", "resolution": list(self.mesh_options(**options)["resolution"])}

    def resolution_for(self, n_panels: int) -> tuple[int, int]:
        """Capytaine ``mesh_sphere`` resolution ``(n_theta, n_phi)`` (full sphere) giving about
        ``n_panels`` square-ish hull panels on a half-submerged sphere: ``n_phi = 2 n_theta``,
        hull panels ``= n_theta/2 * n_phi`` (6400 -> (80, 160), 1600 -> (40, 80))."""
        k = max(2, round(math.sqrt(check_panel_count(n_panels) / 4.0)))
        return (2 * k, 4 * k)

    def mesh(self, resolution: tuple[int, int] | int | None = None, *, symmetric: bool = True,
             lid: bool = True, panel_size: float | None = None, n_panels: int | None = None):
        """Capytaine mesh of the wetted hull and (optionally) a lid on the waterplane.

        Parameters
        ----------
        resolution : (n_theta, n_phi) or int
            Panels along a full meridian and around a parallel (Capytaine's ``mesh_sphere``
            convention), or a number of hull panels (see :meth:`resolution_for`). Default 6400.
        symmetric : bool
            Keep Capytaine's ``RotationSymmetricMesh`` (much faster, see docs/CAPYTAINE_NOTES.md);
            False returns plain merged meshes.
        lid : bool
            Add a lid (for irregular-frequency removal) built from profile points.
        panel_size, n_panels : optional
            Instead of ``resolution`` (:meth:`mesh_options`).

        Returns
        -------
        (hull, lid_mesh or None)
        """
        import capytaine as cpt

        opts = self.mesh_options(panel_size=panel_size, n_panels=n_panels, resolution=resolution)
        nth, nph = opts["resolution"]
        hull = cpt.mesh_sphere(radius=self.radius, center=self.center, resolution=(nth, nph),
                               axial_symmetry=True).immersed_part()
        lid_mesh = None
        if lid:
            # half the hull's meridian density is enough on the lid (notes: same result)
            n_radial = max(2, round(nth / 4 * self.waterplane_radius / self.radius))
            lid_mesh = disc_lid(self.waterplane_radius, n_radial, nph)
        if not symmetric:
            hull = hull.merged()
            lid_mesh = None if lid_mesh is None else lid_mesh.merged()
        return hull, lid_mesh

    def panel_resolution(self, resolution: tuple[int, int] | int | None) -> tuple[int, int]:
        """Normalise a resolution: None (6400 panels), a panel count or ``(n_theta, n_phi)``."""
        if resolution is None:
            return self.resolution_for(self.default_panels)
        if np.ndim(resolution) == 0:
            return self.resolution_for(resolution)
        try:
            nth, nph = (int(v) for v in resolution)
        except (TypeError, ValueError):
            raise InputError(f"resolution must be (n_theta, n_phi) or a panel count, got {resolution}") from None
        if nth < 4 or nph < 4 or nth % 2:
            raise InputError(f"resolution (n_theta, n_phi) = {resolution}: need n_theta even >= 4 and n_phi >= 4")
        return nth, nph

