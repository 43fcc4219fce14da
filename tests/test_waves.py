"""Waves: spectra against their closed forms, realisations, dispersion, excitation convention."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate

import synthetic_hydro as sh
from hybridwsi.errors import InputError
from hybridwsi.waves import (
    JONSWAP,
    AiryKinematics,
    PiersonMoskowitz,
    Regular,
    dispersion_k,
    excitation_force,
    particle_velocity,
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


# ---------------------------------------------------------------------- particle kinematics
def test_deep_water_particle_velocity_is_the_closed_form():
    """u = a ω e^{kz} cos(ωt + φ − kx), w = −a ω e^{kz} sin(ωt + φ − kx) for η = a cos(ωt + φ)
    at x = 0 (so w(z = 0) = ∂η/∂t), and the same with the wave turned by β along its ray."""
    g, a, period, phase = 9.80665, 1.5, 8.0, 0.4
    w_ = 2 * np.pi / period
    k = w_**2 / g
    t = np.linspace(0.0, 30.0, 61)
    z = np.array([-60.0, -10.0, -1.0, 0.0])
    x = 17.0
    theta = w_ * t[:, None] + phase - k * x
    u, w = particle_velocity(Regular(period, 2 * a, phase), t, x, z, g=g)
    np.testing.assert_allclose(u, a * w_ * np.exp(k * z) * np.cos(theta), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(w, -a * w_ * np.exp(k * z) * np.sin(theta), rtol=1e-12, atol=1e-14)
    # the kinematic free-surface condition of linear theory at x = 0
    eta_dot = -a * w_ * np.sin(w_ * t + phase)
    _, w0 = particle_velocity(Regular(period, 2 * a, phase), t, 0.0, 0.0, g=g)
    np.testing.assert_allclose(w0, eta_dot, rtol=1e-12, atol=1e-14)
    # oblique wave: the phase depends on the distance along the ray, x cos β + y sin β
    beta = 0.7
    u_b, w_b = particle_velocity(Regular(period, 2 * a, phase, direction=beta), t,
                                 x * np.cos(beta), z, y=x * np.sin(beta), g=g)
    np.testing.assert_allclose(u_b, u, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(w_b, w, rtol=1e-10, atol=1e-12)


def test_finite_depth_particle_velocity_is_the_cosh_sinh_form():
    """u = a ω cosh(k(z+h))/sinh(kh) cos θ, w = −a ω sinh(k(z+h))/sinh(kh) sin θ, k from
    ω² = g k tanh(kh); w = 0 on the seabed, and a scalar time or point drops its axis."""
    g, h, a, period, phase = 9.81, 12.0, 0.5, 9.0, -1.1
    w_ = 2 * np.pi / period
    k = dispersion_k(w_, h, g)
    assert w_**2 == pytest.approx(g * k * np.tanh(k * h), rel=1e-12)
    t = np.linspace(0.0, 20.0, 41)
    z = np.linspace(-h, 0.0, 7)
    x = -5.0
    theta = w_ * t[:, None] + phase - k * x
    wave = Regular(period, 2 * a, phase)
    u, w = particle_velocity(wave, t, x, z, depth=h, g=g)
    np.testing.assert_allclose(
        u, a * w_ * np.cosh(k * (z + h)) / np.sinh(k * h) * np.cos(theta), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(
        w, -a * w_ * np.sinh(k * (z + h)) / np.sinh(k * h) * np.sin(theta), rtol=1e-12, atol=1e-14)
    assert np.abs(w[:, 0]).max() < 1e-14  # impermeable seabed
    u1, w1 = particle_velocity(wave, t[5], x, z[3], depth=h, g=g)
    assert np.shape(u1) == np.shape(w1) == ()
    assert u1 == pytest.approx(u[5, 3], rel=1e-12) and w1 == pytest.approx(w[5, 3], rel=1e-12)


@pytest.mark.parametrize("depth", [np.inf, 30.0])
def test_particle_velocity_is_divergence_free(depth):
    """Continuity ∂u/∂x + ∂w/∂z = 0 for an irregular sea (central differences: truncation
    (k δ)²/6 ~ 1e-9 relative; a wrong sign or profile of w leaves a residual of order 1)."""
    wave = JONSWAP(hs=3.0, tp=9.0, seed=4, n_components=40)
    t, x, z, d = np.array([3.0, 11.7, 25.2]), 4.0, np.array([-20.0, -6.0, -1.5]), 1e-4
    u_p, _ = particle_velocity(wave, t, x + d, z, depth=depth)
    u_m, _ = particle_velocity(wave, t, x - d, z, depth=depth)
    _, w_p = particle_velocity(wave, t, x, z + d, depth=depth)
    _, w_m = particle_velocity(wave, t, x, z - d, depth=depth)
    du_dx, dw_dz = (u_p - u_m) / (2 * d), (w_p - w_m) / (2 * d)
    assert np.abs(du_dx).max() > 1e-2  # a real gradient, not two zeros
    np.testing.assert_allclose(du_dx + dw_dz, 0.0, atol=1e-7 * np.abs(du_dx).max())


def test_kinematics_scalar_and_array_times_agree_and_ramp():
    """One time (a solver stage) and a time series take different routes: same numbers; the
    ramp scales both velocities by ½(1 − cos πt/T_r) (none at all when T_r = 0, even t < 0)."""
    wave = JONSWAP(hs=2.0, tp=7.0, seed=2, n_components=30, direction=0.3)
    z = np.array([-30.0, -3.0])
    line = AiryKinematics(wave, z, 2.0, -1.0, depth=50.0, ramp=10.0)
    t = np.array([-1.0, 0.0, 4.0, 10.0, 33.3])
    series_u, series_w = line.speed(t), line.vertical(t)
    for i, ti in enumerate(t):
        np.testing.assert_allclose(line.speed(ti), series_u[i], rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(line.vertical(ti), series_w[i], rtol=1e-12, atol=1e-15)
    bare = AiryKinematics(wave, z, 2.0, -1.0, depth=50.0)
    np.testing.assert_allclose(series_u[2], bare.speed(4.0) * 0.5 * (1 - np.cos(0.4 * np.pi)),
                               rtol=1e-12)
    assert np.all(series_u[:2] == 0.0) and np.all(series_w[:2] == 0.0)
    np.testing.assert_allclose(bare.speed(-1.0), bare.speed(np.array([-1.0]))[0], rtol=1e-12)
    ux, uy = line.components(t)
    np.testing.assert_allclose(np.hypot(ux, uy), np.abs(series_u), rtol=1e-14)
    np.testing.assert_allclose(uy[2:] / ux[2:], np.tan(0.3), rtol=1e-12)  # zeros before t = 0


def test_kinematics_below_the_seabed_is_an_input_error():
    with pytest.raises(InputError, match="below the seabed"):
        particle_velocity(Regular(8.0, 1.0), 0.0, 0.0, [-5.0, -21.0], depth=20.0)
    with pytest.raises(InputError, match="ramp"):
        AiryKinematics(Regular(8.0, 1.0), [-1.0], ramp=-1.0)
