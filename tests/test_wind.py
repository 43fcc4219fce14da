"""Hub-height wind: the Kaimal spectrum of IEC 61400-1, its rotor average, and the seeded
periodic realisation (hybridwsi.wind)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate
import scipy.special

from hybridwsi.errors import InputError
from hybridwsi.wind import (
    SteadyWind,
    TurbulentWind,
    kaimal_spectrum,
    length_scale,
    rotor_average,
    wind_from_dict,
)

U, HUB, R = 11.4, 90.0, 63.0


def test_kaimal_spectrum_integrates_to_the_variance():
    """∫₀^∞ S_u df = σ² (adaptive quadrature, independent of the closed-form integral), and
    IEC's integral scale above 60 m: L = 8.1 × 42 m."""
    assert length_scale(HUB) == pytest.approx(340.2)
    assert length_scale(50.0) == pytest.approx(8.1 * 35.0)
    sigma = 1.2
    total = scipy.integrate.quad(lambda f: kaimal_spectrum(f, U, sigma, HUB), 0, np.inf,
                                 limit=200)[0]
    assert total == pytest.approx(sigma**2, rel=1e-8)


def _struve_average(f: np.ndarray) -> np.ndarray:
    """The disk average in closed form (modified Struve L and Bessel I functions), as RAFT's
    Rotor.IECKaimal writes it: an independent derivation of the same χ(f)."""
    kappa = 12.0 * np.sqrt((f / U) ** 2 + (0.12 / length_scale(HUB)) ** 2)
    x = 2.0 * R * kappa
    sv, iv = scipy.special.modstruve, scipy.special.iv
    return 2.0 / (R * kappa) ** 3 * (sv(1, x) - iv(1, x) - 2 / math.pi
                                    + R * kappa * (-2 * sv(-2, x) + 2 * iv(2, x) + 1))


def test_rotor_average_against_two_independent_forms():
    """χ(f) by Gauss-Legendre equals the adaptive quadrature of the coherence over the disk
    line-picking density (1e-9), and the Struve closed form below 0.1 Hz (1e-7; above, the
    closed form loses digits to the cancellation of exponentially large terms: 3 % at 0.3 Hz).
    χ(0) < 1 (IEC's coherence keeps a frequency-independent decay, 12 × 0.12 d/L: 0.79 over
    this rotor); χ ≈ 2/(κR)² for eddies much smaller than the rotor."""
    f = np.array([0.0, 1e-4, 1e-3, 0.01, 0.03, 0.1, 0.3, 1.0, 2.0])
    chi = rotor_average(f, U, R, HUB)
    big_l = length_scale(HUB)
    for fk, ck in zip(f, chi):
        kappa = 12.0 * math.sqrt((fk / U) ** 2 + (0.12 / big_l) ** 2)

        def integrand(d: float) -> float:
            s = d / (2 * R)
            pdf = 4 * d / (math.pi * R * R) * (math.acos(s) - s * math.sqrt(1 - s * s))
            return math.exp(-kappa * d) * pdf

        ref = scipy.integrate.quad(integrand, 0, 2 * R, limit=400, epsabs=1e-15, epsrel=1e-12)[0]
        assert ck == pytest.approx(ref, rel=1e-9)
    low = f < 0.1
    np.testing.assert_allclose(chi[low], _struve_average(f[low]), rtol=1e-7)
    assert chi[0] == pytest.approx(0.7905, abs=1e-4)
    kappa = 12.0 * 2.0 / U
    assert chi[-1] == pytest.approx(2.0 / (kappa * R) ** 2, rel=0.1)


def test_realisation_has_the_spectrum_and_the_variance():
    """Over one period the periodogram at the realisation's frequencies is S(f_k) (the synthesis
    scaling, to rounding), and the variance is the spectrum's integral between 1/period and
    1/(2 dt) (closed form σ²[(1 + 6 f₁L/U)^(-2/3) − (1 + 6 f₂L/U)^(-2/3)]) within the Riemann
    sum's 2 %."""
    for radius in (None, R):
        wind = TurbulentWind(U, 0.12, seed=7, rotor_radius=radius, period=1800.0, dt=0.2)
        n = wind.values.size
        spec = np.fft.rfft(wind.values - U)
        f = wind.frequencies()
        periodogram = 2.0 * np.abs(spec[1:f.size + 1]) ** 2 / n**2 * wind.period
        np.testing.assert_allclose(periodogram, wind.spectrum(f), rtol=1e-9)
        assert np.mean(wind.values) == pytest.approx(U, abs=1e-12)
    point = TurbulentWind(U, 0.12, seed=7, rotor_radius=None, period=3600.0, dt=0.25)
    scale = 6.0 * length_scale(HUB) / U
    expected = point.sigma**2 * ((1 + scale / 3600.0) ** (-2 / 3) - (1 + scale * 2.0) ** (-2 / 3))
    assert np.var(point.values) == pytest.approx(expected, rel=0.02)
    # the rotor average removes the small eddies: the variance falls to ∫ χ S df / ∫ S df
    averaged = TurbulentWind(U, 0.12, seed=7, period=3600.0, dt=0.25)
    ratio = (scipy.integrate.quad(averaged.spectrum, 1 / 3600.0, 2.0, limit=400, points=[0.01])[0]
             / scipy.integrate.quad(point.spectrum, 1 / 3600.0, 2.0, limit=400, points=[0.01])[0])
    assert 0.4 < ratio < 0.5
    assert np.var(averaged.values) / np.var(point.values) == pytest.approx(ratio, rel=0.02)


def test_welch_estimate_of_a_long_realisation_follows_kaimal():
    """A different check of the same thing, as a user would do it: Welch's estimate over an
    hour (segments of 600 s) lies on the target spectrum within its ~20 % scatter between
    0.005 and 0.5 Hz."""
    import scipy.signal

    wind = TurbulentWind(U, 0.1, seed=3, rotor_radius=None, period=3600.0, dt=0.25)
    f, pxx = scipy.signal.welch(wind.values, fs=1 / wind.dt, nperseg=2400)
    band = (f >= 0.005) & (f <= 0.5)
    ratio = pxx[band] / wind.spectrum(f[band])
    assert abs(np.median(ratio) - 1.0) < 0.1
    assert np.all((ratio > 0.4) & (ratio < 2.5))


def test_seeded_periodic_and_interpolated():
    a = TurbulentWind(18.0, 0.1, seed=11, period=600.0)
    b = TurbulentWind(18.0, 0.1, seed=11, period=600.0)
    c = TurbulentWind(18.0, 0.1, seed=12, period=600.0)
    np.testing.assert_array_equal(a.values, b.values)
    assert np.abs(a.values - c.values).max() > 0.5
    t = np.linspace(0.0, 599.0, 1234)
    np.testing.assert_allclose(a.speed(t + 600.0), a.speed(t), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(a.speed(np.arange(4) * a.dt), a.values[:4])
    mid = a.speed(np.array([0.5 * a.dt]))[0]
    assert mid == pytest.approx(0.5 * (a.values[0] + a.values[1]))
    assert wind_from_dict(a.to_dict()).values.tobytes() == a.values.tobytes()
    steady = SteadyWind(8.0)
    assert np.all(steady.speed(np.arange(3.0)) == 8.0)
    assert wind_from_dict(steady.to_dict()) == steady


@pytest.mark.parametrize("kwargs", [dict(mean=-1.0, turbulence_intensity=0.1),
                                    dict(mean=10.0, turbulence_intensity=-0.1),
                                    dict(mean=10.0, turbulence_intensity=0.1, period=100.3),
                                    dict(mean=10.0, turbulence_intensity=0.1, seed=1.5),
                                    dict(mean=float("nan"), turbulence_intensity=0.1)])
def test_bad_wind_is_refused(kwargs):
    with pytest.raises(InputError):
        TurbulentWind(**kwargs)


def test_bad_steady_wind_and_type_are_refused():
    with pytest.raises(InputError):
        SteadyWind(-3.0)
    with pytest.raises(InputError, match="wind type"):
        wind_from_dict({"type": "gust"})
