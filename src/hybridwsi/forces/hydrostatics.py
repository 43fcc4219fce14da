"""Exact (nonlinear) hydrostatic restoring force through the body interface.

``ExactHydrostatic(body, dofs)`` is the net hydrostatic + gravity generalised force of a body
displaced by ``q`` (N on translations, N m on rotations). The DOFs the body's geometry can do
exactly (``body.exact_restoring_dofs``; a body with only ``buoyancy_force(z)``, like the
sphere of the paper, does Heave) take ``body.restoring_force(q_E, E)`` evaluated at their own
displacements; the other DOFs, and the couplings between the two groups, stay linear with the
stiffness matrix C:

    F_E = F_exact(q_E) − C_EL q_L,        F_L = −C_LE q_E − C_LL q_L

(E: exact DOFs, L: linear ones). With every DOF exact this is the body's exact force; with
small displacements it tends to ``−C q`` (the linearisation, :meth:`linear_coefficients`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.dofs import check_dofs
from hybridwsi.errors import InputError
from hybridwsi.forces.base import KnownComponent, as_matrix, kinematic


def exact_dofs(body: Any, dofs: Sequence[str]) -> list[str]:
    """The DOFs of ``dofs`` (in their order) whose restoring force ``body`` computes exactly."""
    if hasattr(body, "restoring_force") and hasattr(body, "exact_restoring_dofs"):
        can = set(check_dofs(body.exact_restoring_dofs))
    elif hasattr(body, "buoyancy_force"):  # bodies before the restoring_force interface
        can = {"Heave"}
    else:
        raise InputError("an exact hydrostatic force needs a body with restoring_force(q, dofs) "
                         "and exact_restoring_dofs (or buoyancy_force(z) for heave), e.g. "
                         "hybridwsi.bodies.FloatingSphere")
    return [d for d in dofs if d in can]


class ExactHydrostatic(KnownComponent):
    """Exact hydrostatic restoring force of ``body`` on ``dofs`` (see module doc).

    Parameters
    ----------
    body : Body
        A body with ``restoring_force(q, dofs)`` and ``exact_restoring_dofs`` (or, for heave
        only, ``buoyancy_force(z)``), and ``hydrostatic_stiffness(dofs)``.
    dofs : sequence of str
        The DOFs of the run, in its order.
    stiffness : float or ndarray, optional
        Linear stiffness C (n, n) [N/m, N/rad, N m/m, N m/rad per pair] for the DOFs that are
        not exact and for the couplings; default ``body.hydrostatic_stiffness(dofs)``.
        ``cummins.simulate`` passes the coefficients' C so that the linear part is the same
        as in its linear runs.

    Raises
    ------
    InputError
        When the body can do none of ``dofs`` exactly.
    """

    name = "exact_hydrostatic"

    def __init__(self, body: Any, dofs: Sequence[str],
                 stiffness: float | np.ndarray | None = None) -> None:
        self.body = body
        self.dofs = list(check_dofs(dofs))
        self.exact = exact_dofs(body, self.dofs)
        if not self.exact:
            raise InputError(f"the body computes no exact restoring force for DOFs {self.dofs}")
        n = len(self.dofs)
        c = body.hydrostatic_stiffness(self.dofs) if stiffness is None else stiffness
        self.stiffness = as_matrix(c, n, "hydrostatic stiffness")
        self._ie = [self.dofs.index(d) for d in self.exact]
        self._il = [i for i in range(n) if i not in self._ie]

    def _exact(self, q: np.ndarray) -> np.ndarray:
        """Exact force on the exact DOFs at their displacements ``q`` (len(exact),)."""
        if hasattr(self.body, "restoring_force") and hasattr(self.body, "exact_restoring_dofs"):
            out = np.asarray(self.body.restoring_force(q, self.exact), dtype=float).reshape(-1)
        else:
            out = np.array([float(self.body.buoyancy_force(float(q[0])))])
        if out.size != len(self.exact):
            raise InputError(f"body.restoring_force returned {out.size} values for "
                             f"{len(self.exact)} DOF")
        return out

    def restoring(self, z: np.ndarray) -> np.ndarray:
        """Generalised restoring force [N, N m] at displacement ``z`` (n,) [m, rad]."""
        ie, il = self._ie, self._il
        if not il:  # every DOF exact: the body's force alone (no linear remainder to add)
            return self._exact(z[ie])
        f = -self.stiffness @ z
        f[ie] = self._exact(z[ie]) - self.stiffness[np.ix_(ie, il)] @ z[il]
        return f

    def force(self, hist: xr.Dataset) -> np.ndarray:
        z = kinematic(hist, "z")
        if z.shape[1] != len(self.dofs):
            raise InputError(f"exact hydrostatics is for DOFs {self.dofs}; the history has "
                             f"{z.shape[1]} DOF")
        return np.stack([self.restoring(zk) for zk in z])

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        zero = np.zeros((n_dof, n_dof))
        return zero, zero.copy(), as_matrix(self.stiffness, n_dof, "hydrostatic stiffness")

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        return self.restoring(z)

    def describe(self) -> str:
        linear = [d for d in self.dofs if d not in self.exact]
        return (f"{self.name}(exact {','.join(self.exact)}"
                + (f"; linear {','.join(linear)})" if linear else ")"))
