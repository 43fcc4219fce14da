"""Issue 16 (data layer): units honoured or refused, impossible physics refused, big CSVs read
column by column with every check of the string parser kept.

The references are independent of the code: unit definitions (1 in = 25.4 mm, 1 ft = 0.3048 m,
1 h = 3600 s), Archimedes (a body heavier than the water it displaces sinks), the float range
(IEEE 754 max ≈ 1.8e308) and the string parser's own messages on the same files.
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hybridwsi import history as h
from hybridwsi.errors import InputError
from hybridwsi.history.text import TextTable
from hybridwsi.importers import read_history

BAD = Path(__file__).parent / "data" / "bad"


def _decay(n: int = 200, dt: float = 0.01, dof=("Heave",)) -> xr.Dataset:
    t = np.arange(n) * dt
    w = 2 * np.pi / 0.76
    z = np.column_stack([0.01 * np.exp(-0.1 * t) * np.cos(w * t + k) for k in range(len(dof))])
    zdot = np.gradient(z, dt, axis=0)
    zddot = np.gradient(zdot, dt, axis=0)
    return h.make_history(t, z, zdot, zddot, {"F_tot": 7.06 * zddot}, dof=list(dof), mass=7.06)


# ------------------------------------------------------------------------------- units
@pytest.mark.parametrize("unit, quantity, factor", [
    ("mm", "length", 1e-3), ("cm", "length", 1e-2), ("km", "length", 1e3),
    ("in", "length", 0.0254), ("ft", "length", 0.3048), ("ms", "time", 1e-3),
    ("min", "time", 60.0), ("h", "time", 3600.0), ("hours", "time", 3600.0),
    ("kN", "force", 1e3), ("MN", "force", 1e6), ("kN m", "moment", 1e3), ("kNm", "moment", 1e3),
    ("N.m", "moment", 1.0), ("deg", "angle", math.pi / 180), ("ft/s", "velocity", 0.3048),
    ("mm/s^2", "acceleration", 1e-3), ("m s-2", "acceleration", 1.0),
    ("in/min^2", "acceleration", 0.0254 / 3600), ("deg/s²", "angular_acceleration", math.pi / 180),
])
def test_unit_table(unit, quantity, factor):
    assert h.unit_factor(unit, quantity, "x") == pytest.approx(factor, rel=1e-15)


@pytest.mark.parametrize("unit, quantity", [("furlong", "length"), ("mN", "force"),
                                            ("m", "angle"), ("kg", "force"), ("m/s", "length")])
def test_unknown_or_wrong_units_are_refused(unit, quantity):
    with pytest.raises(InputError, match=f"unit '{unit}'"):
        h.unit_factor(unit, quantity, "x")


def _netcdf_with_units(tmp_path: Path, **units: str) -> Path:
    ds = _decay()
    for name, unit in units.items():
        ds[name].attrs = {k: v for k, v in ds[name].attrs.items() if k != "units_per_dof"}
        ds[name].attrs["units"] = unit
    path = tmp_path / "h.nc"
    ds.to_netcdf(path)
    return path


def test_netcdf_units_are_converted_to_si(tmp_path):
    ref = _decay()
    path = _netcdf_with_units(tmp_path, time="ms", z="mm", zdot="mm/s", zddot="cm/s^2",
                              F_tot="kN")
    got = read_history(path)
    np.testing.assert_allclose(got["time"].values, ref["time"].values * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(got["z"].values, ref["z"].values * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(got["zdot"].values, ref["zdot"].values * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(got["zddot"].values, ref["zddot"].values * 1e-2, rtol=1e-15)
    np.testing.assert_allclose(got["F_tot"].values, ref["F_tot"].values * 1e3, rtol=1e-15)
    assert got["z"].attrs["units"] == "m" and json.loads(got["F_tot"].attrs["units_per_dof"]) == ["N"]
    assert got["time"].attrs["units"] == "s"


def test_netcdf_time_in_hours(tmp_path):
    got = read_history(_netcdf_with_units(tmp_path, time="hours"))
    assert float(got["time"][1] - got["time"][0]) == pytest.approx(0.01 * 3600)


@pytest.mark.parametrize("var", ["z", "time", "F_tot"])
def test_netcdf_unknown_unit_is_refused_naming_variable_and_unit(tmp_path, var):
    with pytest.raises(InputError) as err:
        read_history(_netcdf_with_units(tmp_path, **{var: "furlong"}))
    msg = str(err.value)
    assert "furlong" in msg and f"'{var}" in msg and "\n" not in msg


def test_rotation_in_metres_is_refused(tmp_path):
    ds = _decay(dof=("Heave", "Pitch"))
    ds["z"].attrs["units_per_dof"] = json.dumps(["m", "m"])
    ds.to_netcdf(tmp_path / "p.nc")
    with pytest.raises(InputError, match="z on Pitch|disagree"):
        read_history(tmp_path / "p.nc")


def test_validate_refuses_a_non_si_history_read_without_conversion(tmp_path):
    """select/hybrid read NetCDF with read_netcdf (no conversion): validate is the backstop."""
    ds = h.read_netcdf(_netcdf_with_units(tmp_path, z="mm"))
    with pytest.raises(InputError, match="'z' is in mm, not SI"):
        h.validate(ds)


def test_csv_units_share_the_table(tmp_path):
    p = tmp_path / "ft.csv"
    p.write_text("time [min],z [ft],F_tot [kN]\n" + "".join(
        f"{k / 60:.17g},{k},{2 * k}\n" for k in range(12)))
    ds = h.read_csv(p)
    np.testing.assert_allclose(ds["time"].values, np.arange(12.0), rtol=1e-14)
    np.testing.assert_allclose(ds["z"].values[:, 0], 0.3048 * np.arange(12))
    np.testing.assert_allclose(ds["F_tot"].values[:, 0], 2e3 * np.arange(12))


# ------------------------------------------------------------------------------- mass
@pytest.mark.parametrize("mass", [-7.0, 0.0, float("nan"), float("inf")])
def test_impossible_mass_is_refused_everywhere(tmp_path, mass):
    ds = _decay()
    with pytest.raises(InputError, match="mass must be"):
        h.set_mass(ds, mass)
    with pytest.raises(InputError, match="mass must be"):
        h.make_history(ds["time"].values, ds["z"].values, mass=mass)
    bad = ds.copy()
    bad["mass"] = (("dof", "dof_j"), [[mass]])
    with pytest.raises(InputError, match="mass must be"):
        h.validate(bad)
    p = tmp_path / "m.csv"
    p.write_text(f"# mass [kg]: {mass}\ntime [s],z [m]\n" + "".join(
        f"{0.01 * k},{0.001 * k}\n" for k in range(10)))
    with pytest.raises(InputError, match="mass must be|'mass \\[kg\\]' is not a number"):
        read_history(p)


def test_mass_matrix_must_be_positive_definite():
    ds = _decay(dof=("Heave", "Pitch"))
    with pytest.raises(InputError, match="positive definite"):
        h.set_mass(ds, [[1.0, 2.0], [2.0, 1.0]])
    with pytest.raises(InputError, match="symmetric"):
        h.set_mass(ds, [[1.0, 0.5], [0.0, 1.0]])


def test_a_body_heavier_than_its_displacement_is_warned_loudly():
    import dataclasses

    from hybridwsi import bodies
    from hybridwsi.hydro.bem import warn_if_sinks

    sphere = bodies.FloatingSphere.paper()
    rho_v = sphere.rho * (2 / 3) * math.pi * 0.15**3  # Archimedes, hemisphere
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not warn_if_sinks(sphere)  # 7.06 kg vs rho V = 7.056 kg: floats
    with pytest.warns(UserWarning, match="SINKS.*1000 kg vs rho V = 7.056"):
        assert warn_if_sinks(dataclasses.replace(sphere, mass=1000.0))
    assert rho_v == pytest.approx(7.0559, rel=1e-4)


# ------------------------------------------------------------------------------- pooling
def test_check_compatible():
    a = _decay()
    h.check_compatible([a, a.copy()])
    with pytest.raises(InputError, match="time step 0.02 s"):
        h.check_compatible([a, _decay(dt=0.02)])
    with pytest.raises(InputError, match="different bodies"):
        h.check_compatible([a, h.set_mass(a, 8.0)])
    with pytest.raises(InputError, match="DOFs"):
        h.check_compatible([a, _decay(dof=("Surge",))])


# ------------------------------------------------------------------------------- regression
def test_regression_refuses_overflowing_and_constant_data():
    from hybridwsi.diagnostic.regression import regress

    ds = _decay()
    with pytest.raises(InputError, match="squares overflow"):
        regress(ds.assign(z=ds["z"] * 1e300))
    with pytest.raises(InputError, match="squares overflow"):
        regress(ds.assign(F_tot=ds["F_tot"] * 0 + 1e300))
    with pytest.raises(InputError, match="the motion is constant"):
        regress(ds.assign(z=ds["z"] * 0, zdot=ds["zdot"] * 0, zddot=ds["zddot"] * 0))
    assert regress(ds).alpha[0, 0] == pytest.approx(7.06, rel=1e-9)  # Newton still holds


def test_nan_force_is_refused_by_validate():
    ds = _decay()
    f = ds["F_tot"].values.copy()
    f[5, 0] = np.nan
    with pytest.raises(InputError, match="'F_tot' has 1 NaN/inf value"):
        h.validate(ds.assign(F_tot=(("time", "dof"), f, ds["F_tot"].attrs)))


# ------------------------------------------------------------------------------- big CSVs
@pytest.fixture
def lazy_tables(monkeypatch):
    """Every corpus file (a few hundred bytes) read through the lazy path (header from the
    head, columns by pandas), as a multi-megabyte file would be."""
    monkeypatch.setattr(TextTable, "HEAD_BYTES", 120)
    return monkeypatch


@pytest.mark.parametrize("name, message", [
    ("nan_cell.csv", "NaN value 'nan' in column 'z [m]' at line 6"),
    ("empty_cell.csv", "empty cell in column 'F_tot [N]' at line 7"),
    ("non_numeric.csv", "non-numeric value '0.0x3' in column 'z [m]' at line 8"),
    ("unsorted_time.csv", "not sorted: line 6"),
    ("duplicated_time.csv", "duplicated at line 7"),
    ("mismatched_lengths.csv", "line 10 has fewer fields"),
    ("extra_field.csv", "line 4 has 4 fields"),
    ("unknown_unit.csv", "unit 'furlong'"),
    ("too_few_samples.csv", "5 data rows; at least 8"),
])
def test_lazy_reader_keeps_every_message(lazy_tables, name, message):
    assert (BAD / name).stat().st_size > TextTable.HEAD_BYTES
    with pytest.raises(InputError) as err:
        h.read_csv(BAD / name, forces=["F_tot"] if name == "empty_cell.csv" else None)
    assert message in str(err.value)


def test_lazy_reader_reads_only_the_named_columns(tmp_path, lazy_tables):
    n, width = 50, 200
    t = np.arange(n) * 0.01
    cols = {"time [s]": t, "z [mm]": np.sin(t), "F_tot [kN]": np.cos(t)}
    cols |= {f"junk{k}": np.full(n, float(k)) for k in range(width)}
    cols["note"] = ["text"] * n  # a non-numeric column that is never parsed
    lines = [",".join(cols)] + [",".join(str(v[i]) for v in cols.values()) for i in range(n)]
    p = tmp_path / "wide.csv"
    p.write_text("\n".join(lines) + "\n")
    lazy_tables.setattr(TextTable, "HEAD_BYTES", 4096)  # the header is 1.4 kB long
    with pytest.warns(UserWarning, match=f"{width + 1} of {width + 4} columns ignored"):
        ds = h.read_csv(p, forces=["F_tot"])
    assert set(h.force_names(ds)) == {"F_tot"}
    np.testing.assert_allclose(ds["z"].values[:, 0], 1e-3 * np.sin(t), rtol=1e-15)
    np.testing.assert_allclose(ds["F_tot"].values[:, 0], 1e3 * np.cos(t), rtol=1e-15)
    assert json.loads(ds.attrs["inputs"])["ignored_columns"] == width + 1
    table = TextTable(p, lazy=True)
    assert table.load(["time [s]", "z [mm]", "F_tot [kN]"])  # the fast path was taken
    assert table._cells is None  # and the strings were never split


def test_lazy_and_eager_readers_agree(tmp_path, monkeypatch):
    ds = _decay(dof=("Heave", "Pitch"))
    p = h.to_csv(ds, tmp_path / "rt.csv")
    eager = h.read_csv(p)
    monkeypatch.setattr(TextTable, "HEAD_BYTES", 512)
    assert p.stat().st_size > 512
    lazy = h.read_csv(p)
    xr.testing.assert_identical(lazy, eager)
    xr.testing.assert_allclose(lazy[["z", "F_tot", "mass"]], ds[["z", "F_tot", "mass"]],
                               rtol=0, atol=0)


def test_lazy_reader_with_trailing_separators(tmp_path, lazy_tables):
    """DualSPHysics-style rows ``a;b;c;``: read by the fast path; data in the unnamed trailing
    column is still refused with the string parser's message."""
    rows = "".join(f"{0.01 * k:.2f};{0.001 * k};{7.0 * k};\n" for k in range(40))
    good = tmp_path / "good.csv"
    good.write_text("time [s];z [m];F_tot [N];\n" + rows)
    table = TextTable(good, lazy=True)
    assert table.load(table.columns) and table._cells is None
    np.testing.assert_allclose(h.read_csv(good)["F_tot"].values[:, 0], 7.0 * np.arange(40))
    bad = tmp_path / "bad.csv"
    bad.write_text("time [s];z [m];F_tot [N];\n" + rows.replace("0.05;0.005;35.0;", "0.05;0.005;35.0;9"))
    assert not TextTable(bad, lazy=True).load(["time [s]"])
    with pytest.raises(InputError, match="column 4 has data but no header name"):
        h.read_csv(bad)


def test_derivative_estimation_refuses_overflowing_motion():
    ds = _decay().drop_vars(["zdot", "zddot"])
    with pytest.raises(InputError, match="squares overflow"):
        h.estimate_derivatives(ds.assign(z=ds["z"] * 1e302))
