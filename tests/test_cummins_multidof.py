"""Multi-DOF Cummins runs against the frequency-domain response and closed-form statics.

Coefficients: a synthetic but physically consistent 2-DOF set. The radiation kernel is a sum
of two damped cosines with symmetric positive semi-definite amplitude matrices,

    K(t) = Σ_m K_m e^{−σ_m t} cos(ν_m t),

so B(ω) (its cosine transform) is symmetric positive semi-definite and A(ω) − A∞ (its sine
transform) is exactly Kramers–Kronig consistent (closed forms in ``_b`` and ``_a``). The rigid-
body mass matrix is that of a body whose centre of mass lies ``Z_G`` below the reference
point, so surge and pitch couple through ``M[Surge, Pitch] = m z_G``; the pitch stiffness is
ρg(I_wp + V z_B) − m g z_G of a truncated cylinder (surge has no restoring force).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from hybridwsi import cummins
from hybridwsi.cummins.solvers import solve_linear
from hybridwsi.errors import InputError
from hybridwsi.forces import ConstantForce, ExactHydrostatic, PrescribedForce
from hybridwsi.waves import Regular

RHO, G = 1000.0, 9.81
# truncated cylinder, radius 0.5 m, draft 1 m, floating freely; CM 0.6 m below the waterline
RADIUS, DRAFT, Z_G = 0.5, 1.0, -0.6
VOL = np.pi * RADIUS**2 * DRAFT
MASS = RHO * VOL
I_G = MASS * (3 * RADIUS**2 + DRAFT**2) / 12  # about the CM, solid-cylinder estimate
C55 = RHO * G * (np.pi * RADIUS**4 / 4 + VOL * (-DRAFT / 2)) - MASS * G * Z_G
# kernel modes: (σ [1/s], ν [rad/s], amplitude matrix [[surge, coupling], [coupling, pitch]])
MODES = [(1.5, 2.0, 2000.0 * np.array([[1.0, -0.5], [-0.5, 0.33]])),
         (2.5, 4.0, 800.0 * np.array([[1.0, 0.2], [0.2, 0.1]]))]
A_INF = np.array([[785.0, -392.0], [-392.0, 262.0]])


def _b(w: np.ndarray, s: float, nu: float) -> np.ndarray:
    """∫_0^∞ e^{−st} cos(νt) cos(ωt) dt."""
    return 0.5 * (s / (s**2 + (w - nu) ** 2) + s / (s**2 + (w + nu) ** 2))


def _a(w: np.ndarray, s: float, nu: float) -> np.ndarray:
    """−(1/ω) ∫_0^∞ e^{−st} cos(νt) sin(ωt) dt."""
    return -0.5 / w * ((w + nu) / (s**2 + (w + nu) ** 2) + (w - nu) / (s**2 + (w - nu) ** 2))


def mass_matrix() -> np.ndarray:
    """Rigid-body mass about the reference point: pitch θ moves the CM by θ z_G in surge."""
    return np.array([[MASS, MASS * Z_G], [MASS * Z_G, I_G + MASS * Z_G**2]])


def added_mass(w: float) -> np.ndarray:
    return A_INF + sum(k * _a(np.asarray(w), s, nu) for s, nu, k in MODES)


def damping(w: float) -> np.ndarray:
    return sum(k * _b(np.asarray(w), s, nu) for s, nu, k in MODES)


def excitation(w: np.ndarray) -> np.ndarray:
    """Smooth complex F_e(ω) [N/m, N m/m], shape (nω, 2)."""
    w = np.asarray(w, dtype=float)
    surge = 1500.0 * w * np.exp(-0.1 * w) * np.exp(-0.2j * w)
    pitch = -600.0 * w * np.exp(-0.1 * w) * np.exp(1j * (0.5 - 0.1 * w))
    return np.stack([surge, pitch], axis=-1)


def kernel(dofs: list[str], t_max: float = 12.0, dt: float = 0.005) -> xr.DataArray:
    t = np.arange(0.0, t_max + dt / 2, dt)
    k = sum(km[None] * (np.exp(-s * t) * np.cos(nu * t))[:, None, None] for s, nu, km in MODES)
    return xr.DataArray(k, dims=("time", "radiating_dof", "influenced_dof"),
                        coords={"time": t, "radiating_dof": dofs, "influenced_dof": dofs})


def coefficients(dofs=("Surge", "Pitch"), stiffness=None) -> xr.Dataset:
    """The synthetic set in the coefficient Dataset schema (stored [radiating, influenced])."""
    w = np.linspace(0.05, 12.0, 240)
    dofs = list(dofs)
    c = np.diag([0.0, C55]) if stiffness is None else np.asarray(stiffness, float)
    pair = ("radiating_dof", "influenced_dof")
    rd = ("omega", *pair)
    a = np.stack([added_mass(wi).T for wi in w])
    b = np.stack([damping(wi).T for wi in w])
    return xr.Dataset(
        {"added_mass": (rd, a), "radiation_damping": (rd, b),
         "excitation_force": (("omega", "wave_direction", "influenced_dof"),
                              excitation(w)[:, None, :]),
         "added_mass_inf": (pair, A_INF.T), "hydrostatic_stiffness": (pair, c.T),
         "mass": (pair, mass_matrix().T)},
        coords={"omega": w, "radiating_dof": dofs, "influenced_dof": dofs,
                "wave_direction": [0.0]},
        attrs={"rho": RHO, "g": G, "water_depth": np.inf, "input_hash": "synthetic-2dof"},
    )


def frequency_response(w: float, c: np.ndarray, mass: np.ndarray | None = None) -> np.ndarray:
    """``H(ω) = [−ω²(M + A(ω)) − iωB(ω) + C]⁻¹`` (Capytaine's e^{−iωt} convention)."""
    m = mass_matrix() if mass is None else mass
    return np.linalg.inv(-w**2 * (m + added_mass(w)) - 1j * w * damping(w) + c)


def fit_harmonic(hist: xr.Dataset, w: float, t_from: float) -> np.ndarray:
    """Complex amplitude X per DOF of ``z ≈ Re[X e^{−iωt}] + const`` by least squares over
    whole periods from ``t_from`` on."""
    t = hist.time.values
    period = 2 * np.pi / w
    n_per = np.floor((t[-1] - t_from) / period)
    sel = (t >= t[-1] - n_per * period - 1e-9)
    ts = t[sel]
    basis = np.stack([np.cos(w * ts), np.sin(w * ts), np.ones_like(ts)], axis=1)
    coef = np.linalg.lstsq(basis, hist.z.values[sel], rcond=None)[0]
    return coef[0] + 1j * coef[1]  # Re[X e^{−iωt}] = Re X cos ωt + Im X sin ωt


@pytest.fixture(scope="module")
def sp_coeffs() -> xr.Dataset:
    return coefficients()


@pytest.fixture(scope="module")
def sp_ss(sp_coeffs):
    return cummins.build_system(sp_coeffs, dofs=["Surge", "Pitch"],
                                irf=kernel(["Surge", "Pitch"])).ss


# ------------------------------------------------------------------------- Done means
@pytest.mark.parametrize("w", [0.8, 1.3, 2.2, 3.5])
def test_surge_pitch_regular_waves_equal_frequency_domain_response(sp_coeffs, sp_ss, w):
    assert mass_matrix()[0, 1] != 0  # surge and pitch couple through the mass matrix
    amp = 0.05
    h = cummins.simulate(sp_coeffs, dofs=["Surge", "Pitch"], duration=90.0, dt=0.01,
                         wave=Regular(2 * np.pi / w, 2 * amp), ramp=10.0, radiation_ss=sp_ss)
    x_td = fit_harmonic(h, w, 45.0)
    x_fd = amp * frequency_response(w, np.diag([0.0, C55])) @ excitation(w)
    for i in range(2):  # amplitude within 0.5 % and phase within 0.005 rad, per DOF
        assert abs(x_td[i] - x_fd[i]) <= 0.005 * abs(x_fd[i]), (w, i, x_td, x_fd)
    np.testing.assert_allclose(h.F_tot.values, h.zddot.values @ mass_matrix().T, atol=1e-8)


def test_prescribed_force_from_samples_equals_the_direct_array_and_the_response(sp_coeffs,
                                                                              sp_ss):
    dofs, w, dt = ["Surge", "Pitch"], 1.6, 0.01
    f0 = np.array([300.0, -120.0])  # N, N m
    ts = np.arange(0.0, 70.0 + dt / 2, dt)
    samples = np.cos(w * ts)[:, None] * f0
    h = cummins.simulate(sp_coeffs, dofs=dofs, duration=70.0, dt=dt, radiation_ss=sp_ss,
                         forces=[PrescribedForce.from_series(ts, samples)])
    np.testing.assert_allclose(h.F_ext.values, samples, atol=1e-12)
    # the same force handed to the linear solver as an array on the grid
    sys = cummins.build_system(sp_coeffs, dofs=dofs, radiation_ss=sp_ss)
    z = solve_linear(sys, samples, np.zeros(2), np.zeros(2), dt).z
    np.testing.assert_allclose(h.z.values, z, rtol=0, atol=1e-14 * np.abs(z).max())
    # and the steady state is the frequency-domain response to F0 cos ωt = Re[F0 e^{−iωt}]
    x_fd = frequency_response(w, np.diag([0.0, C55])) @ f0
    x_td = fit_harmonic(h, w, 40.0)
    assert np.all(np.abs(x_td - x_fd) <= 0.005 * np.abs(x_fd))


def test_constant_force_shifts_the_static_equilibrium_by_inverse_stiffness():
    dofs = ["Heave", "Pitch"]
    c = np.array([[7700.0, 350.0], [350.0, C55]])  # heave–pitch coupled (asymmetric waterplane)
    co = coefficients(dofs, stiffness=c)
    f = np.array([150.0, 40.0])  # N, N m
    h = cummins.simulate(co, dofs=dofs, duration=60.0, dt=0.01, forces=[ConstantForce(f)],
                         irf=kernel(dofs))
    np.testing.assert_allclose(h.z.values[-1], np.linalg.solve(c, f), rtol=1e-4)
    np.testing.assert_allclose(h.F_hs.values[-1], -f, rtol=1e-4)


def test_units_and_matrices_per_dof(sp_coeffs, sp_ss):
    h = cummins.simulate(sp_coeffs, dofs=["Surge", "Pitch"], duration=1.0, dt=0.01,
                         z0=[0.01, 0.02], radiation_ss=sp_ss)
    assert json.loads(h.z.attrs["units_per_dof"]) == ["m", "rad"]
    assert json.loads(h.zdot.attrs["units_per_dof"]) == ["m/s", "rad/s"]
    assert json.loads(h.zddot.attrs["units_per_dof"]) == ["m/s^2", "rad/s^2"]
    for name in cummins.FORCES:
        assert json.loads(h[name].attrs["units_per_dof"]) == ["N", "N m"]
        assert h[name].attrs["units"] == "N, N m"
    assert h.z.attrs["units"] == "m, rad"
    # force-equation orientation M[i influenced, j radiating], as hydro.coefficients returns
    for name, ref in (("mass", mass_matrix()), ("added_mass_inf", A_INF),
                      ("hydrostatic_stiffness", np.diag([0.0, C55]))):
        assert h[name].dims == ("dof", "dof_j")
        np.testing.assert_array_equal(h[name].values, ref)
    assert json.loads(h["mass"].attrs["units_per_pair"]) == [["kg", "kg m"], ["kg m", "kg m^2"]]
    assert json.loads(h["hydrostatic_stiffness"].attrs["units_per_pair"]) == [
        ["N/m", "N/rad"], ["N m/m", "N m/rad"]]
    batch = cummins.simulate_batch(sp_coeffs, [{"z0": [0.01, 0.0]}], dofs=["Surge", "Pitch"],
                                   duration=1.0, dt=0.01, radiation_ss=sp_ss)
    assert json.loads(batch.F_tot.attrs["units_per_dof"]) == ["N", "N m"]
    np.testing.assert_array_equal(batch["added_mass_inf"].values, A_INF)


# ------------------------------------------------------------------------- exact hydrostatics
class _Buoy:
    """A test body: exact heave restoring F = −k z − k3 z³ (a flaring hull), linear pitch."""

    exact_restoring_dofs = ("Heave",)

    def __init__(self, k: float, k3: float, c: np.ndarray) -> None:
        self.k, self.k3, self.c = k, k3, c

    def restoring_force(self, q, dofs):
        assert list(dofs) == ["Heave"]
        q = np.asarray(q, dtype=float)
        return -self.k * q - self.k3 * q**3

    def hydrostatic_stiffness(self, dofs):
        return self.c


def test_heave_pitch_with_exact_heave_restoring_conserves_energy():
    dofs = ["Heave", "Pitch"]
    c = np.array([[7700.0, 350.0], [350.0, C55]])
    body = _Buoy(c[0, 0], 4.0e6, c)
    co = coefficients(dofs, stiffness=c)
    h = cummins.simulate(co, dofs=dofs, body=body, nonlinear_hydrostatics=True,
                         duration=6.0, dt=0.002, z0=[0.08, 0.05], radiation="none")
    z, v = h.z.values, h.zdot.values
    # exact heave force plus the linear coupling; pitch stays linear
    np.testing.assert_allclose(h.F_hs.values[:, 0],
                               -c[0, 0] * z[:, 0] - 4.0e6 * z[:, 0] ** 3 - c[0, 1] * z[:, 1],
                               rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(h.F_hs.values[:, 1], -z @ c[1], rtol=1e-12, atol=1e-9)
    # conservative force field, no radiation: kinetic + potential energy is constant
    meff = mass_matrix() + A_INF
    pot = 0.5 * np.einsum("ti,ij,tj->t", z, c, z) + 1.0e6 * z[:, 0] ** 4
    e = 0.5 * np.einsum("ti,ij,tj->t", v, meff, v) + pot
    assert np.ptp(e) < 1e-7 * e[0]
    # the cubic term matters: the linear run drifts away from it
    lin = cummins.simulate(co, dofs=dofs, duration=6.0, dt=0.002, z0=[0.08, 0.05],
                           radiation="none")
    assert np.max(np.abs(lin.z.values[:, 0] - z[:, 0])) > 0.01


def test_sphere_heave_pitch_nonlinear_is_exact_heave_and_linear_pitch():
    from hybridwsi.bodies import FloatingSphere

    sphere = FloatingSphere(radius=0.15, rho=998.2, g=9.81)  # in equilibrium at z = 0
    dofs = ["Heave", "Pitch"]
    c = sphere.hydrostatic_stiffness(dofs)
    co = coefficients(dofs, stiffness=c)
    co["mass"] = (("radiating_dof", "influenced_dof"), sphere.mass_matrix(dofs).T)
    co["added_mass_inf"] = (("radiating_dof", "influenced_dof"), np.diag([3.5, 0.01]))
    comp = ExactHydrostatic(sphere, dofs, c)
    assert comp.exact == ["Heave"] and comp.describe() == "exact_hydrostatic(exact Heave; linear Pitch)"
    h = cummins.simulate(co, dofs=dofs, body=sphere, nonlinear_hydrostatics=True,
                         duration=1.0, dt=0.002, z0=[0.04, 0.1], radiation="none")
    np.testing.assert_allclose(h.F_hs.values[:, 0], sphere.buoyancy_force(h.z.values[:, 0]),
                               rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(h.F_hs.values[:, 1], -c[1, 1] * h.z.values[:, 1], rtol=1e-12)
    # a sphere about its centre has no pitch stiffness (ρg(πR⁴/4 + V z_B) = 0): it stays tilted
    assert abs(c[1, 1]) < 1e-12 * c[0, 0]
    np.testing.assert_allclose(h.z.values[:, 1], 0.1, atol=1e-12)
    # decoupled (diagonal M, A∞, C): heave is the 1-DOF nonlinear run on the DOF subset
    heave = cummins.simulate(co, dofs=["Heave"], body=sphere, nonlinear_hydrostatics=True,
                             duration=1.0, dt=0.002, z0=0.04, radiation="none")
    np.testing.assert_allclose(h.z.values[:, 0], heave.z.values[:, 0], rtol=0, atol=1e-15)
    assert np.ptp(heave.z.values) > 0.07  # it did oscillate
    # the sphere's exact DOFs are Surge, Sway, Heave and Yaw (bodies.Body.exact_restoring_dofs)
    with pytest.raises(InputError, match="no exact restoring"):
        cummins.simulate(coefficients(), dofs=["Pitch"], body=sphere,
                         nonlinear_hydrostatics=True, duration=1.0, dt=0.01, radiation="none")


# ------------------------------------------------------------------------- components alone
def test_time_only_components_in_the_diagnostic_view(sp_coeffs, sp_ss):
    h = cummins.simulate(sp_coeffs, dofs=["Surge", "Pitch"], duration=2.0, dt=0.01,
                         wave=Regular(3.0, 0.1), ramp=1.0, radiation_ss=sp_ss)
    exc = PrescribedForce("F_exc")
    assert exc.time_only and exc.variable == "F_exc" and exc.describe() == "prescribed(F_exc)"
    np.testing.assert_array_equal(exc.force(h), h.F_exc.values)
    for comp in (exc, ConstantForce([1.0, 2.0])):
        assert all(not np.any(m) for m in comp.linear_coefficients(2))
    np.testing.assert_array_equal(ConstantForce([1.0, 2.0]).force(h)[-1], [1.0, 2.0])
    series = PrescribedForce.from_series([0.0, 4.0], [[0.0, 0.0], [4.0, 8.0]])
    np.testing.assert_allclose(series.force(h), np.outer(h.time.values, [1.0, 2.0]))
    np.testing.assert_allclose(series.ode_force(1.5, np.zeros(2), np.zeros(2), np.zeros(0)),
                               [1.5, 3.0])
    with pytest.raises(InputError, match="covers"):
        series.time_force(np.array([0.0, 5.0]))
    with pytest.raises(InputError, match="DOF"):
        PrescribedForce.from_series([0.0, 4.0], [0.0, 1.0]).time_force(np.array([1.0]), 2)
