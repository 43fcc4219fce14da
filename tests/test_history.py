"""TimeHistory I/O, derivative estimation and resampling (hybridwsi.history).

References are analytic: derivatives of sines/multisines, exact round trips, unit factors.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from hybridwsi import history as h
from hybridwsi.errors import InputError
from hybridwsi.importers import read_history

DATA = Path(__file__).parent / "data"
BAD = DATA / "bad"

T0 = 0.75  # s, the paper's wave period
W0 = 2 * np.pi / T0


def multisine(t: np.ndarray, comps=((0.02, 1.0, 0.0), (0.01, 2.3, 0.4))):
    """z, zdot, zddot of sum a sin(k w0 t + p), analytic."""
    z = sum(a * np.sin(k * W0 * t + p) for a, k, p in comps)
    zd = sum(a * k * W0 * np.cos(k * W0 * t + p) for a, k, p in comps)
    zdd = sum(-a * (k * W0) ** 2 * np.sin(k * W0 * t + p) for a, k, p in comps)
    return z, zd, zdd


def rel_rms(est: np.ndarray, ref: np.ndarray, trim: int = 0) -> float:
    sl = slice(trim, -trim if trim else None)
    return float(np.sqrt(np.mean((est[sl] - ref[sl]) ** 2)) / np.std(ref))


# ------------------------------------------------------------------ derivative estimation


@pytest.mark.parametrize(
    "comps, tol1, tol2",
    [(((0.02, 1.0, 0.0),), 2e-4, 5e-3), (((0.02, 1.0, 0.0), (0.01, 2.3, 0.4)), 5e-4, 1e-2)],
    ids=["sine", "multisine"],
)
def test_savgol_clean_matches_analytic(comps, tol1, tol2):
    t = np.arange(0, 12, 0.005)
    z, zd, zdd = multisine(t, comps)
    est = h.estimate_derivatives(h.make_history(t, z))
    assert rel_rms(est["zdot"].values[:, 0], zd) < tol1
    assert rel_rms(est["zddot"].values[:, 0], zdd) < tol2
    assert est["zddot"].attrs["estimated"].startswith("savgol(window=")
    assert "polyorder=3" in est["zdot"].attrs["estimated"]


def test_savgol_noisy_multisine_and_window_grows_with_noise():
    t = np.arange(0, 12, 0.005)
    z, zd, zdd = multisine(t)
    rng = np.random.default_rng(1)
    noisy = z + 1e-5 * rng.standard_normal(t.size)  # 0.05 % of the amplitude
    est = h.estimate_derivatives(h.make_history(t, noisy))
    assert rel_rms(est["zdot"].values[:, 0], zd) < 5e-3
    assert rel_rms(est["zddot"].values[:, 0], zdd) < 4e-2
    # the automatic window trades truncation against noise: more noise -> longer window
    w_clean = h.savgol_window(z, 0.005, 3, 2)
    w_noisy = h.savgol_window(z + 1e-4 * rng.standard_normal(t.size), 0.005, 3, 2)
    assert w_noisy > w_clean
    # and the noisy choice beats a naive short window on the same data
    naive = h.estimate_derivatives(h.make_history(t, noisy), window=5)
    assert rel_rms(est["zddot"].values[:, 0], zdd) < 0.5 * rel_rms(naive["zddot"].values[:, 0], zdd)


def test_spline_clean_and_noisy():
    t = np.arange(0, 6, 0.005)
    z, zd, zdd = multisine(t)
    est = h.estimate_derivatives(h.make_history(t, z), method="spline")
    assert "smoothing_spline" in est["zddot"].attrs["estimated"]
    trim = 60  # natural spline: z'' -> 0 at the ends (documented bias)
    assert rel_rms(est["zdot"].values[:, 0], zd, trim) < 5e-3
    assert rel_rms(est["zddot"].values[:, 0], zdd, trim) < 5e-3
    noisy = z + 1e-5 * np.random.default_rng(2).standard_normal(t.size)
    est = h.estimate_derivatives(h.make_history(t, noisy), method="spline")
    assert rel_rms(est["zddot"].values[:, 0], zdd, trim) < 3e-2


def test_estimate_keeps_given_and_overwrites_on_request():
    t = np.arange(0, 5, 0.01)
    z, zd, _ = multisine(t)
    ds = h.make_history(t, z, zdot=zd)
    est = h.estimate_derivatives(ds)
    np.testing.assert_array_equal(est["zdot"].values[:, 0], zd)
    assert "estimated" not in est["zdot"].attrs and "estimated" in est["zddot"].attrs
    again = h.estimate_derivatives(est, overwrite=True, window=11)
    assert again["zdot"].attrs["estimated"].startswith("savgol(window=11,")


@pytest.mark.parametrize("kw", [{"window": 4}, {"window": 3, "polyorder": 3},
                                {"window": 10_001}, {"method": "magic"}])
def test_estimate_bad_parameters(kw):
    t = np.arange(0, 5, 0.01)
    with pytest.raises(InputError):
        h.estimate_derivatives(h.make_history(t, np.sin(t)), **kw)


def test_estimate_constant_z_is_an_input_error():
    t = np.arange(0, 5, 0.01)
    with pytest.raises(InputError, match="constant"):
        h.estimate_derivatives(h.make_history(t, np.zeros_like(t)))


# ------------------------------------------------------------------ resampling


def irregular_times(n=400, dt=0.01, seed=0):
    rng = np.random.default_rng(seed)
    return np.cumsum(dt * (1 + 0.4 * (rng.random(n) - 0.5))) - dt


@pytest.mark.parametrize("method, tol", [("cubic", 1e-5), ("pchip", 4e-3), ("akima", 4e-3),
                                         ("linear", 1e-2)])
def test_resample_onto_uniform_grid(method, tol):
    t = irregular_times()
    z, _, _ = multisine(t)
    ds = h.make_history(t, z, forces={"F": 3 * z}, check=False)
    with pytest.raises(InputError, match="irregularly sampled"):
        h.validate(ds)
    out = h.resample(ds, dt=0.01, method=method)
    h.validate(out)
    assert h.time_step(out) == pytest.approx(0.01)
    ref, _, _ = multisine(out["time"].values)
    assert np.max(np.abs(out["z"].values[:, 0] - ref)) < tol * 0.03
    np.testing.assert_allclose(out["F"].values, 3 * out["z"].values, atol=1e-12)
    assert out["F"].attrs["role"] == "force"
    assert out.attrs["resampled"].startswith(f"{method}(dt=0.01)")


def test_resample_bad_method_and_dt():
    t = irregular_times()
    ds = h.make_history(t, np.sin(t), check=False)
    with pytest.raises(InputError):
        h.resample(ds, method="nearest-ish")
    with pytest.raises(InputError):
        h.resample(ds, dt=-1.0)


# ------------------------------------------------------------------ CSV / NetCDF round trips


def full_history():
    t = np.arange(0, 4, 0.01)
    z, zd, zdd = multisine(t)
    ds = h.make_history(t, z, zd, zdd, {"F_tot": 7.06 * zdd, "F_hs": -692.2 * z}, mass=7.06,
                        source="test", inputs={"case": 1})
    ds["zddot"].attrs["estimated"] = "savgol(window=9, polyorder=3, deriv=2, dt=0.01)"
    return ds


def test_csv_round_trip_is_exact(tmp_path):
    ds = full_history()
    path = h.to_csv(ds, tmp_path / "hist.csv")
    back = h.read_csv(path)
    for name in ("z", "zdot", "zddot", "F_tot", "F_hs"):
        np.testing.assert_array_equal(back[name].values, ds[name].values)
    np.testing.assert_array_equal(back["time"].values, ds["time"].values)
    assert float(back["mass"].values[0, 0]) == 7.06
    assert set(h.force_names(back)) == {"F_tot", "F_hs"}
    assert back["zddot"].attrs["estimated"] == ds["zddot"].attrs["estimated"]
    assert back.attrs["source"] == "test"
    assert not list(tmp_path.glob(".*tmp"))  # atomic write left no temporary file


@pytest.mark.parametrize("extra_columns", [0, 9000])
def test_large_csv_floats_are_correctly_rounded(tmp_path, extra_columns):
    """The fast column reader (lazy header, Arrow/NumPy) gives Python's correctly rounded
    float() of every cell, also for tiny and huge exponents where a fast strtod loses digits;
    a 9 000-column header (longer than the first read) takes the same path."""
    rng = np.random.default_rng(3)
    n = 4000
    t = np.arange(n) * 0.01
    z = rng.standard_normal(n) * 10.0 ** rng.integers(-300, 140, n)
    cells = [repr(float(v)) for v in z]
    header = ["time [s]", "z [m]", "F_tot [N]"] + [f"probe{k:05d}" for k in range(extra_columns)]
    filler = "," + ",".join(["0.5"] * extra_columns) if extra_columns else ""
    path = tmp_path / "big.csv"
    with open(path, "w") as f:
        f.write("# written by a test\n" + ",".join(header) + "\n")
        for k in range(n):
            f.write(f"{float(t[k])!r},{cells[k]},{cells[k]}{filler}\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        back = h.read_csv(path, forces=["F_tot"])
    expect = np.array([float(c) for c in cells])
    np.testing.assert_array_equal(back["z"].values[:, 0], expect)
    np.testing.assert_array_equal(back["F_tot"].values[:, 0], expect)


def test_netcdf_round_trip_through_read_history(tmp_path):
    ds = full_history()
    h.to_netcdf(ds, tmp_path / "hist.nc")
    back = read_history(tmp_path / "hist.nc")
    assert back.attrs["format"] == "netcdf"
    for name in ("z", "zdot", "zddot", "F_tot", "mass"):
        np.testing.assert_array_equal(back[name].values, ds[name].values)
    # the same file through CSV -> read_history gives the same numbers
    h.to_csv(back, tmp_path / "hist.csv")
    again = read_history(tmp_path / "hist.csv")
    np.testing.assert_array_equal(again["F_tot"].values, ds["F_tot"].values)


def surge_pitch_history():
    """Two DOFs of different kinds: Surge (m, N) and Pitch (rad, N m), coupled mass matrix."""
    t = np.arange(0.0, 2.0, 0.01)
    z = np.column_stack([0.02 * np.sin(3 * t), 0.05 * np.cos(3 * t)])
    mass = np.array([[7.0, 0.35], [0.35, 0.12]])  # kg, kg m; kg m, kg m^2
    forces = {"F_tot": np.column_stack([np.cos(t), 0.1 * np.sin(t)])}
    return h.make_history(t, z, 3 * z, -9 * z, forces, dof=["Surge", "Pitch"], mass=mass,
                          source="test")


def test_units_per_dof_follow_the_dof_kinds():
    ds = surge_pitch_history()
    assert ds["z"].attrs["units"] == "m, rad"
    assert json.loads(ds["z"].attrs["units_per_dof"]) == ["m", "rad"]
    assert json.loads(ds["zdot"].attrs["units_per_dof"]) == ["m/s", "rad/s"]
    assert json.loads(ds["zddot"].attrs["units_per_dof"]) == ["m/s^2", "rad/s^2"]
    assert ds["F_tot"].attrs["units"] == "N, N m"
    assert json.loads(ds["F_tot"].attrs["units_per_dof"]) == ["N", "N m"]
    assert ds["mass"].attrs["units"].startswith("per DOF pair")  # kg, kg m, kg m^2 mixed
    heave = full_history()
    assert (heave["z"].attrs["units"], heave["F_tot"].attrs["units"]) == ("m", "N")
    assert heave["mass"].attrs["units"] == "kg"
    # derivatives estimated later carry the same per-DOF units
    est = h.estimate_derivatives(ds.drop_vars(["zdot", "zddot"]))
    assert json.loads(est["zddot"].attrs["units_per_dof"]) == ["m/s^2", "rad/s^2"]


def test_unknown_dof_name_is_an_input_error():
    with pytest.raises(InputError, match="degree"):
        h.make_history(np.arange(10.0), np.zeros(10), dof=["Bob"])


def test_multi_dof_csv_has_units_per_dof_and_round_trips_exactly(tmp_path):
    ds = surge_pitch_history()
    path = h.to_csv(ds, tmp_path / "sp.csv")
    header = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")][0]
    assert header.split(",")[:3] == ["time [s]", "z_Surge [m]", "z_Pitch [rad]"]
    assert "F_tot_Pitch [N m]" in header and "zddot_Pitch [rad/s^2]" in header
    back = h.read_csv(path)  # DOFs and mass from the '#' metadata lines
    assert list(back["dof"].values) == ["Surge", "Pitch"]
    for name in ("z", "zdot", "zddot", "F_tot", "mass"):
        np.testing.assert_array_equal(back[name].values, ds[name].values)
    assert h.force_names(back) == ["F_tot"]
    assert back["F_tot"].attrs["units_per_dof"] == ds["F_tot"].attrs["units_per_dof"]


def test_pitch_csv_in_degrees_and_kilonewton_metres(tmp_path):
    # a rotation's moment column in kN m is a force of that DOF, converted to N m
    p = write(tmp_path, "p.csv", "time [s],z [deg],M [kN m]\n" + "\n".join(
        f"{0.1 * k:.1f},{k},{2 * k}" for k in range(10)))
    ds = h.read_csv(p, dof="Pitch")
    np.testing.assert_allclose(ds["z"].values[:, 0], np.deg2rad(np.arange(10)))
    assert h.force_names(ds) == ["M"]
    np.testing.assert_allclose(ds["M"].values[:, 0], 2e3 * np.arange(10))
    assert ds["M"].attrs["units"] == "N m"


# ------------------------------------------------------------------ CSV reading: formats, units


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_units_separators_comments_and_mapping(tmp_path):
    t = np.arange(12) * 10.0  # ms
    z = np.linspace(0, 11, 12)  # mm
    lines = ["# a comment", "Zeit [ms];Hub (mm);Kraft [kN];Welle [m];label"]
    lines += [f"{a};{b};{c};{c};x # trailing comment" for a, b, c in zip(t, z, 2 * z)]
    p = write(tmp_path, "semi.csv", "\n".join(lines) + "\n")
    ds = h.read_csv(p, time="zeit", z="Hub")
    np.testing.assert_allclose(ds["time"].values, t * 1e-3)
    np.testing.assert_allclose(ds["z"].values[:, 0], z * 1e-3)
    np.testing.assert_allclose(ds["Kraft"].values[:, 0], 2 * z * 1e3)  # kN -> N, a force
    assert h.force_names(ds) == ["Kraft"]
    assert ds["Welle"].attrs["units"] == "m"  # not a force: kept as extra variable
    assert "label" not in ds  # text column skipped

    ws = write(tmp_path, "ws.txt", "t z F\n" + "\n".join(f"{a/1000}  {b}\t{c}" for a, b, c in
                                                         zip(t, z, z)) + "\n")
    ds = h.read_csv(ws, time="t", forces=["F"])
    assert h.force_names(ds) == ["F"] and ds.sizes["time"] == 12


def test_forces_mapping_and_trailing_separator(tmp_path):
    rows = "\n".join(f"{0.1 * k:.1f},{k},{2 * k}," for k in range(10))
    p = write(tmp_path, "trail.csv", "time,z,Fz [N],\n" + rows + "\n")
    ds = h.read_csv(p, forces={"F_tot": "Fz"})
    np.testing.assert_allclose(ds["F_tot"].values[:, 0], 2 * np.arange(10))


def test_irregular_csv_rejected_unless_resample(tmp_path):
    t = irregular_times(60)
    p = write(tmp_path, "irr.csv", "time,z\n" + "\n".join(f"{float(a)!r},{float(np.sin(a))!r}" for a in t))
    with pytest.raises(InputError, match="--resample"):
        h.read_csv(p)
    ds = h.read_csv(p, resample=True)
    assert h.is_uniform(ds) and "resampled" in ds.attrs


def test_pitch_dof_takes_angle_units(tmp_path):
    p = write(tmp_path, "pitch.csv", "time [s],theta [deg]\n" + "\n".join(
        f"{0.1 * k:.1f},{k}" for k in range(10)))
    ds = h.read_csv(p, z="theta", dof="Pitch")
    np.testing.assert_allclose(ds["z"].values[:, 0], np.deg2rad(np.arange(10)))


BAD_CASES = {
    "nan_cell.csv": "NaN value 'nan' in column 'z [m]' at line 6",
    "empty_cell.csv": "empty cell in column 'F_tot [N]' at line 7",
    "non_numeric.csv": "non-numeric value '0.0x3' in column 'z [m]' at line 8",
    "unsorted_time.csv": "not sorted: line 6",
    "duplicated_time.csv": "duplicated at line 7",
    "missing_column.csv": "available columns: time [s], x [m], F_tot [N]",
    "too_few_samples.csv": "5 data rows; at least 8",
    "mismatched_lengths.csv": "line 10 has fewer fields",
    "extra_field.csv": "line 4 has 4 fields",
    "unknown_unit.csv": "unit 'furlong'",
    "unknown_time_unit.csv": "unit 'fortnights'",
    "empty.csv": "is empty",
    "comments_only.csv": "no header",
    "binary_garbage.csv": "binary file",
    "does_not_exist.csv": "file not found",
}


@pytest.mark.parametrize("name", sorted(BAD_CASES))
def test_bad_input_corpus(name):
    with pytest.raises(InputError) as err:
        read_history(BAD / name)
    msg = str(err.value)
    assert BAD_CASES[name] in msg
    assert "\n" not in msg


def test_corrupt_netcdf():
    with pytest.raises(InputError, match="NetCDF"):
        read_history(BAD / "fake.nc")


# ------------------------------------------------------------------ crossings (history.signal)


def _free_decay(t, period, zeta, z_eq):
    """Linear oscillator released at rest 1 above z_eq: crossings of z_eq are exactly half a
    damped period apart (analytic)."""
    wd = 2 * np.pi / period
    wn = wd / np.sqrt(1 - zeta**2)
    return z_eq + np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))


def test_crossings_of_a_sine_are_its_zeros_and_directions_split_them():
    t = np.linspace(0.0, 2.0, 2001)
    z = np.sin(2 * np.pi * t / 0.5 + 0.3)  # zeros at (k pi - 0.3) / (4 pi)
    _, tc = h.crossings(t, z)
    expected = (np.arange(1, 9) * np.pi - 0.3) / (4 * np.pi)
    np.testing.assert_allclose(tc, expected, atol=2e-6)
    up = h.crossings(t, z, direction="up")[1]
    down = h.crossings(t, z, direction="down")[1]
    np.testing.assert_allclose(np.sort(np.r_[up, down]), tc)
    assert np.all(np.cos(2 * np.pi * up / 0.5 + 0.3) > 0)  # rising through zero
    with pytest.raises(InputError, match="direction"):
        h.crossings(t, z, direction="sideways")


def test_crossing_periods_about_the_equilibrium_not_zero():
    t = np.linspace(0.0, 3.0, 30001)
    z = _free_decay(t, 0.8, 0.3, 0.05)
    np.testing.assert_allclose(h.crossing_periods(t, z, 0.05)[:3], 0.8, rtol=1e-3)
    assert h.crossing_periods(t, z, 0.0)[1] > 1.05 * 0.8  # about z = 0 it is wrong
    assert h.mean_crossing_period(t, z, (0.0, 2.5), z_eq=0.05) == pytest.approx(0.8, rel=1e-3)
    # a steady oscillation about an unknown mean: z_eq=None crosses the mean
    t10 = np.arange(0.0, 7.0, 1e-3)  # ten whole periods: their mean is the level
    steady = 0.3 + 0.1 * np.cos(2 * np.pi * t10 / 0.7)
    assert h.mean_crossing_period(t10, steady, z_eq=None) == pytest.approx(0.7, rel=1e-6)
    assert np.isnan(h.mean_crossing_period(t, z, (0.0, 0.3), z_eq=0.05))  # < 3 crossings


def test_a_sample_exactly_at_the_level_is_one_crossing():
    t = np.arange(5.0)
    _, tc = h.crossings(t, np.array([1.0, 0.0, -1.0, 0.0, 1.0]))
    np.testing.assert_allclose(tc, [1.0, 3.0])  # 0.0 counts as above: one crossing per pass
