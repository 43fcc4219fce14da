"""Forcing on the time grid: wave excitation and the forces that depend on time only.

A force component (:class:`hybridwsi.forces.KnownComponent`) with ``time_only = True``
(``ConstantForce``, ``PrescribedForce.from_series``…) is evaluated once on the grid and joins
the input of the linear solver; any other component depends on the motion and goes to the
stepping solver (:mod:`hybridwsi.cummins.solvers`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.forces import ExactHydrostatic, KnownComponent
from hybridwsi.waves import Wave, excitation_force, wave_from_dict


def time_grid(duration: float, dt: float) -> np.ndarray:
    """``0, dt, 2 dt, …`` up to ``duration`` [s] (rounded to a whole number of steps)."""
    for name, v in (("dt", dt), ("duration", duration)):
        if not isinstance(v, (int, float, np.floating, np.integer)) or not np.isfinite(v):
            raise InputError(f"{name} must be a finite number, got {v!r}")
    if dt <= 0:
        raise InputError(f"dt must be > 0, got {dt}")
    if duration < dt:
        raise InputError(f"duration ({duration} s) must be at least one time step dt ({dt} s)")
    n = int(round(duration / dt))
    return np.arange(n + 1) * dt


def as_wave(wave: Wave | Mapping | None) -> Wave | None:
    """A :mod:`hybridwsi.waves` wave from a wave or its dict (``Wave.to_dict``)."""
    if wave is None or isinstance(wave, Wave):
        return wave
    if isinstance(wave, Mapping):
        return wave_from_dict(dict(wave))
    raise InputError(f"wave must be a hybridwsi.waves wave or a dict, got {type(wave).__name__}")


def excitation(wave: Wave | None, coeffs: xr.Dataset, t: np.ndarray, dofs: list[str],
               ramp: float) -> tuple[np.ndarray, np.ndarray | None]:
    """F_exc (nt, n) [N, N m] and the incident elevation η (nt,) [m] (None without waves),
    both ramped over ``ramp`` [s]."""
    if wave is None:
        return np.zeros((t.size, len(dofs))), None
    return excitation_force(wave, coeffs, t, list(dofs), ramp=ramp, with_elevation=True)


def elevation_attrs(ramp: float) -> dict[str, Any]:
    """Attributes of a history's ``eta``: the elevation as applied, ramped like the excitation
    over ``ramp`` [s] (:func:`excitation`). ``ramp`` is recorded on the variable so that a
    reader knows not to ramp the excitation of this η again; an η without it (a measured
    record, or a history written before η was ramped) carries no ramp."""
    return {"units": "m", "long_name": "incident wave elevation, as applied (ramped like the "
                                       "excitation force)", "ramp": float(ramp)}


def split_components(forces: Sequence[KnownComponent] | None
                     ) -> tuple[list[KnownComponent], list[KnownComponent]]:
    """``(time_only, state_dependent)`` components, each checked to be a KnownComponent."""
    if forces is None:
        return [], []
    if isinstance(forces, KnownComponent):
        forces = [forces]
    comps = list(forces)
    bad = [type(c).__name__ for c in comps if not isinstance(c, KnownComponent)]
    if bad:
        raise InputError(f"forces must be hybridwsi.forces.KnownComponent objects (e.g. "
                         f"ConstantForce, PrescribedForce.from_series, LinearDamping); got "
                         f"{', '.join(bad)}")
    if any(isinstance(c, ExactHydrostatic) for c in comps):
        raise InputError("pass nonlinear_hydrostatics=True (with body=) instead of an "
                         "ExactHydrostatic force: it replaces −C z rather than adding to it")
    return [c for c in comps if c.time_only], [c for c in comps if not c.time_only]


def time_forcing(components: Sequence[KnownComponent], t: np.ndarray, n: int) -> np.ndarray:
    """Sum of the time-only components on ``t``, shape (nt, n) [N, N m]."""
    total = np.zeros((t.size, n))
    for comp in components:
        vals = np.asarray(comp.time_force(t, n), dtype=float)
        if vals.shape != total.shape:
            raise InputError(f"force '{comp.describe()}' gave shape {vals.shape}; expected "
                             f"{total.shape} (time, DOF)")
        if not np.all(np.isfinite(vals)):
            raise InputError(f"force '{comp.describe()}' is not finite")
        total += vals
    return total


def state_force(components: Sequence[KnownComponent], t: float, z: np.ndarray, v: np.ndarray,
                x: np.ndarray, offsets: Sequence[int]) -> np.ndarray:
    """Σ ``ode_force`` of the state-dependent components [N, N m]; ``x`` holds their internal
    states, component k's from ``offsets[k]`` on."""
    f = np.zeros(z.size)
    for comp, o in zip(components, offsets):
        val = np.asarray(comp.ode_force(t, z, v, x[o:o + comp.n_states]), dtype=float)
        if val.shape != (z.size,):
            raise InputError(f"force '{comp.describe()}' returned shape {val.shape}; "
                             f"expected ({z.size},)")
        f = f + val
    return f

