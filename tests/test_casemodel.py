"""The case model (issue 28 items 1-2, issue 29's mooring option): a case's force components
built in one place, each recorded in the history, line tensions of every mooring model,
``simulate --case NAME|FILE``."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from hybridwsi import casemodel, waves
from hybridwsi.casemodel import CaseModel, case_components, linear_components
from hybridwsi.cases import case_path, from_dict, load_case, raw_case
from hybridwsi.cli import main
from hybridwsi.errors import InputError
from hybridwsi.files import read_netcdf
from hybridwsi.forces import Hydrostatic, LinearDamping, MooringForce, MorisonDrag
from hybridwsi.forces.mooring import LineTensions, MooringSystem, QuasiStaticMooring

pytest.importorskip("moorpy")

DOFS = ("Surge", "Heave", "Pitch")


@pytest.fixture(scope="module")
def oc3():
    return load_case("oc3_hywind")


@pytest.fixture(scope="module")
def model(oc3) -> CaseModel:
    return CaseModel.build(oc3, dt=0.1)


def test_components_follow_the_forces_table(oc3):
    comps = case_components(oc3, DOFS)
    assert list(comps) == ["mooring", "morison", "rotor", "linear_damping"]
    assert isinstance(comps["mooring"], MooringForce) and isinstance(comps["morison"],
                                                                     MorisonDrag)
    assert isinstance(case_components(oc3, DOFS, mooring="quasi-static")["mooring"],
                      QuasiStaticMooring)
    assert case_components(load_case("paper_sphere"), ("Heave",)) == {}
    klin, damp = linear_components(oc3, DOFS)
    k6 = MooringSystem.from_case(oc3).stiffness()
    idx = [0, 2, 4]
    assert isinstance(klin, Hydrostatic) and isinstance(damp, LinearDamping)
    np.testing.assert_array_equal(klin.linear_coefficients(3)[2], k6[np.ix_(idx, idx)])
    # Table 4-2: B11 = 1e5 N s/m, B33 = 1.3e5 N s/m, no pitch damping
    np.testing.assert_array_equal(np.diag(damp.linear_coefficients(3)[1]), [1e5, 1.3e5, 0.0])


def test_tensions_of_the_table_and_of_moorpy_agree(oc3):
    """Fairlead and anchor tensions of the interpolant (and the anchor from
    V_A = max(V_F - w L, 0)) against MoorPy's own line solution (Line.TB, Line.TA) at random
    states of the table's box: within 1e-3 (measured 2.3e-4)."""
    system = MooringSystem.from_case(oc3)
    table = MooringForce.from_case(oc3).table
    rng = np.random.default_rng(7)
    box = np.array([40.0, 20.0, 6.0, 0.1, 0.15, 0.15])
    q = rng.uniform(-0.95, 0.95, (25, 6)) * box
    ref = []
    for state in q:
        system.force6(state)
        ref.append(system.tensions())
    ref = np.array(ref)
    got = table.tensions(q)
    assert got.shape == (25, 3, 2)
    assert np.max(np.abs(got - ref) / ref) < 1e-3
    # at rest: every line alike; the anchor end lies on the seabed, so T_anchor = H
    system.force6(np.zeros(6))
    rest = system.tensions()
    np.testing.assert_allclose(table.tensions(np.zeros(6)), rest, rtol=1e-4)
    assert np.ptp(rest[:, 0]) < 1e-3 * rest[0, 0]
    # Jonkman 2010 Eq. 5-2: the vertical preload 1 607 kN shared by three lines; with the
    # horizontal tension (= T_anchor on the seabed) the fairlead tension is their hypot
    assert rest[0, 0] == pytest.approx(np.hypot(rest[0, 1], 1_607_000 / 3), rel=1e-3)


def test_simulate_records_each_component_and_the_tensions(model):
    wave = waves.JONSWAP(hs=4.0, tp=10.0, seed=1)
    hist = model.simulate(duration=60.0, dt=0.1, wave=wave, ramp=10.0)
    comps = ["F_mooring", "F_morison", "F_rotor", "F_damping"]
    total = sum(hist[c].values for c in comps)
    assert np.max(np.abs(total - hist["F_ext"].values)) <= 1e-12 * np.abs(
        hist["F_ext"].values).max()
    assert hist.attrs["components_residual"] < 1e-12
    for c in comps:
        assert json.loads(hist[c].attrs["units_per_dof"]) == ["N", "N", "N m"]
        assert hist[c].attrs["role"] == "force"
    assert hist["T_fairlead"].dims == ("time", "line") and hist["T_fairlead"].attrs["units"] == "N"
    assert list(hist["line"].values) == [1, 2, 3]
    # t = 0: the body at rest, the definition's pretension in every line
    np.testing.assert_allclose(hist["T_fairlead"].values[0], 911088.36, rtol=1e-4)
    # the Morison drag is the one component that depends on the waves: not zero
    assert np.abs(hist["F_morison"].values).max() > 0 and "eta" in hist
    case = json.loads(hist.attrs["case"])
    assert case["sha256"] == model.case.sha256 and case["models"]["mooring"] == "table"


def test_quasi_static_mooring_equals_the_table_to_its_interpolation_error(oc3, model):
    wave = waves.JONSWAP(hs=6.0, tp=10.0, seed=2)
    qs = CaseModel.build(oc3, dt=0.1, mooring="quasi-static")
    a = model.simulate(duration=30.0, dt=0.1, wave=wave, ramp=5.0)
    b = qs.simulate(duration=30.0, dt=0.1, wave=wave, ramp=5.0)
    assert b.attrs["components_residual"] < 1e-12
    assert np.max(np.abs(a["z"] - b["z"]).values / np.abs(a["z"]).values.max(axis=0)) < 1e-4
    np.testing.assert_allclose(a["T_fairlead"].values, b["T_fairlead"].values, rtol=1e-4)
    assert isinstance(b.attrs["case"], str) and "quasi-static" in b.attrs["case"]
    assert isinstance(qs.components()["mooring"], LineTensions)


def test_moordyn_without_its_module_is_one_line(tmp_path, monkeypatch):
    folder = tmp_path / "spar"
    folder.mkdir()
    (folder / "lines.dat").write_text("MoorDyn v2 input\n")
    raw = raw_case("oc3_hywind")
    raw["mooring"]["moordyn_file"] = "lines.dat"
    case = from_dict(raw, directory=folder)
    assert case["mooring"]["moordyn_file"] == str((folder / "lines.dat").resolve())
    monkeypatch.setattr(casemodel, "MOORDYN_MODULE", "hybridwsi.forces.no_such_module")
    with pytest.raises(InputError, match="MoorDyn mooring component .* not available"):
        case_components(case, DOFS, mooring="moordyn", dt=0.1)


def test_a_user_sphere_case_with_a_force_table(tmp_path):
    """A user's file beside its force table: a 10 N push ramped in over 2 s lifts the paper
    sphere by F/C once the radiation damping has settled it (C from the coefficients)."""
    folder = tmp_path / "sphere_case"
    folder.mkdir()
    (folder / "push.csv").write_text("time [s],F [N]\n0,0\n2,10\n100,10\n")
    text = case_path("paper_sphere").read_text()
    (folder / "pushed.toml").write_text(text.split("[regular_waves]")[0]
                                        + '[external_force]\nfile = "push.csv"\n'
                                        + "[simulation]\nduration = 15.0\ndt = 0.01\n")
    out = tmp_path / "h.nc"
    assert main(["simulate", "--case", str(folder / "pushed.toml"), "--out", str(out),
                 "--quiet"]) == 0
    hist = read_netcdf(out)
    c = float(hist["hydrostatic_stiffness"].values[0, 0])  # the coefficients' C [N/m]
    assert float(hist["time"][-1]) == 15.0
    assert hist["F_external"].values[-1, 0] == pytest.approx(10.0)
    assert hist["z"].values[-1, 0] == pytest.approx(10.0 / c, rel=1e-2)


def test_simulate_a_copy_of_a_builtin_case_from_another_folder(tmp_path, capsys):
    user = tmp_path / "elsewhere"
    user.mkdir()
    shutil.copy(case_path("oc3_hywind"), user / "my_spar.toml")
    common = ["simulate", "--jonswap", "4", "10", "--seed", "1", "--duration", "20",
              "--dt", "0.1", "--ramp", "5"]
    assert main([*common, "--case", str(user / "my_spar.toml"), "--out",
                 str(tmp_path / "a.nc")]) == 0
    printed = capsys.readouterr().out
    assert "F_mooring, F_morison, F_rotor, F_damping" in printed
    assert "max fairlead tension per line" in printed
    assert main([*common, "--case", "oc3_hywind", "--quiet", "--out",
                 str(tmp_path / "b.nc")]) == 0
    a, b = read_netcdf(tmp_path / "a.nc"), read_netcdf(tmp_path / "b.nc")
    np.testing.assert_array_equal(a["z"].values, b["z"].values)
    assert json.loads(a.attrs["case"])["sha256"] == json.loads(b.attrs["case"])["sha256"]


def test_an_oblique_sea_on_the_spar_is_the_head_sea_turned(model):
    """The spar is a body of revolution: a 30° wave's excitation is the head-sea one turned
    by 30° (surge cos 30°, sway sin 30°, pitch cos 30°, roll −sin 30°), not interpolated."""
    coeffs = model.coeffs
    head = waves.excitation_transfer(coeffs, ["Surge", "Pitch"], [0.0])[1][:, 0]
    beta = np.radians(30.0)
    dofs = ["Surge", "Sway", "Roll", "Pitch"]
    turned = waves.excitation_transfer(coeffs, dofs, [beta])[1][:, 0]
    scale = np.abs(head).max(axis=0)
    np.testing.assert_allclose(turned[:, 0] / scale[0], np.cos(beta) * head[:, 0] / scale[0],
                               atol=1e-12)
    np.testing.assert_allclose(turned[:, 1] / scale[0], np.sin(beta) * head[:, 0] / scale[0],
                               atol=1e-12)
    np.testing.assert_allclose(turned[:, 3] / scale[1], np.cos(beta) * head[:, 1] / scale[1],
                               atol=1e-12)
    np.testing.assert_allclose(turned[:, 2] / scale[1], -np.sin(beta) * head[:, 1] / scale[1],
                               atol=1e-12)


def test_a_heading_the_coefficients_lack_is_refused(model):
    """Without a known symmetry (no body record) one stored heading covers no other."""
    coeffs = model.coeffs.copy()
    coeffs.attrs = {k: v for k, v in coeffs.attrs.items() if k != "body"}
    with pytest.raises(InputError, match="no excitation force for wave direction 0.5235.* rad"):
        waves.excitation_transfer(coeffs, ["Surge"], [np.radians(30.0)])


def test_decay_per_dof_and_the_refusals(tmp_path, capsys):
    out = tmp_path / "d.nc"
    assert main(["simulate", "--case", "oc3_hywind", "--decay", "2,0.5,0.01", "--duration", "5",
                 "--dt", "0.1", "--quiet", "--out", str(out)]) == 0
    np.testing.assert_allclose(read_netcdf(out)["z"].values[0], [2.0, 0.5, 0.01])
    bad = {
        ("--case", "oc3_hywind", "--mass", "5e6"): "--case takes the body",
        ("--case", "oc3_hywind", "--decay", "1,2"): "--decay takes one value or one per DOF",
        ("--coeffs", str(tmp_path / "none.nc"), "--mooring", "table"): "--mooring needs --case",
        ("--case", "paper_sphere", "--mooring", "table"): "no [mooring] table",
    }
    for argv, words in bad.items():
        rc = main(["simulate", *argv, "--duration", "1", "--out", str(tmp_path / "x.nc")])
        err = capsys.readouterr().err
        assert rc == 2 and err.count("\n") == 1 and words in err, err
    assert not (tmp_path / "x.nc").exists()
