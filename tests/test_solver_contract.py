"""One solver contract: every integrator returns a SolverResult, failure as data; stateful
force components (``begin_step``) are stepped by the integrator and checked against the closed
form of a force held over each step."""

from __future__ import annotations

import math

import numpy as np
import pytest
import synthetic_hydro as sh
from _diag_cases import HeldSpring

from hybridwsi import cummins
from hybridwsi.cummins import SolverResult, solvers
from hybridwsi.cummins.system import CumminsSystem
from hybridwsi.errors import InputError, SolverError
from hybridwsi.forces import LinearDamping

M_EFF, C = sh.M + sh.A_INF, sh.C  # kg, N/m
OMEGA = math.sqrt(C / M_EFF)  # rad/s


def _held_recursion(z0: float, k: float, dt: float, n_steps: int) -> np.ndarray:
    """Exact z_n of ``M z̈ + C z = −k z_n`` on every step [t_n, t_n + dt] (zero-order hold)."""
    c, s = math.cos(OMEGA * dt), math.sin(OMEGA * dt)
    z, v, out = z0, 0.0, [z0]
    for _ in range(n_steps):
        p = -k * z / C  # static displacement under the held force
        z, v = p + (z - p) * c + v / OMEGA * s, -(z - p) * OMEGA * s + v * c
        out.append(z)
    return np.array(out)


def test_stateful_component_is_stepped_once_per_step_and_held():
    k, dt, duration, z0 = 0.5 * C, 0.002, 4.0, 0.02
    spring = HeldSpring(k)
    assert spring.stepped and spring.compiled_force(1) is None
    h = cummins.simulate(sh.coefficients(), duration=duration, dt=dt, radiation="none",
                         z0=z0, forces=[spring])
    t = h["time"].values
    # once at every output time (the start of each step, and the last sample), in order
    np.testing.assert_array_equal([c[0] for c in spring.calls], t)
    assert {c[1] for c in spring.calls} == {dt}
    z = h["z"].values[:, 0]
    # RK4 of a linear ODE with constant forcing over the step: local error (ω dt)^5/120,
    # ω dt = 0.016: ~1e-8 of z0 after 2000 steps
    exact = _held_recursion(z0, k, dt, t.size - 1)
    tol = 1e-7 * z0
    np.testing.assert_allclose(z, exact, rtol=0, atol=tol)
    # the force recorded is the held one, and the hold matters: a continuous spring C + k
    # oscillates at sqrt((C + k)/M) without the hold's negative damping (growth)
    np.testing.assert_array_equal(h["F_ext"].values[:, 0], -k * z)
    continuous = z0 * np.cos(math.sqrt((C + k) / M_EFF) * t)
    assert np.max(np.abs(z - continuous)) > 1e3 * tol
    # the hold delays the spring by dt/2 on average, a negative damping k dt/2: the
    # envelope grows as e^{k dt t/(4 M)} (6.6 % in 4 s)
    late = t > duration - 0.8
    peak = np.argmax(np.abs(np.where(late, z, 0.0)))
    growth = math.exp(k * dt * t[peak] / (4 * M_EFF))
    assert abs(z[peak]) == pytest.approx(z0 * growth, rel=1e-3)


def test_stateful_component_takes_the_python_loop(monkeypatch):
    pytest.importorskip("numba")
    from hybridwsi.cummins import compiled

    calls = []
    monkeypatch.setattr(compiled, "run_rk4", lambda *a, **kw: calls.append(1))
    sys = CumminsSystem(["Heave"], np.eye(1) * sh.M, np.eye(1) * sh.A_INF, np.eye(1) * C)
    sol = solvers.solve_rk4(sys, np.zeros((201, 1)), np.array([0.01]), np.zeros(1), 0.01,
                            components=[HeldSpring(1.0), LinearDamping(2.0)])
    assert calls == [] and sol.method == "rk4" and sol.success
    assert sol.counts["begin_step"] == 101 and sol.nfev == 4 * 100 + 1


def _system() -> CumminsSystem:
    return CumminsSystem(["Heave"], np.eye(1) * sh.M, np.eye(1) * sh.A_INF, np.eye(1) * C)


@pytest.mark.filterwarnings("ignore:overflow encountered", "ignore:invalid value")
@pytest.mark.parametrize("name", [i.name for i in solvers.INTEGRATORS])
def test_every_integrator_returns_its_failure_as_data(name):
    """An unstable system (C < 0, growth e^{√(|C|/M) t} overflows): success False, a message,
    no exception; a stable one: success True and the closed-form free oscillation."""
    integ = next(i for i in solvers.INTEGRATORS if i.name == name)
    dt, nt = 0.001, 2001
    n_u = 2 * nt - 1 if integ.half_steps else nt
    bad = _system()
    bad.stiffness = -1e8 * np.eye(1)
    if name == "convolution":
        bad.kernel = np.zeros((3, 1, 1))
    sol = integ.solve(bad, np.zeros((n_u, 1)), np.array([0.01]), np.zeros(1), dt)
    assert isinstance(sol, SolverResult) and not sol.success and sol.status == -1
    assert "not finite" in sol.message or "diverged" in sol.message
    with pytest.raises(SolverError, match=sol.message[:20]):
        sol.raise_on_failure()
    good = _system()
    if name == "convolution":
        good.kernel = np.zeros((3, 1, 1))
    sol = integ.solve(good, np.zeros((n_u, 1)), np.array([0.01]), np.zeros(1), dt)
    assert sol.success and sol.status == 0 and sol.z.shape == (nt, 1)
    np.testing.assert_allclose(sol.t, np.arange(nt) * dt)
    np.testing.assert_allclose(sol.z[:, 0], 0.01 * np.cos(OMEGA * sol.t), atol=2e-6)


def test_registry_picks_by_capability():
    assert solvers.integrator_for("statespace").name == "linear"
    assert solvers.integrator_for("none", state_forces=True).name == "rk4"
    assert solvers.integrator_for("convolution").name == "convolution"
    assert solvers.integrator_for("statespace", batched=True).name == "linear"
    with pytest.raises(InputError, match="statespace"):
        solvers.integrator_for("convolution", state_forces=True)
    with pytest.raises(InputError, match="batch"):
        solvers.integrator_for("convolution", batched=True)
    with pytest.raises(InputError, match="radiation must be one of"):
        solvers.integrator_for("bogus")
