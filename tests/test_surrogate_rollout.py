"""Hybrid rollout: analytic references, stability prediction vs observation per partition."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

import synthetic_hydro as sh
from _diag_cases import HeldSpring

from hybridwsi.diagnostic import stability
from hybridwsi.errors import InputError
from hybridwsi.forces import Hydrostatic
from hybridwsi.history import make_history
from hybridwsi.surrogate.demo import (
    drift,
    evaluate_partition,
    make_histories,
    partitions,
)
from hybridwsi.surrogate.network import ForceNetwork
from hybridwsi.surrogate.rollout import (
    UnstablePartitionError,
    check_stability,
    rollout,
)

torch.set_num_threads(1)
M, C = 7.06, 692.2


def _linear_net(alpha: float, beta: float, gamma: float, hist) -> ForceNetwork:
    """A network that is exactly F = alpha zdd + beta zd + gamma z (single linear layer)."""
    net = ForceNetwork(hidden=(), max_epochs=1, inputs=("z", "zdot", "zddot"))
    net.fit(hist, lambda h: np.zeros((h.sizes["time"], 1)) + 1.0 * h["z"].values)
    with torch.no_grad():
        w = torch.tensor([gamma, beta, alpha], dtype=torch.float64)
        net._ys[:] = 1.0
        net._ym[:] = 0.0
        net.model_[0].weight[:] = (w * net._xs)[None, :]
        net.model_[0].bias[:] = (w * net._xm).sum()
    return net


def _decay_case(z0: float, dt: float, duration: float):
    t = np.arange(0.0, duration + dt / 2, dt)
    z = np.zeros_like(t)
    z[0] = z0
    h = make_history(t, z, np.zeros_like(t), np.zeros_like(t), mass=M)
    h["zddot"][0, 0] = -C * z0 / M  # consistent initial acceleration
    return h


def test_rollout_with_exact_damping_network_matches_analytic_decay():
    """Network = -B zdot (exact), hydrostatics known: free decay of m z'' + B z' + C z = 0."""
    b, z0, dt = 4.0, 0.01, 0.002
    case = _decay_case(z0, dt, 3.0)
    net = _linear_net(0.0, -b, 0.0, case)
    res = rollout(net, [case], mass=M, known=[Hydrostatic(C)], mode="lagged")
    t = res.histories[0]["time"].values
    wn, zeta = np.sqrt(C / M), b / (2 * np.sqrt(C * M))
    wd = wn * np.sqrt(1 - zeta**2)
    exact = z0 * np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))
    np.testing.assert_allclose(res.histories[0]["z"].values[:, 0], exact, atol=0.01 * z0)
    assert res.prediction.stable and not res.blew_up[0]
    implicit = rollout(net, [case], mass=M, known=[Hydrostatic(C)], mode="implicit")
    np.testing.assert_allclose(implicit.histories[0]["z"].values[:, 0], exact, atol=0.005 * z0)


def test_predicted_map_is_the_map_the_rollout_runs_with_lagged_taps():
    """A linear network with lagged taps (window 3, stride 2: z and ż now, 0.02 s and 0.04 s
    ago): iterating the certificate's one-step map from the rollout's start reproduces the
    rollout step by step (a linear network makes the rollout exactly linear). The map used
    to carry the buffer's lags 0 … w−2 instead of 1 … w−1, so the network in the map read
    every tap one sample late (on the OC4 semi that turned a decaying slow mode, −1.8e-3 1/s,
    into a growing one, +6e-4 1/s)."""
    from hybridwsi.surrogate.physics import BatchedPhysics
    from hybridwsi.surrogate.rollout import _linear_map, _start

    dt = 0.01
    t = np.arange(0.0, 1.0 + dt / 2, dt)
    wn = np.sqrt(C / M)
    case = make_history(t, 0.01 * np.cos(wn * t), -0.01 * wn * np.sin(wn * t),
                        -0.01 * wn**2 * np.cos(wn * t), mass=M)
    net = ForceNetwork(hidden=(), max_epochs=1, inputs=("z", "zdot"), window=3, stride=2)
    net.fit(case, lambda h: 1.0 * h["z"].values)
    w = np.array([-30.0, -1.0, 10.0, 0.5, 15.0, -0.5])  # (z, ż) at lags 0, 2, 4 samples
    with torch.no_grad():
        wt = torch.tensor(w, dtype=torch.float64)
        net._ys[:] = 1.0
        net._ym[:] = 0.0
        net.model_[0].weight[:] = (wt * net._xs)[None, :]
        net.model_[0].bias[:] = (wt * net._xm).sum()
    phys = BatchedPhysics(M, [Hydrostatic(C)], 1)
    g = _linear_map(phys.linearised(), net.spec_, dt, "lagged", w[None, :])
    start, _ = _start(phys, net.spec_, [case])
    state = np.concatenate([start.z[0], start.v[0], start.a[0], start.buf[0, 1:].ravel()])
    res = rollout(net, [case], mass=M, known=[Hydrostatic(C)], mode="lagged", check=False,
                  compiled=False, n_steps=60)
    z = res.histories[0]["z"].values[:, 0]  # from the end of the first window on
    assert np.all(np.isfinite(z)) and np.max(np.abs(z)) > 1e-3
    for k in range(1, 61):
        state = g @ state
        assert state[0] == pytest.approx(z[k], rel=1e-9, abs=1e-12), k


@pytest.mark.parametrize("alpha, beta, gamma", [(0.0, -3.0, 0.0), (-3.5, 0.5, 20.0), (6.0, -1.0, 0.0)])
def test_predicted_map_matches_stability_module(alpha, beta, gamma):
    """Window-1 linear network: our one-step map is the stability module's amplification map."""
    dt = 0.01
    case = _decay_case(0.01, dt, 0.2)
    net = _linear_net(alpha, beta, gamma, case)
    pred = check_stability(net, case, mass=M, known=[Hydrostatic(C)], dt=dt, mode="lagged")
    ref = stability.assess(stability.CoupledStep(M, 0.0, 0.0, C, alpha, beta, gamma, dt=dt))
    assert pred.spectral_radius == pytest.approx(ref.loosely_coupled.spectral_radius, rel=1e-9)
    assert pred.loosely_coupled.spectral_radius == ref.loosely_coupled.spectral_radius
    assert pred.added_mass_ratio == pytest.approx(abs(alpha) / M, rel=1e-9)


def test_added_mass_ratio_above_one_is_refused_and_blows_up():
    """alpha_s = -1.5 m in lagged mode: refused by default; forced, it diverges."""
    dt = 0.01
    case = _decay_case(0.01, dt, 2.0)
    net = _linear_net(-1.5 * M, 0.0, 0.0, case)
    with pytest.raises(UnstablePartitionError, match="alpha_s"):
        rollout(net, [case], mass=M, known=[Hydrostatic(C)], mode="lagged")
    with pytest.warns(RuntimeWarning, match="UNSTABLE"):
        res = rollout(net, [case], mass=M, known=[Hydrostatic(C)], mode="lagged", force=True)
    assert res.blew_up[0]


@pytest.fixture(scope="module")
def light_body_data():
    """Synthetic hydrodynamics (A∞ = 3.5 kg) on a light body m = 2.1 kg < A∞."""
    co = sh.coefficients()
    m = 0.3 * sh.M
    train = make_histories(co, m, range(2), hs=0.05, tp=0.8, duration=30.0, dt=0.02)
    test = make_histories(co, m, [1000], hs=0.05, tp=0.8, duration=30.0, dt=0.02)
    return co, m, train, test


NET_KW = {"hidden": (32,), "window": 11, "stride": 5, "max_epochs": 200, "lr": 3e-3,
          "patience": 25, "batch_size": 128, "seed": 0}


def test_partitions_predicted_vs_observed_light_body(light_body_data):
    co, m, train, test = light_body_data
    long_case = make_histories(co, m, [2000], hs=0.05, tp=0.8, duration=1000 * 0.8, dt=0.02)[0]
    rows = {name: evaluate_partition(name, part, train, test, m, net_kw=NET_KW,
                                     long_case=long_case if name == "recommended" else None)
            for name, part in partitions(co).items()}
    a_inf = rows["added_mass_to_network"]
    # the network learnt (most of) the added mass: alpha_s ≈ -A∞ = -3.5 kg, and |alpha_s| > m
    assert -4.5 < a_inf["alpha_s"] < -2.2
    assert a_inf["added_mass_ratio"] >= 1.0
    assert not a_inf["predicted_stable"] and not a_inf["observed_stable"]
    rec = rows["recommended"]
    assert rec["alpha_s"] == 0.0 and rec["predicted_stable"] and rec["observed_stable"]
    assert rec["r2_held_out"] > 0.99
    # held-out seas vs the exact Cummins reference: corrected coupling at dt = 0.02 s is
    # bounded by Newmark's ~2-3 % (the lagged one was ~15 %)
    assert max(rec["held_out_rms_error_z"]) < 0.05
    # 1000 peak periods of the recommended partition: no blow-up, no drift
    assert not rec["long_run"]["blew_up"] and rec["long_run"]["drift"] < 0.01
    assert rec["long_run"]["rms_error_z"] < 0.05
    assert all(r["agree"] for r in rows.values())


def test_sphere_added_mass_partition_is_stable_as_predicted():
    """The paper's sphere has A∞/m ≈ 0.5: leaving A∞ to the network is lagged-stable."""
    co = sh.coefficients()
    train = make_histories(co, sh.M, range(2), hs=0.05, tp=0.8, duration=30.0, dt=0.02)
    test = make_histories(co, sh.M, [1000], hs=0.05, tp=0.8, duration=30.0, dt=0.02)
    part = partitions(co)["added_mass_to_network"]
    row = evaluate_partition("added_mass_to_network", part, train, test, sh.M, net_kw=NET_KW)
    assert row["added_mass_ratio"] < 1.0
    assert row["predicted_stable"] and row["observed_stable"]


def test_sphere_demo_rollouts_within_three_percent():
    """Issue 14: the demo's stable partitions of the sphere-like body roll out held-out seas
    within 3 % of rms z (corrected coupling, dt = 0.01 s), as predicted stable."""
    from hybridwsi.surrogate.demo import hybrid_demo

    rep = hybrid_demo(sh.coefficients(), masses={"body": sh.M}, duration=20.0, n_train=2,
                      n_test=1, long_periods=0)
    for row in rep["bodies"]["body"]["partitions"]:
        assert row["predicted_stable"] and row["observed_stable"]
        assert max(row["held_out_rms_error_z"]) <= 0.03, row["partition"]


def test_drift_metric():
    t = np.arange(0, 100, 0.01)
    ref = make_history(t, np.sin(2 * np.pi * t), mass=M)
    bad = make_history(t, np.sin(2 * np.pi * t) + 0.05 * t / 100, mass=M)
    assert drift(ref, ref) < 1e-3
    assert drift(bad, ref) == pytest.approx(0.0475 / np.sqrt(0.5), rel=0.05)


def test_batched_rollout_equals_single_case_rollouts():
    """Cases in one torch batch evolve independently (same as one at a time)."""
    dt = 0.005
    c1, c2 = _decay_case(0.01, dt, 0.5), _decay_case(-0.02, dt, 0.5)
    net = _linear_net(-1.0, -3.0, 10.0, c1)
    both = rollout(net, [c1, c2], mass=M, known=[Hydrostatic(C)], mode="implicit")
    for i, c in enumerate((c1, c2)):
        one = rollout(net, [c], mass=M, known=[Hydrostatic(C)], mode="implicit")
        np.testing.assert_allclose(both.histories[i]["z"].values, one.histories[0]["z"].values,
                                   rtol=1e-7, atol=1e-12)


def _exact_decay(b: float, z0: float, t: np.ndarray) -> np.ndarray:
    """z(t) of m z'' + b z' + C z = 0 from rest at z0 (underdamped)."""
    wn, zeta = np.sqrt(C / M), b / (2 * np.sqrt(C * M))
    wd = wn * np.sqrt(1 - zeta**2)
    return z0 * np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))


def _decay_error(mode: str, dt: float, b: float = 4.0, z0: float = 0.01) -> float:
    case = _decay_case(z0, dt, 3.0)
    net = _linear_net(0.0, -b, 0.0, case)
    res = rollout(net, [case], mass=M, known=[Hydrostatic(C)], mode=mode, check=False)
    h = res.histories[0]
    return float(np.max(np.abs(h["z"].values[:, 0] - _exact_decay(b, z0, h["time"].values))) / z0)


def test_corrected_coupling_is_second_order_and_lagged_first_order():
    """Damping network in the loop: the one-step lag of the lagged coupling is a first-order
    error; re-evaluating the network on the predicted end-of-step state restores Newmark's
    second order (against the analytic decay)."""
    lag = [_decay_error("lagged", dt) for dt in (0.004, 0.002)]
    cor = [_decay_error("corrected", dt) for dt in (0.004, 0.002)]
    assert 1.7 < lag[0] / lag[1] < 2.3
    assert 3.4 < cor[0] / cor[1] < 4.6
    assert cor[1] < 0.1 * lag[1]


@pytest.mark.parametrize("alpha", [-0.3 * M, -1.5 * M])
def test_corrected_coupling_keeps_the_added_mass_threshold(alpha):
    """Each correction multiplies the lagged inertia error by alpha_s/(m + A_k): the threshold
    stays at |alpha_s| = m + A_k (spectral radius ~ ratio^(k+1) above it) and, below it, an
    odd number of corrections turns the lag's numerical damping negative (an undamped body is
    then weakly unstable), an even number keeps it positive."""
    dt = 0.01
    case = _decay_case(0.01, dt, 2.0)
    net = _linear_net(alpha, 0.0, 0.0, case)
    ratio = abs(alpha) / M
    for k in (1, 2, 3, 4):
        pred = check_stability(net, case, mass=M, known=[Hydrostatic(C)], dt=dt,
                               mode="corrected", corrections=k)
        if ratio > 1:
            assert pred.spectral_radius == pytest.approx(ratio ** (k + 1), rel=0.02)
        elif k % 2:
            assert 1.0 + 1e-5 < pred.spectral_radius < 1.001
        else:
            assert pred.stable
        res = rollout(net, [case], mass=M, known=[Hydrostatic(C)], mode="corrected",
                      corrections=k, force=True, check=False)
        assert res.blew_up[0] == (ratio > 1)


def test_many_corrections_converge_to_the_implicit_coupling():
    """Corrections are fixed-point iterations of the implicit coupling (contraction 0.3)."""
    dt = 0.005
    case = _decay_case(0.01, dt, 1.0)
    net = _linear_net(-0.3 * M, -2.0, 30.0, case)
    imp = rollout(net, [case], mass=M, known=[Hydrostatic(C)], mode="implicit", tol=1e-14,
                  max_iter=200)
    cor = rollout(net, [case], mass=M, known=[Hydrostatic(C)], mode="corrected",
                  corrections=40)
    np.testing.assert_allclose(cor.histories[0]["z"].values, imp.histories[0]["z"].values,
                               rtol=0, atol=1e-12)


def test_corrections_for_follows_the_added_mass_ratio():
    from hybridwsi.surrogate.rollout import corrections_for

    assert corrections_for(0.0) == 1
    assert corrections_for(0.5) == 8  # 0.5^7 = 0.008 <= 1 %, rounded up to even
    assert corrections_for(0.31) == 4  # 0.31^4 = 0.009
    assert corrections_for(0.05) == 2
    assert corrections_for(1.2) == 2
    assert corrections_for(0.999) == 8  # capped


@pytest.mark.skipif(not pytest.importorskip("hybridwsi.surrogate.fast").HAVE_NUMBA,
                    reason="Numba not installed")
@pytest.mark.parametrize("mode, scheme", [("lagged", "newmark"), ("corrected", "newmark"),
                                          ("lagged", "semi_implicit_euler")])
def test_compiled_loop_equals_numpy_stepper(mode, scheme):
    """Radiation memory states, quadratic damping, a wave-elevation input and two cases: the
    compiled loop runs the NumPy stepper's arithmetic (to rounding)."""
    from hybridwsi.forces import QuadraticDamping
    from hybridwsi.forces.radiation import RadiationMemory

    co = sh.coefficients()
    hs = make_histories(co, sh.M, [5, 6], hs=0.05, tp=0.8, duration=6.0, dt=0.02)
    part = partitions(co)["recommended"]
    known = [*part["known"], QuadraticDamping(3.0), RadiationMemory.from_history(hs[0])]
    net = ForceNetwork(inputs=("z", "zdot", "eta"), hidden=(8,), window=4, stride=2, lead=2,
                       max_epochs=3).fit(hs, lambda h: 0.1 * h["F_exc"].values)
    kw = {"mass": sh.M, "known": known, "mode": mode, "scheme": scheme, "check": False}
    a = rollout(net, hs, compiled=True, **kw)
    b = rollout(net, hs, compiled=False, **kw)
    for ha, hb in zip(a.histories, b.histories):
        for var in ("z", "zdot", "zddot", "F_net"):
            ref = hb[var].values
            np.testing.assert_allclose(ha[var].values, ref, rtol=0,
                                       atol=1e-12 * np.nanmax(np.abs(ref)))
    np.testing.assert_array_equal(a.iterations, b.iterations)


def test_stepped_component_in_the_rollout_is_the_lagged_coupling_of_its_force():
    """A spring held over each step (begin_step at the start of the step) in the known part
    with a zero network gives the rollout of a network −C z seen lagged: the same explicit
    force −C z_n in the same step; begin_step runs once per step, for one case only."""
    dt = 0.005
    case = _decay_case(0.01, dt, 1.0)
    spring = HeldSpring(C)
    held = rollout(_linear_net(0.0, 0.0, 0.0, case), [case], mass=M, known=[spring],
                   mode="lagged", check=False)
    lagged = rollout(_linear_net(0.0, 0.0, -C, case), [case], mass=M, known=[],
                     mode="lagged", check=False, compiled=False)
    h, ref = held.histories[0], lagged.histories[0]
    np.testing.assert_allclose(h["z"].values, ref["z"].values, rtol=0, atol=1e-12)
    t = h["time"].values
    np.testing.assert_array_equal([c[0] for c in spring.calls], t)  # once per step and the end
    np.testing.assert_allclose(h["F_known"].values, -C * h["z"].values, rtol=1e-12)
    with pytest.raises(InputError, match="one case at a time"):
        rollout(_linear_net(0.0, 0.0, 0.0, case), [case, case], mass=M, known=[spring],
                mode="lagged", check=False)
