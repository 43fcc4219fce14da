"""The body interface used by the BEM, the Cummins solver and the diagnostic.

Frame and conventions (every body):

- global frame, ``z`` up, origin on the undisturbed free surface ``z = 0``; the body is
  described at rest;
- DOFs are Capytaine's rigid-body motions (:mod:`hybridwsi.dofs`): translations in m, rotations
  in rad about axes through the body's ``reference_point`` (the DOF origin O), forces in N and
  moments in N m about O;
- matrices are in force-equation orientation ``M[i, j]`` (``i`` the DOF receiving the force,
  ``j`` the DOF that moves), so the force is ``F_i = -sum_j M[i, j] q_j``; this is Capytaine's
  ``(influenced_dof, radiating_dof)``.

Rigid-body mass matrix about O (``r = G - O``, ``[r×]`` the cross-product matrix)::

    M = [[ m 1,      -m [r×] ],
         [ m [r×],    I_G + m (|r|² 1 - r rᵀ) ]]

so e.g. ``M[Surge, Pitch] = M[Pitch, Surge] = m (z_G - z_O)`` and
``M[Sway, Roll] = -m (z_G - z_O)``.

Hydrostatic + gravity stiffness about O (the linearisation of the net hydrostatic pressure and
weight moments for rotations about O; Capytaine's and WAMIT's convention), with the waterplane
integrals taken over the waterplane area ``A_wp``::

    C33 = rho g A_wp
    C34 = C43 =  rho g ∫ (y - y_O) dA          C35 = C53 = -rho g ∫ (x - x_O) dA
    C44 = rho g [∫ (y - y_O)² dA + V (z_B - z_O)] - m g (z_G - z_O)
    C55 = rho g [∫ (x - x_O)² dA + V (z_B - z_O)] - m g (z_G - z_O)
    C45 = C54 = -rho g ∫ (x - x_O)(y - y_O) dA
    C46 = -rho g V (x_B - x_O) + m g (x_G - x_O)
    C56 = -rho g V (y_B - y_O) + m g (y_G - y_O)

For a body in vertical equilibrium (``m = rho V``) the ``z_O`` terms cancel and
``C55 = rho g (I_wp + V z_B) - m g z_G`` with ``z`` measured from the still-water level and
``I_wp = ∫ (x - x_O)² dA``. All other entries are zero (surge, sway and yaw have no restoring
force).
"""

from __future__ import annotations

import json
import math
import re
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridwsi.dofs import RIGID_DOFS, check_dofs, index
from hybridwsi.errors import InputError

#: DOFs whose exact restoring force needs only the submerged volume at a heave displacement:
#: horizontal motions (surge, sway, yaw) change neither the volume nor any vertical force
HORIZONTAL_AND_HEAVE = ("Surge", "Sway", "Heave", "Yaw")
#: body classes by name, filled by Body.__init_subclass__ (for body_from_dict)
_BODY_TYPES: dict[str, type] = {}


@dataclass(frozen=True)
class WaterplaneMoments:
    """Integrals over the waterplane area at rest, global frame.

    Attributes
    ----------
    area : float
        ``∫ dA`` [m^2].
    sx, sy : float
        ``∫ x dA``, ``∫ y dA`` [m^3].
    sxx, syy, sxy : float
        ``∫ x² dA``, ``∫ y² dA``, ``∫ x y dA`` [m^4].
    """

    area: float
    sx: float = 0.0
    sy: float = 0.0
    sxx: float = 0.0
    syy: float = 0.0
    sxy: float = 0.0

    def about(self, x0: float, y0: float) -> WaterplaneMoments:
        """The same integrals with ``x - x0`` and ``y - y0`` in place of ``x`` and ``y``."""
        a = self.area
        return WaterplaneMoments(
            area=a, sx=self.sx - a * x0, sy=self.sy - a * y0,
            sxx=self.sxx - 2 * x0 * self.sx + a * x0**2,
            syy=self.syy - 2 * y0 * self.sy + a * y0**2,
            sxy=self.sxy - x0 * self.sy - y0 * self.sx + a * x0 * y0,
        )


class Body(ABC):
    """A rigid floating body (see the module docstring for frame and sign conventions).

    Subclasses provide the attributes ``name`` (str), ``rho`` [kg/m^3], ``g`` [m/s^2],
    ``mass`` [kg], ``cog`` (centre of mass G, global frame [m]) and ``reference_point`` (the
    DOF origin O [m]); the inertia :attr:`inertia_about_cog`; the hydrostatic geometry
    (:meth:`displaced_volume`, :meth:`center_of_buoyancy`, :meth:`waterplane_moments`,
    :attr:`draft`, :meth:`wetted_area`); the Capytaine mesh (:meth:`mesh`,
    :meth:`mesh_description`) and :meth:`to_dict`. Everything else (mass matrix, stiffness, Capytaine body, mesh options,
    restoring force) is derived here once for every body.
    """

    name: str
    rho: float
    g: float
    mass: float
    #: centre of mass G in the global frame [m]
    cog: tuple[float, float, float]
    #: DOF origin O (3 floats) [m]: rotations and moments are about this point
    reference_point: Sequence[float]
    #: default degrees of freedom of this body
    dofs: tuple[str, ...] = RIGID_DOFS
    #: default number of hull panels when neither a panel size nor a count is given
    default_panels: int = 1000

    # ------------------------------------------------------------------ to implement
    @property
    @abstractmethod
    def inertia_about_cog(self) -> np.ndarray:
        """Rotational inertia tensor about G, (3, 3) [kg m^2]."""

    @abstractmethod
    def displaced_volume(self) -> float:
        """Submerged volume V at rest [m^3]."""

    @abstractmethod
    def center_of_buoyancy(self) -> np.ndarray:
        """Centre of buoyancy B at rest, (3,) global frame [m]."""

    @abstractmethod
    def waterplane_moments(self) -> WaterplaneMoments:
        """Waterplane area and its moments at rest, global frame."""

    @property
    @abstractmethod
    def draft(self) -> float:
        """Depth of the lowest wetted point below the still-water level [m] (> 0)."""

    @abstractmethod
    def wetted_area(self) -> float:
        """Wetted hull area at rest [m^2] (sets the panel size for a panel count)."""

    @abstractmethod
    def mesh(self, *, symmetric: bool = True, lid: bool = True, **options: Any):
        """Capytaine meshes ``(hull, lid or None)`` of the wetted hull (clipped at z = 0) and of
        the waterplane lid; ``options`` as returned by :meth:`mesh_options`."""

    @abstractmethod
    def mesh_description(self, **options: Any) -> dict[str, Any]:
        """JSON-able description of the mesh made with ``options`` (for cache keys); has a
        ``"kind"`` entry."""

    @abstractmethod
    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able description with a ``"type"`` entry (:func:`body_from_dict`)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        # body_from_dict dispatches on the class name or its snake_case spelling (the case
        # files' style: "rigid_assembly"; "axisymmetric" for AxisymmetricBody)
        for alias in type_aliases(cls.__name__):
            _BODY_TYPES[alias] = cls

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Body:
        """Inverse of :meth:`to_dict` (the ``"type"`` entry is ignored)."""
        kwargs = {k: v for k, v in dict(data).items() if k != "type"}
        try:
            return cls(**kwargs)
        except TypeError as exc:
            raise InputError(f"cannot build a {cls.__name__} from {kwargs}: {exc}") from None

    # ------------------------------------------------------------------ serialisation
    def to_json(self) -> str:
        """:meth:`to_dict` as JSON text (sorted keys)."""
        return json.dumps(self.to_dict(), sort_keys=True)

    # ------------------------------------------------------------------ mass
    def mass_matrix(self, dofs: Sequence[str] | None = None) -> np.ndarray:
        """Rigid-body mass matrix about the reference point [kg, kg m, kg m^2] for ``dofs``.

        Includes the coupling terms ``± m [r×]`` when the centre of mass is not the reference
        point (``M[Surge, Pitch] = m (z_G - z_O)``) and the parallel-axis inertia
        (module docstring).
        """
        idx = index(self.dofs if dofs is None else dofs)
        r = np.asarray(self.cog, dtype=float) - np.asarray(self.reference_point, dtype=float)
        m = self.mass
        full = np.zeros((6, 6))
        full[:3, :3] = np.eye(3) * m
        full[:3, 3:] = -m * cross_matrix(r)
        full[3:, :3] = m * cross_matrix(r)
        full[3:, 3:] = self.inertia_about_cog + parallel_axis(m, r)
        return full[np.ix_(idx, idx)]

    # ------------------------------------------------------------------ hydrostatics
    def hydrostatic_stiffness(self, dofs: Sequence[str] | None = None) -> np.ndarray:
        """Linear hydrostatic + gravity stiffness about the reference point for ``dofs``.

        Force-equation orientation ``C[influenced, radiating]`` [N/m, N/rad, N m/m, N m/rad];
        formulas and convention in the module docstring (z_B, z_G relative to the reference
        point; the weight term ``- m g (z_G - z_O)`` is included for roll and pitch).
        """
        idx = index(self.dofs if dofs is None else dofs)
        xo, yo, zo = (float(v) for v in self.reference_point)
        wp = self.waterplane_moments().about(xo, yo)
        vol = self.displaced_volume()
        xb, yb, zb = (float(v) for v in self.center_of_buoyancy())
        xg, yg, zg = (float(v) for v in self.cog)
        rg, mg = self.rho * self.g, self.mass * self.g
        c = np.zeros((6, 6))
        c[2, 2] = rg * wp.area
        c[2, 3] = c[3, 2] = rg * wp.sy
        c[2, 4] = c[4, 2] = -rg * wp.sx
        volume_term = rg * vol * (zb - zo) - mg * (zg - zo)
        c[3, 3] = rg * wp.syy + volume_term
        c[4, 4] = rg * wp.sxx + volume_term
        c[3, 4] = c[4, 3] = -rg * wp.sxy
        c[3, 5] = -rg * vol * (xb - xo) + mg * (xg - xo)
        c[4, 5] = -rg * vol * (yb - yo) + mg * (yg - yo)
        return c[np.ix_(idx, idx)]

    # ------------------------------------------------------------------ exact restoring
    @property
    def exact_restoring_dofs(self) -> tuple[str, ...]:
        """DOFs for which :meth:`restoring_force` is exact (nonlinear); empty by default."""
        return ()

    def submerged_volume(self, heave: float | np.ndarray) -> float | np.ndarray:
        """Submerged volume [m^3] after a heave displacement ``heave`` [m] (up positive).

        Raises
        ------
        InputError
            When the geometry gives no exact value (the default).
        """
        raise InputError(f"{type(self).__name__} has no exact submerged volume at a heave "
                         "displacement; use the linear hydrostatic stiffness")

    def restoring_force(self, q: Sequence[float] | np.ndarray,
                        dofs: Sequence[str] | None = None) -> np.ndarray:
        """Exact net hydrostatic + gravity generalised force at displacement ``q``.

        Parameters
        ----------
        q : array_like, shape (..., n_dof)
            Displacements from rest per DOF [m or rad].
        dofs : sequence of str, optional
            DOF names of the last axis of ``q`` (default :attr:`dofs`); each must be in
            :attr:`exact_restoring_dofs`.

        Returns
        -------
        numpy.ndarray, same shape as ``q``
            Force [N] or moment [N m] per DOF: heave ``rho g V(z) - m g`` (zero at equilibrium);
            surge, sway and yaw zero (horizontal motions change no hydrostatic force).

        Raises
        ------
        InputError
            A DOF without an exact restoring force, a shape mismatch or a displacement outside
            the range where the body is partly submerged.
        """
        dofs = check_dofs(self.dofs if dofs is None else dofs)
        inexact = [d for d in dofs if d not in self.exact_restoring_dofs]
        if inexact:
            raise InputError(f"{type(self).__name__} has no exact restoring force for {inexact} "
                             f"(exact: {list(self.exact_restoring_dofs) or 'none'}); use the "
                             "linear hydrostatic stiffness")
        qq = np.asarray(q, dtype=float)
        if qq.ndim == 0 or qq.shape[-1] != len(dofs):
            raise InputError(f"q must have a last axis of length {len(dofs)} (one value per DOF "
                             f"{list(dofs)}), got shape {qq.shape}")
        out = np.zeros_like(qq)
        if "Heave" in dofs:
            k = dofs.index("Heave")
            out[..., k] = self.buoyancy_force(qq[..., k])
        return out

    def buoyancy_force(self, z: float | np.ndarray) -> float | np.ndarray:
        """Exact net vertical force ``rho g V(z) - m g`` [N] at heave displacement ``z`` [m]
        (``V`` from :meth:`submerged_volume`)."""
        force = self.rho * self.g * self.submerged_volume(z) - self.mass * self.g
        return float(force) if np.ndim(force) == 0 else force

    # ------------------------------------------------------------------ meshes
    def mesh_options(self, panel_size: float | None = None, n_panels: int | None = None,
                     **options: Any) -> dict[str, Any]:
        """Canonical mesh options (keyword arguments of :meth:`mesh`) for a request.

        Parameters
        ----------
        panel_size : float, optional
            Target panel edge length [m].
        n_panels : int, optional
            Approximate number of hull panels instead (``panel_size = sqrt(S_wet / n)``).
            Neither: :attr:`default_panels` panels.

        Returns
        -------
        dict
            ``{"panel_size": h}`` [m].
        """
        if options:
            raise InputError(f"{type(self).__name__} meshes take panel_size [m] or n_panels, "
                             f"not {sorted(options)}")
        if panel_size is not None and n_panels is not None:
            raise InputError("give panel_size or n_panels, not both")
        if panel_size is None:
            n = self.default_panels if n_panels is None else check_panel_count(n_panels)
            panel_size = math.sqrt(self.wetted_area() / n)
        return {"panel_size": positive("panel_size", panel_size)}

    def panel_count(self, **options: Any) -> int:
        """Number of hull panels of the mesh made with ``options``."""
        hull, _ = self.mesh(lid=False, **self.mesh_options(**options))
        return int(hull.nb_faces)

    def capytaine_body(self, dofs: Sequence[str] | None = None, *, symmetric: bool = True,
                       lid: bool = True, **options: Any):
        """A ``capytaine.FloatingBody`` of the wetted hull with rigid-body ``dofs`` about the
        reference point, this body's mass and centre of mass, and (optionally) a lid.

        ``options``: mesh resolution (``panel_size`` [m], ``n_panels``; see
        :meth:`mesh_options`).
        """
        import capytaine as cpt

        dofs = check_dofs(self.dofs if dofs is None else dofs)
        hull, lid_mesh = self.mesh(symmetric=symmetric, lid=lid, **self.mesh_options(**options))
        kwargs = {} if lid_mesh is None else {"lid_mesh": lid_mesh}
        return cpt.FloatingBody(
            mesh=hull,
            dofs=cpt.rigid_body_dofs(only=list(dofs),
                                     rotation_center=tuple(float(v) for v in self.reference_point)),
            center_of_mass=self.cog, mass=self.mass, name=self.name, **kwargs,
        )


# ---------------------------------------------------------------------------- helpers
def cross_matrix(r: Sequence[float] | np.ndarray) -> np.ndarray:
    """``[r×]``, the matrix with ``[r×] v = r × v``."""
    x, y, z = (float(v) for v in r)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def parallel_axis(mass: float, r: Sequence[float] | np.ndarray) -> np.ndarray:
    """Inertia [kg m^2] of a point ``mass`` at offset ``r`` [m]: ``m (|r|² 1 - r rᵀ)``."""
    rr = np.asarray(r, dtype=float)
    return mass * (float(rr @ rr) * np.eye(3) - np.outer(rr, rr))


def positive(name: str, value: Any) -> float:
    """``value`` as a positive finite float, else :class:`InputError`."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise InputError(f"{name} must be positive and finite, got {value!r}")
    return v


def check_panel_count(n_panels: Any) -> int:
    """A hull panel count (integer >= 16)."""
    try:
        ok = int(n_panels) == n_panels and n_panels >= 16
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise InputError(f"n_panels must be an integer >= 16, got {n_panels!r}")
    return int(n_panels)


def vector3(name: str, value: Any) -> tuple[float, float, float]:
    """Three finite floats [m], else :class:`InputError`."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.empty(0)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be 3 finite numbers [m], got {value!r}")
    return tuple(float(v) for v in arr)


def inertia_matrix(name: str, value: Any) -> np.ndarray:
    """Inertia about the centre of mass [kg m^2]: None (zero), 3 diagonal values or a
    symmetric 3x3 matrix."""
    if value is None:
        return np.zeros((3, 3))
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.empty(0)
    if arr.shape == (3,):
        arr = np.diag(arr)
    if arr.shape != (3, 3) or not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be 3 diagonal values or a 3x3 matrix [kg m^2], got {value!r}")
    if not np.allclose(arr, arr.T, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(arr).max())):
        raise InputError(f"{name} must be a symmetric 3x3 matrix [kg m^2]")
    return arr


def as_tuple_matrix(arr: np.ndarray) -> tuple[tuple[float, ...], ...]:
    """A (3, 3) array as nested tuples (hashable, for frozen dataclasses)."""
    return tuple(tuple(float(v) for v in row) for row in np.asarray(arr))


def disc_lid(radius: float, n_radial: int, n_around: int):
    """Capytaine lid on the waterplane disc ``r <= radius`` at z = 0, normals down, as a
    ``RotationSymmetricMesh`` of ``n_radial`` rings and ``n_around`` sectors (made from profile
    points: ``generate_lid()`` is empty on a rotation-symmetric mesh)."""
    import capytaine as cpt

    pts = np.array([(r, 0.0, 0.0) for r in np.linspace(0.0, radius, n_radial + 1)])
    lid = cpt.RotationSymmetricMesh.from_profile_points(pts, n=n_around)
    return lid.with_normal_vector_going_down()


def type_aliases(class_name: str) -> tuple[str, ...]:
    """Names :func:`body_from_dict` accepts for a body class: the class name, its snake_case
    spelling and that without a trailing ``_body`` (``"AxisymmetricBody"``,
    ``"axisymmetric_body"``, ``"axisymmetric"``)."""
    snake = re.sub(r"(?<!^)(?=[A-Z])", "_", class_name).lower()
    return tuple(dict.fromkeys((class_name, snake, snake.removesuffix("_body"))))


def body_from_dict(data: dict[str, Any]) -> Body:
    """Rebuild any body from its :meth:`Body.to_dict` (dispatch on ``"type"``: a class name or
    its snake_case alias, :func:`type_aliases`)."""
    if not isinstance(data, dict) or "type" not in data:
        raise InputError(f"a body description needs a 'type' entry, got {data!r}")
    cls = _BODY_TYPES.get(str(data["type"]))
    if cls is None:
        names = sorted({c.__name__ for c in _BODY_TYPES.values()})
        raise InputError(f"unknown body type {data['type']!r}; choose from {names} (or their "
                         "snake_case names)")
    return cls.from_dict(data)
