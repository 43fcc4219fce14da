"""Radiation and excitation impulse responses: exact quadrature, analytic transform pairs,
round trips K -> B, Ogilvie's relation and the frequency-domain excitation.

The BEM-based checks use the shipped paper coefficients (6400 panels, 400 frequencies,
``hybridwsi.hydro.bem.paper_coefficients``), so no BEM run is needed here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
from scipy.integrate import quad

from hybridwsi.errors import InputError
from hybridwsi.hydro import bem
from hybridwsi.hydro.irf import (
    added_mass_from_irf,
    damping_from_irf,
    excitation_from_elevation,
    excitation_irf,
    filon_linear,
    ogilvie_check,
    radiation_irf,
)

R, RHO, G = 0.15, 998.2, 9.81


@pytest.fixture(scope="module")
def coeffs() -> xr.Dataset:
    return bem.paper_coefficients()


@pytest.fixture(scope="module")
def kernel(coeffs) -> xr.DataArray:
    return radiation_irf(coeffs)


def synthetic(b_of_w, omega) -> xr.Dataset:
    """A minimal coefficient Dataset with a given B(ω) (1 DOF)."""
    b = np.asarray(b_of_w(omega), float)[:, None, None]
    return xr.Dataset({"radiation_damping": (("omega", "radiating_dof", "influenced_dof"), b)},
                      coords={"omega": omega, "radiating_dof": ["Heave"],
                              "influenced_dof": ["Heave"]})


# ------------------------------------------------------------------------- quadrature
@pytest.mark.parametrize("kind", ["cos", "sin"])
def test_filon_is_exact_for_piecewise_linear(kind):
    rng = np.random.default_rng(0)
    x = np.sort(rng.uniform(0, 3, 12))
    f = rng.normal(size=12)
    trig = np.cos if kind == "cos" else np.sin
    for k in (0.0, 1e-3, 0.7, 9.0, 60.0):
        ref = sum(quad(lambda u, a=a, b=b: trig(k * u) * np.interp(u, x, f), a, b,
                       epsabs=1e-13, epsrel=1e-13)[0] for a, b in zip(x[:-1], x[1:]))
        assert filon_linear(x, f, np.array([k]), kind)[0] == pytest.approx(ref, abs=1e-10)


def test_radiation_irf_matches_analytic_pair():
    # B = b0 ω e^{-aω}  <->  K = (2/π) b0 (a² - t²)/(a² + t²)²  (exact cosine transform)
    a, b0 = 0.5, 3.0
    omega = bem.paper_frequencies()
    K = radiation_irf(synthetic(lambda w: b0 * w * np.exp(-a * w), omega), t_max=20.0)
    t = K["time"].values
    exact = (2 / np.pi) * b0 * (a**2 - t**2) / (a**2 + t**2) ** 2
    err = np.abs(K.values[:, 0, 0] - exact).max()
    assert err < 1e-3 * np.abs(exact).max()
    assert K.dims == ("time", "radiating_dof", "influenced_dof") and K.name == "K"
    assert K.attrs["units"] == "kg/s^2"


def test_radiation_irf_input_errors():
    omega = np.linspace(1, 10, 10)
    with pytest.raises(InputError):
        radiation_irf(synthetic(lambda w: np.where(w > 5, np.nan, w), omega))
    with pytest.raises(InputError):
        radiation_irf(xr.Dataset())
    with pytest.raises(InputError):
        radiation_irf(synthetic(lambda w: w, omega), tail="cubic")
    with pytest.raises(InputError):
        radiation_irf(synthetic(lambda w: np.exp(-w), omega), t=[-1.0, 0.0])


# ------------------------------------------------------------------------- paper sphere
def test_shipped_paper_coefficients_are_the_paper_set_up(coeffs):
    assert coeffs.sizes["omega"] == 400 and coeffs.attrs["n_panels"] == 6400
    assert json_flags(coeffs) == []
    # converged A(∞) = half the displaced mass (Hulme); the paper's 3.50 kg is A(40 rad/s)
    a_half = 0.5 * RHO * 2 / 3 * math.pi * R**3
    assert float(coeffs["added_mass_inf"][0, 0]) == pytest.approx(a_half, rel=1e-3)


def json_flags(ds):
    import json

    return json.loads(ds.attrs["quality_flags"])


def test_truncation_is_reported(kernel):
    t_max = kernel.attrs["t_max"]
    assert 0.5 < t_max < 30.0 and kernel["time"].values[-1] == pytest.approx(t_max, abs=0.006)
    k = np.abs(kernel.values[:, 0, 0])
    assert k[-1] <= kernel.attrs["tol"] * k.max() * 1.01
    assert kernel.attrs["tail"] == "asymptotic" and kernel.attrs["tail_remainder_bound"] < 1e-3 * k.max()


def test_round_trip_K_to_B(coeffs, kernel):
    w = coeffs["omega"].values
    b = coeffs["radiation_damping"].values[:, 0, 0]
    b_back = damping_from_irf(kernel, w).values[:, 0, 0]
    assert np.abs(b_back - b).max() < 0.01 * b.max()
    band = b > 0.1 * b.max()
    np.testing.assert_allclose(b_back[band], b[band], rtol=0.02)


def test_ogilvie_consistency(coeffs, kernel):
    # default truncation (|K| < 1e-4 max, ~3.5 s): the slow tail of K matters only at low ω
    chk = ogilvie_check(coeffs, kernel, band=(0.3, 35.0))
    assert chk.attrs["max_relative_deviation"] < 0.01
    # a 20 s kernel: A∞ implied at every BEM frequency agrees with the ω = ∞ solve to 0.1 %
    long = ogilvie_check(coeffs, radiation_irf(coeffs, t_max=20.0))
    assert long.attrs["max_relative_deviation"] < 1e-3
    a_back = added_mass_from_irf(kernel, coeffs["omega"].values, coeffs["added_mass_inf"])
    sel = (coeffs["omega"] > 0.3) & (coeffs["omega"] < 35.0)
    np.testing.assert_allclose(a_back.values[sel.values], coeffs["added_mass"].values[sel.values],
                               rtol=0.01)


# ------------------------------------------------------------------------- excitation
def test_excitation_kernel_static_gain_is_hydrostatic(coeffs):
    ke = excitation_irf(coeffs, dt=0.002, t_max=5.0)
    dt = 0.002
    # ∫K_e dt = F̂(0): a very long wave lifts the body by the hydrostatic force rho g pi R^2
    assert ke.values[:, 0].sum() * dt == pytest.approx(RHO * G * math.pi * R**2, rel=0.01)


def test_excitation_from_regular_wave_matches_frequency_domain(coeffs):
    i = int(np.argmin(np.abs(coeffs["omega"].values - 8.3)))
    w0 = float(coeffs["omega"][i])                       # a BEM frequency near resonance
    f_hat = coeffs["excitation_force"].isel(omega=i, wave_direction=0, influenced_dof=0).item()
    t = np.arange(0.0, 30.0, 0.002)
    a = 0.025
    force = excitation_from_elevation(coeffs, t, a * np.cos(w0 * t)).values[:, 0]
    expected = np.real(f_hat * a * np.exp(-1j * w0 * t))
    mid = (t > 6.0) & (t < 24.0)                         # away from the record ends
    assert np.abs(force[mid] - expected[mid]).max() < 0.01 * np.abs(f_hat) * a
