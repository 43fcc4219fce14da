"""scripts/sph_compare_kramer.py: the decay measures of a closed-form record, and the earlier
runs' curves that ``--with-curves`` brings into the figure unchanged."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hybridwsi import cli
from hybridwsi.files import read_netcdf
from hybridwsi.history import make_history, to_netcdf

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "docs" / "figures" / "decay3d_vs_kramer.nc"
T_D, ZETA, Z0 = 0.7702, 0.088, 0.03  # the experiment's damped fit (01D), H0 = 0.1 D [m]


def _script(cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, str(ROOT / "scripts" / "sph_compare_kramer.py"),
                           *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def damped_record(tmp_path_factory) -> Path:
    """A free decay z = Z0 exp(-zeta w t) cos(w_d t) with the experiment's T_d and zeta."""
    t = np.arange(0.0, 4.0, 0.002)
    wd = 2 * np.pi / T_D
    w = wd / np.sqrt(1 - ZETA ** 2)
    z = (Z0 * np.exp(-ZETA * w * t) * np.cos(wd * t))[:, None]
    zero = np.zeros_like(z)
    hist = make_history(t, z, zero, zero, {"F_tot": zero}, dof=["Heave"], mass=np.eye(1))
    path = tmp_path_factory.mktemp("record") / "damped.nc"
    to_netcdf(hist, path)
    return path


def test_table_fits_the_closed_form_and_earlier_curves_are_drawn_unchanged(tmp_path,
                                                                            damped_record):
    res = _script(tmp_path, f"{damped_record}:closed form", "--table",
                  "--with-curves", str(SHIPPED), "--png", "fig.png")
    assert res.returncode == 0, res.stderr
    row = next(line for line in res.stdout.splitlines() if line.startswith("| closed form |"))
    t_d, zeta = (float(c) for c in row.split("|")[2:4])
    assert t_d == pytest.approx(T_D, abs=2e-4) and zeta == pytest.approx(ZETA, abs=5e-4)
    new, old = read_netcdf(tmp_path / "fig.nc"), read_netcdf(SHIPPED)
    assert list(new["run"].values) == ["closed form", *old["run"].values]
    for run in old["run"].values:  # the earlier runs' curves, bit for bit
        np.testing.assert_array_equal(new["heave_over_H0"].sel(run=run).values,
                                      old["heave_over_H0"].sel(run=run).values)
    assert json.loads(new.attrs["run_inputs"])["SPH D/12"]["dp"] == 0.025
    assert any(str(SHIPPED) in spec for spec in json.loads(new.attrs["runs"]))
    assert (tmp_path / "fig.png").stat().st_size > 10_000


@pytest.mark.parametrize("extra, message", [
    (["--with-curves", "x.nc"], "error: sph_compare_kramer.py: --with-curves needs --png"),
    (["--with-curves", "RECORD", "--png", "f.png"], "not the figure data"),
])
def test_with_curves_refuses_bad_use_in_one_line(tmp_path, damped_record, extra, message):
    args = [str(damped_record) if a == "RECORD" else a for a in extra]
    res = _script(tmp_path, str(damped_record), *args)
    assert res.returncode == cli.EXIT_ERROR
    assert message in res.stderr and res.stderr.count("\n") == 1, res.stderr
    assert not (tmp_path / "f.png").exists()
