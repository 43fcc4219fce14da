"""The compiled rollout loops of hybridwsi.surrogate.fast: the vectorisable tanh, and the
batch kernel (cases inner) against the per-case kernel and the NumPy/torch stepper."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import synthetic_hydro as sh  # noqa: E402

fast = pytest.importorskip("hybridwsi.surrogate.fast")
pytestmark = pytest.mark.skipif(not fast.HAVE_NUMBA, reason="Numba not installed")


def _tanh_array(x: np.ndarray) -> np.ndarray:
    import numba

    @numba.njit(error_model="numpy")
    def apply(x):
        out = np.empty_like(x)
        for i in range(x.size):
            out[i] = fast._tanh(x[i])
        return out
    return apply(x)


def test_tanh_matches_numpy_to_rounding():
    """Relative error < 1e-15 from 1e-300 to saturation (no 1 - ... cancellation near 0),
    odd, ±1 at ±inf, NaN propagated (the divergence watch relies on it)."""
    x = np.concatenate([np.linspace(-40.0, 40.0, 400001), np.geomspace(1e-300, 2.0, 4001)])
    x = np.concatenate([x, -x])
    x = x[x != 0.0]  # 0 -> 0 below
    ref = np.tanh(x)
    got = _tanh_array(x)
    assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-15
    np.testing.assert_array_equal(_tanh_array(np.array([np.inf, -np.inf, 0.0])), [1.0, -1.0, 0.0])
    assert np.isnan(_tanh_array(np.array([np.nan]))[0])


def _both_kernels(monkeypatch, call):
    """``call()`` with the per-case kernel and with the batch kernel; checks the batch
    kernel ran."""
    ran = []
    orig = fast._kernel_batch

    def spy(*args):
        ran.append(True)
        return orig(*args)
    monkeypatch.setattr(fast, "_kernel_batch", spy)
    monkeypatch.setattr(fast, "BATCH_MIN", 10**9)
    per_case = call()
    assert not ran
    monkeypatch.setattr(fast, "BATCH_MIN", 1)
    batch = call()
    assert ran
    return per_case, batch


@pytest.mark.parametrize("mode, scheme", [("lagged", "newmark"), ("corrected", "newmark"),
                                          ("lagged", "semi_implicit_euler")])
@pytest.mark.parametrize("n_cases", [2, 9])
def test_batch_kernel_equals_per_case_kernel_and_stepper(monkeypatch, mode, scheme, n_cases):
    """Radiation memory states, quadratic damping, a wave-elevation input, two hidden layers:
    the batch kernel runs the per-case kernel's arithmetic and the NumPy stepper's (whose
    network is NumPy for <= 8 cases and torch beyond: the torch reference) to rounding."""
    from hybridwsi.forces import QuadraticDamping
    from hybridwsi.forces.radiation import RadiationMemory
    from hybridwsi.surrogate.demo import make_histories, partitions
    from hybridwsi.surrogate.network import ForceNetwork
    from hybridwsi.surrogate.rollout import rollout

    co = sh.coefficients()
    hs = make_histories(co, sh.M, range(5, 5 + n_cases), hs=0.05, tp=0.8, duration=4.0,
                        dt=0.02)
    known = [*partitions(co)["recommended"]["known"], QuadraticDamping(3.0),
             RadiationMemory.from_history(hs[0])]
    net = ForceNetwork(inputs=("z", "zdot", "eta"), hidden=(12, 9), window=4, stride=2, lead=2,
                       max_epochs=3).fit(hs[:2], lambda h: 0.1 * h["F_exc"].values)
    kw = {"mass": sh.M, "known": known, "mode": mode, "scheme": scheme, "check": False}
    per_case, batch = _both_kernels(monkeypatch, lambda: rollout(net, hs, compiled=True, **kw))
    stepper = rollout(net, hs, compiled=False, **kw)
    for hb, hp, hn in zip(batch.histories, per_case.histories, stepper.histories):
        for var in ("z", "zdot", "zddot", "F_net", "F_known"):
            ref = hn[var].values
            tol = 1e-12 * np.nanmax(np.abs(ref))
            np.testing.assert_allclose(hb[var].values, ref, rtol=0, atol=tol)
            np.testing.assert_allclose(hb[var].values, hp[var].values, rtol=0, atol=tol)
    np.testing.assert_array_equal(batch.blew_up, stepper.blew_up)
    np.testing.assert_array_equal(batch.iterations, per_case.iterations)


def _growing_problem(n_cases: int, window: int = 3):
    """A linear ODE z̈ = z + F_net (e^t growth) and a small tanh network, as arrays."""
    from hybridwsi.diagnostic.integrators import LaggedIntegrator

    dt, nd, nch = 0.01, 1, 2
    integ = LaggedIntegrator("newmark", dt, np.eye(1), np.zeros((1, 1)), -np.eye(1))
    prob = fast.ExplicitProblem(
        scheme=0, lhs_inv=integ._lhs_inv, damping=np.zeros((1, 1)), stiffness=-np.eye(1),
        coef=np.array([dt, integ._c_v, integ._c_z, integ._c_z1, integ._c_v1]),
        quad=np.zeros(1), p_ss=np.zeros((0, 0)), q_ss=np.zeros((0, 1)), c_out=np.zeros((1, 0)),
        chan_pos=np.array([[0], [1], [-1]]), eta_pos=np.zeros(0, dtype=np.int64),
        window=window, stride=1, corrections=0)
    rng = np.random.default_rng(3)
    layers = fast.FoldedLayers((0.1 * rng.standard_normal((window * nch, 5)),
                                0.1 * rng.standard_normal((5, nd))),
                               (0.01 * rng.standard_normal(5), np.zeros(nd)), "tanh")
    z0 = 1e-3 * (1.0 + np.arange(n_cases))[:, None]
    buf0 = np.zeros((n_cases, window, nch))
    buf0[:, 0, 0] = z0[:, 0]
    n_t = 1200
    return (prob, layers, z0, np.zeros_like(z0), z0.copy(), np.zeros((n_cases, 0)), buf0,
            np.zeros((n_cases, n_t, nd)), np.zeros((n_cases, n_t, 0)), window - 1, 0, 1000)


@pytest.mark.parametrize("ref_amp, all_blow", [([1e-3, 1e6, 1e-2], False),
                                               ([1e-3, 2e-3, 1e-2], True)])
def test_batch_kernel_divergence_watch_as_per_case(monkeypatch, ref_amp, all_blow):
    """Cases that grow beyond BLOWUP_FACTOR x their reference amplitude are flagged, NaN after
    the step their divergence was seen, and the loop stops once all have diverged: the
    batch kernel (which runs diverged cases on) reports exactly what the per-case one does."""
    args = _growing_problem(len(ref_amp))
    run = lambda: fast.run_explicit(*args, np.asarray(ref_amp), 20.0)
    (zp, vp, ap, xp, bp, np_), (zb, vb, ab, xb, bb, nb) = _both_kernels(monkeypatch, run)
    assert bb.tolist() == ([True, True, True] if all_blow else [True, False, True])
    np.testing.assert_array_equal(bb, bp)
    assert nb == np_ and (nb < 1000) == all_blow
    for got, ref in ((zb, zp), (vb, vp), (ab, ap)):
        assert got.shape == ref.shape == (3, 1001, 1)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(ref))
        np.testing.assert_allclose(got, ref, rtol=1e-13, atol=0, equal_nan=True)
    # the growth is e^t: a diverged case stops within 50 steps of crossing 20 x its amplitude
    first_nan = np.argmax(np.isnan(zb[0, :, 0]))
    crossing = np.argmax(np.abs(zb[0, :, 0]) > 20.0 * ref_amp[0])
    assert 0 < crossing < first_nan <= crossing + 51
