"""Identifiability under a stated force accuracy (issue 14 item 5, docs/THEORY.md §3b).

References are analytic: the linear oscillator (m + A) z̈ + b ż + C z = F0 sin ωt with the
paper's m, A∞, C, whose F_bb = F_tot − F_hs − F_A∞ = (m + A) z̈ + C z exactly, so α = m + A,
β = 0, γ = C and the dynamic stiffness at ω is C − ω² (m + A); and the least-squares
sensitivity, checked by actually perturbing the force and refitting.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from _diag_cases import A_INF, C_HS, M, multisine
from hybridwsi.diagnostic import AddedMass, Hydrostatic, regress
from hybridwsi.diagnostic.regression import force_error_for_shift
from hybridwsi.errors import InputError
from hybridwsi.history import make_history

T = np.arange(0.0, 30.0, 0.01)
W = 2 * np.pi / 0.75  # regular-wave frequency of the paper [rad/s]
B = 0.5  # small damping [N s/m] (ζ ≈ 0.003)
KNOWN = [Hydrostatic(C_HS), AddedMass(A_INF)]
MULTI = (3.1, 5.7, 12.4)  # well separated from each other [rad/s]


def oscillator(t: np.ndarray, transient: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Steady state at W plus a free transient at the natural frequency, analytic.

    ``transient`` is the transient's amplitude at t = 0 relative to the steady amplitude.
    """
    mt = M + A_INF
    x = 1.0 / (C_HS - mt * W**2 + 1j * B * W)  # response to F0 = 1 N
    wn = np.sqrt(C_HS / mt)
    zeta = B / (2 * np.sqrt(C_HS * mt))
    wd = wn * np.sqrt(1 - zeta**2)
    d = transient * abs(x)
    e = np.exp(-zeta * wn * t)
    z = (x * np.exp(1j * W * t)).imag + d * e * np.sin(wd * t)
    zd = (1j * W * x * np.exp(1j * W * t)).imag + d * e * (wd * np.cos(wd * t)
                                                          - zeta * wn * np.sin(wd * t))
    zdd = (np.sin(W * t) - B * zd - C_HS * z) / mt  # the equation of motion
    return z, zd, zdd


def oscillator_history(transient: float = 0.003, f_extra: np.ndarray | None = None):
    z, zd, zdd = oscillator(T, transient)
    f_tot = M * zdd + (0.0 if f_extra is None else f_extra)
    return make_history(T, z, zd, zdd, forces={"F_tot": f_tot}, mass=M)


def normalised_svd(*cols: np.ndarray):
    """U, S, Vᵀ and column norms of the centred, column-normalised regressors (independent)."""
    x = np.column_stack(cols)
    xc = x - x.mean(axis=0)
    scale = np.linalg.norm(xc, axis=0)
    u, s, vt = np.linalg.svd(xc / scale, full_matrices=False)
    return u, s, vt, scale


def centred_norm(f: np.ndarray) -> float:
    return float(np.linalg.norm(f - f.mean()))


def test_leftover_transient_is_not_identifiable_at_one_percent():
    hist = oscillator_history(0.003)
    res = regress(hist, known=KNOWN)
    # noise-free: the split itself is exact and its standard errors tiny ...
    assert res.alpha[0, 0] == pytest.approx(M + A_INF, rel=1e-6)
    assert res.gamma[0, 0] == pytest.approx(C_HS, rel=1e-6)
    assert res.normalised_stderr["alpha"] < 1e-6
    # ... yet a force error far below 1 % moves α by 10 %
    assert res.force_error_10pct[0] < 1e-3
    assert not res.identifiable and not res.identifiable_dof[0]
    combos = {c["name"]: c for c in res.identifiable_combinations}
    dyn = combos["dynamic_stiffness"]
    assert dyn["omega"] == pytest.approx(W, rel=1e-4)
    assert float(np.squeeze(dyn["value"])) == pytest.approx(C_HS - W**2 * (M + A_INF), rel=2e-3)
    assert float(np.squeeze(combos["damping"]["value"])) == pytest.approx(0.0, abs=1e-6)
    assert any("force accuracy 1 %" in w for w in res.warnings)
    d = res.to_dict()
    assert d["identifiable"] is False and d["force_accuracy"] == 0.01
    assert d["force_error_10pct"] == pytest.approx(res.force_error_10pct[0])
    json.dumps(d)


def test_leftover_transient_is_identifiable_with_a_stated_accuracy_of_1e_5():
    res = regress(oscillator_history(0.003), known=KNOWN, force_accuracy=1e-5)
    assert res.identifiable and res.identifiable_dof.tolist() == [True]
    assert res.force_error_10pct[0] > 1e-5
    assert res.identifiable_combinations == []
    assert res.to_dict()["force_accuracy"] == 1e-5


def test_force_error_scales_with_the_transient():
    """The weak singular value, hence the tolerable force error, is proportional to the
    amplitude of the only second frequency (first order in the transient)."""
    e1 = regress(oscillator_history(0.003), known=KNOWN).force_error_10pct[0]
    e2 = regress(oscillator_history(0.03), known=KNOWN).force_error_10pct[0]
    assert e2 / e1 == pytest.approx(10.0, rel=0.02)


@pytest.mark.parametrize("term, col", [("alpha", 0), ("gamma", 2)])
def test_worst_force_error_moves_the_coefficient_by_ten_percent(term, col):
    """Perturb F by ε‖P F‖ along U S⁻¹ Vᵀ e_k (the worst direction): the refit moves the
    coefficient by exactly 10 %; along the weakest direction U[:, min] alone by nearly 10 %;
    a random error of the same size much less."""
    hist = oscillator_history(0.003)
    base = regress(hist, known=KNOWN)
    eps = base.force_error_terms[term][0, 0]
    z, zd, zdd = (hist[k].values[:, 0] for k in ("z", "zdot", "zddot"))
    u, s, vt, scale = normalised_svd(zdd, zd, z)
    size = eps * centred_norm(hist["F_tot"].values[:, 0])
    value = getattr(base, term)[0, 0]

    def moved(delta: np.ndarray) -> float:
        res = regress(oscillator_history(0.003, f_extra=delta), known=KNOWN)
        return (getattr(res, term)[0, 0] - value) / value

    worst = u @ (vt[:, col] / s)
    assert abs(value) * scale[col] > centred_norm(hist["F_tot"].values[:, 0])  # own-value regime
    assert abs(moved(size * worst / np.linalg.norm(worst))) == pytest.approx(0.1, rel=1e-6)
    weak = abs(moved(size * u[:, -1]))
    assert 0.099 < weak <= 0.1 + 1e-9
    rng = np.random.default_rng(0)
    noise = rng.normal(size=T.size)
    assert abs(moved(size * noise / np.linalg.norm(noise))) < 0.01


def test_formula_matches_the_weakest_direction_approximation():
    """ε ≈ 0.1 |θ_n| S_min / (‖P F‖ |V_k,min|) when S_min ≪ the other singular values."""
    hist = oscillator_history(0.003)
    res = regress(hist, known=KNOWN)
    z, zd, zdd = (hist[k].values[:, 0] for k in ("z", "zdot", "zddot"))
    _, s, vt, scale = normalised_svd(zdd, zd, z)
    fn = centred_norm(hist["F_tot"].values[:, 0])
    theta_n = res.alpha[0, 0] * scale[0]
    approx = 0.1 * theta_n * s[-1] / (fn * abs(vt[-1, 0]))
    assert res.force_error_terms["alpha"][0, 0] == pytest.approx(approx, rel=1e-3)


def test_multisine_stays_identifiable_at_one_percent():
    al, be, ga = M + A_INF, 0.4, C_HS
    z, zd, zdd = multisine(T, [0.02, 0.01, 0.006], MULTI, [0.3, 1.1, 2.0])
    hist = make_history(T, z, zd, zdd, forces={"F_tot": al * zdd + be * zd + ga * z})
    res = regress(hist)
    assert res.identifiable and res.force_error_10pct[0] > 0.01
    np.testing.assert_allclose([res.alpha[0, 0], res.gamma[0, 0]], [al, ga], rtol=1e-8)


def test_free_decay_needs_infinite_accuracy():
    """Rank-deficient data: no force accuracy makes the split unique (ε = 0)."""
    z, zd, zdd = oscillator(T, 1.0)
    zdd_free = -(B * zd + C_HS * z) / (M + A_INF)  # drop the forcing: z̈, ż, z dependent
    # an exactly dependent set: z̈ from the homogeneous equation of the same z, ż
    hist = make_history(T, z, zd, zdd_free, forces={"F_tot": M * zdd_free})
    res = regress(hist, force_accuracy=0.0)
    assert res.force_error_10pct[0] == 0.0 and not res.identifiable


def _two_dof(heave_transient: float):
    """Heave: near-monochromatic oscillator motion; Pitch: multi-sine. Uncoupled forces."""
    zh, zdh, zddh = oscillator(T, heave_transient)
    zp, zdp, zddp = multisine(T, [0.05, 0.03, 0.02], MULTI, [0.2, 0.9, 1.7])
    z, zd, zdd = (np.column_stack(p) for p in ((zh, zp), (zdh, zdp), (zddh, zddp)))
    al = np.diag([M + A_INF, 0.12])  # kg, kg m^2
    be = np.diag([0.0, 0.8])  # N s/m, N m s/rad
    ga = np.diag([C_HS, 40.0])  # N/m, N m/rad
    f = zdd @ al.T + zd @ be.T + z @ ga.T
    return z, zd, zdd, f, (al, be, ga)


def test_two_dof_force_error_per_dof_and_pair():
    z, zd, zdd, f, (al, be, ga) = _two_dof(0.003)
    hist = make_history(T, z, zd, zdd, forces={"F_tot": f}, dof=["Heave", "Pitch"])
    res = regress(hist, force_accuracy=[1e-7, 0.01])
    for got, want in ((res.alpha, al), (res.beta, be), (res.gamma, ga)):
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-7)
    ea, eg = res.force_error_terms["alpha"], res.force_error_terms["gamma"]
    # the heave column (motion at one frequency) is weak for both rows, the pitch column is not
    assert np.all(ea[:, 0] < 1e-3) and np.all(eg[:, 0] < 1e-3)
    assert np.all(ea[:, 1] > 0.01) and np.all(eg[:, 1] > 0.01)
    # per influenced DOF: Heave at 1e-7 passes, Pitch (whose heave coupling is not
    # separable) fails at 1 %
    assert res.identifiable_dof.tolist() == [True, False] and not res.identifiable
    np.testing.assert_allclose(res.force_error_10pct, np.minimum(ea, eg).min(axis=1))
    d = res.to_dict()
    assert d["identifiable_dof"] == [True, False] and d["force_accuracy"] == [1e-7, 0.01]
    assert np.shape(d["force_error_10pct_terms"]["alpha"]) == (2, 2)
    json.dumps(d)


def test_two_dof_perturbation_moves_only_its_own_row():
    """A worst-case error on the pitch moment moves α_PP by 10 % of its reference — here the
    moment itself, α_PP z̈_P being a small part of it — and leaves the heave row alone."""
    z, zd, zdd, f, _ = _two_dof(0.003)
    hist = make_history(T, z, zd, zdd, forces={"F_tot": f}, dof=["Heave", "Pitch"])
    base = regress(hist)
    u, s, vt, scale = normalised_svd(zdd[:, 0], zdd[:, 1], zd[:, 0], zd[:, 1], z[:, 0], z[:, 1])
    k = 1  # column of z̈_Pitch → α[Pitch, Pitch]
    worst = u @ (vt[:, k] / s)
    eps = base.force_error_terms["alpha"][1, 1]
    delta = eps * centred_norm(f[:, 1]) * worst / np.linalg.norm(worst)
    pert = f.copy()
    pert[:, 1] += delta
    res = regress(make_history(T, z, zd, zdd, forces={"F_tot": pert}, dof=["Heave", "Pitch"]))
    contribution = abs(base.alpha[1, 1]) * scale[k]
    assert contribution < centred_norm(f[:, 1])  # the floor applies
    moved = abs(res.alpha[1, 1] - base.alpha[1, 1]) * scale[k]
    assert moved == pytest.approx(0.1 * centred_norm(f[:, 1]), rel=1e-6)
    np.testing.assert_allclose(res.alpha[0], base.alpha[0], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(res.gamma[0], base.gamma[0], rtol=1e-9, atol=1e-9)


def test_units_per_dof_pair_in_table_and_dict():
    z, zd, zdd, f, _ = _two_dof(0.3)
    res = regress(make_history(T, z, zd, zdd, forces={"F_tot": f}, dof=["Heave", "Pitch"]))
    units = res.to_dict()["units"]
    assert units["alpha"] == [["kg", "kg m"], ["kg m", "kg m^2"]]
    assert units["beta"][1][1] == "N m s/rad" and units["gamma"][1][1] == "N m/rad"
    assert units["gamma"][0][1] == "N/rad" and units["beta"][1][0] == "N m s/m"
    table = res.to_table()
    for label in ("α [kg m^2]", "β [N m s/rad]", "γ [N m/rad]", "γ [N/m]", "Pitch,Heave"):
        assert label in table
    assert "assumed force accuracy 1 %" in table


def test_force_error_for_shift_handles_zero_force_and_free_slopes():
    sv, vt = np.array([1.0, 0.5]), np.eye(2)
    eps = force_error_for_shift(sv, vt, np.array([[2.0, 0.0], [0.1, 0.0]]), np.array([1.0, 0.0]),
                                free=np.array([False, True]))
    # slope 0: 0.1 · max(2, 1) / (1 · 1/1); slope 1 free → 0; zero force → NaN
    assert eps[0, 0] == pytest.approx(0.2) and eps[1, 0] == 0.0
    assert np.all(np.isnan(eps[:, 1]))


@pytest.mark.parametrize("bad", [-0.01, np.nan, [0.01, 0.02], "x"])
def test_bad_force_accuracy_raises(bad):
    with pytest.raises(InputError, match="force_accuracy"):
        regress(oscillator_history(0.003), known=KNOWN, force_accuracy=bad)
