"""The structured residual of a heave decay: a few physical terms fitted on measurements.

``F_res = −a(z) z̈ − b₁ ż − b₂ |ż| ż − k₁ z − k₃ z³`` with a position-dependent added-mass change
``a(z) = a₁ z + a₂ z²`` (the added mass of a sphere lifted out of the water falls towards
zero), linear plus quadratic drag and an amplitude-dependent stiffness; linear in its
coefficients, so it is fitted by least squares on the measured residual force
(:meth:`StructuredResidual.fit`, one step) or on the measured heave (:func:`fit_output_error`,
the simulation error, through :func:`integrate_decay`). Used by the Kramer study
(:mod:`hybridwsi.surrogate.kramer`), whose :class:`~hybridwsi.surrogate.kramer.KramerSetup`
is the ``setup`` here: mass and ``added_mass_inf`` [kg], the linear hydrostatic
``stiffness`` [N/m], ``hydrostatic_table()``, the radiation ``memory``, ``te0`` [s], the BEM
``coeffs``, ``drop_heights`` [m], ``dt`` and ``duration`` [s].
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from hybridwsi.diagnostic.stability import CoupledStep, StabilityReport, assess
from hybridwsi.hydro import coefficients
from hybridwsi.surrogate import _decay_kernel
from hybridwsi.surrogate.multistep import rk4_step

if TYPE_CHECKING:  # the set-up's module imports this one
    from hybridwsi.surrogate.kramer import KramerSetup


#: names of the structured model's coefficients, in the order of :func:`structured_columns`
STRUCTURED_TERMS = ("a1", "a2", "b1", "b2", "k1", "k3")
STRUCTURED_UNITS = {"a1": "kg/m", "a2": "kg/m^2", "b1": "N s/m", "b2": "N s^2/m^2",
                    "k1": "N/m", "k3": "N/m^3"}
#: measured samples right after release left out of every fit [s]: the Savitzky–Golay
#: derivatives there come from the polynomial of the first window across the release jerk
RELEASE_SKIP = 0.03


def fit_rows(hist: xr.Dataset, setup: KramerSetup) -> np.ndarray:
    """Boolean mask of the samples a residual fit uses (after ``RELEASE_SKIP``)."""
    return hist["time"].values >= RELEASE_SKIP


# --------------------------------------------------------------------- structured model
def structured_columns(z: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Regressors of the structured residual, ``F_res = columns @ coef`` (n, 6) [N per unit]."""
    return np.column_stack([-z * a, -z * z * a, -v, -np.abs(v) * v, -z, -z ** 3])


@dataclass
class StructuredResidual:
    """``F_res = −(a₁ z + a₂ z²) z̈ − b₁ ż − b₂ |ż| ż − k₁ z − k₃ z³`` [N], fitted by least squares.

    Attributes
    ----------
    coef : ndarray
        ``a1 [kg/m], a2 [kg/m²], b1 [N s/m], b2 [N s²/m²], k1 [N/m], k3 [N/m³]``.
    trained_on : list of str
        The drops whose samples entered the fit.
    n_samples : int
        Samples in the fit.
    """

    coef: np.ndarray = field(default_factory=lambda: np.zeros(len(STRUCTURED_TERMS)))
    trained_on: list[str] = field(default_factory=list)
    n_samples: int = 0

    @classmethod
    def fit(cls, hists: Sequence[xr.Dataset], setup: KramerSetup) -> StructuredResidual:
        """Least squares of ``F_bb`` on :func:`structured_columns` over ``hists``.

        Each drop's rows are divided by its drop height so that every drop weighs the same in
        the fit, as in the error measure (heave / H0).
        """
        xs, ys = [], []
        for h in hists:
            rows = fit_rows(h, setup)
            w = 1.0 / float(h.attrs["drop_height_m"])
            z, v, a = (h[k].values[rows, 0] for k in ("z", "zdot", "zddot"))
            xs.append(w * structured_columns(z, v, a))
            ys.append(w * h["F_bb"].values[rows, 0])
        x, y = np.concatenate(xs), np.concatenate(ys)
        scale = np.sqrt(np.mean(x ** 2, axis=0))  # column scaling: terms differ by 1e6
        coef = np.linalg.lstsq(x / scale, y, rcond=None)[0] / scale
        return cls(coef, [str(h.attrs["drop"]) for h in hists], int(y.size))

    def mass_change(self, z: float) -> float:
        """Added-mass change ``a₁ z + a₂ z²`` [kg] at heave ``z`` [m]."""
        return float(self.coef[0] * z + self.coef[1] * z * z)

    def force(self, z: float, v: float) -> float:
        """The residual force without its acceleration part [N]."""
        _, _, b1, b2, k1, k3 = self.coef
        return float(-b1 * v - b2 * abs(v) * v - k1 * z - k3 * z ** 3)

    def linearised(self, amplitude: float, omega: float) -> dict[str, float]:
        """α, β, γ of ``F_res`` at equilibrium [kg, N s/m, N/m]; the quadratic drag as the
        equivalent linear damping of an oscillation of ``amplitude`` [m] at ``omega`` [rad/s]
        (``8/(3π) b₂ ω A``). Sign convention of the diagnostic: ``F ≈ α z̈ + β ż + γ z``.
        """
        b_eq = self.coef[2] + 8.0 / (3.0 * np.pi) * self.coef[3] * omega * amplitude
        return {"alpha": 0.0, "beta": float(-b_eq), "gamma": float(-self.coef[4])}

    def stability(self, setup: KramerSetup) -> StabilityReport:
        """Predicted stability of the hybrid about equilibrium (a ``StabilityReport``, no Δt:
        its ``stable`` is the continuous setting's).

        The residual linearised at zero amplitude (:meth:`linearised`) on the one-frequency
        Cummins model at the natural frequency ω = 2π/Te0, ``(m + A(ω)) z̈ + B(ω) ż + C z``:
        the radiation damping must be there, or any small negative b₁ (which B(ω) ≈ 14 N s/m
        absorbs) would be predicted unstable.
        """
        w = 2 * np.pi / setup.te0
        lin = self.linearised(0.0, w)
        return assess(CoupledStep(
            setup.mass, known_mass=coefficients.at_frequency(setup.coeffs, "added_mass", w),
            known_damping=coefficients.at_frequency(setup.coeffs, "radiation_damping", w),
            known_stiffness=setup.stiffness, alpha=lin["alpha"], beta=lin["beta"],
            gamma=lin["gamma"]))

    def to_dict(self) -> dict[str, Any]:
        return {"coefficients": {k: float(c) for k, c in zip(STRUCTURED_TERMS, self.coef)},
                "units": STRUCTURED_UNITS, "trained_on": self.trained_on,
                "n_samples": self.n_samples}


def integrate_decay(setup: KramerSetup, h0: float | np.ndarray,
                    coef: np.ndarray | None = None, duration: float | None = None,
                    dt: float | None = None, added_mass: Any | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Free decays from rest at ``h0`` [m] with the known physics plus a structured residual.

    ``(m + A∞ + a(z)) z̈ = F_hs,exact(z) − C_r x + F_res(z, ż)``, ``ẋ = A_r x + B_r ż`` (RK4):
    the Cummins equation of :func:`hybridwsi.cummins.simulate` (``nonlinear_hydrostatics=True``;
    with ``coef`` None the two agree to round-off) plus the structured residual, whose
    position-dependent mass the constant-mass solver there cannot carry. Batched: ``h0`` (n,)
    and ``coef`` (n, 6) (:data:`STRUCTURED_TERMS`) run n decays in one loop.

    With ``added_mass`` (an object whose ``evaluate(z)`` returns A∞(z) [kg] and dA∞/dz [kg/m],
    e.g. ``scripts/kramer_structure_variants.py``'s Capytaine table) the constant A∞ is
    replaced by A∞(z), and the whole position-dependent mass
    ``M(z) = m + A∞(z) + a(z)`` enters in Lagrangian form,
    ``M(z) z̈ + ½ M'(z) ż² = F``: the kinetic energy ½ M(z) ż² is then conserved by the inertia
    terms (a plain ``M(z) z̈`` would create energy as the sphere re-enters the water).

    Returns
    -------
    t : ndarray (nt,)
        Time [s].
    z : ndarray (n, nt) or (nt,) for a scalar ``h0``
        Heave [m]; NaN from where a run left the range where the sphere floats.
    """
    dt = float(dt or setup.dt)
    duration = float(duration or setup.duration)
    scalar = np.ndim(h0) == 0
    h0 = np.atleast_1d(np.asarray(h0, dtype=float))
    n_run = h0.size
    c = np.zeros((n_run, len(STRUCTURED_TERMS))) if coef is None else \
        np.broadcast_to(np.asarray(coef, dtype=float), (n_run, len(STRUCTURED_TERMS)))
    a1, a2, b1, b2, k1, k3 = c.T
    r = float(setup.body.radius)
    z_tab, f_tab = setup.hydrostatic_table()
    ss = setup.memory.ss
    ar, br, cr = ss.A, ss.B[:, 0], ss.C[0]
    m0 = setup.mass + setup.added_mass_inf
    lagrangian = added_mass is not None

    def rhs(y: np.ndarray) -> np.ndarray:
        z, v, x = y[:, 0], y[:, 1], y[:, 2:]
        f = np.interp(z, z_tab, f_tab) - x @ cr - b1 * v - b2 * np.abs(v) * v - k1 * z \
            - k3 * z ** 3
        mass = m0 + a1 * z + a2 * z * z
        if lagrangian:
            a_z, da_z = added_mass.evaluate(z)
            mass = mass - setup.added_mass_inf + a_z
            f = f - 0.5 * (da_z + a1 + 2.0 * a2 * z) * v * v
        return np.column_stack((v, f / mass, x @ ar.T + np.outer(v, br)))

    n = int(round(duration / dt))
    t = np.arange(n + 1) * dt
    if _decay_kernel.HAVE_NUMBA and not lagrangian:  # the same loop compiled (~50x faster)
        zs = _decay_kernel.structured_decays(
            *(np.ascontiguousarray(a, dtype=float) for a in (z_tab, f_tab, ar, br, cr)),
            float(m0), np.ascontiguousarray(c), h0, dt, n, r)
        return t, (zs[0] if scalar else zs)
    y = np.zeros((n_run, 2 + ar.shape[0]))  # (z, ż, x)
    y[:, 0] = h0
    zs = np.full((n_run, n + 1), np.nan)
    zs[:, 0] = h0
    alive = np.ones(n_run, bool)
    for k in range(n):
        y = rk4_step(rhs, y, dt)
        z = y[:, 0]
        alive &= np.isfinite(z) & (np.abs(z) <= r)  # left the water / diverged
        zs[alive, k + 1] = z[alive]
        if not alive.any():
            break
    return t, (zs[0] if scalar else zs)


def fit_output_error(setup: KramerSetup, targets: dict[str, tuple[np.ndarray, np.ndarray]],
                     coef0: np.ndarray, free: Sequence[str], *, dt: float = 0.004,
                     duration: float | None = None, fit_lead: bool = False,
                     added_mass: Any | None = None, max_nfev: int = 40
                     ) -> tuple[np.ndarray, float, dict[str, Any]]:
    """Refine the structured coefficients by least squares on the simulated heave.

    It reads better whole: its closures (coefficient scaling, residuals, the cached batched
    finite-difference Jacobian) share the fit's state and make sense only together.

    Minimises Σ_drops Σ_t (z_model(t)/H0 − z_meas(t)/H0)² over the ``free`` coefficients
    (others stay at ``coef0``): the simulation error, not the one-step force error, so
    derivative errors of the measured z do not bias the fit. The Jacobian is by forward
    differences, all perturbed runs batched in one :func:`integrate_decay` call.

    Parameters
    ----------
    targets : dict
        ``{drop: (t [s], z / H0 [-])}`` of the *training* drops only.
    coef0 : ndarray (6,)
        Start (e.g. the one-step least-squares fit).
    free : sequence of str
        Names from :data:`STRUCTURED_TERMS` to fit.
    dt, duration : float
        RK4 step and length [s] of the fitting runs.
    added_mass : object, optional
        Position-dependent A∞(z) of the known physics (:func:`integrate_decay`).
    fit_lead : bool
        Also fit one release lead δ [s] shared by the drops (the model released at
        t = −δ on the data's clock: the experiment's t = 0 is a release detection on a 2-ms
        sampled record).
    max_nfev : int
        Evaluation budget of the Levenberg–Marquardt solver (each evaluation is one batched
        run of the base and the perturbed models).

    Returns
    -------
    coef : ndarray (6,)
    lead : float
        δ [s] (0 unless ``fit_lead``).
    info : dict
    """
    from scipy.optimize import least_squares

    idx = [STRUCTURED_TERMS.index(k) for k in free]
    drops = list(targets)
    h0 = np.array([setup.drop_heights[d] for d in drops])
    t_end = min(float(targets[d][0][-1]) for d in drops)
    duration = float(duration or t_end)
    scale = np.array([10.0, 100.0, 1.0, 1.0, 10.0, 1e4])[idx]  # typical sizes, for the step
    n_c = len(idx)

    def coefs(p: np.ndarray) -> np.ndarray:
        c = np.array(coef0, dtype=float)
        c[idx] = p[:n_c] * scale
        return c

    def lead_of(p: np.ndarray) -> float:
        return float(p[n_c]) * 1e-3 if fit_lead else 0.0

    def residuals(z_runs: np.ndarray, t: np.ndarray, lead: float) -> np.ndarray:
        out = []
        for k, d in enumerate(drops):
            te, ze = targets[d]
            sel = (te >= 0) & (te <= duration - 0.05)  # fixed rows; |δ| < 50 ms
            zi = np.interp(te[sel] + lead, t, z_runs[k] / h0[k])
            out.append(np.where(np.isfinite(zi), zi - ze[sel], 10.0))  # a crash costs a lot
        return np.concatenate(out)

    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def evaluate(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = p.tobytes()
        if key not in cache:
            eps = 1e-4 * np.maximum(np.abs(p), 1.0)
            ps = [p] + [p + e * np.eye(p.size)[i] for i, e in enumerate(eps)]
            c = np.repeat(np.stack([coefs(q) for q in ps]), len(drops), axis=0)
            t, z = integrate_decay(setup, np.tile(h0, len(ps)), c, duration=duration, dt=dt,
                                   added_mass=added_mass)
            r = [residuals(z[j * len(drops):(j + 1) * len(drops)], t, lead_of(q))
                 for j, q in enumerate(ps)]
            jac = np.column_stack([(r[i + 1] - r[0]) / eps[i] for i in range(p.size)])
            cache.clear()
            cache[key] = (r[0], jac)
        return cache[key]

    p0 = np.asarray(coef0, dtype=float)[idx] / scale
    if fit_lead:
        p0 = np.append(p0, 0.0)  # δ in ms
    sol = least_squares(lambda p: evaluate(p)[0], p0, jac=lambda p: evaluate(p)[1],
                        method="lm", max_nfev=int(max_nfev))
    info = {"cost_start": float(0.5 * np.sum(evaluate(p0)[0] ** 2)), "cost": float(sol.cost),
            "nfev": int(sol.nfev), "status": int(sol.status), "free": list(free),
            "drops": drops, "n_points": int(sol.fun.size),
            "rms_fit": float(np.sqrt(2 * sol.cost / sol.fun.size))}
    return coefs(sol.x), lead_of(sol.x), info
