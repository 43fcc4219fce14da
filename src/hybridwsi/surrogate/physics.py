"""The known force components of a hybrid rollout, evaluated for a batch of cases.

:class:`BatchedPhysics` holds the partition's known components (docs/THEORY.md §1) with their
linear part ``−B_k ż − C_k z`` and acceleration part ``A_k`` folded into matrices, the
quadratic damping and radiation memory vectorised over cases, and any other component
(nonlinear, with internal states, or stepped with ``begin_step``) evaluated case by case. The
coupled integrators (:mod:`hybridwsi.surrogate.coupled`) and the stability prediction of the
rollout (:func:`hybridwsi.surrogate.rollout.check_stability`) use it.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.forces import (
    AddedMass,
    Hydrostatic,
    KnownComponent,
    LinearDamping,
    QuadraticDamping,
    as_matrix,
    summed_linear_coefficients,
)
from hybridwsi.history import time_step


class BatchedPhysics:
    """Known components evaluated for a batch of cases, states ``(n_cases, n)`` arrays.

    Linear terms, quadratic damping and radiation memory are vectorised; any other
    component falls back to a loop over cases through its ``ode_force``/``state_derivative``.
    A component stepped by the integrator (``begin_step``, e.g. a coupled mooring code) holds
    one state of its own, so it is evaluated for one case only (:meth:`begin_step`).

    Parameters
    ----------
    mass : float or ndarray
        Rigid-body mass [kg, kg m, kg m²] (scalar, diagonal or (n_dof, n_dof)).
    known : sequence of KnownComponent
        The partition's known components.
    n_dof : int
    """

    def __init__(self, mass: float | np.ndarray, known: Sequence[KnownComponent],
                 n_dof: int) -> None:
        self.n_dof = n_dof
        self.known = list(known)
        a_k, _, _ = summed_linear_coefficients(self.known, n_dof)
        self.mass = as_matrix(mass, n_dof, "mass")
        self.m_eff = self.mass + a_k
        try:
            self.m_inv = np.linalg.inv(self.m_eff)
        except np.linalg.LinAlgError:
            raise InputError("m + A_k is singular; check the mass and added mass") from None
        self.b_lin = np.zeros((n_dof, n_dof))
        self.c_lin = np.zeros((n_dof, n_dof))
        self.quad = np.zeros(n_dof)
        self.ss: list[tuple[slice, np.ndarray, np.ndarray, np.ndarray]] = []
        self.other: list[tuple[slice, KnownComponent]] = []
        n = 0
        for comp in self.known:
            if comp.time_only:
                continue  # a time series: added by the rollout as a prescribed force
            if isinstance(comp, (Hydrostatic, LinearDamping, AddedMass)):
                _, b, c = comp.linear_coefficients(n_dof)
                self.b_lin += b
                self.c_lin += c
            elif type(comp) is QuadraticDamping:
                self.quad += np.diag(as_matrix(comp.value, n_dof, comp.name))
            elif hasattr(comp, "ss") and comp.n_states:  # forces.RadiationMemory
                sl = slice(n, n + comp.n_states)
                self.ss.append((sl, comp.ss.A, comp.ss.B, comp.ss.C))
                n += comp.n_states
            else:
                self.other.append((slice(n, n + comp.n_states), comp))
                n += comp.n_states
        self.n_states = n
        self.stepped = [comp for _, comp in self.other if comp.stepped]
        self._quad = bool(np.any(self.quad))
        self.other_states = any(comp.n_states for _, comp in self.other)
        self._trap: dict[float, list] = {}

    def ss_trapezoid(self, dt: float) -> list:
        """Per state-space block ``(slice, (I - dt/2 A)^-1, I + dt/2 A, B)`` (cached per dt)."""
        if dt not in self._trap:
            blocks = []
            for sl, a, b, _ in self.ss:
                eye = np.eye(a.shape[0])
                blocks.append((sl, np.linalg.inv(eye - 0.5 * dt * a), eye + 0.5 * dt * a, b))
            self._trap[dt] = blocks
        return self._trap[dt]

    @property
    def has_remainder(self) -> bool:
        """Whether any known force is not linear ``-B_k v - C_k z`` (quadratic damping,
        memory states, other components)."""
        return bool(self._quad or self.ss or self.other)

    @functools.cached_property
    def compiled_forces(self) -> list | None:
        """The Numba kernels (:class:`hybridwsi.forces._compiled.CompiledForce`) of the
        :attr:`other` components, in their order, for the compiled rollout loop; None when
        one has none (internal states, ``begin_step``, no kernel, no Numba). Built once."""
        forces = [None if comp.n_states or comp.stepped else comp.compiled_force(self.n_dof)
                  for _, comp in self.other]
        return forces if all(f is not None for f in forces) else None

    def _add_remainder(self, f: np.ndarray, t: float, z: np.ndarray, v: np.ndarray,
                       x: np.ndarray, other: bool = True) -> np.ndarray:
        """``f`` plus the known forces beyond the linear part [N], (n_cases, n_dof) (without
        the :attr:`other` components when ``other`` is False)."""
        if self._quad:  # an all-zero coefficient adds exactly nothing
            f = f - self.quad * np.abs(v) * v
        for sl, _, _, c in self.ss:
            f -= np.dot(x[:, sl], c.T)
        for sl, comp in self.other if other else ():
            f += np.stack([comp.ode_force(t, z[i], v[i], x[i, sl]) for i in range(len(z))])
        return f

    def force(self, t: float, z: np.ndarray, v: np.ndarray, x: np.ndarray, *,
              other: bool = True) -> np.ndarray:
        """Known force without its acceleration part [N], (n_cases, n_dof) (``other`` False:
        without the :attr:`other` components).

        Row-wise: with no ``other`` components (``t`` unused) the rows may stack any batch of
        states, e.g. all time steps of a trajectory at once.
        """
        # np.dot, not @: on tall (rows, n_dof) operands ``@`` runs a non-BLAS loop, ~15x
        # slower for one dof (the whole trajectory goes through here after a rollout)
        return self._add_remainder(-np.dot(v, self.b_lin.T) - np.dot(z, self.c_lin.T), t, z, v,
                                   x, other)

    def explicit_force(self, t: float, z: np.ndarray, v: np.ndarray, x: np.ndarray) -> np.ndarray:
        """The known force minus its linear ``-B_k v - C_k z`` part [N] (treated explicitly),
        computed directly (zero when :attr:`has_remainder` is False)."""
        return self._add_remainder(np.zeros(np.shape(z)), t, z, v, x)

    def begin_step(self, t: float, z: np.ndarray, v: np.ndarray, dt: float) -> None:
        """``begin_step`` of the stepped components at the start of a step at ``t`` [s] on
        the start-of-step state (one case: ``z, v`` of shape (1, n_dof))."""
        if len(z) != 1:
            raise InputError(f"{', '.join(c.describe() for c in self.stepped)} "
                             "(begin_step) holds one state of its own: roll out one case at a "
                             "time")
        for comp in self.stepped:
            comp.begin_step(t, z[0].copy(), v[0].copy(), dt)

    def state_derivative(self, t: float, z: np.ndarray, v: np.ndarray, x: np.ndarray) -> np.ndarray:
        dx = np.zeros_like(x)
        for sl, a, b, _ in self.ss:
            dx[:, sl] = x[:, sl] @ a.T + v @ b.T
        for sl, comp in self.other:
            if comp.n_states:
                dx[:, sl] = np.stack([comp.state_derivative(t, z[i], v[i], x[i, sl])
                                      for i in range(len(z))])
        return dx

    def linearised(self) -> BatchedPhysics:
        """The same physics with nonlinear memoryless components replaced by their
        ``linear_coefficients`` (used for the stability prediction)."""
        known = []
        for comp in self.known:
            if comp.time_only:
                continue
            if isinstance(comp, (Hydrostatic, LinearDamping, AddedMass)) or (
                    hasattr(comp, "ss") and comp.n_states):
                known.append(comp)
            else:
                _, b, c = comp.linear_coefficients(self.n_dof)
                known += [LinearDamping(b), Hydrostatic(c)]
        return BatchedPhysics(self.m_eff - summed_linear_coefficients(known, self.n_dof)[0],
                              known, self.n_dof)


def initial_states(phys: BatchedPhysics, hs: Sequence[xr.Dataset], k0: int) -> np.ndarray:
    """Internal states (n_cases, n_states) at sample ``k0`` of the case histories ``hs``:
    the state ODE integrated along the reference ż (Heun)."""
    x = np.zeros((len(hs), phys.n_states))
    if k0 == 0:
        return x
    dt = time_step(hs[0])
    z = np.stack([np.asarray(h["z"].values, float) for h in hs])
    v = np.stack([np.asarray(h["zdot"].values, float) for h in hs])
    t = np.asarray(hs[0]["time"].values, float)
    for k in range(k0):  # Heun: only a short warm-up window
        g0 = phys.state_derivative(t[k], z[:, k], v[:, k], x)
        xp = x + dt * g0
        x = x + 0.5 * dt * (g0 + phys.state_derivative(t[k + 1], z[:, k + 1], v[:, k + 1], xp))
    return x
