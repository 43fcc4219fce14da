"""Incident waves (regular, JONSWAP, Pierson–Moskowitz) and their excitation force time series.

Sign convention (Capytaine's): a complex amplitude ``X`` stands for the real signal
``Re[X e^{-iωt}]`` (see ``capytaine.bem.airy_waves``: the incident elevation at the origin has
complex amplitude 1 per unit wave amplitude). A wave is a sum of linear components

    η(t) = Σ_j a_j cos(ω_j t + φ_j) = Re[Σ_j a_j e^{-i(ω_j t + φ_j)}]        at x = y = 0,

so the excitation force of the BEM transfer function ``F_e(ω)`` [N/m] is

    F_exc(t) = Re[Σ_j a_j F_e(ω_j) e^{-i(ω_j t + φ_j)}] = Σ_j a_j |F_e| cos(ω_j t + φ_j − arg F_e).

(With the opposite, ``e^{+iωt}``, convention the same force reads
``Re[Σ a_j conj(F_e) e^{i(ω_j t + φ_j)}]``.)

Spectra (single-sided, in ω, [m² s/rad]):

- Pierson–Moskowitz (Bretschneider form, DNV-RP-C205 eq. 3.5.5):
  ``S_PM(ω) = 5/16 Hs² ωp⁴ ω⁻⁵ exp(−5/4 (ω/ωp)⁻⁴)``, ``ωp = 2π/Tp``; its integral is exactly
  ``m0 = Hs²/16``.
- JONSWAP: ``S_J(ω) = N_γ S_PM(ω) γ^{exp(−(ω−ωp)²/(2σ²ωp²))}``, σ = 0.07 (ω ≤ ωp) or 0.09;
  ``N_γ`` is computed numerically so that ``m0 = Hs²/16`` exactly (DNV's approximation
  ``1 − 0.287 ln γ`` is within ~1 %).

A realisation uses ``n_components`` equally spaced frequencies ``ω_j`` (mid-points of bins of
width Δω over ``omega_range``), amplitudes ``a_j = sqrt(2 S(ω_j) Δω)`` and phases uniform on
[0, 2π) drawn from ``numpy.random.default_rng(seed)``; it repeats after ``2π/Δω``.

Directions: a wave travels towards its heading ``direction`` β [rad] from +X (Capytaine's
``wave_direction``; 0: along +X). A JONSWAP sea may be short-crested with the cos-2s spreading
function of Longuet-Higgins et al. (1963) (DNV-RP-C205 §3.5.8 with the half-angle cosine)

    S(ω, θ) = S(ω) D(θ − β),   D(θ) = Γ(s + 1) / (2 √π Γ(s + ½)) cos^{2s}(θ/2),  |θ| ≤ π,

whose integral over θ is 1 (so ∫∫ S D dθ dω = m0 = Hs²/16) and whose mean cos θ is s/(s + 1).
The realisation is the single-summation one (each frequency component has its own direction,
which keeps the sea ergodic and the amplitudes those of the long-crested sea): component j
travels towards ``β + F⁻¹((π_j + ½)/N)``, ``F`` the cumulative D (closed form with the
regularised incomplete beta function, :func:`spreading_quantile`) and ``π`` a permutation of
0 … N−1 drawn from the same generator after the phases, so a spread sea has the phases of the
long-crested sea of the same seed, and the same elevation at the origin.

A BEM excitation is stored at a few headings; a component's transfer function at any heading
comes from :func:`excitation_transfer`: the stored heading itself, else the body's symmetry
(:func:`heading_symmetry`: axisymmetric bodies from any one heading; a columns hull with the
dihedral symmetry of order n from [0, π/n]), else linear interpolation of the real and
imaginary parts between the two nearest stored headings (as HydroDyn does with WAMIT's), of
the forces and moments in each wave's own frame (x along its heading), so that the part of
the variation that is the wave turning is exact and only the shape's part is interpolated.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import scipy.fft
import scipy.integrate
import scipy.optimize
import scipy.special
import xarray as xr

from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.errors import InputError
from hybridwsi.limits import MAX_WAVE_HEIGHT

G = 9.81
_BLOCK = 1 << 20  # values of the (time × component) phase matrix evaluated at once


def _height(name: str, value: float) -> float:
    """A wave height [m]: positive and at most :data:`~hybridwsi.limits.MAX_WAVE_HEIGHT`."""
    v = _positive(name, value)
    if v > MAX_WAVE_HEIGHT:
        raise InputError(f"{name} must be at most {MAX_WAVE_HEIGHT:g} m (the highest wave "
                         f"measured at sea), got {value!r}")
    return v


def _positive(name: str, value: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(v) or v <= 0:
        raise InputError(f"{name} must be a finite positive number, got {value!r}")
    return v


def _uniform_step(t: np.ndarray) -> float | None:
    """Step of a uniform grid ``t_k = t_0 + k dt`` (to 1e-9 dt), else None."""
    if t.size < 3:
        return None
    dt = (t[-1] - t[0]) / (t.size - 1)
    if not dt > 0:
        return None
    k = np.arange(t.size)
    return dt if np.max(np.abs(t - (t[0] + k * dt))) <= 1e-9 * dt else None


def harmonic_sum(t: np.ndarray, amplitude: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """``Re[Σ_j c_j e^{-iω_j t}]`` for complex amplitudes ``c_j``; shape (nt,) or (nt, ...).

    ``amplitude`` has shape (n_components,) or (n_components, n_out). On a uniform grid the
    phasors are factorised, ``e^{-iω(t_0 + (aB + b)dt)} = e^{-iω(t_0 + aB dt)} e^{-iω b dt}``, so
    only ``B + nt/B`` exponentials per component are evaluated (a time series of 60 000 samples
    costs a few hundred µs instead of milliseconds); the phase differs from the direct product
    ``ω t`` by rounding only (< 1e-12 rad over hours).
    """
    t = np.asarray(t, dtype=float)
    c = np.asarray(amplitude, dtype=complex)
    omega = np.asarray(omega, dtype=float)
    flat = c.reshape(c.shape[0], -1)
    out = np.empty((t.size, flat.shape[1]))
    rows = max(1, _BLOCK // max(omega.size, 1))  # blocks keep the phase matrix ≤ _BLOCK values
    dt = _uniform_step(t)
    if dt is None:  # irregular grid: Re c cos ωt + Im c sin ωt, real products
        re, im = np.ascontiguousarray(flat.real), np.ascontiguousarray(flat.imag)
        for s in range(0, t.size, rows):
            ph = np.outer(t[s:s + rows], omega)
            blk = out[s:s + rows]
            np.matmul(np.cos(ph), re, out=blk)
            blk += np.sin(ph) @ im
    else:
        # block length balancing the exponentials (rows × n_comp) against the per-block
        # overhead (~10 µs, i.e. ~500 exponentials) of nt/rows blocks
        rows = min(rows, t.size, max(16, int(np.sqrt(500.0 * t.size / max(omega.size, 1)))))
        within = np.exp(-1j * np.outer(np.arange(rows) * dt, omega))  # (rows, n_comp)
        for s in range(0, t.size, rows):
            start = np.exp(-1j * omega * (t[0] + s * dt))  # block start phasor, (n_comp,)
            n = min(rows, t.size - s)
            out[s:s + n] = (within[:n] @ (start[:, None] * flat)).real
    return out.reshape(t.size, *c.shape[1:])


@dataclass(frozen=True)
class WaveComponents:
    """Linear components of a wave: ``η(t) = Σ a cos(ω t + φ)``."""

    amplitude: np.ndarray  # [m]
    omega: np.ndarray  # [rad/s]
    phase: np.ndarray  # [rad]
    #: propagation direction [rad] of each component; None: the wave's one ``direction``
    direction: np.ndarray | None = None

    def directions(self, default: float = 0.0) -> np.ndarray:
        """Direction [rad] of every component (``default`` when the wave has one direction)."""
        if self.direction is None:
            return np.full(self.omega.shape, float(default))
        return np.asarray(self.direction, dtype=float)

    @property
    def complex_amplitude(self) -> np.ndarray:
        """``a e^{-iφ}``, so that ``η = Re[Σ c e^{-iωt}]`` (Capytaine's convention)."""
        return self.amplitude * np.exp(-1j * self.phase)


class Wave:
    """Base class: subclasses implement :meth:`components` and :meth:`to_dict`."""

    direction: float = 0.0
    #: components below the coefficients' lowest frequency are allowed: their transfer
    #: function is interpolated towards the long-wave limit (:func:`long_wave_limit`); a
    #: record's content there. Synthetic seas must lie inside the range.
    long_waves: bool = False

    def components(self) -> WaveComponents:  # pragma: no cover - abstract
        raise NotImplementedError

    def component_directions(self, comp: WaveComponents | None = None) -> np.ndarray:
        """Propagation direction [rad] of each component of ``comp`` (default: this wave's)."""
        comp = self.components() if comp is None else comp
        return comp.directions(float(getattr(self, "direction", 0.0)))

    def elevation(self, t: np.ndarray) -> np.ndarray:
        """Incident wave elevation η(t) [m] at the origin."""
        comp = self.components()
        return harmonic_sum(t, comp.complex_amplitude, comp.omega)

    def to_dict(self) -> dict[str, Any]:  # pragma: no cover - abstract
        raise NotImplementedError


@dataclass
class Regular(Wave):
    """Regular (monochromatic) wave ``η = H/2 cos(2π t/T + phase)``.

    Parameters
    ----------
    period : float
        Wave period T [s].
    height : float
        Wave height H [m] (crest to trough, = 2 × amplitude).
    phase : float
        Phase φ [rad].
    direction : float
        Propagation direction [rad] (Capytaine's ``wave_direction``).
    """

    period: float
    height: float
    phase: float = 0.0
    direction: float = 0.0

    def __post_init__(self) -> None:
        self.period = _positive("wave period", self.period)
        self.height = _height("wave height", self.height)
        if not np.isfinite(self.phase):
            raise InputError("wave phase must be finite")

    @property
    def omega(self) -> float:
        """Angular frequency [rad/s]."""
        return 2 * np.pi / self.period

    def spectrum(self, omega: np.ndarray) -> np.ndarray:
        """A regular wave has a line spectrum: zero density everywhere (m0 = H²/8)."""
        return np.zeros_like(np.asarray(omega, dtype=float))

    def components(self) -> WaveComponents:
        return WaveComponents(np.array([self.height / 2]), np.array([self.omega]),
                              np.array([float(self.phase)]))

    def to_dict(self) -> dict[str, Any]:
        return {"type": "regular", **asdict(self)}


def spectral_moment(spectrum, omega_p: float, order: int = 0) -> float:
    """``m_n = ∫_0^∞ ω^n S(ω) dω`` by adaptive quadrature split at the peak ``omega_p``."""
    f = lambda w: w**order * spectrum(w)  # noqa: E731
    return (scipy.integrate.quad(f, 0, omega_p, limit=200)[0]
            + scipy.integrate.quad(f, omega_p, np.inf, limit=200)[0])


def _pm_shape(omega: np.ndarray, hs: float, wp: float) -> np.ndarray:
    """Pierson–Moskowitz spectrum [m² s/rad]; zero at ω ≤ 0."""
    w = np.asarray(omega, dtype=float)
    out = np.zeros_like(w)
    pos = w > 0
    r = wp / w[pos]
    out[pos] = 5 / 16 * hs**2 * wp**4 / w[pos] ** 5 * np.exp(-1.25 * r**4)
    return out


def spreading_function(theta: Any, s: float) -> np.ndarray:
    """cos-2s directional spreading ``D(θ) = Γ(s+1) / (2 √π Γ(s+½)) cos^{2s}(θ/2)`` [1/rad]
    at angles ``θ`` [rad] from the mean direction (wrapped to (−π, π]); ∫ D dθ = 1."""
    th = np.angle(np.exp(1j * np.asarray(theta, dtype=float)))
    norm = math.exp(math.lgamma(s + 1.0) - math.lgamma(s + 0.5)) / (2.0 * math.sqrt(math.pi))
    return norm * np.abs(np.cos(0.5 * th)) ** (2.0 * s)


def spreading_quantile(p: Any, s: float) -> np.ndarray:
    """Inverse of the cumulative cos-2s spreading, θ [rad] in (−π, π) with ``F(θ) = p``:
    ``F(θ) = ½ + ½ sgn(θ) I_{sin²(θ/2)}(½, s + ½)`` (I the regularised incomplete beta)."""
    q = 2.0 * np.asarray(p, dtype=float) - 1.0
    x = scipy.special.betaincinv(0.5, s + 0.5, np.abs(q))
    return np.sign(q) * 2.0 * np.arcsin(np.sqrt(x))


@dataclass
class JONSWAP(Wave):
    """Irregular JONSWAP sea state (see module docstring for the formulas).

    Parameters
    ----------
    hs : float
        Significant wave height Hs [m].
    tp : float
        Peak period Tp [s].
    gamma : float
        Peak enhancement factor γ ≥ 1 (3.3 by default; 1 gives Pierson–Moskowitz).
    seed : int
        Seed of the random phases.
    n_components : int
        Number of frequency components.
    omega_range : (float, float), optional
        Frequency band [rad/s]; default ``(0.5 ωp, 4 ωp)`` (holds > 99 % of m0 for γ = 3.3).
    direction : float
        Propagation direction [rad] (the mean direction of a spread sea).
    spreading : float, optional
        Exponent s > 0 of the cos-2s spreading function (module docstring; wind sea about
        5–15, swell 25 and more); None: long-crested.
    """

    hs: float
    tp: float
    gamma: float = 3.3
    seed: int = 0
    n_components: int = 200
    omega_range: tuple[float, float] | None = None
    direction: float = 0.0
    spreading: float | None = None
    _norm: float = field(default=1.0, init=False, repr=False)

    def __post_init__(self) -> None:
        self.hs = _height("Hs", self.hs)
        self.tp = _positive("Tp", self.tp)
        if not (np.isfinite(self.gamma) and self.gamma >= 1):
            raise InputError(f"JONSWAP gamma must be >= 1, got {self.gamma}")
        if int(self.n_components) < 1:
            raise InputError("n_components must be >= 1")
        self.n_components = int(self.n_components)
        if self.omega_range is None:
            self.omega_range = (0.5 * self.omega_p, 4.0 * self.omega_p)
        lo, hi = (float(v) for v in self.omega_range)
        if not (0 < lo < hi and np.isfinite(hi)):
            raise InputError(f"omega_range must satisfy 0 < low < high, got {self.omega_range}")
        self.omega_range = (lo, hi)
        if not np.isfinite(self.direction):
            raise InputError(f"wave direction must be finite, got {self.direction}")
        if self.spreading is not None:
            self.spreading = _positive("spreading exponent s", self.spreading)
        self._norm = 1.0
        self._norm = self.hs**2 / 16 / spectral_moment(self.spectrum, self.omega_p)

    @property
    def omega_p(self) -> float:
        """Peak angular frequency ωp = 2π/Tp [rad/s]."""
        return 2 * np.pi / self.tp

    def spectrum(self, omega: np.ndarray) -> np.ndarray:
        """One-sided spectral density S(ω) [m² s/rad]."""
        w = np.asarray(omega, dtype=float)
        wp = self.omega_p
        sigma = np.where(w <= wp, 0.07, 0.09)
        peak = self.gamma ** np.exp(-((w - wp) ** 2) / (2 * sigma**2 * wp**2))
        return self._norm * _pm_shape(w, self.hs, wp) * peak

    def components(self) -> WaveComponents:
        lo, hi = self.omega_range
        dw = (hi - lo) / self.n_components
        w = lo + dw * (np.arange(self.n_components) + 0.5)
        amp = np.sqrt(2 * self.spectrum(w) * dw)
        rng = np.random.default_rng(self.seed)
        phase = rng.uniform(0, 2 * np.pi, w.size)
        if self.spreading is None:
            return WaveComponents(amp, w, phase)
        # equal-probability directions, one per component, assigned by a seeded permutation
        # drawn after the phases (module docstring)
        p = (rng.permutation(w.size) + 0.5) / w.size
        return WaveComponents(amp, w, phase,
                              self.direction + spreading_quantile(p, self.spreading))

    def directional_spectrum(self, omega: Any, theta: Any) -> np.ndarray:
        """``S(ω) D(θ − β)`` [m² s/rad²] at frequencies ``omega`` [rad/s] and directions
        ``theta`` [rad] (broadcast); needs ``spreading``."""
        if self.spreading is None:
            raise InputError("a long-crested sea has no directional density (give spreading)")
        return self.spectrum(omega) * spreading_function(np.asarray(theta) - self.direction,
                                                          self.spreading)

    def to_dict(self) -> dict[str, Any]:
        d = {k: v for k, v in asdict(self).items() if not k.startswith("_")
             and not (k == "spreading" and v is None)}  # long-crested: as before spreading
        return {"type": type(self).__name__.lower(), **d}


class PiersonMoskowitz(JONSWAP):
    """Pierson–Moskowitz sea state: JONSWAP with γ = 1 (fully developed sea)."""

    def __init__(self, hs: float, tp: float, seed: int = 0, n_components: int = 200,
                 omega_range: tuple[float, float] | None = None, direction: float = 0.0,
                 spreading: float | None = None):
        super().__init__(hs=hs, tp=tp, gamma=1.0, seed=seed, n_components=n_components,
                         omega_range=omega_range, direction=direction, spreading=spreading)


class ElevationRecord(Wave):
    """A recorded wave elevation η(t) at the body's reference point, as a wave.

    Its components are the discrete Fourier transform of the record padded with zeros to
    ``pad`` times its length (``scipy.fft.next_fast_len``): the excitation force
    ``F_exc = Re[Σ_j c_j F_e(ω_j) e^{-iω_j t}]`` (:func:`excitation_force`) is then the
    convolution of the record with the excitation impulse response (non-causal: the force
    at t feels the elevation before and after t), evaluated at any time, the solver's half
    steps included. The padding makes that convolution linear instead of circular (the end of
    the record does not wrap onto its start), exactly for impulse responses shorter than
    ``(pad - 1)`` record lengths; the record is taken as calm before its first and after its
    last sample, so the force within one impulse-response length of either end feels the
    missing sea (ramp the start; leave the end out of comparisons: tests/test_wave_elevation.py
    measures it).

    η is taken as measured from the still-water level, its mean included: the mean of a
    finite record of waves is not zero (25.3 periods of a regular wave: 0.6 % of its
    amplitude), and removing it would shift the heave force by ρ g A_wp times that mean (1.3 %
    of the sphere's force amplitude). A probe with a datum offset must be corrected first.
    Components above ``omega_max`` (the coefficients' highest frequency) are left out
    (:attr:`variance_outside` is their share of η's variance); those below the coefficients'
    lowest frequency, the mean among them, take the transfer function interpolated between
    its long-wave limit (:func:`long_wave_limit`: a uniform rise of the water, ``C[:, Heave]``)
    and its value there (:attr:`Wave.long_waves`).

    Parameters
    ----------
    time : array, shape (n,)
        Sample times [s], uniform (the first sample becomes t = 0 of the wave).
    eta : array, shape (n,)
        Elevation [m] at the reference point.
    omega_max : float, optional
        Highest frequency kept [rad/s]; None: all but the Nyquist bin.
    pad : float
        Padded length over the record length (>= 2 for a linear convolution).
    source : str
        Where the record came from (recorded by :meth:`to_dict`).
    direction : float
        Propagation direction [rad] of the excitation transfer function used.
    """

    long_waves = True

    def __init__(self, time: Any, eta: Any, *, omega_max: float | None = None,
                 pad: float = 2.0, source: str = "", direction: float = 0.0) -> None:
        t = np.asarray(time, dtype=float)
        x = np.asarray(eta, dtype=float)
        if t.ndim != 1 or x.shape != t.shape or t.size < 8:
            raise InputError("a wave-elevation record needs matching 1-D time and eta with "
                             ">= 8 samples")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
            raise InputError("the wave-elevation record holds NaN or inf")
        dt = _uniform_step(t)
        if dt is None:
            raise InputError("the wave-elevation record's time is not uniformly sampled "
                             "(resample it first)")
        if not pad >= 1.0:
            raise InputError(f"pad must be >= 1, got {pad}")
        self.dt, self.t0, self.n = float(dt), float(t[0]), int(t.size)
        self.duration = self.dt * (self.n - 1)
        self.source, self.direction = source, float(direction)
        self.mean = float(np.mean(x))
        m = scipy.fft.next_fast_len(int(math.ceil(pad * self.n)), real=True)
        spectrum = np.fft.rfft(x, n=m)
        omega = 2.0 * np.pi * np.arange(spectrum.size) / (m * self.dt)
        inner = np.ones(spectrum.size, dtype=bool)
        if m % 2 == 0:
            inner[-1] = False  # the Nyquist bin has no phase; never kept
        keep = inner.copy()
        if omega_max is not None:
            keep &= omega <= float(omega_max) * (1 + 1e-12)
        # η_k = Re Σ_j c_j e^{-iω_j t_k} with c_j = 2 conj(X_j) / m (rfft: Σ η e^{-iωt}),
        # the mean (ω = 0) counted once
        c = 2.0 * np.conj(spectrum) / m
        c[0] /= 2.0
        power = np.abs(c) ** 2
        total = power[inner].sum()
        self.variance_outside = float(power[inner & ~keep].sum() / total) if total > 0 else 0.0
        self.omega_max = None if omega_max is None else float(omega_max)
        self.sha256 = hashlib.sha256(np.ascontiguousarray(np.column_stack([t, x])).tobytes()
                                     ).hexdigest()
        self._components = WaveComponents(np.abs(c[keep]), omega[keep], -np.angle(c[keep]))

    def components(self) -> WaveComponents:
        return self._components

    def to_dict(self) -> dict[str, Any]:
        return {"type": "elevation_record", "source": self.source, "sha256": self.sha256,
                "n_samples": self.n, "dt": self.dt, "t0": self.t0, "mean": self.mean,
                "omega_max": self.omega_max, "variance_outside": self.variance_outside,
                "n_components": int(self._components.omega.size), "direction": self.direction}


def wave_from_dict(d: dict[str, Any]) -> Wave:
    """Rebuild a wave from :meth:`Wave.to_dict` output."""
    d = dict(d)
    kind = d.pop("type", None)
    try:
        if kind == "regular":
            return Regular(**d)
        if kind == "jonswap":
            return JONSWAP(**d)
        if kind == "piersonmoskowitz":
            d.pop("gamma", None)
            return PiersonMoskowitz(**d)
        if kind == "elevation_record":
            raise InputError("a wave-elevation record is not stored in its description; "
                             "read the record again (hybridwsi simulate --wave-elevation)")
    except TypeError as exc:
        raise InputError(f"bad wave description: {exc}") from None
    raise InputError(f"unknown wave type '{kind}' (regular, jonswap, piersonmoskowitz)")


def dispersion_k(omega: float | np.ndarray, depth: float = np.inf, g: float = G) -> np.ndarray:
    """Wavenumber k [rad/m] solving ``ω² = g k tanh(k h)`` (deep water: ``k = ω²/g``).

    Parameters
    ----------
    omega : float or array
        Angular frequency [rad/s], ≥ 0.
    depth : float
        Water depth h [m] (``inf`` for deep water).
    g : float
        Gravity [m/s²].
    """
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    if np.any(~np.isfinite(w)) or np.any(w < 0):
        raise InputError("omega must be finite and >= 0")
    if not depth > 0:
        raise InputError(f"water depth must be > 0, got {depth}")
    k_deep = w**2 / g
    if np.isinf(depth):
        return k_deep if np.ndim(omega) else k_deep[0]
    out = np.zeros_like(w)
    for i, (wi, kd) in enumerate(zip(w, k_deep)):
        if wi == 0:
            continue
        # k lies between the deep- and shallow-water values, whichever is larger, and their sum
        lo = max(kd, wi / np.sqrt(g * depth))
        hi = kd + wi / np.sqrt(g * depth)
        out[i] = scipy.optimize.brentq(lambda k: k * np.tanh(k * depth) - wi**2 / g,
                                       lo * (1 - 1e-12), hi * (1 + 1e-12), xtol=1e-14, rtol=1e-13)
    return out if np.ndim(omega) else out[0]


def ramp_factor(t: np.ndarray, ramp: float) -> np.ndarray:
    """Half-cosine ramp ``½(1 − cos(π t/T_r))`` for ``t < T_r``, 1 afterwards."""
    t = np.asarray(t, dtype=float)
    if ramp < 0 or not np.isfinite(ramp):
        raise InputError(f"ramp must be a finite duration >= 0 [s], got {ramp}")
    if ramp == 0:
        return np.ones_like(t)
    out = np.ones_like(t)
    on = t < ramp  # the cosine only where the ramp acts (long runs: a few % of the samples)
    out[on] = 0.5 * (1 - np.cos(np.pi * np.clip(t[on], 0, ramp) / ramp))
    return out


def _airy_profile(k: np.ndarray, z: np.ndarray, depth: float, sign: float) -> np.ndarray:
    """``(e^{kz} + sign e^{-k(z + 2h)}) / (1 - e^{-2kh})``, shape (n_z, n_k): cosh (sign +1) or
    sinh (sign −1) of ``k (z + h)`` over ``sinh(k h)`` without overflow at large ``k h``;
    ``e^{kz}`` in deep water (``depth = inf``)."""
    kz = np.outer(z, k)
    if np.isinf(depth):
        return np.exp(kz)
    kh = np.asarray(k) * depth
    return (np.exp(kz) + sign * np.exp(-kz - 2.0 * kh)) / -np.expm1(-2.0 * kh)


def airy_depth_factor(k: np.ndarray, z: np.ndarray, depth: float) -> np.ndarray:
    """``cosh(k (z + h)) / sinh(k h)`` for every (z, k) pair, shape (n_z, n_k): the depth
    profile of the horizontal Airy particle velocity per unit ``a ω`` (deep water ``e^{kz}``)."""
    return _airy_profile(k, z, depth, 1.0)


def airy_vertical_factor(k: np.ndarray, z: np.ndarray, depth: float) -> np.ndarray:
    """``sinh(k (z + h)) / sinh(k h)`` for every (z, k) pair, shape (n_z, n_k): the depth
    profile of the vertical Airy particle velocity per unit ``a ω`` (deep water ``e^{kz}``)."""
    return _airy_profile(k, z, depth, -1.0)


class AiryKinematics:
    """Linear (Airy) wave particle velocity at points on one vertical line ``(x, y, z_i)``.

    For a wave of components ``η = Σ a_j cos(ω_j t + φ_j)`` at the origin travelling in its
    direction β, with ``k_j`` from the finite-depth dispersion relation and
    ``θ_j = ω_j t + φ_j − k_j (x cos β + y sin β)``:

        u = Σ_j a_j ω_j cosh(k_j (z + h)) / sinh(k_j h) cos θ_j    (horizontal, along β)
        w = −Σ_j a_j ω_j sinh(k_j (z + h)) / sinh(k_j h) sin θ_j   (vertical, up)

    (deep water: both profiles ``e^{k z}``), so that ``w(z = 0) = ∂η/∂t`` and
    ``∂u/∂s + ∂w/∂z = 0``. An optional half-cosine ramp (:func:`ramp_factor`) multiplies both.
    Everything that does not depend on t is computed once here: the line is evaluated at
    many times (a time-stepping solver calls it every stage).

    Parameters
    ----------
    wave : Wave
        The incident wave (:class:`Regular`, :class:`JONSWAP`, ...).
    z : array_like, shape (n_z,)
        Heights of the points [m] (global z, up from the still-water level), ``z >= -h``.
    x, y : float
        Horizontal position of the line [m].
    depth : float
        Water depth h [m] (``inf`` for deep water).
    g : float
        Gravity [m/s²] of the dispersion relation.
    ramp : float
        Half-cosine ramp duration [s] (0: none).

    Attributes
    ----------
    omega, phase : ndarray, shape (n_comp,)
        Component frequencies [rad/s] and phases [rad] at the line (``φ_j − k_j s``);
        components of zero amplitude are dropped.
    profile : ndarray, shape (n_z, n_comp)
        ``a_j ω_j cosh(k_j (z + h)) / sinh(k_j h)`` [m/s], the horizontal amplitudes.
    vertical_profile : ndarray, shape (n_z, n_comp)
        ``a_j ω_j sinh(k_j (z + h)) / sinh(k_j h)`` [m/s], the vertical amplitudes.
    cos_beta, sin_beta : float
        Direction cosines of the propagation direction β.
    ramp : float
        Ramp duration [s].
    """

    def __init__(self, wave: Wave, z: Any, x: float = 0.0, y: float = 0.0,
                 depth: float = np.inf, g: float = G, ramp: float = 0.0) -> None:
        z = np.atleast_1d(np.asarray(z, dtype=float))
        if z.ndim != 1 or not np.all(np.isfinite(z)):
            raise InputError("wave kinematics: z must be finite heights [m]")
        if not depth > 0:
            raise InputError(f"water depth must be > 0, got {depth}")
        if np.any(z < -depth):
            raise InputError(f"wave kinematics: point at z = {z.min():g} m is below the seabed "
                             f"(depth {depth:g} m)")
        ramp_factor(np.zeros(1), ramp)  # validates the ramp (finite, >= 0)
        comp = wave.components()
        keep = (comp.amplitude > 0) & (comp.omega > 0)  # a still level (ω = 0) has no flow
        omega, amp = comp.omega[keep], comp.amplitude[keep]
        k = dispersion_k(omega, depth, g)
        if comp.direction is not None and np.ptp(wave.component_directions(comp)) > 0:
            raise InputError("the wave kinematics along a line (an axisymmetric body's Morison "
                             "strips) take a long-crested sea; a spread sea needs the members' "
                             "kinematics (AiryPoints)")
        beta = float(getattr(wave, "direction", 0.0))
        self.cos_beta, self.sin_beta = math.cos(beta), math.sin(beta)
        # phase at the line's horizontal position, folded into the component phase
        self.phase = comp.phase[keep] - k * (x * math.cos(beta) + y * math.sin(beta))
        self.omega = omega
        self.profile = airy_depth_factor(k, z, depth) * (amp * omega)
        self.vertical_profile = airy_vertical_factor(k, z, depth) * (amp * omega)
        self._profile_t = np.ascontiguousarray(self.profile.T)
        self.ramp = float(ramp)

    def _ramped(self, t: np.ndarray | float, values: np.ndarray) -> np.ndarray:
        if np.ndim(t) == 0:
            if self.ramp > 0.0 and float(t) < self.ramp:  # ramp 0: none, even at t < 0
                values *= 0.5 * (1.0 - math.cos(math.pi * max(float(t), 0.0) / self.ramp))
            return values
        return values * ramp_factor(t, self.ramp)[:, None]

    def speed(self, t: float | np.ndarray) -> np.ndarray:
        """Horizontal velocity along β, u [m/s]: (n_z,) for a scalar t [s], else (nt, n_z)."""
        if np.ndim(t) == 0:  # one time (a solver stage): a direct matrix-vector product
            return self._ramped(t, np.cos(self.omega * float(t) + self.phase) @ self._profile_t)
        c = self.profile * np.exp(-1j * self.phase)  # Re[c e^{-iωt}] = profile cos(ωt + φ)
        return self._ramped(t, harmonic_sum(np.asarray(t, dtype=float), c.T, self.omega))

    def vertical(self, t: float | np.ndarray) -> np.ndarray:
        """Vertical velocity w [m/s] (up): (n_z,) for a scalar t [s], else (nt, n_z)."""
        c = self.vertical_profile * (-1j * np.exp(-1j * self.phase))  # Re[−i P e^{-iθ}] = −P sin θ
        out = harmonic_sum(np.atleast_1d(np.asarray(t, dtype=float)), c.T, self.omega)
        return self._ramped(t, out[0] if np.ndim(t) == 0 else out)

    def components(self, t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Horizontal velocity components ``(u_x, u_y)`` [m/s], each shaped as :meth:`speed`."""
        u = self.speed(t)
        return u * self.cos_beta, u * self.sin_beta



class AiryPoints:
    """Linear (Airy) wave particle velocity and acceleration at scattered points ``(x, y, z)``
    (the elements of a frame of members), formulas of :class:`AiryKinematics` with the phase
    ``θ_ij = ω_j t + φ_j − k_j (x_i cos β_j + y_i sin β_j)`` per point (β_j the component's
    direction: the wave's one direction, or its own in a spread sea):

        u_h = Σ_j P_ij cos θ_ij (along β_j),   w = −Σ_j Q_ij sin θ_ij,
        ∂u_h/∂t = −Σ_j ω_j P_ij sin θ_ij,      ∂w/∂t = −Σ_j ω_j Q_ij cos θ_ij,

    ``P_ij = a_j ω_j cosh(k_j (z_i + h)) / sinh(k_j h)``, ``Q_ij`` the same with sinh. The
    optional half-cosine ramp multiplies velocity and acceleration (its own time derivative is
    left out: it is slow against the waves).

    Parameters
    ----------
    wave : Wave
        The incident wave.
    points : array_like, shape (n, 3)
        Positions [m], global frame at rest, ``z >= -h``.
    depth, g, ramp : float
        Water depth h [m] (``inf``: deep water), gravity [m/s²], ramp duration [s].
    """

    def __init__(self, wave: Wave, points: Any, depth: float = np.inf, g: float = G,
                 ramp: float = 0.0) -> None:
        pts = np.asarray(points, dtype=float).reshape(-1, 3)
        if not np.all(np.isfinite(pts)):
            raise InputError("wave kinematics: points must be finite [m]")
        if not depth > 0:
            raise InputError(f"water depth must be > 0, got {depth}")
        if np.any(pts[:, 2] < -depth):
            raise InputError("wave kinematics: a point is below the seabed")
        ramp_factor(np.zeros(1), ramp)
        comp = wave.components()
        keep = comp.amplitude > 0
        omega, amp = comp.omega[keep], comp.amplitude[keep]
        k = dispersion_k(omega, depth, g)
        beta = wave.component_directions(comp)[keep]
        #: (n_comp, 2) unit horizontal direction of each component
        self.direction = np.column_stack([np.cos(beta), np.sin(beta)])
        self.omega = omega
        #: (n, n_comp) phase at each point [rad]
        self.phase = comp.phase[keep] - (pts[:, :2] @ self.direction.T) * k
        self.horizontal = airy_depth_factor(k, pts[:, 2], depth) * (amp * omega)
        self.vertical = airy_vertical_factor(k, pts[:, 2], depth) * (amp * omega)
        self.ramp = float(ramp)
        # the sums as one complex matrix-vector product per call: Σ_j P_ij cos θ_ij =
        # Re Σ_j (P_ij e^{iφ_ij}) e^{iω_j t}, so a call costs n_comp exponentials instead of
        # n × n_comp cosines and sines (rows: u_x, u_y, w of every point)
        e_phase = np.exp(1j * self.phase)
        self._amplitudes = np.concatenate([
            self.horizontal * self.direction[:, 0] * e_phase,
            self.horizontal * self.direction[:, 1] * e_phase,
            self.vertical * e_phase])

    def velocity_acceleration(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Velocity [m/s] and acceleration [m/s²] at one time ``t`` [s], each (n, 3), read-only.

        u_x + i(·) = Σ_j C_ij e^{iω_j t}: velocity Re (horizontal), −Im (vertical); the
        acceleration is the same sum with ω_j e^{iω_j t}: −Im (horizontal), −Re (vertical).
        The last two times are kept: an RK4 step asks twice at its midpoint, and its end is
        the next step's start (5 calls a step become 2).
        """
        t = float(t)
        memo = self.__dict__.setdefault("_memo", {})
        if t not in memo:
            if len(memo) >= 2:
                del memo[next(iter(memo))]  # the oldest
            memo[t] = self._evaluate(t)
        return memo[t]

    def _evaluate(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        phasor = np.exp(1j * self.omega * float(t))
        both = self._amplitudes @ np.stack([phasor, self.omega * phasor], axis=1)  # (3n, 2)
        n = self.phase.shape[0]
        f = float(ramp_factor(np.array([float(t)]), self.ramp)[0]) if self.ramp else 1.0
        vel = np.concatenate([both[:2 * n, 0].real, -both[2 * n:, 0].imag]) * f
        acc = np.concatenate([-both[:2 * n, 1].imag, -both[2 * n:, 1].real]) * f
        out = vel.reshape(3, n).T, acc.reshape(3, n).T
        for a in out:
            a.flags.writeable = False  # shared by the calls at the same time
        return out


def particle_velocity(wave: Wave, t: float | np.ndarray, x: float, z: Any, *, y: float = 0.0,
                      depth: float = np.inf, g: float = G, ramp: float = 0.0
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Linear Airy particle velocity ``(u, w)`` [m/s] at points ``(x, y, z)`` and times ``t``.

    ``u`` is horizontal along the wave direction β (``u_x = u cos β``, ``u_y = u sin β``), ``w``
    vertical (up); formulas in :class:`AiryKinematics`. Shapes: ``z`` (n_z,) and ``t`` (nt,)
    give (nt, n_z); a scalar ``t`` drops the time axis, a scalar ``z`` the point axis.
    """
    line = AiryKinematics(wave, z, x, y, depth, g, ramp)
    u, w = line.speed(t), line.vertical(t)
    if np.ndim(z) == 0:
        u, w = u[..., 0], w[..., 0]
    return u, w


def heading_symmetry(coeffs: xr.Dataset) -> int | None:
    """The body's symmetry about the vertical axis through the coefficients' origin, from
    ``attrs["body"]``: 0 axisymmetric (spar, sphere), ``n`` the dihedral group of order n
    (a ``ColumnsBody`` with ``symmetry = n``: n-fold rotation and a mirror plane xOz), None
    unknown (the stored headings only)."""
    raw = coeffs.attrs.get("body")
    try:
        body = json.loads(raw) if isinstance(raw, str) else {}
    except ValueError:
        return None
    hull = body.get("hull", body) if isinstance(body, dict) else {}
    ref = np.asarray(coeffs.attrs.get("reference_point", (0.0, 0.0, 0.0)), dtype=float)
    if not isinstance(hull, dict) or ref.size < 2 or np.any(np.abs(ref.reshape(-1)[:2]) > 1e-9):
        return None  # symmetry about an axis that is not the phase origin's: not used
    if hull.get("type") in ("AxisymmetricBody", "FloatingSphere"):
        return 0
    order = hull.get("symmetry")
    if hull.get("type") == "ColumnsBody" and isinstance(order, int) and order >= 1:
        return order
    return None


def _rotation(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def _mirror(angle: float) -> np.ndarray:
    """Reflection of the horizontal plane across the line at ``angle`` [rad] from +X."""
    c, s = math.cos(2 * angle), math.sin(2 * angle)
    return np.array([[c, s], [s, -c]])


def _dof_map(q: np.ndarray) -> np.ndarray:
    """6×6 map of a (force, moment) vector under the horizontal orthogonal map ``q`` (z kept):
    forces transform as vectors, moments as pseudo-vectors (times det q)."""
    q3 = np.eye(3)
    q3[:2, :2] = q
    out = np.zeros((6, 6))
    out[:3, :3], out[3:, 3:] = q3, np.linalg.det(q) * q3
    return out


def _reduce_heading(beta: float, order: int | None, stored: np.ndarray
                    ) -> tuple[float, np.ndarray]:
    """``(β', Q)`` with ``β = Q β'`` and β' a heading the stored ones cover (module
    docstring): the body's symmetry group maps the excitation as ``F(Qβ') = T(Q) F(β')``."""
    if order == 0:  # axisymmetric: rotate the first stored heading onto β
        return float(stored[0]), _rotation(beta - float(stored[0]))
    if order is None:
        return beta, np.eye(2)
    sector = 2 * math.pi / order
    k = math.floor(beta / sector + 1e-12)
    b = beta - k * sector
    q = _rotation(k * sector)
    if b > 0.5 * sector + 1e-12:  # the mirror line at π/n
        b, q = sector - b, q @ _mirror(0.5 * sector)
    return max(b, 0.0), q


def _stored_heading(vals: np.ndarray, dirs: np.ndarray, beta: float) -> np.ndarray:
    """Excitation (n_omega, 6) at heading ``beta`` [rad]: a stored one within 1e-6 rad, else
    linear in heading between the two stored ones around it (no extrapolation), in the frame
    of each wave (x along its heading): the force turns with the wave, so what is left to
    interpolate is what the body's shape adds (exact for a body of revolution)."""
    rel = np.angle(np.exp(1j * (dirs - beta)))
    i = int(np.argmin(np.abs(rel)))
    if abs(rel[i]) <= 1e-6:
        return vals[:, i]
    lo = np.where(rel < 0, -rel, np.inf)
    hi = np.where(rel > 0, rel, np.inf)
    a, b = int(np.argmin(lo)), int(np.argmin(hi))
    span = lo[a] + hi[b]
    if not (np.isfinite(span) and span < math.pi):
        raise InputError(f"no excitation force for wave direction {beta:g} rad: the "
                         f"coefficients' headings {', '.join(f'{d:g}' for d in dirs)} rad "
                         "do not surround it (and the body's symmetry does not give it)")
    fa = vals[:, a] @ _dof_map(_rotation(-float(dirs[a]))).T  # into each wave's frame
    fb = vals[:, b] @ _dof_map(_rotation(-float(dirs[b]))).T
    return ((hi[b] * fa + lo[a] * fb) / span) @ _dof_map(_rotation(beta)).T


def _dihedral_heading(six: np.ndarray, dirs: np.ndarray, beta: float, order: int
                      ) -> np.ndarray | None:
    """F_e(ω, 6 DOFs) at heading ``beta`` [rad] of a body with the dihedral symmetry of
    ``order`` n, from the stored headings in [0, π/n] by trigonometric interpolation in each
    wave's frame: there the force is periodic in β with period 2π/n and, by the mirror xOz,
    even (surge, heave, pitch: Σ a_p cos(p n β)) or odd (sway, roll, yaw: Σ b_p sin(p n β));
    m + 1 stored headings k π/(n m) fit a_0 … a_m and b_1 … b_(m−1) exactly (the odd part
    vanishes on the mirror lines 0 and π/n). None when the stored headings do not allow it
    (fewer than two in [0, π/n], or a singular fit)."""
    half = math.pi / order
    inside = [(float(d), i) for i, d in enumerate(dirs) if -1e-9 <= d <= half + 1e-9]
    inside.sort()
    if len(inside) < 2 or inside[0][0] > 1e-9 or inside[-1][0] < half - 1e-9:
        return None
    h = np.array([d for d, _ in inside])
    fw = np.stack([six[:, i] @ _dof_map(_rotation(-d)).T for d, i in inside], axis=1)
    out = np.empty((six.shape[0], 6), dtype=complex)
    interior = (h > 1e-9) & (h < half - 1e-9)
    n_odd = int(interior.sum())
    for cols, basis, rows in (((0, 2, 4), np.cos, np.ones(h.size, bool)), ((1, 3, 5), np.sin,
                                                                         interior)):
        p = np.arange(h.size) if basis is np.cos else np.arange(1, n_odd + 1)
        m = basis(np.outer(h[rows], p) * order)
        if m.size and np.linalg.cond(m) > 1e8:
            return None
        coef = (np.linalg.solve(m, fw[:, rows][:, :, list(cols)].transpose(1, 0, 2).reshape(
            m.shape[0], -1)) if m.size else np.zeros((0, six.shape[0] * 3)))
        at = basis(p * order * beta)
        out[:, list(cols)] = (at @ coef).reshape(six.shape[0], 3) if m.size else 0.0
    return out @ _dof_map(_rotation(beta)).T


def excitation_transfer(coeffs: xr.Dataset, dofs: list[str], directions: Any
                        ) -> tuple[np.ndarray, np.ndarray]:
    """ω grid [rad/s] and F_e(ω, heading, dof) [N/m, N m/m] at each wave ``directions`` [rad]
    (module docstring: a stored heading, else the body's symmetry, else linear interpolation
    between the stored headings). Shape (n_omega, n_directions, n_dof).

    Positional indexing on the stored arrays: xarray's label selection costs more than the
    rest of a short simulation.
    """
    if "excitation_force" not in coeffs:
        raise InputError("coefficients have no 'excitation_force'; cannot apply waves")
    fe = coeffs.variables["excitation_force"]
    have = [str(v) for v in coeffs["influenced_dof"].values]
    missing = [d for d in dofs if d not in have]
    if missing:
        raise InputError(f"excitation_force has no DOF {missing}")
    dims = [d for d in fe.dims if d != "wave_direction"]
    if sorted(dims) != ["influenced_dof", "omega"]:
        raise InputError(f"excitation_force has dimensions {fe.dims}; expected omega, "
                         "influenced_dof and optionally wave_direction")
    order = ["omega", "wave_direction", "influenced_dof"] if "wave_direction" in fe.dims \
        else ["omega", "influenced_dof"]
    vals = np.asarray(fe.transpose(*order).values)
    if vals.ndim == 2:
        vals = vals[:, None, :]
    if not np.all(np.isfinite(vals)):
        raise InputError("excitation_force contains NaN/inf")
    dirs = (np.asarray(coeffs["wave_direction"].values, dtype=float).reshape(-1)
            if "wave_direction" in fe.dims else np.zeros(1))
    # the full six-vector (missing DOFs 0) so the symmetry maps can mix the DOFs
    six = np.zeros(vals.shape[:2] + (6,), dtype=complex)
    rigid = tuple(RIGID_DOFS)
    for j, name in enumerate(have):
        if name in rigid:
            six[:, :, rigid.index(name)] = vals[:, :, j]
    absent = [rigid.index(d) for d in rigid if d not in have]
    sym = heading_symmetry(coeffs)
    beta = np.asarray(directions, dtype=float).reshape(-1)
    out = np.empty((vals.shape[0], beta.size, len(dofs)), dtype=complex)
    cache: dict[float, np.ndarray] = {}
    for n, b in enumerate(beta):
        key = round(float(b), 12)
        if key not in cache:
            cache[key] = _heading_force(vals, six, dirs, have, rigid, absent, sym, float(b), dofs)
        out[:, n] = cache[key]
    return np.asarray(coeffs["omega"].values, dtype=float), out


def _heading_force(vals: np.ndarray, six: np.ndarray, dirs: np.ndarray, have: list[str],
                   rigid: tuple[str, ...], absent: list[int], sym: int | None, beta: float,
                   dofs: list[str]) -> np.ndarray:
    """F_e(ω, dof) at one heading (:func:`excitation_transfer`)."""
    rel = np.angle(np.exp(1j * (dirs - beta)))
    if np.min(np.abs(rel)) <= 1e-6:  # a stored heading: as stored, any DOF
        return vals[:, int(np.argmin(np.abs(rel)))][:, [have.index(d) for d in dofs]]
    rows = [rigid.index(d) if d in rigid else -1 for d in dofs]
    # another heading mixes the DOFs: all six needed, but a body of revolution's transverse
    # DOFs are 0 at its stored heading, so missing ones are exact zeros there
    if min(rows) < 0 or (absent and sym != 0):
        raise InputError(f"wave direction {beta:g} rad: the excitation at a heading the "
                         f"coefficients do not hold needs all six rigid DOFs (have {have})")
    full = _dihedral_heading(six, dirs, beta, sym) if sym else None
    if full is None:
        base, q = _reduce_heading(beta, sym, dirs)
        full = _stored_heading(six, dirs, base) @ _dof_map(q).T
    return full[:, rows]


def long_wave_limit(coeffs: xr.Dataset, dofs: list[str]) -> np.ndarray:
    """``F_e(ω → 0)`` [N/m, N m/m] on ``dofs``: a wave much longer than the body lifts the
    water around it uniformly, so the force per unit elevation is the hydrostatic stiffness
    against heave, ``C[dof, Heave]`` (C33; C35, C34 through the waterplane's moments); zero
    when the coefficients have no heave."""
    if "hydrostatic_stiffness" not in coeffs:
        raise InputError("coefficients have no 'hydrostatic_stiffness': the long-wave limit "
                         "of the excitation force is unknown")
    c = coeffs["hydrostatic_stiffness"]
    if "Heave" not in [str(d) for d in c["radiating_dof"].values]:
        return np.zeros(len(dofs))
    column = c.sel(radiating_dof="Heave")
    have = [str(d) for d in column["influenced_dof"].values]
    return np.array([float(column.values[have.index(d)]) if d in have else 0.0 for d in dofs])


def components_within(wave: Wave, grid: np.ndarray, what: str, hint: str, *,
                      allow_below: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [rad/s] and complex amplitudes ``a e^{-iφ}`` [m] of the wave's components
    with a nonzero amplitude, checked to lie inside ``grid``'s range (a transfer function is
    interpolated there, never extrapolated; else :class:`InputError` naming ``what`` and
    ``hint``). ``allow_below``: components below the range are the caller's to handle."""
    comp = wave.components()
    keep = comp.amplitude > 0
    w = comp.omega[keep]
    below = bool(w.size) and w.min() < grid[0] * (1 - 1e-9) and not allow_below
    if w.size and (below or w.max() > grid[-1] * (1 + 1e-9)):
        raise InputError(f"wave frequencies {w.min():.4g}–{w.max():.4g} rad/s fall outside "
                         f"{what} {grid[0]:.4g}–{grid[-1]:.4g} rad/s ({hint})")
    return w, comp.complex_amplitude[keep]


def excitation_force(wave: Wave, coeffs: xr.Dataset, t: np.ndarray,
                     dof: str | list[str] = "Heave", *, ramp: float = 0.0,
                     with_elevation: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Wave excitation force F_exc(t) [N] from the BEM transfer function.

    ``F_e(ω)`` is interpolated linearly (real and imaginary parts) at the wave's component
    frequencies, which must lie inside the coefficients' ω range; see the module docstring for
    the sign convention. ``ramp`` [s] multiplies the force by a half-cosine ramp to avoid the
    start-up transient.

    Returns
    -------
    ndarray, shape (nt,) for one ``dof`` (str) or (nt, n_dof) for a list.
        With ``with_elevation=True`` a pair ``(force, eta)``: the incident elevation η(t) [m]
        from the same harmonic sum, at no extra cost, ramped like the force: the sea the body
        was given, so that a history holding η alone is self-consistent (the excitation of
        its η through the transfer function is the force applied, within the impulse
        response's spread over the ramp; tests/test_hybrid_model.py measures it).
    """
    dofs = [dof] if isinstance(dof, str) else list(dof)
    comp = wave.components()
    beta = wave.component_directions(comp)[comp.amplitude > 0]
    unique, which = np.unique(beta, return_inverse=True)
    w_grid, vals = excitation_transfer(coeffs, dofs, unique)
    w, amplitude = components_within(wave, w_grid, "the coefficients' range",
                                     "narrow omega_range or recompute the BEM coefficients",
                                     allow_below=wave.long_waves)
    if w.size and w.min() < w_grid[0] * (1 - 1e-9):  # a record's long waves: towards ω = 0
        w_grid = np.concatenate([[0.0], w_grid])
        limit = np.broadcast_to(long_wave_limit(coeffs, dofs), (1, unique.size, len(dofs)))
        vals = np.concatenate([limit, vals])
    tf = np.empty((w.size, len(dofs)), dtype=complex)
    for u in range(unique.size):  # each heading's components (one for a long-crested sea)
        sel = which == u
        for i in range(len(dofs)):
            tf[sel, i] = (np.interp(w[sel], w_grid, vals[:, u, i].real)
                          + 1j * np.interp(w[sel], w_grid, vals[:, u, i].imag))
    c = amplitude[:, None]
    both = harmonic_sum(t, np.concatenate([c * tf, c], axis=1), w)
    force, eta = both[:, :-1], both[:, -1]
    r = ramp_factor(t, ramp)
    force *= r[:, None]
    eta *= r
    force = force[:, 0] if isinstance(dof, str) else force
    return (force, eta) if with_elevation else force
