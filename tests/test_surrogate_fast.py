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


# ------------------------------------------- nonlinear known components with Numba kernels
#: OC3-Hywind in surge, heave and pitch: the known part of the MoorDyn hybrid's partition (a)
OC3_DOFS = ("Surge", "Heave", "Pitch")


@pytest.fixture(scope="module")
def oc3_known():
    """Hydrostatics, A∞, the additional damping, a small quadratic damping, the tabulated
    quasi-static mooring and the operating NREL 5-MW rotor in turbulent wind (8 m/s, TI 0.1:
    the force depends on t), and three 30 s cases (JONSWAP excitation and η, each from a
    different small start) at Δt 0.1 s; the mass."""
    from hybridwsi.cases import load_case
    from hybridwsi.cummins.forcing import excitation
    from hybridwsi.forces import AddedMass, Hydrostatic, MooringForce, QuadraticDamping
    from hybridwsi.forces.linear import mass_from
    from hybridwsi.forces.morison import additional_damping
    from hybridwsi.forces.rotor import rotor_from_case
    from hybridwsi.history import make_history
    from hybridwsi.hydro import coefficients as cf
    from hybridwsi.report.fowt import oc3_coefficients
    from hybridwsi.waves import JONSWAP

    case = load_case("oc3_hywind")
    co, dofs = oc3_coefficients(case), list(OC3_DOFS)
    rotor = rotor_from_case({**case, "rotor": {**case["rotor"], "state": "operating",
                                               "wind_speed": 8.0, "wind_seed": 1,
                                               "turbulence_intensity": 0.1}}, dofs)
    known = [Hydrostatic(cf.matrix(co, "hydrostatic_stiffness", dofs)),
             AddedMass(cf.matrix(co, "added_mass_inf", dofs)), additional_damping(case, dofs),
             QuadraticDamping(np.array([2e5, 1e5, 1e9])), MooringForce.from_case(case, dofs),
             rotor]
    t = np.arange(301) * 0.1
    hs = []
    for seed in (1, 2, 3):
        f_exc, eta = excitation(JONSWAP(hs=4.0, tp=10.0, seed=seed), co, t, dofs, 5.0)
        z = 0.1 * seed * np.array([1.0, 0.05, 0.002]) * np.sin(0.3 * t)[:, None]
        hs.append(make_history(t, z, np.gradient(z, t, axis=0), np.zeros_like(z),
                               forces={"F_exc": f_exc}, dof=dofs, check=False,
                               extra_vars={"eta": (("time", "probe"), eta[:, None])}))
    return known, hs, mass_from(None, co, dofs)


@pytest.fixture(scope="module")
def oc3_net(oc3_known):
    from hybridwsi.surrogate.network import ForceNetwork

    _, hs, _ = oc3_known
    return ForceNetwork(inputs=("z", "zdot", "eta"), hidden=(8,), window=3, stride=2, lead=2,
                        max_epochs=2, seed=0).fit(hs[:1], lambda h: 0.05 * h["F_exc"].values)


@pytest.mark.parametrize("mode, corrections", [("lagged", 1), ("corrected", 2)])
def test_mooring_table_and_operating_rotor_run_compiled_as_the_stepper(
        monkeypatch, oc3_known, oc3_net, mode, corrections):
    """The tabulated mooring and the operating rotor known (partition (a) of the OC3 MoorDyn
    hybrid): the compiled loop, per case and batched, runs them through their Numba kernels
    and gives the NumPy stepper's trajectories and forces (their ``ode_force``) to rounding."""
    from hybridwsi.surrogate.physics import BatchedPhysics
    from hybridwsi.surrogate.rollout import rollout

    known, hs, mass = oc3_known
    phys = BatchedPhysics(mass, known, 3)
    assert [type(c).__name__ for _, c in phys.other] == ["MooringForce", "OperatingRotor"]
    assert fast.supported("tanh", phys.compiled_forces, mode, "newmark")
    kw = {"mass": mass, "known": known, "mode": mode, "corrections": corrections,
          "check": False, "prescribed": "F_exc", "amplitude": 30.0}
    compiled, run = [], fast.run_explicit
    monkeypatch.setattr(fast, "run_explicit", lambda *a: compiled.append(1) or run(*a))
    per_case, batch = _both_kernels(monkeypatch, lambda: rollout(oc3_net, hs, **kw))
    assert compiled == [1, 1]  # the default (compiled=None) took the compiled loop
    stepper = rollout(oc3_net, hs, compiled=False, **kw)
    assert compiled == [1, 1]
    for hb, hp, hn in zip(batch.histories, per_case.histories, stepper.histories):
        assert np.ptp(hn["z"].sel(dof="Surge").values) > 5.0  # the rotor pushes it
        for var in ("z", "zdot", "zddot", "F_net", "F_known"):
            ref = hn[var].values
            scale = np.max(np.abs(ref), axis=0)  # per DOF
            for got in (hp, hb):
                err = np.max(np.abs(got[var].values - ref), axis=0) / scale
                assert np.all(err < 1e-10), (var, err)


def test_known_component_without_kernel_keeps_the_stepper(monkeypatch, oc3_known, oc3_net):
    """A nonlinear known component without a Numba kernel (its own ``ode_force``, no
    ``compiled_force``): the rollout takes the NumPy stepper; forcing the compiled loop is
    refused (it would leave the component out)."""
    from hybridwsi.errors import InputError
    from hybridwsi.forces import KnownComponent
    from hybridwsi.surrogate.physics import BatchedPhysics
    from hybridwsi.surrogate.rollout import rollout

    class Cubic(KnownComponent):
        name = "cubic_spring"

        def ode_force(self, t, z, zdot, x):
            return -1e3 * np.asarray(z) ** 3

        def force(self, hist):
            return -1e3 * hist["z"].values ** 3

        def linear_coefficients(self, n):
            return np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))

    known, hs, mass = oc3_known
    known = [*known, Cubic()]
    assert BatchedPhysics(mass, known, 3).compiled_forces is None
    assert not fast.supported("tanh", None, "lagged", "newmark")
    monkeypatch.setattr(fast, "run_explicit", lambda *a: pytest.fail("compiled loop ran"))
    kw = {"mass": mass, "known": known, "check": False, "prescribed": "F_exc",
          "amplitude": 30.0, "n_steps": 20}
    assert not rollout(oc3_net, hs[:1], **kw).solution.failed.any()
    with pytest.raises(InputError, match="Numba kernel of every nonlinear known component"):
        rollout(oc3_net, hs[:1], compiled=True, **kw)


@pytest.mark.parametrize("compiled", [True, False])
def test_kernel_failure_raises_as_the_stepper(oc3_known, oc3_net, compiled):
    """A state leaving a component's table (a 200 MN surge push drives the platform out of the
    mooring table / the rotor's wind range within seconds) is a SolverError on both paths,
    as ``ode_force`` raises it in the stepper — never an extrapolated force."""
    from hybridwsi.errors import SolverError
    from hybridwsi.surrogate.rollout import rollout

    known, hs, mass = oc3_known
    push = np.stack([h["F_exc"].values for h in hs[:1]])
    push[..., 0] += 2e8
    with pytest.raises(SolverError, match="outside"):
        rollout(oc3_net, hs[:1], mass=mass, known=known, check=False, prescribed=push,
                amplitude=1e4, compiled=compiled)
