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
from hybridwsi.diagnostic.stability import StabilityReport, prescribed_force_stability
from hybridwsi.errors import InputError, SolverError
from hybridwsi.history import make_history, time_step, validate


@dataclass
class ReconstructionResult:
    """Reconstructed motion and its error against the reference.

    Attributes
    ----------
    history : xarray.Dataset
        TimeHistory (source ``"reconstruction"``) with z, ż, z̈ and the prescribed force
        ``F_prescribed`` [N].
    error : ndarray, shape (n_time, n_dof)
        ``z − z_ref`` [m].
    metrics : dict
        Per DOF: ``rms_error`` [m], ``max_error`` [m], ``nrms_error`` (RMS error / std of z_ref),
        ``final_drift`` [m] (error at the last sample).
    stability : StabilityReport
        Setting (a) for the ODE actually integrated (known part plus moved terms).
    solver_message : str
        ``solve_ivp``'s message.
    n_rhs_evals : int
        Right-hand-side evaluations.
    """

    history: xr.Dataset
    error: np.ndarray
    metrics: dict[str, list[float]]
    stability: StabilityReport
    solver_message: str
    n_rhs_evals: int
    inputs: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (metrics, stability, solver info; not the time series)."""
        return {
            "metrics": self.metrics,
            "stability": self.stability.to_dict(),
            "solver_message": self.solver_message,
            "n_rhs_evals": self.n_rhs_evals,
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
    method: str = "DOP853",
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
        :func:`scipy.integrate.solve_ivp` method and tolerances (atol in m, m/s).
    max_step : float, optional
        Largest solver step [s]; default the sampling interval.

    Returns
    -------
    ReconstructionResult

    Raises
    ------
    InputError
        Missing mass or kinematics, mismatched DOF, singular ``m + A_k − α``.
    SolverError
        When ``solve_ivp`` fails (its message is included).
    """
    validate(hist)
    given = as_components(known)
    # a force of time only (e.g. the excitation) is the same inside or outside the prescribed
    # force: it stays in F_p instead of being subtracted and integrated back
    comps = [c for c in given if not c.time_only]
    t = np.asarray(hist["time"].values, dtype=float)
    n_dof = hist.sizes["dof"]
    m = mass_from(hist, None) if mass is None else as_matrix(mass, n_dof, "mass")
    if m is None:
        raise InputError("no mass given: pass mass=... or store 'mass' in the history")
    if not np.all(np.isfinite(m)):
        raise InputError("mass must be finite")
    alpha, beta, gamma = _moved_terms(move_identified, n_dof)
    moving = move_identified is not None
    z_ref, zd_ref = kinematics(hist, ("z", "zdot"))
    f_p = black_box_force(hist, force, comps)
    if moving:
        (zdd_ref,) = kinematics(hist, ("zddot",))
        # F_bb − (F̄ + α z̈ + β ż + γ z) + F̄: the mean stays prescribed
        f_p = f_p - zdd_ref @ alpha.T - zd_ref @ beta.T - z_ref @ gamma.T

    a_k, b_k, c_k = summed_linear_coefficients(comps, n_dof)
    m_eff = m + a_k - alpha
    sv = np.linalg.svd(m_eff, compute_uv=False)
    if sv[-1] <= 1e-8 * np.linalg.norm(m + a_k, 2):
        raise InputError(
            "m + A_k − α is singular: the moved α cancels the inertia (α ≈ m + A_k, as when "
            "F_bb is the whole equation of motion); move terms identified on a force component"
        )
    m_inv = np.linalg.inv(m_eff)
    stab = prescribed_force_stability(m, a_k - alpha, b_k - beta, c_k - gamma)

    spline = _UniformSpline(t, f_p)
    # memoryless components with the default (linear) ode_force are folded into two matrices
    # once, instead of being rebuilt at every right-hand-side call (identical result)
    linear = [c for c in comps if _is_plain_linear(c)]
    other = [c for c in comps if not _is_plain_linear(c)]
    _, b_lin, c_lin = summed_linear_coefficients(linear, n_dof)
    b_ode, c_ode = beta - b_lin, gamma - c_lin
    n_states = [c.n_states for c in other]
    offsets = np.cumsum([2 * n_dof, *n_states])
    y0 = np.concatenate([z_ref[0], zd_ref[0], *[c.initial_state(hist) for c in other]])

    def accel_and_states(ti: float, y: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
        z, zd = y[:n_dof], y[n_dof : 2 * n_dof]
        f = spline(ti) + b_ode @ zd + c_ode @ z
        dx = []
        for c, lo, hi in zip(other, offsets[:-1], offsets[1:]):
            x = y[lo:hi]
            f = f + c.ode_force(ti, z, zd, x)
            if c.n_states:
                dx.append(c.state_derivative(ti, z, zd, x))
        return m_inv @ f, dx

    def rhs(ti: float, y: np.ndarray) -> np.ndarray:
        acc, dx = accel_and_states(ti, y)
        return np.concatenate([y[n_dof : 2 * n_dof], acc, *dx])

    step = time_step(hist) if max_step is None else float(max_step)
    sol = scipy.integrate.solve_ivp(
        rhs, (t[0], t[-1]), y0, method=method, t_eval=t, rtol=rtol, atol=atol, max_step=step
    )
    if not sol.success or sol.y.shape[1] != t.size:
        raise SolverError(f"reconstruction failed: {sol.message}")
    if not np.all(np.isfinite(sol.y)):
        i = int(np.flatnonzero(~np.isfinite(sol.y).all(axis=0))[0])
        raise SolverError(f"reconstruction diverged (non-finite state) at t = {t[i]:.6g} s")
    z, zd = sol.y[:n_dof].T, sol.y[n_dof : 2 * n_dof].T
    zdd = np.array([accel_and_states(ti, yi)[0] for ti, yi in zip(t, sol.y.T)])
    err = z - z_ref
    inputs = {
        "force": force,
        "known": [c.describe() for c in given],
        "moved_identified": None if not moving else {
            "alpha": alpha.tolist(), "beta": beta.tolist(), "gamma": gamma.tolist()},
        "method": method, "rtol": rtol, "atol": atol, "max_step": step,
        "interpolation": "cubic spline (not-a-knot)",
        "reference": {"source": hist.attrs.get("source", ""),
                      "inputs": hist.attrs.get("inputs", "{}")},
    }
    out = make_history(
        t, z, zd, zdd, forces={"F_prescribed": f_p}, dof=[str(d) for d in hist["dof"].values],
        mass=m, source="reconstruction", inputs=inputs,
    )
    return ReconstructionResult(
        history=out, error=err, metrics=_error_metrics(err, z_ref), stability=stab,
        solver_message=str(sol.message), n_rhs_evals=int(sol.nfev), inputs=inputs,
    )
