"""Forces that depend on time only: a constant force and a prescribed time series.

Both set ``time_only = True``: a generator (``hybridwsi.cummins.simulate``) evaluates them once
on its time grid through :meth:`~hybridwsi.forces.KnownComponent.time_force` and keeps its
linear solver. In the diagnostic they have no stiffness, damping or inertia (zero
``linear_coefficients``): they drive the body, they do not change its dynamics.

Units per DOF: N on translations, N m on rotations (:func:`hybridwsi.dofs.force_unit`).
"""

from __future__ import annotations

import hashlib

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.forces.base import KnownComponent


def _zero_coefficients(n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    z = np.zeros((n_dof, n_dof))
    return z, z.copy(), z.copy()


def _hist_dofs(hist: xr.Dataset) -> int:
    if "dof" not in hist.sizes or "time" not in hist.sizes:
        raise InputError("history has no (time, dof) dimensions")
    return int(hist.sizes["dof"])


def _columns(values: np.ndarray, n_dof: int | None, what: str) -> np.ndarray:
    """``values`` (nt, k) checked to have one column per DOF of the run (``n_dof``)."""
    if n_dof is None or values.shape[1] == n_dof:
        return values
    raise InputError(f"{what} has {values.shape[1]} DOF column(s); the run has {n_dof} DOF")


class ConstantForce(KnownComponent):
    """A force constant in time, ``F = value`` [N or N m per DOF].

    Parameters
    ----------
    value : float or sequence of float
        One value per DOF, in the run's DOF order (N for translations, N m for rotations). A
        scalar is allowed for a 1-DOF run only (a scalar N and N m at once is ambiguous).
    """

    name = "constant"
    time_only = True

    def __init__(self, value: float | np.ndarray) -> None:
        arr = np.asarray(value, dtype=float)
        if arr.ndim > 1 or arr.size == 0:
            raise InputError(f"ConstantForce value must be a scalar or a vector, got shape "
                             f"{arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise InputError("ConstantForce value must be finite")
        self.value = arr.reshape(-1)

    def _vector(self, n_dof: int) -> np.ndarray:
        if self.value.size == n_dof:
            return self.value
        raise InputError(f"ConstantForce has {self.value.size} value(s); the run has "
                         f"{n_dof} DOF (give one value per DOF)")

    def force(self, hist: xr.Dataset) -> np.ndarray:
        return np.broadcast_to(self._vector(_hist_dofs(hist)),
                               (hist.sizes["time"], hist.sizes["dof"])).copy()

    def time_force(self, t: np.ndarray, n_dof: int | None = None) -> np.ndarray:
        vec = self.value if n_dof is None else self._vector(n_dof)
        return np.broadcast_to(vec, (np.size(t), vec.size)).copy()

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return _zero_coefficients(n_dof)

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        return self._vector(z.size).copy()

    def describe(self) -> str:
        return f"{self.name}={np.array2string(self.value, precision=6)}"


class PrescribedForce(KnownComponent):
    """A known force given as a time series [N or N m per DOF].

    Two sources, one class:

    - ``PrescribedForce("F_exc")`` reads the history variable ``F_exc`` (e.g. the BEM wave
      excitation a Cummins history carries); ``force(hist)`` returns ``hist[variable]``. It
      has no series of its own, so a generator cannot integrate it (:meth:`time_force` and
      :meth:`ode_force` raise); the hybrid rollout reads it from each case history.
    - :meth:`from_series` holds explicit samples ``(time, values)``, linearly interpolated at
      any time inside the sampled interval (outside it: ``InputError``, no extrapolation).
    """

    name = "prescribed"
    time_only = True

    def __init__(self, variable: str = "F_exc") -> None:
        self.variable = variable
        self._time: np.ndarray | None = None
        self._values: np.ndarray | None = None

    @classmethod
    def from_series(cls, time: np.ndarray, values: np.ndarray, *,
                    name: str = "external") -> PrescribedForce:
        """A force from samples: ``time`` (ns,) [s] strictly increasing, ``values`` (ns,) for one
        DOF or (ns, n_dof) [N or N m per DOF]; ``name`` labels it (``describe``)."""
        ts = np.asarray(time, dtype=float)
        vs = np.asarray(values, dtype=float)
        if ts.ndim != 1 or ts.size < 2 or not np.all(np.isfinite(ts)) \
                or np.any(np.diff(ts) <= 0):
            raise InputError("prescribed force time must be finite and strictly increasing "
                             "with >= 2 samples")
        if vs.ndim not in (1, 2) or vs.shape[0] != ts.size:
            raise InputError(f"prescribed force has {ts.size} time samples but values of "
                             f"shape {vs.shape} (need {ts.size} samples per DOF)")
        if not np.all(np.isfinite(vs)):
            raise InputError("prescribed force values contain NaN/inf")
        obj = cls(name)
        obj._time, obj._values = ts, vs.reshape(ts.size, -1)
        return obj

    @property
    def has_series(self) -> bool:
        """True when built from samples (:meth:`from_series`)."""
        return self._time is not None

    def _interp(self, t: np.ndarray) -> np.ndarray:
        """The samples at ``t`` [s], shape (nt, n_col), with the range check."""
        ts, vs = self._time, self._values
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if ts[0] > t.min() + 1e-9 or ts[-1] < t.max() - 1e-9:
            raise InputError(f"prescribed force '{self.variable}' covers {ts[0]:g}–{ts[-1]:g} s "
                             f"but {t.min():g}–{t.max():g} s are needed")
        return np.stack([np.interp(t, ts, vs[:, i]) for i in range(vs.shape[1])], axis=1)

    def _no_series(self) -> InputError:
        return InputError(f"prescribed force '{self.variable}' is a time series; the solver "
                          "must read it from the history (hybrid rollout does)")

    def force(self, hist: xr.Dataset) -> np.ndarray:
        if self.has_series:
            vals = self._interp(np.asarray(hist["time"].values, dtype=float))
            return _columns(vals, _hist_dofs(hist), f"prescribed force '{self.variable}'")
        if self.variable not in hist:
            raise InputError(f"history has no '{self.variable}' for the prescribed force")
        return np.asarray(hist[self.variable].values, dtype=float)

    def time_force(self, t: np.ndarray, n_dof: int | None = None) -> np.ndarray:
        if not self.has_series:
            raise self._no_series()
        return _columns(self._interp(t), n_dof, f"prescribed force '{self.variable}'")

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return _zero_coefficients(n_dof)

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        if not self.has_series:
            raise self._no_series()
        return _columns(self._interp(t), z.size, f"prescribed force '{self.variable}'")[0]

    def describe(self) -> str:
        if not self.has_series:
            return f"prescribed({self.variable})"
        digest = hashlib.sha1(np.ascontiguousarray(
            np.column_stack([self._time, self._values])).tobytes()).hexdigest()[:12]
        return (f"prescribed({self.variable}: {self._time.size} samples "
                f"{self._time[0]:g}–{self._time[-1]:g} s, sha1 {digest})")
