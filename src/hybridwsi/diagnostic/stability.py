"""Stability of a force partition in three settings (docs/THEORY.md §4).

The known part is written ``F_known = −A_k z̈ − B_k ż − C_k z`` (matrices n×n, from
:func:`hybridwsi.forces.summed_linear_coefficients`); ``m`` is the rigid-body mass.

a. :func:`prescribed_force_stability` — reconstruction with a prescribed ``F_bb(t)`` (paper
   Eq. 4): the error ``e = z − z_ref`` obeys ``(m + A_k) ë + B_k ė + C_k e = 0``.
b. :func:`surrogate_stability` — a state-dependent surrogate linearised as
   ``F_s ≈ α_s z̈ + β_s ż + γ_s z`` in a continuous (monolithic) loop:
   ``(m + A_k − α_s) z̈ + (B_k − β_s) ż + (C_k − γ_s) z = 0``.
c. :func:`loosely_coupled_stability` — the surrogate sees the previous step's kinematics; the
   one-step amplification matrix is built from the very step function the hybrid rollout uses,
   :func:`hybridwsi.diagnostic.integrators.lagged_step` (documented there), and
   :func:`max_stable_dt` finds the largest stable Δt.

Eigenvalues of the second-order systems are the generalised eigenvalues of the first-order
pencil ``([0, I; −C, −B], [I, 0; 0, M])`` (infinite ones when M is singular).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg

from hybridwsi.forces import KnownComponent, as_matrix, summed_linear_coefficients
from hybridwsi.diagnostic.integrators import check_scheme, lagged_step
from hybridwsi.errors import InputError

#: real parts within this fraction of the largest |eigenvalue| count as zero
RE_RTOL = 1e-9
#: spectral radius above 1 + this counts as unstable (below 1 − this as decaying)
RHO_TOL = 1e-9
#: relative singular-value threshold for "singular" matrices
SING_RTOL = 1e-12


@dataclass
class StabilityReport:
    """Outcome of one stability setting.

    Attributes
    ----------
    setting : str
        ``"prescribed_force"``, ``"surrogate"`` or ``"loosely_coupled"``.
    verdict : str
        Short keyword: ``drift``/``neutral``/``damped``/``unstable`` (a),
        ``stable``/``marginal``/``unstable`` (b, c).
    message : str
        Plain-language explanation.
    eigenvalues : ndarray or None
        Continuous eigenvalues [1/s] (a, b) or eigenvalues of the one-step map (c).
    spectral_radius : float or None
        Largest |eigenvalue| of the one-step map (c).
    dt : float or None
        Time step [s] (c).
    scheme : str or None
        Integrator (c).
    max_stable_dt : float or None
        Largest stable time step [s] (c); ``inf`` when stable at every tested step.
    conditions : dict
        Setting-specific details (sign conditions, added-mass ratio, ...).
    """

    setting: str
    verdict: str
    message: str
    eigenvalues: np.ndarray | None = None
    spectral_radius: float | None = None
    dt: float | None = None
    scheme: str | None = None
    max_stable_dt: float | None = None
    conditions: dict[str, Any] = field(default_factory=dict)

    @property
    def stable(self) -> bool:
        """True for verdicts under which errors do not grow exponentially or drift."""
        return self.verdict in ("damped", "neutral", "stable", "marginal")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (complex eigenvalues as ``[re, im]``; inf as the string)."""
        def num(x: Any) -> Any:
            if x is None:
                return None
            x = float(x)
            return x if math.isfinite(x) else ("inf" if x > 0 else None)

        eig = None
        if self.eigenvalues is not None:
            eig = [[num(v.real), num(v.imag)] for v in np.asarray(self.eigenvalues, complex)]
        return {
            "setting": self.setting,
            "verdict": self.verdict,
            "message": self.message,
            "eigenvalues": eig,
            "spectral_radius": num(self.spectral_radius),
            "dt": num(self.dt),
            "scheme": self.scheme,
            "max_stable_dt": num(self.max_stable_dt),
            "conditions": {k: (num(v) if isinstance(v, (float, int, np.floating)) and
                               not isinstance(v, bool) else v)
                           for k, v in self.conditions.items()},
        }


# --------------------------------------------------------------------------- helpers
def _n_dof(*values: Any) -> int:
    n = 1
    for v in values:
        a = np.asarray(v, dtype=float)
        if a.ndim == 2:
            n = max(n, a.shape[0])
        elif a.ndim == 1:
            n = max(n, a.size)
    return n


def _mats(n: int, **values: Any) -> list[np.ndarray]:
    out = []
    for name, v in values.items():
        m = as_matrix(0.0 if v is None else v, n, name)
        if not np.all(np.isfinite(m)):
            raise InputError(f"{name} must be finite")
        out.append(m)
    return out


def system_eigenvalues(mass: np.ndarray, damping: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """Eigenvalues λ [1/s] of ``M ë + B ė + C e = 0`` (generalised; inf where M is singular)."""
    n = mass.shape[0]
    eye, zero = np.eye(n), np.zeros((n, n))
    a = np.block([[zero, eye], [-stiffness, -damping]])
    b = np.block([[eye, zero], [zero, mass]])
    lam = scipy.linalg.eig(a, b, right=False)
    return np.where(np.isfinite(lam), lam, np.inf + 0j)


def _re_tol(lam: np.ndarray) -> float:
    finite = np.abs(lam[np.isfinite(lam)])
    return RE_RTOL * max(float(finite.max()) if finite.size else 0.0, 1e-300)


def _is_singular(m: np.ndarray) -> bool:
    s = np.linalg.svd(m, compute_uv=False)
    return bool(s[0] == 0 or s[-1] <= SING_RTOL * s[0])


def _drift_directions(damping: np.ndarray, stiffness: np.ndarray) -> int:
    """Number of independent error directions with a Jordan block at λ = 0 (double integrator).

    λ = 0 has a Jordan chain when some ``e ∈ null(C)`` has ``B e ∈ range(C)``: then errors grow
    linearly. Counted as ``dim null(C) − rank(Lᵀ B N)`` with N, L bases of null(C), null(Cᵀ).
    """
    u, s, vt = np.linalg.svd(stiffness)
    tol = SING_RTOL * max(s[0], 0.0)
    null_mask = s <= tol if s[0] > 0 else np.ones_like(s, dtype=bool)
    k = int(null_mask.sum())
    if k == 0:
        return 0
    proj = u[:, null_mask].T @ damping @ vt[null_mask].T
    sp = np.linalg.svd(proj, compute_uv=False)
    scale = max(np.linalg.norm(damping, 2), 1e-300)
    return k - int(np.sum(sp > SING_RTOL * scale))


def _min_sym_eig(m: np.ndarray) -> float:
    return float(np.linalg.eigvalsh(0.5 * (m + m.T)).min())


# --------------------------------------------------------------------------- (a)
def prescribed_force_stability(
    mass: float | np.ndarray,
    A_k: float | np.ndarray = 0.0,
    B_k: float | np.ndarray = 0.0,
    C_k: float | np.ndarray = 0.0,
) -> StabilityReport:
    """Error dynamics of the reconstruction with a prescribed force (docs/THEORY.md §4a).

    Parameters
    ----------
    mass : float or ndarray
        Rigid-body mass m [kg] (scalar, diagonal vector or n×n matrix).
    A_k, B_k, C_k : float or ndarray
        Known added mass [kg], damping [N s/m] and stiffness [N/m], ``F_known = −A_k z̈ − B_k ż
        − C_k z``.

    Returns
    -------
    StabilityReport
        ``verdict`` is ``"drift"`` (zero eigenvalue with a Jordan block: errors grow linearly),
        ``"neutral"`` (eigenvalues on the imaginary axis: errors persist), ``"damped"`` (all
        Re λ < 0) or ``"unstable"`` (some Re λ > 0).
    """
    n = _n_dof(mass, A_k, B_k, C_k)
    m, a, b, c = _mats(n, mass=mass, A_k=A_k, B_k=B_k, C_k=C_k)
    m_tot = m + a
    if _is_singular(m_tot):
        raise InputError("m + A_k is singular: the ODE cannot be solved for the acceleration")
    lam = system_eigenvalues(m_tot, b, c)
    tol = _re_tol(lam)
    n_drift = _drift_directions(b, c)
    max_re = float(np.max(lam.real))
    if max_re > tol:
        verdict = "unstable"
        msg = (f"unstable: reconstruction errors grow exponentially (largest Re λ = "
               f"{max_re:.4g} 1/s); the known part has negative stiffness or damping")
    elif n_drift:
        verdict = "drift"
        msg = (f"drift: with the force prescribed, {n_drift} direction(s) have neither restoring "
               "force nor damping (a double integrator), so any error in the initial state or "
               "in F_bb grows linearly in time; add a known stiffness (e.g. hydrostatics) or move "
               "the identified γ into the ODE")
    elif np.any(np.abs(lam.real) <= tol):
        verdict = "neutral"
        msg = ("neutral: errors neither grow nor decay (undamped oscillation or persistent "
               "offset) because the prescribed force carries no feedback; known damping "
               "(B_k > 0) or moving the identified β into the ODE makes them decay")
    else:
        verdict = "damped"
        msg = (f"damped: errors decay (slowest rate {-max_re:.4g} 1/s, time constant "
               f"{-1.0 / max_re:.4g} s)")
    return StabilityReport("prescribed_force", verdict, msg, eigenvalues=lam,
                           conditions={"drift_directions": n_drift})


# --------------------------------------------------------------------------- (b)
def surrogate_stability(
    mass: float | np.ndarray,
    A_k: float | np.ndarray,
    B_k: float | np.ndarray,
    C_k: float | np.ndarray,
    alpha_s: float | np.ndarray,
    beta_s: float | np.ndarray,
    gamma_s: float | np.ndarray,
) -> StabilityReport:
    """Continuous stability with a linearised state-dependent surrogate (docs/THEORY.md §4b).

    ``(m + A_k − α_s) z̈ + (B_k − β_s) ż + (C_k − γ_s) z = 0``; units kg, N s/m, N/m.
    ``verdict`` is ``"stable"`` (all Re λ < 0), ``"marginal"`` (max Re λ = 0) or
    ``"unstable"``. ``conditions`` holds the sign conditions: the smallest eigenvalue of the
    symmetric part of each effective matrix (``mass``, ``damping``, ``stiffness``) and whether
    it is positive — sufficient for stability with symmetric matrices, necessary in 1 DOF.
    """
    n = _n_dof(mass, A_k, B_k, C_k, alpha_s, beta_s, gamma_s)
    m, a, b, c, al, be, ga = _mats(n, mass=mass, A_k=A_k, B_k=B_k, C_k=C_k,
                                   alpha_s=alpha_s, beta_s=beta_s, gamma_s=gamma_s)
    m_eff, b_eff, c_eff = m + a - al, b - be, c - ga
    cond = {}
    for name, mat in (("mass", m_eff), ("damping", b_eff), ("stiffness", c_eff)):
        cond[f"{name}_min_eig"] = _min_sym_eig(mat)
        cond[f"{name}_positive"] = bool(cond[f"{name}_min_eig"] > 0)
    failed = [k for k in ("mass", "damping", "stiffness") if not cond[f"{k}_positive"]]
    lam = system_eigenvalues(m_eff, b_eff, c_eff)
    if _is_singular(m_eff):
        msg = ("unstable: m + A_k − α_s is singular — the surrogate cancels the inertia, so the "
               "acceleration cannot be resolved (algebraic loop); keep α in the known part")
        return StabilityReport("surrogate", "unstable", msg, eigenvalues=lam, conditions=cond)
    tol = _re_tol(lam)
    max_re = float(np.max(lam.real))
    detail = ("; failing sign condition(s): " + ", ".join(
        {"mass": "m + A_k − α_s > 0", "damping": "B_k − β_s > 0",
         "stiffness": "C_k − γ_s > 0"}[k] for k in failed)) if failed else ""
    if max_re > tol:
        verdict, msg = "unstable", f"unstable: Re λ = {max_re:.4g} 1/s > 0{detail}"
    elif max_re >= -tol:
        verdict, msg = "marginal", f"marginal: eigenvalues on the imaginary axis{detail}"
    else:
        verdict, msg = "stable", f"stable: all Re λ < 0 (slowest decay rate {-max_re:.4g} 1/s)"
    return StabilityReport("surrogate", verdict, msg, eigenvalues=lam, conditions=cond)


# --------------------------------------------------------------------------- (c)
def amplification_matrix(
    mass: np.ndarray,
    A_k: np.ndarray,
    B_k: np.ndarray,
    C_k: np.ndarray,
    alpha_s: np.ndarray,
    beta_s: np.ndarray,
    gamma_s: np.ndarray,
    dt: float,
    scheme: str = "semi_implicit_euler",
) -> np.ndarray:
    """One-step map G (3n×3n) of :func:`lagged_step` on the carried state ``[z, ż, z̈_lag]``.

    Built column by column by stepping unit states with the linear surrogate
    ``F_x = α_s z̈_lag + β_s ż + γ_s z`` (all n×n matrices), so G is exactly the integrator's map.
    """
    n = mass.shape[0]
    m_tot = mass + A_k

    def force(t: float, z: np.ndarray, v: np.ndarray, acc: np.ndarray) -> np.ndarray:
        return alpha_s @ acc + beta_s @ v + gamma_s @ z

    g = np.empty((3 * n, 3 * n))
    for k in range(3 * n):
        s = np.zeros(3 * n)
        s[k] = 1.0
        g[:, k] = np.concatenate(
            lagged_step(scheme, 0.0, dt, s[:n], s[n:2 * n], s[2 * n:], m_tot, B_k, C_k, force)
        )
    return g


def _spectral_radius(*args: Any) -> float:
    return float(np.max(np.abs(np.linalg.eigvals(amplification_matrix(*args)))))


def added_mass_ratio(mass: np.ndarray, A_k: np.ndarray, alpha_s: np.ndarray) -> float:
    """Spectral radius of ``(m + A_k)⁻¹ α_s``: ≥ 1 means the lagged coupling fails at every Δt."""
    return float(np.max(np.abs(np.linalg.eigvals(np.linalg.solve(mass + A_k, alpha_s)))))


def max_stable_dt(
    mass: float | np.ndarray,
    A_k: float | np.ndarray,
    B_k: float | np.ndarray,
    C_k: float | np.ndarray,
    alpha_s: float | np.ndarray,
    beta_s: float | np.ndarray,
    gamma_s: float | np.ndarray,
    scheme: str = "semi_implicit_euler",
    *,
    dt_range: tuple[float, float] | None = None,
    n_grid: int = 60,
    rtol: float = 1e-6,
) -> float:
    """Largest Δt [s] such that every tested smaller Δt has spectral radius ≤ 1 (+ ``RHO_TOL``).

    Scans ``n_grid`` log-spaced steps over ``dt_range`` (default ``1e-4/ω`` to ``1e2/ω`` with ω
    the largest |continuous eigenvalue| of the known and of the surrogate-in-the-loop system),
    then bisects the first stable→unstable bracket to relative precision ``rtol``.
    Returns ``inf`` when stable at every tested step and ``0`` when unstable at the smallest —
    always the case when ``added_mass_ratio ≥ 1`` (as Δt → 0 the map keeps the eigenvalues of
    ``(m + A_k)⁻¹ α_s``).
    """
    check_scheme(scheme)
    n = _n_dof(mass, A_k, B_k, C_k, alpha_s, beta_s, gamma_s)
    mats = _mats(n, mass=mass, A_k=A_k, B_k=B_k, C_k=C_k,
                 alpha_s=alpha_s, beta_s=beta_s, gamma_s=gamma_s)
    m, a, b, c, al, be, ga = mats
    if _is_singular(m + a):
        raise InputError("m + A_k is singular: the ODE cannot be solved for the acceleration")
    if added_mass_ratio(m, a, al) >= 1.0:
        return 0.0
    if dt_range is None:
        lam = np.concatenate([system_eigenvalues(m + a, b, c),
                              system_eigenvalues(m + a - al, b - be, c - ga)])
        lam = np.abs(lam[np.isfinite(lam)])
        omega = float(lam.max()) if lam.size and lam.max() > 0 else 1.0
        dt_range = (1e-4 / omega, 1e2 / omega)
    lo, hi = map(float, dt_range)
    if not (0 < lo < hi and math.isfinite(hi)):
        raise InputError(f"dt_range must satisfy 0 < low < high < inf, got {dt_range}")

    def unstable(dt: float) -> bool:
        return _spectral_radius(*mats, dt, scheme) > 1.0 + RHO_TOL

    grid = np.geomspace(lo, hi, n_grid)
    bad = [unstable(dt) for dt in grid]
    if not any(bad):
        return math.inf
    i = bad.index(True)
    if i == 0:
        return 0.0
    good, badt = float(grid[i - 1]), float(grid[i])
    while badt / good - 1.0 > rtol:
        mid = math.sqrt(good * badt)
        good, badt = (good, mid) if unstable(mid) else (mid, badt)
    return good


def loosely_coupled_stability(
    mass: float | np.ndarray,
    A_k: float | np.ndarray,
    B_k: float | np.ndarray,
    C_k: float | np.ndarray,
    alpha_s: float | np.ndarray,
    beta_s: float | np.ndarray,
    gamma_s: float | np.ndarray,
    dt: float,
    scheme: str = "semi_implicit_euler",
) -> StabilityReport:
    """Stability of the lagged (explicit) surrogate coupling at step ``dt`` [s] (docs/THEORY.md §4c).

    Uses the amplification matrix of :func:`hybridwsi.diagnostic.integrators.lagged_step`
    (state ``[z, ż, z̈_lag]``). ``verdict``: ``"stable"`` (spectral radius < 1), ``"marginal"``
    (= 1 within ``RHO_TOL``) or ``"unstable"``; ``max_stable_dt`` from :func:`max_stable_dt`.
    """
    check_scheme(scheme)
    if not (isinstance(dt, (int, float, np.floating)) and math.isfinite(dt) and dt > 0):
        raise InputError(f"dt must be a positive number of seconds, got {dt!r}")
    n = _n_dof(mass, A_k, B_k, C_k, alpha_s, beta_s, gamma_s)
    mats = _mats(n, mass=mass, A_k=A_k, B_k=B_k, C_k=C_k,
                 alpha_s=alpha_s, beta_s=beta_s, gamma_s=gamma_s)
    if _is_singular(mats[0] + mats[1]):
        raise InputError("m + A_k is singular: the ODE cannot be solved for the acceleration")
    lam = np.linalg.eigvals(amplification_matrix(*mats, float(dt), scheme))
    rho = float(np.max(np.abs(lam)))
    ratio = added_mass_ratio(mats[0], mats[1], mats[4])
    dt_max = max_stable_dt(*mats, scheme)
    if rho > 1.0 + RHO_TOL:
        verdict = "unstable"
        msg = f"unstable at Δt = {dt:.4g} s: spectral radius {rho:.6g} > 1"
    elif rho >= 1.0 - RHO_TOL:
        verdict = "marginal"
        msg = f"marginal at Δt = {dt:.4g} s: spectral radius {rho:.6g} = 1 (errors do not decay)"
    else:
        verdict = "stable"
        msg = f"stable at Δt = {dt:.4g} s: spectral radius {rho:.6g} < 1"
    if ratio >= 1.0:
        msg += (f"; |α_s|/(m + A_k) = {ratio:.3g} ≥ 1: the lagged surrogate is unstable at every "
                "Δt (added-mass instability) — move α into the known part (implicit)")
    elif math.isfinite(dt_max):
        msg += f"; largest stable Δt ≈ {dt_max:.4g} s"
    else:
        msg += "; stable at every tested Δt"
    return StabilityReport(
        "loosely_coupled", verdict, msg, eigenvalues=lam, spectral_radius=rho, dt=float(dt),
        scheme=scheme, max_stable_dt=dt_max, conditions={"added_mass_ratio": ratio},
    )


# --------------------------------------------------------------------------- convenience
def assess(
    result: Any,
    mass: float | np.ndarray,
    known: Iterable[KnownComponent | str] = (),
    dt: float | None = None,
    scheme: str = "semi_implicit_euler",
) -> dict[str, StabilityReport]:
    """Settings (a), (b) and, when ``dt`` is given, (c) for a regression result.

    The identified ``result.alpha, beta, gamma`` play the surrogate (α_s, β_s, γ_s); ``known``
    gives ``(A_k, B_k, C_k)``; ``mass`` is m [kg].
    """
    from hybridwsi.diagnostic.regression import as_components

    n = result.alpha.shape[0]
    a, b, c = summed_linear_coefficients(as_components(known), n)
    m = as_matrix(mass, n, "mass")
    out = {
        "prescribed_force": prescribed_force_stability(m, a, b, c),
        "surrogate": surrogate_stability(m, a, b, c, result.alpha, result.beta, result.gamma),
    }
    if dt is not None:
        out["loosely_coupled"] = loosely_coupled_stability(
            m, a, b, c, result.alpha, result.beta, result.gamma, dt, scheme
        )
    return out
