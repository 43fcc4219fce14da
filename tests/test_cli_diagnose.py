"""``hybridwsi diagnose`` and ``hybridwsi import``: end to end and the bad-input corpus.

Physics references are the parameters of the analytic forced oscillator (m, A, C of the
paper's sphere): regressing ``F_tot - F_hs - F_A`` must return alpha = m + A, beta = 0,
gamma = C (docs/THEORY.md §1, case 3), and alpha = m, beta = gamma = 0 for ``F_tot`` (case 1).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hybridwsi import history as h
from hybridwsi.cli import main
from hybridwsi.commands.diagnose import EXAMPLE, example_history
from hybridwsi.importers import read_history

DATA = Path(__file__).parent / "data"
BAD = DATA / "bad"
M, A, C = EXAMPLE["mass_kg"], EXAMPLE["added_mass_inf_kg"], EXAMPLE["stiffness_N_per_m"]
CASE3 = ["--known", f"hydrostatic={C}", "--known", f"added_mass={A}"]

BAD_FILES = [
    "nan_cell.csv", "empty_cell.csv", "non_numeric.csv", "unsorted_time.csv",
    "duplicated_time.csv", "missing_column.csv", "too_few_samples.csv",
    "mismatched_lengths.csv", "extra_field.csv", "unknown_unit.csv", "unknown_time_unit.csv",
    "empty.csv", "comments_only.csv", "binary_garbage.csv", "fake.nc", "does_not_exist.csv",
]


def assert_one_error_line(rc: int, err: str) -> None:
    assert rc != 0
    lines = err.strip("\n").splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: ")
    assert "Traceback" not in err


@pytest.mark.parametrize("name", BAD_FILES)
def test_bad_corpus_through_cli(name, capsys):
    rc = main(["diagnose", str(BAD / name), "--force-column", "F_tot", "--mass", "7.06"])
    assert_one_error_line(rc, capsys.readouterr().err)


@pytest.mark.parametrize("name", ["nan_cell.csv", "binary_garbage.csv", "unknown_unit.csv"])
def test_bad_corpus_through_import(name, capsys, tmp_path):
    rc = main(["import", str(BAD / name), "--out", str(tmp_path / "x.nc")])
    assert_one_error_line(rc, capsys.readouterr().err)
    assert not (tmp_path / "x.nc").exists()


@pytest.mark.parametrize("argv", [
    ["diagnose"],  # neither FILE nor --example
    ["diagnose", "--example", "--known", "hydrostatic"],
    ["diagnose", "--example", "--known", "spring=3"],
    ["diagnose", "--example", "--known", "quadratic_damping"],  # has no matrix to read
    ["diagnose", "--example", "--known", "hydrostatic", "--coeffs", str(BAD / "fake.nc")],
    ["diagnose", "--example", "--force-column", "F_nope"],
    ["diagnose", "--example", "--mass", "-1"],
    ["diagnose", "--example", "--target-dt", "0"],
    ["diagnose", str(DATA / "dsph_floatinginfo.csv"), "--zdot", "w"],
    ["diagnose", str(DATA / "dsph_floatingace.csv"), "--resample"],  # no z in the file
    ["import", str(DATA / "dsph_floatinginfo.csv"), "--out", "x.txt"],
])
def test_bad_options_one_line(argv, capsys):
    assert_one_error_line(main(argv), capsys.readouterr().err)


def test_console_script_subprocess(tmp_path):
    exe = Path(sys.executable).with_name("hybridwsi")
    assert exe.exists(), "console script not installed in this environment"
    bad = subprocess.run([str(exe), "diagnose", str(BAD / "unsorted_time.csv")],
                         capture_output=True, text=True, timeout=120)
    assert_one_error_line(bad.returncode, bad.stderr)
    assert "not sorted" in bad.stderr
    out = tmp_path / "ex.json"
    good = subprocess.run([str(exe), "diagnose", "--example", *CASE3, "--json", str(out)],
                          capture_output=True, text=True, timeout=120)
    assert good.returncode == 0, good.stderr
    assert "Traceback" not in good.stderr
    res = json.loads(out.read_text())
    assert res["alpha"] == pytest.approx(M + A, rel=1e-9)
    assert res["gamma"] == pytest.approx(C, rel=1e-9)


def test_example_case1_and_case3_json(tmp_path, capsys):
    out = tmp_path / "case1.json"
    assert main(["diagnose", "--example", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "α [kg]" in printed and "stability [" in printed
    res = json.loads(out.read_text())
    assert res["alpha"] == pytest.approx(M, rel=1e-9)
    assert abs(res["beta"]) < 1e-9 and abs(res["gamma"]) < 1e-9
    for key in ("alpha", "beta", "gamma", "mean_force", "stderr", "condition_number",
                "identifiable", "identifiable_combinations", "warnings", "stability", "input",
                "hybridwsi_version"):
        assert key in res
    assert res["identifiable"] is True  # three frequencies separate alpha and gamma
    # case 1: prescribed total force with nothing known is a double integrator (drift)
    verdicts = {r["setting"]: r["verdict"] for r in res["stability"]}
    assert verdicts["prescribed_force"] == "drift"

    out3 = tmp_path / "case3.json"
    assert main(["diagnose", "--example", *CASE3, "--target-dt", "0.01", "--json", str(out3)]) == 0
    res3 = json.loads(out3.read_text())
    assert res3["alpha"] == pytest.approx(M + A, rel=1e-9)
    assert res3["gamma"] == pytest.approx(C, rel=1e-9)
    assert res3["input"]["known"] == [f"hydrostatic={C}", f"added_mass={A}"]
    assert {r["setting"] for r in res3["stability"]} >= {"prescribed_force", "loosely_coupled"}


def test_known_added_mass_inf_and_its_alias_agree(tmp_path):
    outs = []
    for name in ("added_mass_inf", "added_mass"):
        out = tmp_path / f"{name}.json"
        assert main(["diagnose", "--example", "--known", f"hydrostatic={C}", "--known",
                     f"{name}={A}", "--json", str(out)]) == 0
        outs.append(json.loads(out.read_text()))
    assert outs[0]["alpha"] == outs[1]["alpha"] == pytest.approx(M + A, rel=1e-9)
    assert outs[0]["known"] == outs[1]["known"] == [f"hydrostatic={C}", f"added_mass_inf={A}"]


def test_diagnose_csv_with_estimated_derivatives(tmp_path, capsys):
    ex = example_history()
    csv = tmp_path / "zonly.csv"
    h.to_csv(ex.drop_vars(["zdot", "zddot"]), csv)
    out = tmp_path / "res.json"
    assert main(["diagnose", str(csv), "--force-column", "F_tot", *CASE3, "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    # derivative error moves alpha/gamma a little along the unresolved direction only
    assert res["alpha"] == pytest.approx(M + A, rel=0.02)
    assert res["gamma"] == pytest.approx(C, rel=0.02)
    assert abs(res["beta"]) < 0.5
    assert any("estimated from z by savgol" in w for w in res["warnings"])
    assert set(res["input"]["estimated"]) == {"zdot", "zddot"}
    assert res["input"]["format"] == "csv"
    assert "note: zddot was not in the file" in capsys.readouterr().out


def test_import_then_diagnose_netcdf(tmp_path, capsys):
    nc = tmp_path / "dsph.nc"
    assert main(["import", str(DATA / "dsph_floatinginfo.csv"), "--out", str(nc),
                 "--mass", "7.06"]) == 0
    assert "dualsphysics-info" in capsys.readouterr().out
    ds = read_history(nc)
    assert set(h.force_names(ds)) == {"F_fluid", "F_tot"}
    # F_tot = m z'' of a single-frequency motion: the fit recovers m z'' (alpha = m, gamma = 0
    # only as the identifiable combination gamma - w^2 alpha = -m w^2)
    out = tmp_path / "r.json"
    assert main(["diagnose", str(nc), "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    w = 2 * np.pi / 0.75
    assert res["gamma"] - w**2 * res["alpha"] == pytest.approx(-7.06 * w**2, rel=1e-6)


def test_import_kramer_to_csv(tmp_path, capsys):
    src = Path(h.__file__).parents[1] / "data" / "kramer2021_sphere_decay" / \
        "05D_CI95_Normalized_every5th.csv"
    out = tmp_path / "k.csv"
    assert main(["import", str(src), "--out", str(out), "--derivatives", "savgol"]) == 0
    ds = read_history(out)
    assert ds["z"].values[0, 0] == pytest.approx(0.15, rel=3e-3)  # 0.5 D
    assert "savgol" in ds["zddot"].attrs["estimated"]
