"""Case files (issue 28 item 1): one schema, checked recursively; a corpus of broken case
files each refused in one line naming the file and the key; units; relative paths; the
canonical content hash."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from hybridwsi.casemodel import body_from_case
from hybridwsi.cases import (
    available,
    case_path,
    from_dict,
    load_case,
    mooring_model,
    raw_case,
)
from hybridwsi.cases.schema import CASE, Number, Table, iter_nodes
from hybridwsi.cli import main
from hybridwsi.errors import InputError
from hybridwsi.units import convert_unit, parse_unit

OC3_TEXT = case_path("oc3_hywind").read_text()
SPHERE_TEXT = """\
name = "my_sphere"
[body]
type = "sphere"
radius = 0.15
mass = 7.06
rho = 998.2
g = 9.81
[bem]
omega_min = 0.1
omega_max = 40.0
n_omega = 12
n_panels = 400
"""


def _edit(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


#: id -> (case text, words the one error line must contain: the key and the problem)
BROKEN: dict[str, tuple[str, tuple[str, ...]]] = {
    "unknown-top-key": ('colour = "red"\n' + OC3_TEXT, ("colour", "unknown key",
                                                         "allowed in the top level")),
    "unknown-table": (OC3_TEXT + "\n[wind]\nspeed = 11.4\n", ("wind", "unknown key")),
    "unknown-nested-key": (_edit(OC3_TEXT, "n_lines = 3", "n_lines = 3\nstiffness = 1.0"),
                           ("mooring.stiffness", "unknown key")),
    "unknown-hull-key": (_edit(OC3_TEXT, 'structure = "platform"',
                               'structure = "platform"\ncolour = "yellow"'),
                         ("body.hull.colour", "unknown key")),
    "missing-EA": (_edit(OC3_TEXT, "EA = 384243000.0", ""), ("mooring.EA", "missing")),
    "missing-body": ('name = "x"\n', ("body", "missing")),
    "empty-file": ("", ("body", "missing")),
    "missing-radius": (_edit(SPHERE_TEXT, "radius = 0.15\n", ""), ("body.radius", "missing")),
    "EA-text": (_edit(OC3_TEXT, "EA = 384243000.0", 'EA = "stiff"'),
                ("mooring.EA", "expected a number [N]")),
    "depth-in-seconds": (_edit(OC3_TEXT, "water_depth = 320.0           # m\n",
                               'water_depth = "320 s"\n'),
                         ("environment.water_depth", "'s' is not a unit of m")),
    "depth-unknown-unit": (_edit(OC3_TEXT, "water_depth = 320.0           # m\n",
                                 'water_depth = "320 parsec"\n'),
                           ("environment.water_depth", "unknown unit 'parsec'")),
    "damping-rotation-in-linear-unit": (
        _edit(OC3_TEXT, "Yaw = 13000000.0 }", 'Yaw = "1.3e7 N s/m" }'),
        ("hydrodynamics.additional_damping.Yaw", "not a unit of N m s/rad")),
    "rho-negative": (_edit(SPHERE_TEXT, "rho = 998.2", "rho = -998.2"),
                     ("body.rho", "must be > 0")),
    "g-nan": (_edit(SPHERE_TEXT, "g = 9.81", "g = nan"), ("body.g", "NaN")),
    "EA-inf": (_edit(OC3_TEXT, "EA = 384243000.0", "EA = inf"), ("mooring.EA", "finite")),
    "n-lines-bool": (_edit(OC3_TEXT, "n_lines = 3", "n_lines = true"),
                     ("mooring.n_lines", "expected an integer")),
    "n-lines-fraction": (_edit(OC3_TEXT, "n_lines = 3", "n_lines = 2.5"),
                         ("mooring.n_lines", "integer")),
    "n-omega-one": (_edit(SPHERE_TEXT, "n_omega = 12", "n_omega = 1"),
                    ("bem.n_omega", ">= 2")),
    "body-type-unknown": (_edit(SPHERE_TEXT, 'type = "sphere"', 'type = "submarine"'),
                          ("body.type", "submarine")),
    "dof-unknown": (_edit(OC3_TEXT, 'default_dofs = ["Surge", "Heave", "Pitch"]',
                          'default_dofs = ["Surge", "Wobble"]'),
                    ("default_dofs[1]", "DOF name")),
    "default-dofs-outside-dofs": (
        _edit(OC3_TEXT, 'dofs = ["Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"]',
              'dofs = ["Surge", "Heave"]'),
        ("default_dofs", "Pitch not among the case's dofs")),
    "profile-point-of-three": (_edit(OC3_TEXT, "[0.0, -120.0],", "[0.0, -120.0, 1.0],"),
                               ("body.hull.profile[0]", "expected 2 entries")),
    "profile-z-decreasing": (_edit(OC3_TEXT, "[3.25, 10.0],", "[3.25, -20.0],"),
                             ("body.hull.profile", "must not decrease")),
    "reference-point-short": (_edit(OC3_TEXT, "reference_point = [0.0, 0.0, 0.0]",
                                    "reference_point = [0.0, 0.0]"),
                              ("body.reference_point", "expected 3 entries")),
    "item-without-mass": (_edit(OC3_TEXT, "mass = 249718.0\n", ""),
                          ("body.items[1].mass", "missing")),
    "omega-max-below-min": (_edit(SPHERE_TEXT, "omega_max = 40.0", "omega_max = 0.05"),
                            ("bem.omega_max", "above omega_min")),
    "panels-twice": (_edit(SPHERE_TEXT, "n_panels = 400", "n_panels = 400\npanel_size = 0.01"),
                     ("bem", "at most one of panel_size, n_panels")),
    "morison-without-drag": (SPHERE_TEXT + "[forces]\nmorison = true\n",
                             ("forces.morison", "no [hydrodynamics] drag_cd")),
    "mooring-model-unknown": (OC3_TEXT + '\n[forces]\nmooring = "elastic"\n',
                              ("forces.mooring", "'elastic'")),
    "moordyn-without-input": (_edit(OC3_TEXT, 'moordyn_file = "oc3_hywind_moordyn.dat"\n', "")
                              + '\n[forces]\nmooring = "moordyn"\n',
                              ("forces.mooring", "needs [mooring] moordyn_file")),
    "moordyn-input-missing": (_edit(OC3_TEXT, 'moordyn_file = "oc3_hywind_moordyn.dat"',
                                    'moordyn_file = "lines/nowhere.dat"'),
                              ("mooring.moordyn_file", "MoorDyn input file 'lines/nowhere.dat' "
                                                       "not found")),
    "mooring-without-table": (SPHERE_TEXT + '[forces]\nmooring = "table"\n',
                              ("forces.mooring", "no [mooring] table")),
    "convolution-nonlinear": (SPHERE_TEXT + '[forces]\nhydrostatics = "nonlinear"\n'
                                            'radiation = "convolution"\n',
                              ("forces.radiation", "linear hydrostatics only")),
    "mesh-file-missing": (_edit(SPHERE_TEXT, 'type = "sphere"\nradius = 0.15',
                                'type = "mesh"\nmesh_file = "nowhere/hull.gdf"\ncog = [0, 0, 0]'),
                          ("body.mesh_file", "not found")),
    "force-table-missing": (SPHERE_TEXT + '[external_force]\nfile = "f.csv"\n',
                            ("external_force.file", "not found")),
    "damping-key-not-a-dof": (_edit(OC3_TEXT, "Surge = 100000.0, Sway", "Wobble = 1.0, Sway"),
                              ("hydrodynamics.additional_damping.Wobble", "DOF name")),
    "sweep-unknown-key": (_edit(OC3_TEXT, "duration = 3600.0", "hs = 4.0"),
                          ("sweep.hs", "unknown key")),
    "regular-period-text": (_edit(OC3_TEXT, "period = [2.0, 4.8,", 'period = ["two", 4.8,'),
                            ("regular_waves.period", "two")),
    "network-hidden-zero": (_edit(OC3_TEXT, "hidden = [32, 32]", "hidden = [32, 0]"),
                            ("hybrid.network.hidden[1]", ">= 1")),
    "inertia-not-3": (_edit(OC3_TEXT, "inertia = [0.0, 0.0, 0.0]", "inertia = [0.0, 0.0]"),
                      ("body.items[1].inertia", "3 principal moments")),
    "not-toml": ("[body\nradius = 1\n", ("not valid TOML",)),
    "duplicate-key": (SPHERE_TEXT + "[bem]\nn_omega = 3\n", ("not valid TOML",)),
}


@pytest.mark.parametrize("name", available())
def test_builtin_cases_are_valid(name):
    case = load_case(name)
    assert case.name == name and len(case.sha256) == 64
    assert case["forces"]["hydrostatics"] == "linear"
    body_from_case(case)  # every built-in body builds


@pytest.mark.parametrize("cid", sorted(BROKEN))
def test_broken_case_file_is_one_line_naming_file_and_key(cid, tmp_path):
    text, words = BROKEN[cid]
    path = tmp_path / f"{cid}.toml"
    path.write_text(text)
    with pytest.raises(InputError) as err:
        load_case(path)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(str(path)), msg
    for word in words:
        assert word in msg, (word, msg)


def test_binary_case_file_is_refused(tmp_path):
    path = tmp_path / "garbage.toml"
    path.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(InputError, match="garbage.toml: not a UTF-8"):
        load_case(path)
    with pytest.raises(InputError, match="not found"):
        load_case(tmp_path / "absent.toml")
    with pytest.raises(InputError, match="unknown case 'nope'"):
        load_case("nope")


@pytest.mark.parametrize("command", [
    ["simulate", "--duration", "1"], ["bem", "--quick"],
    ["sweep", "--hs", "1", "--tp", "10", "--scheduler", "synchronous"]])
def test_commands_refuse_a_broken_case_in_one_line(command, tmp_path, capsys):
    bad = tmp_path / "spar.toml"
    bad.write_text(BROKEN["EA-text"][0])
    out = tmp_path / "out"
    assert main([command[0], "--case", str(bad), *command[1:], "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"error: {bad}: mooring.EA:"), err
    assert not out.exists()


def test_units_in_values_are_converted_and_checked():
    assert parse_unit("N m s/rad") == (1.0, (1, 2, -1, -1))
    assert convert_unit(1.025, "t/m^3", "kg/m^3") == pytest.approx(1025.0)
    assert convert_unit(1.0, "kN m/deg", "N m/rad") == pytest.approx(1e3 * 180 / 3.141592653589793)
    for bad, to in (("s", "m"), ("N m", "N m/rad"), ("kg/m^2", "kg/m^3")):
        with pytest.raises(InputError, match="is not a unit of"):
            convert_unit(1.0, bad, to)
    raw = raw_case("oc3_hywind")
    raw["environment"].update(water_depth="1049.8688 ft", rho="1.025 t/m^3")
    raw["mooring"].update(line1_heading="0 rad", EA="384243 kN")
    raw["hydrodynamics"]["additional_damping"]["Yaw"] = "13000 kN m s/rad"
    case = from_dict(raw)
    assert case["environment"]["water_depth"] == pytest.approx(320.0, rel=1e-7)
    assert case["environment"]["rho"] == pytest.approx(1025.0)
    assert case["mooring"]["EA"] == pytest.approx(384243000.0)
    assert case["hydrodynamics"]["additional_damping"]["Yaw"] == pytest.approx(1.3e7)


def test_every_number_of_the_schema_says_its_unit():
    """Documentation contract: a number key without a unit is a pure number on purpose."""
    pure = {"drag_cd", "morison_ca", "deep_water_kh", "gamma", "hdx", "gain", "alpha_body",
            "lr", "input_noise", "val_fraction", "weight_decay", "perturbation",
            "turbulence_intensity", "pitch_ki",
            "cd", "ca",  # members' Morison coefficients (axial_cd: a list of them)
            "tol",  # [radiation] relative fit error
            "spreading"}  # [simulation] cos-2s exponent s
    for at, node in iter_nodes(CASE):
        if isinstance(node, Number) and not node.integer and node.unit == "":
            name = at[-1]
            assert name in pure or str(at[0]) in ("force_accuracy", "experiment") \
                or name in ("<name>", "[]"), at


def test_canonical_hash_ignores_place_name_and_spelling_and_sees_every_value(tmp_path):
    ref = load_case("oc3_hywind")
    copy = tmp_path / "elsewhere" / "my_spar.toml"
    copy.parent.mkdir()
    shutil.copy(case_path("oc3_hywind"), copy)
    mine = load_case(copy)
    assert mine.sha256 == ref.sha256 and mine.path == copy.resolve()
    assert mine == ref  # the same content
    # comments, key order, number spelling and units do not change it
    raw = raw_case("oc3_hywind")
    raw["environment"] = {"water_depth": "320 m", "g": 9.80665, "rho": 1025}
    raw = dict(reversed(list(raw.items())))
    assert from_dict(raw).sha256 == ref.sha256
    # any value does
    raw["mooring"]["EA"] = 384243001.0
    assert from_dict(raw).sha256 != ref.sha256
    # defaults written out or left to the schema are one case
    raw = raw_case("oc3_hywind")
    raw["forces"] = {"mooring": "table", "radiation": "statespace"}
    assert from_dict(raw).sha256 == ref.sha256
    raw["forces"]["mooring"] = "quasi-static"
    assert from_dict(raw).sha256 != ref.sha256


def test_paths_are_relative_to_the_case_file_and_hashed_by_content(tmp_path, monkeypatch):
    folder = tmp_path / "project"
    (folder / "data").mkdir(parents=True)
    (folder / "data" / "push.csv").write_text("time [s],F [kN]\n0,0\n10,1\n")
    path = folder / "sphere.toml"
    path.write_text(SPHERE_TEXT + '[external_force]\nfile = "data/push.csv"\n')
    monkeypatch.chdir(tmp_path)  # not the case's folder
    case = load_case(path)
    assert case["external_force"]["file"] == str((folder / "data" / "push.csv").resolve())
    assert case["forces"]["external_force"] is True
    # the same case moved with its file: the same hash; the file's content changed: another
    moved = tmp_path / "moved"
    shutil.copytree(folder, moved)
    assert load_case(moved / "sphere.toml").sha256 == case.sha256
    (moved / "data" / "push.csv").write_text("time [s],F [kN]\n0,0\n10,2\n")
    assert load_case(moved / "sphere.toml").sha256 != case.sha256


def test_forces_table_is_resolved_and_mooring_model_overridden():
    oc3, sphere = load_case("oc3_hywind"), load_case("paper_sphere")
    assert oc3["forces"] == {"hydrostatics": "linear", "radiation": "statespace",
                             "excitation": True, "mooring": "table", "morison": True,
                             "rotor": True, "linear_damping": True, "external_force": False,
                             "drift": False}
    assert sphere["forces"]["mooring"] == "none" and not sphere["forces"]["morison"]
    assert mooring_model(oc3) == "table"
    assert mooring_model(oc3, "quasi-static") == "quasi-static"
    raw = raw_case("oc3_hywind")
    raw["mooring"].pop("moordyn_file", None)
    with pytest.raises(InputError, match="no moordyn_file"):
        mooring_model(from_dict(raw), "moordyn")
    with pytest.raises(InputError, match="no \\[mooring\\] table"):
        mooring_model(sphere, "table")
    assert isinstance(CASE, Table) and json.dumps(oc3)  # plain values only


DOC = Path(__file__).resolve().parents[1] / "docs" / "CASES.md"


def test_docs_reference_is_the_schema_and_its_example_loads(tmp_path):
    from hybridwsi.cases.schema import markdown_reference

    text = DOC.read_text()
    block = text.split("<!-- schema reference: begin -->\n")[1].split(
        "<!-- schema reference: end -->")[0]
    assert block == markdown_reference()
    example = text.split("```toml\n")[1].split("```")[0]
    (tmp_path / "plate_spar.toml").write_text(example)
    case = load_case(tmp_path / "plate_spar.toml")
    assert case["environment"]["water_depth"] == 200.0
    assert case["hydrodynamics"]["additional_damping"] == {"Heave": 20000.0}
    assert case["forces"]["morison"] and case["forces"]["mooring"] == "none"
    body = body_from_case(case)
    # floating: the displaced mass of the profile
    assert body.mass == pytest.approx(1025.0 * body.displaced_volume(), rel=1e-12)
