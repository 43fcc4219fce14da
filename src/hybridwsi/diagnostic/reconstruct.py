"""Reconstruction of the reference motion with a prescribed black-box force (paper Eq. 4).

Integrates, from the reference ``z(t0)``, ``ż(t0)`` and the known components' internal states,

    (m + A_k − α) z̈ = Σ ode_force(known) + β ż + γ z + F_p(t)

where, by default, ``α = β = γ = 0`` and ``F_p = F_bb = F_force − Σ F_known(z_ref)`` (paper
Eq. 3–4). With ``move_identified=RegressionResult`` the identified ``α z̈ + β ż + γ z`` are
moved into the ODE and only the residual ``F_p = F_bb − (F̄ + α z̈_ref + β ż_ref + γ z_ref) + F̄``
is prescribed (docs/THEORY.md §4a), which restores the feedback that prescribing the whole force
removed.

``F_p(t)`` is interpolated between samples by a not-a-knot cubic spline
(:class:`scipy.interpolate.CubicSpline`); the ODE is solved by :func:`scipy.integrate.solve_ivp`
with the step capped at the sampling interval (so no force sample is stepped over).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.integrate
import scipy.interpolate
import xarray as xr

from hybridwsi.forces import (
    KnownComponent,
    as_matrix,
    black_box_force,
    summed_linear_coefficients,
)
from hybridwsi.forces.linear import mass_from
from hybridwsi.diagnostic.regression import RegressionResult, as_components, kinematics
from hybridwsi.cummins.result import SolverResult, failure, first_non_finite
from hybridwsi.diagnostic.stability import CoupledStep, StabilityReport, assess
from hybridwsi.errors import InputError
from hybridwsi.history import make_history, time_step, validate


@dataclass
class ReconstructionResult:
    """Reconstructed motion and its error against the reference.

    Attributes
    ----------
    history : xarray.Dataset or None
        TimeHistory (source ``"reconstruction"``) with z, ż, z̈ and the prescribed force
        ``F_prescribed`` [N]; None when the integration failed.
    error : ndarray, shape (n_time, n_dof), or None
        ``z − z_ref`` [m] (None when the integration failed).
    metrics : dict
        Per DOF: ``rms_error`` [m], ``max_error`` [m], ``nrms_error`` (RMS error / std of z_ref),
        ``final_drift`` [m] (error at the last sample); inf when the integration failed.
    stability : StabilityReport
        The ODE actually integrated (known part plus moved terms, the rest prescribed):
        its setting (a), ``stability.prescribed``, is the reconstruction's error dynamics.
    solution : SolverResult
        The integrator's result: ``success``, ``message``, ``nfev`` (right-hand-side
        evaluations), the solution (:mod:`hybridwsi.cummins.result`).
    """

    history: xr.Dataset | None
    error: np.ndarray | None
    metrics: dict[str, list[float]]
    stability: StabilityReport
    solution: SolverResult
    inputs: dict[str, Any] = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """The reconstruction reached the end of the reference."""
        return self.solution.success

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (metrics, stability, solver info; not the time series)."""
        return {
            "metrics": self.metrics,
            "stability": self.stability.prescribed.to_dict(),
            "solver_message": self.solution.message,
            "n_rhs_evals": self.solution.nfev,
            "inputs": self.inputs,
        }


class _UniformSpline:
    """Fast scalar-time evaluation of a not-a-knot cubic spline on a uniform grid.

    Same values as :class:`scipy.interpolate.CubicSpline` (its coefficients are reused); the
    interval is found by division instead of a search, which matters inside ``solve_ivp``.
    """

    def __init__(self, t: np.ndarray, values: np.ndarray) -> None:
        cs = scipy.interpolate.CubicSpline(t, values, axis=0)
        self.t0, self.dt, self.last = float(t[0]), float((t[-1] - t[0]) / (t.size - 1)), t.size - 2
        self.x = cs.x
        self.c = np.ascontiguousarray(np.moveaxis(cs.c, 1, 0))  # (interval, 4, n_dof)

    def __call__(self, ti: float) -> np.ndarray:
        i = min(max(int((ti - self.t0) / self.dt), 0), self.last)
        # guard against rounding at the interval edges of a slightly non-uniform grid
        if ti < self.x[i] and i > 0:
            i -= 1
        elif ti >= self.x[i + 1] and i < self.last:
            i += 1
        h = ti - self.x[i]
        c = self.c[i]
        return ((c[0] * h + c[1]) * h + c[2]) * h + c[3]


def _is_plain_linear(comp: KnownComponent) -> bool:
    """True for a memoryless component whose ODE force is the default ``−B ż − C z``."""
    return comp.n_states == 0 and type(comp).ode_force is KnownComponent.ode_force


def _moved_terms(
    result: RegressionResult | None, n_dof: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if result is None:
        return tuple(np.zeros((n_dof, n_dof)) for _ in range(3))  # type: ignore[return-value]
    if not isinstance(result, RegressionResult):
        raise InputError("move_identified must be a RegressionResult (from diagnostic.regress)")
    if result.alpha.shape != (n_dof, n_dof):
        raise InputError(
            f"move_identified has {result.alpha.shape[0]} DOF but the history has {n_dof}"
        )
    return result.alpha, result.beta, result.gamma


def _error_metrics(err: np.ndarray, z_ref: np.ndarray) -> dict[str, list[float]]:
    std = z_ref.std(axis=0)
    rms = np.sqrt((err**2).mean(axis=0))
    return {
        "rms_error": rms.tolist(),
        "max_error": np.abs(err).max(axis=0).tolist(),
        "nrms_error": np.where(std > 0, rms / np.where(std > 0, std, 1.0), np.inf).tolist(),
        "final_drift": err[-1].tolist(),
    }


def reconstruct(
    hist: xr.Dataset,
    force: str = "F_tot",
    known: Iterable[KnownComponent | str] = (),
    *,
    mass: float | np.ndarray | None = None,
    move_identified: RegressionResult | None = None,
    method: str = "RK45",
    rtol: float = 1e-9,
    atol: float = 1e-12,
    max_step: float | None = None,
) -> ReconstructionResult:
    """Integrate paper Eq. 4 with the black-box force prescribed and compare with the reference.

    Parameters
    ----------
    hist : xarray.Dataset
        Reference TimeHistory with z, ż (and z̈ when an added mass is known or terms are moved).
    force : str
        Total force variable [N].
    known : iterable of KnownComponent or "NAME=VALUE"
        Components integrated as physics (their ``ode_force``/internal states, ``A_k`` on the
        left-hand side) and removed from the prescribed force; components of time only
        (``time_only``, e.g. a prescribed excitation) stay in the prescribed force.
    mass : float or ndarray, optional
        Rigid-body mass m [kg]; default ``hist["mass"]``.
    move_identified : RegressionResult, optional
        Move its ``α z̈ + β ż + γ z`` into the ODE and prescribe only the residual.
    method, rtol, atol : str, float, float
        :func:`scipy.integrate.solve_ivp` method and tolerances (atol in m, m/s). The step is
        bounded by the sampling interval (``max_step``), where RK45 already meets the
        tolerance: it takes the same steps as DOP853 with 6 instead of 15 evaluations each
        (Fig. 2 of ``reproduce --quick``: errors equal to 1e-11 m, 2.4x fewer evaluations).
    max_step : float, optional
        Largest solver step [s]; default the sampling interval.

    Returns
    -------
    ReconstructionResult
        A failed integration (``solve_ivp`` gave up, the state became non-finite) is returned
        with ``success`` False and the reason in ``solution.message``, not raised.

    Raises
    ------
    InputError
        Missing mass or kinematics, mismatched DOF, singular ``m + A_k − α``, a component
        stepped by fixed-step integrators (``begin_step``).
    """
    validate(hist)
    given = as_components(known)
    # a force of time only (e.g. the excitation) is the same inside or outside the prescribed
    # force: it stays in F_p instead of being subtracted and integrated back
    comps = [c for c in given if not c.time_only]
    stepped = [c.describe() for c in comps if c.stepped]
    if stepped:
        raise InputError(f"the reconstruction's adaptive integrator cannot step "
                         f"{', '.join(stepped)} (begin_step): use its linearisation as known")
    m = _mass(hist, mass)
    alpha, beta, gamma = _moved_terms(move_identified, hist.sizes["dof"])
    f_p = _prescribed_force(hist, force, comps, move_identified, (alpha, beta, gamma))
    ode = PrescribedODE(m, comps, alpha, beta, gamma)
    t = np.asarray(hist["time"].values, dtype=float)
    z_ref, zd_ref = kinematics(hist, ("z", "zdot"))
    step = time_step(hist) if max_step is None else float(max_step)
    sol = solve_prescribed(ode, f_p, z_ref[0], zd_ref[0], step, t=t, method=method, rtol=rtol,
                           atol=atol, x0=ode.initial_states(hist))
    inputs = _inputs(hist, force, given, None if move_identified is None else
                     (alpha, beta, gamma), method=method, rtol=rtol, atol=atol, max_step=step)
    stab = assess(CoupledStep(m, ode.a_k - alpha, ode.b_k - beta, ode.c_k - gamma))
    if not sol.success:
        inf = [math.inf] * z_ref.shape[1]
        metrics = {"rms_error": inf, "max_error": inf, "nrms_error": inf, "final_drift": inf}
        return ReconstructionResult(None, None, metrics, stab, sol, inputs)
    err = sol.z - z_ref
    out = make_history(
        t, sol.z, sol.v, sol.a, forces={"F_prescribed": f_p},
        dof=[str(d) for d in hist["dof"].values], mass=m, source="reconstruction",
        inputs=inputs,
    )
    return ReconstructionResult(out, err, _error_metrics(err, z_ref), stab, sol, inputs)


def _inputs(hist: xr.Dataset, force: str, given: list[KnownComponent],
            moved: tuple[np.ndarray, np.ndarray, np.ndarray] | None, **solver: Any
            ) -> dict[str, Any]:
    """The reconstruction's inputs as recorded in its history (and the reference's)."""
    return {
        "force": force,
        "known": [c.describe() for c in given],
        "moved_identified": None if moved is None else {
            k: v.tolist() for k, v in zip(("alpha", "beta", "gamma"), moved)},
        **solver,
        "interpolation": "cubic spline (not-a-knot)",
        "reference": {"source": hist.attrs.get("source", ""),
                      "inputs": hist.attrs.get("inputs", "{}")},
    }


def _mass(hist: xr.Dataset, mass: float | np.ndarray | None) -> np.ndarray:
    """The rigid-body mass matrix [kg, kg m, kg m²]: given, or the history's."""
    m = mass_from(hist, None) if mass is None else as_matrix(mass, hist.sizes["dof"], "mass")
    if m is None:
        raise InputError("no mass given: pass mass=... or store 'mass' in the history")
    if not np.all(np.isfinite(m)):
        raise InputError("mass must be finite")
    return m


def _prescribed_force(hist: xr.Dataset, force: str, comps: list[KnownComponent],
                      moving: RegressionResult | None,
                      moved: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """``F_p`` (n_time, n_dof) [N, N m]: F_bb, less the moved ``α z̈ + β ż + γ z`` of the
    reference (the mean stays prescribed)."""
    f_p = black_box_force(hist, force, comps)
    if moving is not None:
        alpha, beta, gamma = moved
        z_ref, zd_ref, zdd_ref = kinematics(hist, ("z", "zdot", "zddot"))
        f_p = f_p - zdd_ref @ alpha.T - zd_ref @ beta.T - z_ref @ gamma.T
    return f_p


class PrescribedODE:
    """``(m + A_k − α) z̈ = Σ ode_force(known) + β ż + γ z + F_p(t)`` and its internal states.

    Memoryless components with the default (linear) ``ode_force`` are folded into two matrices
    once, instead of being rebuilt at every right-hand-side call (identical result).
    """

    def __init__(self, m: np.ndarray, comps: list[KnownComponent], alpha: np.ndarray,
                 beta: np.ndarray, gamma: np.ndarray) -> None:
        n = m.shape[0]
        self.n_dof = n
        self.a_k, self.b_k, self.c_k = summed_linear_coefficients(comps, n)
        m_eff = m + self.a_k - alpha
        sv = np.linalg.svd(m_eff, compute_uv=False)
        if sv[-1] <= 1e-8 * np.linalg.norm(m + self.a_k, 2):
            raise InputError(
                "m + A_k − α is singular: the moved α cancels the inertia (α ≈ m + A_k, as when "
                "F_bb is the whole equation of motion); move terms identified on a force "
                "component"
            )
        self.m_inv = np.linalg.inv(m_eff)
        linear = [c for c in comps if _is_plain_linear(c)]
        self.other = [c for c in comps if not _is_plain_linear(c)]
        _, b_lin, c_lin = summed_linear_coefficients(linear, n)
        self.b_ode, self.c_ode = beta - b_lin, gamma - c_lin
        self.offsets = np.cumsum([2 * n, *[c.n_states for c in self.other]])

    def initial_states(self, hist: xr.Dataset) -> np.ndarray:
        """The components' internal states at the first sample of ``hist``."""
        return np.concatenate([np.zeros(0), *[c.initial_state(hist) for c in self.other]])

    def accel_and_states(self, ti: float, y: np.ndarray, f_p: np.ndarray
                         ) -> tuple[np.ndarray, list[np.ndarray]]:
        """z̈ [m/s², rad/s²] and the internal states' derivatives, with ``F_p(ti) = f_p``."""
        n = self.n_dof
        z, zd = y[:n], y[n:2 * n]
        f = f_p + self.b_ode @ zd + self.c_ode @ z
        dx = []
        for c, lo, hi in zip(self.other, self.offsets[:-1], self.offsets[1:]):
            x = y[lo:hi]
            f = f + c.ode_force(ti, z, zd, x)
            if c.n_states:
                dx.append(c.state_derivative(ti, z, zd, x))
        return self.m_inv @ f, dx


def solve_prescribed(ode: PrescribedODE, u: np.ndarray, z0: np.ndarray, v0: np.ndarray,
                     dt: float, *, progress: bool = False, t: np.ndarray, method: str = "RK45",
                     rtol: float = 1e-9, atol: float = 1e-12, x0: np.ndarray | None = None
                     ) -> SolverResult:
    """The reconstruction ODE by :func:`scipy.integrate.solve_ivp` (the solver contract).

    ``u`` is ``F_p`` on the times ``t`` [N, N m] (not-a-knot cubic spline in between), ``dt``
    the largest step [s] (so no force sample is stepped over), ``x0`` the components' states.
    Returns z, ż, z̈ on ``t``; ``nfev`` the right-hand-side evaluations; a failure as data.
    """
    n = ode.n_dof
    spline = _UniformSpline(t, u)

    def rhs(ti: float, y: np.ndarray) -> np.ndarray:
        acc, dx = ode.accel_and_states(ti, y, spline(ti))
        return np.concatenate([y[n:2 * n], acc, *dx])

    y0 = np.concatenate([z0, v0, np.zeros(0) if x0 is None else x0])
    sol = scipy.integrate.solve_ivp(rhs, (t[0], t[-1]), y0, method=method, t_eval=t,
                                    rtol=rtol, atol=atol, max_step=dt)
    y = np.full((y0.size, t.size), np.nan)
    done = np.asarray(sol.y, dtype=float).reshape(y0.size, -1)  # [] when the first step failed
    y[:, :done.shape[1]] = done
    z, v = y[:n].T, y[n:2 * n].T
    kw = dict(x=y[2 * n:].T, method=method, nfev=int(sol.nfev),
              counts={"samples": done.shape[1]})
    if not sol.success or done.shape[1] != t.size:
        return failure(t, z, v, f"reconstruction failed: {sol.message}", **kw)
    t_bad = first_non_finite(t, z, v)
    if t_bad is not None:
        return failure(t, z, v, f"reconstruction diverged (non-finite state) at t = "
                                f"{t_bad:.6g} s", **kw)
    acc = np.array([ode.accel_and_states(ti, yi, spline(ti))[0] for ti, yi in zip(t, y.T)])
    return SolverResult(t, z, v, a=acc, forces={"F_prescribed": u}, message=str(sol.message),
                        **kw)
