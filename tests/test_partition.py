"""Component selection: analytic partitions of a Cummins history, and the select CLI."""

from __future__ import annotations

import json

import pytest
import synthetic_hydro as sh

from hybridwsi import cummins, waves
from hybridwsi.cli import main
from hybridwsi.diagnostic.partition import enumerate_partitions, select_partition
from hybridwsi.errors import InputError
from hybridwsi.history import to_netcdf


@pytest.fixture(scope="module")
def hist():
    return cummins.simulate(sh.coefficients(), duration=20.0, dt=0.01, ramp=2.0,
                            wave=waves.JONSWAP(hs=0.05, tp=0.8, seed=0))


def test_enumeration_excludes_double_radiation_damping():
    parts = enumerate_partitions(["hydrostatic", "radiation_memory", "linear_damping"])
    assert ("radiation_memory", "linear_damping") not in parts
    assert () in parts and ("hydrostatic", "radiation_memory") in parts
    assert len(parts) == 6


def test_selection_matches_theory(hist):
    cands = ["hydrostatic", "added_mass_inf", "radiation_memory", "excitation"]
    table = select_partition(hist, sh.coefficients(), cands, dt=0.01).set_index("partition")
    # Table 1 / THEORY §1: without the excitation known, F_bb is the tautology m z'' + ... :
    row = table.loc["hydrostatic"]
    assert row["alpha"] == pytest.approx(sh.M, rel=1e-6) and row["gamma"] == pytest.approx(sh.C, rel=1e-6)
    assert row["added_mass_ratio"] == pytest.approx(1.0, rel=1e-6) and not row["feasible"]
    row = table.loc["hydrostatic+added_mass_inf"]
    assert row["alpha"] == pytest.approx(sh.M + sh.A_INF, rel=1e-6) and not row["feasible"]
    # excitation known, A∞ left to the residual: alpha ≈ -A∞ (the added mass), ratio A∞/m
    row = table.loc["hydrostatic+radiation_memory+excitation"]
    assert row["alpha"] == pytest.approx(-sh.A_INF, rel=0.01)
    assert row["added_mass_ratio"] == pytest.approx(sh.A_INF / sh.M, rel=0.01)
    # everything known: nothing left, residual sensitivities ≈ 0 and exact reconstruction
    row = table.loc["hydrostatic+added_mass_inf+radiation_memory+excitation"]
    assert abs(row["alpha"]) < 0.02 * sh.M and abs(row["gamma"]) < 0.01 * sh.C
    assert row["feasible"] and row["recon_nrms"] < 0.01
    best = table[table["rank"] == 1]
    assert bool(best["feasible"].iloc[0])
    assert "excitation" in best.index[0]  # only excitation-known partitions escape ratio 1
    assert (table[~table["feasible"]]["rank"].min() > table[table["feasible"]]["rank"].max())


def test_select_cli_writes_json(tmp_path, hist, capsys):
    f, c, out = tmp_path / "h.nc", tmp_path / "c.nc", tmp_path / "sel.json"
    to_netcdf(hist, f)
    to_netcdf(sh.coefficients(), c)
    rc = main(["select", str(f), "--coeffs", str(c), "--candidates",
               "hydrostatic,added_mass_inf,excitation", "--no-reconstruct", "--json", str(out)])
    assert rc == 0
    doc = json.loads(out.read_text())
    assert len(doc["partitions"]) == 8 and doc["partitions"][0]["rank"] == 1
    assert "hybridwsi_version" in doc and "hydrostatic" in capsys.readouterr().out


def test_select_errors(tmp_path, hist, capsys):
    bare = hist.drop_vars(["hydrostatic_stiffness", "added_mass_inf"], errors="ignore")
    with pytest.raises(InputError, match="not available"):
        select_partition(bare, None, ["hydrostatic"])
    assert main(["select", str(tmp_path / "missing.nc")]) == 2
    assert "error:" in capsys.readouterr().err
