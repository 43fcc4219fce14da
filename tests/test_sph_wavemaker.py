"""Pure-Python parts of the SPH tank: Biésel transfer function, dispersion, paddle motion,
wave analysis, the Martin & Moyce table. No PySPH needed (except one cross-check)."""

import math

import numpy as np
import pytest

from hybridwsi.errors import InputError
from hybridwsi.sph import wavemaker as wm
from hybridwsi.sph.dam_break import MARTIN_MOYCE_N2_A225


def _biesel_textbook(kd):
    # Dean & Dalrymple (1991) Eq. 6.25, written as printed
    return 2 * (np.cosh(2 * kd) - 1) / (np.sinh(2 * kd) + 2 * kd)


@pytest.mark.parametrize("kd", [0.05, 0.3, 1.0, 2.5, 6.0])
def test_biesel_matches_textbook_formula(kd):
    assert wm.biesel_ratio(kd) == pytest.approx(_biesel_textbook(kd), rel=1e-12)


def test_biesel_shallow_and_deep_limits():
    # shallow water: H/S -> kd (piston displaces the whole column); deep water: H/S -> 2
    for kd in (1e-4, 1e-3):
        assert wm.biesel_ratio(kd) == pytest.approx(kd, rel=1e-5)
    assert wm.biesel_ratio(20.0) == pytest.approx(2.0, rel=1e-12)


def test_wavenumber_solves_dispersion_and_limits():
    g = 9.81
    for T, d in [(0.75, 0.9), (1.0, 0.4), (5.0, 0.1)]:
        k = wm.wavenumber(T, d, g)
        assert g * k * math.tanh(k * d) == pytest.approx((2 * math.pi / T) ** 2, rel=1e-10)
    # deep water k = omega^2/g, shallow water k = omega / sqrt(g d)
    assert wm.wavenumber(0.5, 50.0) == pytest.approx((2 * math.pi / 0.5) ** 2 / g, rel=1e-10)
    w = 2 * math.pi / 60.0
    assert wm.wavenumber(60.0, 1.0) == pytest.approx(w / math.sqrt(g * 1.0), rel=1e-3)


def test_piston_stroke_gives_height():
    T, d, H = 0.75, 0.9, 0.05
    S = wm.piston_stroke(H, T, d)
    k = wm.wavenumber(T, d)
    assert S * _biesel_textbook(k * d) == pytest.approx(H, rel=1e-12)


def test_piston_motion_derivatives_consistent():
    S, T, tr = 0.04, 1.0, 2.0
    eps = 1e-6
    for t in (0.3, 1.1, 1.9, 2.5, 7.3):
        x_m, v_m, _ = wm.piston_motion(t - eps, S, T, tr)
        x_p, v_p, _ = wm.piston_motion(t + eps, S, T, tr)
        _, v, a = wm.piston_motion(t, S, T, tr)
        assert (x_p - x_m) / (2 * eps) == pytest.approx(v, rel=1e-6, abs=1e-9)
        assert (v_p - v_m) / (2 * eps) == pytest.approx(a, rel=1e-5, abs=1e-7)
    # after the ramp the amplitude is S/2
    xs = [wm.piston_motion(t, S, T, tr)[0] for t in np.linspace(3, 4, 401)]
    assert max(xs) == pytest.approx(S / 2, rel=1e-4)


def test_zero_upcrossing_on_known_sine():
    t = np.arange(0, 20, 0.01)
    H, T, n = wm.zero_upcrossing(t, 0.02 * np.sin(2 * np.pi * t / 1.3) + 0.5, t_start=2.0)
    assert T == pytest.approx(1.3, rel=1e-3)
    assert H == pytest.approx(0.04, rel=1e-3)
    assert n >= 10


def test_group_velocity_limits_and_energy_flux_derivative():
    g = 9.81
    # deep water: c_g = g T / (4 pi); shallow: sqrt(g d)
    assert wm.group_velocity(0.75, 50.0, g) == pytest.approx(g * 0.75 / (4 * math.pi), rel=1e-6)
    assert wm.group_velocity(60.0, 0.2, g) == pytest.approx(math.sqrt(g * 0.2), rel=1e-3)
    # independent definition: c_g = d omega / d k from the dispersion relation
    d, T = 0.45, 0.75
    k = wm.wavenumber(T, d, g)
    omega = lambda kk: math.sqrt(g * kk * math.tanh(kk * d))  # noqa: E731
    dk = 1e-6 * k
    assert wm.group_velocity(T, d, g) == pytest.approx((omega(k + dk) - omega(k - dk)) / (2 * dk),
                                                       rel=1e-6)


def test_probe_waves_skips_the_transient_before_the_ramped_train_arrives():
    # a wave train whose front reaches each probe at x / c_g: before it, a larger transient
    # that the analysis must leave out
    T, d, t_ramp = 0.75, 0.45, 1.5
    cg = wm.group_velocity(T, d)
    t = np.arange(0.0, 12.0, 0.005)
    xs = np.array([0.9, 1.8])
    eta = np.zeros((t.size, 2))
    for i, x in enumerate(xs):
        arrive = t_ramp + x / cg
        eta[:, i] = np.where(t < arrive, 0.05 * np.sin(2 * np.pi * t / 1.1),
                             (0.01 * (i + 1)) * np.sin(2 * np.pi * t / T))
    res = wm.probe_waves(t, eta, xs, T, d, t_ramp)
    for i, r in enumerate(res):
        assert r["t_start"] == pytest.approx(t_ramp + xs[i] / cg + T)
        assert r["H"] == pytest.approx(0.02 * (i + 1), rel=2e-3)
        assert r["T"] == pytest.approx(T, rel=2e-3)
    with pytest.raises(InputError, match="probes"):
        wm.probe_waves(t, eta[:, :1], xs, T, d, t_ramp)


@pytest.mark.parametrize("bad", [{"period": -1, "depth": 1}, {"period": 1, "depth": 0},
                                 {"period": float("nan"), "depth": 1}])
def test_bad_input_raises_input_error(bad):
    with pytest.raises(InputError):
        wm.wavenumber(**bad)
    with pytest.raises(InputError):
        wm.zero_upcrossing(np.arange(10.0), np.ones(10))


def test_martin_moyce_table_is_pysph_s():
    pytest.importorskip("pysph")
    from pysph.examples.db_exp_data import get_martin_moyce_2

    t, z = get_martin_moyce_2()
    np.testing.assert_array_equal(MARTIN_MOYCE_N2_A225, np.c_[t, z])


def test_koshizuka_oka_tables_are_pysph_s():
    pytest.importorskip("pysph")
    from pysph.examples.db_exp_data import (
        get_koshizuka_oka_data,
        get_koshizuka_oka_mps_data,
    )

    from hybridwsi.sph.dam_break import KOSHIZUKA_OKA_EXP, KOSHIZUKA_OKA_MPS

    np.testing.assert_array_equal(KOSHIZUKA_OKA_EXP, np.c_[get_koshizuka_oka_data()])
    np.testing.assert_array_equal(KOSHIZUKA_OKA_MPS, np.c_[get_koshizuka_oka_mps_data()])


# --------------------------------------------------------------------------- free-surface probe
class _Particles:
    """Stand-in for a PySPH fluid array (the probe reads x, y, z, m, rho, h only)."""

    def __init__(self, x, y, vol, dp):
        self.x, self.y, self.z = x, y, np.zeros_like(x)
        self.m, self.rho, self.h = 1000.0 * vol, np.full_like(x, 1000.0), np.full_like(x, 1.3 * dp)

    def get_number_of_particles(self):
        return len(self.x)


def _wave_particles(dp, depth, amp, k, phase, jitter, seed, length=3.0):
    # still-water lattice stretched vertically to the linear-wave surface depth + eta(x), as the
    # particles of a long wave are; volumes stretched alike; then random disorder of +-jitter dp
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid(np.arange(dp / 2, length, dp), np.arange(dp / 2, depth, dp),
                         indexing="ij")
    x, y = gx.ravel(), gy.ravel()
    stretch = 1.0 + amp * np.cos(k * x - phase) / depth
    x = x + jitter * dp * rng.uniform(-1, 1, x.size)
    y = y * stretch + jitter * dp * rng.uniform(-1, 1, x.size)
    return _Particles(x, y, dp * dp * stretch, dp)


def test_free_surface_probe_flat_lattice_and_droplet():
    from hybridwsi.sph.tank import free_surface

    dp, d = 0.02, 0.4
    calm = _wave_particles(dp, d, 0.0, 1.0, 0.0, 0.0, 0)
    assert free_surface(calm, 1.5, dp, 2) == pytest.approx(d, abs=0.02 * dp)
    # a detached droplet 5 dp above the probe is not the free surface
    drop = _Particles(np.r_[calm.x, 1.5], np.r_[calm.y, d + 5 * dp], np.r_[calm.m / 1000, dp * dp], dp)
    assert free_surface(drop, 1.5, dp, 2) == pytest.approx(d, abs=0.02 * dp)


def test_free_surface_probe_tracks_a_disordered_linear_wave():
    # H/dp = 2.5 as in the validation run; particles disordered by +-0.2 dp (SPH particles are
    # never on a lattice). Reference: the analytic surface A cos(kx - wt). The former probe
    # (top particle + dp/2) measured H 27 % low here: noise makes extra zero up-crossings.
    from hybridwsi.sph.tank import free_surface

    dp, d, amp, lam = 0.02, 0.4, 0.025, 1.46
    k, xp = 2 * np.pi / lam, 1.5
    t = np.arange(0.0, 3.0, 0.02)
    eta = np.array([free_surface(_wave_particles(dp, d, amp, k, 2 * np.pi * ti, 0.2, i), xp, dp, 2)
                    for i, ti in enumerate(t)]) - d
    exact = amp * np.cos(k * xp - 2 * np.pi * t)
    assert np.max(np.abs(eta - exact)) < 0.25 * dp
    H, T, _ = wm.zero_upcrossing(t, eta)
    assert H == pytest.approx(2 * amp, rel=0.08)
    assert T == pytest.approx(1.0, rel=0.02)
