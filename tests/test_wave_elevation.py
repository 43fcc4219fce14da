"""A recorded wave elevation as the wave of a run (issue 28 item 2): the excitation force from
the BEM transfer function over the record's Fourier components (waves.ElevationRecord),
against the regular wave it records and against the frequency-domain response."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from hybridwsi import cummins, waves
from hybridwsi.casemodel import case_coefficients, elevation_wave
from hybridwsi.cases import load_case
from hybridwsi.cli import main
from hybridwsi.errors import InputError
from hybridwsi.files import read_netcdf, to_netcdf
from hybridwsi.hydro import coefficients as cf
from hybridwsi.hydro.bem import paper_coefficients


@pytest.fixture(scope="module")
def sphere() -> xr.Dataset:
    return paper_coefficients()


def _record(wave: waves.Wave, length: float, dt: float, coeffs: xr.Dataset
            ) -> tuple[np.ndarray, waves.ElevationRecord]:
    t = np.arange(0.0, length + dt / 2, dt)
    return t, waves.ElevationRecord(t, wave.elevation(t),
                                    omega_max=float(coeffs["omega"].max()))


def test_record_of_a_regular_wave_gives_its_force_away_from_the_ends(sphere):
    """The record is the regular wave cut to [0, 40.3 s] (not a whole number of periods: its
    mean is not zero): inside it, away from either end by more than the sphere's short
    excitation response, the convolution gives the regular wave's force (measured 1.3e-5 of
    its amplitude from 3 s to 37 s)."""
    reg = waves.Regular(period=1.0, height=0.05)
    t, rec = _record(reg, 40.3, 0.01, sphere)
    assert rec.variance_outside < 2e-3  # the cut's leakage above 40 rad/s
    f_rec, eta_rec = waves.excitation_force(rec, sphere, t, with_elevation=True)
    f_reg = waves.excitation_force(reg, sphere, t)
    inner = (t >= 3.0) & (t <= 37.0)
    scale = np.abs(f_reg).max()
    assert np.abs(f_rec - f_reg)[inner].max() < 1e-4 * scale
    # η itself loses the cut's leakage above 40 rad/s (Gibbs ringing, 0.25 % of a)
    assert np.abs(eta_rec - reg.elevation(t))[inner].max() < 5e-3 * 0.025
    # the calm after the record: the force in its last second feels it (non-causal response)
    assert np.abs(f_rec - f_reg)[t >= 39.8].max() > 1e-2 * scale


def test_record_on_the_spar_matches_the_regular_force_in_every_dof():
    """OC3-Hywind (BEM from 0.025 rad/s: the record's longer waves and its mean take the
    long-wave limit C[:, Heave]): from 50 s after the start to 100 s before the end within
    2e-4 in surge, heave and pitch (measured 1.7e-4); the spar's anticipating response makes
    the last ~50 s feel the calm after the record (3e-3 of the heave force)."""
    coeffs = case_coefficients(load_case("oc3_hywind"))
    dofs = ["Surge", "Heave", "Pitch"]
    assert waves.long_wave_limit(coeffs, dofs)[1] == pytest.approx(
        cf.matrix(coeffs, "hydrostatic_stiffness", ["Heave"])[0, 0])
    reg = waves.Regular(period=10.0, height=2.0)
    t, rec = _record(reg, 903.0, 0.1, coeffs)
    f_rec = waves.excitation_force(rec, coeffs, t, dofs)
    f_reg = waves.excitation_force(reg, coeffs, t, dofs)
    err = np.abs(f_rec - f_reg) / np.abs(f_reg).max(axis=0)
    assert np.all(err[(t >= 50.0) & (t <= 803.0)].max(axis=0) < 2e-4), err.max(axis=0)
    assert err[t >= 883.0, 1].max() > 0.1


def test_response_to_a_recorded_regular_wave_is_the_frequency_domain_one(sphere):
    """Heave of the sphere driven by the record: steady amplitude and phase equal
    X = F_e a / (C - ω² (m + A(ω)) - iω B(ω)) (Capytaine's e^{-iωt}) within 0.05 %
    (measured 1.6e-4 at dt = 0.01 s; the time integration's error is O(dt²): 1.1e-3 at 0.02)."""
    period, height, dt = 1.0, 0.05, 0.01
    w = 2.0 * np.pi / period
    t, rec = _record(waves.Regular(period=period, height=height), 20.0, dt, sphere)
    hist = cummins.simulate(sphere, duration=16.0, dt=dt, wave=rec, ramp=3.0)
    m = cf.matrix(sphere, "mass", ["Heave"])[0, 0]
    a = cf.at_frequency(sphere, "added_mass", w, ["Heave"])[0, 0]
    b = cf.at_frequency(sphere, "radiation_damping", w, ["Heave"])[0, 0]
    c = cf.matrix(sphere, "hydrostatic_stiffness", ["Heave"])[0, 0]
    fe = sphere["excitation_force"].sel(influenced_dof="Heave").squeeze().values
    f_hat = (np.interp(w, sphere["omega"].values, fe.real)
             + 1j * np.interp(w, sphere["omega"].values, fe.imag))
    x_fd = f_hat * height / 2 / (c - w**2 * (m + a) - 1j * w * b)
    tt = hist["time"].values
    win = tt >= 10.0  # six periods, the start transient gone
    basis = np.column_stack([np.cos(w * tt[win]), np.sin(w * tt[win]), np.ones(win.sum())])
    coef, *_ = np.linalg.lstsq(basis, hist["z"].values[win, 0], rcond=None)
    x_td = coef[0] + 1j * coef[1]  # z = Re(X e^{-iωt}) = Re X cos ωt + Im X sin ωt
    assert abs(x_td - x_fd) < 5e-4 * abs(x_fd), (x_td, x_fd)


def test_simulate_wave_elevation_equals_regular_after_the_ramp(sphere, tmp_path):
    """The command line: --wave-elevation of a CSV holding the regular wave's elevation
    (in mm, longer than the run) gives --regular's force and motion after the ramp."""
    t = np.arange(0.0, 16.0 + 1e-9, 0.02)
    eta = waves.Regular(period=1.0, height=0.05).elevation(t)
    csv = tmp_path / "probe.csv"
    np.savetxt(csv, np.column_stack([t, 1e3 * eta]), delimiter=",", fmt="%.17g",
               header="time [s],eta [mm]", comments="")
    common = ["simulate", "--coeffs", str(tmp_path / "sphere.nc"), "--duration", "12",
              "--dt", "0.02", "--ramp", "3", "--quiet"]
    to_netcdf(sphere, tmp_path / "sphere.nc")
    assert main([*common, "--regular", "1.0", "0.05", "--out", str(tmp_path / "r.nc")]) == 0
    assert main([*common, "--wave-elevation", str(csv), "--out", str(tmp_path / "e.nc")]) == 0
    r, e = read_netcdf(tmp_path / "r.nc"), read_netcdf(tmp_path / "e.nc")
    after = r["time"].values >= 3.0
    for name, tol in (("F_exc", 1e-4), ("z", 1e-3)):
        a, b = r[name].values[after], e[name].values[after]
        assert np.abs(a - b).max() < tol * np.abs(a).max(), name
    wave = __import__("json").loads(e.attrs["inputs"])["wave"]
    assert wave["type"] == "elevation_record" and wave["source"] == "probe.csv:eta"
    # the record's own file (a history with eta) is a record too: NetCDF in, same force
    assert main([*common, "--wave-elevation", str(tmp_path / "r.nc"), "--out",
                 str(tmp_path / "e2.nc")]) == 0
    e2 = read_netcdf(tmp_path / "e2.nc")
    assert e2.sizes["time"] == e.sizes["time"]


def test_bad_records_are_refused(sphere, tmp_path, capsys):
    t = np.arange(0.0, 20.0, 0.01)
    noise = np.random.default_rng(0).normal(size=t.size)  # white: most of it above 40 rad/s
    cases = {
        "noise.csv": ("time [s],eta [m]", np.column_stack([t, noise]), "variance lies above"),
        "irregular.csv": ("time [s],eta [m]", np.column_stack([t ** 1.01, np.sin(t)]),
                          "not uniformly sampled"),
        "force.csv": ("time [s],eta [N]", np.column_stack([t, np.sin(t)]), "not a length"),
        "short.csv": ("time [s],eta [m]", np.column_stack([t[:5], t[:5]]), "at least 8"),
    }
    for name, (header, data, words) in cases.items():
        np.savetxt(tmp_path / name, data, delimiter=",", header=header, comments="")
        with pytest.raises(InputError, match=words):
            elevation_wave(sphere, tmp_path / name)
    to_netcdf(sphere, tmp_path / "c.nc")
    np.savetxt(tmp_path / "ok.csv", np.column_stack([t, 0.01 * np.sin(6 * t)]), delimiter=",",
               header="time [s],wave [m]", comments="")
    for extra, words in ((["--wave-elevation", str(tmp_path / "ok.csv")], "'eta' not found"),
                         (["--wave-elevation", str(tmp_path / "ok.csv"), "--eta", "wave",
                           "--duration", "30"], "longer than the wave-elevation record"),
                         (["--eta", "wave"], "--eta names the column")):
        rc = main(["simulate", "--coeffs", str(tmp_path / "c.nc"), *extra, "--out",
                   str(tmp_path / "h.nc")])
        err = capsys.readouterr().err
        assert rc == 2 and err.count("\n") == 1 and words in err, err
    assert not (tmp_path / "h.nc").exists()
