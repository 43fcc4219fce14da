"""The wind turbine rotor as a force component: parked, a constant thrust, or operating.

Four models:

- :class:`ParkedRotor` (the default): no aerodynamic force at all (blades feathered, no wind).
  Its mass and inertia are part of the rigid assembly, not of this component.
- :class:`RotorThrust`: a constant thrust ``T`` [N] along +X at the hub plus a user-given
  linear damping ``B_aero`` [N/(m/s)] on the hub's fore-aft velocity (a hand-set operating
  point; the hub moves with the platform, small-angle rigid kinematics about the reference
  point O: ``v_hub = Surge' + Pitch' r_z − Yaw' r_y`` with ``r = hub − O``; force
  ``Q = j (T − B_aero jᵀż)`` with ``j = (1, 0, 0, 0, r_z, −r_y)``).
- :class:`OperatingRotor` (and :class:`PIControlledRotor`): the NREL 5-MW rotor in steady or
  turbulent wind. The thrust and
  torque of its steady operating curve (:class:`RotorTable`, from CCBlade with the baseline
  torque and pitch controller, ``scripts/rotor_table.py``) evaluated at the rotor-relative wind
  speed ``U_rel = U(t) − s·v_hub``: the wind (:mod:`hybridwsi.wind`) minus the hub's velocity
  along the shaft (unit vector ``s``, downwind, tilted by the shaft tilt), from all six DOFs.
  The thrust acts along ``s`` at the hub; with it the shaft torque's reaction, the moment
  ``Q s`` the aerodynamic torque puts on the nacelle in steady state (the rotor turns
  clockwise looking downwind, FAST's convention). Generalised force:

      F = T(U_rel) j_T + Q(U_rel) j_Q,   j_T = (s, r × s),  j_Q = (0, s),  s·v_hub = j_Tᵀ ż

  so the mean wind gives a mean force (the mean offset) and the slope of the curve an
  aerodynamic damping ``B = T'(U) j_T j_Tᵀ + Q'(U) j_Q j_Tᵀ`` (``linear_coefficients``).

Two controller models (docs/OC3_HYWIND.md "The rotor" compares them with RAFT):

- ``controller = "quasi-steady"`` (:class:`OperatingRotor`): the rotor speed and blade pitch
  follow the wind as in steady state at every instant, so the thrust follows the operating
  curve T(U) and its slope dT/dU *along the curve* is the aerodynamic damping. Below rated
  (8 m/s: +95.6 kN s/m) positive; above rated the pitch controller holds the power, the
  thrust falls with the wind speed and dT/dU < 0 (18 m/s: −18.7 kN s/m; 11.3–11.6 m/s: −520
  to −160): the negative aerodynamic damping of pitch-controlled floating turbines (Larsen &
  Hanson 2007, J. Phys. Conf. Ser. 75 012073; Jonkman 2008, AIAA 2008-1306). It is the exact
  low-frequency limit of any controller with integral action — right for surge (0.05 rad/s,
  far below the pitch controller's bandwidth) and the worst case for the pitch mode (0.21
  rad/s). Memoryless, with a Numba kernel.
- ``controller = "pi"`` (:class:`PIControlledRotor`): the rotor speed from the rigid
  drivetrain, the DISCON generator-torque law and the gain-scheduled PI pitch law
  (:mod:`hybridwsi.forces.controller`; OC3-Hywind's detuned gains by default), the thrust from
  CCBlade's coefficient surfaces: the controller lags fast motion, so the damping depends on
  frequency — the operating-curve slope for slow motion, the frozen ∂T/∂U (+78.5 kN s/m at
  18 m/s) for fast motion; with the detuned gains the pitch mode is damped (+16 kN s/m at
  0.21 rad/s and 18 m/s) where the quasi-steady model undamps it. Three internal states.

Both leave out dynamic inflow, rotational sampling, tower and blade flexibility, gyroscopic
moments and the 0.4 % of 1/cos(tilt) between the shaft-axis and horizontal wind speeds.
Outside the table (2–30 m/s relative wind: the curve continued past cut-in 3 m/s and cut-out
25 m/s) the component refuses the state (:class:`~hybridwsi.errors.SolverError`): shut-down
is not modelled.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.dofs import RIGID_DOFS, check_dofs, index
from hybridwsi.errors import InputError, SolverError
from hybridwsi.files import DATA, data_path, read_netcdf
from hybridwsi.forces.base import KnownComponent, kinematic
from hybridwsi.forces.controller import PI_GAINS, THETA_K, PitchPI, TorqueLaw
from hybridwsi.forces.mooring import bicubic_patches
from hybridwsi.wind import SteadyWind, TurbulentWind, number

#: rotor states of a case's ``[rotor]`` table
STATES = ("parked", "thrust", "operating")
#: controller models of :class:`OperatingRotor`
CONTROLLERS = ("quasi-steady", "pi")
#: the variables :class:`RotorTable` needs, with their units
TABLE_VARIABLES = {"thrust": "N", "torque": "N m", "dT_dU": "N s/m", "dT_dU_frozen": "N s/m",
                   "dQ_dU": "N s", "dQ_dOmega": "N m s/rad", "dQ_dpitch": "N m/rad",
                   "dOmega_dU": "rad/m", "dpitch_dU": "rad s/m", "rotor_speed": "rad/s",
                   "blade_pitch": "rad"}


def _finite(name: str, value: Any) -> float:
    return number(f"rotor: {name}", value)


class RotorThrust(KnownComponent):
    """Constant thrust at hub height with linear aerodynamic damping (module docstring).

    Parameters
    ----------
    thrust : float
        Mean rotor thrust T [N] along +X (downwind).
    aero_damping : float
        B_aero [N/(m/s)] on the hub's fore-aft velocity (may be negative on purpose).
    hub : (3,) floats
        Point where the thrust acts (the hub / rotor apex) [m], global frame at rest. Only its
        height (and its y, for a yaw moment) matter: the thrust is along X.
    dofs : sequence of str
        DOFs of the histories and ODE states (any subset; the others are held at rest).
    reference_point : (3,) floats
        O [m], the point rotations and moments are about.
    """

    name = "rotor"

    def __init__(self, thrust: float = 0.0, aero_damping: float = 0.0,
                 hub: Sequence[float] = (0.0, 0.0, 0.0), dofs: Sequence[str] | str = RIGID_DOFS,
                 *, reference_point: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        self.thrust = _finite("thrust", thrust)
        self.aero_damping = _finite("aero_damping", aero_damping)
        hub_arr, ref = np.asarray(hub, dtype=float), np.asarray(reference_point, dtype=float)
        if hub_arr.shape != (3,) or ref.shape != (3,) or not np.all(np.isfinite(hub_arr)):
            raise InputError("rotor: hub and reference_point must be 3 finite numbers [m]")
        self.hub = tuple(float(v) for v in hub_arr)
        self.reference_point = tuple(float(v) for v in ref)
        self.dofs = check_dofs(dofs)
        r = hub_arr - ref
        #: hub fore-aft velocity per unit DOF rate = generalised force per unit hub force
        self.lever = np.array([1.0, 0.0, 0.0, 0.0, r[2], -r[1]])[index(self.dofs)]
        # without damping the force is a constant: a generator keeps its linear solver
        self.time_only = self.aero_damping == 0.0

    def _check(self, n_dof: int) -> None:
        if n_dof != len(self.dofs):
            raise InputError(f"rotor component is set up for {len(self.dofs)} DOFs "
                             f"({', '.join(self.dofs)}), got {n_dof}")

    def hub_force(self, zdot: np.ndarray) -> np.ndarray:
        """Fore-aft hub force ``T − B_aero v_hub`` [N] for rates (..., n_dof), shape (...)."""
        zdot = np.asarray(zdot, dtype=float)
        self._check(zdot.shape[-1])
        return self.thrust - self.aero_damping * (zdot @ self.lever)

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """Rotor force on the history, shape (n_time, n_dof) [N, N m]."""
        dofs = tuple(str(d) for d in hist["dof"].values)
        if dofs != self.dofs:
            raise InputError(f"rotor DOFs {list(self.dofs)} differ from the history's "
                             f"{list(dofs)}")
        return self.hub_force(kinematic(hist, "zdot"))[:, None] * self.lever

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Rotor force for rates of shape (n_dof,) or (batch, n_dof) [N, N m]."""
        return np.asarray(self.hub_force(zdot))[..., None] * self.lever

    def mean_force(self) -> np.ndarray:
        """The force at rest, ``T j`` (n_dof,) [N, N m] (what moves the equilibrium)."""
        return self.thrust * self.lever

    def compiled_force(self, n_dof: int) -> Any:
        """Numba kernel of :meth:`ode_force` (``(T − B_aero jᵀż) j``), or None without Numba."""
        from hybridwsi.forces._compiled import rotor_force  # imports Numba: on demand

        self._check(n_dof)
        return rotor_force(self.thrust, self.aero_damping, self.lever)

    def time_force(self, t: np.ndarray, n_dof: int | None = None) -> np.ndarray:
        """The constant ``T j`` at times ``t``, shape (nt, n_dof) (only without damping)."""
        if not self.time_only:
            return super().time_force(t, n_dof)
        self._check(len(self.dofs) if n_dof is None else n_dof)
        return np.broadcast_to(self.thrust * self.lever, (np.size(t), self.lever.size)).copy()

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """No added mass or stiffness; damping ``B_aero j jᵀ`` (the mean thrust is constant)."""
        self._check(n_dof)
        zero = np.zeros((n_dof, n_dof))
        return zero, self.aero_damping * np.outer(self.lever, self.lever), zero.copy()

    def describe(self) -> str:
        return (f"rotor(thrust {self.thrust:.6g} N at z = {self.hub[2]:g} m, aero damping "
                f"{self.aero_damping:.6g} N s/m, DOFs {','.join(self.dofs)})")


class ParkedRotor(RotorThrust):
    """A parked rotor: no aerodynamic force (the default state of a case)."""

    name = "parked_rotor"

    def __init__(self, dofs: Sequence[str] | str = RIGID_DOFS, hub: Sequence[float] = (0.0, 0.0, 0.0),
                 *, reference_point: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        super().__init__(0.0, 0.0, hub, dofs, reference_point=reference_point)

    def describe(self) -> str:
        return f"parked_rotor(no force, DOFs {','.join(self.dofs)})"


class RotorTable:
    """A rotor's steady operating curve against hub-height wind speed (module docstring).

    Parameters
    ----------
    data : xarray.Dataset
        Coordinate ``wind_speed`` [m/s] (strictly increasing) and the variables of
        :data:`TABLE_VARIABLES` in their units (the file ``scripts/rotor_table.py`` writes).
    source : str
        Where the table came from (for messages and ``describe``).
    """

    def __init__(self, data: xr.Dataset, source: str = "dataset") -> None:
        if "wind_speed" not in data.coords:
            raise InputError(f"rotor table {source}: no 'wind_speed' coordinate")
        u = np.asarray(data["wind_speed"].values, dtype=float)
        if u.ndim != 1 or u.size < 2 or not np.all(np.isfinite(u)) or np.any(np.diff(u) <= 0):
            raise InputError(f"rotor table {source}: wind_speed must be finite and strictly "
                             "increasing (>= 2 values)")
        for name, unit in TABLE_VARIABLES.items():
            if name not in data:
                raise InputError(f"rotor table {source}: missing variable '{name}'")
            if data[name].attrs.get("units", unit) != unit:
                raise InputError(f"rotor table {source}: '{name}' must be in {unit}, got "
                                 f"{data[name].attrs['units']}")
            if data[name].dims != ("wind_speed",) or not np.all(np.isfinite(data[name].values)):
                raise InputError(f"rotor table {source}: '{name}' must be finite over wind_speed")
        self.data, self.source = data, source
        self.wind_speed = u
        self.thrust_values = np.asarray(data["thrust"].values, dtype=float)
        self.torque_values = np.asarray(data["torque"].values, dtype=float)

    @classmethod
    def from_file(cls, path: str | Path) -> RotorTable:
        """Read a table written by ``scripts/rotor_table.py`` (InputError when unreadable)."""
        return cls(read_netcdf(path), source=str(path))

    @classmethod
    def nrel_5mw(cls) -> RotorTable:
        """The shipped NREL 5-MW table (``hybridwsi/data/rotor_nrel5mw.nc``)."""
        return cls.from_file(DATA / DEFAULT_TABLE)

    @property
    def range(self) -> tuple[float, float]:
        """Smallest and largest tabulated wind speed [m/s]."""
        return float(self.wind_speed[0]), float(self.wind_speed[-1])

    def _check(self, u: np.ndarray) -> np.ndarray:
        lo, hi = self.range
        bad = ~((u >= lo) & (u <= hi))
        if np.any(bad):
            raise InputError(f"rotor table: wind speed {np.asarray(u)[bad].flat[0]:.6g} m/s outside "
                             f"[{lo:g}, {hi:g}] m/s")
        return u

    def value(self, name: str, u: float | np.ndarray) -> np.ndarray:
        """Variable ``name`` linearly interpolated at wind speeds ``u`` [m/s]."""
        u = self._check(np.asarray(u, dtype=float))
        return np.interp(u, self.wind_speed, np.asarray(self.data[name].values, dtype=float))

    def thrust(self, u: float | np.ndarray) -> np.ndarray:
        """Steady aerodynamic thrust [N] along the shaft."""
        return self.value("thrust", u)

    def torque(self, u: float | np.ndarray) -> np.ndarray:
        """Steady aerodynamic torque [N m] about the shaft."""
        return self.value("torque", u)

    def thrust_slope(self, u: float | np.ndarray) -> np.ndarray:
        """dT/dU [N s/m] along the operating curve (the aerodynamic damping)."""
        return self.value("dT_dU", u)

    def torque_slope(self, u: float | np.ndarray) -> np.ndarray:
        """dQ/dU [N s] along the operating curve: Q_U + Q_Ω dΩ/dU + Q_θ dθ/dU."""
        return (self.value("dQ_dU", u) + self.value("dQ_dOmega", u) * self.value("dOmega_dU", u)
                + self.value("dQ_dpitch", u) * self.value("dpitch_dU", u))


#: the shipped table (``scripts/rotor_table.py``)
DEFAULT_TABLE = "rotor_nrel5mw.nc"


def shaft_levers(hub: Sequence[float], reference_point: Sequence[float], shaft_tilt: float,
                 torque_reaction: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """``(j_T, j_Q)`` (6,): the generalised force per unit thrust along the shaft and per unit
    shaft torque, ``j_T = (s, r × s)``, ``j_Q = (0, s)`` with ``s = (cos τ, 0, −sin τ)`` the
    downwind shaft axis tilted by ``shaft_tilt`` τ [rad] and ``r = hub − O`` [m]. ``j_Tᵀ ż``
    is also the hub's velocity along the shaft (small rotations)."""
    s = np.array([np.cos(shaft_tilt), 0.0, -np.sin(shaft_tilt)])
    r = np.asarray(hub, dtype=float) - np.asarray(reference_point, dtype=float)
    j_t = np.concatenate([s, np.cross(r, s)])
    j_q = np.concatenate([np.zeros(3), s]) if torque_reaction else np.zeros(6)
    return j_t, j_q


class OperatingRotor(KnownComponent):
    """The operating rotor: operating-curve thrust and torque at the relative wind (module doc).

    Parameters
    ----------
    table : RotorTable
        Steady operating curve (:meth:`RotorTable.nrel_5mw`).
    wind : SteadyWind or TurbulentWind
        Hub-height wind U(t) [m/s] (:mod:`hybridwsi.wind`).
    hub : (3,) floats
        Rotor apex [m], where the thrust acts (global frame at rest).
    dofs : sequence of str
        DOFs of the histories and ODE states (any subset; the others are held at rest).
    reference_point : (3,) floats
        O [m], the point rotations and moments are about.
    shaft_tilt : float
        τ [rad], the shaft's upward tilt at the rotor (NREL 5-MW: 5 deg).
    torque_reaction : bool
        Include the moment ``Q s`` of the shaft torque on the nacelle.
    """

    name = "operating_rotor"
    #: how rotor speed and pitch follow the wind (module docstring)
    controller = "quasi-steady"

    def __init__(self, table: RotorTable, wind: SteadyWind | TurbulentWind,
                 hub: Sequence[float], dofs: Sequence[str] | str = RIGID_DOFS, *,
                 reference_point: Sequence[float] = (0.0, 0.0, 0.0), shaft_tilt: float = 0.0,
                 torque_reaction: bool = True) -> None:
        if not isinstance(table, RotorTable):
            raise InputError("rotor: table must be a RotorTable")
        if not isinstance(wind, (SteadyWind, TurbulentWind)):
            raise InputError("rotor: wind must be a hybridwsi.wind.SteadyWind or TurbulentWind")
        self.table, self.wind = table, wind
        self.hub = _point("hub", hub)
        self.reference_point = _point("reference_point", reference_point)
        self.shaft_tilt = _finite("shaft_tilt", shaft_tilt)
        self.torque_reaction = bool(torque_reaction)
        self.dofs = check_dofs(dofs)
        j_t, j_q = shaft_levers(self.hub, self.reference_point, self.shaft_tilt,
                                self.torque_reaction)
        #: generalised force per N of thrust = hub velocity along the shaft per unit rate
        self.lever = j_t[index(self.dofs)]
        #: generalised force per N m of shaft torque
        self.torque_lever = j_q[index(self.dofs)]
        table.thrust(wind.mean)  # the mean wind must be in the table (InputError otherwise)

    def _check(self, n_dof: int) -> None:
        if n_dof != len(self.dofs):
            raise InputError(f"rotor component is set up for {len(self.dofs)} DOFs "
                             f"({', '.join(self.dofs)}), got {n_dof}")

    def relative_wind(self, t: float | np.ndarray, zdot: np.ndarray) -> np.ndarray:
        """``U(t) − j_Tᵀ ż`` [m/s] for rates (..., n_dof) at times ``t`` (broadcast)."""
        zdot = np.asarray(zdot, dtype=float)
        self._check(zdot.shape[-1])
        return self.wind.speed(t) - zdot @ self.lever

    def _wrench(self, u_rel: np.ndarray, t: float | np.ndarray) -> np.ndarray:
        lo, hi = self.table.range
        bad = ~((u_rel >= lo) & (u_rel <= hi))
        if np.any(bad):
            k = np.flatnonzero(np.ravel(bad))[0]
            when = np.broadcast_to(np.asarray(t, dtype=float), np.shape(u_rel)).flat[k]
            raise SolverError(f"rotor: relative wind speed {np.ravel(u_rel)[k]:.6g} m/s at t = "
                              f"{when:.6g} s is outside the table [{lo:g}, {hi:g}] m/s")
        thrust = np.interp(u_rel, self.table.wind_speed, self.table.thrust_values)
        torque = np.interp(u_rel, self.table.wind_speed, self.table.torque_values)
        return thrust[..., None] * self.lever + torque[..., None] * self.torque_lever

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """Rotor force on the history, shape (n_time, n_dof) [N, N m]."""
        dofs = tuple(str(d) for d in hist["dof"].values)
        if dofs != self.dofs:
            raise InputError(f"rotor DOFs {list(self.dofs)} differ from the history's "
                             f"{list(dofs)}")
        t = np.asarray(hist["time"].values, dtype=float)
        return self._wrench(self.relative_wind(t, kinematic(hist, "zdot")), t)

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Rotor force for rates of shape (n_dof,) or (batch, n_dof) at time t [N, N m]."""
        return self._wrench(np.asarray(self.relative_wind(t, zdot)), t)

    def compiled_force(self, n_dof: int) -> Any:
        """Numba kernel of :meth:`ode_force`, or None without Numba."""
        from hybridwsi.forces._compiled import operating_rotor_force  # imports Numba: on demand

        self._check(n_dof)
        dt, samples = self.wind.samples()
        return operating_rotor_force(self.table.wind_speed, self.table.thrust_values,
                                     self.table.torque_values, self.lever, self.torque_lever,
                                     dt, samples)

    def mean_force(self) -> np.ndarray:
        """The force at rest in the mean wind, (n_dof,) [N, N m] (what moves the equilibrium)."""
        return self._wrench(np.asarray(self.wind.mean), 0.0)

    @property
    def aero_damping(self) -> float:
        """dT/dU [N s/m] of the operating curve at the mean wind speed."""
        return float(self.table.thrust_slope(self.wind.mean))

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """No added mass or stiffness; damping ``T' j_T j_Tᵀ + Q' j_Q j_Tᵀ`` at the mean wind
        (slopes along the operating curve), [N s/m, N s, N m s/rad per DOF pair]."""
        self._check(n_dof)
        u = self.wind.mean
        zero = np.zeros((n_dof, n_dof))
        damping = (self.aero_damping * np.outer(self.lever, self.lever)
                   + float(self.table.torque_slope(u)) * np.outer(self.torque_lever, self.lever))
        return zero, damping, zero.copy()

    def describe(self) -> str:
        return (f"operating_rotor({self.wind.describe()}, {self.controller} controller, hub z = "
                f"{self.hub[2]:g} m, tilt {np.degrees(self.shaft_tilt):g} deg, "
                f"torque reaction {'on' if self.torque_reaction else 'off'}, "
                f"DOFs {','.join(self.dofs)})")


class RotorAerodynamics:
    """Thrust T [N] and torque Q [N m] at any (wind speed, rotor speed, pitch) from a table's
    coefficient surfaces CT, CQ (tip-speed ratio, pitch): C¹ bicubic patches with the node
    values and slopes of the interpolating spline (as the mooring table), evaluated with
    Python floats for one state (the ODE right-hand side) and NumPy arrays for many. The
    linearisation takes the patches' own derivatives: it is the slope of what is integrated.
    """

    def __init__(self, table: RotorTable) -> None:
        data = table.data
        for name in ("thrust_coefficient_surface", "torque_coefficient_surface"):
            if name not in data or data[name].dims != ("tsr", "pitch"):
                raise InputError(f"rotor table {table.source}: the 'pi' controller needs "
                                 f"'{name}' over (tsr, pitch) (scripts/rotor_table.py)")
        tsr, pitch = (np.asarray(data[n].values, dtype=float) for n in ("tsr", "pitch"))
        steps = np.diff(tsr), np.diff(pitch)
        if not all(np.allclose(d, d[0], rtol=1e-9) for d in steps):
            raise InputError(f"rotor table {table.source}: the surfaces need a uniform grid")
        self.origin, self.step = (tsr[0], pitch[0]), (steps[0][0], steps[1][0])
        self.shape = (tsr.size - 1, pitch.size - 1)  # cells
        self.tsr_range, self.pitch_range = (tsr[0], tsr[-1]), (pitch[0], pitch[-1])
        self.rho = float(data.attrs["air_density"])
        self.radius = float(data.attrs["rotor_radius"])        # Rtip: the tip-speed ratio's
        self.area_radius = float(data.attrs["rotor_area_radius"])  # Rtip cos(precone)
        self.area = np.pi * self.area_radius**2
        powers = np.arange(1.0, 4.0)
        self.cells: dict[str, np.ndarray] = {}
        for key, name in (("T", "thrust_coefficient_surface"), ("Q", "torque_coefficient_surface")):
            a = bicubic_patches(tsr, pitch, np.asarray(data[name].values, dtype=float))
            du, dv = np.zeros_like(a), np.zeros_like(a)
            du[..., :3, :] = a[..., 1:, :] * powers[:, None]  # ∂/∂u of Σ a_pq u^p v^q
            dv[..., :, :3] = a[..., :, 1:] * powers
            for tag, arr in (("", a), ("_u", du), ("_v", dv)):
                self.cells[key + tag] = arr.reshape(-1, 16)
        self._lists = {k: v.tolist() for k, v in self.cells.items()}

    def _locate(self, lam: Any, pitch: Any) -> tuple[Any, Any, Any]:
        """Cell index and local coordinates; SolverError outside the surfaces."""
        x = (lam - self.origin[0]) / self.step[0]
        y = (pitch - self.origin[1]) / self.step[1]
        nx, ny = self.shape
        one = isinstance(x, float)
        inside = ((0.0 <= x <= nx and 0.0 <= y <= ny) if one else
                  bool(np.all((x >= 0.0) & (x <= nx) & (y >= 0.0) & (y <= ny))))
        if not inside:
            raise SolverError(f"rotor: operating point outside the coefficient surfaces (tip-"
                              f"speed ratio {np.ravel(lam)[0]:.4g}, pitch "
                              f"{np.degrees(np.ravel(pitch)[0]):.4g} deg)")
        if one:
            i, j = min(int(x), nx - 1), min(int(y), ny - 1)
        else:
            i, j = np.minimum(x.astype(np.intp), nx - 1), np.minimum(y.astype(np.intp), ny - 1)
        return i * ny + j, x - i, y - j

    def coefficient(self, name: str, lam: Any, pitch: Any) -> Any:
        """``T``/``Q`` coefficient (or its ∂/∂tsr ``T_u``, ∂/∂pitch ``T_v`` per grid step)."""
        from hybridwsi.forces._compiled import bicubic  # the mooring table's formula

        k, u, v = self._locate(lam, pitch)
        cells = self._lists[name][k] if isinstance(k, int) else self.cells[name][k].T
        return bicubic(cells, 0, u, v)

    def loads(self, u: Any, omega: Any, pitch: Any) -> tuple[Any, Any]:
        """(T [N], Q [N m]) at wind speed u [m/s], rotor speed omega [rad/s], pitch [rad]
        (floats or arrays that broadcast)."""
        if not (u > 0.0 if isinstance(u, float) else np.all(np.asarray(u) > 0.0)):
            raise SolverError(f"rotor: relative wind speed {np.min(u):.4g} m/s is not positive")
        lam = omega * self.radius / u
        q = 0.5 * self.rho * self.area * u * u
        return (q * self.coefficient("T", lam, pitch),
                q * self.area_radius * self.coefficient("Q", lam, pitch))

    def partials(self, u: float, omega: float, pitch: float) -> dict[str, float]:
        """∂T, ∂Q per m/s (``_U``), per rad/s (``_Omega``), per rad (``_pitch``)."""
        lam = omega * self.radius / u
        q = 0.5 * self.rho * self.area * u**2
        out = {}
        for name, scale in (("T", q), ("Q", q * self.area_radius)):
            c = float(self.coefficient(name, lam, pitch))
            c_lam = float(self.coefficient(name + "_u", lam, pitch)) / self.step[0]
            c_p = float(self.coefficient(name + "_v", lam, pitch)) / self.step[1]
            out[name + "_U"] = scale * (2.0 * c / u - c_lam * lam / u)
            out[name + "_Omega"] = scale * c_lam * self.radius / u
            out[name + "_pitch"] = scale * c_p
        return out


class PIControlledRotor(OperatingRotor):
    """The operating rotor with rotor-speed dynamics and the baseline controller.

    The thrust is T(U_rel, Ω, θ) of the coefficient surfaces (:class:`RotorAerodynamics`);
    the rotor speed obeys the rigid drivetrain ``I Ω' = Q(U_rel, Ω, θ) − N τ_g``; the generator
    torque τ_g follows the DISCON law (:class:`~hybridwsi.forces.controller.TorqueLaw`) and the
    pitch the gain-scheduled PI law (:class:`~hybridwsi.forces.controller.PitchPI`), both on
    the generator speed low-pass filtered at ``filter_hz`` (DISCON: 0.25 Hz, first order). The
    moment on the nacelle is the drivetrain's, ``N τ_g`` about the shaft. No pitch actuator
    dynamics or rate limit (8 deg/s), no drivetrain torsion.

    Internal states (deviations from the steady state at the mean wind, so that zero states
    start the run in steady operation): rotor speed δΩ [rad/s], filtered generator speed
    δω_f [rad/s], integrated speed error δ∫e [rad].

    Parameters
    ----------
    table, wind, hub, dofs, reference_point, shaft_tilt, torque_reaction
        As :class:`OperatingRotor` (the table must hold the coefficient surfaces).
    pitch_control : PitchPI
        Gains on the generator speed.
    torque_law : TorqueLaw
        Generator torque law (region 3: constant power or constant torque).
    drivetrain_inertia : float
        I [kg m²] about the shaft, rotor side (rotor + N² × generator).
    filter_hz : float
        Corner frequency [Hz] of the generator-speed filter.
    """

    name = "pi_controlled_rotor"
    controller = "pi"
    n_states = 3

    def __init__(self, table: RotorTable, wind: SteadyWind | TurbulentWind,
                 hub: Sequence[float], dofs: Sequence[str] | str = RIGID_DOFS, *,
                 pitch_control: PitchPI, torque_law: TorqueLaw, drivetrain_inertia: float,
                 filter_hz: float = 0.25, reference_point: Sequence[float] = (0.0, 0.0, 0.0),
                 shaft_tilt: float = 0.0, torque_reaction: bool = True) -> None:
        super().__init__(table, wind, hub, dofs, reference_point=reference_point,
                         shaft_tilt=shaft_tilt, torque_reaction=torque_reaction)
        self.aero = RotorAerodynamics(table)
        self.pi, self.law = pitch_control, torque_law
        self.inertia = number("rotor: drivetrain_inertia", drivetrain_inertia, positive=True)
        self.filter_rate = 2.0 * np.pi * number("rotor: filter_hz", filter_hz, positive=True)
        self.gearbox = float(table.data.attrs["gearbox_ratio"])
        self._last_key: tuple | None = None
        self._last: tuple = ()
        self.omega0, self.pitch0 = self.steady_state(wind.mean)
        self.integral0 = self.pi.integral_for(self.pitch0) if self.pitch0 > 0 else 0.0

    def steady_state(self, u: float) -> tuple[float, float]:
        """(Ω [rad/s], θ [rad]) where the drivetrain is balanced and the PI law at rest, at a
        constant wind u [m/s], on this model's own surfaces (so zero states are steady)."""
        import scipy.optimize

        n, w_ref = self.gearbox, self.pi.reference_speed

        def balance(omega: float, pitch: float = 0.0) -> float:
            q = float(self.aero.loads(u, omega, pitch)[1])
            return q - n * float(self.law.torque(n * omega, pitch))

        lo = 1.05 * self.aero.tsr_range[0] * u / self.aero.radius
        if balance(w_ref / n) < 0.0:
            return scipy.optimize.brentq(balance, lo, w_ref / n, xtol=1e-13), 0.0
        pitch = scipy.optimize.brentq(lambda p: balance(w_ref / n, p), 0.0,
                                      float(self.aero.pitch_range[1]) - 1e-6, xtol=1e-13)
        return w_ref / n, pitch

    def _evaluate(self, t: float, zdot: np.ndarray, x: np.ndarray) -> tuple:
        """(thrust [N], drivetrain moment [N m], state derivative) on one state or a batch.

        The ODE right-hand side asks for the force and the state derivative of the same state
        one after the other: the last evaluation is kept (one aerodynamic evaluation each)."""
        x = np.asarray(x, dtype=float)
        zdot = np.asarray(zdot, dtype=float)
        key = (float(t), zdot.tobytes(), x.tobytes())
        if key == self._last_key:
            return self._last
        u = self.relative_wind(t, zdot)
        if x.ndim == 1:  # one state: floats
            u = float(u)
            omega, w_f, integral = (self.omega0 + float(x[0]),
                                    self.gearbox * self.omega0 + float(x[1]),
                                    self.integral0 + float(x[2]))
        else:
            omega, w_f, integral = (self.omega0 + x[..., 0], self.gearbox * self.omega0
                                    + x[..., 1], self.integral0 + x[..., 2])
        error = w_f - self.pi.reference_speed
        pitch = self.pi.command(error, integral)
        thrust, torque = self.aero.loads(u, omega, pitch)
        reaction = self.gearbox * self.law.torque(w_f, pitch)
        parts = ((torque - reaction) / self.inertia,
                 self.filter_rate * (self.gearbox * omega - w_f),
                 np.where((integral <= 0.0) & (error < 0.0), 0.0, error))  # anti-windup
        xdot = (np.array([float(p) for p in parts]) if x.ndim == 1
                else np.stack(np.broadcast_arrays(*parts), axis=-1))
        self._last_key, self._last = key, (thrust, reaction, xdot)
        return self._last

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Thrust along the shaft and the drivetrain torque's moment [N, N m], (…, n_dof)."""
        thrust, reaction, _ = self._evaluate(t, zdot, x)
        return (np.asarray(thrust)[..., None] * self.lever
                + np.asarray(reaction)[..., None] * self.torque_lever)

    def state_derivative(self, t: float, z: np.ndarray, zdot: np.ndarray,
                         x: np.ndarray) -> np.ndarray:
        """(δΩ', δω_f', δ∫e'): drivetrain, speed filter, integrator with anti-windup."""
        return self._evaluate(t, zdot, x)[2]

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """Rotor force on a history [N, N m]: the states integrated along it (RK4, ż linear
        between samples), from steady operation at the first sample."""
        dofs = tuple(str(d) for d in hist["dof"].values)
        if dofs != self.dofs:
            raise InputError(f"rotor DOFs {list(self.dofs)} differ from the history's "
                             f"{list(dofs)}")
        t = np.asarray(hist["time"].values, dtype=float)
        v = kinematic(hist, "zdot")
        x = np.zeros((t.size, self.n_states))
        for k in range(t.size - 1):
            h, vm = t[k + 1] - t[k], 0.5 * (v[k] + v[k + 1])
            f = lambda tk, vk, xk: self.state_derivative(tk, None, vk, xk)  # noqa: E731
            k1 = f(t[k], v[k], x[k])
            k2 = f(t[k] + h / 2, vm, x[k] + h / 2 * k1)
            k3 = f(t[k] + h / 2, vm, x[k] + h / 2 * k2)
            k4 = f(t[k + 1], v[k + 1], x[k] + h * k3)
            x[k + 1] = x[k] + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return np.stack([self.ode_force(t[k], None, v[k], x[k]) for k in range(t.size)])

    def compiled_force(self, n_dof: int) -> Any:
        """None: a component with internal states runs the NumPy loop."""
        return None

    def mean_force(self) -> np.ndarray:
        return self.ode_force(0.0, None, np.zeros(len(self.dofs)), np.zeros(self.n_states))

    def linearisation(self) -> tuple[np.ndarray, ...]:
        """``(A, B, C, D)``: ``y' = A y + B δU``, ``(δT, δM) = C y + D δU`` about the steady
        state (y = the states, without the integral below rated where it is held; δM the
        drivetrain moment N δτ_g)."""
        n, inertia = self.gearbox, self.inertia
        d = self.aero.partials(self.wind.mean, self.omega0, self.pitch0)
        active = self.pitch0 > 0.0  # below rated the pitch sits at 0 and the integral is held
        gain = self.pi.slope(self.pitch0) if active else 0.0
        slope_g = float(self.law.slope(n * self.omega0, self.pitch0))
        kp, ki = gain * self.pi.kp, gain * self.pi.ki
        a = np.array([[d["Q_Omega"] / inertia, (d["Q_pitch"] * kp - n * slope_g) / inertia,
                       d["Q_pitch"] * ki / inertia],
                      [self.filter_rate * n, -self.filter_rate, 0.0],
                      [0.0, 1.0 if active else 0.0, 0.0]])
        b = np.array([d["Q_U"] / inertia, 0.0, 0.0])
        c = np.array([[d["T_Omega"], d["T_pitch"] * kp, d["T_pitch"] * ki],
                      [0.0, n * slope_g, 0.0]])
        keep = slice(None) if active else slice(0, 2)  # a held integral is no state
        return a[keep, keep], b[keep], c[:, keep], np.array([d["T_U"], 0.0])

    def state_space(self, n_dof: int) -> tuple[np.ndarray, ...]:
        """``(A_s, B_s, C_s, D_s)`` of the linearised rotor force on the platform's DOFs:
        ``y' = A_s y + B_s ż``, ``F = C_s y + D_s ż`` (δU = −j_Tᵀ ż), for
        :func:`hybridwsi.hydro.modal.damped_modes` ``state_force``."""
        self._check(n_dof)
        a, b, c, d = self.linearisation()
        levers = np.column_stack([self.lever, self.torque_lever])  # (n_dof, 2)
        return (a, -np.outer(b, self.lever), levers @ c, -(levers @ d)[:, None] * self.lever)

    def transfer(self, omega: float | np.ndarray) -> np.ndarray:
        """(δT/δU, δM/δU)(iω) [N s/m, N s], shape (…, 2): the linearised response to the
        relative wind at frequencies ``omega`` [rad/s]."""
        a, b, c, d = self.linearisation()
        w = np.atleast_1d(np.asarray(omega, dtype=float))
        eye = np.eye(b.size)
        out = np.array([c @ np.linalg.solve(1j * wk * eye - a, b) + d for wk in w])
        return out.reshape(*np.shape(omega), 2)

    @property
    def aero_damping(self) -> float:
        """dT/dU [N s/m] in the limit of slow motion (the operating-curve slope)."""
        return float(self.transfer(0.0)[0].real)

    def damping_at(self, omega: float, n_dof: int) -> np.ndarray:
        """Aerodynamic damping matrix [N s/m …] at one frequency: Re of the transfer times
        j_T j_Tᵀ (thrust) and j_Q j_Tᵀ (drivetrain moment)."""
        self._check(n_dof)
        h = self.transfer(omega)
        return (h[0].real * np.outer(self.lever, self.lever)
                + h[1].real * np.outer(self.torque_lever, self.lever))

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """No added mass or stiffness; the damping of slow motion (:meth:`damping_at` 0; use
        :meth:`damping_at` for the platform's frequencies: the controller's lag changes it)."""
        zero = np.zeros((n_dof, n_dof))
        return zero, self.damping_at(0.0, n_dof), zero.copy()

    def describe(self) -> str:
        return (f"pi_controlled_rotor({self.wind.describe()}, PI kp {self.pi.kp:g} s ki "
                f"{self.pi.ki:g}, region 3 {self.law.region3}, filter "
                f"{self.filter_rate / (2 * np.pi):g} Hz, hub z = {self.hub[2]:g} m, tilt "
                f"{np.degrees(self.shaft_tilt):g} deg, DOFs {','.join(self.dofs)})")


def _point(name: str, value: Sequence[float]) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InputError(f"rotor: {name} must be 3 finite numbers [m]")
    return tuple(float(v) for v in arr)


def wind_from_case(table: Mapping[str, Any], hub_height: float) -> SteadyWind | TurbulentWind:
    """The wind of a case's ``[rotor]`` table: ``wind_speed`` [m/s], ``turbulence_intensity``
    (0 or absent: steady), ``wind_seed``, ``wind_period`` [s], ``wind_dt`` [s],
    ``rotor_averaged`` (true), ``rotor_radius`` [m] (63)."""
    if "wind_speed" not in table:
        raise InputError("rotor: state 'operating' needs wind_speed [m/s] in [rotor]")
    ti = number("rotor: turbulence_intensity", table.get("turbulence_intensity", 0.0), minimum=0.0)
    if ti == 0.0:
        return SteadyWind(table["wind_speed"])
    radius = table.get("rotor_radius", 63.0) if table.get("rotor_averaged", True) else None
    return TurbulentWind(table["wind_speed"], ti, seed=table.get("wind_seed", 0),
                         hub_height=hub_height, rotor_radius=radius,
                         period=table.get("wind_period", 3600.0), dt=table.get("wind_dt", 0.25))


def _table_path(table: Mapping[str, Any], case_dir: str | Path | None) -> Path:
    """``[rotor] table``: a file shipped in ``hybridwsi/data`` or a path relative to the case
    file's folder (default: the shipped NREL 5-MW table)."""
    return data_path(table.get("table", DEFAULT_TABLE),
                     Path(case_dir) if case_dir is not None else None, "rotor table")


def rotor_from_case(case: Mapping[str, Any], dofs: Sequence[str] | str | None = None, *,
                    case_dir: str | Path | None = None) -> KnownComponent:
    """The rotor of a case's optional ``[rotor]`` table (absent: parked).

    ``[rotor]`` keys: ``state`` (``"parked"``, ``"thrust"`` or ``"operating"``), ``hub`` [m]
    (x, y, z of the rotor apex); for ``"thrust"``: ``thrust`` [N], ``aero_damping``
    [N/(m/s)]; for ``"operating"``: ``table`` (NetCDF of ``scripts/rotor_table.py``, path
    relative to the case file's folder ``case_dir``, default the built-in cases' folder),
    ``shaft_tilt`` [deg], ``controller`` (``"quasi-steady"`` or ``"pi"``),
    ``torque_reaction`` (true) and the wind keys of :func:`wind_from_case`; for ``"pi"``
    also ``drivetrain_inertia`` [kg m^2], ``torque_region3`` (``"constant_torque"`` default,
    or ``"constant_power"``), ``speed_filter_hz`` (0.25) and the gains of
    :func:`pitch_control_from_case`. ``dofs`` default the case's ``default_dofs``.
    """
    table = case.get("rotor", {})
    state = str(table.get("state", "parked"))
    if state not in STATES:
        raise InputError(f"rotor: state must be one of {list(STATES)}, got {state!r}")
    dofs = dofs if dofs is not None else case.get("default_dofs", RIGID_DOFS)
    ref = case.get("body", {}).get("reference_point", (0.0, 0.0, 0.0))
    hub = table.get("hub", (0.0, 0.0, 0.0))
    if state == "parked":
        return ParkedRotor(dofs, hub, reference_point=ref)
    if state == "thrust":
        try:
            return RotorThrust(table["thrust"], table.get("aero_damping", 0.0), table["hub"],
                               dofs, reference_point=ref)
        except KeyError as exc:
            raise InputError(f"rotor: state 'thrust' needs {exc} in [rotor]") from None
    if "hub" not in table:
        raise InputError("rotor: state 'operating' needs hub [m] in [rotor]")
    tilt = np.radians(_finite("shaft_tilt", table.get("shaft_tilt", 0.0)))
    case_dir = case_dir if case_dir is not None else getattr(case, "directory", None)
    curve = RotorTable.from_file(_table_path(table, case_dir))
    wind = wind_from_case(table, _point("hub", hub)[2])
    kw = dict(reference_point=ref, shaft_tilt=tilt,
              torque_reaction=bool(table.get("torque_reaction", True)))
    controller = str(table.get("controller", "quasi-steady"))
    if controller not in CONTROLLERS:
        raise InputError(f"rotor: controller must be one of {list(CONTROLLERS)}, "
                         f"got {controller!r}")
    if controller == "quasi-steady":
        return OperatingRotor(curve, wind, hub, dofs, **kw)
    if "drivetrain_inertia" not in table:
        raise InputError("rotor: controller 'pi' needs drivetrain_inertia [kg m^2] in [rotor]")
    return PIControlledRotor(
        curve, wind, hub, dofs, pitch_control=pitch_control_from_case(table),
        torque_law=TorqueLaw.from_attrs(curve.data.attrs,
                                        str(table.get("torque_region3", "constant_torque"))),
        drivetrain_inertia=table["drivetrain_inertia"],
        filter_hz=table.get("speed_filter_hz", 0.25), **kw)


def pitch_control_from_case(table: Mapping[str, Any]) -> PitchPI:
    """The PI pitch law of ``[rotor]``: ``pi_gains`` (``"oc3_detuned"`` default, or
    ``"baseline"``), overridden by ``pitch_kp`` [s] / ``pitch_ki`` [-] (generator speed), and
    ``pitch_theta_k`` [deg] (gain scheduling, 6.302336)."""
    name = str(table.get("pi_gains", "oc3_detuned"))
    if name not in PI_GAINS:
        raise InputError(f"rotor: pi_gains must be one of {list(PI_GAINS)}, got {name!r}")
    kp, ki = PI_GAINS[name]
    theta_k = np.radians(_finite("pitch_theta_k", table.get("pitch_theta_k",
                                                              np.degrees(THETA_K))))
    return PitchPI(_finite("pitch_kp", table.get("pitch_kp", kp)),
                   _finite("pitch_ki", table.get("pitch_ki", ki)), float(theta_k))
