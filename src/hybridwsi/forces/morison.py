"""Morison's equation: strip drag on a vertical body of revolution (the spar), on a frame of
cylindrical members in 6 DOFs (the semi-submersible, :class:`MemberMorison`), and the additional
linear damping of a case.

:class:`MorisonDrag` is the drag term of Morison's equation on a vertical axisymmetric body
(OC3-Hywind: the spar, Cd = 0.6). Only the drag term: the inertia term is supplied by the
potential-flow (BEM) added mass and excitation (Morison Ca = 0 there). The body is cut into
``N`` horizontal strips from the keel up to the still-water level (SWL); strip ``k`` has its
centre at ``(x_a, y_a, z_k)`` on the body axis, length ``dz_k`` and the mean diameter ``D_k`` of
the profile over the strip (the exact integral of the piecewise-linear (r, z) profile, so
``Σ D_k dz_k`` is the projected area whatever ``N``). The force on a strip is

    dF_k = ½ ρ Cd D_k dz_k |u_k| u_k,      u_k = u_wave(z_k, t) − v_k   (horizontal, 2-D),

the relative velocity transverse to the (vertical) axis. The strip velocity comes from all six
DOFs by small-angle rigid kinematics about the reference point O, ``v_k = v_O + ω × r_k`` with
``r_k = (x_a, y_a, z_k) − O`` and ``ω = (roll rate, pitch rate, yaw rate)``:

    v_x = Surge' + Pitch' r_z − Yaw' r_y,      v_y = Sway' + Yaw' r_x − Roll' r_z.

Written ``v_k = J_k q'`` (``J_k`` the (2, 6) strip Jacobian), the generalised force on the DOFs
is ``Q = Σ_k J_kᵀ dF_k``: the horizontal forces and their moments about O (e.g. the pitch
moment ``Σ r_z dF_x``, the roll moment ``−Σ r_z dF_y``). Heave produces no transverse
velocity, so no drag (axial drag on the keel is not modelled; the definition's additional
linear damping B33 stands in for it).

Assumptions (small motions, as the linear potential-flow model around it): strips stay at their
rest positions (the axis is not tilted; the wave velocity is evaluated at the undisplaced strip
centres, so a mean offset does not shift the wave phase); no drag above the SWL and no
wave stretching; linear Airy kinematics (optional).

The wave particle velocity (optional: pass ``wave``, off by default) is the linear Airy
horizontal velocity of every component of a :class:`hybridwsi.waves.Regular` /
:class:`~hybridwsi.waves.JONSWAP` wave, in its direction β, at finite depth h
(:class:`hybridwsi.waves.AiryKinematics` on the strip centres):

    u(x, z, t) = Σ_j a_j ω_j cosh(k_j (z + h)) / sinh(k_j h) cos(ω_j t + φ_j − k_j (x cos β + y sin β))

(the elevation at the origin is ``η = Σ a_j cos(ω_j t + φ_j)``, the convention of
:mod:`hybridwsi.waves`; ``k_j`` from the finite-depth dispersion relation). An optional
half-cosine ramp multiplies it, as the excitation's ``ramp``.

:func:`additional_damping` builds the case's additional linear damping (OC3 Table 4-2: B11 =
B22 = 1e5 N/(m/s), B33 = 1.3e5 N/(m/s), B66 = 1.3e7 N m/(rad/s)) as a
:class:`~hybridwsi.forces.linear.LinearDamping` on chosen DOFs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.bodies.members import MemberElements, point_jacobians
from hybridwsi.dofs import RIGID_DOFS, check_dofs, index
from hybridwsi.errors import InputError
from hybridwsi.forces.base import KnownComponent, kinematic
from hybridwsi.forces.linear import LinearDamping
from hybridwsi.hydro.strip import case_elements
from hybridwsi.waves import AiryKinematics, AiryPoints, Wave

#: default strip length [m] (OC3: 120 strips along the 120 m draft; pure surge is exact for
#: any length, the pitch-rate moment within 3.5e-5 of 2400 strips; docs/OC3_HYWIND.md)
DEFAULT_STRIP_LENGTH = 1.0
#: energy-equivalent linearisation of u|u| for a harmonic u of amplitude U: (8 / 3π) U u
_HARMONIC_FACTOR = 8.0 / (3.0 * math.pi)


@dataclass(frozen=True)
class Strips:
    """Horizontal strips of a vertical body of revolution, keel to still-water level.

    Attributes
    ----------
    z : ndarray, shape (n,)
        Strip centres [m] (global z, up from the SWL).
    length : ndarray, shape (n,)
        Strip lengths dz [m].
    diameter : ndarray, shape (n,)
        Mean diameter of the profile over each strip [m].
    """

    z: np.ndarray
    length: np.ndarray
    diameter: np.ndarray

    @property
    def projected_area(self) -> float:
        """``Σ D dz`` [m²], the body's projected (silhouette) area below the SWL."""
        return float(self.diameter @ self.length)


def profile_strips(profile: Any, strip_length: float | None = DEFAULT_STRIP_LENGTH,
                   n_strips: int | None = None) -> Strips:
    """Equal strips from the keel to the SWL of an axisymmetric (r, z) profile.

    Parameters
    ----------
    profile : sequence of (r, z)
        The profile [m] of :class:`hybridwsi.bodies.AxisymmetricBody` (keel centre first, z
        non-decreasing, crossing z = 0).
    strip_length : float, optional
        Target strip length [m]; the draft is divided into ``ceil(draft / strip_length)``
        equal strips. Ignored when ``n_strips`` is given.
    n_strips : int, optional
        Number of strips.

    Returns
    -------
    Strips
        Each strip's diameter is the exact mean of ``2 r(z)`` over it (horizontal steps of the
        profile, such as the keel disc, have no height and no transverse area).
    """
    try:
        rz = np.asarray(profile, dtype=float)
    except (TypeError, ValueError):
        raise InputError("Morison drag: profile must be a list of (r, z) points [m]") from None
    if (rz.ndim != 2 or rz.shape[1] != 2 or rz.shape[0] < 2 or not np.all(np.isfinite(rz))
            or np.any(np.diff(rz[:, 1]) < 0) or np.any(rz[:, 0] < 0)):
        raise InputError("Morison drag: profile must be >= 2 finite (r >= 0, z) points with z "
                         "non-decreasing from the keel up")
    keel = float(rz[0, 1])
    if not keel < 0.0 <= rz[-1, 1]:
        raise InputError(f"Morison drag: profile must run from below the SWL (keel at {keel} m) "
                         "to at least z = 0")
    if n_strips is None:
        if strip_length is None or not (math.isfinite(strip_length) and strip_length > 0):
            raise InputError(f"Morison drag: strip_length must be > 0 [m], got {strip_length}")
        n_strips = max(1, math.ceil(-keel / strip_length - 1e-9))
    if int(n_strips) != n_strips or n_strips < 1:
        raise InputError(f"Morison drag: n_strips must be a positive integer, got {n_strips}")
    edges = np.linspace(keel, 0.0, int(n_strips) + 1)
    rint = _radius_integral(rz, edges)
    dz = np.diff(edges)
    return Strips(z=0.5 * (edges[:-1] + edges[1:]), length=dz, diameter=2.0 * np.diff(rint) / dz)


def _radius_integral(rz: np.ndarray, zq: np.ndarray) -> np.ndarray:
    """``∫_{z_keel}^{zq} r(z) dz`` [m²] of the piecewise-linear profile, at each ``zq``."""
    keep = np.diff(rz[:, 1]) > 0  # horizontal steps have no height
    z1, z2 = rz[:-1, 1][keep], rz[1:, 1][keep]
    r1, r2 = rz[:-1, 0][keep], rz[1:, 0][keep]
    start = np.concatenate([[0.0], np.cumsum(0.5 * (r1 + r2) * (z2 - z1))])
    i = np.clip(np.searchsorted(z2, zq, side="left"), 0, z1.size - 1)
    s = np.clip(zq - z1[i], 0.0, z2[i] - z1[i])
    return start[i] + s * (r1[i] + 0.5 * (r2[i] - r1[i]) / (z2[i] - z1[i]) * s)


def strip_jacobians(strips: Strips, axis_xy: Sequence[float] = (0.0, 0.0),
                    reference_point: Sequence[float] = (0.0, 0.0, 0.0)
                    ) -> tuple[np.ndarray, np.ndarray]:
    """``(J_x, J_y)``, each (n_strips, 6): horizontal strip velocity per unit DOF rate.

    ``v_x = J_x q'`` and ``v_y = J_y q'`` [m/s] for ``q' = (Surge', Sway', Heave' [m/s], Roll',
    Pitch', Yaw' [rad/s])``, small-angle rigid kinematics ``v_O + ω × r`` about O.
    """
    o = np.asarray(reference_point, dtype=float)
    rx, ry = float(axis_xy[0]) - o[0], float(axis_xy[1]) - o[1]
    rz = strips.z - o[2]
    jx, jy = np.zeros((rz.size, 6)), np.zeros((rz.size, 6))
    jx[:, 0], jx[:, 4], jx[:, 5] = 1.0, rz, -ry
    jy[:, 1], jy[:, 3], jy[:, 5] = 1.0, -rz, rx
    return jx, jy


class MorisonDrag(KnownComponent):
    """Morison strip-theory drag on a vertical body of revolution (module docstring).

    Parameters
    ----------
    strips : Strips
        The strips (:func:`profile_strips`).
    cd : float or array, shape (n_strips,)
        Transverse drag coefficient Cd [-] (OC3: 0.6).
    rho : float
        Water density [kg/m³].
    dofs : sequence of str
        DOFs of the histories and ODE states this component acts on (any subset of the six;
        the others are held at rest).
    reference_point : (3,) floats
        O [m], the point rotations and moments are about (OC3: the SWL on the centreline).
    axis_xy : (2,) floats
        Horizontal position of the body axis [m] (default the origin).
    wave : hybridwsi.waves.Wave, optional
        Add the Airy particle velocity of this wave to the relative velocity (off by default).
    water_depth : float
        h [m] of the wave kinematics (``inf`` for deep water).
    g : float
        Gravity [m/s²] of the dispersion relation.
    ramp : float
        Half-cosine ramp of the wave velocity [s] (0: none), as the excitation's.

    Notes
    -----
    ``linear_coefficients`` returns zero damping until :meth:`linearise_on` (the mean tangent
    damping over a history, as :class:`~hybridwsi.forces.linear.QuadraticDamping`) or
    :meth:`linearise_at` (the energy-equivalent damping at a stated velocity amplitude) is
    called; no added mass, no stiffness.
    """

    name = "morison_drag"

    def __init__(self, strips: Strips, cd: float | np.ndarray, rho: float,
                 dofs: Sequence[str] | str = RIGID_DOFS, *,
                 reference_point: Sequence[float] = (0.0, 0.0, 0.0),
                 axis_xy: Sequence[float] = (0.0, 0.0), wave: Wave | None = None,
                 water_depth: float = math.inf, g: float = 9.81, ramp: float = 0.0) -> None:
        self.strips = strips
        self.dofs = check_dofs(dofs)
        cd_arr = np.broadcast_to(np.asarray(cd, dtype=float), strips.z.shape)
        if not (np.all(np.isfinite(cd_arr)) and np.all(cd_arr >= 0)):
            raise InputError(f"Morison drag: Cd must be finite and >= 0, got {cd}")
        if not (math.isfinite(rho) and rho > 0):
            raise InputError(f"Morison drag: rho must be > 0, got {rho}")
        if not water_depth > 0:
            raise InputError(f"Morison drag: water depth must be > 0, got {water_depth}")
        self.cd, self.rho = cd_arr.copy(), float(rho)
        self.reference_point = tuple(float(v) for v in reference_point)
        #: ½ ρ Cd D dz per strip [kg/m]: dF = coef |u| u
        self.coef = 0.5 * self.rho * self.cd * strips.diameter * strips.length
        jx, jy = strip_jacobians(strips, axis_xy, self.reference_point)
        idx = index(self.dofs)
        self._jx, self._jy = jx[:, idx], jy[:, idx]
        self._jx_t, self._jy_t = np.ascontiguousarray(self._jx.T), np.ascontiguousarray(self._jy.T)
        self.wave = wave
        self._wave = None if wave is None else AiryKinematics(
            wave, strips.z, float(axis_xy[0]), float(axis_xy[1]), water_depth, g, ramp)
        # the transverse y velocity vanishes when no chosen DOF moves a strip sideways and the
        # wave runs along x (head seas in Surge/Heave/Pitch): skip it then
        self._two_d = bool(np.any(self._jy)) or (
            self._wave is not None and abs(self._wave.sin_beta) > 0.0)
        self._b_eq: np.ndarray | None = None

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_body(cls, body: Any, cd: float, dofs: Sequence[str] | str | None = None, *,
                  strip_length: float | None = DEFAULT_STRIP_LENGTH, n_strips: int | None = None,
                  **kwargs: Any) -> MorisonDrag:
        """Strips of an :class:`~hybridwsi.bodies.AxisymmetricBody` (or of the axisymmetric
        hull of a :class:`~hybridwsi.bodies.RigidAssembly`), its ρ, g and reference point.

        ``kwargs``: ``wave``, ``water_depth``, ``ramp`` (see the class).
        """
        hull = getattr(body, "hull", body)
        profile = getattr(hull, "profile", None)
        if profile is None:
            raise InputError(f"Morison drag needs an axisymmetric (r, z) profile; "
                             f"{type(hull).__name__} has none")
        kwargs.setdefault("g", body.g)
        return cls(profile_strips(profile, strip_length, n_strips), cd, body.rho,
                   body.dofs if dofs is None else dofs,
                   reference_point=body.reference_point, **kwargs)

    @classmethod
    def from_case(cls, case: Mapping[str, Any], dofs: Sequence[str] | str | None = None, *,
                  wave: Wave | None = None, ramp: float = 0.0) -> MorisonDrag:
        """The drag of a case (``load_case("oc3_hywind")``): the ``[body]`` profile (an
        axisymmetric body, or the ``[body.hull]`` of a rigid assembly),
        ``[hydrodynamics] drag_cd``, ``[environment]`` ρ, g, depth, ``[drag]`` strip settings
        (``strip_length`` [m] or ``n_strips``); ``dofs`` default the case's ``default_dofs``.
        """
        try:
            env, body = case["environment"], case["body"]
            hull = body["hull"] if "hull" in body else body
            profile, cd = hull["profile"], case["hydrodynamics"]["drag_cd"]
            rho, g, depth = env["rho"], env["g"], env["water_depth"]
        except KeyError as exc:
            raise InputError(f"case has no Morison drag entry {exc}") from None
        drag = case.get("drag", {})
        strips = profile_strips(profile, drag.get("strip_length", DEFAULT_STRIP_LENGTH),
                                drag.get("n_strips"))
        return cls(strips, cd, rho, dofs if dofs is not None else case.get("default_dofs",
                                                                          RIGID_DOFS),
                   reference_point=body.get("reference_point", (0.0, 0.0, 0.0)), wave=wave,
                   water_depth=depth, g=g, ramp=ramp)

    # ------------------------------------------------------------------ evaluation
    def _check(self, n_dof: int) -> None:
        if n_dof != len(self.dofs):
            raise InputError(f"Morison drag is set up for {len(self.dofs)} DOFs "
                             f"({', '.join(self.dofs)}), got {n_dof}")

    def _relative(self, t: Any, zdot: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """Horizontal relative velocity ``u = u_wave − v`` at the strips, (..., n_strips)."""
        ux = -(zdot @ self._jx_t)
        uy = -(zdot @ self._jy_t) if self._two_d else None
        if self._wave is not None:
            wx, wy = self._wave.components(t)
            ux += wx
            if uy is not None:
                uy += wy
        return ux, uy

    def generalised_force(self, t: Any, zdot: np.ndarray) -> np.ndarray:
        """Drag ``Q = Σ J_kᵀ dF_k`` [N, N m] for DOF rates ``zdot`` (..., n_dof) [m/s, rad/s].

        ``t`` [s] is a scalar, or one time per row of ``zdot`` (wave kinematics only).
        """
        zdot = np.asarray(zdot, dtype=float)
        self._check(zdot.shape[-1])
        ux, uy = self._relative(t, zdot)
        if uy is None:
            return (self.coef * np.abs(ux) * ux) @ self._jx
        w = self.coef * np.hypot(ux, uy)
        return (w * ux) @ self._jx + (w * uy) @ self._jy

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """Drag on the history's velocities (and times), shape (n_time, n_dof) [N, N m]."""
        self._check_history(hist)
        return self.generalised_force(np.asarray(hist["time"].values, dtype=float),
                                      kinematic(hist, "zdot"))

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Drag at one time ``t`` for rates ``zdot`` of shape (n_dof,) or (batch, n_dof)."""
        return self.generalised_force(t, zdot)

    def compiled_force(self, n_dof: int) -> Any:
        """Numba kernel of :meth:`ode_force` for one state, or None without Numba."""
        from hybridwsi.forces._compiled import morison_force

        self._check(n_dof)
        return morison_force(self.coef, self._jx, self._jy, self._two_d, self._wave)

    def _check_history(self, hist: xr.Dataset) -> None:
        dofs = tuple(str(d) for d in hist["dof"].values)
        if dofs != self.dofs:
            raise InputError(f"Morison drag DOFs {list(self.dofs)} differ from the history's "
                             f"{list(dofs)}")

    # ------------------------------------------------------------------ linearisation
    def linearise_on(self, hist: xr.Dataset) -> MorisonDrag:
        """Set the damping to the mean tangent of the drag over ``hist`` (its relative velocity).

        ``B_eq = mean_t Σ_k coef_k J_kᵀ (|u| 1 + u uᵀ/|u|) J_k`` = ``−mean ∂Q/∂q'``; for one
        DOF and one strip this is ``2 coef mean|u|``, :class:`QuadraticDamping`'s rule.
        """
        self._check_history(hist)
        ux, uy = self._relative(np.asarray(hist["time"].values, dtype=float),
                                kinematic(hist, "zdot"))
        n_t = ux.shape[0]
        if uy is None:
            b = (2.0 * self.coef * np.abs(ux).sum(axis=0) / n_t * self._jx_t) @ self._jx
        else:
            speed = np.hypot(ux, uy)
            inv = np.divide(1.0, speed, out=np.zeros_like(speed), where=speed > 0)
            cxx = (speed + ux * ux * inv).mean(axis=0) * self.coef
            cyy = (speed + uy * uy * inv).mean(axis=0) * self.coef
            cxy = (ux * uy * inv).mean(axis=0) * self.coef
            b = ((cxx * self._jx_t) @ self._jx + (cyy * self._jy_t) @ self._jy
                 + (cxy * self._jx_t) @ self._jy + (cxy * self._jy_t) @ self._jx)
        self._b_eq = b
        return self

    def linearise_at(self, amplitude: Sequence[float] | np.ndarray) -> MorisonDrag:
        """Set the damping energy-equivalent to the drag of a harmonic motion (body in still
        water) whose DOF velocity amplitudes are ``amplitude`` (n_dof,) [m/s, rad/s], in phase.

        Each strip then moves harmonically with amplitude ``V_k = |J_k amplitude|`` along a fixed
        direction, and ``B_eq = Σ_k (8/3π) coef_k V_k J_kᵀ J_k`` dissipates per cycle exactly
        the energy the quadratic drag does along that motion (Borgman's linearisation).
        """
        amp = np.asarray(amplitude, dtype=float).reshape(-1)
        self._check(amp.size)
        if not np.all(np.isfinite(amp)):
            raise InputError("Morison drag: velocity amplitude must be finite")
        w = _HARMONIC_FACTOR * self.coef * np.hypot(self._jx @ amp, self._jy @ amp)
        self._b_eq = (w * self._jx_t) @ self._jx + (w * self._jy_t) @ self._jy
        return self

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        self._check(n_dof)
        zero = np.zeros((n_dof, n_dof))
        b = self._b_eq if self._b_eq is not None else zero.copy()
        return zero, b.copy(), zero.copy()

    def describe(self) -> str:
        cd = np.unique(self.cd)
        cd_text = f"{cd[0]:g}" if cd.size == 1 else "per strip"
        waves = "" if self.wave is None else f", wave kinematics {type(self.wave).__name__}"
        return (f"morison_drag(Cd {cd_text}, {self.strips.z.size} strips, projected area "
                f"{self.strips.projected_area:.6g} m^2, DOFs {','.join(self.dofs)}{waves})")


def additional_damping(case: Mapping[str, Any], dofs: Sequence[str] | str | None = None
                       ) -> LinearDamping:
    """The case's additional linear damping on ``dofs`` as a :class:`LinearDamping`.

    Reads ``[hydrodynamics] additional_damping`` (a table DOF name -> B [N/(m/s) or
    N m/(rad/s)]; absent DOFs are 0), builds the 6x6 diagonal and keeps the rows and columns of
    ``dofs`` (default: the case's ``default_dofs``). OC3: B11 = B22 = 1e5, B33 = 1.3e5,
    B66 = 1.3e7 (Table 4-2).
    """
    table = case.get("hydrodynamics", {}).get("additional_damping")
    if not isinstance(table, Mapping):
        raise InputError("case has no [hydrodynamics] additional_damping table")
    names = check_dofs(list(table)) if table else ()
    diag = np.zeros(6)
    for name, value in zip(names, table.values()):
        diag[RIGID_DOFS.index(name)] = float(value)
    if not (np.all(np.isfinite(diag)) and np.all(diag >= 0)):
        raise InputError("additional damping must be finite and >= 0")
    idx = index(dofs if dofs is not None else case.get("default_dofs", RIGID_DOFS))
    return LinearDamping(np.diag(diag)[np.ix_(idx, idx)])


# ============================================================================================
# Morison's equation on a frame of cylindrical members (semi-submersibles)
# ============================================================================================
class MemberMorison(KnownComponent):
    """Morison's equation on every member of a frame, in 6 DOFs, on the relative velocity.

    Per element ``k`` (centre r_k, axis t_k, length l_k, diameter D_k) and per end disc ``e``
    (area A_e, normal n_e), with ``u = u_wave − v`` the relative velocity and
    ``u_n = (1 − t tᵀ) u`` its part normal to the axis:

        transverse drag   dF = ½ ρ Cd D l |u_n| u_n
        axial end drag    dF = ½ ρ Cd_ax A |u·n| (u·n) n       (heave plates)
        inertia           dF = ρ (1 + Ca) V (1 − t tᵀ) a_wave − ρ Ca V (1 − t tᵀ) a_body

    The inertia terms act only on members outside the potential-flow model (``potential =
    false``: pontoons and braces), whose added mass and wave inertia the BEM does not hold;
    the columns get drag only. The body acceleration part is the constant added-mass matrix
    ``A_m = Σ ρ Ca V Jᵀ (1 − t tᵀ) J`` returned by :meth:`linear_coefficients` (moved to the
    left-hand side of the ODE). Forces and moments about the reference point: ``Q = Σ Jᵀ dF``
    (:func:`point_jacobians`). Small motions: elements stay at their rest positions, no drag
    above the still-water level, no wave stretching.

    Parameters
    ----------
    elements : MemberElements
        :func:`member_elements`.
    rho : float
        Water density [kg/m³].
    dofs : sequence of str
        DOFs of the histories and ODE states (others held at rest).
    reference_point : (3,) floats
        O [m].
    wave : hybridwsi.waves.Wave, optional
        Linear Airy kinematics of this wave (off: still water).
    water_depth, g, ramp : float
        Depth [m], gravity [m/s²] and half-cosine ramp [s] of the wave kinematics.
    inertia : bool
        Include the slender members' inertia (added mass, wave inertia). False when the
        coefficients already hold it (:func:`hybridwsi.hydro.strip.with_slender_members`):
        then this component is the members' drag only.
    """

    name = "member_morison"

    def __init__(self, elements: MemberElements, rho: float,
                 dofs: Sequence[str] | str = RIGID_DOFS, *,
                 reference_point: Sequence[float] = (0.0, 0.0, 0.0), wave: Wave | None = None,
                 water_depth: float = math.inf, g: float = 9.81, ramp: float = 0.0,
                 inertia: bool = True) -> None:
        if not (math.isfinite(rho) and rho > 0):
            raise InputError(f"Morison: rho must be > 0, got {rho}")
        self.inertia = bool(inertia)
        self.elements, self.rho = elements, float(rho)
        self.dofs = check_dofs(dofs)
        idx = index(self.dofs)
        e = elements
        self._jac = point_jacobians(e.centre, reference_point)[:, :, idx]
        self._jac_end = point_jacobians(e.end_centre, reference_point)[:, :, idx]
        self._t = e.tangent
        #: ½ ρ Cd D l per element and ½ ρ Cd_ax A per end disc [kg/m]
        self.coef = 0.5 * self.rho * e.cd * e.diameter * e.length
        self.coef_end = 0.5 * self.rho * e.end_cd * e.end_area
        inertia_volume = np.where(e.inertia & self.inertia, e.volume, 0.0)
        self._fk = self.rho * (1.0 + e.ca) * inertia_volume
        normal_jac = self._jac - np.einsum("nk,nl,nld->nkd", self._t, self._t, self._jac)
        self._added_mass = np.einsum("n,nkd,nke->de", self.rho * e.ca * inertia_volume,
                                     normal_jac, normal_jac)
        self.wave = wave
        self._wave = None if wave is None else AiryPoints(
            wave, np.concatenate([e.centre, e.end_centre]), water_depth, g, ramp)
        self._b_eq: np.ndarray | None = None

    @classmethod
    def from_case(cls, case: Mapping[str, Any], dofs: Sequence[str] | str | None = None, *,
                  wave: Wave | None = None, ramp: float = 0.0, inertia: bool = True
                  ) -> MemberMorison:
        """The members of ``[body.hull]`` (``[[body.hull.members]]`` with their Morison
        coefficients; :func:`hybridwsi.hydro.strip.case_elements`), ``[environment]`` ρ, g,
        depth; ``dofs`` default the case's ``default_dofs``; ``inertia`` as in the class."""
        try:
            env = case["environment"]
            ref = case["body"].get("reference_point", (0.0, 0.0, 0.0))
            rho, g = env["rho"], env["g"]
        except (KeyError, AttributeError) as exc:
            raise InputError(f"case has no Morison entry {exc}") from None
        return cls(case_elements(case), rho,
                   dofs if dofs is not None else case.get("default_dofs", RIGID_DOFS),
                   reference_point=ref, wave=wave, water_depth=env.get("water_depth", math.inf),
                   g=g, ramp=ramp, inertia=inertia)

    # ------------------------------------------------------------------ evaluation
    def _check(self, n_dof: int) -> None:
        if n_dof != len(self.dofs):
            raise InputError(f"Morison members are set up for {len(self.dofs)} DOFs "
                             f"({', '.join(self.dofs)}), got {n_dof}")

    def _relative(self, t: float, zdot: np.ndarray):
        """Relative velocity at elements and end discs (..., n, 3), (..., m, 3), and the wave
        acceleration at the elements (n, 3) or None."""
        u = -np.einsum("nkd,...d->...nk", self._jac, zdot)
        u_end = -np.einsum("nkd,...d->...nk", self._jac_end, zdot)
        acc = None
        if self._wave is not None:
            vel, a = self._wave.velocity_acceleration(t)
            n = self._jac.shape[0]
            u, u_end, acc = u + vel[:n], u_end + vel[n:], a[:n]
        return u, u_end, acc

    def generalised_force(self, t: float, zdot: np.ndarray) -> np.ndarray:
        """Drag and wave inertia ``Σ Jᵀ dF`` [N, N m] for DOF rates ``zdot`` (..., n_dof)
        [m/s, rad/s] at one time ``t`` [s] (no body-acceleration part)."""
        zdot = np.asarray(zdot, dtype=float)
        self._check(zdot.shape[-1])
        u, u_end, acc = self._relative(t, zdot)
        un = u - np.sum(u * self._t, axis=-1, keepdims=True) * self._t
        f = (self.coef * np.linalg.norm(un, axis=-1))[..., None] * un
        if acc is not None and np.any(self._fk):
            an = acc - np.sum(acc * self._t, axis=-1, keepdims=True) * self._t
            f = f + self._fk[:, None] * an
        q = np.einsum("nkd,...nk->...d", self._jac, f)
        if self.coef_end.size:
            w = np.sum(u_end * self.elements.end_axis, axis=-1)
            f_end = (self.coef_end * np.abs(w) * w)[..., None] * self.elements.end_axis
            q = q + np.einsum("nkd,...nk->...d", self._jac_end, f_end)
        return q

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        return self.generalised_force(t, zdot)

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """Total Morison force on a history (n_time, n_dof) [N, N m], with ``−A_m z̈``."""
        dofs = tuple(str(d) for d in hist["dof"].values)
        if dofs != self.dofs:
            raise InputError(f"Morison member DOFs {list(self.dofs)} differ from the "
                             f"history's {list(dofs)}")
        times = np.asarray(hist["time"].values, dtype=float)
        zdot = kinematic(hist, "zdot")
        out = np.array([self.generalised_force(t, v) for t, v in zip(times, zdot)])
        if np.any(self._added_mass):
            out -= kinematic(hist, "zddot") @ self._added_mass.T
        return out

    # ------------------------------------------------------------------ linearisation
    def added_mass(self) -> np.ndarray:
        """``A_m`` (n_dof, n_dof) [kg, kg m, kg m²]: Morison added mass of the members outside
        the potential-flow model."""
        return self._added_mass.copy()

    def linearise_at(self, amplitude: Sequence[float] | np.ndarray) -> MemberMorison:
        """Damping energy-equivalent to the drag of a harmonic motion in still water with DOF
        velocity amplitudes ``amplitude`` (n_dof,) [m/s, rad/s], in phase (Borgman): per
        element ``(8/3π) coef |(1 − t tᵀ) J a| Jᵀ (1 − t tᵀ) J``, per disc
        ``(8/3π) coef |n·J a| Jᵀ n nᵀ J``."""
        amp = np.asarray(amplitude, dtype=float).reshape(-1)
        self._check(amp.size)
        if not np.all(np.isfinite(amp)):
            raise InputError("Morison: velocity amplitude must be finite")
        normal_jac = self._jac - np.einsum("nk,nl,nld->nkd", self._t, self._t, self._jac)
        speed = np.linalg.norm(normal_jac @ amp, axis=-1)
        b = np.einsum("n,nkd,nke->de", _HARMONIC_FACTOR * self.coef * speed, normal_jac,
                      normal_jac)
        axial = np.einsum("nk,nkd->nd", self.elements.end_axis, self._jac_end)
        b += np.einsum("n,nd,ne->de", _HARMONIC_FACTOR * self.coef_end * np.abs(axial @ amp),
                       axial, axial)
        self._b_eq = b
        return self

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        self._check(n_dof)
        zero = np.zeros((n_dof, n_dof))
        b = self._b_eq if self._b_eq is not None else zero.copy()
        return self._added_mass.copy(), b.copy(), zero

    def describe(self) -> str:
        e = self.elements
        waves = "" if self.wave is None else f", wave kinematics {type(self.wave).__name__}"
        inertia = len(set(np.array(e.member)[e.inertia])) if self.inertia else 0
        return (f"member_morison({len(set(e.member))} members, {e.length.size} elements, "
                f"{e.end_cd.size} axial end discs, Morison inertia on {inertia} members, "
                f"DOFs {','.join(self.dofs)}{waves})")
