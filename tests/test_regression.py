"""Regression of the black-box force (paper Eq. 5–7) against analytic truth."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st

from _diag_cases import A_INF, C_HS, M, forced_oscillator, multisine
from hybridwsi.diagnostic import (
    AddedMass,
    Hydrostatic,
    LinearDamping,
    frequency_domain_split,
    regress,
)
from hybridwsi.errors import InputError
from hybridwsi.history import make_history

T = np.arange(0.0, 30.0, 0.01)
OMEGAS = (3.1, 5.7, 8.4)


def _multisine_history(alpha, beta, gamma, fbar=1.5, noise_f=None, dof=("Heave",)):
    """History whose F_tot = F̄ + α z̈ + β ż + γ z exactly (plus optional force noise)."""
    nd = len(dof)
    cols = [multisine(T, [0.02, 0.01, 0.006], np.array(OMEGAS) * (1 + 0.13 * j),
                      [0.3 + j, 1.1, 2.0 * j], offset=0.004 * (j + 1)) for j in range(nd)]
    z, zd, zdd = (np.stack([c[k] for c in cols], axis=1) for k in range(3))
    al, be, ga = (np.atleast_2d(x) for x in (alpha, beta, gamma))
    f = fbar + zdd @ al.T + zd @ be.T + z @ ga.T
    if noise_f is not None:
        f = f + noise_f
    return make_history(T, z, zd, zdd, forces={"F_tot": f}, dof=list(dof), mass=M)


def test_multifrequency_1dof_exact():
    res = regress(_multisine_history(10.56, -0.4, 692.2))
    assert res.identifiable
    np.testing.assert_allclose([res.alpha[0, 0], res.beta[0, 0], res.gamma[0, 0]],
                               [10.56, -0.4, 692.2], rtol=1e-6)
    assert res.mean_force[0] == pytest.approx(1.5, rel=1e-6)
    assert res.r2[0] == pytest.approx(1.0, abs=1e-12)
    assert res.condition_number < 10


def test_multifrequency_2dof_matrices():
    al = np.array([[10.0, 1.5], [-0.7, 4.0]])
    be = np.array([[0.5, -0.2], [0.1, 2.0]])
    ga = np.array([[700.0, -30.0], [15.0, 120.0]])
    res = regress(_multisine_history(al, be, ga, dof=("Heave", "Pitch")))
    assert res.identifiable
    for got, want in ((res.alpha, al), (res.beta, be), (res.gamma, ga)):
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-6 * np.abs(want).max())
    d = res.to_dict()
    assert np.shape(d["alpha"]) == (2, 2) and np.shape(d["stderr"]["gamma"]) == (2, 2)
    json.dumps(d)


def test_single_frequency_reports_dynamic_stiffness():
    w, alpha, beta, gamma = 2 * np.pi / 0.75, 10.56, 0.3, 692.2
    z, zd, zdd = multisine(T, [0.025], [w], [0.4], offset=0.001)
    f = 2.0 + alpha * zdd + beta * zd + gamma * z
    res = regress(make_history(T, z, zd, zdd, forces={"F_tot": f}))
    assert not res.identifiable
    combos = {c["name"]: c for c in res.identifiable_combinations}
    dyn = combos["dynamic_stiffness"]
    assert dyn["omega"] == pytest.approx(w, rel=1e-6)
    assert float(np.squeeze(dyn["value"])) == pytest.approx(gamma - w**2 * alpha, rel=1e-5)
    assert float(np.squeeze(combos["damping"]["value"])) == pytest.approx(beta, rel=1e-6)
    # the non-identifiable direction is (Δα, Δβ, Δγ) ∝ (1, 0, ω²)
    null = combos["null_direction"]
    direction = np.array([null["alpha"][0], null["beta"][0], null["gamma"][0]])
    np.testing.assert_allclose(direction / direction[2], [1 / w**2, 0, 1], atol=1e-6)
    assert np.isinf(res.stderr["alpha"][0, 0])  # α alone is not determined
    assert any("single-frequency" in msg for msg in res.warnings)
    d = res.to_dict()
    assert d["identifiable"] is False
    json.dumps(d)


def test_free_decay_is_rank_deficient_with_the_oscillator_as_null_direction():
    m, b, k = M, 8.0, C_HS  # damping ratio ≈ 0.057
    wn = np.sqrt(k / m)
    zeta = b / (2 * np.sqrt(k * m))
    wd = wn * np.sqrt(1 - zeta**2)
    # analytic free decay z = e^{-ζωn t} (z0 cos ωd t + (ζωn z0/ωd) sin ωd t)
    z0 = 0.03
    e = np.exp(-zeta * wn * T)
    c1, c2 = z0, zeta * wn * z0 / wd
    z = e * (c1 * np.cos(wd * T) + c2 * np.sin(wd * T))
    zd = e * ((c2 * wd - zeta * wn * c1) * np.cos(wd * T) - (c1 * wd + zeta * wn * c2) * np.sin(wd * T))
    zdd = -(b * zd + k * z) / m
    res = regress(make_history(T, z, zd, zdd, forces={"F_tot": m * zdd}))
    assert not res.identifiable
    null = next(c for c in res.identifiable_combinations if c["name"] == "null_direction")
    direction = np.array([null["alpha"][0], null["beta"][0], null["gamma"][0]])
    np.testing.assert_allclose(direction / direction[2], [m / k, b / k, 1.0], rtol=1e-6)
    assert any("not unique" in msg for msg in res.warnings)
    # with damping the free decay does not pin β down: it must not be reported as determined
    assert "damping" not in {c["name"] for c in res.identifiable_combinations}


def test_two_dof_single_frequency_claims_no_combination():
    """Both DOF at one ω: one motion pattern cannot separate the 2×2 coupling terms."""
    w = 8.4
    cols = [multisine(T, [a], [w], [p]) for a, p in ((0.02, 0.3), (0.01, 1.3))]
    z, zd, zdd = (np.stack([c[k] for c in cols], axis=1) for k in range(3))
    al, ga = np.array([[10.0, 1.0], [0.5, 3.0]]), np.array([[700.0, 10.0], [5.0, 100.0]])
    f = zdd @ al.T + 0.3 * zd + z @ ga.T
    res = regress(make_history(T, z, zd, zdd, forces={"F_tot": f}, dof=["Heave", "Pitch"]))
    names = {c["name"] for c in res.identifiable_combinations}
    assert not res.identifiable and names == {"null_direction"}
    assert np.all(np.isinf(res.stderr["gamma"]))


@pytest.mark.parametrize(
    "known, expect",
    [
        ([], (M, 0.0, 0.0)),
        ([Hydrostatic(C_HS)], (M, 0.0, C_HS)),
        ([Hydrostatic(C_HS), AddedMass(A_INF)], (M + A_INF, 0.0, C_HS)),
    ],
)
def test_table1_cases(known, expect):
    """m z̈ + B ż + C z = F_e with F_tot = F_e − B ż − C z (transient + T = 0.75 s forcing)."""
    b = 1.5
    w = 2 * np.pi / 0.75
    t = np.arange(0.0, 15.0, 0.005)
    z, zd, zdd = forced_oscillator(t, M, b, C_HS, lambda s: 3.0 * np.sin(w * s))
    f_tot = 3.0 * np.sin(w * t) - b * zd - C_HS * z
    res = regress(make_history(t, z, zd, zdd, forces={"F_tot": f_tot}, mass=M), known=known)
    got = [res.alpha[0, 0], res.beta[0, 0], res.gamma[0, 0]]
    for g, e, scale in zip(got, expect, (M, 1.0, C_HS)):
        assert g == pytest.approx(e, abs=1e-6 * scale)
    assert res.identifiable


def test_noisy_z_with_savgol_derivatives_and_hac_intervals():
    """Noisy z, Savitzky–Golay derivatives, AR(1) force noise (~2 % of the force): estimates
    within 3 %, and each 95 % interval covers the truth in at least 4 of 5 noise draws."""
    al, be, ga = 10.56, 15.0, 692.2
    t = np.arange(0.0, 80.0, 0.01)
    z, zd, zdd = multisine(t, [0.02, 0.012, 0.008], OMEGAS, [0.3, 1.1, 2.0])
    f = 1.5 + al * zdd + be * zd + ga * z
    covered = {"alpha": 0, "beta": 0, "gamma": 0}
    for seed in range(5):
        rng = np.random.default_rng(seed)
        e = scipy.signal.lfilter([1.0], [1.0, -0.95], rng.normal(0, 0.1, t.size))
        z_meas = z + rng.normal(0, 2e-5, t.size)
        zd_est = scipy.signal.savgol_filter(z_meas, 31, 5, deriv=1, delta=0.01)
        zdd_est = scipy.signal.savgol_filter(z_meas, 31, 5, deriv=2, delta=0.01)
        res = regress(make_history(t, z_meas, zd_est, zdd_est, forces={"F_tot": f + e}))
        assert res.identifiable
        for name, truth in (("alpha", al), ("beta", be), ("gamma", ga)):
            assert getattr(res, name)[0, 0] == pytest.approx(truth, rel=0.03), name
            lo, hi = res.ci95[name][0, 0]
            covered[name] += int(lo <= truth <= hi)
    assert min(covered.values()) >= 4, covered


def test_hac_interval_coverage_under_autocorrelated_noise():
    """Monte Carlo: 95 % HAC intervals of β cover the truth ≳ 90 % of the time (ρ = 0.9 noise),
    where white-noise (lag 0) intervals would badly under-cover."""
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 40.0, 0.01)
    z, zd, zdd = multisine(t, [0.02, 0.012, 0.008], OMEGAS, [0.3, 1.1, 2.0])
    f = 10.0 * zdd + 2.0 * zd + 600.0 * z
    hits_hac, hits_naive, n_rep = 0, 0, 60
    for _ in range(n_rep):
        e = scipy.signal.lfilter([1.0], [1.0, -0.9], rng.normal(0, 0.5, t.size))
        hist = make_history(t, z, zd, zdd, forces={"F_tot": f + e})
        for lags, counter in ((None, "hac"), (0, "naive")):
            lo, hi = regress(hist, hac_lags=lags).ci95["beta"][0, 0]
            if lo <= 2.0 <= hi:
                if counter == "hac":
                    hits_hac += 1
                else:
                    hits_naive += 1
    assert hits_hac / n_rep >= 0.85
    assert hits_naive / n_rep < 0.75


# ---------------------------------------------------------------- hypothesis properties
_Z, _ZD, _ZDD = multisine(T, [0.02, 0.01, 0.006], OMEGAS, [0.3, 1.1, 2.0], offset=0.002)
_RNG = np.random.default_rng(3)
_F = 4.0 * _ZDD - 1.0 * _ZD + 300 * _Z + 50 * _Z**2 + _RNG.normal(0, 0.05, T.size)
_HIST = make_history(T, _Z, _ZD, _ZDD, forces={"F_tot": _F})
_BASE = regress(_HIST, hac_lags=5)


@settings(max_examples=15, deadline=None)
@given(k=st.floats(-5e3, 5e3), a=st.floats(-50, 50), b=st.floats(-50, 50))
def test_removing_known_components_shifts_coefficients(k, a, b):
    """Removing F = −k z adds +k z to F_bb, so γ → γ + k; likewise α → α + A, β → β + B."""
    res = regress(_HIST, known=[Hydrostatic(k), AddedMass(a), LinearDamping(b)], hac_lags=5)
    assert res.gamma[0, 0] - _BASE.gamma[0, 0] == pytest.approx(k, abs=1e-7 * (1 + abs(k)) + 1e-6)
    assert res.alpha[0, 0] - _BASE.alpha[0, 0] == pytest.approx(a, abs=1e-8 * (1 + abs(a)) + 1e-8)
    assert res.beta[0, 0] - _BASE.beta[0, 0] == pytest.approx(b, abs=1e-8 * (1 + abs(b)) + 1e-7)


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_fix_alpha_at_the_free_estimate_reproduces_beta_gamma(seed):
    """Frisch–Waugh–Lovell: fixing α at its free LS estimate leaves β̂, γ̂ unchanged."""
    rng = np.random.default_rng(seed)
    f = _F + rng.normal(0, 1.0, T.size)
    hist = make_history(T, _Z, _ZD, _ZDD, forces={"F_tot": f})
    free = regress(hist, hac_lags=3)
    fixed = regress(hist, fix_alpha=free.alpha, hac_lags=3)
    np.testing.assert_allclose(fixed.beta, free.beta, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(fixed.gamma, free.gamma, rtol=1e-9)
    assert fixed.stderr["alpha"][0, 0] == 0.0 and fixed.fixed_alpha


def test_fix_alpha_on_single_frequency_recovers_gamma():
    w = 2 * np.pi / 0.75
    z, zd, zdd = multisine(T, [0.025], [w], [0.4])
    f = (M + A_INF) * zdd + 0.2 * zd + C_HS * z
    res = regress(make_history(T, z, zd, zdd, forces={"F_tot": f}), fix_alpha=M + A_INF)
    assert res.gamma[0, 0] == pytest.approx(C_HS, rel=1e-8)
    assert res.beta[0, 0] == pytest.approx(0.2, rel=1e-8)


def test_outputs_and_table():
    res = regress(_HIST, known=["hydrostatic=100"])
    d = res.to_dict()
    for key in ("alpha", "beta", "gamma", "mean_force", "stderr", "condition_number",
                "identifiable", "identifiable_combinations", "warnings", "r2",
                "singular_values", "ci95", "dominant_omega"):
        assert key in d
    assert isinstance(d["alpha"], float) and set(d["stderr"]) == {"alpha", "beta", "gamma"}
    json.dumps(d)
    assert d["dominant_omega"] == pytest.approx(OMEGAS[0], rel=0.02)
    table = res.to_table()
    assert "α [kg]" in table and "condition number" in table and "hydrostatic" in table


def test_bad_input_raises_input_error():
    with pytest.raises(InputError, match="no force 'F_x'"):
        regress(_HIST, force="F_x")
    with pytest.raises(InputError, match="fix_alpha"):
        regress(_HIST, fix_alpha=np.ones(3))
    nozdd = make_history(T, _Z, _ZD, None, forces={"F_tot": _F})
    with pytest.raises(InputError, match="zddot"):
        regress(nozdd)
    with pytest.raises(InputError, match="NAME=VALUE"):
        regress(_HIST, known=["hydrostatic"])


def test_frequency_domain_split_per_harmonic():
    """Re(F̂/Ẑ) = γ − ω²α and Im(F̂/Ẑ)/ω = β at each excited frequency (leakage-limited)."""
    al, be, ga = 10.56, 4.0, 692.2
    z, zd, zdd = multisine(T, [0.02, 0.01, 0.006], OMEGAS, [0.3, 1.1, 2.0], offset=0.002)
    hist = make_history(T, z, zd, zdd, forces={"F_tot": 1.5 + al * zdd + be * zd + ga * z})
    ds = frequency_domain_split(hist, omegas=OMEGAS)
    w = np.asarray(OMEGAS)
    np.testing.assert_allclose(ds["dynamic_stiffness"].values, ga - w**2 * al, atol=0.2)
    np.testing.assert_allclose(ds["damping"].values, be, rtol=0.03)
    np.testing.assert_allclose(ds["motion_amplitude"].values, [0.02, 0.01, 0.006], rtol=1e-3)
    assert ds.attrs["alpha"] == pytest.approx(al, rel=1e-3)
    assert ds.attrs["gamma"] == pytest.approx(ga, rel=1e-3)
    # single frequency (default ω = spectral peak): only the dynamic stiffness is reported
    z1, zd1, zdd1 = multisine(T, [0.02], [8.4], [0.3])
    one = frequency_domain_split(
        make_history(T, z1, zd1, zdd1, forces={"F_tot": al * zdd1 + be * zd1 + ga * z1}))
    assert float(one["dynamic_stiffness"][0]) == pytest.approx(ga - 8.4**2 * al, abs=0.05)
    assert "alpha" not in one.attrs
    with pytest.raises(InputError, match="Nyquist"):
        frequency_domain_split(hist, omegas=[1000.0])
