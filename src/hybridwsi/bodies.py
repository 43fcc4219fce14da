"""Floating bodies: geometry, mass properties, hydrostatics and Capytaine meshes.

The only body so far is :class:`FloatingSphere`, the paper's test case (a sphere floating with
its centre at the still-water level). Coordinates: ``z`` up, origin on the undisturbed free
surface above the sphere's centre (so a half-submerged sphere has its centre at the origin).

Capytaine is imported lazily (only by :meth:`FloatingSphere.mesh` and
:meth:`FloatingSphere.capytaine_body`) so that importing this module stays cheap.

Capytaine 3 pitfalls handled here (``/work/shared/design/CAPYTAINE_NOTES.md``): the lid of an
axisymmetric mesh is built from profile points, because ``generate_lid()`` returns an empty
lid on a ``RotationSymmetricMesh``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from hybridwsi.dofs import RIGID_DOFS, check_dofs
from hybridwsi.errors import InputError

def cap_volume(depth: float | np.ndarray, radius: float) -> float | np.ndarray:
    """Volume [m^3] of a spherical cap of height ``depth`` [m] cut from a sphere of ``radius``."""
    d = np.asarray(depth, dtype=float)
    vol = math.pi * d**2 * (3.0 * radius - d) / 3.0
    return float(vol) if vol.ndim == 0 else vol


@dataclass(frozen=True)
class FloatingSphere:
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
    """

    radius: float = 0.15
    mass: float | None = None
    draft: float | None = None
    center_of_mass: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: Any = None
    rho: float = 998.2
    g: float = 9.81

    def __post_init__(self) -> None:
        r = _positive("radius", self.radius)
        draft = r if self.draft is None else _positive("draft", self.draft)
        if not draft < 2.0 * r:
            raise InputError(f"draft {draft} m must be smaller than the diameter {2 * r} m")
        rho, g = _positive("rho", self.rho), _positive("g", self.g)
        mass = rho * cap_volume(draft, r) if self.mass is None else _positive("mass", self.mass)
        cog = np.asarray(self.center_of_mass, dtype=float)
        if cog.shape != (3,) or not np.all(np.isfinite(cog)):
            raise InputError(f"center_of_mass must be 3 finite numbers [m], got {self.center_of_mass}")
        inertia = _inertia_matrix(self.inertia, mass, r)
        # frozen dataclass: normalised values are written once here
        for name, value in (("radius", r), ("draft", draft), ("mass", mass), ("rho", rho), ("g", g),
                            ("center_of_mass", tuple(float(c) for c in cog))):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "inertia", tuple(map(tuple, inertia.tolist())))

    # ------------------------------------------------------------------ presets
    @classmethod
    def paper(cls) -> FloatingSphere:
        """The paper's sphere: R = 0.15 m, m = 7.06 kg, half submerged, rho = 998.2, g = 9.81."""
        return cls(radius=0.15, mass=7.06, rho=998.2, g=9.81)

    @classmethod
    def kramer2021(cls) -> FloatingSphere:
        """Kramer et al. (2021) decay-test sphere: D = 0.300 m, m = 7.056 kg, CoG 34.8 mm below
        the centre, Ixx = Iyy = 0.098252, Izz = 0.073052 kg m^2, rho = 998.2, g = 9.82."""
        return cls(radius=0.15, mass=7.056, center_of_mass=(0.0, 0.0, -0.0348),
                   inertia=(0.098252, 0.098252, 0.073052), rho=998.2, g=9.82)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> FloatingSphere:
        """Inverse of :meth:`to_dict`."""
        data = {k: v for k, v in dict(data).items() if k != "type"}
        try:
            return cls(**data)
        except TypeError as exc:
            raise InputError(f"cannot build a FloatingSphere from {data}: {exc}") from None

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able description (used for hashing and NetCDF attrs)."""
        d = asdict(self)
        d["center_of_mass"] = list(self.center_of_mass)
        d["inertia"] = [list(row) for row in self.inertia]
        return {"type": "FloatingSphere", **d}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

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
    def waterplane_radius(self) -> float:
        """Radius of the waterplane circle [m]."""
        zc = self.radius - self.draft
        return math.sqrt(self.radius**2 - zc**2)

    def displaced_volume(self) -> float:
        """Submerged volume at rest [m^3] (spherical cap of height ``draft``)."""
        return cap_volume(self.draft, self.radius)

    def center_of_buoyancy(self) -> float:
        """Vertical position of the centre of buoyancy in the global frame [m] (negative)."""
        d, r = self.draft, self.radius
        # centroid of a cap of height d, measured from the sphere centre: 3(2R - d)^2 / (4(3R - d))
        return self.center[2] - 3.0 * (2.0 * r - d) ** 2 / (4.0 * (3.0 * r - d))

    # ------------------------------------------------------------------ hydrostatics
    def hydrostatic_stiffness(self, dofs: Sequence[str] = ("Heave",)) -> np.ndarray:
        """Analytic linear hydrostatic stiffness matrix [N/m, N, N m/rad] for ``dofs``.

        Heave: ``rho g A_wp`` (``rho g pi R^2`` when half submerged). Roll/pitch about the centre
        of mass: ``rho g (I_wp + V z_B) - m g z_G`` with z from the still-water level. Surge, sway
        and yaw have no restoring force; heave-roll/pitch couplings vanish by axial symmetry.
        """
        dofs = check_dofs(dofs)
        a = self.waterplane_radius
        rg = self.rho * self.g
        diag = {
            "Heave": rg * math.pi * a**2,
            "Roll": rg * (math.pi * a**4 / 4 + self.displaced_volume() * self.center_of_buoyancy())
            - self.mass * self.g * self.cog[2],
        }
        diag["Pitch"] = diag["Roll"]
        return np.diag([diag.get(d, 0.0) for d in dofs])

    def buoyancy_force(self, z: float | np.ndarray) -> float | np.ndarray:
        """Exact (nonlinear) net vertical hydrostatic force [N] at heave displacement ``z`` [m].

        ``F(z) = rho g V_sub(draft - z) - m g`` with the spherical-cap volume, so
        ``F(0) = rho g V_sub - m g`` (zero for a body in equilibrium) and ``dF/dz(0) = -C_33``.
        Valid while the sphere is partly submerged: ``draft - 2R <= z <= draft`` (``|z| <= R``
        for a half-submerged sphere).

        Raises
        ------
        InputError
            If any ``z`` is outside that range or not finite.
        """
        zz = np.asarray(z, dtype=float)
        lo, hi = self.draft - 2.0 * self.radius, self.draft
        if not np.all(np.isfinite(zz)) or np.any(zz < lo - 1e-12) or np.any(zz > hi + 1e-12):
            bad = zz[~(np.isfinite(zz) & (zz >= lo - 1e-12) & (zz <= hi + 1e-12))].ravel()[0]
            raise InputError(
                f"heave displacement z = {bad:.6g} m is outside [{lo:.6g}, {hi:.6g}] m where the "
                "sphere is partly submerged; the spherical-cap buoyancy is not defined there"
            )
        depth = np.clip(self.draft - zz, 0.0, 2.0 * self.radius)
        force = self.rho * self.g * cap_volume(depth, self.radius) - self.mass * self.g
        return float(force) if np.ndim(force) == 0 else force

    # ------------------------------------------------------------------ mass
    def mass_matrix(self, dofs: Sequence[str] = ("Heave",)) -> np.ndarray:
        """Rigid-body mass matrix [kg, kg m^2] about the centre of mass for ``dofs``."""
        dofs = check_dofs(dofs)
        full = np.zeros((6, 6))
        full[:3, :3] = np.eye(3) * self.mass
        full[3:, 3:] = np.asarray(self.inertia)
        idx = [RIGID_DOFS.index(d) for d in dofs]
        return full[np.ix_(idx, idx)]

    # ------------------------------------------------------------------ meshes
    def resolution_for(self, n_panels: int) -> tuple[int, int]:
        """Capytaine ``mesh_sphere`` resolution ``(n_theta, n_phi)`` (full sphere) giving about
        ``n_panels`` square-ish hull panels on a half-submerged sphere: ``n_phi = 2 n_theta``,
        hull panels ``= n_theta/2 * n_phi`` (6400 -> (80, 160), 1600 -> (40, 80))."""
        if int(n_panels) != n_panels or n_panels < 16:
            raise InputError(f"n_panels must be an integer >= 16, got {n_panels}")
        k = max(2, round(math.sqrt(n_panels / 4.0)))
        return (2 * k, 4 * k)

    def mesh(self, resolution: tuple[int, int] | int | None = None, *, symmetric: bool = True,
             lid: bool = True):
        """Capytaine mesh of the wetted hull and (optionally) a lid on the waterplane.

        Parameters
        ----------
        resolution : (n_theta, n_phi) or int
            Panels along a full meridian and around a parallel (Capytaine's ``mesh_sphere``
            convention), or a number of hull panels (see :meth:`resolution_for`). Default 6400.
        symmetric : bool
            Keep Capytaine's ``RotationSymmetricMesh`` (much faster, see CAPYTAINE_NOTES.md);
            False returns plain merged meshes.
        lid : bool
            Add a lid (for irregular-frequency removal) built from profile points.

        Returns
        -------
        (hull, lid_mesh or None)
        """
        import capytaine as cpt

        nth, nph = self.panel_resolution(resolution)
        hull = cpt.mesh_sphere(radius=self.radius, center=self.center, resolution=(nth, nph),
                               axial_symmetry=True).immersed_part()
        lid_mesh = None
        if lid:
            # half the hull's meridian density is enough on the lid (notes: same result)
            n_radial = max(2, round(nth / 4 * self.waterplane_radius / self.radius))
            pts = np.array([(r, 0.0, 0.0) for r in np.linspace(0.0, self.waterplane_radius,
                                                                 n_radial + 1)])
            lid_mesh = cpt.RotationSymmetricMesh.from_profile_points(pts, n=nph)
            lid_mesh = lid_mesh.with_normal_vector_going_down()
        if not symmetric:
            hull = hull.merged()
            lid_mesh = None if lid_mesh is None else lid_mesh.merged()
        return hull, lid_mesh

    def capytaine_body(self, dofs: Sequence[str] = ("Heave",), *,
                       resolution: tuple[int, int] | int | None = None, symmetric: bool = True,
                       lid: bool = True):
        """A ``capytaine.FloatingBody`` with rigid-body ``dofs`` about the centre of mass."""
        import capytaine as cpt

        dofs = check_dofs(dofs)
        hull, lid_mesh = self.mesh(resolution, symmetric=symmetric, lid=lid)
        kwargs = {} if lid_mesh is None else {"lid_mesh": lid_mesh}
        return cpt.FloatingBody(
            mesh=hull, dofs=cpt.rigid_body_dofs(only=list(dofs), rotation_center=self.cog),
            center_of_mass=self.cog, mass=self.mass, name="sphere", **kwargs,
        )

    def panel_resolution(self, resolution: tuple[int, int] | int | None) -> tuple[int, int]:
        """Normalise a resolution: None (6400 panels), a panel count or ``(n_theta, n_phi)``."""
        if resolution is None:
            return self.resolution_for(6400)
        if np.ndim(resolution) == 0:
            return self.resolution_for(int(resolution))
        try:
            nth, nph = (int(v) for v in resolution)
        except (TypeError, ValueError):
            raise InputError(f"resolution must be (n_theta, n_phi) or a panel count, got {resolution}") from None
        if nth < 4 or nph < 4 or nth % 2:
            raise InputError(f"resolution (n_theta, n_phi) = {resolution}: need n_theta even >= 4 and n_phi >= 4")
        return nth, nph


def _positive(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise InputError(f"{name} must be positive and finite, got {value!r}")
    return v


def _inertia_matrix(inertia: Any, mass: float, radius: float) -> np.ndarray:
    if inertia is None:
        return np.eye(3) * 0.4 * mass * radius**2  # uniform solid sphere
    arr = np.asarray(inertia, dtype=float)
    if arr.shape == (3,):
        arr = np.diag(arr)
    if arr.shape != (3, 3) or not np.all(np.isfinite(arr)):
        raise InputError(f"inertia must be 3 diagonal values or a 3x3 matrix [kg m^2], got {inertia}")
    return arr
