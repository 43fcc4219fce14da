"""Slow-drift (difference-frequency) wave force in irregular seas by Newman's approximation.

In a sea of linear components ``η = Σ_j a_j cos θ_j``, ``θ_j = ω_j t + φ_j``, the second-order
force at the difference frequencies is ``F(t) = Σ_i Σ_j a_i a_j Re[T_ij e^{-i(θ_i − θ_j)}]``
with the quadratic transfer function (QTF) ``T``. Its diagonal is the mean drift of a regular
wave, ``T_jj = D(ω_j)`` [N/m², N m/m²] (:mod:`hybridwsi.hydro.drift`); Newman (1974) replaced
the off-diagonal terms by ``T_ij ≈ ½ (D(ω_i) + D(ω_j))``, which is accurate when the difference
frequency ω_i − ω_j is small against the scale on which the QTF varies (docs/OC3_HYWIND.md
"Slow drift": what it leaves out for a spar). Then

    F(t) = Re[B(t) Ā(t)],   A(t) = Σ_j a_j e^{-iθ_j},   B(t) = Σ_j a_j D(ω_j) e^{-iθ_j}

(difference frequencies only, O(N) per time instead of O(N²)). Its mean is ``Σ a_j² D(ω_j)``,
the Riemann sum of ``2 ∫ S(ω) D(ω) dω`` (:func:`spectral_mean`), and its one-sided spectrum at
a difference frequency μ is ``8 ∫ S(ω) S(ω + μ) T²(ω, ω + μ) dω`` (Pinkster 1980;
:func:`newman_spectrum`).

:class:`SlowDriftForce` is the force component: time only (the body's motion does not enter:
no wave-drift damping), zero linear coefficients, deterministic for the wave's seed. The wave
is the one that drives the excitation (same components, phases and direction), and with a
ramp the force is multiplied by the ramp squared (it is quadratic in the wave amplitude).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import scipy.integrate
import xarray as xr

from hybridwsi.dofs import RIGID_DOFS, check_dofs
from hybridwsi.errors import InputError
from hybridwsi.files import data_path, read_netcdf
from hybridwsi.forces.base import KnownComponent
from hybridwsi.hydro.drift import table_coefficients
from hybridwsi.waves import Wave, components_within, harmonic_sum, ramp_factor

def table_path(table: str | Path, folder: Path | None = None) -> Path:
    """Where a drift table named in a case lives: an absolute path, a path relative to
    ``folder`` (the case file's), or the name of a file shipped in ``hybridwsi/data``."""
    return data_path(table, folder, "drift table")


def load_table(table: str | Path | xr.Dataset, folder: Path | None = None) -> xr.Dataset:
    """A drift table (:func:`hybridwsi.hydro.drift.drift_table`): a Dataset, or a file found by
    :func:`table_path` (``"drift_oc3_hywind.nc"`` is shipped)."""
    if isinstance(table, xr.Dataset):
        return table
    return read_netcdf(table_path(table, folder))


class SlowDriftForce(KnownComponent):
    """Newman's-approximation slow-drift force of one wave (module docstring).

    Parameters
    ----------
    omega : (n_omega,) array
        Frequencies [rad/s] of the drift coefficients, increasing.
    coefficients : (n_omega, n_dof) array
        Mean drift D [N/m² on translations, N m/m² on rotations] per DOF of the run.
    wave : hybridwsi.waves.Wave
        The sea (its components, phases and direction); every component with a nonzero
        amplitude must lie inside the table's frequencies (no extrapolation).
    dofs : sequence of str
        DOFs of the run, in the column order of ``coefficients``.
    ramp : float
        Half-cosine ramp [s] of the excitation; the force is multiplied by its square.
    """

    name = "slow_drift"
    time_only = True

    def __init__(self, omega: np.ndarray, coefficients: np.ndarray, wave: Wave,
                 dofs: Sequence[str] | str = RIGID_DOFS, *, ramp: float = 0.0) -> None:
        self.dofs = check_dofs(dofs)
        w_tab = np.asarray(omega, dtype=float)
        d_tab = np.asarray(coefficients, dtype=float).reshape(w_tab.size, -1)
        if d_tab.shape[1] != len(self.dofs) or not np.all(np.isfinite(d_tab)):
            raise InputError(f"drift coefficients must be finite, one column per DOF "
                             f"({len(self.dofs)}), got shape {d_tab.shape}")
        if w_tab.size < 2 or np.any(np.diff(w_tab) <= 0):
            raise InputError("drift coefficient frequencies must be increasing (>= 2)")
        if not isinstance(wave, Wave):
            raise InputError(f"wave must be a hybridwsi.waves.Wave, got {type(wave).__name__}")
        w, amplitude = components_within(wave, w_tab, "the drift table's",
                                         "narrow the wave's omega_range or extend the table")
        self.ramp = float(ramp)
        ramp_factor(np.zeros(1), self.ramp)  # checks the ramp
        self.wave = wave
        self.table_omega, self.table_coefficients = w_tab, d_tab
        self.omega = w
        self.amplitude = amplitude  # a e^{-iφ}
        #: D at the wave's components, (n_comp, n_dof)
        self.drift = np.column_stack([np.interp(w, w_tab, d_tab[:, k])
                                      for k in range(d_tab.shape[1])])

    @classmethod
    def from_case(cls, case: Mapping[str, Any], dofs: Sequence[str] | str | None = None, *,
                  wave: Wave, ramp: float = 0.0, table: str | Path | xr.Dataset | None = None,
                  field: str | None = None) -> SlowDriftForce:
        """The slow drift of a case's ``[drift]`` table in ``wave``.

        ``[drift] table`` names the shipped coefficients (``hybridwsi/data``) or a path
        relative to the case file,
        ``field`` the method (``"combined"``: far field on surge/sway/yaw, near field on
        heave/roll/pitch; ``"far_field"``; ``"near_field"``); the arguments override them.
        ``dofs`` default to the case's ``default_dofs``; the wave's direction picks the table's
        heading.
        """
        cfg = case.get("drift") if isinstance(case, Mapping) else None
        if table is None and not (isinstance(cfg, Mapping) and "table" in cfg):
            raise InputError("case has no [drift] table")
        cfg = cfg if isinstance(cfg, Mapping) else {}
        dofs = check_dofs(dofs if dofs is not None else case.get("default_dofs", RIGID_DOFS))
        case_file = getattr(case, "path", None)
        data = load_table(table if table is not None else cfg["table"],
                          None if case_file is None else Path(case_file).parent)
        w, d = table_coefficients(data, dofs, direction=float(getattr(wave, "direction", 0.0)),
                                  field=field or cfg.get("field", "combined"))
        return cls(w, d, wave, dofs, ramp=ramp)

    # ------------------------------------------------------------------ evaluation
    def _check(self, n_dof: int | None) -> None:
        if n_dof is not None and n_dof != len(self.dofs):
            raise InputError(f"slow-drift force is set up for {len(self.dofs)} DOFs "
                             f"({', '.join(self.dofs)}), got {n_dof}")

    def time_force(self, t: np.ndarray, n_dof: int | None = None) -> np.ndarray:
        """F(t) [N, N m per DOF], shape (nt, n_dof)."""
        self._check(n_dof)
        t = np.atleast_1d(np.asarray(t, dtype=float))
        c = self.amplitude[:, None] * np.column_stack([np.ones(self.omega.size), self.drift])
        # Σ c e^{-iωt} = Re − i Re(i ·): two real harmonic sums give the complex envelope
        re, im_neg = np.split(harmonic_sum(t, np.hstack([c, 1j * c]), self.omega), 2, axis=1)
        z = re - 1j * im_neg  # columns: A(t), B_k(t)
        force = (z[:, 1:] * z[:, :1].conj()).real
        return force * ramp_factor(t, self.ramp)[:, None] ** 2

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """The force at the history's times, shape (n_time, n_dof) [N, N m]."""
        dofs = tuple(str(d) for d in hist["dof"].values)
        if dofs != self.dofs:
            raise InputError(f"slow-drift DOFs {list(self.dofs)} differ from the history's "
                             f"{list(dofs)}")
        return self.time_force(np.asarray(hist["time"].values, dtype=float))

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        self._check(z.shape[-1])
        return self.time_force(np.array([float(t)]))[0]

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """No added mass, damping or stiffness: the force does not depend on the motion."""
        self._check(n_dof)
        z = np.zeros((n_dof, n_dof))
        return z, z.copy(), z.copy()

    def mean_force(self) -> np.ndarray:
        """The realisation's mean ``Σ a_j² D(ω_j)`` [N, N m per DOF] (after the ramp)."""
        return np.abs(self.amplitude) ** 2 @ self.drift

    def describe(self) -> str:
        return (f"slow_drift(Newman, {self.omega.size} components, DOFs {','.join(self.dofs)}, "
                f"mean {np.array2string(self.mean_force(), precision=4)})")


# ---------------------------------------------------------------------------- spectral forms
def _interpolant(omega: np.ndarray, coefficients: np.ndarray):
    """D(ω) for one DOF, linear in ω, zero outside the table (the wave must not reach there)."""
    w, d = np.asarray(omega, dtype=float), np.asarray(coefficients, dtype=float)
    return lambda x: np.interp(x, w, d, left=0.0, right=0.0)


def spectral_mean(spectrum, omega: np.ndarray, coefficients: np.ndarray,
                  band: tuple[float, float]) -> float:
    """Mean slow-drift force ``2 ∫ S(ω) D(ω) dω`` [N or N m] over ``band`` [rad/s] for one DOF
    (``spectrum``: one-sided S(ω) [m² s/rad], e.g. ``JONSWAP.spectrum``)."""
    d = _interpolant(omega, coefficients)
    lo, hi = band
    knots = [k for k in np.asarray(omega, dtype=float) if lo < k < hi]
    val, _ = scipy.integrate.quad(lambda x: 2.0 * spectrum(x) * d(x), lo, hi, points=knots,
                                  limit=400)
    return float(val)


def newman_spectrum(mu: np.ndarray, spectrum, omega: np.ndarray, coefficients: np.ndarray,
                    band: tuple[float, float], n_points: int = 4001) -> np.ndarray:
    """One-sided spectrum [N² s/rad] of the slow-drift force at difference frequencies ``mu``
    [rad/s] for one DOF, Newman's closed form ``S_F(μ) = 8 ∫ S(ω) S(ω+μ) T²(ω, ω+μ) dω`` with
    ``T = ½ (D(ω) + D(ω+μ))``, the sea restricted to ``band`` [rad/s] (Pinkster 1980);
    trapezoidal rule on ``n_points`` frequencies across the band."""
    d = _interpolant(omega, coefficients)
    lo, hi = band
    x = np.linspace(lo, hi, int(n_points))
    s_x, d_x = spectrum(x), d(x)
    out = []
    for m in np.atleast_1d(np.asarray(mu, dtype=float)):
        inside = x + m <= hi
        xs = x[inside]
        t = 0.5 * (d_x[inside] + d(xs + m))
        out.append(scipy.integrate.trapezoid(8.0 * s_x[inside] * spectrum(xs + m) * t * t, xs)
                   if xs.size > 1 else 0.0)
    return np.asarray(out)


def band_of(wave: Wave) -> tuple[float, float]:
    """The frequency band [rad/s] a realisation of ``wave`` covers (its bins' outer edges)."""
    comp = wave.components()
    w = comp.omega
    if w.size < 2:
        raise InputError("a spectral form needs an irregular wave (>= 2 components)")
    dw = float(np.mean(np.diff(w)))
    return float(w[0] - dw / 2), float(w[-1] + dw / 2)


__all__ = ["SlowDriftForce", "load_table", "table_path", "spectral_mean", "newman_spectrum", "band_of"]
