"""Stability settings (docs/THEORY.md §4) against hand-derived results."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _diag_cases import A_INF, C_HS, M
from hybridwsi.diagnostic import (
    CoupledStep,
    Hydrostatic,
    StabilityReport,
    amplification_matrix,
    assess,
    lagged_step,
    max_stable_dt,
    regress,
)
from hybridwsi.diagnostic.stability import MAP_RTOL, surrogate_stability
from hybridwsi.errors import InputError
from hybridwsi.history import make_history

WN = math.sqrt(C_HS / M)


def prescribed(*known):
    """Setting (a) of ``m, A_k, B_k, C_k``."""
    return assess(CoupledStep(*known)).prescribed


def continuous(*matrices):
    """Setting (b) of ``m, A_k, B_k, C_k, α, β, γ``."""
    return assess(CoupledStep(*matrices)).continuous


def lagged(*matrices, dt, scheme):
    """The report of ``m, A_k, B_k, C_k, α, β, γ`` at ``dt`` with ``scheme``."""
    return assess(CoupledStep(*matrices, dt=dt, scheme=scheme))


# ------------------------------------------------------------------ (a) prescribed force
def test_case1_drifts_case2_neutral_damping_decays():
    case1 = prescribed(M)
    assert case1.verdict == "drift" and not case1.stable
    case2 = prescribed(M, 0.0, 0.0, C_HS)
    assert case2.verdict == "neutral"
    np.testing.assert_allclose(sorted(case2.eigenvalues.imag), [-WN, WN], rtol=1e-12)
    case3 = prescribed(M, A_INF, 0.0, C_HS)
    np.testing.assert_allclose(np.abs(case3.eigenvalues), math.sqrt(C_HS / (M + A_INF)), rtol=1e-12)
    damped = prescribed(M, 0.0, 2.0, C_HS)
    assert damped.verdict == "damped"
    np.testing.assert_allclose(damped.eigenvalues.real, -2.0 / (2 * M), rtol=1e-10)
    assert prescribed(M, 0.0, 0.0, -C_HS).verdict == "unstable"
    # damping without stiffness: offsets persist but do not grow (no Jordan block)
    assert prescribed(M, 0.0, 2.0, 0.0).verdict == "neutral"


def test_two_dof_drift_only_in_the_unrestrained_direction():
    m = np.diag([7.0, 0.1])
    c = np.diag([700.0, 0.0])  # second DOF has no restoring force and no damping
    rep = prescribed(m, 0.0, 0.0, c)
    assert rep.verdict == "drift" and rep.conditions["drift_directions"] == 1
    assert prescribed(m, 0.0, np.diag([0.0, 1.0]), c).verdict == "neutral"
    json.dumps(rep.to_dict())


def test_singular_inertia_is_an_input_error():
    with pytest.raises(InputError, match="singular"):
        prescribed(1.0, -1.0)


# ------------------------------------------------------------------ (b) surrogate in the loop
@settings(max_examples=40, deadline=None)
@given(
    dm=st.floats(-5, 5).filter(lambda x: abs(x) > 1e-3),
    db=st.floats(-5, 5).filter(lambda x: abs(x) > 1e-3),
    dc=st.floats(-500, 500).filter(lambda x: abs(x) > 1e-2),
)
def test_surrogate_routh_hurwitz(dm, db, dc):
    """1 DOF: m_eff s² + b_eff s + c_eff is Hurwitz iff all three coefficients share a sign."""
    m, a_k, b_k, c_k = 2.0, 1.0, 0.5, 100.0
    alpha, beta, gamma = m + a_k - dm, b_k - db, c_k - dc
    rep = continuous(m, a_k, b_k, c_k, alpha, beta, gamma)
    hurwitz = (dm > 0 and db > 0 and dc > 0) or (dm < 0 and db < 0 and dc < 0)
    assert (rep.verdict == "stable") == hurwitz
    assert rep.conditions["mass_positive"] == (dm > 0)
    assert rep.conditions["damping_positive"] == (db > 0)
    assert rep.conditions["stiffness_positive"] == (dc > 0)


def test_surrogate_cancelling_inertia_is_unstable():
    rep = continuous(M, A_INF, 0.0, C_HS, M + A_INF, 0.0, 0.0)
    assert rep.verdict == "unstable" and "algebraic loop" in rep.message


# ------------------------------------------------------------------ (c) lagged coupling
@pytest.mark.parametrize("scheme", ["semi_implicit_euler", "newmark"])
def test_added_mass_ratio_above_one_is_unstable_for_every_dt(scheme):
    mt = M + A_INF
    step = CoupledStep(M, A_INF, 1.0, C_HS, -1.2 * mt, 0.0, 0.0, scheme=scheme)
    assert max_stable_dt(step) == 0.0
    for dt in (1e-6, 1e-4, 1e-3):
        rep = lagged(M, A_INF, 1.0, C_HS, -1.2 * mt, 0.0, 0.0, dt=dt, scheme=scheme)
        assert rep.loosely_coupled.verdict == "unstable" and not rep.stable
        assert rep.added_mass_ratio == pytest.approx(1.2)
        assert rep.loosely_coupled.conditions["added_mass_ratio"] == pytest.approx(1.2)


@pytest.mark.parametrize("scheme", ["semi_implicit_euler", "newmark"])
def test_added_mass_ratio_half_is_stable_for_small_dt(scheme):
    mt = M + A_INF
    rep = lagged(M, A_INF, 1.0, C_HS, -0.5 * mt, 0.0, 0.0, dt=1e-3, scheme=scheme)
    assert rep.loosely_coupled.verdict == "stable" and rep.spectral_radius < 1.0 and rep.stable
    assert rep.max_stable_dt > 1e-3


def test_pure_lag_eigenvalue_is_alpha_over_mass():
    """Without B, C, β, γ the lagged acceleration obeys a_n = (α/M) a_{n−1} exactly."""
    g = amplification_matrix(CoupledStep(2.0, 1.0, 0.0, 0.0, -0.9, 0.0, 0.0, dt=0.01,
                                         scheme="semi_implicit_euler"))
    assert np.sort(np.linalg.eigvals(g).real)[0] == pytest.approx(-0.3, abs=1e-12)


def test_symplectic_euler_limit_is_two_over_omega():
    """Semi-implicit Euler on m z̈ + C z = 0 is stable iff Δt ≤ 2/ω_n (hand derivation)."""
    dt_max = max_stable_dt(CoupledStep(M, 0.0, 0.0, C_HS, scheme="semi_implicit_euler"))
    assert dt_max == pytest.approx(2.0 / WN, rel=1e-5)
    # a surrogate stiffness γ_s changes the effective ω: limit 2/sqrt((C − γ_s)/m)
    dt_g = max_stable_dt(CoupledStep(M, 0.0, 0.0, C_HS, 0.0, 0.0, 0.5 * C_HS,
                                     scheme="semi_implicit_euler"))
    assert dt_g == pytest.approx(2.0 / math.sqrt(0.5 * C_HS / M), rel=1e-5)


def test_newmark_average_acceleration_is_unconditionally_stable():
    assert max_stable_dt(CoupledStep(M, A_INF, 0.0, C_HS, scheme="newmark")) == math.inf


def test_largest_stable_dt_agrees_with_the_verdict_when_small_steps_are_unstable():
    """Newmark, z̈ + z = F lagged, F = β ż + γ z with a learned anti-damping β = 0.01 N s/m and
    γ = 0.5 N/m: the continuous system is unstable (Re λ = β/2 > 0), but the one-step lag of
    γ z acts as a damping γ Δt (F(t) ≈ γ z(t − Δt) ≈ γ z − γ Δt ż), so the lagged step is
    stable above Δt* = β/γ = 0.02 s (to first order) and unstable below. At Δt = 2Δt* the
    verdict is stable, so the largest stable Δt must be at least Δt (it was 0: the search
    started at the unstable small steps)."""
    beta, gamma = 0.01, 0.5
    dt_star = beta / gamma
    step = CoupledStep(1.0, 0.0, 0.0, 1.0, 0.0, beta, gamma, scheme="newmark")
    rho = [float(np.max(np.abs(np.linalg.eigvals(amplification_matrix(step, f * dt_star)))))
           for f in (0.9, 1.1)]
    assert rho[0] > 1.0 > rho[1]  # the closed-form threshold within 10 %
    assert assess(step.with_dt(dt_star)).continuous.verdict == "unstable"
    above = assess(step.with_dt(2 * dt_star))
    assert above.stable and above.loosely_coupled.verdict == "stable"
    assert above.max_stable_dt >= 2 * dt_star
    assert max_stable_dt(step.with_dt(2 * dt_star)) >= 2 * dt_star
    below = assess(step.with_dt(0.5 * dt_star))
    assert not below.stable and below.max_stable_dt < 0.5 * dt_star


def _symplectic_map(damping: float, stiffness: float, dt: float) -> np.ndarray:
    """Semi-implicit Euler on (z, ż) of z̈ + b ż + c z = 0 (unit mass), b explicit."""
    return np.array([[1.0 - dt**2 * stiffness, dt * (1.0 - dt * damping)],
                     [-dt * stiffness, 1.0 - dt * damping]])


@pytest.mark.parametrize("dt", [1.0, 2.0])
def test_step_map_function_sets_the_largest_stable_dt_of_that_map(dt):
    """A rollout's own map holds damping the lag-0 step leaves out (the radiation memory's
    states): the lag-0 step (learned anti-damping β = 0.01, no known damping, Newmark) is
    unstable at every Δt, the caller's map (semi-implicit Euler on z̈ + (b − β) ż + z = 0,
    b = 0.5) is stable up to its closed-form limit Δt_max = (√(b'² + 4c) − b')/c, b' = b − β
    (Jury: the root λ = −1 at c Δt² + 2 b' Δt − 4 = 0). The report's Δt limit is that map's,
    on the side of the verdict at Δt."""
    b, beta, c = 0.5, 0.01, 1.0
    limit = (math.sqrt((b - beta) ** 2 + 4 * c) - (b - beta)) / c
    step = CoupledStep(1.0, 0.0, 0.0, c, 0.0, beta, 0.0, dt=dt, scheme="newmark")
    rep = assess(step, step_map=lambda h: _symplectic_map(b - beta, c, h))
    assert rep.loosely_coupled.verdict == "unstable"
    assert rep.loosely_coupled.max_stable_dt == 0.0  # the lag-0 map's: another system
    assert rep.stable == (dt < limit)
    assert (1 - MAP_RTOL) * limit <= rep.max_stable_dt <= limit  # the stable end, to 1 %
    assert (rep.max_stable_dt >= dt) == rep.stable


def test_lagged_step_tracks_the_analytic_oscillator():
    """Stepping m z̈ + C z = 0 with a lagged surrogate stiffness part γ_s converges to cos(ω t)."""
    gamma_s = -0.3 * C_HS  # surrogate supplies 30 % of the restoring force (lagged)
    c_k = 0.7 * C_HS
    m = np.eye(1) * M
    for scheme in ("semi_implicit_euler", "newmark"):
        dt, n = 1e-4, 20000
        z, v, a = np.array([0.01]), np.array([0.0]), np.array([-C_HS * 0.01 / M])
        for i in range(n):
            z, v, a = lagged_step(scheme, i * dt, dt, z, v, a, m, np.zeros((1, 1)),
                                  np.eye(1) * c_k, lambda t, zz, vv, aa: gamma_s * zz)
        assert z[0] == pytest.approx(0.01 * math.cos(WN * n * dt), abs=2e-4 * 0.01 * 10)


# ------------------------------------------------------------------ assess
def test_assess_on_a_regression_result():
    t = np.arange(0.0, 20.0, 0.01)
    z = 0.02 * np.sin(3.1 * t) + 0.01 * np.sin(7.3 * t)
    zd = 0.02 * 3.1 * np.cos(3.1 * t) + 0.01 * 7.3 * np.cos(7.3 * t)
    zdd = -0.02 * 3.1**2 * np.sin(3.1 * t) - 0.01 * 7.3**2 * np.sin(7.3 * t)
    # a "surrogate" force with α = −2 kg, β = −1 N s/m, γ = −50 N/m
    hist = make_history(t, z, zd, zdd, forces={"F_s": -2.0 * zdd - 1.0 * zd - 50.0 * z})
    res = regress(hist, force="F_s")
    out = assess(CoupledStep.from_components(M, [Hydrostatic(C_HS)], res, dt=0.01))
    assert out.prescribed.verdict == "neutral"
    assert out.continuous.verdict == "stable"  # M+2, +1, C+50 all positive
    assert out.added_mass_ratio == pytest.approx(2.0 / M, rel=1e-6)
    np.testing.assert_allclose(out.step.alpha, res.alpha)  # the surrogate's α travels along
    json.dumps(out.to_dict())


def test_report_json_round_trip_keeps_every_verdict():
    """The certificate of a learned component: ρ and the added-mass ratio at Δt, the largest
    stable Δt, α, β, γ — through JSON and back, unchanged."""
    step = CoupledStep(np.diag([M, 2 * M]), np.diag([A_INF, 0.0]), 0.5, np.diag([C_HS, 0.0]),
                       -0.4 * np.eye(2), [[-1.0, 0.2], [0.1, -0.5]], np.diag([-30.0, 0.0]),
                       dt=0.01, scheme="newmark", mode="corrected", corrections=2)
    rep = assess(step)
    back = StabilityReport.from_dict(json.loads(json.dumps(rep.to_dict())))
    for k in ("mass", "known_mass", "known_damping", "known_stiffness", "alpha", "beta",
              "gamma"):
        np.testing.assert_array_equal(getattr(back.step, k), getattr(step, k))
    assert (back.step.dt, back.step.scheme, back.step.mode, back.step.corrections) == \
        (0.01, "newmark", "corrected", 2)
    for k in ("spectral_radius", "added_mass_ratio", "max_stable_dt", "stable",
              "continuous_stable"):
        assert getattr(back, k) == getattr(rep, k), k
    assert 0 < rep.max_stable_dt < math.inf
    for a, b in zip(back.settings, rep.settings):
        assert (a.setting, a.verdict, a.message) == (b.setting, b.verdict, b.message)
        np.testing.assert_array_equal(a.eigenvalues, b.eigenvalues)
    assert back.to_dict() == rep.to_dict()
    # no learned part, Newmark: stable at every Δt (inf survives JSON as "inf")
    free = assess(CoupledStep(M, A_INF, 0.0, C_HS, dt=0.01))
    assert math.isinf(free.max_stable_dt)
    assert math.isinf(StabilityReport.from_dict(json.loads(json.dumps(free.to_dict())))
                      .max_stable_dt)


def test_positional_continuous_setting_is_the_assessment():
    args = (M, A_INF, 0.5, C_HS, -1.0, 0.2, 30.0)
    assert surrogate_stability(*args).to_dict() == continuous(*args).to_dict()
