"""OC4-DeepCwind semi-submersible: the case as a body, its mass properties and hydrostatics
against the definition, the panel mesh and its quality (issue 30 items 1-2).

References: the definition (Robertson et al. 2014, NREL/TP-5000-60601: Table 3-3, Eq. 4-3, as
cited in ``cases/oc4_semi.toml``), the OpenFAST deck's own composition of the platform (ElastoDyn
steel + HydroDyn filled members), and closed-form cylinder geometry.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from hybridwsi.bodies import ColumnsBody, Member, RigidAssembly, body_from_dict
from hybridwsi.bodies.assembly import MassItem, combine
from hybridwsi.bodies.quality import mesh_quality
from hybridwsi.casemodel import bem_arguments, body_from_case
from hybridwsi.cases import from_dict, load_case, raw_case
from hybridwsi.errors import InputError

CASE = load_case("oc4_semi")
RHO, G = 1025.0, 9.80665


@pytest.fixture(scope="module")
def body() -> RigidAssembly:
    return body_from_case(CASE)


# ------------------------------------------------------------------------- mass properties
def deck_platform() -> tuple[float, np.ndarray, np.ndarray]:
    """The platform as the OpenFAST deck builds it: ElastoDyn's steel (PtfmMass 3 852 180 kg,
    PtfmCMzt -8.6588 m, PtfmRIner = PtfmPIner 2.56193e9, PtfmYIner 4.24265e9 kg m²) plus
    HydroDyn's filled members (water 1025 kg/m³ inside the upper columns, inner diameter
    12 - 2 x 0.06 m, from -14 m up to FillFSLoc -6.17 m, and the base columns, 24 - 2 x 0.06 m,
    from -19.94 m to -14.89 m), which HydroDyn carries as translating masses (no rotational
    inertia of their own)."""
    items = [MassItem("steel", 3_852_180.0, (0.0, 0.0, -8.6588),
                      (2.56193e9, 2.56193e9, 4.24265e9))]
    for k, (x, y) in enumerate(((-28.86751, 0.0), (14.43376, 25.0), (14.43376, -25.0))):
        for part, (r, z0, z1) in (("upper", (5.94, -14.0, -6.17)),
                                  ("base", (11.94, -19.94, -14.89))):
            items.append(MassItem(f"{part}_{k}", RHO * math.pi * r**2 * (z1 - z0),
                                  (x, y, 0.5 * (z0 + z1))))
    return combine(items)


def test_platform_item_is_the_decks_steel_plus_ballast():
    """Table 3-3 (mass 1.3473e7 kg, CM -13.46 m, roll = pitch 6.827e9, yaw 1.226e10 kg m²)
    against the deck's composition: within 0.5 % (measured: +0.02 %, 0.00 %, -0.38 %, +0.02 %)."""
    (platform,) = [it for it in CASE["body"]["items"] if it["name"] == "platform"]
    mass, cog, inertia = deck_platform()
    assert mass == pytest.approx(platform["mass"], rel=0.005)
    assert cog[2] == pytest.approx(platform["cm"][2], rel=0.005)
    assert np.allclose(cog[:2], 0.0, atol=1e-4)
    assert np.diag(inertia) == pytest.approx(platform["inertia"], rel=0.005)


def test_case_body_is_the_assembly_of_the_definition(body):
    items = CASE["body"]["items"]
    mass = sum(it["mass"] for it in items)
    assert isinstance(body, RigidAssembly) and isinstance(body.hull, ColumnsBody)
    assert body.mass == pytest.approx(mass, rel=1e-12) == pytest.approx(14_072_718.0, rel=1e-9)
    zg = sum(it["mass"] * it["cm"][2] for it in items) / mass
    assert body.cog[2] == pytest.approx(zg, rel=1e-12)
    assert tuple(body.reference_point) == (0.0, 0.0, 0.0)
    assert (body.rho, body.g) == (RHO, G)
    assert body.hull.mass == 13_473_000.0 and len(body.items) == 3  # platform is the hull's
    # roll inertia about the SWL: platform (own + m z²) + the turbine's point masses + rotor
    ixx = (6.827e9 + 13_473_000.0 * 13.46**2 + 249_718.0 * 43.4**2 + 240_000.0 * 89.35**2
           + 110_000.0 * 90.0**2 + 38_759_236.0)
    assert body.mass_matrix()[3, 3] == pytest.approx(ixx, rel=1e-9)
    assert body_from_dict(json.loads(body.to_json())) == body


def test_vertical_balance_leaves_the_mooring_pretension(body):
    """Buoyancy exceeds the weight by 1.89 MN (192 t): the three lines' vertical pull at rest
    (tests/test_oc4_forces.py checks it against MoorPy)."""
    excess = RHO * body.displaced_volume() - body.mass
    assert 1.8e5 < excess < 2.1e5


# ------------------------------------------------------------------------- hydrostatics
def test_hydrostatics_against_the_definition(body):
    """Displacement (PtfmVol0), C33 and C44 = C55 without the weight term (Eq. 4-3) within 1 %
    (measured +0.02 %, -0.40 %, +0.93 %)."""
    hyd = CASE["hydrodynamics"]
    vol = body.displaced_volume()
    assert vol == pytest.approx(hyd["displaced_volume"], rel=0.01)
    c = body.hydrostatic_stiffness()
    assert c[2, 2] == pytest.approx(hyd["C33"], rel=0.01)
    wp, zb = body.waterplane_moments(), body.center_of_buoyancy()[2]
    for k, (second, name) in enumerate(((wp.syy, "C44"), (wp.sxx, "C55"))):
        without_weight = RHO * G * (second + vol * zb)
        assert without_weight == pytest.approx(hyd[name], rel=0.01)
        weight = -body.mass * G * body.cog[2]
        assert c[3 + k, 3 + k] == pytest.approx(without_weight + weight, rel=1e-12)
    # symmetric platform: no heave-roll/pitch coupling (C35 = 51 N/rad from the deck's
    # 5-digit column positions: 14.43376 against 28.86751 / 2), roll = pitch
    assert abs(c[2, 3]) < 1e-9 * c[2, 2] and abs(c[2, 4]) < 1e-4 * c[2, 2]
    assert c[3, 3] == pytest.approx(c[4, 4], rel=1e-5)


def test_columns_and_members_closed_forms():
    """Column volumes (π r² h per stage), the inclined brace cut by the free surface and its
    elliptical waterplane."""
    hull = body_from_case(CASE).hull
    parts = hull.volume_parts()
    assert parts["column (0, 0)"][0] == pytest.approx(math.pi * 3.25**2 * 20, rel=1e-12)
    offset = math.pi * (12**2 * 6 + 6**2 * 14)
    assert parts["column (-28.8675, 0)"][0] == pytest.approx(offset, rel=1e-12)
    zc = -(math.pi * 12**2 * 6 * 17 + math.pi * 36 * 14 * 7) / offset
    assert parts["column (-28.8675, 0)"][1][2] == pytest.approx(zc, rel=1e-12)
    (brace,) = [m for m in hull.members if m.name == "cross_brace_2"]
    a, b = (np.array(p) for p in brace.ends)
    wet = np.linalg.norm(b - a) * 16.2 / 25.33
    assert parts["cross_brace_2"][0] == pytest.approx(math.pi * 0.8**2 * wet, rel=1e-12)
    # waterplane: 4 circles + 3 brace ellipses pi R^2 / cos(phi), cos(phi) = dz / length
    braces = [m for m in hull.members if m.name.startswith("cross_brace")]
    area = math.pi * (3.25**2 + 3 * 6**2) + sum(
        math.pi * 0.8**2 * math.dist(*m.ends) / 25.33 for m in braces)
    assert hull.waterplane_moments().area == pytest.approx(area, rel=1e-12)


def test_member_and_body_checks():
    good = {"name": "c", "ends": [[0, 0, -10], [0, 0, 5]], "diameter": 2.0, "potential": True,
            "cd": 0.6}
    assert Member.from_dict(good).to_dict() == {  # Morison coefficients are not geometry
        "name": "c", "ends": [[0.0, 0.0, -10.0], [0.0, 0.0, 5.0]], "diameter": 2.0,
        "potential": True}
    tilted = {**good, "ends": [[0, 0, -10], [1, 0, 5]]}
    with pytest.raises(InputError, match="vertical"):
        ColumnsBody([tilted], mass=1.0, cog=(0, 0, 0))
    gap = [good, {**good, "name": "d", "ends": [[0, 0, -20], [0, 0, -11]]}]
    with pytest.raises(InputError, match="end to end"):
        ColumnsBody(gap, mass=1.0, cog=(0, 0, 0))
    with pytest.raises(InputError, match="unknown|cannot build"):
        Member.from_dict({**good, "colour": "red"})
    with pytest.raises(InputError, match="symmetry = 3"):
        ColumnsBody([good], mass=1.0, cog=(0, 0, 0), symmetry=3)
    with pytest.raises(InputError, match="coincident"):
        Member("x", ((0, 0, 0), (0, 0, 0)), 1.0)


# ------------------------------------------------------------------------- the mesh
@pytest.mark.parametrize("panel_size", [3.0, pytest.param(1.0, marks=pytest.mark.slow)])
def test_mesh_is_watertight_outward_and_holds_the_displacement(body, panel_size):
    """Closed up to the waterline, consistently oriented, normals into the water; volume within
    1 % of the columns' exact one and of the definition's displacement less the slender
    members (which are not meshed); the symmetric mesh equals the full one."""
    hull, lid = body.mesh(panel_size=panel_size)
    q = mesh_quality(hull)
    assert q.watertight and q.outward
    assert q.boundary_edges > 0 and q.boundary_edges_off_waterline == 0
    assert q.max_panel_size < 1.5 * math.sqrt(2) * panel_size
    columns = sum(v for k, (v, _) in body.hull.volume_parts().items() if k.startswith("column"))
    slender = body.displaced_volume() - columns
    assert q.volume == pytest.approx(columns, rel=0.01)
    assert q.volume == pytest.approx(CASE["hydrodynamics"]["displaced_volume"] - slender,
                                     rel=0.01)
    assert q.waterline_length == pytest.approx(2 * math.pi * (3.25 + 3 * 6.0), rel=0.01)
    full, _ = body.mesh(panel_size=panel_size, symmetric=False)
    assert type(hull).__name__ == "RotationSymmetricMesh" and full.nb_faces == hull.nb_faces
    assert full.volume == pytest.approx(q.volume, rel=1e-9)
    lid_full = lid.merged()
    assert np.all(lid_full.faces_normals[:, 2] < -0.999)  # the lid's normals point down
    assert np.sum(lid_full.faces_areas) == pytest.approx(full.waterplane_area, rel=1e-9)


def test_mesh_hydrostatics_follow_the_exact_ones(body):
    """Capytaine's mesh integrals (columns only) against the exact frusta of the columns."""
    hull, _ = body.mesh(panel_size=2.0, symmetric=False)
    wp = hull.waterplane_area
    assert wp == pytest.approx(math.pi * (3.25**2 + 3 * 36.0), rel=0.01)
    cob = hull.center_of_buoyancy
    assert cob[2] == pytest.approx(-(math.pi * 3.25**2 * 20 * 10 + 3 * math.pi * (
        144 * 6 * 17 + 36 * 14 * 7)) / (math.pi * 3.25**2 * 20 + 3 * math.pi * (
            144 * 6 + 36 * 14)), rel=0.005)


def test_bem_tables_of_the_case():
    args = bem_arguments(CASE)
    assert args["wave_directions"] == pytest.approx(np.radians([0.0, 30.0, 60.0]))
    assert args["water_depth"] == 200.0 and args["panel_size"] == 1.25
    assert bem_arguments(CASE, "bem_quick")["panel_size"] == 3.0
    raw = raw_case("oc4_semi")
    raw["bem"]["wave_directions_deg"] = ["x"]
    with pytest.raises(InputError, match="bem.wave_directions_deg"):
        from_dict(raw)  # the schema refuses it, naming the key
    raw = raw_case("oc4_semi")
    raw["body"]["hull"]["members"][0]["ends"] = [[0.0, 0.0, -20.0]]
    with pytest.raises(InputError, match="members"):
        from_dict(raw)
