"""Stability of a force partition in three settings, assessed in one place (docs/THEORY.md §4).

A partition is described by a :class:`CoupledStep`: the rigid-body mass ``m``, the known part
``F_known = −A_k z̈ − B_k ż − C_k z`` (matrices n×n, from
:func:`hybridwsi.forces.summed_linear_coefficients`; ``A_k`` is A∞, ``added_mass_inf``, when
the added mass is known), the learned (or identified) part linearised as
``F_s ≈ α z̈ + β ż + γ z``, and the step Δt, scheme and coupling mode of the hybrid solver.
:func:`assess` judges it and returns one :class:`StabilityReport`:

a. prescribed force — reconstruction with a prescribed ``F_bb(t)`` (paper Eq. 4): the error
   ``e = z − z_ref`` obeys ``(m + A_k) ë + B_k ė + C_k e = 0``.
b. continuous — the surrogate in a continuous (monolithic) loop:
   ``(m + A_k − α) z̈ + (B_k − β) ż + (C_k − γ) z = 0``.
c. loosely coupled — the surrogate sees the previous step's kinematics; the one-step
   amplification matrix is built from the very step function the hybrid rollout uses,
   :func:`hybridwsi.diagnostic.integrators.lagged_step` (documented there), and
   :func:`max_stable_dt` finds the largest stable Δt. A rollout whose surrogate has memory
   (feature lags) passes the amplification matrix of its own step map instead
   (``assess(step, step_map=G)``, :func:`hybridwsi.surrogate.rollout.check_stability`).

Eigenvalues of the second-order systems are the generalised eigenvalues of the first-order
pencil ``([0, I; −C, −B], [I, 0; 0, M])`` (infinite ones when M is singular).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import scipy.linalg

from hybridwsi.forces import KnownComponent, as_matrix, summed_linear_coefficients
from hybridwsi.diagnostic.integrators import check_scheme, lagged_step
from hybridwsi.diagnostic.regression import as_components
from hybridwsi.errors import InputError

#: real parts within this fraction of the largest |eigenvalue| count as zero
RE_RTOL = 1e-9
#: spectral radius above 1 + this counts as unstable (below 1 − this as decaying)
RHO_TOL = 1e-9
#: relative precision of the largest stable Δt of a caller's step map (:func:`assess`)
MAP_RTOL = 1e-2
#: relative singular-value threshold for "singular" matrices
SING_RTOL = 1e-12
#: coupling modes of the hybrid solver (:mod:`hybridwsi.surrogate.coupled`)
MODES = ("lagged", "corrected", "implicit")
#: the matrices of a CoupledStep, in order, with their symbols
MATRICES = {"mass": "m", "known_mass": "A_k", "known_damping": "B_k",
            "known_stiffness": "C_k", "alpha": "α", "beta": "β", "gamma": "γ"}


def _num(x: Any) -> Any:
    """A JSON number: None for None/NaN/−inf, the string "inf" for +inf."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else ("inf" if x > 0 else None)


def _from_num(x: Any) -> float | None:
    """Inverse of :func:`_num` (None stays None)."""
    return None if x is None else (math.inf if x == "inf" else float(x))


# --------------------------------------------------------------------------- the step
@dataclass(frozen=True, eq=False)
class CoupledStep:
    """The matrices and Δt of a coupled step: everything the stability of a partition depends
    on (docs/THEORY.md §4).

    Matrices are n×n in force-equation orientation ``[influenced i, radiating j]`` with units
    per DOF pair (:func:`hybridwsi.dofs.coefficient_unit`: kg, N s/m, N/m for translations; kg
    m², N m s/rad, N m/rad for rotations); a scalar means that value times the identity, a
    vector the diagonal.

    Attributes
    ----------
    mass : ndarray
        Rigid-body mass ``m``.
    known_mass, known_damping, known_stiffness : ndarray
        ``A_k, B_k, C_k`` of the known components, ``F_known = −A_k z̈ − B_k ż − C_k z``
        (``A_k`` is A∞, ``added_mass_inf``, when the added mass is known).
    alpha, beta, gamma : ndarray
        ``α, β, γ`` of the learned (or identified) component, ``F_s ≈ α z̈ + β ż + γ z``.
    dt : float or None
        Step of the hybrid solver [s]; None for the continuous settings only.
    scheme : {"newmark", "semi_implicit_euler"}
        Integrator of the lagged step (:mod:`hybridwsi.diagnostic.integrators`).
    mode : {"lagged", "corrected", "implicit"}
        Coupling of the learned force (:mod:`hybridwsi.surrogate.coupled`).
    corrections : int
        Predictor-corrector passes of the ``corrected`` mode (0 otherwise).
    """

    mass: np.ndarray
    known_mass: np.ndarray = 0.0  # type: ignore[assignment]
    known_damping: np.ndarray = 0.0  # type: ignore[assignment]
    known_stiffness: np.ndarray = 0.0  # type: ignore[assignment]
    alpha: np.ndarray = 0.0  # type: ignore[assignment]
    beta: np.ndarray = 0.0  # type: ignore[assignment]
    gamma: np.ndarray = 0.0  # type: ignore[assignment]
    dt: float | None = None
    scheme: str = "newmark"
    mode: str = "lagged"
    corrections: int = 0

    def __post_init__(self) -> None:
        values = [getattr(self, k) for k in MATRICES]
        n = 1
        for v in values:
            a = np.asarray(v, dtype=float)
            n = max(n, a.shape[0] if a.ndim == 2 else (a.size if a.ndim == 1 else 1))
        for name, v in zip(MATRICES, values):
            m = np.array(as_matrix(0.0 if v is None else v, n, name), dtype=float)
            if not np.all(np.isfinite(m)):
                raise InputError(f"{name} ({MATRICES[name]}) must be finite")
            m.setflags(write=False)
            object.__setattr__(self, name, m)
        check_scheme(self.scheme)
        if self.mode not in MODES:
            raise InputError(f"mode must be one of {', '.join(MODES)}, got '{self.mode}'")
        if self.dt is not None:
            dt = self.dt
            if not (isinstance(dt, (int, float, np.floating)) and math.isfinite(dt) and dt > 0):
                raise InputError(f"dt must be a positive number of seconds, got {dt!r}")
            object.__setattr__(self, "dt", float(dt))
        object.__setattr__(self, "corrections", int(self.corrections))

    @classmethod
    def from_components(cls, mass: float | np.ndarray,
                        known: Iterable[KnownComponent | str] = (), surrogate: Any = None,
                        **step: Any) -> CoupledStep:
        """The step of a partition: ``A_k, B_k, C_k`` summed over the ``known`` components
        (objects or ``"NAME=VALUE"``), ``α, β, γ`` from ``surrogate`` (anything with
        ``alpha, beta, gamma``, e.g. a :class:`~hybridwsi.diagnostic.RegressionResult` or a
        network's linearisation; None: no learned part); ``step`` sets ``dt``, ``scheme``,
        ``mode``, ``corrections``."""
        comps = as_components(known)
        m = np.asarray(mass, dtype=float)
        n = (np.asarray(surrogate.alpha).shape[0] if surrogate is not None
             else (m.shape[0] if m.ndim else 1))
        a, b, c = summed_linear_coefficients(comps, n)
        learned = {} if surrogate is None else {
            k: np.asarray(getattr(surrogate, k), dtype=float) for k in ("alpha", "beta", "gamma")}
        return cls(as_matrix(mass, n, "mass"), a, b, c, **learned, **step)

    @property
    def n_dof(self) -> int:
        return self.mass.shape[0]

    @property
    def inertia(self) -> np.ndarray:
        """``m + A_k``, the matrix of z̈ in the ODE [kg, kg m, kg m²]."""
        return self.mass + self.known_mass

    def with_dt(self, dt: float | None) -> CoupledStep:
        """The same step at another Δt [s]."""
        return replace(self, dt=dt)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: matrices as nested lists [units per DOF pair], dt [s], scheme, mode."""
        return {**{k: getattr(self, k).tolist() for k in MATRICES},
                "dt": self.dt, "scheme": self.scheme, "mode": self.mode,
                "corrections": self.corrections}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> CoupledStep:
        """Inverse of :meth:`to_dict`."""
        return cls(**{k: np.asarray(d[k], dtype=float) for k in MATRICES}, dt=d.get("dt"),
                   scheme=d.get("scheme", "newmark"), mode=d.get("mode", "lagged"),
                   corrections=int(d.get("corrections", 0)))


# --------------------------------------------------------------------------- the verdicts
@dataclass
class SettingVerdict:
    """The verdict of one setting (a, b or c) of a :class:`StabilityReport`.

    Attributes
    ----------
    setting : str
        ``"prescribed_force"`` (a), ``"surrogate"`` (b, continuous) or ``"loosely_coupled"``
        (c).
    verdict : str
        ``drift``/``neutral``/``damped``/``unstable`` (a), ``stable``/``marginal``/``unstable``
        (b, c).
    message : str
        Plain-language explanation.
    eigenvalues : ndarray
        Continuous eigenvalues [1/s] (a, b) or eigenvalues of the one-step map (c).
    spectral_radius, dt, max_stable_dt : float or None
        Largest |eigenvalue| of the one-step map, its Δt and the largest stable Δt [s] (c).
    scheme : str or None
        Integrator (c).
    conditions : dict
        Setting-specific details (sign conditions, drift directions, added-mass ratio).
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
        eig = None
        if self.eigenvalues is not None:
            eig = [[_num(v.real), _num(v.imag)] for v in np.asarray(self.eigenvalues, complex)]
        return {
            "setting": self.setting,
            "verdict": self.verdict,
            "message": self.message,
            "eigenvalues": eig,
            "spectral_radius": _num(self.spectral_radius),
            "dt": _num(self.dt),
            "scheme": self.scheme,
            "max_stable_dt": _num(self.max_stable_dt),
            "conditions": {k: (_num(v) if isinstance(v, (float, int, np.floating)) and
                               not isinstance(v, bool) else v)
                           for k, v in self.conditions.items()},
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> SettingVerdict:
        """Inverse of :meth:`to_dict` (a None eigenvalue part, an infinite one, is inf)."""
        eig = d.get("eigenvalues")
        if eig is not None:
            eig = np.array([complex(math.inf if re is None else re, 0.0 if im is None else im)
                            for re, im in eig])
        cond = {k: (_from_num(v) if v == "inf" else v) for k, v in d.get("conditions", {}).items()}
        return cls(d["setting"], d["verdict"], d["message"], eig, _from_num(d.get("spectral_radius")),
                   _from_num(d.get("dt")), d.get("scheme"), _from_num(d.get("max_stable_dt")), cond)


@dataclass
class StabilityReport:
    """The stability of a coupled step: the one result type of the assessment (:func:`assess`).

    Attributes
    ----------
    step : CoupledStep
        What was assessed (matrices, Δt, scheme, mode), so α, β, γ of the learned component
        travel with the verdict.
    prescribed, continuous : SettingVerdict
        Settings (a) and (b).
    loosely_coupled : SettingVerdict or None
        Setting (c) at ``step.dt`` for the lag-0 sensitivities α, β, γ (None without a Δt).
    spectral_radius : float or None
        Spectral radius of the coupled step map at ``step.dt``: setting (c)'s, or that of the
        step map the caller passed (a rollout's, with every feature lag of its network).
    added_mass_ratio : float
        ``max |eig((m + A_k)⁻¹ α)|``: ≥ 1 is the added-mass instability of the lagged coupling
        at every Δt, and the divergence of the implicit fixed point.
    max_stable_dt : float or None
        Largest stable Δt [s] of the lagged step (inf: stable at every tested Δt).
    rho_tol : float
        Margin on the spectral radius of :attr:`stable`.
    """

    step: CoupledStep
    prescribed: SettingVerdict
    continuous: SettingVerdict
    loosely_coupled: SettingVerdict | None
    spectral_radius: float | None
    added_mass_ratio: float
    max_stable_dt: float | None
    rho_tol: float = RHO_TOL

    @property
    def continuous_stable(self) -> bool:
        """Setting (b): the surrogate in a continuous loop does not make errors grow."""
        return self.continuous.stable

    @property
    def stable(self) -> bool:
        """The coupled run is predicted stable: spectral radius ≤ 1 + ``rho_tol`` at Δt (and,
        for the ``implicit`` mode, a contracting fixed point, added-mass ratio < 1); without a
        Δt, setting (b)."""
        if self.spectral_radius is None:
            return self.continuous_stable
        return bool(self.spectral_radius <= 1.0 + self.rho_tol
                    and (self.step.mode != "implicit" or self.added_mass_ratio < 1.0))

    @property
    def settings(self) -> list[SettingVerdict]:
        """The settings assessed, (a), (b) and, with a Δt, (c)."""
        return [s for s in (self.prescribed, self.continuous, self.loosely_coupled)
                if s is not None]

    # the learned component's α, β, γ (the names of the rollout's former prediction)
    @property
    def alpha_s(self) -> np.ndarray:
        return self.step.alpha

    @property
    def beta_s(self) -> np.ndarray:
        return self.step.beta

    @property
    def gamma_s(self) -> np.ndarray:
        return self.step.gamma

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary; :meth:`from_dict` restores it."""
        return {
            "step": self.step.to_dict(),
            "stable": self.stable,
            "continuous_stable": self.continuous_stable,
            "spectral_radius": _num(self.spectral_radius),
            "added_mass_ratio": _num(self.added_mass_ratio),
            "max_stable_dt": _num(self.max_stable_dt),
            "rho_tol": self.rho_tol,
            "settings": {s.setting: s.to_dict() for s in self.settings},
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> StabilityReport:
        """Inverse of :meth:`to_dict`."""
        sets = {k: SettingVerdict.from_dict(v) for k, v in d["settings"].items()}
        return cls(CoupledStep.from_dict(d["step"]), sets["prescribed_force"], sets["surrogate"],
                   sets.get("loosely_coupled"), _from_num(d.get("spectral_radius")),
                   _from_num(d["added_mass_ratio"]), _from_num(d.get("max_stable_dt")),
                   float(d.get("rho_tol", RHO_TOL)))


# --------------------------------------------------------------------------- helpers
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


# --------------------------------------------------------------------------- assessment
def assess(step: CoupledStep, *,
           step_map: np.ndarray | Callable[[float], np.ndarray] | None = None,
           rho_tol: float = RHO_TOL) -> StabilityReport:
    """Judge a coupled step in the three settings (docs/THEORY.md §4): the one assessment.

    Parameters
    ----------
    step : CoupledStep
        Mass, known part, learned part, Δt, scheme, mode.
    step_map : ndarray or callable, optional
        The caller's own step map (a rollout whose network has several feature lags and whose
        known part has internal states): its amplification matrix at ``step.dt``, or a
        function ``dt -> matrix``. Its spectral radius at ``step.dt`` is the report's; given
        as a function, the report's ``max_stable_dt`` is that of the same map
        (:func:`max_stable_dt` with its radius), so the two agree (``max_stable_dt ≥ dt``
        exactly when stable at ``dt``). Given as a matrix (one Δt only), the report's
        ``max_stable_dt`` is setting (c)'s, of the lag-0 map, which can disagree with the
        verdict. Default: the map of :func:`hybridwsi.diagnostic.integrators.lagged_step`
        (setting c).
    rho_tol : float
        Margin on the spectral radius of :attr:`StabilityReport.stable` (and of
        ``max_stable_dt`` and setting (c)'s verdict).

    Returns
    -------
    StabilityReport

    Raises
    ------
    InputError
        ``m + A_k`` singular (no acceleration can be solved for).
    """
    if _is_singular(step.inertia):
        raise InputError("m + A_k is singular: the ODE cannot be solved for the acceleration")
    ratio = added_mass_ratio(step.mass, step.known_mass, step.alpha)
    lagged = None if step.dt is None else _loosely_coupled(step, ratio, rho_tol)
    rho = None if lagged is None else lagged.spectral_radius
    dt_max = None if lagged is None else lagged.max_stable_dt
    if callable(step_map):
        if step.dt is None:
            raise InputError("a step map function needs the step's dt")
        rho = _radius_of(step_map, step.dt)
        # to 1 % (each evaluation is an eigenvalue problem of the whole map; the bracket's
        # stable end is returned, so the limit errs on the safe side)
        dt_max = max_stable_dt(step, radius=lambda dt: _radius_of(step_map, dt),
                               rho_tol=rho_tol, rtol=MAP_RTOL)
    elif step_map is not None:
        rho = float(np.max(np.abs(np.linalg.eigvals(step_map))))
    return StabilityReport(step, _prescribed(step), _continuous(step), lagged, rho, ratio,
                           dt_max, float(rho_tol))


def _radius_of(step_map: Callable[[float], np.ndarray], dt: float) -> float:
    """Spectral radius of ``step_map(dt)``."""
    return float(np.max(np.abs(np.linalg.eigvals(step_map(dt)))))


def added_mass_ratio(mass: np.ndarray, known_mass: np.ndarray, alpha: np.ndarray) -> float:
    """Spectral radius of ``(m + A_k)⁻¹ α``: ≥ 1 means the lagged coupling fails at every Δt."""
    return float(np.max(np.abs(np.linalg.eigvals(np.linalg.solve(mass + known_mass, alpha)))))


def _prescribed(step: CoupledStep) -> SettingVerdict:
    """(a): error dynamics of the reconstruction with the force prescribed, ``(m + A_k) ë +
    B_k ė + C_k e = 0``: ``drift`` (zero eigenvalue with a Jordan block: errors grow
    linearly), ``neutral`` (eigenvalues on the imaginary axis), ``damped`` or ``unstable``."""
    b, c = step.known_damping, step.known_stiffness
    lam = system_eigenvalues(step.inertia, b, c)
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
    return SettingVerdict("prescribed_force", verdict, msg, eigenvalues=lam,
                          conditions={"drift_directions": n_drift})


def _continuous(step: CoupledStep) -> SettingVerdict:
    """(b): ``(m + A_k − α) z̈ + (B_k − β) ż + (C_k − γ) z = 0``: ``stable`` (all Re λ < 0),
    ``marginal`` or ``unstable``; ``conditions`` the smallest eigenvalue of the symmetric part
    of each effective matrix and whether it is positive — sufficient for stability with
    symmetric matrices, necessary in 1 DOF."""
    m_eff = step.inertia - step.alpha
    b_eff, c_eff = step.known_damping - step.beta, step.known_stiffness - step.gamma
    cond = {}
    for name, mat in (("mass", m_eff), ("damping", b_eff), ("stiffness", c_eff)):
        cond[f"{name}_min_eig"] = _min_sym_eig(mat)
        cond[f"{name}_positive"] = bool(cond[f"{name}_min_eig"] > 0)
    failed = [k for k in ("mass", "damping", "stiffness") if not cond[f"{k}_positive"]]
    lam = system_eigenvalues(m_eff, b_eff, c_eff)
    if _is_singular(m_eff):
        msg = ("unstable: m + A_k − α_s is singular — the surrogate cancels the inertia, so the "
               "acceleration cannot be resolved (algebraic loop); keep α in the known part")
        return SettingVerdict("surrogate", "unstable", msg, eigenvalues=lam, conditions=cond)
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
    return SettingVerdict("surrogate", verdict, msg, eigenvalues=lam, conditions=cond)


def amplification_matrix(step: CoupledStep, dt: float | None = None) -> np.ndarray:
    """One-step map G (3n×3n) of :func:`lagged_step` on the carried state ``[z, ż, z̈_lag]``
    at ``dt`` [s] (default ``step.dt``).

    Built column by column by stepping unit states with the linear surrogate
    ``F_x = α z̈_lag + β ż + γ z``, so G is exactly the integrator's map.
    """
    dt = step.dt if dt is None else dt
    n = step.n_dof
    alpha, beta, gamma = step.alpha, step.beta, step.gamma

    def force(t: float, z: np.ndarray, v: np.ndarray, acc: np.ndarray) -> np.ndarray:
        return alpha @ acc + beta @ v + gamma @ z

    g = np.empty((3 * n, 3 * n))
    for k in range(3 * n):
        s = np.zeros(3 * n)
        s[k] = 1.0
        g[:, k] = np.concatenate(
            lagged_step(step.scheme, 0.0, dt, s[:n], s[n:2 * n], s[2 * n:], step.inertia,
                        step.known_damping, step.known_stiffness, force)
        )
    return g


def _spectral_radius(step: CoupledStep, dt: float) -> float:
    return float(np.max(np.abs(np.linalg.eigvals(amplification_matrix(step, dt)))))


def max_stable_dt(step: CoupledStep, *, dt_range: tuple[float, float] | None = None,
                  n_grid: int = 60, rtol: float = 1e-6,
                  radius: Callable[[float], float] | None = None,
                  rho_tol: float = RHO_TOL) -> float:
    """Largest stable Δt [s] of a step map, consistent with the verdict at ``step.dt``.

    Stable means spectral radius ≤ 1 + ``rho_tol`` (the margin of
    :attr:`StabilityReport.stable`). The map is ``radius(dt)`` (the spectral radius of the
    caller's own step map at ``dt``, e.g. a rollout's with every feature lag and internal
    state), default the amplification matrix of :func:`lagged_step` for ``step``.

    - ``step.dt`` set and the map stable there: the upper end of the stable interval that
      contains ``step.dt`` (≥ ``step.dt``; ``inf`` when stable at every tested larger Δt).
      A lagged surrogate can be unstable at small Δt and stable at larger ones (the lag of a
      learned stiffness adds damping ∝ Δt that can outweigh a learned anti-damping), so the
      interval need not reach down to 0.
    - otherwise: the largest Δt such that every tested smaller Δt is stable (``0`` when
      unstable at the smallest; always the case for the default map when
      ``added_mass_ratio ≥ 1``: as Δt → 0 it keeps the eigenvalues of ``(m + A_k)⁻¹ α``).

    So ``max_stable_dt(step) ≥ step.dt`` exactly when the map is stable at ``step.dt``.
    Scans ``n_grid`` log-spaced steps over ``dt_range`` (default ``1e-4/ω`` to ``1e2/ω``, ω the
    largest |continuous eigenvalue| of the known and of the surrogate-in-the-loop system;
    above ``step.dt`` from ``step.dt`` on), stopping at the first unstable one, then bisects
    the stable→unstable bracket to relative precision ``rtol``.
    """
    if _is_singular(step.inertia):
        raise InputError("m + A_k is singular: the ODE cannot be solved for the acceleration")
    lo, hi = map(float, _dt_range(step) if dt_range is None else dt_range)
    if not (0 < lo < hi and math.isfinite(hi)):
        raise InputError(f"dt_range must satisfy 0 < low < high < inf, got {dt_range}")
    if radius is None:
        if added_mass_ratio(step.mass, step.known_mass, step.alpha) >= 1.0:
            return 0.0
        radius = lambda dt: _spectral_radius(step, dt)  # noqa: E731

    def unstable(dt: float) -> bool:
        return radius(dt) > 1.0 + rho_tol

    if step.dt is not None and not unstable(step.dt):
        if step.dt >= hi:
            return math.inf
        n_above = max(2, int(round(n_grid * math.log(hi / step.dt) / math.log(hi / lo))) + 1)
        grid = np.geomspace(step.dt, hi, n_above)
    else:
        grid = np.geomspace(lo, hi, n_grid)
    good = None
    for dt in map(float, grid):
        if unstable(dt):
            break
        good = dt
    else:
        return math.inf
    if good is None:
        return 0.0
    badt = dt
    while badt / good - 1.0 > rtol:
        mid = math.sqrt(good * badt)
        good, badt = (good, mid) if unstable(mid) else (mid, badt)
    return good


def _dt_range(step: CoupledStep) -> tuple[float, float]:
    """Default Δt range [s] of :func:`max_stable_dt`: ``1e-4/ω`` to ``1e2/ω``."""
    lam = np.concatenate([
        system_eigenvalues(step.inertia, step.known_damping, step.known_stiffness),
        system_eigenvalues(step.inertia - step.alpha, step.known_damping - step.beta,
                           step.known_stiffness - step.gamma)])
    lam = np.abs(lam[np.isfinite(lam)])
    omega = float(lam.max()) if lam.size and lam.max() > 0 else 1.0
    return 1e-4 / omega, 1e2 / omega


def _loosely_coupled(step: CoupledStep, ratio: float, rho_tol: float = RHO_TOL
                     ) -> SettingVerdict:
    """(c) at ``step.dt``: the amplification matrix of :func:`lagged_step` (state ``[z, ż,
    z̈_lag]``): ``stable`` (spectral radius < 1), ``marginal`` (= 1 within ``rho_tol``) or
    ``unstable``, with :func:`max_stable_dt` of the same map and margin."""
    dt, scheme = step.dt, step.scheme
    lam = np.linalg.eigvals(amplification_matrix(step))
    rho = float(np.max(np.abs(lam)))
    dt_max = max_stable_dt(step, rho_tol=rho_tol)
    if rho > 1.0 + rho_tol:
        verdict = "unstable"
        msg = f"unstable at Δt = {dt:.4g} s: spectral radius {rho:.6g} > 1"
    elif rho >= 1.0 - rho_tol:
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
    return SettingVerdict(
        "loosely_coupled", verdict, msg, eigenvalues=lam, spectral_radius=rho, dt=float(dt),
        scheme=scheme, max_stable_dt=dt_max, conditions={"added_mass_ratio": ratio},
    )


def surrogate_stability(*matrices: float | np.ndarray) -> SettingVerdict:
    """Setting (b) of ``CoupledStep(*matrices)`` — the positional form ``(m, A_k, B_k, C_k, α,
    β, γ)``, a public shorthand (no caller inside the package since the Kramer study moved to
    :func:`assess`); new code: ``assess(CoupledStep(...)).continuous``."""
    return _continuous(CoupledStep(*matrices))
