"""Wind at the rotor: steady, or turbulent with the Kaimal spectrum of IEC 61400-1.

Only the longitudinal (along +X, downwind) component at hub height is modelled: the wind the
rotor's thrust responds to. No shear, no lateral or vertical components, no rotational
sampling (a blade sweeping through eddies puts energy at 3P; the thrust of
:class:`hybridwsi.forces.rotor.OperatingRotor` sees the disk-averaged wind).

Spectrum (IEC 61400-1:2005 Annex B, Eqs. B.14 and B.15; one-sided, in Hz, [(m/s)²/Hz]):

    S_u(f) = 4 σ² (L/U) / (1 + 6 f L/U)^{5/3},     L = 8.1 Λ,  Λ = 0.7 z_hub (z_hub ≤ 60 m)
                                                                 or 42 m (above)

with σ = TI · U (the case gives the turbulence intensity TI; IEC's normal turbulence model
would give σ = I_ref (0.75 U + 5.6)). Its integral from 0 to f is σ² [1 − (1 + 6 f L/U)^{−2/3}].

Rotor average: the disk-averaged wind of a rotor of radius R has the spectrum
S_rot(f) = χ(f) S_u(f), with χ the mean of IEC's exponential coherence (Eq. B.16)

    Coh(d, f) = exp(−12 √((f d/U)² + (0.12 d/L)²))

over two points drawn uniformly on the disk, whose distance d has the density
p(d) = (4d/(πR²)) [acos(d/2R) − (d/2R) √(1 − (d/2R)²)] on [0, 2R] (disk line picking):
χ(f) = ∫₀^{2R} Coh(d, f) p(d) dd, evaluated by Gauss–Legendre quadrature. RAFT's
``Rotor.IECKaimal`` gives the same quantity in closed form (modified Struve and Bessel
functions; tests compare the two). Why the disk average is enough here: the thrust of a
BEM rotor is an integral over the disk of loads that are, to first order, linear in the local
wind, so its low-frequency fluctuation is that of the disk-averaged wind; eddies smaller than
the rotor (f ≳ U/(2R) ≈ 0.1 Hz at 12 m/s) average out.

Realisation (as TurbSim does): periodic, with period ``period`` (default 3600 s) sampled at
``dt``: frequencies f_k = k/period (k = 1 … n/2 − 1, n = period/dt), amplitudes
a_k = √(2 S(f_k) Δf), phases uniform on [0, 2π) from ``numpy.random.default_rng(seed)``,

    u(t_j) = U + Σ_k a_k cos(2π f_k t_j + φ_k)          (one inverse real FFT),

linearly interpolated between samples and repeated after ``period``. Its variance is
Σ a_k²/2, the spectrum's integral from 1/period to 1/(2 dt) (a Riemann sum of it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hybridwsi.errors import InputError

#: Gauss–Legendre nodes of the disk-average quadrature (the integrand is smooth)
_QUAD_NODES = 64


def number(name: str, value: Any, *, positive: bool = False, minimum: float | None = None
           ) -> float:
    """``value`` as a finite float (optionally > 0 or ≥ ``minimum``), else InputError."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v) or (positive and v <= 0) or (minimum is not None and v < minimum):
        need = "positive" if positive else (f">= {minimum:g}" if minimum is not None else "")
        raise InputError(f"{name} must be a finite {need} number, got {value!r}".replace("  ", " "))
    return v


def length_scale(hub_height: float) -> float:
    """IEC 61400-1 longitudinal integral scale L = 8.1 Λ [m] (Λ = 0.7 z below 60 m, else 42 m)."""
    return 8.1 * (0.7 * hub_height if hub_height <= 60.0 else 42.0)


def kaimal_spectrum(f: np.ndarray, mean: float, sigma: float, hub_height: float) -> np.ndarray:
    """Kaimal spectrum S_u(f) [(m/s)²/Hz] of the longitudinal wind at a point (module doc).

    Parameters
    ----------
    f : array_like
        Frequency [Hz] (≥ 0).
    mean : float
        Mean hub-height wind speed U [m/s].
    sigma : float
        Standard deviation σ [m/s].
    hub_height : float
        Height of the point [m] (sets the integral scale).
    """
    scale = length_scale(hub_height) / mean
    return 4.0 * sigma**2 * scale / (1.0 + 6.0 * np.asarray(f, dtype=float) * scale) ** (5 / 3)


def rotor_average(f: np.ndarray, mean: float, radius: float, hub_height: float) -> np.ndarray:
    """χ(f): ratio of the disk-averaged to the point spectrum (module doc), shape of ``f``."""
    f = np.asarray(f, dtype=float)
    x, w = np.polynomial.legendre.leggauss(_QUAD_NODES)
    d = radius * (x + 1.0)  # nodes on [0, 2R]
    s = d / (2.0 * radius)
    pdf = 4.0 * d / (math.pi * radius**2) * (np.arccos(s) - s * np.sqrt(1.0 - s**2))
    big_l = length_scale(hub_height)
    kappa = 12.0 * np.sqrt((f[..., None] / mean) ** 2 + (0.12 / big_l) ** 2)
    return np.exp(-kappa * d) @ (w * pdf * radius)


@dataclass(frozen=True)
class SteadyWind:
    """A constant hub-height wind ``mean`` [m/s] along +X."""

    mean: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean", number("wind speed", self.mean, minimum=0.0))

    def speed(self, t: float | np.ndarray) -> np.ndarray:
        """Wind speed [m/s] at times ``t`` [s] (same shape)."""
        return np.full(np.shape(t), self.mean)

    def samples(self) -> tuple[float, np.ndarray]:
        """``(dt, u)``: the periodic samples a kernel interpolates (one sample: constant)."""
        return 1.0, np.array([self.mean])

    def to_dict(self) -> dict[str, Any]:
        return {"type": "steady", "mean": self.mean}

    def describe(self) -> str:
        return f"steady wind {self.mean:g} m/s"


@dataclass(frozen=True)
class TurbulentWind:
    """Turbulent hub-height wind with the Kaimal spectrum, seeded and periodic (module doc).

    Parameters
    ----------
    mean : float
        Mean hub-height wind speed U [m/s].
    turbulence_intensity : float
        σ/U (e.g. 0.1; IEC class B at 15 m/s: 0.157).
    seed : int
        Seed of the random phases (``numpy.random.default_rng``).
    hub_height : float
        [m], sets the integral scale.
    rotor_radius : float or None
        R [m] of the disk average; None: the point spectrum at the hub.
    period, dt : float
        Repeat period and sample step [s] of the realisation.
    """

    mean: float
    turbulence_intensity: float
    seed: int = 0
    hub_height: float = 90.0
    rotor_radius: float | None = 63.0
    period: float = 3600.0
    dt: float = 0.25
    values: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 - frozen dataclass
        set_("mean", number("wind speed", self.mean, positive=True))
        set_("turbulence_intensity", number("turbulence intensity", self.turbulence_intensity,
                                            minimum=0.0))
        set_("hub_height", number("hub height", self.hub_height, positive=True))
        if self.rotor_radius is not None:
            set_("rotor_radius", number("rotor radius", self.rotor_radius, positive=True))
        set_("period", number("wind period", self.period, positive=True))
        set_("dt", number("wind time step", self.dt, positive=True))
        if not isinstance(self.seed, (int, np.integer)) or isinstance(self.seed, bool):
            raise InputError(f"wind seed must be an integer, got {self.seed!r}")
        n = int(round(self.period / self.dt))
        if n < 4 or abs(n * self.dt - self.period) > 1e-9 * self.period:
            raise InputError(f"wind period {self.period:g} s must be a whole number (>= 4) of "
                             f"steps dt = {self.dt:g} s")
        set_("values", self._realisation(n))

    @property
    def sigma(self) -> float:
        """σ = TI · U [m/s] of the point spectrum."""
        return self.turbulence_intensity * self.mean

    def spectrum(self, f: np.ndarray) -> np.ndarray:
        """Spectrum [(m/s)²/Hz] the realisation is drawn from: Kaimal × χ (or the point one)."""
        s = kaimal_spectrum(f, self.mean, self.sigma, self.hub_height)
        if self.rotor_radius is None:
            return s
        return s * rotor_average(f, self.mean, self.rotor_radius, self.hub_height)

    def frequencies(self) -> np.ndarray:
        """The realisation's frequencies f_k = k/period [Hz], k = 1 … n/2 − 1."""
        n = self.values.size
        return np.arange(1, (n + 1) // 2) / self.period

    def _realisation(self, n: int) -> np.ndarray:
        f = np.arange(1, (n + 1) // 2) / self.period
        amp = np.sqrt(2.0 * self.spectrum(f) / self.period)
        phase = np.random.default_rng(self.seed).uniform(0.0, 2.0 * math.pi, f.size)
        coef = np.zeros(n // 2 + 1, dtype=complex)
        coef[1:f.size + 1] = 0.5 * n * amp * np.exp(1j * phase)
        return self.mean + np.fft.irfft(coef, n)

    def speed(self, t: float | np.ndarray) -> np.ndarray:
        """Wind speed [m/s] at times ``t`` [s]: linear between samples, periodic."""
        return periodic_interp(np.asarray(t, dtype=float), self.dt, self.values)

    def samples(self) -> tuple[float, np.ndarray]:
        """``(dt, u)``: the periodic samples (:func:`periodic_interp`)."""
        return self.dt, self.values

    def to_dict(self) -> dict[str, Any]:
        return {"type": "kaimal", "mean": self.mean,
                "turbulence_intensity": self.turbulence_intensity, "seed": int(self.seed),
                "hub_height": self.hub_height, "rotor_radius": self.rotor_radius,
                "period": self.period, "dt": self.dt}

    def describe(self) -> str:
        avg = "point" if self.rotor_radius is None else f"rotor-averaged R {self.rotor_radius:g} m"
        return (f"Kaimal wind {self.mean:g} m/s, TI {self.turbulence_intensity:g}, seed "
                f"{self.seed}, {avg}, period {self.period:g} s")


def periodic_interp(t: np.ndarray, dt: float, values: np.ndarray) -> np.ndarray:
    """Samples ``values[k]`` at ``k dt``, repeating with period ``len(values) dt``, linearly
    interpolated at ``t`` [s] (the arithmetic of the rotor's compiled kernel)."""
    x = t / dt
    k = np.floor(x)
    w = x - k
    n = values.size
    i = np.mod(k, n).astype(np.int64)
    return values[i] * (1.0 - w) + values[(i + 1) % n] * w


def wind_from_dict(d: dict[str, Any]) -> SteadyWind | TurbulentWind:
    """Inverse of ``to_dict`` (``{"type": "steady" | "kaimal", ...}``)."""
    kind = d.get("type")
    args = {k: v for k, v in d.items() if k != "type"}
    if kind == "steady":
        return SteadyWind(**args)
    if kind == "kaimal":
        return TurbulentWind(**args)
    raise InputError(f"unknown wind type {kind!r} (steady, kaimal)")
