"""Radiation state-space realisation: checked against closed-form kernels and their transforms."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import synthetic_hydro as sh
from hybridwsi.forces import KnownComponent
from hybridwsi.errors import InputError
from hybridwsi.history import make_history
from hybridwsi.forces import RadiationMemory
from hybridwsi.hydro.statespace import RadiationSS, fit_radiation_ss

DOF = ["Heave"]


# The closed-form kernels below have ∫K dt = B(0) ≠ 0 (they are not radiation kernels of a
# floating body): they are fitted with low_frequency="free" (what "auto" picks for them too).
FREE = {"low_frequency": "free"}


def _da(t: np.ndarray, k: np.ndarray, dofs=DOF) -> xr.DataArray:
    k = k.reshape(t.size, len(dofs), len(dofs))
    return xr.DataArray(k, dims=("time", "radiating_dof", "influenced_dof"),
                        coords={"time": t, "radiating_dof": dofs, "influenced_dof": dofs})


def test_three_pole_kernel_recovers_exact_poles_and_minimal_order():
    t = np.arange(0, 10, 0.005)
    k = 20 * np.exp(-1.5 * t) * np.cos(4 * t) + 10 * np.exp(-3 * t)
    ss = fit_radiation_ss(_da(t, k), tol=1e-6, **FREE)
    assert ss.order == 3  # no lower order can represent three distinct poles
    expected = np.sort_complex(np.array([-1.5 + 4j, -1.5 - 4j, -3.0]))
    np.testing.assert_allclose(np.sort_complex(ss.poles), expected, atol=1e-6)
    assert ss.fit_error["time"] < 1e-6 and ss.n_reflected == 0
    np.testing.assert_allclose(ss.impulse(t)[:, 0, 0], k, atol=1e-6 * k.max())


def test_frequency_response_matches_analytic_damping_and_added_mass():
    ss = fit_radiation_ss(sh.irf(t_max=8.0), **FREE)
    w = np.array([0.5, 3.0, 7.0, 12.0, 30.0])
    np.testing.assert_allclose([ss.equivalent_damping(x)[0, 0] for x in w], sh.damping(w),
                               rtol=1e-4)
    a = [sh.A_INF + ss.equivalent_added_mass(x)[0, 0] for x in w]
    np.testing.assert_allclose(a, sh.added_mass(w), rtol=1e-4)
    co = sh.coefficients()
    ss_b = fit_radiation_ss(sh.irf(t_max=8.0), coeffs=co, **FREE)
    assert ss_b.fit_error["frequency_bem"] < 1e-3
    assert ss_b.fit_error["frequency"] < 1e-2


def test_order_selection_is_the_smallest_meeting_tol():
    t = np.arange(0, 10, 0.005)
    k = 20 * np.exp(-1.5 * t) * np.cos(4 * t) + 10 * np.exp(-3 * t)
    loose = fit_radiation_ss(_da(t, k), tol=0.5, **FREE)
    fixed1 = fit_radiation_ss(_da(t, k), order=1, **FREE)
    assert loose.order < 3
    assert fixed1.order == 1 and fixed1.fit_error["time"] > 0.01
    with pytest.warns(UserWarning, match="fit error"):
        capped = fit_radiation_ss(_da(t, k), max_order=2, tol=1e-6, **FREE)
    assert not capped.converged and capped.order <= 2


def test_growing_kernel_gives_stable_model():
    # a kernel that grows over the window has an unstable ERA pole; it must be reflected
    t = np.arange(0, 4, 0.01)
    k = np.exp(0.3 * t) * np.cos(5 * t)
    ss = fit_radiation_ss(_da(t, k), order=2, **FREE)
    assert np.all(ss.poles.real < 0)
    assert ss.n_reflected == 2
    np.testing.assert_allclose(np.abs(ss.poles.imag), 5.0, rtol=1e-3)


def test_mimo_kernel_by_one_stacked_realisation():
    t = np.arange(0, 8, 0.01)
    dofs = ["Surge", "Heave"]
    k = np.zeros((t.size, 2, 2))
    k[:, 0, 0] = 30 * np.exp(-2 * t) * np.cos(5 * t)
    k[:, 1, 1] = 50 * np.exp(-4 * t) * np.cos(7 * t)
    k[:, 0, 1] = k[:, 1, 0] = 5 * np.exp(-3 * t)
    ss = fit_radiation_ss(_da(t, k, dofs), tol=1e-5, **FREE)
    # McMillan degree: 2 per oscillatory pole pair (rank-1 residues) + 2 for the rank-2
    # coupling residue [[0, 5], [5, 0]] of the pole −3
    assert ss.order == 6
    np.testing.assert_allclose(ss.impulse(t), k, atol=1e-4 * np.abs(k).max())
    assert ss.radiating_dof == dofs and ss.influenced_dof == dofs


def test_radiation_memory_force_equals_frequency_domain_force():
    # steady harmonic motion z = Z sin ωt: F_mem = −(A(ω) − A∞) z̈ − B(ω) ż (Ogilvie)
    ss = fit_radiation_ss(sh.irf(t_max=8.0), **FREE)
    w, amp, dt = 6.0, 0.02, 0.002
    t = np.arange(0, 12, dt)
    z, zd, zdd = amp * np.sin(w * t), amp * w * np.cos(w * t), -amp * w**2 * np.sin(w * t)
    hist = make_history(t, z, zd, zdd)
    comp = RadiationMemory(ss)
    f = comp.force(hist)[:, 0]
    f_ref = -(sh.added_mass(w) - sh.A_INF) * zdd - sh.damping(w) * zd
    late = t > 6  # after the start-up transient (kernel decays in ~2 s)
    assert np.max(np.abs(f[late] - f_ref[late])) < 2e-3 * np.max(np.abs(f_ref))
    # and against a direct trapezoidal convolution of the exact kernel
    kern = sh.kernel(t)
    conv = -dt * (np.convolve(kern, zd)[: t.size] - 0.5 * (kern * zd[0] + kern[0] * zd))
    assert np.max(np.abs(f - conv)) < 1e-3 * np.max(np.abs(conv))


def test_radiation_memory_component_contract():
    ss = fit_radiation_ss(sh.irf(), **FREE)
    comp = RadiationMemory(ss)
    assert isinstance(comp, KnownComponent) and comp.n_states == ss.order
    for mat in comp.linear_coefficients(1):
        np.testing.assert_array_equal(mat, 0.0)
    np.testing.assert_allclose(comp.equivalent_damping(7.0)[0, 0], sh.damping(7.0), rtol=1e-4)
    x = np.ones(ss.order)
    np.testing.assert_allclose(comp.ode_force(0.0, np.zeros(1), np.zeros(1), x), -ss.C @ x)
    np.testing.assert_allclose(comp.state_derivative(0.0, np.zeros(1), np.ones(1), x),
                               ss.A @ x + ss.B[:, 0])
    other = make_history(np.arange(10.0), np.zeros((10, 2)), np.zeros((10, 2)),
                         dof=["Surge", "Heave"])
    with pytest.raises(InputError, match="DOFs"):
        comp.force(other)


def test_to_dict_round_trip():
    ss = fit_radiation_ss(sh.irf(), **FREE)
    back = RadiationSS.from_dict(ss.to_dict())
    t = np.linspace(0, 3, 50)
    np.testing.assert_allclose(back.impulse(t), ss.impulse(t))
    assert back.order == ss.order and back.fit_error == ss.fit_error


@pytest.mark.parametrize(
    "kernel, kwargs, match",
    [
        (np.full(50, np.nan), {"dt": 0.01}, "NaN"),
        (np.zeros(50), {"dt": 0.01}, "identically zero"),
        (np.ones(50), {}, "time step"),
        (np.ones(50), {"dt": 0.01, "method": "prony"}, "method"),
        (np.ones(50), {"dt": 0.01, "tol": 2.0}, "tol"),
    ],
)
def test_bad_input_raises_input_error(kernel, kwargs, match):
    with pytest.raises(InputError, match=match):
        fit_radiation_ss(kernel, **kwargs)


def test_non_uniform_kernel_time_is_rejected():
    t = np.sort(np.concatenate([np.arange(0, 1, 0.01), [0.555]]))
    with pytest.raises(InputError, match="uniform"):
        fit_radiation_ss(_da(t, np.exp(-t)))
