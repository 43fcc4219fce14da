"""Importers: Kramer et al. (2021) decay data and DualSPHysics floating-body CSV.

References: the measured decay's known properties (drop height, period ratios computed in the
data README, the 95 % band), linear theory's natural period Te0, and the analytic motion the
hand-made DualSPHysics files were written from (z = 0.01 cos(w t), T = 0.75 s, m = 7.06 kg,
fluid force = m (z'' + g); the jittered files: the forced oscillator of
``data/make_dsph_jittered.py`` at DualSPHysics-like irregular output times).
"""

from __future__ import annotations

import filecmp
import json
import importlib.util
import warnings
from pathlib import Path

import numpy as np
import pytest

from hybridwsi import history as h
from hybridwsi import importers as im
from hybridwsi.errors import InputError

DATA = Path(__file__).parent / "data"
W = 2 * np.pi / 0.75
M = 7.06
PACKAGED = Path(im.__file__).parents[1] / "data" / "kramer2021_sphere_decay"


def zero_crossing_periods(ds) -> np.ndarray:
    """Full periods [s] from successive zero crossings (t > 0), linear interpolation."""
    t, z = ds["time"].values, ds["z"].values[:, 0]
    s = np.flatnonzero((z[:-1] > 0) != (z[1:] > 0))
    s = s[t[s] > 0]
    tc = t[s] - z[s] * (t[s + 1] - t[s]) / (z[s + 1] - z[s])
    return 2 * np.diff(tc)


# ------------------------------------------------------------------ Kramer 2021


def test_kramer_dir_lookup_order(monkeypatch, tmp_path):
    monkeypatch.setenv("HYBRIDWSI_KRAMER_DIR", str(tmp_path))
    assert im.kramer_data_dir() == tmp_path
    monkeypatch.setenv("HYBRIDWSI_KRAMER_DIR", str(tmp_path / "nope"))
    with pytest.raises(InputError, match="HYBRIDWSI_KRAMER_DIR"):
        im.kramer_data_dir()
    monkeypatch.delenv("HYBRIDWSI_KRAMER_DIR")
    assert (im.kramer_data_dir() / "01D_CI95_Normalized_every5th.csv").is_file()


def test_packaged_copy_matches_shared_data():
    shared = Path(im.__file__).resolve().parents[4] / "shared" / "data" / "kramer2021_sphere_decay"
    names = ["01D_CI95_Normalized_every5th.csv", "03D_CI95_Normalized_every5th.csv",
             "05D_CI95_Normalized_every5th.csv", "README.md", "numerical/LPF1_01D.csv"]
    for name in names:
        assert (PACKAGED / name).is_file()
        if shared.is_dir():
            assert filecmp.cmp(PACKAGED / name, shared / name, shallow=False)


def test_kramer_measured_decay_01D():
    path = PACKAGED / "01D_CI95_Normalized_every5th.csv"
    assert im.detect_format(path) == "kramer"
    ds = im.read_kramer_decay(path)
    t, z = ds["time"].values, ds["z"].values[:, 0]
    assert h.is_uniform(ds) and h.time_step(ds) == pytest.approx(0.01, rel=1e-4)
    # held at the drop height H0 = 0.1 D = 0.03 m before release (t < 0)
    assert np.allclose(z[t < 0], 0.03, rtol=3e-3)
    assert np.all(ds["ci95_lower"].values <= ds["z"].values + 1e-12)
    assert np.all(ds["z"].values <= ds["ci95_upper"].values + 1e-12)
    # first trough -0.853 H0 near t/Te0 = 0.51 (README); periods close to Te0 = 0.7561 s
    i = np.argmin(z)
    assert z[i] / 0.03 == pytest.approx(-0.853, abs=2e-3)
    assert t[i] / 0.7561 == pytest.approx(0.51, abs=0.02)
    periods = zero_crossing_periods(ds) / 0.7561
    np.testing.assert_allclose(periods[:5], [1.040, 1.009, 1.005, 0.997, 1.007], atol=5e-3)
    assert float(ds["mass"].values[0, 0]) == pytest.approx(7.056)


def test_kramer_drop_height_from_name_and_override():
    ds = im.read_kramer_decay(PACKAGED / "03D_CI95_Normalized_every5th.csv")
    assert ds["z"].values[0, 0] == pytest.approx(0.09, rel=3e-3)
    ds = im.read_kramer_decay(PACKAGED / "03D_CI95_Normalized_every5th.csv", drop_height=0.1)
    assert ds["z"].values[0, 0] == pytest.approx(0.1, rel=3e-3)
    with pytest.raises(InputError, match="drop height"):
        im.read_kramer_decay(PACKAGED / "01D_CI95_Normalized_every5th.csv", drop_height=-1)


def test_kramer_numerical_regular_and_irregular():
    lpf0 = im.read_kramer_numerical(PACKAGED / "numerical" / "LPF0_01D.csv")  # dt = 0.01 s
    assert h.is_uniform(lpf0) and lpf0["z"].values[0, 0] == pytest.approx(0.03)
    # a linear potential-flow decay oscillates at Te0 = 0.7561 s (README: 2 pi sqrt((m+A)/k))
    assert np.median(zero_crossing_periods(lpf0)) == pytest.approx(0.7561, rel=0.01)

    path = PACKAGED / "numerical" / "LPF1_01D.csv"
    assert im.detect_format(path) == "kramer-numerical"
    with pytest.raises(InputError, match="irregularly sampled"):
        im.read_kramer_numerical(path)
    raw = im.read_kramer_numerical(path, require_uniform=False)
    assert not h.is_uniform(raw)
    res = im.read_kramer_numerical(path, resample=True)
    assert h.is_uniform(res) and "resampled" in res.attrs
    # the resampled curve passes through the original samples (cubic interpolation)
    z_at = np.interp(raw["time"].values, res["time"].values, res["z"].values[:, 0])
    assert np.max(np.abs(z_at - raw["z"].values[:, 0])) < 2e-4
    assert np.median(zero_crossing_periods(res)) == pytest.approx(0.7561, rel=0.01)


# ------------------------------------------------------------------ DualSPHysics


def test_floatinginfo_matches_analytic_motion():
    path = DATA / "dsph_floatinginfo.csv"
    assert im.detect_format(path) == "dualsphysics-info"
    ds = im.read_dualsphysics_floatinginfo(path, mass=M)
    t = ds["time"].values
    np.testing.assert_allclose(ds["z"].values[:, 0], 0.01 * np.cos(W * t) - 0.01, atol=1e-9)
    np.testing.assert_allclose(ds["zdot"].values[:, 0], -0.01 * W * np.sin(W * t), atol=1e-9)
    np.testing.assert_allclose(ds["zddot"].values[:, 0], -0.01 * W**2 * np.cos(W * t), atol=1e-8)
    # Newton: the fluid force balances inertia and weight, m z'' = F_fluid - m g
    np.testing.assert_allclose(ds["F_fluid"].values - M * 9.81, ds["F_tot"].values, atol=1e-6)
    assert set(h.force_names(ds)) == {"F_fluid", "F_tot"}


def test_floatinginfo_column_variants_and_mkbound(tmp_path):
    # comma separator, capitalised names, no heave column (z from center.z), two bodies
    rows = ["mkbound,Time [s],Center.Z [m],FVel.Z [m/s]"]
    for k in range(10):
        for mk, z0 in ((61, 0.5), (62, 1.0)):
            rows.append(f"{mk},{0.1 * k:.1f},{z0 + 0.001 * k * mk},{0.01 * mk}")
    p = tmp_path / "FloatingMotion.csv"
    p.write_text("\n".join(rows) + "\n")
    assert im.detect_format(p) == "dualsphysics-info"
    with pytest.raises(InputError, match="several floating bodies"):
        im.read_dualsphysics_floatinginfo(p)
    ds = im.read_dualsphysics_floatinginfo(p, mkbound=62)
    np.testing.assert_allclose(ds["z"].values[:, 0], 0.062 * np.arange(10), atol=1e-12)
    assert "initial value" in ds["z"].attrs["description"]
    with pytest.raises(InputError, match="no mkbound 70"):
        im.read_dualsphysics_floatinginfo(p, mkbound=70)


def test_floatingace_drops_predictor_rows_and_states_missing_z():
    path = DATA / "dsph_floatingace.csv"
    assert im.detect_format(path) == "dualsphysics-ace"
    with pytest.warns(UserWarning, match="no displacement"):
        with pytest.raises(InputError, match="irregularly sampled"):
            im.read_dualsphysics_floatingace(path, mass=M, resample=False)
    with pytest.warns(UserWarning):
        raw = im.read_dualsphysics_floatingace(path, mass=M, require_uniform=False)
    t = raw["time"].values
    assert t.size == 30  # 60 rows, the 30 predictor rows dropped
    np.testing.assert_allclose(raw["zddot"].values[:, 0], -0.01 * W**2 * np.cos(W * t), atol=1e-8)
    np.testing.assert_allclose(raw["F_tot"].values, M * raw["zddot"].values)
    assert "z" not in raw and "z and zdot" in raw.attrs["missing"]
    for resample in (True, None):  # asked, and by default (solver steps within 50 % of dt)
        with pytest.warns(UserWarning):
            res = im.read_dualsphysics_floatingace(path, resample=resample)
        assert h.is_uniform(res)
        assert ("automatic" in res.attrs["resampled"]) == (resample is None)
        tt = res["time"].values
        np.testing.assert_allclose(res["zddot"].values[:, 0], -0.01 * W**2 * np.cos(W * tt),
                                   atol=2e-3)


# ------------------------------------------------------------------ DualSPHysics as it comes


def jittered_generator():
    """tests/data/make_dsph_jittered.py, which wrote the jittered files (analytic motion)."""
    spec = importlib.util.spec_from_file_location("make_dsph_jittered",
                                                  DATA / "make_dsph_jittered.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_dualsphysics_files_as_they_come_are_resampled_without_flags():
    gen = jittered_generator()
    info_path = DATA / "dsph_floatinginfo_jittered.csv"
    ace_path = DATA / "dsph_floatingace_jittered.csv"
    raw_t = np.loadtxt(info_path, delimiter=";", skiprows=1, usecols=1)
    steps = np.diff(raw_t)
    assert steps.min() < 0.00987 and steps.max() > 0.01013  # as irregular as a real file
    info = im.read_history(info_path, mass=gen.M)
    assert info.attrs["format"] == "dualsphysics-info" and h.is_uniform(info)
    assert "automatic" in info.attrs["resampled"] and "401 samples" in info.attrs["resampled"]
    assert h.time_step(info) == pytest.approx(0.01, rel=2e-3)
    # the resampled history is the analytic motion on the uniform grid (heave = z - z(0))
    t = info["time"].values
    z, zd, zdd = gen.motion(t)
    z0 = gen.motion(np.zeros(1))[0][0]
    for name, exact in (("z", z - z0), ("zdot", zd), ("zddot", zdd)):
        np.testing.assert_allclose(info[name].values[:, 0], exact, rtol=0,
                                   atol=1e-6 * np.ptp(exact), err_msg=name)
    np.testing.assert_allclose(info["F_fluid"].values[:, 0], gen.M * (zdd + gen.G),
                               rtol=0, atol=1e-6 * gen.M * np.ptp(zdd))
    with pytest.warns(UserWarning, match="no displacement"):
        ace = im.read_history(ace_path)
    assert ace.attrs["format"] == "dualsphysics-ace" and "automatic" in ace.attrs["resampled"]
    exact = gen.motion(ace["time"].values)[2]
    np.testing.assert_allclose(ace["zddot"].values[:, 0], exact, rtol=0, atol=1e-6 * np.ptp(exact))


def test_dualsphysics_gaps_and_generic_csv_jitter_are_still_refused(tmp_path):
    lines = (DATA / "dsph_floatinginfo_jittered.csv").read_text().splitlines()
    gap = tmp_path / "FloatingInfo_gap.csv"
    gap.write_text("\n".join(lines[:100] + lines[101:]) + "\n")  # one output missing
    with pytest.raises(InputError, match="irregularly sampled"):
        im.read_history(gap)
    assert h.is_uniform(im.read_history(gap, resample=True))  # when asked
    with pytest.raises(InputError, match="irregularly sampled"):
        im.read_dualsphysics_floatinginfo(DATA / "dsph_floatinginfo_jittered.csv",
                                          resample=False)
    generic = tmp_path / "generic.csv"
    t = 0.01 * np.arange(100) + np.where(np.arange(100) % 2, 1e-4, 0.0)
    generic.write_text("time [s],z [m]\n" + "\n".join(f"{a},{np.sin(a)}" for a in t) + "\n")
    assert im.detect_format(generic) == "csv"
    with pytest.raises(InputError, match="irregularly sampled"):
        im.read_history(generic)


# ------------------------------------------------------------------ dispatch


def test_read_history_dispatch_and_options(tmp_path):
    ds = im.read_history(PACKAGED / "01D_CI95_Normalized_every5th.csv", drop_height=0.03)
    assert ds.attrs["format"] == "kramer"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ace = im.read_history(DATA / "dsph_floatingace.csv", resample=True, mass=M)
    assert ace.attrs["format"] == "dualsphysics-ace" and float(ace["mass"].values[0, 0]) == M
    with pytest.raises(InputError, match="do not apply"):
        im.read_history(DATA / "dsph_floatinginfo.csv", zdot="w")
    with pytest.raises(InputError, match="unknown format"):
        im.read_history(DATA / "dsph_floatinginfo.csv", format="wamit")
    # forced format on a plain CSV reader
    forced = im.read_history(DATA / "dsph_floatinginfo.csv", format="csv", time="time",
                            z="heave", forces=["fluidforcelin.z"])
    assert h.force_names(forced) == ["fluidforcelin.z"]


def test_import_and_diagnose_take_jittered_dualsphysics_without_flags(tmp_path, capsys):
    from hybridwsi.cli import main

    gen = jittered_generator()
    src = DATA / "dsph_floatinginfo_jittered.csv"
    nc = tmp_path / "h.nc"
    assert main(["import", str(src), "--out", str(nc), "--mass", str(gen.M)]) == 0
    notes = [ln for ln in capsys.readouterr().out.splitlines() if "resampled" in ln]
    assert len(notes) == 1 and "automatic" in notes[0]
    assert h.is_uniform(im.read_history(nc))
    res = tmp_path / "r.json"
    assert main(["diagnose", str(src), "--mass", str(gen.M), "--known", f"hydrostatic={gen.C}",
                 "--known", f"added_mass_inf={gen.A}", "--json", str(res)]) == 0
    notes = [ln for ln in capsys.readouterr().out.splitlines() if "resampled" in ln]
    assert len(notes) == 1 and notes[0].startswith("note: time resampled")
    # F_tot - F_hs - F_A = (m + A) z'' + C z on the resampled grid (docs/THEORY.md §1, case 3)
    out = json.loads(res.read_text())
    assert out["alpha"] == pytest.approx(gen.M + gen.A, rel=1e-6)
    assert out["gamma"] == pytest.approx(gen.C, rel=1e-6)
    assert abs(out["beta"]) < 1e-6 * gen.C
