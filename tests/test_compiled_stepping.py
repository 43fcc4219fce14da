"""The compiled (Numba) RK4 loop and force kernels against the NumPy path they replace.

The NumPy loop (``solvers.COMPILED = False``) and the component methods are the reference:
the compiled path must give the same histories to ~1e-12 of each variable's range (the only
difference is the summation order), raise the same errors, and step aside (NumPy loop) for any
component without a kernel or without Numba.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("moorpy")
pytest.importorskip("numba")

import hybridwsi.cummins.compiled as compiled  # noqa: E402
import hybridwsi.forces._compiled as kernels  # noqa: E402
from hybridwsi.cases import load_case  # noqa: E402
from hybridwsi.cummins import build_system, simulate, solvers  # noqa: E402
from hybridwsi.errors import InputError, SolverError  # noqa: E402
from hybridwsi.forces import KnownComponent, LinearDamping, MooringForce, MorisonDrag  # noqa: E402
from hybridwsi.forces.mooring import MooringTable  # noqa: E402
from hybridwsi.casemodel import linear_components  # noqa: E402
from hybridwsi.report.fowt import oc3_coefficients  # noqa: E402
from hybridwsi.waves import JONSWAP  # noqa: E402

#: the DOFs in a non-canonical order: nothing may assume Surge first or Pitch last
DOFS3 = ("Pitch", "Surge", "Heave")
RTOL = 1e-12


@pytest.fixture(scope="module")
def case() -> dict:
    return load_case("oc3_hywind")


@pytest.fixture(scope="module")
def coeffs(case):
    return oc3_coefficients(case)


@pytest.fixture(scope="module")
def mooring_table(case) -> MooringTable:
    return MooringForce.from_case(case, DOFS3).table


@pytest.fixture
def spy(monkeypatch):
    """Count the runs of the compiled loop."""
    calls = []
    real = compiled.run_rk4

    def counted(*args, **kw):
        calls.append(1)
        return real(*args, **kw)

    monkeypatch.setattr(compiled, "run_rk4", counted)
    return calls


def _both(monkeypatch, run):
    """``run()`` on the compiled loop and on the NumPy loop."""
    fast = run()
    monkeypatch.setattr(solvers, "COMPILED", False)
    slow = run()
    monkeypatch.setattr(solvers, "COMPILED", True)
    return fast, slow


def _assert_same(fast, slow, names=("z", "zdot", "zddot", "F_hs", "F_rad_mem", "F_ext",
                                    "F_tot")):
    for name in names:
        a, b = fast[name].values, slow[name].values
        scale = np.abs(b).max(axis=0)
        assert np.all(np.abs(a - b) <= RTOL * scale + 1e-300), name


def test_oc3_sea_state_matches_numpy_loop(case, coeffs, mooring_table, monkeypatch, spy):
    """3 DOF in a JONSWAP sea: nonlinear mooring, Morison drag with wave kinematics and ramp,
    additional damping and a linear stiffness (the default kernel), all compiled."""
    wave = JONSWAP(hs=6.0, tp=10.0, gamma=3.3, seed=3, n_components=60)
    mooring = MooringForce(mooring_table, DOFS3)
    drag = MorisonDrag.from_case(case, DOFS3, wave=wave, ramp=20.0)
    stiffness, damping = linear_components(case, DOFS3,
                                           stiffness=0.1 * mooring_table.stiffness())
    kw = dict(dofs=DOFS3, duration=80.0, dt=0.1, wave=wave, ramp=20.0, z0=[0.01, 2.0, 0.3])

    fast, slow = _both(monkeypatch, lambda: simulate(
        coeffs, forces=[mooring, drag, damping, stiffness], **kw))
    assert len(spy) == 1  # the first run only
    _assert_same(fast, slow)
    assert fast["z"].values[:, 1].std() > 0.1  # a real response, not a trivial zero run


def test_six_dof_oblique_sea_matches_numpy_loop(case, coeffs, monkeypatch, spy):
    """All six DOFs (shuffled), drag kinematics of a sea 30° off x (the 2-D drag branch; the
    excitation is tabulated for head seas only, so the body starts displaced in still water
    instead) and every mooring DOF."""
    dofs = ("Yaw", "Heave", "Roll", "Surge", "Pitch", "Sway")
    wave = JONSWAP(hs=4.0, tp=9.0, gamma=3.3, seed=5, n_components=30, direction=math.pi / 6)
    mooring = MooringForce.from_case(case, dofs)
    drag = MorisonDrag.from_case(case, dofs, wave=wave)
    ss = build_system(coeffs, dofs=dofs, dt=0.1).ss
    kw = dict(dofs=dofs, duration=40.0, dt=0.1, radiation_ss=ss,
              z0=[0.02, 0.2, 0.01, 3.0, 0.02, 1.0], zdot0=[0.0, 0.0, 0.002, 0.1, 0.0, 0.05])
    fast, slow = _both(monkeypatch, lambda: simulate(coeffs, forces=[mooring, drag], **kw))
    assert len(spy) == 1
    _assert_same(fast, slow)


class _Spring(KnownComponent):
    """A user component with its own ode_force and no kernel: the NumPy loop must run it."""

    name = "cubic_spring"

    def force(self, hist):
        return -1e3 * hist["z"].values ** 3

    def linear_coefficients(self, n_dof):
        zero = np.zeros((n_dof, n_dof))
        return zero, zero, zero.copy()

    def ode_force(self, t, z, zdot, x):
        return -1e3 * z ** 3


def test_component_without_kernel_keeps_numpy_loop(case, coeffs, mooring_table, spy):
    assert _Spring().compiled_force(3) is None
    mooring = MooringForce(mooring_table, DOFS3)
    simulate(coeffs, dofs=DOFS3, duration=2.0, dt=0.1, forces=[mooring, _Spring()], z0=0.1)
    assert spy == []


def test_default_kernel_is_the_linear_ode_force():
    """``KnownComponent.compiled_force``: −B ż − C z of linear_coefficients, any DOF count."""
    rng = np.random.default_rng(0)
    b = rng.normal(size=(4, 4))
    comp = LinearDamping(b)
    k = comp.compiled_force(4)
    z, v, out = rng.normal(size=4), rng.normal(size=4), np.empty(4)
    assert k.kernel(0.3, z, v, out, k.fdata, k.idata) == 0
    np.testing.assert_allclose(out, comp.ode_force(0.3, z, v, np.zeros(0)), rtol=1e-14)


def test_morison_kernel_matches_generalised_force(case):
    """Single states at times before, at and after the ramp, 3-DOF and 6-DOF oblique."""
    rng = np.random.default_rng(1)
    sea = JONSWAP(hs=6.0, tp=12.0, gamma=3.3, seed=1, n_components=50, direction=0.4)
    for dofs, wave in ((DOFS3, None), (DOFS3, sea), (case["dofs"], sea)):
        drag = MorisonDrag.from_case(case, dofs, wave=wave, ramp=30.0)
        k = drag.compiled_force(len(dofs))
        out = np.empty(len(dofs))
        for t in (-1.0, 0.0, 7.3, 7.3, 30.0, 812.45):  # 7.3 twice: the cached wave speed
            v = rng.normal(size=len(dofs)) * 0.5
            assert k.kernel(t, np.zeros(len(dofs)), v, out, k.fdata, k.idata) == 0
            ref = drag.ode_force(t, None, v, None)
            assert np.abs(out - ref).max() <= RTOL * np.abs(ref).max()


def test_mooring_table_paths_agree(mooring_table):
    """force6 by the kernel (one state, a batch) against the NumPy float and array paths."""
    import hybridwsi.forces.mooring as mod

    table = mooring_table
    half = np.array(list(table.ranges.values()))
    q = np.random.default_rng(2).uniform(-1.0, 1.0, (40, 6)) * half
    scalar = np.array([table._force6_scalar(s) for s in q])
    array = np.stack(table._wrench(q.T[:, :, None], mod._ArrayMath, table._cells_array,
                                   table._lines_all), axis=-1)
    array[:, 5] -= table.lines.yaw_spring * q[:, 5]
    one = np.array([table.force6(s) for s in q])
    batch = table.force6(q)
    scale = np.abs(scalar - table.preload()).max(axis=0)  # each DOF's force excursion
    for got in (one, batch, array):
        assert np.all(np.abs(got - scalar) <= 1e-11 * scale)
    with pytest.raises(SolverError, match="outside the tabulated range"):
        table.force6(np.array([2.0 * half[0], 0, 0, 0, 0, 0]))
    with pytest.raises(SolverError, match="outside the tabulated range"):
        table.force6(np.array([[0.0] * 6, [0, 0, np.nan, 0, 0, 0]]))


@pytest.mark.filterwarnings("ignore:overflow encountered")  # the NumPy loop on its way to inf
def test_errors_match_numpy_loop(coeffs, mooring_table, monkeypatch):
    """Leaving the mooring table, and a diverging state, raise the same SolverError."""
    mooring = MooringForce(mooring_table, DOFS3)
    for kw, match in ((dict(forces=[mooring], z0=[0.0, 80.0, 0.0]), "outside the tabulated"),
                      (dict(forces=[LinearDamping(-1e13)], zdot0=[0.0, 1.0, 0.0]),
                       "diverged at t")):
        messages = []
        for flag in (True, False):
            monkeypatch.setattr(solvers, "COMPILED", flag)
            with pytest.raises(SolverError, match=match) as err:
                simulate(coeffs, dofs=DOFS3, duration=30.0, dt=0.1, **kw)
            messages.append(str(err.value))
        assert messages[0] == messages[1]


def test_without_numba_everything_falls_back(case, coeffs, monkeypatch, spy):
    """HAVE_NUMBA False: no kernels, the table's float path, the NumPy loop."""
    monkeypatch.setattr(kernels, "HAVE_NUMBA", False)
    mooring = MooringForce.from_case(case, DOFS3)
    assert mooring.compiled_force(3) is None and mooring.table._single is None
    assert LinearDamping(1.0).compiled_force(3) is None
    assert MorisonDrag.from_case(case, DOFS3).compiled_force(3) is None
    hist = simulate(coeffs, dofs=DOFS3, duration=2.0, dt=0.1, forces=[mooring],
                    z0=[0.01, 0.5, 0.1])
    assert spy == [] and np.isfinite(hist["z"].values).all()


# ------------------------------------------------- quadratic damping and rotor thrust kernels
def _rotor(dofs):
    """NREL 5-MW-like operating point: 800 kN thrust at the hub 90 m up (a little off the
    x-z plane, for a yaw moment), dT/dU 1.2e5 N s/m (the module docstring's order)."""
    from hybridwsi.forces import RotorThrust

    return RotorThrust(8.0e5, 1.2e5, (-5.0, 1.5, 90.0), dofs)


def test_quadratic_and_rotor_kernels_match_ode_force():
    """Single states, all six DOFs shuffled and three: the kernels are the NumPy methods."""
    from hybridwsi.forces import QuadraticDamping

    rng = np.random.default_rng(4)
    for dofs in (DOFS3, ("Yaw", "Heave", "Roll", "Surge", "Pitch", "Sway")):
        n = len(dofs)
        quad = QuadraticDamping(rng.uniform(1e4, 1e6, n))
        for comp in (quad, QuadraticDamping(2.5e5), _rotor(dofs)):
            k = comp.compiled_force(n)
            out = np.empty(n)
            for _ in range(20):
                v = rng.normal(size=n)
                assert k.kernel(1.0, rng.normal(size=n), v, out, k.fdata, k.idata) == 0
                ref = comp.ode_force(1.0, np.zeros(n), v, None)
                assert np.abs(out - ref).max() <= RTOL * np.abs(ref).max()
    with pytest.raises(InputError, match="set up for 3 DOFs"):
        _rotor(DOFS3).compiled_force(2)


def test_quadratic_damping_and_damped_rotor_run_compiled(case, coeffs, mooring_table,
                                                         monkeypatch, spy):
    """A sea state with mooring, Morison drag, a quadratic damping and an operating rotor with
    aerodynamic damping: the compiled loop runs and matches the NumPy loop."""
    from hybridwsi.forces import QuadraticDamping

    wave = JONSWAP(hs=5.0, tp=10.0, gamma=3.3, seed=6, n_components=40)
    forces = [MooringForce(mooring_table, DOFS3), MorisonDrag.from_case(case, DOFS3, wave=wave),
              QuadraticDamping([2.0e9, 3.0e5, 1.0e5]), _rotor(DOFS3)]
    assert not forces[3].time_only  # the damped rotor is state-dependent: it needs its kernel
    kw = dict(dofs=DOFS3, duration=60.0, dt=0.1, wave=wave, ramp=15.0, z0=[0.01, 2.0, 0.3])
    fast, slow = _both(monkeypatch, lambda: simulate(coeffs, forces=forces, **kw))
    assert len(spy) == 1
    _assert_same(fast, slow)
    # the thrust moved the platform downwind: a real, nonzero response of every force
    assert fast["z"].values[-200:, 1].mean() > 1.0


def test_quadratic_and_rotor_without_numba_fall_back(monkeypatch):
    from hybridwsi.forces import QuadraticDamping

    monkeypatch.setattr(kernels, "HAVE_NUMBA", False)
    assert QuadraticDamping(1.0).compiled_force(3) is None
    assert _rotor(DOFS3).compiled_force(3) is None
