"""Reconstruction (paper Eq. 4) against analytic error dynamics."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from _diag_cases import C_HS, M, forced_oscillator
from hybridwsi.diagnostic import Hydrostatic, KnownComponent, reconstruct, regress
from hybridwsi.errors import InputError, SolverError
from hybridwsi.history import make_history

B_REF = 5.0
W = 2 * math.pi / 0.75
T = np.arange(0.0, 20.0, 0.01)
WN = math.sqrt(C_HS / M)


def _reference(bias=None):
    """m z̈ + B ż + C z = F_e; history carries F_tot (+ optional perturbation) and F_damp."""
    z, zd, zdd = forced_oscillator(T, M, B_REF, C_HS, lambda s: 3.0 * np.sin(W * s))
    f_tot = 3.0 * np.sin(W * T) - B_REF * zd - C_HS * z
    if bias is not None:
        f_tot = f_tot + bias
    forces = {"F_tot": f_tot, "F_damp": -B_REF * zd}
    return make_history(T, z, zd, zdd, forces=forces, mass=M, source="test")


def test_clean_reconstruction_is_exact():
    hist = _reference()
    rec = reconstruct(hist, known=[Hydrostatic(C_HS)])
    amp = float(np.abs(hist["z"].values).max())
    assert rec.metrics["max_error"][0] < 1e-6 * amp
    assert rec.metrics["nrms_error"][0] < 1e-6
    assert rec.history.attrs["source"] == "reconstruction"
    assert "hydrostatic" in rec.history.attrs["inputs"]
    np.testing.assert_allclose(rec.history["zddot"].values, hist["zddot"].values,
                               atol=1e-5 * float(np.abs(hist["zddot"].values).max()))
    json.dumps(rec.to_dict())


def test_case1_drifts_quadratically_under_a_force_bias():
    """Nothing known: a constant force error δ gives e(t) = δ t² / (2 m) (double integrator)."""
    delta = 0.01
    rec = reconstruct(_reference(bias=delta), mass=M)
    assert rec.stability.prescribed.verdict == "drift"
    np.testing.assert_allclose(rec.error[:, 0], delta * T**2 / (2 * M), atol=1e-5 * delta * 400 / M)
    assert rec.metrics["final_drift"][0] == pytest.approx(delta * T[-1] ** 2 / (2 * M), rel=1e-4)


def test_case2_stays_bounded_under_a_force_bias():
    """Hydrostatics known: e(t) = (δ/C)(1 − cos ω_n t), bounded by 2 δ / C."""
    delta = 0.01
    rec = reconstruct(_reference(bias=delta), known=[Hydrostatic(C_HS)], mass=M)
    assert rec.stability.prescribed.verdict == "neutral"
    np.testing.assert_allclose(rec.error[:, 0], delta / C_HS * (1 - np.cos(WN * T)),
                               atol=1e-3 * delta / C_HS)  # spline error of F_tot ~1e-4
    assert rec.metrics["max_error"][0] <= 2 * delta / C_HS * (1 + 1e-4)


def test_moving_identified_damping_makes_errors_decay():
    """F_damp regressed gives β = −B; moving it into the ODE turns neutral into damped."""
    bump = 0.5 * np.exp(-(((T - 1.0) / 0.05) ** 2))  # short force error early in the run
    hist = _reference(bias=bump)
    ident = regress(hist, force="F_damp")
    assert ident.beta[0, 0] == pytest.approx(-B_REF, rel=1e-6)
    late = T > 15.0
    plain = reconstruct(hist, known=[Hydrostatic(C_HS)])
    moved = reconstruct(hist, known=[Hydrostatic(C_HS)], move_identified=ident)
    assert plain.stability.prescribed.verdict == "neutral" and moved.stability.prescribed.verdict == "damped"
    amp_plain = np.abs(plain.error[late, 0]).max()
    amp_moved = np.abs(moved.error[late, 0]).max()
    # error envelope decays like exp(−B t / 2m) after the bump (≈ e^{-4.9} by t = 15 s)
    assert amp_moved < 3 * math.exp(-B_REF * 14.0 / (2 * M)) * amp_plain
    assert amp_plain > 0.5 * np.abs(plain.error[(T > 2) & (T < 4), 0]).max()  # persists


def test_errors():
    hist = _reference()
    no_mass = hist.drop_vars(["mass", "dof_j"])
    with pytest.raises(InputError, match="mass"):
        reconstruct(no_mass)

    class Bad(KnownComponent):
        name = "bad"

        def force(self, h):
            return np.zeros((h.sizes["time"], 1))

        def linear_coefficients(self, n):
            return np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))

        def ode_force(self, t, z, zd, x):
            return np.full(1, np.nan)

    bad = reconstruct(hist, known=[Bad()])  # a failed integration is data, not an exception
    assert not bad.success and bad.history is None and bad.metrics["nrms_error"] == [math.inf]
    with pytest.raises(SolverError, match="reconstruction"):
        bad.solution.raise_on_failure()
    other = regress(hist)  # α = m: moving it leaves no inertia
    with pytest.raises(InputError, match="singular"):
        reconstruct(hist, move_identified=other)
