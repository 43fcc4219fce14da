"""Force-sensitivity regression of the black-box force (paper Eq. 5–7, docs/THEORY.md §2–3).

``F_bb = F_force − Σ F_known`` on the reference history is fitted as

    F_bb,i(t) ≈ F̄_i + Σ_j α_ij z̈_j(t) + β_ij ż_j(t) + γ_ij z_j(t)

with an intercept (docs/THEORY.md §2: centring only the force biases α, β, γ whenever the
kinematics have a non-zero window mean). Numerics: the regressor columns are centred (which is
exactly the intercept fit) and scaled to unit norm, and the system is solved through the SVD of
that matrix (minimum-norm solution when it is rank-deficient), never via the normal equations.

Uncertainty: residuals of a time series are autocorrelated, so standard errors are
heteroskedasticity- and autocorrelation-consistent (HAC, Newey–West with the Bartlett kernel).
The lag is ``max(floor(4 (n/100)^(2/9)), Andrews' AR(1) plug-in)`` unless given (Andrews 1991,
Econometrica 59: 817–858), so smooth residuals (e.g. from filtered derivatives) get long lags.

Identifiability (docs/THEORY.md §3 and §3b) is reported, not assumed.
Noise-free data always give tiny standard errors, so the verdict rests on a stated force
accuracy: for every coefficient the smallest relative force error that moves it by 10 %
(:func:`force_error_for_shift`) is compared with ``force_accuracy`` (default 1 %, the usual
accuracy of CFD/SPH forces). Also reported: singular values and condition number of the centred,
column-normalised regressor matrix (the intercept column excluded), the normalised standard
errors, and — when the split is not identifiable — the combinations the data do determine: for
near-single-frequency motion the dynamic stiffness ``γ − ω² α`` and the damping ``β`` at the
dominant frequency; for rank-deficient data (free decay of a linear system) the null-space
direction along which (α, β, γ) can move without changing the fit.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.signal
import xarray as xr

from hybridwsi.dofs import coefficient_unit, force_unit
from hybridwsi.errors import InputError
from hybridwsi.forces import (
    KnownComponent,
    as_matrix,
    black_box_force,
    parse_known,
)
from hybridwsi.history import check_regressors, validate

#: condition number of the column-normalised regressors above which a singular direction counts
#: as weak when deciding which combinations are determined (no longer part of the verdict:
#: the force-accuracy test below is the quantitative version of it)
COND_MAX = 1e3
#: default relative force accuracy (RMS error / RMS of the centred force): ~1 % for CFD/SPH
FORCE_ACCURACY = 0.01
#: relative shift of α or γ that counts as "moved" in the force-accuracy test
SHIFT = 0.1
#: normalised standard error (see ``regress``) of α or γ above which the split is not identifiable
REL_STDERR_MAX = 0.05
#: singular-value ratio below which the regressors count as linearly dependent (rank-deficient)
RANK_RTOL = 1e-7
#: share of the motion's spectral power near the peak above which the motion is "single-frequency"
SINGLE_FREQ_SHARE = 0.9
#: two-sided 95 % normal quantile
Z95 = 1.959963984540054
_TERMS = ("alpha", "beta", "gamma")
_SYMBOL = {"alpha": "α", "beta": "β", "gamma": "γ"}
_QUANTITY = {"alpha": "mass", "beta": "damping", "gamma": "stiffness"}


def coefficient_units(dofs: Sequence[str], term: str) -> list[list[str]]:
    """Units of the (influenced i, radiating j) entries of ``alpha``/``beta``/``gamma``.

    ``"?"`` for a DOF name outside Capytaine's six (histories do not enforce the names).
    """

    def unit(i: str, j: str) -> str:
        try:
            return coefficient_unit(i, j, _QUANTITY[term])
        except InputError:
            return "?"

    return [[unit(i, j) for j in dofs] for i in dofs]


def _unit_label(dofs: Sequence[str], term: str) -> str:
    """One unit when all DOF pairs share it, else a pointer to the per-pair units."""
    units = {u for row in coefficient_units(dofs, term) for u in row}
    return units.pop() if len(units) == 1 else f"units of {_SYMBOL[term]} per DOF pair"


@dataclass
class RegressionResult:
    """Force sensitivities of ``F_bb`` and how well the data determine them.

    Units are per DOF pair (influenced i, radiating j), from
    :func:`hybridwsi.dofs.coefficient_unit`: e.g. Heave–Heave α [kg], β [N s/m], γ [N/m];
    Pitch–Pitch α [kg m^2], β [N m s/rad], γ [N m/rad] (:meth:`units`).

    Attributes
    ----------
    alpha, beta, gamma : ndarray, shape (n_dof, n_dof)
        ``∂F_bb,i/∂z̈_j``, ``∂F_bb,i/∂ż_j``, ``∂F_bb,i/∂z_j`` (mass, damping, stiffness units).
    mean_force : ndarray, shape (n_dof,)
        Intercept F̄ [N or N m].
    stderr : dict of str to ndarray
        HAC standard errors of ``alpha``, ``beta``, ``gamma`` (and ``mean_force``); a fixed α has
        zero standard error.
    ci95 : dict of str to ndarray
        95 % intervals, arrays of shape (n_dof, n_dof, 2) (lower, upper).
    r2 : ndarray, shape (n_dof,)
        Coefficient of determination of the full model per DOF.
    singular_values : ndarray
        Singular values of the centred, column-normalised regressor matrix (no intercept column).
    condition_number : float
        Their ratio max/min (inf when a column is constant).
    identifiable : bool
        Every influenced DOF is identifiable (``identifiable_dof``).
    identifiable_combinations : list of dict
        When not identifiable: ``dynamic_stiffness`` (``value``, ``stderr``, ``omega``),
        ``damping`` and/or ``null_direction``/``weakest_direction`` entries.
    warnings : list of str
        Plain-language warnings.
    dominant_omega : float or None
        Spectral peak of z [rad/s] (interpolated), None when z has no oscillation.
    force_accuracy : ndarray, shape (n_dof,)
        Relative accuracy assumed for the force on each DOF (RMS error / RMS of the centred
        force ``hist[force]``).
    force_error_10pct : ndarray, shape (n_dof,)
        Per influenced DOF i: the smallest relative error of the force on i that moves one of
        ``alpha[i, :]``, ``gamma[i, :]`` by 10 % (:func:`force_error_for_shift`); 0 when the
        split is not unique, inf when nothing can move (α fixed and γ free of the data).
    force_error_terms : dict of str to ndarray
        The same per entry, ``"alpha"`` and ``"gamma"``, shape (n_dof, n_dof) (inf for a fixed α).
    identifiable_dof : ndarray of bool, shape (n_dof,)
        ``force_error_10pct > force_accuracy`` and normalised stderr of α and γ below
        ``REL_STDERR_MAX``.
    """

    alpha: np.ndarray
    beta: np.ndarray
    gamma: np.ndarray
    mean_force: np.ndarray
    stderr: dict[str, np.ndarray]
    ci95: dict[str, np.ndarray]
    r2: np.ndarray
    singular_values: np.ndarray
    condition_number: float
    identifiable: bool
    identifiable_combinations: list[dict[str, Any]]
    warnings: list[str]
    dominant_omega: float | None
    n_samples: int
    force: str
    known: list[str]
    dof: list[str] = field(default_factory=lambda: ["Heave"])
    fixed_alpha: bool = False
    hac_lags: int = 0
    normalised_stderr: dict[str, float] = field(default_factory=dict)
    force_accuracy: np.ndarray = field(default_factory=lambda: np.array([FORCE_ACCURACY]))
    force_error_10pct: np.ndarray = field(default_factory=lambda: np.array([np.nan]))
    force_error_terms: dict[str, np.ndarray] = field(default_factory=dict)
    identifiable_dof: np.ndarray = field(default_factory=lambda: np.array([False]))

    @property
    def n_dof(self) -> int:
        return self.alpha.shape[0]

    def coefficients(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(alpha, beta, gamma)`` as (n_dof, n_dof) matrices."""
        return self.alpha, self.beta, self.gamma

    def units(self) -> dict[str, list[list[str]]]:
        """Units of ``alpha``, ``beta``, ``gamma`` per (influenced, radiating) DOF pair."""
        return {k: coefficient_units(self.dof, k) for k in _TERMS}

    def _shape(self, arr: Any) -> Any:
        """JSON form: floats for 1 DOF, nested lists for n DOF (recursively)."""
        if isinstance(arr, dict):
            return {k: self._shape(v) for k, v in arr.items()}
        a = np.asarray(arr, dtype=float)
        if self.n_dof == 1 and a.ndim <= 2 and a.size == 1:
            return _json_float(a.reshape(-1)[0])
        if self.n_dof == 1 and a.ndim == 3:  # ci95: (1, 1, 2) -> [lo, hi]
            a = a.reshape(-1)
        return _json_list(a)

    def _per_dof(self, arr: Any) -> Any:
        """JSON form of a per-DOF vector: a float for 1 DOF, else a list."""
        return _json_float(arr[0]) if self.n_dof == 1 else _json_list(arr)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (floats for 1 DOF, nested lists for n DOF; inf/NaN -> None)."""
        units = self.units()
        return {
            "force": self.force,
            "known": list(self.known),
            "dof": list(self.dof),
            "n_samples": self.n_samples,
            "alpha": self._shape(self.alpha),
            "beta": self._shape(self.beta),
            "gamma": self._shape(self.gamma),
            "units": {k: u[0][0] if self.n_dof == 1 else u for k, u in units.items()},
            "mean_force": self._per_dof(self.mean_force),
            "stderr": {k: self._shape(self.stderr[k]) for k in _TERMS},
            "ci95": {k: self._shape(self.ci95[k]) for k in _TERMS},
            "r2": self._per_dof(self.r2),
            "singular_values": _json_list(self.singular_values),
            "condition_number": _json_float(self.condition_number),
            "identifiable": bool(self.identifiable),
            "identifiable_dof": [bool(v) for v in self.identifiable_dof],
            "force_accuracy": self._per_dof(self.force_accuracy),
            "force_error_10pct": self._per_dof(self.force_error_10pct),
            "force_error_10pct_terms": {k: self._shape(v)
                                        for k, v in self.force_error_terms.items()},
            "identifiable_combinations": [
                {k: (v if isinstance(v, str) else self._shape(v)) for k, v in c.items()}
                for c in self.identifiable_combinations
            ],
            "warnings": list(self.warnings),
            "dominant_omega": _json_float(self.dominant_omega),
            "fixed_alpha": self.fixed_alpha,
            "hac_lags": self.hac_lags,
            "normalised_stderr": {k: _json_float(v) for k, v in self.normalised_stderr.items()},
        }

    def to_table(self) -> str:
        """Readable text table of the coefficients, their 95 % intervals and the diagnostics."""
        lines = [f"F_bb = {self.force}" + "".join(f" - {k}" for k in self.known)
                 + f"   ({self.n_samples} samples, HAC lag {self.hac_lags})"]
        pair_w = max(len(f"{i},{j}") for i in self.dof for j in self.dof) + 2
        header = (f"{'term':<18}{'i,j':<{pair_w}}{'value':>14}{'stderr':>12}"
                  f"{'95% interval':>30}")
        lines += [header, "-" * len(header)]
        units = self.units()
        for name in _TERMS:
            val, se, ci = getattr(self, name), self.stderr[name], self.ci95[name]
            for i, di in enumerate(self.dof):
                for j, dj in enumerate(self.dof):
                    label = f"{_SYMBOL[name]} [{units[name][i][j]}]"
                    lines.append(
                        f"{label:<18}{f'{di},{dj}':<{pair_w}}{val[i, j]:>14.6g}{se[i, j]:>12.3g}"
                        f"{f'[{ci[i, j, 0]:.5g}, {ci[i, j, 1]:.5g}]':>30}"
                    )
        fbar = ", ".join(f"{v:.6g} {_force_unit(d)}" for v, d in zip(self.mean_force, self.dof))
        lines.append(f"F̄ = {fbar};  R² = {', '.join(f'{v:.6f}' for v in self.r2)}")
        sv = ", ".join(f"{v:.3g}" for v in self.singular_values)
        lines.append(f"singular values = [{sv}];  condition number = {self.condition_number:.3g}")
        for i, d in enumerate(self.dof):
            lines.append(
                f"{d}: a force error of {_percent(self.force_error_10pct[i])} moves α or γ by "
                f"10 %; assumed force accuracy {_percent(self.force_accuracy[i])} -> "
                f"identifiable = {bool(self.identifiable_dof[i])}"
            )
        omega = "n/a" if self.dominant_omega is None else f"{self.dominant_omega:.6g} rad/s"
        lines.append(f"identifiable = {self.identifiable};  dominant ω = {omega}")
        for comb in self.identifiable_combinations:
            if "value" in comb:
                txt = np.array2string(np.asarray(comb["value"], dtype=float), precision=6)
            else:  # a direction in (α, β, γ) space
                txt = ", ".join(
                    f"Δ{_SYMBOL[k]} {np.array2string(np.asarray(comb[k]), precision=6)}"
                    for k in _TERMS if k in comb
                )
            if comb.get("stderr") is not None:
                txt += " ± " + np.array2string(np.asarray(comb["stderr"], dtype=float), precision=3)
            lines.append(f"  {comb['name']}: {txt}" + (f"  ({comb['note']})" if "note" in comb else ""))
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)


def _force_unit(dof: str) -> str:
    """N or N m for a rigid-body DOF, ``?`` for a name outside Capytaine's six."""
    try:
        return force_unit(dof)
    except InputError:
        return "?"


def _percent(x: float) -> str:
    """A relative error as a percentage with 2 significant digits (inf/NaN spelled out)."""
    x = float(x)
    return f"{100 * x:.2g} %" if math.isfinite(x) else ("any size" if x > 0 else "n/a")


def _json_float(x: Any) -> float | None:
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def _json_list(a: Any) -> Any:
    a = np.asarray(a, dtype=float)
    if a.ndim == 0:
        return _json_float(a)
    return [_json_list(v) for v in a]


def as_components(known: Iterable[KnownComponent | str] | None) -> list[KnownComponent]:
    """Known components from objects or ``"NAME=VALUE"`` strings (see ``parse_known``)."""
    out: list[KnownComponent] = []
    for k in known or ():
        if isinstance(k, str):
            out.append(parse_known(k))
        elif isinstance(k, KnownComponent):
            out.append(k)
        else:
            raise InputError(f"known components must be KnownComponent or 'NAME=VALUE', got {k!r}")
    return out


def kinematics(hist: xr.Dataset, names: Sequence[str] = ("z", "zdot", "zddot")) -> list[np.ndarray]:
    """Kinematic arrays (n_time, n_dof) of a history, with a clear error when one is missing."""
    out = []
    for name in names:
        if name not in hist:
            raise InputError(
                f"history has no '{name}'; estimate the derivatives of z first "
                "(e.g. a Savitzky-Golay filter) and store them as 'zdot'/'zddot'"
            )
        out.append(np.asarray(hist[name].values, dtype=float))
    return out


# --------------------------------------------------------------------------- HAC covariance
def newey_west_lag(n: int) -> int:
    """Newey–West (1994) rule-of-thumb lag ``floor(4 (n/100)^(2/9))``."""
    return int(math.floor(4.0 * (n / 100.0) ** (2.0 / 9.0)))


def andrews_lag(scores: np.ndarray) -> int:
    """Andrews (1991) AR(1) plug-in lag for the Bartlett kernel, ``1.1447 (α̂(1) n)^(1/3)``.

    Each score column is fitted with an AR(1) model; columns are weighted equally.
    """
    g = np.ascontiguousarray((scores - scores.mean(axis=0)).T)  # rows: contiguous series
    n = g.shape[1]
    den0 = np.einsum("ij,ij->i", g[:, :-1], g[:, :-1])
    ok = den0 > 0
    if not ok.any():
        return 0
    g = g[ok]
    cross = np.einsum("ij,ij->i", g[:, 1:], g[:, :-1])
    rho = np.clip(cross / den0[ok], -0.999, 0.999)  # AR(1) must be stationary
    # variance of the AR(1) innovations, sum((g1 - rho g0)^2)/(n-1), expanded
    g1sq = np.einsum("ij,ij->i", g[:, 1:], g[:, 1:])
    s2 = (g1sq - 2 * rho * cross + rho**2 * den0[ok]) / (n - 1)
    s2 = np.maximum(s2, 0.0)
    num = np.sum(4 * rho**2 * s2**2 / ((1 - rho) ** 6 * (1 + rho) ** 2))
    den = np.sum(s2**2 / (1 - rho) ** 4)
    if den <= 0:
        return 0
    return int(math.ceil(1.1447 * (num / den * n) ** (1.0 / 3.0)))


def hac_meat(scores: np.ndarray, lags: int) -> np.ndarray:
    """Bartlett-weighted long-run sum ``Σ_t Σ_s w(t−s) g_t g_sᵀ`` of scores (n, k).

    ``w(l) = max(0, 1 − |l|/(lags+1))``; not divided by n. The Bartlett kernel is the
    autocorrelation of a box of ``lags+1`` ones, so the sum equals
    ``Σ_u S_u S_uᵀ / (lags+1)`` with ``S_u`` the moving sums of ``lags+1`` consecutive scores
    (partial at the ends): O(n k²) whatever the lag.
    """
    n, k = scores.shape
    lags = int(min(max(lags, 0), n - 1))
    if lags == 0:
        return scores.T @ scores
    csum = np.zeros((n + 1, k))
    np.cumsum(scores, axis=0, out=csum[1:])
    w = lags + 1
    # windows starting at u = -lags..n-1: partial head, full middle, partial tail
    head = csum[1:w]  # u < 0: sums of g[0 .. u+lags]
    mid = csum[w:] - csum[: n + 1 - w]  # full windows
    tail = csum[n] - csum[n + 1 - w : n]  # sums of g[u .. n-1]
    meat = head.T @ head + mid.T @ mid + tail.T @ tail
    return meat / w


# --------------------------------------------------------------------------- spectrum of z
def _spectral_power(z: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hann-windowed periodogram of the detrended columns of z, normalised per column."""
    zc = scipy.signal.detrend(z, axis=0, type="linear")
    win = scipy.signal.windows.hann(z.shape[0], sym=False)
    spec = np.abs(np.fft.rfft(zc * win[:, None], axis=0)) ** 2
    tot = spec.sum(axis=0)
    spec = spec[:, tot > 0] / tot[tot > 0]
    omega = 2 * np.pi * np.fft.rfftfreq(z.shape[0], dt)
    return omega, spec.sum(axis=1), zc * win[:, None]


def dominant_frequency(
    z: np.ndarray, dt: float, *, refine: bool = False, band_rtol: float = 0.05
) -> tuple[float | None, float]:
    """Dominant angular frequency [rad/s] of z (n, n_dof) and the share of power near it.

    The peak of the Hann-windowed periodogram is located by parabolic interpolation of the log
    power over three bins; with ``refine`` the windowed DTFT magnitude is then maximised
    continuously within ±1 bin (accurate to ~1e-7 relative for a pure sinusoid).
    The share counts power within ``max(band_rtol ω, 3 Δω)`` of the peak.
    """
    omega, power, zw = _spectral_power(z, dt)
    if power.size < 4 or not np.any(power[1:] > 0):
        return None, 0.0
    k = int(np.argmax(power[1:-1])) + 1
    dw = omega[1] - omega[0]
    lp = np.log(np.maximum(power[k - 1 : k + 2], 1e-300))
    curv = lp[0] - 2 * lp[1] + lp[2]
    shift = 0.5 * (lp[0] - lp[2]) / curv if curv < 0 else 0.0
    w0 = omega[k] + float(np.clip(shift, -0.5, 0.5)) * dw
    if refine:
        t = np.arange(z.shape[0]) * dt
        scale = np.linalg.norm(zw, axis=0)
        zn = zw[:, scale > 0] / scale[scale > 0]

        def neg_power(w: float) -> float:
            return -float(np.sum(np.abs(np.exp(-1j * w * t) @ zn) ** 2))

        res = scipy.optimize.minimize_scalar(
            neg_power, bounds=(max(w0 - dw, 0.5 * w0), w0 + dw), method="bounded",
            options={"xatol": 1e-10 * w0},
        )
        w0 = float(res.x)
    band = max(band_rtol * w0, 3 * dw)
    share = float(power[np.abs(omega - w0) <= band].sum() / power.sum())
    return w0, share


# --------------------------------------------------------------------------- regression
@dataclass
class _Fit:
    coef: np.ndarray  # (p, n_out) physical slopes
    intercept: np.ndarray  # (n_out,)
    cov: list[np.ndarray]  # per output, (p+1, p+1) covariance of [F̄, slopes]
    sv: np.ndarray
    vt: np.ndarray  # right singular vectors (normalised coordinates)
    scale: np.ndarray
    resid: np.ndarray
    lags: int
    free: np.ndarray  # (p,) bool: slope undetermined (rank-deficient direction)


def _fit(x: np.ndarray, y: np.ndarray, hac_lags: int | None) -> _Fit:
    """Least squares of y (n, q) on [1, x] (n, p) via the SVD of centred, normalised x."""
    n, p = x.shape
    xm, ym = x.mean(axis=0), y.mean(axis=0)
    xc = x - xm
    scale = np.linalg.norm(xc, axis=0)
    safe = np.where(scale > 0, scale, 1.0)
    xn = xc / safe
    u, sv, vt = scipy.linalg.svd(xn, full_matrices=False, check_finite=False)
    keep = sv > max(n, p) * np.finfo(float).eps * (sv[0] if sv.size else 0.0)
    inv_sv = np.where(keep, 1.0 / np.where(keep, sv, 1.0), 0.0)
    yc = y - ym
    coef_n = vt.T @ (inv_sv[:, None] * (u.T @ yc))  # (p, q) minimum-norm solution
    resid = yc - xn @ coef_n
    # bread (D'D)^+ of the design D = [1, xn]: block-diagonal because xn is centred
    bread = np.zeros((p + 1, p + 1))
    bread[0, 0] = 1.0 / n
    bread[1:, 1:] = (vt.T * inv_sv**2) @ vt
    # map [c0, coef_n] -> [F̄, slopes]: slopes = coef_n/scale, F̄ = c0 - xm·slopes
    tmap = np.zeros((p + 1, p + 1))
    tmap[0, 0] = 1.0
    tmap[0, 1:] = -xm / safe
    tmap[1:, 1:] = np.diag(1.0 / safe)
    lags_used = 0
    covs = []
    dof_corr = n / max(n - (p + 1), 1)
    for i in range(y.shape[1]):
        scores = np.empty((n, p + 1))
        scores[:, 0] = resid[:, i]
        np.multiply(xn, resid[:, i : i + 1], out=scores[:, 1:])
        lags = (
            int(hac_lags)
            if hac_lags is not None
            else max(newey_west_lag(n), andrews_lag(scores))
        )
        lags = min(lags, n // 2)
        lags_used = max(lags_used, lags)
        cov_n = bread @ hac_meat(scores, lags) @ bread * dof_corr
        covs.append(tmap @ cov_n @ tmap.T)
    coef = coef_n / safe[:, None]
    intercept = ym - xm @ coef
    # slopes that move along an exact null direction are undetermined (infinite stderr)
    null = vt[sv <= RANK_RTOL * (sv[0] if sv.size else 0.0)]
    free = np.any(np.abs(null) > 1e-6, axis=0) if null.size else np.zeros(p, dtype=bool)
    return _Fit(coef, intercept, covs, sv, vt, safe, resid, lags_used, free)


def force_error_for_shift(
    sv: np.ndarray,
    vt: np.ndarray,
    coef_n: np.ndarray,
    force_norm: np.ndarray,
    *,
    free: np.ndarray | None = None,
    shift: float = SHIFT,
) -> np.ndarray:
    """Smallest relative force error that moves each fitted slope by ``shift`` (10 %).

    Parameters
    ----------
    sv, vt : ndarray, shapes (r,) and (r, p)
        Singular values and right singular vectors of the centred, column-normalised regressors
        ``X_n = P X D⁻¹ = U S Vᵀ`` (``P`` centring, ``D = diag‖P X_k‖``).
    coef_n : ndarray, shape (p, q)
        Normalised slopes ``θ_n = D θ`` for each of the q influenced DOF (output columns).
    force_norm : ndarray, shape (q,)
        ``‖P F_i‖``: norm of the centred force on DOF i the accuracy refers to [N or N m].
    free : ndarray of bool, shape (p,), optional
        Slopes moved by an exact null direction (rank-deficient data): their error is 0.
    shift : float
        Relative shift that counts (0.1).

    Returns
    -------
    ndarray, shape (p, q)
        ``ε[k, i]``: relative force error ``‖δF_i‖ / ‖P F_i‖`` that moves slope k of DOF i by
        ``shift`` times its reference; NaN when ``‖P F_i‖ = 0``.

    Notes
    -----
    Derivation (docs/THEORY.md §3b). Least squares is linear in the force, so a force
    error ``δF_i`` on DOF i moves the normalised slopes of that DOF (and no other) exactly by

        δθ_n = V S⁻¹ Uᵀ P δF_i = V S⁻¹ Uᵀ δF_i      (the columns of U are centred)

    — a constant error only moves the intercept, hence the centred norms. For slope k,
    ``δθ_n,k = g_kᵀ Uᵀ δF_i`` with ``g_k = S⁻¹ V[:, k]`` (k-th column of Vᵀ scaled by 1/S), so by
    Cauchy–Schwarz the largest move by an error of norm ``ε ‖P F_i‖`` is ``ε ‖P F_i‖ ‖g_k‖``,
    reached by ``δF_i ∝ U g_k``, with ``‖g_k‖² = Σ_m V_km² / S_m²``. The column scale cancels
    in the relative shift (``δθ_k/θ_k = δθ_n,k/θ_n,k``), and ``|θ_n,k| = |θ_k| ‖P X_k‖`` is the
    norm of term k's contribution to the fitted force, so

        ε_k,i = shift · max(|θ_n,k,i|, ‖P F_i‖) / (‖P F_i‖ ‖g_k‖).

    When one singular value is much smaller than the others, ``‖g_k‖ ≈ |V_k,min| / S_min`` and
    the worst error is the weakest direction ``δF ∝ U[:, min]``: ε ≈ shift |θ_n,k| S_min /
    (‖P F_i‖ |V_k,min|). The reference is the larger of the term's contribution and the force:
    a term smaller than the force — in particular a zero one (γ = 0 when nothing is known, a
    zero coupling) — is "moved" when its contribution changes by 10 % of the force, the same
    scale the normalised standard error uses; a term larger than the force (known parts that
    cancel, case 3 near resonance) is judged by its own value.
    """
    sv = np.asarray(sv, dtype=float)
    vt = np.asarray(vt, dtype=float)
    coef_n = np.asarray(coef_n, dtype=float)
    fn = np.asarray(force_norm, dtype=float)
    ok = sv > RANK_RTOL * (sv[0] if sv.size else 0.0)
    gain = np.sqrt(np.sum((vt[ok] / sv[ok, None]) ** 2, axis=0))  # ‖g_k‖, shape (p,)
    if free is not None:
        gain = np.where(free, np.inf, gain)
    with np.errstate(divide="ignore", invalid="ignore"):
        ref = np.maximum(np.abs(coef_n), fn[None, :])
        eps = shift * ref / (fn[None, :] * gain[:, None])
    return np.where(fn[None, :] > 0, eps, np.nan)


def _force_accuracy(value: float | Sequence[float] | np.ndarray, n_dof: int) -> np.ndarray:
    """Per-DOF relative force accuracy from a scalar or one value per DOF."""
    try:
        acc = np.broadcast_to(np.asarray(value, dtype=float).reshape(-1), (n_dof,)).copy()
    except (TypeError, ValueError):
        raise InputError(f"force_accuracy must be a number or one number per DOF ({n_dof}), "
                         f"got {value!r}") from None
    if not np.all(np.isfinite(acc)) or np.any(acc < 0):
        raise InputError(f"force_accuracy must be finite and non-negative, got {value!r}")
    return acc


def _force_errors(
    fit: _Fit, terms: Sequence[str], n_dof: int, force_norm: np.ndarray
) -> dict[str, np.ndarray]:
    """:func:`force_error_for_shift` of α and γ as [influenced, radiating] matrices (inf: fixed)."""
    eps = force_error_for_shift(fit.sv, fit.vt, fit.coef * fit.scale[:, None], force_norm,
                                free=fit.free)
    out = {k: np.full((n_dof, n_dof), np.inf) for k in ("alpha", "gamma")}
    for b, name in enumerate(terms):
        if name in out:
            out[name] = eps[b * n_dof:(b + 1) * n_dof, :].T.copy()
    return out


def _blocks(
    fit: _Fit, n_dof: int, terms: Sequence[str]
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Split stacked slopes / variances into (n_dof, n_dof) matrices per term."""
    val, se, cov_idx = {}, {}, {}
    for b, name in enumerate(terms):
        cols = slice(b * n_dof, (b + 1) * n_dof)
        val[name] = fit.coef[cols, :].T.copy()
        se[name] = np.array(
            [np.sqrt(np.clip(np.diag(c)[1:][cols], 0, None)) for c in fit.cov]
        )
        se[name][:, fit.free[cols]] = np.inf
        cov_idx[name] = np.arange(b * n_dof, (b + 1) * n_dof) + 1
    return val, se, cov_idx


def regress(hist: xr.Dataset, force: str = "F_tot", known: Iterable[KnownComponent | str] = (),
            *, fix_alpha: float | np.ndarray | None = None, hac_lags: int | None = None,
            frequency_tol: float = 0.05,
            force_accuracy: float | Sequence[float] = FORCE_ACCURACY) -> RegressionResult:
    """Regress the black-box force on the reference motion (paper Eq. 5–7 with an intercept).

    Parameters
    ----------
    hist : xarray.Dataset
        TimeHistory with ``z``, ``zdot``, ``zddot`` and the force ``force``.
    force : str
        Name of the total force variable [N] (``m z̈ = F_tot``).
    known : iterable of KnownComponent or "NAME=VALUE"
        Components removed with their physical sign: ``F_bb = hist[force] − Σ known``.
    fix_alpha : float or ndarray, optional
        Fixed α [kg] (e.g. ``m + A∞`` from BEM): ``α z̈`` is subtracted and only
        ``[1, ż, z]`` is regressed (the remedy for single-frequency data, docs/THEORY.md §3).
    hac_lags : int, optional
        Bartlett lag of the Newey–West covariance; default automatic (module docstring).
    frequency_tol : float
        Relative half-width of the band around the spectral peak of z used to decide that the
        motion is single-frequency (≥ 90 % of its power in the band).
    force_accuracy : float or sequence of float
        Relative accuracy of ``hist[force]`` per DOF (RMS error over RMS of the centred force;
        default 0.01, typical of CFD/SPH; use ~1e-6 or less for BEM/Cummins data, whose force is
        exact to the integrator's precision). The split is called identifiable only when a force
        error larger than this is needed to move α or γ by 10 % (:func:`_identifiability`).

    Returns
    -------
    RegressionResult
        ``singular_values`` and ``condition_number`` are those of the centred,
        column-normalised regressor matrix *without* the intercept column.
    """
    validate(hist)
    if hac_lags is not None and (not isinstance(hac_lags, (int, np.integer)) or hac_lags < 0):
        raise InputError(f"hac_lags must be a non-negative integer, got {hac_lags!r}")
    if not 0 < frequency_tol < 1:
        raise InputError(f"frequency_tol must be in (0, 1), got {frequency_tol!r}")
    comps = as_components(known)
    z, zd, zdd = kinematics(hist)
    n, n_dof = z.shape
    accuracy = _force_accuracy(force_accuracy, n_dof)
    f_bb = black_box_force(hist, force, comps)
    # refuse here what would otherwise overflow in the fit (garbage α, β, γ or a NaN lag)
    check_regressors({"z": z, "zdot": zd, "zddot": zdd}, {f"{force} - known": f_bb})
    alpha_fixed = _fixed_alpha(fix_alpha, n_dof)
    fixed = alpha_fixed is not None
    terms = ("beta", "gamma") if fixed else _TERMS
    if n < 3 * len(terms) * n_dof + 2:
        raise InputError(f"{n} samples are too few to regress {len(terms) * n_dof + 1} coefficients")
    y = f_bb - zdd @ alpha_fixed.T if fixed else f_bb
    fit = _fit(np.hstack([zd, z] if fixed else [zdd, zd, z]), y, hac_lags)
    val, se, idx = _blocks(fit, n_dof, terms)
    if fixed:
        val["alpha"], se["alpha"] = alpha_fixed, np.zeros((n_dof, n_dof))
    st = _statistics(fit, val, se, terms, f_bb, {"alpha": zdd, "beta": zd, "gamma": z})
    f_gen = np.asarray(hist[force].values, dtype=float)  # the generator's force (δF_bb = δF)
    ident = _identifiability(fit, terms, n_dof, f_gen, accuracy, st["nse"])
    dofs = [str(d) for d in hist["dof"].values]
    dt = float((hist["time"].values[-1] - hist["time"].values[0]) / (n - 1))
    omega0, combos, warnings_ = _interpretation(hist, force, fit, val, idx, terms, z, dt,
                                                frequency_tol, st, ident, accuracy)
    return RegressionResult(
        alpha=val["alpha"], beta=val["beta"], gamma=val["gamma"], mean_force=fit.intercept,
        stderr={**{k: se[k] for k in _TERMS}, "mean_force": st["mean_se"]}, ci95=st["ci"],
        r2=st["r2"], singular_values=fit.sv, condition_number=st["cond"],
        identifiable=bool(ident["dof"].all()), identifiable_combinations=combos,
        warnings=warnings_, dominant_omega=omega0, n_samples=n, force=force,
        known=[c.describe() for c in comps], dof=dofs, fixed_alpha=fixed, hac_lags=fit.lags,
        normalised_stderr=st["nse"], force_accuracy=accuracy,
        force_error_10pct=ident["eps_dof"], force_error_terms=ident["eps_terms"],
        identifiable_dof=ident["dof"],
    )


def _fixed_alpha(fix_alpha: float | np.ndarray | None, n_dof: int) -> np.ndarray | None:
    """The fixed α (n_dof, n_dof) [kg, kg m, kg m²], or None when α is regressed."""
    if fix_alpha is None:
        return None
    alpha = as_matrix(fix_alpha, n_dof, "fix_alpha")
    if not np.all(np.isfinite(alpha)):
        raise InputError("fix_alpha must be finite")
    return alpha


def _statistics(fit: _Fit, val: dict[str, np.ndarray], se: dict[str, np.ndarray],
                terms: Sequence[str], f_bb: np.ndarray, kin: dict[str, np.ndarray]
                ) -> dict[str, Any]:
    """Standard error of F̄, 95 % intervals, R² per DOF, condition number and the normalised
    standard errors ``‖stderr‖ · rms(centred regressor) / rms(centred F_bb)`` per term."""
    n = f_bb.shape[0]
    mean_se = np.array([math.sqrt(max(c[0, 0], 0.0)) for c in fit.cov])
    ci = {k: np.stack([val[k] - Z95 * se[k], val[k] + Z95 * se[k]], axis=-1) for k in _TERMS}
    pred = (fit.intercept + kin["alpha"] @ val["alpha"].T + kin["beta"] @ val["beta"].T
            + kin["gamma"] @ val["gamma"].T)
    ss_tot = ((f_bb - f_bb.mean(axis=0)) ** 2).sum(axis=0)
    ss_res = ((f_bb - pred) ** 2).sum(axis=0)
    r2 = np.where(ss_tot > 0, 1.0 - ss_res / np.where(ss_tot > 0, ss_tot, 1.0), 1.0)
    sv = fit.sv
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
    f_rms = float(np.sqrt(ss_tot.sum() / n)) or 1.0
    nse = {}
    for k in terms:
        reg_rms = np.sqrt(((kin[k] - kin[k].mean(axis=0)) ** 2).mean(axis=0))  # per DOF j
        nse[k] = float(np.linalg.norm(se[k] * reg_rms[None, :]) / f_rms)
    return {"mean_se": mean_se, "ci": ci, "r2": r2, "cond": cond, "nse": nse}


def _identifiability(fit: _Fit, terms: Sequence[str], n_dof: int, f_gen: np.ndarray,
                     accuracy: np.ndarray, nse: dict[str, float]) -> dict[str, Any]:
    """Per DOF, whether α and γ are identifiable under the stated force accuracy.

    DOF i is identifiable when

    - ``force_error_10pct[i] > force_accuracy[i]``: the smallest relative error of the force on
      i that moves any α_ij or γ_ij by 10 % (:func:`force_error_for_shift`) exceeds the stated
      accuracy — a *systematic* error the residuals cannot reveal (noise-free data give tiny
      standard errors whatever the conditioning); and
    - the normalised standard error of α and γ is below ``REL_STDERR_MAX`` (0.05) — the *random*
      error already in the data, which the force accuracy does not describe. The normalised
      standard error of a term is ``‖stderr‖ · rms(centred regressor) / rms(centred F_bb)``,
      the uncertainty of its force contribution relative to the force.

    The condition number is no longer a separate condition: the force-error test is its
    quantitative form (ε ≈ 0.1 S_min/|V_k,min| for a term about as large as the force, so at 1 %
    accuracy a condition number above ~20 already fails, and the old limit 1e3 corresponded to
    an accuracy of ~1e-4), and with a stated accuracy of 1e-5 noise-free data of condition 1e4
    are rightly identifiable. ``f_gen`` is the generator's force (δF_bb = δF) [N, N m].
    """
    f_norm = np.linalg.norm(f_gen - f_gen.mean(axis=0), axis=0)
    eps_terms = _force_errors(fit, terms, n_dof, f_norm)
    eps_dof = np.minimum(eps_terms["alpha"].min(axis=1), eps_terms["gamma"].min(axis=1))
    stderr_ok = all(nse.get(k, 0.0) < REL_STDERR_MAX for k in ("alpha", "gamma"))
    ident_dof = (eps_dof > accuracy) & stderr_ok  # NaN (constant force) is never identifiable
    return {"f_norm": f_norm, "eps_terms": eps_terms, "eps_dof": eps_dof,
            "stderr_ok": stderr_ok, "dof": ident_dof}


def _interpretation(hist: xr.Dataset, force: str, fit: _Fit, val: dict[str, np.ndarray],
                    idx: dict[str, np.ndarray], terms: Sequence[str], z: np.ndarray, dt: float,
                    frequency_tol: float, st: dict[str, Any], ident: dict[str, Any],
                    accuracy: np.ndarray) -> tuple[float | None, list[dict[str, Any]], list[str]]:
    """Dominant frequency [rad/s], the combinations the data determine when the split is not
    identifiable, and the plain-language warnings."""
    n_dof = z.shape[1]
    dofs = [str(d) for d in hist["dof"].values]
    omega0, _ = dominant_frequency(z, dt, band_rtol=frequency_tol)
    warnings_: list[str] = []
    combos: list[dict[str, Any]] = []
    if not ident["dof"].all():
        reason = _reason(dofs, ident["eps_dof"], accuracy, st["cond"], st["nse"],
                         ident["stderr_ok"])
        omega0 = _explain(fit, val, idx, terms, n_dof, z, dt, frequency_tol, reason, dofs,
                          combos, warnings_) or omega0
    if np.any(ident["f_norm"] == 0):
        warnings_.append(f"'{force}' is constant on some DOF: a relative force accuracy means "
                         "nothing there, so that DOF is not called identifiable")
    if np.any(st["r2"] < 0.9):
        warnings_.append(
            f"the linear model explains only {100 * float(st['r2'].min()):.1f} % of the variance "
            "of F_bb: the force is not well described by constant α, β, γ (nonlinear or "
            "history-dependent terms)"
        )
    est = [k for k in ("zdot", "zddot") if hist[k].attrs.get("estimated")]
    if est:
        warnings_.append(
            f"{' and '.join(est)} were estimated from z: derivative errors bias α (and γ) "
            "along the direction the data cannot resolve"
        )
    return omega0, combos, warnings_


def _reason(
    dofs: Sequence[Any], eps_dof: np.ndarray, accuracy: np.ndarray, cond: float,
    nse: dict[str, float], stderr_ok: bool,
) -> str:
    """Why the split is not identifiable, in one clause."""
    parts = [
        f"on {d} a force error of {_percent(e)} moves α or γ by 10 %, less than the assumed "
        f"force accuracy {_percent(a)}"
        for d, e, a in zip(dofs, eps_dof, accuracy) if not e > a
    ]
    if not stderr_ok:
        parts.append("normalised stderr "
                     + ", ".join(f"{_SYMBOL[k]} {v:.2g}" for k, v in nse.items())
                     + f" above {REL_STDERR_MAX:g}")
    return f"condition number {cond:.3g}; " + "; ".join(parts)


def _weak_directions(fit: _Fit, terms: Sequence[str], n_dof: int,
                     combos: list[dict[str, Any]], warnings_: list[str]) -> None:
    """The weakest direction(s) of the normalised regressors, mapped to physical (Δα, Δβ, Δγ):
    the null space when the regressors are linearly dependent."""
    sv = fit.sv
    rank_deficient = sv[-1] <= RANK_RTOL * sv[0]
    n_null = int(np.sum(sv <= RANK_RTOL * sv[0])) if rank_deficient else 1
    for v in fit.vt[-n_null:]:
        d_phys = v / fit.scale
        d_phys = d_phys / np.max(np.abs(d_phys))
        entry: dict[str, Any] = {
            "name": "null_direction" if rank_deficient else "weakest_direction",
            "note": "adding any multiple of this (Δα, Δβ, Δγ) leaves the fit "
            + ("unchanged" if rank_deficient else "almost unchanged"),
        }
        for b, name in enumerate(terms):
            entry[name] = d_phys[b * n_dof : (b + 1) * n_dof]
        combos.append(entry)
    if rank_deficient:
        warnings_.append(
            "the regressors are linearly dependent (e.g. free decay of a linear system, where "
            "z̈, ż, z satisfy its own equation of motion): the split of α, β, γ is not unique; "
            "see the null_direction"
        )


def _explain(
    fit: _Fit,
    val: dict[str, np.ndarray],
    idx: dict[str, np.ndarray],
    terms: Sequence[str],
    n_dof: int,
    z: np.ndarray,
    dt: float,
    frequency_tol: float,
    reason: str,
    dofs: Sequence[str],
    combos: list[dict[str, Any]],
    warnings_: list[str],
) -> float | None:
    """Fill the identifiable combinations and warnings of a non-identifiable fit: the
    weakest (or null) direction of (α, β, γ), then what the dominant frequency determines."""
    warnings_.append(
        f"α, β, γ are not separately identifiable ({reason}): the regressors z̈, ż, z are "
        "(nearly) linearly dependent, so the split reported is one of many that fit the force "
        "within its accuracy"
    )
    _weak_directions(fit, terms, n_dof, combos, warnings_)
    omega, share = dominant_frequency(z, dt, refine=True, band_rtol=frequency_tol)
    if omega is None or "alpha" not in terms:
        return omega
    remedy = ("remedies: fix α from BEM (fix_alpha = m + A∞), use richer (multi-frequency or "
              "irregular) excitation, or split the force per harmonic (frequency_domain_split)")
    w2 = omega**2
    p = fit.vt.shape[1]
    weak = fit.vt[fit.sv < fit.sv[0] / COND_MAX]  # poorly determined directions (normalised)

    def estimable(weights: dict[int, float]) -> bool:
        """c'θ is determined by the data iff c (normalised coordinates) ⟂ weak directions."""
        c = np.zeros(p)
        for k, v in weights.items():
            c[k - 1] = v  # idx counts the intercept as 0
        c_n = c / fit.scale
        return weak.size == 0 or np.linalg.norm(weak @ c_n) <= 1e-2 * np.linalg.norm(c_n)

    ia, ib, ig = idx["alpha"], idx["beta"], idx["gamma"]
    single = share >= SINGLE_FREQ_SHARE
    dyn_ok = single and all(estimable({ig[j]: 1.0, ia[j]: -w2}) for j in range(n_dof))
    damp_ok = all(estimable({ib[j]: 1.0}) for j in range(n_dof))
    if dyn_ok:
        dyn = val["gamma"] - w2 * val["alpha"]
        dyn_se = np.array([[math.sqrt(max(c[ig[j], ig[j]] + w2**2 * c[ia[j], ia[j]]
                                          - 2 * w2 * c[ia[j], ig[j]], 0.0))
                            for j in range(n_dof)] for c in fit.cov])
        combos.append({"name": "dynamic_stiffness", "value": dyn, "stderr": dyn_se,
                       "omega": omega, "note": "γ − ω² α at the dominant frequency "
                       f"[{_unit_label(dofs, 'gamma')}]"})
    if damp_ok:
        beta_se = np.array([[math.sqrt(max(c[ib[j], ib[j]], 0.0)) for j in range(n_dof)]
                            for c in fit.cov])
        combos.append({"name": "damping", "value": val["beta"].copy(), "stderr": beta_se,
                       "omega": omega, "note": f"β [{_unit_label(dofs, 'beta')}]"})
    found = " and ".join(k for k, ok in (("the dynamic stiffness γ − ω²α", dyn_ok),
                                         ("the damping β", damp_ok)) if ok)
    if not single:
        warnings_.append(("the damping β is determined; " if damp_ok else "") + remedy)
    elif found:
        warnings_.append(
            f"the motion is nearly single-frequency (ω = {omega:.6g} rad/s, {100 * share:.0f} % "
            f"of its power): only {found} are determined; fix α (fix_alpha = m + A∞ from BEM) "
            "or use multi-frequency/irregular excitation to split α from γ"
        )
    else:
        warnings_.append(
            f"the motion is nearly single-frequency (ω = {omega:.6g} rad/s) and not even γ − ω²α "
            "or β is determined (with several DOF one motion pattern cannot separate the "
            "coupling terms); " + remedy
        )
    return omega


# --------------------------------------------------------------------------- per harmonic
def frequency_domain_split(
    hist: xr.Dataset,
    force: str = "F_tot",
    known: Iterable[KnownComponent | str] = (),
    omegas: Sequence[float] | None = None,
) -> xr.Dataset:
    """Per-harmonic split ``F_bb(ω)/Z(ω) = −ω² α + iω β + γ`` (docs/THEORY.md §3 remedy), 1 DOF.

    Both signals are detrended, Hann-windowed and Fourier-transformed at each ω (a DTFT, so ω
    need not fall on an FFT bin). The real part of the ratio is the dynamic stiffness
    ``γ − ω² α`` [N/m], the imaginary part over ω the damping ``β(ω)`` [N s/m]. Valid for
    steady periodic motion with well-separated frequencies (leakage between them is the error).

    Parameters
    ----------
    hist, force, known
        As in :func:`regress`.
    omegas : sequence of float, optional
        Angular frequencies [rad/s]; default the dominant frequency of z.

    Returns
    -------
    xarray.Dataset
        Coordinate ``omega``; variables ``transfer`` (complex, N/m), ``dynamic_stiffness``,
        ``damping``, ``motion_amplitude`` [m]. With two or more frequencies the least-squares
        fit of ``Re = γ − ω² α`` is stored in attrs ``alpha`` [kg] and ``gamma`` [N/m].
    """
    validate(hist)
    if hist.sizes["dof"] != 1:
        raise InputError("frequency_domain_split handles 1 DOF; coupled DOF need one run per DOF")
    (z,) = kinematics(hist, ("z",))
    f_bb = black_box_force(hist, force, as_components(known))
    check_regressors({"z": z}, {f"{force} - known": f_bb})
    t = np.asarray(hist["time"].values, dtype=float)
    dt = float((t[-1] - t[0]) / (t.size - 1))
    if omegas is None:
        w0, _ = dominant_frequency(z, dt, refine=True)
        if w0 is None:
            raise InputError("z does not oscillate: give omegas explicitly")
        omegas = [w0]
    w = np.asarray(omegas, dtype=float).ravel()
    if w.size == 0 or np.any(~np.isfinite(w)) or np.any(w <= 0):
        raise InputError("omegas must be positive finite angular frequencies [rad/s]")
    if np.any(w >= np.pi / dt):
        raise InputError(f"omegas must be below the Nyquist frequency {np.pi / dt:.6g} rad/s")
    win = scipy.signal.windows.hann(t.size, sym=False)
    basis = np.exp(-1j * np.outer(w, t - t[0])) * win  # (n_omega, n_time)
    z_hat = basis @ scipy.signal.detrend(z[:, 0])
    f_hat = basis @ scipy.signal.detrend(f_bb[:, 0])
    if np.any(np.abs(z_hat) == 0):
        raise InputError("z has no content at one of the omegas")
    h = f_hat / z_hat
    attrs: dict[str, Any] = {"force": force, "known": json.dumps([c.describe() for c in as_components(known)])}
    if w.size >= 2:
        (gam, alph), *_ = scipy.linalg.lstsq(np.column_stack([np.ones_like(w), -w**2]), h.real)
        attrs.update(alpha=float(alph), gamma=float(gam))
    amp = 2 * np.abs(z_hat) / win.sum()
    return xr.Dataset(
        {
            "transfer": ("omega", h, {"units": "N/m"}),
            "dynamic_stiffness": ("omega", h.real, {"units": "N/m"}),
            "damping": ("omega", h.imag / w, {"units": "N s/m"}),
            "motion_amplitude": ("omega", amp, {"units": "m"}),
        },
        coords={"omega": ("omega", w, {"units": "rad/s"})},
        attrs=attrs,
    )
