"""Cummins solver: analytic decay, frequency-domain RAOs, force bookkeeping, batches, errors."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
import scipy.integrate
import xarray as xr

import synthetic_hydro as sh
from hybridwsi import cummins
from hybridwsi.errors import InputError
from hybridwsi.forces import ConstantForce, ExactHydrostatic, LinearDamping, PrescribedForce
from hybridwsi.history import read_netcdf, to_netcdf, validate
from hybridwsi.waves import JONSWAP, Regular


@pytest.fixture(scope="module")
def co() -> xr.Dataset:
    return sh.coefficients()


@pytest.fixture(scope="module")
def kern() -> xr.DataArray:
    return sh.irf(t_max=8.0)


def _amplitude(hist: xr.Dataset, omega: float, t_from: float) -> float:
    """Steady-state amplitude by least squares on cos/sin at ω (no peak-sampling error)."""
    t = hist.time.values
    sel = t >= t_from
    basis = np.stack([np.cos(omega * t[sel]), np.sin(omega * t[sel])], axis=1)
    c = np.linalg.lstsq(basis, hist.z.values[sel, 0], rcond=None)[0]
    return float(np.hypot(*c))


def _rao(a: float, b: float, fe: complex, omega: float, m: float, c: float) -> float:
    return abs(fe) / abs(c - omega**2 * (m + a) + 1j * omega * b)


def _rel_rms(x: np.ndarray, ref: np.ndarray) -> float:
    return float(np.linalg.norm(x - ref) / np.linalg.norm(ref))


def test_statespace_and_convolution_agree_in_decay(co, kern):
    kw = dict(duration=8.0, dt=0.005, z0=0.03, irf=kern)
    ss = cummins.simulate(co, **kw)
    cv = cummins.simulate(co, radiation="convolution", **kw)
    assert _rel_rms(ss.z.values, cv.z.values) < 0.005
    assert _rel_rms(ss.F_rad_mem.values, cv.F_rad_mem.values) < 0.01


@pytest.mark.parametrize("radiation", ["statespace", "convolution"])
def test_regular_wave_amplitude_equals_frequency_domain_rao(co, kern, radiation):
    i = 80  # ω = 8.1 rad/s, near resonance (ω_n ≈ 8.1): the most sensitive place
    w = float(co.omega[i])
    h = cummins.simulate(co, duration=16.0, dt=0.005, wave=Regular(2 * np.pi / w, 0.05),
                         ramp=3.0, irf=kern, radiation=radiation)
    rao = _rao(sh.added_mass(w), sh.damping(w), sh.excitation(w), w, sh.M, sh.C)
    assert _amplitude(h, w, 9.0) == pytest.approx(0.025 * rao, rel=0.005)


def test_decay_without_memory_is_the_analytic_cosine(co):
    h = cummins.simulate(co, duration=5.0, dt=0.01, z0=0.02, zdot0=0.1, radiation="none")
    wn = np.sqrt(sh.C / (sh.M + sh.A_INF))
    t = h.time.values
    exact = 0.02 * np.cos(wn * t) + 0.1 / wn * np.sin(wn * t)
    np.testing.assert_allclose(h.z.values[:, 0], exact, atol=1e-10)  # exact discretisation
    np.testing.assert_allclose(h.F_rad_mem.values, 0.0)


def test_newmark_convolution_is_second_order_for_zero_kernel(co):
    wn = np.sqrt(sh.C / (sh.M + sh.A_INF))
    zero = sh.irf(t_max=1.0) * 0.0
    errs = []
    for dt in (0.01, 0.005):
        h = cummins.simulate(co, duration=3.0, dt=dt, z0=0.02, irf=zero, radiation="convolution")
        errs.append(np.max(np.abs(h.z.values[:, 0] - 0.02 * np.cos(wn * h.time.values))))
    # Newmark's period error (ω dt)²/12 gives a phase lag of ~0.013 rad after 3 s at dt = 0.01
    assert errs[0] < 0.015 * 0.02
    assert errs[0] / errs[1] == pytest.approx(4.0, rel=0.1)


@pytest.mark.parametrize("radiation", ["statespace", "convolution"])
def test_total_force_is_mass_times_acceleration(co, kern, radiation):
    ts = np.linspace(0.0, 4.0, 4001)
    h = cummins.simulate(co, duration=4.0, dt=0.01, wave=JONSWAP(0.05, 0.8, seed=3),
                         forces=[PrescribedForce.from_series(ts, 2.0 * np.sin(3 * ts))],
                         z0=0.01, irf=kern, radiation=radiation, ramp=1.0)
    validate(h)
    m = float(h.mass.values[0, 0])
    np.testing.assert_allclose(h.F_tot.values, m * h.zddot.values, atol=1e-12 * 50)
    parts = sum(h[k].values for k in ("F_hs", "F_rad_inf", "F_rad_mem", "F_exc", "F_ext"))
    np.testing.assert_allclose(h.F_tot.values, parts, atol=1e-12)
    np.testing.assert_allclose(h.F_hs.values, -sh.C * h.z.values)
    np.testing.assert_allclose(h.F_rad_inf.values, -sh.A_INF * h.zddot.values)
    assert "eta" in h and h.eta.dims == ("time", "probe")
    inputs = json.loads(h.attrs["inputs"])
    assert inputs["coeffs_hash"] == "synthetic-v1" and inputs["wave"]["type"] == "jonswap"
    assert inputs["dt"] == 0.01 and inputs["radiation"] == radiation
    assert inputs["forces"][0].startswith("prescribed(external: 4001 samples")
    np.testing.assert_allclose(h.F_ext.values[:, 0], 2.0 * np.sin(3 * h.time.values), atol=1e-4)


def test_constant_force_gives_static_offset_and_series_forms_agree(co, kern):
    f0 = 10.0
    h = cummins.simulate(co, duration=20.0, dt=0.01, forces=[ConstantForce(f0)], irf=kern)
    assert h.z.values[-1, 0] == pytest.approx(f0 / sh.C, rel=1e-4)  # static: C z = F
    t = h.time.values
    series = cummins.simulate(co, duration=20.0, dt=0.01, irf=kern, forces=[
        PrescribedForce.from_series(np.array([0.0, 20.0]), np.array([f0, f0]))])
    arr = cummins.simulate(co, duration=20.0, dt=0.01, irf=kern,
                           forces=[PrescribedForce.from_series(t, np.full(t.size, f0))])
    np.testing.assert_allclose(series.z.values, h.z.values, atol=1e-14)
    np.testing.assert_allclose(arr.F_ext.values, f0)


def test_state_dependent_force_is_a_damped_oscillator(co):
    # F_ext = −b ż with K ≡ 0: z = e^{−ζωn t}(z0 cos ωd t + ζωn z0/ωd sin ωd t), RK4 accuracy
    b, z0 = 5.0, 0.02
    mt = sh.M + sh.A_INF
    h = cummins.simulate(co, duration=3.0, dt=0.005, z0=z0, radiation="none",
                         forces=[LinearDamping(b)])
    wn = np.sqrt(sh.C / mt)
    zeta = b / (2 * mt * wn)
    wd = wn * np.sqrt(1 - zeta**2)
    t = h.time.values
    exact = np.exp(-zeta * wn * t) * (z0 * np.cos(wd * t) + zeta * wn * z0 / wd * np.sin(wd * t))
    np.testing.assert_allclose(h.z.values[:, 0], exact, atol=1e-8)
    np.testing.assert_allclose(h.F_ext.values, -b * h.zdot.values)
    np.testing.assert_allclose(h.F_tot.values, sh.M * h.zddot.values, atol=1e-10)


def test_batch_equals_individual_runs(co, kern):
    cases = [{"z0": 0.02}, {"wave": Regular(0.8, 0.04)},
             {"wave": {"type": "jonswap", "hs": 0.03, "tp": 0.9, "seed": 1},
              "forces": [ConstantForce(1.5)]}]
    kw = dict(duration=3.0, dt=0.01, irf=kern)
    batch = cummins.simulate_batch(co, cases, **kw)
    assert batch.z.dims == ("case", "time", "dof") and batch.sizes["case"] == 3
    for c, case in enumerate(cases):
        single = cummins.simulate(co, **case, **kw)
        for name in ("z", "zdot", "zddot", "F_tot", "F_rad_mem", "F_exc"):
            np.testing.assert_allclose(batch[name].values[c], single[name].values, atol=1e-10)
    params = xr.Dataset({"z0": ("case", [0.01, 0.0]), "period": ("case", [0.7, 0.9]),
                         "height": ("case", [0.0 + 1e-3, 0.02])})
    from_ds = cummins.simulate_batch(co, params, **kw)
    single = cummins.simulate(co, z0=0.0, wave=Regular(0.9, 0.02), **kw)
    np.testing.assert_allclose(from_ds.z.values[1], single.z.values, atol=1e-10)


def test_netcdf_round_trip_keeps_inputs(co, kern, tmp_path):
    h = cummins.simulate(co, duration=1.0, dt=0.01, wave=Regular(0.75, 0.05), irf=kern)
    back = read_netcdf(to_netcdf(h, tmp_path / "h.nc"))
    np.testing.assert_allclose(back.z.values, h.z.values)
    assert json.loads(back.attrs["inputs"]) == json.loads(h.attrs["inputs"])
    assert json.loads(back.attrs["radiation_ss"])["order"] >= 2


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"dt": 0.0}, "dt must be > 0"),
        ({"dt": -0.1}, "dt must be > 0"),
        ({"duration": 0.001}, "duration"),
        ({"radiation": "fft"}, "radiation must be"),
        ({"nonlinear_hydrostatics": True}, "body"),
        (lambda: {"forces": [PrescribedForce.from_series(np.arange(2.0), np.ones(7))]},
         "samples"),
        ({"forces": [PrescribedForce.from_series(np.array([0.0, 0.5]), np.ones(2))]}, "covers"),
        ({"forces": [lambda t: 1.0]}, "KnownComponent"),
        ({"forces": [ConstantForce([1.0, 2.0])]}, "one value per DOF"),
        ({"forces": [PrescribedForce("F_exc")]}, "read it from the history"),
        ({"forces": [LinearDamping(1.0)], "radiation": "convolution"}, "statespace"),
        ({"z0": float("nan")}, "z0"),
        ({"dofs": ["Pitch"]}, "no DOF"),
        ({"mass": -20.0}, "positive definite"),
    ],
)
def test_bad_input(co, kern, kwargs, match):
    base = dict(duration=1.0, dt=0.01, irf=kern)
    with pytest.raises(InputError, match=match):
        base.update(kwargs() if callable(kwargs) else kwargs)  # a bad component fails early
        cummins.simulate(co, **base)


def test_bad_coefficients(kern):
    nan = sh.coefficients()
    nan["hydrostatic_stiffness"][:] = np.nan
    with pytest.raises(InputError, match="NaN"):
        cummins.simulate(nan, duration=1.0, dt=0.01, irf=kern)
    no_mass = sh.coefficients().drop_vars("mass")
    with pytest.raises(InputError, match="mass"):
        cummins.simulate(no_mass, duration=1.0, dt=0.01, irf=kern)
    no_exc = sh.coefficients().drop_vars("excitation_force")
    with pytest.raises(InputError, match="excitation_force"):
        cummins.simulate(no_exc, duration=1.0, dt=0.01, irf=kern, wave=Regular(1.0, 0.01))


# ---------------------------------------------------------------- nonlinear hydrostatics
@pytest.fixture(scope="module")
def sphere():
    from hybridwsi.bodies import FloatingSphere

    # mass = displaced mass: exactly in equilibrium at z = 0 (the paper's 7.06 kg is 4 g heavy)
    return FloatingSphere(radius=0.15, rho=998.2, g=9.81)


def _sphere_coeffs(sphere) -> xr.Dataset:
    co = sh.coefficients()
    co["hydrostatic_stiffness"][:] = sphere.rho * sphere.g * np.pi * sphere.radius**2
    co["mass"][:] = sphere.mass
    return co


def test_nonlinear_hydrostatics_small_drop_matches_linear(sphere, kern):
    co = _sphere_coeffs(sphere)
    kw = dict(duration=3.0, dt=0.005, z0=0.0005, irf=kern)
    lin = cummins.simulate(co, **kw)
    nl = cummins.simulate(co, nonlinear_hydrostatics=True, body=sphere, **kw)
    assert _rel_rms(nl.z.values, lin.z.values) < 0.01


def test_nonlinear_hydrostatic_force_is_the_spherical_cap_and_conserves_energy(sphere):
    co = _sphere_coeffs(sphere)
    r, rho, g, m = sphere.radius, sphere.rho, sphere.g, sphere.mass
    h = cummins.simulate(co, duration=2.0, dt=0.002, z0=0.3 * r, radiation="none",
                         nonlinear_hydrostatics=True, body=sphere)
    z = h.z.values[:, 0]
    depth = r - z  # submerged cap height of a half-submerged sphere raised by z
    cap = np.pi * depth**2 * (3 * r - depth) / 3
    np.testing.assert_allclose(h.F_hs.values[:, 0], rho * g * cap - m * g, rtol=1e-10, atol=1e-9)
    # no radiation: kinetic + hydrostatic potential energy is conserved (RK4 drift only)
    pot = np.array([-scipy.integrate.quad(sphere.buoyancy_force, 0.0, zi)[0] for zi in z[::50]])
    kin = 0.5 * (m + sh.A_INF) * h.zdot.values[::50, 0] ** 2
    e = kin + pot
    assert np.ptp(e) < 1e-6 * e[0]
    # the spring softens (F = −C (z − z³/3R²)): period from the energy integral
    # T = 4 ∫_0^{z0} dz / sqrt(2 (U(z0) − U(z)) / M), with z = z0 sin θ to remove the singularity
    z0, mt = 0.3 * r, m + sh.A_INF
    u = lambda x: -scipy.integrate.quad(sphere.buoyancy_force, 0.0, x)[0]  # noqa: E731
    integrand = lambda th: z0 * np.cos(th) / np.sqrt(2 * (u(z0) - u(z0 * np.sin(th))) / mt)  # noqa: E731
    period = 4 * scipy.integrate.quad(integrand, 0, np.pi / 2 - 1e-9)[0]
    t = h.time.values
    cross = [t[i] - z[i] * (t[i + 1] - t[i]) / (z[i + 1] - z[i])
             for i in range(z.size - 1) if z[i] * z[i + 1] < 0]
    assert 2 * (cross[1] - cross[0]) == pytest.approx(period, rel=1e-4)
    assert period > 2 * np.pi * np.sqrt(mt / sphere.hydrostatic_stiffness()[0, 0]) * 1.008


# ---------------------------------------------------------------- real Capytaine coefficients
@pytest.fixture(scope="module")
def bem(sphere):
    from hybridwsi.hydro import bem as bem_mod
    from hybridwsi.hydro.irf import radiation_irf

    with warnings.catch_warnings():  # the coarse mesh warns about the highest frequencies
        warnings.simplefilter("ignore", UserWarning)
        co = bem_mod.compute(sphere, np.geomspace(0.1, 40.0, 60), n_panels=600,
                             use_cache=False, progress=False)
        return co, radiation_irf(co)


def test_bem_decay_statespace_matches_convolution(bem):
    co, k = bem
    kw = dict(duration=8.0, dt=0.005, z0=0.03, irf=k)
    ss = cummins.simulate(co, **kw)
    cv = cummins.simulate(co, radiation="convolution", **kw)
    assert _rel_rms(ss.z.values, cv.z.values) < 0.005
    assert json.loads(ss.attrs["inputs"])["radiation_ss"]["fit_error"]["frequency_bem"] < 0.01


@pytest.mark.parametrize("i", [38, 42])  # ω = 4.7 and 7.1 rad/s
def test_bem_regular_wave_amplitude_equals_rao(bem, i):
    co, k = bem
    w = float(co.omega[i])
    h = cummins.simulate(co, duration=16.0, dt=0.005, wave=Regular(2 * np.pi / w, 0.05),
                         ramp=3.0, irf=k)
    rao = _rao(co.added_mass.values[i, 0, 0], co.radiation_damping.values[i, 0, 0],
               co.excitation_force.values[i, 0, 0], w, co.mass.values[0, 0], co.hydrostatic_stiffness.values[0, 0])
    assert _amplitude(h, w, 9.0) == pytest.approx(0.025 * rao, rel=0.005)


# ---------------------------------------------------------------- command line
def test_cli_simulate_writes_a_history(co, tmp_path, capsys):
    from hybridwsi.cli import main

    coeffs = to_netcdf(co, tmp_path / "coeffs.nc")
    csv = tmp_path / "force.csv"
    csv.write_text("time,force\n0,0\n5,4\n")
    out = tmp_path / "hist.nc"
    rc = main(["simulate", "--coeffs", str(coeffs), "--regular", "0.8", "0.03",
               "--external-force", str(csv), "--duration", "2", "--dt", "0.01", "--out", str(out),
               "--quiet"])
    assert rc == 0
    h = read_netcdf(out)
    validate(h)
    np.testing.assert_allclose(h.F_ext.values[:, 0], 0.8 * h.time.values, atol=1e-12)
    np.testing.assert_allclose(h.F_tot.values, sh.M * h.zddot.values, atol=1e-10)
    assert json.loads(h.attrs["inputs"])["wave"]["period"] == 0.8
    rc = main(["simulate", "--coeffs", str(coeffs), "--dt", "-1", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2 and "--dt" in err and "must be positive" in err


def test_exact_hydrostatic_is_not_a_force_to_add(co, kern, sphere):
    with pytest.raises(InputError, match="nonlinear_hydrostatics"):
        cummins.simulate(co, duration=1.0, dt=0.01, irf=kern,
                         forces=[ExactHydrostatic(sphere, ["Heave"])])


def test_cli_force_file_is_read_by_column_name(co, tmp_path):
    from hybridwsi.cli import main

    coeffs = to_netcdf(co, tmp_path / "coeffs.nc")
    csv = tmp_path / "force.csv"
    # the force is not the second column, and its unit is kN
    csv.write_text("# made by hand\ntime [s];eta [m];F_ext [kN]\n0;9;0\n2;9;0.004\n")
    out = tmp_path / "hist.nc"
    rc = main(["simulate", "--coeffs", str(coeffs), "--external-force", str(csv),
               "--duration", "2", "--dt", "0.01", "--out", str(out), "--quiet"])
    assert rc == 0
    np.testing.assert_allclose(read_netcdf(out).F_ext.values[:, 0],
                               2.0 * read_netcdf(out).time.values, atol=1e-12)
    csv.write_text("time,eta,moment\n0,1,2\n2,1,2\n")
    assert main(["simulate", "--coeffs", str(coeffs), "--external-force", str(csv),
                 "--duration", "2", "--out", str(out), "--quiet"]) == 2


def test_radiation_model_is_fitted_once_per_coefficient_content(co, monkeypatch, tmp_path):
    """Repeated simulations of one body reuse the kernel's state-space fit (same history),
    from memory and, in a new process (memory emptied), from the disk cache; coefficients with
    another B(ω) are fitted anew and give another memory force; a corrupt disk entry is fitted
    again."""
    import hybridwsi.cummins.system as system
    from hybridwsi.hydro import ss_cache

    calls = []
    fit = system.fit_radiation_ss
    monkeypatch.setattr(system, "fit_radiation_ss", lambda *a, **k: calls.append(1) or fit(*a, **k))
    monkeypatch.setattr(ss_cache, "_memory", type(ss_cache._memory)())
    monkeypatch.setenv("HYBRIDWSI_CACHE", str(tmp_path))
    kw = dict(duration=4.0, dt=0.005, z0=0.03)
    first = cummins.simulate(co, **kw)
    n_first = len(calls)
    again = cummins.simulate(co.copy(deep=True), **kw)
    assert n_first >= 1 and len(calls) == n_first
    np.testing.assert_array_equal(first.z.values, again.z.values)
    ss_cache._memory.clear()  # as a new process: the disk entry
    (entry,) = (tmp_path / "radiation_ss").glob("*.npz")
    from_disk = cummins.simulate(co, **kw)
    assert len(calls) == n_first
    np.testing.assert_array_equal(first.z.values, from_disk.z.values)
    ss_cache._memory.clear()
    entry.write_bytes(entry.read_bytes()[:100])  # truncated
    cummins.simulate(co, **kw)
    assert len(calls) == 2 * n_first
    stiffer = co.assign(radiation_damping=2.0 * co["radiation_damping"])
    other = cummins.simulate(stiffer, **kw)
    assert len(calls) > 2 * n_first
    # twice the damping: twice the memory force at the first steps (same motion there)
    f0, f1 = first.F_rad_mem.values[1:20, 0], other.F_rad_mem.values[1:20, 0]
    np.testing.assert_allclose(f1, 2.0 * f0, rtol=0.05)
