"""Analytic and ODE-simulated reference motions shared by the diagnostic tests."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import scipy.integrate

from hybridwsi.forces import KnownComponent

# the paper's sphere (docs/THEORY.md §6)
M, A_INF, C_HS = 7.06, 3.50, 692.2


def multisine(
    t: np.ndarray,
    amps: Sequence[float],
    omegas: Sequence[float],
    phases: Sequence[float],
    offset: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """z, ż, z̈ of ``offset + Σ a sin(ω t + φ)`` (analytic derivatives)."""
    z = offset + sum(a * np.sin(w * t + p) for a, w, p in zip(amps, omegas, phases))
    zd = sum(a * w * np.cos(w * t + p) for a, w, p in zip(amps, omegas, phases))
    zdd = sum(-a * w**2 * np.sin(w * t + p) for a, w, p in zip(amps, omegas, phases))
    return z, zd, zdd


def forced_oscillator(
    t: np.ndarray, m: float, b: float, c: float, f_ext: Callable[[np.ndarray], np.ndarray],
    z0: float = 0.0, v0: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Solve ``m z̈ + b ż + c z = f_ext(t)`` tightly with solve_ivp; z̈ from the equation."""
    sol = scipy.integrate.solve_ivp(
        lambda ti, y: [y[1], (f_ext(ti) - b * y[1] - c * y[0]) / m],
        (t[0], t[-1]), [z0, v0], method="DOP853", t_eval=t, rtol=1e-12, atol=1e-14,
    )
    assert sol.success, sol.message
    z, zd = sol.y
    return z, zd, (f_ext(t) - b * zd - c * z) / m


class HeldSpring(KnownComponent):
    """A spring −k z evaluated once per step, at its start, and held over the step (the lagged
    coupling of a code stepped by the integrator, ``begin_step``); records its calls."""

    name = "held_spring"

    def __init__(self, k: float) -> None:
        self.k, self.calls, self.held = k, [], np.zeros(1)

    def begin_step(self, t, z, zdot, dt):
        self.calls.append((t, dt))
        self.held = -self.k * z

    def ode_force(self, t, z, zdot, x):
        return self.held.copy()

    def force(self, hist):
        return -self.k * hist["z"].values

    def linear_coefficients(self, n):
        return np.zeros((n, n)), np.zeros((n, n)), self.k * np.eye(n)
