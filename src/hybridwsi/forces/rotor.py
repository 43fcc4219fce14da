"""The wind turbine rotor as a force component, deliberately simple.

Two models, nothing more:

- :class:`ParkedRotor` (the default): no aerodynamic force at all (blades feathered, no wind).
  Its mass and inertia are part of the rigid assembly, not of this component.
- :class:`RotorThrust`: a constant mean thrust ``T`` [N] along +X (downwind) acting on a line at
  hub height, plus a linear aerodynamic damping ``B_aero`` [N/(m/s)] on the hub's fore-aft
  velocity. The hub moves with the platform (small-angle rigid kinematics about the reference
  point O): ``v_hub = Surge' + Pitch' r_z − Yaw' r_y`` with ``r = hub − O``. The force on the
  hub is ``F_x = T − B_aero v_hub``, so the generalised force is ``Q = j F_x`` with
  ``j = (1, 0, 0, 0, r_z, −r_y)``: a surge force ``F_x`` and a pitch moment ``r_z F_x`` (plus a
  yaw moment if the hub is off the x-z plane). The damping is the surge–pitch matrix
  ``B_aero j jᵀ = B_aero [[1, r_z], [r_z, r_z²]]``.

What it is NOT: no blade-element-momentum aerodynamics, no wind field or turbulence, no
rotor speed, no blade-pitch or torque control (so no negative damping above rated unless
``B_aero < 0`` is given on purpose), no gyroscopic moments, no shaft tilt (the thrust is
horizontal; the 5° tilt would add a vertical component T sin 5°), no tower or blade
flexibility. The numbers (T, B_aero) come from the user or the case's ``[rotor]`` table; for
the NREL 5-MW turbine the steady thrust at the rated 11.4 m/s is about 800 kN (Jonkman et al.
2009, NREL/TP-500-38060, steady-state responses), and ``B_aero`` is the slope dT/dU of the
thrust curve at the operating point.

The mean thrust moves the equilibrium (OC3: ~20 m surge, ~0.05 rad pitch with the linear
restoring); ``linear_coefficients`` hold only the damping (a constant force has no linear
part). Without damping (and so when parked) the component is ``time_only``: a generator
evaluates it once on its time grid and keeps its linear solver.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.dofs import RIGID_DOFS, check_dofs, index
from hybridwsi.errors import InputError
from hybridwsi.forces.base import KnownComponent, kinematic

#: rotor states of a case's ``[rotor]`` table
STATES = ("parked", "thrust")


def _finite(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"rotor: {name} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise InputError(f"rotor: {name} must be finite, got {value!r}")
    return v


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


def rotor_from_case(case: Mapping[str, Any], dofs: Sequence[str] | str | None = None
                    ) -> RotorThrust:
    """The rotor of a case's optional ``[rotor]`` table (absent: parked).

    ``[rotor]``: ``state`` (``"parked"`` or ``"thrust"``), ``hub`` [m] (x, y, z), ``thrust``
    [N], ``aero_damping`` [N/(m/s)]; ``dofs`` default the case's ``default_dofs``.
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
    try:
        return RotorThrust(table["thrust"], table.get("aero_damping", 0.0), table["hub"], dofs,
                           reference_point=ref)
    except KeyError as exc:
        raise InputError(f"rotor: state 'thrust' needs {exc} in [rotor]") from None
