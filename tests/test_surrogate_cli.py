"""``hybridwsi hybrid`` and ``hybridwsi sweep`` command lines."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("torch")

import synthetic_hydro as sh

from hybridwsi.cli import main
from hybridwsi.history import to_netcdf
from hybridwsi.surrogate.demo import make_histories


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("hyb")
    co = d / "coeffs.nc"
    to_netcdf(sh.coefficients(np.linspace(0.1, 40.0, 200)), co)
    out = {}
    for body, mass in (("sphere", sh.M), ("light", 0.3 * sh.M)):
        hs = make_histories(sh.coefficients(), mass, range(3), hs=0.05, tp=0.8, duration=20.0,
                            dt=0.02)
        out[body] = [str(to_netcdf(h, d / f"{body}{i}.nc")) for i, h in enumerate(hs)]
    return co, out


def test_hybrid_cli_trains_checks_and_reports(tmp_path, files, capsys):
    co, hists = files
    rc = main(["hybrid", *hists["sphere"], "--coeffs", str(co), "--out", str(tmp_path),
               "--epochs", "150", "--test-fraction", "0.34"])
    assert rc == 0
    rep = json.loads((tmp_path / "report.json").read_text())
    assert rep["stability"]["stable"] and rep["stability"]["step"]["alpha"] == [[0.0]]
    assert rep["inputs"]["n_train"] == 2 and len(rep["held_out_rms_error_z"]) == 1
    assert rep["held_out_rms_error_z"][0] < 0.5 and rep["held_out_r2_force"][0] > 0.95
    assert (tmp_path / "network.pt").is_file() and (tmp_path / "network.json").is_file()
    assert "spectral radius" in capsys.readouterr().out


def test_hybrid_cli_refuses_unstable_partition(tmp_path, files, capsys):
    co, hists = files
    rc = main(["hybrid", *hists["light"], "--coeffs", str(co), "--out", str(tmp_path),
               "--partition", "added_mass_to_network", "--epochs", "150",
               "--test-fraction", "0.34"])
    assert rc == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]  # after the training progress bar
    assert last.startswith("error:") and "predicted unstable" in last and "--allow-unstable" in last


def test_cli_bad_input(tmp_path, capsys):
    assert main(["hybrid", str(tmp_path / "none.nc"), "--out", str(tmp_path)]) == 2
    assert main(["sweep", "--hs", "0.1,x", "--tp", "1", "--out", str(tmp_path)]) == 2
    assert "error:" in capsys.readouterr().err
