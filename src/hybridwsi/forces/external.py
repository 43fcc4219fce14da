"""Forces given as functions of time (placeholder: the full module comes with issue 12's
Cummins change; only the API the diagnostic and the surrogate use is here)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.forces.base import KnownComponent


class PrescribedForce(KnownComponent):
    """A known force [N, N m] given as a time series in the history (e.g. ``F_exc``).

    It has no state dependence, so ``linear_coefficients`` are zero; solvers add its series
    as a prescribed force (``time_only``).
    """

    name = "prescribed"
    time_only = True

    def __init__(self, variable: str = "F_exc") -> None:
        self.variable = variable

    def force(self, hist: xr.Dataset) -> np.ndarray:
        if self.variable not in hist:
            raise InputError(f"history has no '{self.variable}' for the prescribed force")
        return np.asarray(hist[self.variable].values, dtype=float)

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        z = np.zeros((n_dof, n_dof))
        return z, z.copy(), z.copy()

    def describe(self) -> str:
        return f"prescribed({self.variable})"
