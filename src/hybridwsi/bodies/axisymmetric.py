"""A body of revolution about the vertical axis from an (r, z) profile: cylinders, spars with
tapers and heave plates, buoys.

The profile is a polyline of ``(r, z)`` points [m] in the global frame at rest (z up from the
still-water level), from the keel centre ``(0, z_keel)`` up to a point above the waterline;
``z`` never decreases along it (horizontal steps are allowed: bottoms, heave plates). The
solid is the polyline turned about the z axis (closed by a disc at its top end). Between two
points it is a frustum, so volume, centre of buoyancy, waterplane and the submerged volume at
any heave displacement are exact sums of frusta.

The Capytaine mesh is ``RotationSymmetricMesh.from_profile_points`` of the immersed profile
(clipped at z = 0 by construction), which keeps Capytaine's axial symmetry (about 100x faster
than the full mesh), and a lid built from profile points (``generate_lid()`` is empty on a
rotation-symmetric mesh).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridwsi.bodies.base import (HORIZONTAL_AND_HEAVE, Body, WaterplaneMoments,
                                   as_tuple_matrix, disc_lid, inertia_matrix, positive, vector3)
from hybridwsi.errors import InputError


@dataclass(frozen=True)
class AxisymmetricBody(Body):
    """A floating body of revolution about the z axis.

    Parameters
    ----------
    profile : sequence of (r, z)
        Profile points [m] from the keel centre (r = 0) up to above the waterline, z
        non-decreasing (module docstring).
    mass : float, optional
        Mass [kg]; default the displaced mass ``rho V`` (floating in equilibrium).
    cog : (3,) floats
        Centre of mass G in the global frame [m]; default ``(0, 0, 0)``.
    inertia : (3,) or (3, 3) floats, optional
        Inertia about G [kg m^2]; default zero (give it for rotational DOFs).
    reference_point : (3,) floats, optional
        DOF origin O [m]; default the centre of mass.
    rho, g : float
        Water density [kg/m^3] (default sea water, 1025) and gravity [m/s^2].
    name : str
        Name of the Capytaine body.
    """

    profile: Any
    mass: float | None = None
    cog: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: Any = None
    reference_point: Any = None
    rho: float = 1025.0
    g: float = 9.81
    name: str = "axisymmetric"

    def __post_init__(self) -> None:
        rz = _check_profile(self.profile)
        rho, g = positive("rho", self.rho), positive("g", self.g)
        cog = vector3("cog", self.cog)
        mass = (rho * _volume(_clip(rz, 0.0))[0] if self.mass is None
                else positive("mass", self.mass))
        ref = cog if self.reference_point is None else vector3("reference_point", self.reference_point)
        for name, value in (("profile", tuple(map(tuple, rz.tolist()))), ("rho", rho), ("g", g),
                            ("cog", cog), ("mass", mass), ("reference_point", ref),
                            ("inertia", as_tuple_matrix(inertia_matrix("inertia", self.inertia))),
                            ("name", str(self.name))):
            object.__setattr__(self, name, value)

    # ------------------------------------------------------------------ description
    def to_dict(self) -> dict[str, Any]:
        return {"type": "AxisymmetricBody", "profile": [list(p) for p in self.profile],
                "mass": self.mass, "cog": list(self.cog),
                "inertia": [list(row) for row in self.inertia],
                "reference_point": list(self.reference_point), "rho": self.rho, "g": self.g,
                "name": self.name}

    @property
    def inertia_about_cog(self) -> np.ndarray:
        return np.asarray(self.inertia, dtype=float)

    # ------------------------------------------------------------------ geometry
    @property
    def immersed_profile(self) -> np.ndarray:
        """The profile clipped at z = 0, shape (n, 2) [m]."""
        return _clip(np.asarray(self.profile), 0.0)

    @property
    def draft(self) -> float:
        return -float(self.profile[0][1])

    @property
    def waterline_radius(self) -> float:
        """Radius of the waterplane circle [m]."""
        return float(self.immersed_profile[-1, 0])

    def displaced_volume(self) -> float:
        return _volume(self.immersed_profile)[0]

    def center_of_buoyancy(self) -> np.ndarray:
        vol, moment = _volume(self.immersed_profile)
        return np.array([0.0, 0.0, moment / vol])

    def waterplane_moments(self) -> WaterplaneMoments:
        a = self.waterline_radius
        return WaterplaneMoments(area=math.pi * a**2, sxx=math.pi * a**4 / 4,
                                 syy=math.pi * a**4 / 4)

    def wetted_area(self) -> float:
        rz = self.immersed_profile
        dr, dz = np.diff(rz[:, 0]), np.diff(rz[:, 1])
        return float(np.sum(math.pi * (rz[:-1, 0] + rz[1:, 0]) * np.hypot(dr, dz)))

    # ------------------------------------------------------------------ exact hydrostatics
    @property
    def exact_restoring_dofs(self) -> tuple[str, ...]:
        return HORIZONTAL_AND_HEAVE

    def submerged_volume(self, heave: float | np.ndarray) -> float | np.ndarray:
        """Volume [m^3] below the still-water level after a heave ``heave`` [m] (up positive):
        the frusta of the profile below ``z = -heave``.

        Raises
        ------
        InputError
            Outside ``[-freeboard, draft]`` (the waterline must cut the profile) or not finite.
        """
        zz = np.asarray(heave, dtype=float)
        rz = np.asarray(self.profile)
        lo, hi = -rz[-1, 1], -rz[0, 1]
        ok = np.isfinite(zz) & (zz >= lo - 1e-12) & (zz <= hi + 1e-12)
        if not np.all(ok):
            raise InputError(f"heave displacement {zz[~ok].ravel()[0]:.6g} m is outside "
                             f"[{lo:.6g}, {hi:.6g}] m where the waterline cuts the profile")
        vol = np.array([_volume(_clip(rz, -z))[0] for z in np.clip(zz, lo, hi).ravel()])
        return float(vol[0]) if zz.ndim == 0 else vol.reshape(zz.shape)

    # ------------------------------------------------------------------ meshes
    def _discretisation(self, panel_size: float) -> tuple[np.ndarray, int]:
        """Immersed profile points at spacing <= ``panel_size`` and the number of sectors
        (a multiple of 4 with arcs <= ``panel_size`` at the largest radius)."""
        rz = self.immersed_profile
        pts = [rz[:1]]
        for p, q in zip(rz[:-1], rz[1:]):
            n = max(1, math.ceil(math.hypot(*(q - p)) / panel_size - 1e-9))
            pts.append(p + np.outer(np.arange(1, n + 1) / n, q - p))
        n_around = max(8, 4 * math.ceil(math.pi * rz[:, 0].max() / (2 * panel_size) - 1e-9))
        return np.concatenate(pts), n_around

    def mesh_description(self, **options: Any) -> dict[str, Any]:
        h = self.mesh_options(**options)["panel_size"]
        pts, n_around = self._discretisation(h)
        return {"kind": "axisymmetric_profile", "panel_size": h, "n_around": n_around,
                "n_along": len(pts) - 1}

    def mesh(self, *, symmetric: bool = True, lid: bool = True, **options: Any):
        """Capytaine ``(hull, lid or None)``; ``options``: ``panel_size`` [m] or ``n_panels``."""
        import capytaine as cpt

        h = self.mesh_options(**options)["panel_size"]
        pts, n_around = self._discretisation(h)
        xyz = np.column_stack([pts[:, 0], np.zeros(len(pts)), pts[:, 1]])
        hull = cpt.RotationSymmetricMesh.from_profile_points(xyz, n=n_around, name=self.name)
        lid_mesh = None
        if lid:
            a = self.waterline_radius
            lid_mesh = disc_lid(a, max(1, math.ceil(a / h - 1e-9)), n_around)
        if not symmetric:
            hull = hull.merged()
            lid_mesh = None if lid_mesh is None else lid_mesh.merged()
        return hull, lid_mesh


# ---------------------------------------------------------------------------- profile maths
def _check_profile(profile: Any) -> np.ndarray:
    try:
        rz = np.asarray(profile, dtype=float)
    except (TypeError, ValueError):
        raise InputError("profile must be a list of (r, z) points [m]") from None
    if rz.ndim != 2 or rz.shape[1] != 2 or rz.shape[0] < 2 or not np.all(np.isfinite(rz)):
        raise InputError(f"profile must be at least two finite (r, z) points [m], got {profile!r}")
    if np.any(rz[:, 0] < 0) or rz[0, 0] != 0:
        raise InputError("profile radii must be >= 0 and start at the keel centre (r = 0)")
    if np.any(np.diff(rz[:, 1]) < 0):
        raise InputError("profile z must not decrease from the keel up")
    if not rz[0, 1] < 0 < rz[-1, 1]:
        raise InputError(f"profile must start below the waterline and end above it (z from "
                         f"{rz[0, 1]} to {rz[-1, 1]} m)")
    at_wl = rz[np.isclose(rz[:, 1], 0.0, rtol=0, atol=1e-12), 0]
    if at_wl.size > 1 and np.ptp(at_wl) > 0:
        raise InputError("profile has a horizontal step at the waterline z = 0 (no unique "
                         "waterplane)")
    if not _clip(rz, 0.0)[-1, 0] > 0:
        raise InputError("profile radius at the waterline must be > 0 (the body needs a waterplane)")
    return rz


def _clip(rz: np.ndarray, z_cut: float) -> np.ndarray:
    """The profile below ``z_cut``, ending with an interpolated point at ``z_cut``."""
    below = rz[rz[:, 1] < z_cut]
    if below.shape[0] == 0:
        return rz[:1]
    k = below.shape[0]
    if k == rz.shape[0]:
        return rz
    p, q = rz[k - 1], rz[k]
    r = p[0] + (q[0] - p[0]) * (z_cut - p[1]) / (q[1] - p[1])
    return np.vstack([below, [r, z_cut]])


def _volume(rz: np.ndarray) -> tuple[float, float]:
    """Volume [m^3] and first moment ``∫ z dV`` [m^4] of the solid of revolution of ``rz``.

    Each segment is a frustum r(t) = a + d t, z(t) = z1 + h t, t in [0, 1]:
    ``V = pi h (a² + a d + d²/3)`` and
    ``∫ z dV = pi h [z1 (a² + a d + d²/3) + h (a²/2 + 2 a d/3 + d²/4)]``.
    """
    a, d = rz[:-1, 0], np.diff(rz[:, 0])
    z1, h = rz[:-1, 1], np.diff(rz[:, 1])
    s0 = a**2 + a * d + d**2 / 3
    s1 = a**2 / 2 + 2 * a * d / 3 + d**2 / 4
    return float(np.sum(math.pi * h * s0)), float(np.sum(math.pi * h * (z1 * s0 + h * s1)))
