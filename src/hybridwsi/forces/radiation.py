"""Radiation memory ``F = -∫K(t-τ) ż(τ) dτ`` as a force component with internal states.

The states are those of the radiation state-space realisation
(:class:`hybridwsi.hydro.statespace.RadiationSS`): ``ẋ = A_r x + B_r ż``, ``F = -C_r x``.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.forces.base import KnownComponent, kinematic
from hybridwsi.hydro.irf import radiation_irf
from hybridwsi.hydro.statespace import RadiationSS, fit_radiation_ss, simulate_states


class RadiationMemory(KnownComponent):
    """Radiation memory force ``F = −∫K(t−τ) ż(τ) dτ`` as internal states (see module doc).

    ``linear_coefficients`` returns zeros: the memory force has no instantaneous
    acceleration/velocity/position proportionality (its effect enters the ODE through the
    ``n_states`` internal states). Use :meth:`equivalent_damping` for the damping it amounts
    to at one frequency (``B(ω) = Re K̂(ω)``).
    """

    name = "radiation_memory"

    def __init__(self, ss: RadiationSS, dofs: Sequence[str] | None = None) -> None:
        self.ss = ss
        self.dofs = list(dofs) if dofs is not None else list(ss.radiating_dof)
        self.n_states = ss.order

    @classmethod
    def from_history(cls, hist: xr.Dataset) -> RadiationMemory | None:
        """The realisation a Cummins history carries (``attrs["radiation_ss"]``), or None."""
        if "radiation_ss" not in hist.attrs:
            return None
        return cls(RadiationSS.from_dict(json.loads(hist.attrs["radiation_ss"])))

    @classmethod
    def from_coefficients(cls, coeffs: xr.Dataset,
                          dofs: Sequence[str] | None = None) -> RadiationMemory:
        """A state-space fit of the radiation kernel of ``coeffs`` restricted to ``dofs``.

        The kernel is computed for all DOFs (:func:`hybridwsi.hydro.irf.radiation_irf`) and
        its ``dofs`` rows and columns are fitted: the other DOFs are held fixed, so they
        radiate nothing.
        """
        kernel = radiation_irf(coeffs)
        if dofs is not None:
            have = [str(d) for d in kernel["radiating_dof"].values]
            missing = [d for d in dofs if d not in have]
            if missing:
                raise InputError(f"radiation damping has no DOF {missing} (it has {have})")
            kernel = kernel.sel(radiating_dof=list(dofs), influenced_dof=list(dofs))
        return cls(fit_radiation_ss(kernel))

    def _check(self, dofs: Sequence[str]) -> None:
        if list(dofs) != self.ss.radiating_dof or list(dofs) != self.ss.influenced_dof:
            raise InputError(f"radiation memory is fitted for DOFs {self.ss.radiating_dof}, "
                             f"the history has {list(dofs)}")

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """Memory force [N] on the reference velocity (state space driven by sampled ż).

        The body is taken at rest before the first sample (zero initial states), and ż is
        interpolated linearly between samples (first-order hold, exact for that input).
        """
        self._check([str(d) for d in hist["dof"].values])
        v = kinematic(hist, "zdot")
        t = np.asarray(hist["time"].values, dtype=float)
        x = simulate_states(self.ss, v, float((t[-1] - t[0]) / (t.size - 1)))
        return -x @ self.ss.C.T

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        z = np.zeros((n_dof, n_dof))
        return z, z.copy(), z.copy()

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        return -self.ss.C @ x

    def state_derivative(self, t: float, z: np.ndarray, zdot: np.ndarray,
                         x: np.ndarray) -> np.ndarray:
        return self.ss.A @ x + self.ss.B @ zdot

    def equivalent_damping(self, omega: float) -> np.ndarray:
        """Damping matrix [N s/m] the memory force amounts to at frequency ``omega`` [rad/s]."""
        return self.ss.equivalent_damping(omega)

    def describe(self) -> str:
        return f"{self.name}(order={self.ss.order}, fit={json.dumps(self.ss.fit_error)})"
