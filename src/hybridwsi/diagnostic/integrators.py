"""One-step integrators of the loosely coupled (lagged) hybrid solver.

This is the single definition of the time stepping used both by the hybrid rollout
(``hybridwsi.surrogate``) and by the stability analysis (:mod:`hybridwsi.diagnostic.stability`,
setting c), which builds its amplification matrix by calling :func:`lagged_step` on unit
states — so the analysed map is exactly the map that is run.

Equation of motion (n DOF)::

    M z̈ = −B ż − C z + F_x(t, z, ż, z̈_lag)

``M = m + A_k`` [kg], ``B = B_k`` [N s/m], ``C = C_k`` [N/m] are the linear known part (matrices
n×n), and ``F_x`` [N] is everything evaluated *explicitly, once per step, on the start-of-step
kinematics*: the surrogate force (which therefore sees lagged kinematics), external/wave
excitation, and any nonlinear remainder of the known components.

Signature (both schemes)::

    z1, zdot1, zddot1 = lagged_step(scheme, t, dt, z, zdot, zddot, M, B, C, explicit_force)

with ``z, zdot, zddot`` arrays of shape (n,) and ``explicit_force(t, z, zdot, zddot) -> (n,)``.

``"semi_implicit_euler"`` (symplectic Euler). Carried state ``[z_n, ż_n, a_{n−1}]`` where
``a_{n−1}`` is the acceleration computed in the previous step::

    F  = F_x(t_n, z_n, ż_n, a_{n−1})
    a_n = M⁻¹ (F − B ż_n − C z_n)
    ż_{n+1} = ż_n + Δt a_n ;  z_{n+1} = z_n + Δt ż_{n+1}
    returns (z_{n+1}, ż_{n+1}, a_n)

``"newmark"`` (average acceleration, β_N = 1/4, γ_N = 1/2; the linear known part implicit).
Carried state ``[z_n, ż_n, a_n]``::

    F  = F_x(t_n, z_n, ż_n, a_n)
    (M + γ_N Δt B + β_N Δt² C) a_{n+1} = F − B (ż_n + (1−γ_N) Δt a_n)
                                           − C (z_n + Δt ż_n + (½−β_N) Δt² a_n)
    ż_{n+1} = ż_n + Δt ((1−γ_N) a_n + γ_N a_{n+1})
    z_{n+1} = z_n + Δt ż_n + Δt² ((½−β_N) a_n + β_N a_{n+1})
    returns (z_{n+1}, ż_{n+1}, a_{n+1})

:class:`LaggedIntegrator` is the same step with the scheme, Δt and matrices fixed (the implicit
solve factorised once); :func:`lagged_step` is implemented with it, so a rollout stepping a
``LaggedIntegrator`` runs exactly the map whose amplification matrix is analysed.

A surrogate linearised as ``F_x ≈ α_s z̈ + β_s ż + γ_s z`` gives ``a ← (α_s/M) a + …`` from one
step to the next: for ``|α_s|/M ≥ 1`` the lagged coupling is unstable at every Δt (the
added-mass instability of partitioned fluid–structure solvers).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from hybridwsi.errors import InputError

SCHEMES = ("semi_implicit_euler", "newmark")
NEWMARK_BETA = 0.25
NEWMARK_GAMMA = 0.5

ExplicitForce = Callable[[float, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def check_scheme(scheme: str) -> str:
    """Return ``scheme`` or raise InputError naming the valid ones."""
    if scheme not in SCHEMES:
        raise InputError(f"unknown scheme '{scheme}' (choose from {', '.join(SCHEMES)})")
    return scheme


class LaggedIntegrator:
    """:func:`lagged_step` with the scheme, ``dt`` and the matrices fixed: the solve of the
    implicit linear part is factorised once (``M⁻¹`` or ``(M + γ_N Δt B + β_N Δt² C)⁻¹``) and
    the step coefficients precomputed, so a long rollout pays only a few small products per
    step. :func:`lagged_step` is this class applied once, so both run the same arithmetic.

    Parameters
    ----------
    scheme : {"semi_implicit_euler", "newmark"}
    dt : float
        Step [s].
    mass, damping, stiffness : ndarray, shape (n, n)
        ``M = m + A_k`` [kg], ``B_k`` [N s/m], ``C_k`` [N/m].
    """

    def __init__(self, scheme: str, dt: float, mass: np.ndarray, damping: np.ndarray,
                 stiffness: np.ndarray) -> None:
        self.scheme, self.dt = check_scheme(scheme), dt
        self.damping, self.stiffness = damping, stiffness
        # zero matrices contribute exactly nothing: skip their products
        self._use_b, self._use_c = bool(np.any(damping)), bool(np.any(stiffness))
        if scheme == "newmark":
            bn, gn = NEWMARK_BETA, NEWMARK_GAMMA
            lhs = mass + gn * dt * damping + bn * dt**2 * stiffness
            self._c_v, self._c_z = (1.0 - gn) * dt, (0.5 - bn) * dt**2
            self._c_z1, self._c_v1 = bn * dt**2, gn * dt
        else:
            lhs = mass
        self._lhs_inv = np.linalg.inv(lhs)

    def step(self, z: np.ndarray, zdot: np.ndarray, zddot: np.ndarray, f: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """New carried state from the carried state and the explicit force ``f`` [N].

        Arrays have shape (n,) or (n, n_cases) (columns are independent cases).
        """
        if self.scheme == "semi_implicit_euler":
            r = f
            if self._use_b:
                r = r - self.damping @ zdot
            if self._use_c:
                r = r - self.stiffness @ z
            acc = self._lhs_inv @ r
            v1 = zdot + self.dt * acc
            return z + self.dt * v1, v1, acc
        v_pred = zdot + self._c_v * zddot
        z_pred = z + self.dt * zdot + self._c_z * zddot
        r = f
        if self._use_b:
            r = r - self.damping @ v_pred
        if self._use_c:
            r = r - self.stiffness @ z_pred
        acc = self._lhs_inv @ r
        return z_pred + self._c_z1 * acc, v_pred + self._c_v1 * acc, acc


def lagged_step(
    scheme: str,
    t: float,
    dt: float,
    z: np.ndarray,
    zdot: np.ndarray,
    zddot: np.ndarray,
    mass: np.ndarray,
    damping: np.ndarray,
    stiffness: np.ndarray,
    explicit_force: ExplicitForce,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Advance the loosely coupled system by one step of ``dt`` [s] (see module docstring).

    Parameters
    ----------
    scheme : {"semi_implicit_euler", "newmark"}
    t : float
        Start time of the step [s].
    dt : float
        Step [s].
    z, zdot, zddot : ndarray, shape (n,)
        Carried state: displacement [m], velocity [m/s] and the last computed acceleration
        [m/s²] (``a_{n−1}`` for semi-implicit Euler, ``a_n`` for Newmark).
    mass, damping, stiffness : ndarray, shape (n, n)
        ``M = m + A_k`` [kg], ``B_k`` [N s/m], ``C_k`` [N/m].
    explicit_force : callable
        ``explicit_force(t, z, zdot, zddot) -> ndarray (n,)`` [N], evaluated once on the
        start-of-step state.

    Returns
    -------
    z, zdot, zddot : ndarray, shape (n,)
        The new carried state.

    Notes
    -----
    Equivalent to ``LaggedIntegrator(scheme, dt, mass, damping, stiffness).step(z, zdot,
    zddot, explicit_force(t, z, zdot, zddot))``; long runs should build the integrator once.
    """
    check_scheme(scheme)
    f = np.asarray(explicit_force(t, z, zdot, zddot), dtype=float)
    return LaggedIntegrator(scheme, dt, mass, damping, stiffness).step(z, zdot, zddot, f)
