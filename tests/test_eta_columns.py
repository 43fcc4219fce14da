"""Wave-elevation columns in tabular data (issue 28 item 6): ``--eta COL`` of ``import``,
``diagnose`` and ``hybrid`` from CSV (units in the header) and OpenFAST (``Wave1Elev``)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from hybridwsi import history as h
from hybridwsi import importers as im
from hybridwsi.cli import main
from hybridwsi.errors import InputError
from hybridwsi.files import read_netcdf

T = np.arange(0.0, 20.0, 0.05)
ETA = 0.3 * np.cos(2 * np.pi * T / 4.0)
Z = 0.02 * np.sin(2 * np.pi * T / 4.0)


def _csv(path: Path, eta_header: str = "wave [mm]", scale: float = 1e3) -> Path:
    np.savetxt(path, np.column_stack([T, Z, scale * ETA, 10 * Z]), delimiter=",",
               fmt="%.17g", header=f"time [s],z [m],{eta_header},F_tot [N]", comments="")
    return path


def test_csv_eta_column_with_its_unit(tmp_path):
    ds = h.read_csv(_csv(tmp_path / "tank.csv"), eta="wave")
    assert ds["eta"].dims == ("time", "probe") and list(ds["probe"].values) == ["wave"]
    np.testing.assert_allclose(ds["eta"].values[:, 0], ETA, rtol=1e-14)
    assert ds["eta"].attrs["units"] == "m"
    assert set(h.force_names(ds)) == {"F_tot"}  # the elevation is neither force nor extra
    # a column called eta is found without asking; to_csv writes it back that way
    plain = h.read_csv(_csv(tmp_path / "plain.csv", "eta [m]", 1.0))
    np.testing.assert_array_equal(plain["eta"].values[:, 0], ETA)
    h.to_csv(ds, tmp_path / "back.csv")
    back = h.read_csv(tmp_path / "back.csv")
    np.testing.assert_array_equal(back["eta"].values, ds["eta"].values)
    for header, words in (("wave [N]", "not a length"), ("wave [m]", "'swell' not found")):
        with pytest.raises(InputError, match=words):
            h.read_csv(_csv(tmp_path / "bad.csv", header), eta="swell" if "m]" in header
                       else "wave")


def test_import_and_diagnose_take_eta(tmp_path, capsys):
    src = _csv(tmp_path / "tank.csv")
    out = tmp_path / "tank.nc"
    assert main(["import", str(src), "--eta", "wave", "--out", str(out)]) == 0
    assert "wave elevation: wave" in capsys.readouterr().out
    np.testing.assert_allclose(read_netcdf(out)["eta"].values[:, 0], ETA, rtol=1e-14)
    assert main(["diagnose", str(src), "--eta", "wave", "--mass", "1", "--quiet"]) == 0
    assert main(["import", str(src), "--eta", "swell", "--out", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "wave-elevation column 'swell' not found" in err
    assert not (tmp_path / "x.nc").exists()


def test_openfast_eta_channel(tmp_path):
    pytest.importorskip("openfast_io")
    sys.path.insert(0, str(Path(__file__).parent))
    from test_openfast import platform_channels, write_out

    t = np.arange(0.0, 60.0, 0.1)
    ch = platform_channels(t)
    ch["Wave1Elev"] = ("m", 2.0 * np.cos(0.5 * t))
    ch["Wave2Elev"] = ("m", 1.0 * np.sin(0.5 * t))
    path = write_out(tmp_path / "run.out", ch)
    both = im.read_openfast(path)
    assert both.sizes["probe"] == 2
    one = im.read_history(path, eta="Wave2Elev")
    assert one.sizes["probe"] == 1 and list(one["probe"].values) == ["Wave2Elev"]
    np.testing.assert_allclose(one["eta"].values[:, 0], np.sin(0.5 * t), atol=1e-3)
    with pytest.raises(InputError, match="no wave-elevation channel 'Wave9Elev'"):
        im.read_openfast(path, eta="Wave9Elev")
    # the same file as a wave-elevation record (simulate --wave-elevation)
    tt, eta, name = im.read_elevation(path)
    assert name == "run.out:Wave1Elev"
    np.testing.assert_allclose(eta, 2.0 * np.cos(0.5 * tt), atol=1e-3)
