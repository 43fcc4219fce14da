"""Waves: spectra against their closed forms, realisations, dispersion, excitation convention."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate

import synthetic_hydro as sh
from hybridwsi.errors import InputError
from hybridwsi.waves import (
    JONSWAP,
    PiersonMoskowitz,
    Regular,
    dispersion_k,
    excitation_force,
    wave_from_dict,
)


def _m0(spectrum, wp: float) -> float:
    return (scipy.integrate.quad(spectrum, 0, wp, limit=200)[0]
            + scipy.integrate.quad(spectrum, wp, np.inf, limit=200)[0])


def test_pierson_moskowitz_is_the_closed_form_and_integrates_to_hs2_over_16():
    hs, tp = 0.1, 1.2
    wp = 2 * np.pi / tp
    pm = PiersonMoskowitz(hs, tp)
    w = np.linspace(0.2, 40, 500)
    closed = 5 / 16 * hs**2 * wp**4 * w**-5 * np.exp(-1.25 * (w / wp) ** -4)  # DNV-RP-C205
    np.testing.assert_allclose(pm.spectrum(w), closed, rtol=1e-6)
    m0 = _m0(pm.spectrum, wp)
    assert m0 == pytest.approx(hs**2 / 16, rel=1e-6)


def test_jonswap_peak_normalisation_and_m0():
    hs, tp, gamma = 0.08, 1.0, 3.3
    js = JONSWAP(hs, tp, gamma=gamma)
    wp = 2 * np.pi / tp
    w = np.linspace(0.5 * wp, 3 * wp, 20001)
    assert w[np.argmax(js.spectrum(w))] == pytest.approx(wp, rel=2e-3)
    # peak enhancement: S_J(ωp) / S_PM(ωp) = γ × normalisation, DNV: 1 − 0.287 ln γ
    ratio = js.spectrum(wp) / PiersonMoskowitz(hs, tp).spectrum(wp)
    assert ratio / gamma == pytest.approx(1 - 0.287 * np.log(gamma), rel=0.02)
    m0 = _m0(js.spectrum, wp)
    assert m0 == pytest.approx(hs**2 / 16, rel=1e-5)


def test_realisation_variance_is_m0_and_seeded():
    hs, tp = 0.06, 0.9
    js = JONSWAP(hs, tp, seed=7, n_components=256)
    comp = js.components()
    dw = comp.omega[1] - comp.omega[0]
    t = np.arange(0, 2 * np.pi / dw, 0.01)  # one full repeat period: exact variance Σ a²/2
    eta = js.elevation(t)
    assert np.var(eta) == pytest.approx(np.sum(comp.amplitude**2) / 2, rel=1e-3)
    assert np.var(eta) == pytest.approx(hs**2 / 16, rel=0.03)  # band holds > 97 % of m0
    assert np.array_equal(eta, JONSWAP(hs, tp, seed=7, n_components=256).elevation(t))
    assert not np.allclose(eta, JONSWAP(hs, tp, seed=8, n_components=256).elevation(t))
    assert wave_from_dict(js.to_dict()).elevation(t[:100]) == pytest.approx(eta[:100])


def test_regular_wave_elevation():
    wave = Regular(period=0.75, height=0.05, phase=0.3)
    t = np.linspace(0, 3, 301)
    np.testing.assert_allclose(wave.elevation(t), 0.025 * np.cos(2 * np.pi / 0.75 * t + 0.3),
                               atol=1e-15)


def test_dispersion_limits_and_residual():
    g = 9.81
    w = np.array([0.5, 2.0, 8.0])
    h = 0.9
    k = dispersion_k(w, h, g)
    np.testing.assert_allclose(w**2, g * k * np.tanh(k * h), rtol=1e-12)
    np.testing.assert_allclose(dispersion_k(w, 1e4, g), w**2 / g, rtol=1e-10)  # deep
    np.testing.assert_allclose(dispersion_k(w, np.inf, g), w**2 / g)
    kh_small = dispersion_k(0.01, 0.5, g)  # shallow: k = ω / sqrt(g h)
    assert kh_small == pytest.approx(0.01 / np.sqrt(g * 0.5), rel=1e-4)
    with pytest.raises(InputError):
        dispersion_k(-1.0, 1.0)


def test_excitation_force_convention_and_ramp():
    # Capytaine: F(t) = Re[a F_e e^{-i(ωt+φ)}], so the force lags the crest by arg(F_e)
    co = sh.coefficients()
    w = float(co.omega[80])
    wave = Regular(2 * np.pi / w, 0.04, phase=0.2)
    t = np.linspace(0, 5, 1001)
    fe = complex(co.excitation_force.values[80, 0, 0])
    expected = 0.02 * abs(fe) * np.cos(w * t + 0.2 - np.angle(fe))
    np.testing.assert_allclose(excitation_force(wave, co, t), expected, atol=1e-9 * abs(fe))
    ramped = excitation_force(wave, co, t, ramp=2.0)
    assert ramped[0] == 0.0
    np.testing.assert_allclose(ramped[t >= 2.0], expected[t >= 2.0], atol=1e-12)
    two = excitation_force(wave, co, t, ["Heave"])
    assert two.shape == (t.size, 1)


def test_excitation_outside_coefficient_range_is_an_input_error():
    co = sh.coefficients(np.linspace(1.0, 20.0, 50))
    with pytest.raises(InputError, match="outside"):
        excitation_force(Regular(10.0, 0.1), co, np.linspace(0, 1, 10))
    with pytest.raises(InputError, match="wave direction"):
        excitation_force(Regular(1.0, 0.1, direction=1.0), co, np.linspace(0, 1, 10))


@pytest.mark.parametrize("make", [lambda: Regular(-1, 0.1), lambda: Regular(1, float("nan")),
                                  lambda: JONSWAP(0.1, 1.0, gamma=0.5),
                                  lambda: JONSWAP(0.1, 1.0, omega_range=(3.0, 1.0))])
def test_bad_wave_parameters(make):
    with pytest.raises(InputError):
        make()


@pytest.fixture(scope="module")
def bem_long_waves(tmp_path_factory):
    pytest.importorskip("capytaine")
    from hybridwsi.bodies import FloatingSphere
    from hybridwsi.hydro import bem

    sphere = FloatingSphere.paper()
    co = bem.compute(sphere, np.array([0.2, 0.4, 8.0]), n_panels=400, use_cache=False,
                     progress=False, include_inf=False, include_zero=False)
    return sphere, co


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_long_wave_excitation_is_hydrostatic_and_in_phase(bem_long_waves):
    # independent physics: for λ ≫ R the heave excitation is F = ρ g A_wp η (Froude–Krylov),
    # in phase with the elevation; checks the e^{-iωt} convention end to end with Capytaine
    sphere, co = bem_long_waves
    c33 = sphere.rho * sphere.g * np.pi * sphere.radius**2
    wave = Regular(2 * np.pi / 0.2, 1.0)
    t = np.linspace(0, wave.period, 400)
    f = excitation_force(wave, co, t)
    np.testing.assert_allclose(f, c33 * wave.elevation(t), atol=0.01 * c33)
