"""Bodies: mass properties, hydrostatics and exact restoring checked against hand formulas, and
BEM coefficients of one cylinder made three ways (profile, mesh file, Capytaine's plain mesh).

Sign convention checked here (``hybridwsi.bodies.base``): matrices are ``M[influenced i,
radiating j]`` about the reference point O; a pitch rotation θ moves a point at r by
``θ (z - z_O, 0, -(x - x_O))``, so ``M[Surge, Pitch] = m (z_G - z_O)`` and
``M[Heave, Pitch] = -m (x_G - x_O)``.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import xarray as xr

from hybridwsi.bodies import (AxisymmetricBody, Body, FloatingSphere, MassItem, MeshBody,
                              RigidAssembly, body_from_dict, cap_volume)
from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.errors import InputError
from hybridwsi.hydro import bem, coefficients

RHO, G = 1025.0, 9.81
RHO_S, G_S = 998.2, 9.81                       # the paper's sphere
A_CYL, D_CYL, FREEBOARD = 1.0, 1.0, 0.5        # radius, draft, freeboard [m]
PANEL = 0.2                                    # -> 5 bottom rings, 5 side rows, 32 sectors
CYL_RES = (5, 32, 10)                          # Capytaine's (nr, ntheta, nz) of the same panels


def cylinder(**kw) -> AxisymmetricBody:
    args = dict(profile=[(0, -D_CYL), (A_CYL, -D_CYL), (A_CYL, FREEBOARD)], cog=(0, 0, -0.4),
                inertia=(300.0, 300.0, 200.0), rho=RHO, g=G)
    return AxisymmetricBody(**{**args, **kw})


def write_gdf(mesh, path) -> None:
    """A WAMIT GDF file (ULEN, g, no symmetry, one vertex per line) of a Capytaine mesh."""
    quads = mesh.vertices[mesh.faces]
    lines = ["cylinder from capytaine.mesh_vertical_cylinder", f"1.0 {G}", "0 0", str(len(quads))]
    lines += [f"{x:.16g} {y:.16g} {z:.16g}" for quad in quads for x, y, z in quad]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def cylinder_mesh_file(tmp_path_factory):
    import capytaine as cpt

    mesh = cpt.mesh_vertical_cylinder(length=2 * D_CYL, radius=A_CYL, center=(0, 0, 0),
                                      resolution=CYL_RES)
    path = tmp_path_factory.mktemp("meshes") / "cylinder.gdf"
    write_gdf(mesh, path)  # the whole cylinder: MeshBody clips it at z = 0
    return path


# ------------------------------------------------------------------------- hydrostatics
def test_cylinder_profile_hydrostatics_are_analytic():
    body = cylinder()  # default mass: floating in equilibrium
    vol, zb = math.pi * A_CYL**2 * D_CYL, -D_CYL / 2
    assert body.mass == pytest.approx(RHO * vol, rel=1e-12)
    assert body.displaced_volume() == pytest.approx(vol, rel=1e-12)
    np.testing.assert_allclose(body.center_of_buoyancy(), (0, 0, zb), atol=1e-12)
    assert body.wetted_area() == pytest.approx(math.pi * A_CYL**2 + 2 * math.pi * A_CYL * D_CYL)
    c = body.hydrostatic_stiffness(("Surge", "Heave", "Pitch"))
    assert c[1, 1] == pytest.approx(RHO * G * math.pi * A_CYL**2, rel=1e-12)
    c55 = RHO * G * (math.pi * A_CYL**4 / 4 + vol * zb) - body.mass * G * body.cog[2]
    assert c[2, 2] == pytest.approx(c55, rel=1e-9)
    assert np.all(c[0] == 0) and c[1, 2] == 0
    # in equilibrium the reference point's height does not matter; a horizontal offset x_O
    # moves the waterplane inertia (A x_O^2) and couples heave and pitch (C35 = rho g A x_O)
    shifted = cylinder(reference_point=(0.3, 0.0, 2.0)).hydrostatic_stiffness(("Heave", "Pitch"))
    area = math.pi * A_CYL**2
    assert shifted[1, 1] == pytest.approx(c55 + RHO * G * area * 0.3**2, rel=1e-9)
    assert shifted[0, 1] == shifted[1, 0] == pytest.approx(RHO * G * area * 0.3, rel=1e-12)


def test_sphere_pitch_stiffness_is_buoyancy_times_lever():
    # every pressure force passes through the centre: rotating about G, the buoyancy rho g V
    # acts at the lever z_centre - z_G = 0.0348 m and the weight has none
    k = FloatingSphere.kramer2021()
    c = k.hydrostatic_stiffness(("Roll", "Pitch"))
    assert np.allclose(np.diag(c), k.rho * k.g * k.displaced_volume() * 0.0348, rtol=1e-9)


def test_tapered_spar_volume_and_buoyancy_centre_against_quadrature():
    from scipy.integrate import quad

    profile = [(0, -12), (2.5, -12), (2.5, -10), (1.5, -9), (1.5, -4), (1.0, -2), (1.0, 3)]
    body = AxisymmetricBody(profile=profile, rho=RHO, g=G)
    rz = np.array(profile, dtype=float)[1:]  # radius as a function of z (monotonic part)

    def area(z):
        return math.pi * np.interp(z, rz[:, 1], rz[:, 0]) ** 2

    knots = list(rz[:, 1][rz[:, 1] < 0])
    vol = quad(area, -12, 0, points=knots, epsabs=0, epsrel=1e-13)[0]
    moment = quad(lambda z: z * area(z), -12, 0, points=knots, epsabs=0, epsrel=1e-13)[0]
    assert body.displaced_volume() == pytest.approx(vol, rel=1e-10)
    assert body.center_of_buoyancy()[2] == pytest.approx(moment / vol, rel=1e-10)
    assert body.waterline_radius == 1.0 and body.draft == 12.0
    # submerged volume after heaving 2.5 m up: the profile below z = -2.5
    v_up = quad(area, -12, -2.5, points=knots[:-1], epsabs=0, epsrel=1e-13)[0]
    assert body.submerged_volume(2.5) == pytest.approx(v_up, rel=1e-10)


def test_mesh_body_hydrostatics_match_capytaine_and_the_polygon(cylinder_mesh_file):
    # a 32-gon waterplane: area (n/2) a^2 sin(2 pi / n); Capytaine's own stiffness (with the
    # weight term) on the same mesh for an off-axis centre of mass and reference point
    body = MeshBody(cylinder_mesh_file, mass=3000.0, cog=(0.1, 0.05, -0.4),
                    inertia=(300, 300, 200), reference_point=(0.3, -0.2, -0.1), rho=RHO, g=G)
    n = CYL_RES[1]
    polygon = n / 2 * A_CYL**2 * math.sin(2 * math.pi / n)
    assert body.hydrostatic_stiffness(("Heave",))[0, 0] == pytest.approx(RHO * G * polygon,
                                                                          rel=1e-10)
    cbody = body.capytaine_body(RIGID_DOFS, lid=False)
    ref = cbody.compute_hydrostatic_stiffness(rho=RHO, g=G)
    ref = ref.transpose("influenced_dof", "radiating_dof").values
    np.testing.assert_allclose(body.hydrostatic_stiffness(RIGID_DOFS), ref, rtol=1e-9,
                               atol=1e-9 * np.abs(ref).max())
    assert body.hydrostatic_stiffness(RIGID_DOFS)[3, 5] != 0  # roll-yaw: off-axis G and B
    # and close to the analytic cylinder (discretisation of the circle)
    exact = cylinder(mass=3000.0, cog=(0.1, 0.05, -0.4), reference_point=(0.3, -0.2, -0.1))
    np.testing.assert_allclose(body.hydrostatic_stiffness(RIGID_DOFS),
                               exact.hydrostatic_stiffness(RIGID_DOFS), rtol=0.02,
                               atol=0.02 * RHO * G * math.pi)


# ------------------------------------------------------------------------- mass properties
def test_assembly_mass_cm_and_inertia_by_hand():
    hull = cylinder(mass=2000.0, cog=(0, 0, -0.6), inertia=(400.0, 500.0, 600.0))
    items = [MassItem("nacelle", 100.0, (1.0, 0.0, 5.0)),
             MassItem("ballast", 900.0, (0.0, 0.5, -0.9), inertia_about_cm=(10.0, 20.0, 30.0))]
    asm = RigidAssembly(hull, items, reference_point=(0.0, 0.0, 0.0))
    m = 3000.0
    xg, yg, zg = 100.0 / m, 450.0 / m, (2000 * -0.6 + 100 * 5.0 + 900 * -0.9) / m
    assert asm.mass == m
    assert asm.cog == pytest.approx((xg, yg, zg), rel=1e-12)
    # inertia about the total CM, term by term (parallel axis theorem written out)
    parts = [(2000.0, (0, 0, -0.6), (400, 500, 600)), (100.0, (1.0, 0, 5.0), (0, 0, 0)),
             (900.0, (0, 0.5, -0.9), (10, 20, 30))]
    ixx = sum(i[0] + mk * ((c[1] - yg) ** 2 + (c[2] - zg) ** 2) for mk, c, i in parts)
    iyy = sum(i[1] + mk * ((c[0] - xg) ** 2 + (c[2] - zg) ** 2) for mk, c, i in parts)
    izz = sum(i[2] + mk * ((c[0] - xg) ** 2 + (c[1] - yg) ** 2) for mk, c, i in parts)
    ixz = sum(-mk * (c[0] - xg) * (c[2] - zg) for mk, c, _ in parts)
    ixy = sum(-mk * (c[0] - xg) * (c[1] - yg) for mk, c, _ in parts)
    inertia = asm.inertia_about_cog
    assert np.diag(inertia) == pytest.approx((ixx, iyy, izz), rel=1e-12)
    assert inertia[0, 2] == pytest.approx(ixz, rel=1e-12)
    assert inertia[0, 1] == pytest.approx(ixy, rel=1e-12)
    # hydrostatics: the hull's geometry, the whole structure's weight
    vol, zb = math.pi * A_CYL**2 * D_CYL, -D_CYL / 2
    c55 = RHO * G * (math.pi * A_CYL**4 / 4 + vol * zb) - m * G * zg
    assert asm.hydrostatic_stiffness(("Pitch",))[0, 0] == pytest.approx(c55, rel=1e-9)
    assert body_from_dict(json.loads(asm.to_json())) == asm


def test_mass_matrix_couplings_for_an_off_centre_cm():
    body = cylinder(mass=1000.0, cog=(0.2, -0.3, -0.5), inertia=(50.0, 60.0, 70.0),
                    reference_point=(0.0, 0.0, 0.0))
    m, (xg, yg, zg) = body.mass, body.cog
    mm = body.mass_matrix(RIGID_DOFS)
    i = {d: k for k, d in enumerate(RIGID_DOFS)}
    expected = {("Surge", "Pitch"): m * zg, ("Surge", "Yaw"): -m * yg,
                ("Sway", "Roll"): -m * zg, ("Sway", "Yaw"): m * xg,
                ("Heave", "Roll"): m * yg, ("Heave", "Pitch"): -m * xg}
    for (a, b), v in expected.items():
        assert mm[i[a], i[b]] == pytest.approx(v, rel=1e-12)
        assert mm[i[b], i[a]] == pytest.approx(v, rel=1e-12)
    assert mm[i["Pitch"], i["Pitch"]] == pytest.approx(60.0 + m * (xg**2 + zg**2), rel=1e-12)
    # kinetic energy 1/2 v^T M v equals that of the rigid motion v_P = v_O + w x (P - O),
    # summed over a point-mass model with the same mass, CM and inertia (random velocities)
    rng = np.random.default_rng(1)
    pts = np.array([(xg, yg, zg)]) + np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0],
                                               [0, 0, 1], [0, 0, -1]]) * 0.8
    w = np.full(6, m / 6)
    # diagonal inertia of that model: 2 * (m/6) * 0.64 on each axis pair
    model = cylinder(mass=1000.0, cog=(xg, yg, zg), inertia=np.full(3, 4 * m / 6 * 0.64),
                     reference_point=(0.0, 0.0, 0.0))
    for _ in range(3):
        v = rng.normal(size=6)
        vp = v[:3] + np.cross(v[3:], pts)
        energy = 0.5 * np.sum(w * np.sum(vp**2, axis=1))
        assert 0.5 * v @ model.mass_matrix(RIGID_DOFS) @ v == pytest.approx(energy, rel=1e-12)


# ------------------------------------------------------------------------- exact restoring
def test_cylinder_exact_heave_force_is_linear():
    body = cylinder()
    z = np.linspace(-FREEBOARD, D_CYL, 7)
    f = body.restoring_force(z[:, None], ("Heave",))[:, 0]
    np.testing.assert_allclose(f, -RHO * G * math.pi * A_CYL**2 * z,
                               atol=1e-9 * RHO * G * math.pi)
    q = np.array([0.3, 0.2, 0.1])  # surge, heave, yaw: horizontal motions give no force
    out = body.restoring_force(q, ("Surge", "Heave", "Yaw"))
    assert out[0] == 0 and out[2] == 0
    assert out[1] == pytest.approx(-RHO * G * math.pi * A_CYL**2 * 0.2, rel=1e-12)
    with pytest.raises(InputError, match="no exact restoring"):
        body.restoring_force([0.1], ("Pitch",))
    with pytest.raises(InputError, match="outside"):
        body.buoyancy_force(1.2)


def test_cone_and_frustum_exact_heave_force():
    d, slope = 2.0, 0.5                     # cone, apex at the keel: r = slope (z + d)
    cone = AxisymmetricBody(profile=[(0, -d), (slope * (d + 1.0), 1.0)], rho=RHO, g=G)
    for z in (-0.7, 0.0, 0.4, 1.5):
        h = d - z                           # submerged height
        vol = math.pi * (slope * h) ** 2 * h / 3
        assert cone.buoyancy_force(z) == pytest.approx(RHO * G * vol - cone.mass * G, rel=1e-12,
                                                       abs=1e-9)
    r1, r2, zt = 1.0, 0.6, 1.0              # frustum narrowing upwards, flat bottom at -d
    frustum = AxisymmetricBody(profile=[(0, -d), (r1, -d), (r2, zt)], mass=5000.0, rho=RHO, g=G)
    for z in (-0.5, 0.0, 0.8):
        h = d - z
        rz = r1 + (r2 - r1) * h / (d + zt)
        vol = math.pi * h * (r1**2 + r1 * rz + rz**2) / 3
        assert frustum.buoyancy_force(z) == pytest.approx(RHO * G * vol - 5000.0 * G, rel=1e-12)
    # the linearisation of the exact force is the stiffness
    eps = 1e-6
    slope_f = (frustum.buoyancy_force(eps) - frustum.buoyancy_force(-eps)) / (2 * eps)
    assert -slope_f == pytest.approx(frustum.hydrostatic_stiffness(("Heave",))[0, 0], rel=1e-7)


def test_sphere_restoring_is_the_cap_buoyancy():
    s = FloatingSphere.paper()
    z = np.array([-0.1, 0.0, 0.05])
    expected = RHO_S * G_S * cap_volume(s.draft - z, s.radius) - s.mass * G_S
    np.testing.assert_array_equal(s.buoyancy_force(z), expected)
    np.testing.assert_array_equal(s.restoring_force(z[:, None])[:, 0], expected)
    assert s.dofs == ("Heave",) and tuple(s.reference_point) == s.cog


def test_mesh_body_has_no_exact_restoring_and_fixed_panels(cylinder_mesh_file):
    body = MeshBody(cylinder_mesh_file, mass=3000.0, cog=(0, 0, -0.4), rho=RHO, g=G)
    assert body.exact_restoring_dofs == ()
    with pytest.raises(InputError, match="no exact"):
        body.restoring_force([0.1], ("Heave",))
    with pytest.raises(InputError, match="sets the panels"):
        body.mesh_options(panel_size=0.1)
    assert body.draft == pytest.approx(D_CYL) and body.name == "cylinder"


# ------------------------------------------------------------------------- descriptions
def test_round_trips_and_dispatch(cylinder_mesh_file):
    bodies = [FloatingSphere.kramer2021(), cylinder(reference_point=(0, 0, 0.1)),
              MeshBody(cylinder_mesh_file, mass=3000.0, cog=(0, 0, -0.4), rho=RHO, g=G),
              RigidAssembly(cylinder(), [MassItem("top", 10.0, (0, 0, 3.0))])]
    for body in bodies:
        assert isinstance(body, Body)
        again = body_from_dict(json.loads(body.to_json()))
        assert type(again) is type(body) and again == body
        np.testing.assert_allclose(again.hydrostatic_stiffness(RIGID_DOFS),
                                   body.hydrostatic_stiffness(RIGID_DOFS))
    with pytest.raises(InputError, match="unknown body type"):
        body_from_dict({"type": "Barge"})


@pytest.mark.parametrize("profile", [
    [(0, -1), (1, -1), (1, -2)],           # z decreases
    [(0.5, -1), (1, -1), (1, 1)],          # does not start on the axis
    [(0, -1), (1, -1), (1, -0.5)],         # does not reach the waterline
    [(0, -1), (1, 0), (2, 0), (2, 1)],     # horizontal step at the waterline
    [(0, -1), (1, -1), (0, 0), (0, 1)],    # no waterplane
    [(0, -1)],
])
def test_bad_profiles_are_rejected(profile):
    with pytest.raises(InputError):
        AxisymmetricBody(profile=profile)


def test_bad_inputs(tmp_path):
    with pytest.raises(InputError, match="not found"):
        MeshBody(tmp_path / "none.gdf", mass=1.0, cog=(0, 0, 0))
    with pytest.raises(InputError, match="resolution"):
        cylinder().mesh_options(resolution=(8, 16))
    with pytest.raises(InputError, match="symmetric"):
        cylinder(inertia=[[1, 2, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(InputError):
        MassItem("x", -1.0, (0, 0, 0))
    with pytest.raises(InputError):
        RigidAssembly("hull")
    with pytest.raises(InputError, match="Body"):
        bem.compute("sphere", [1.0])


def test_panel_size_sets_the_profile_mesh():
    body = cylinder()
    hull, lid = body.mesh(panel_size=PANEL)
    nr, nth, nz = CYL_RES
    assert hull.nb_faces == nth * (nr + nz // 2) and lid.nb_faces == nth * nr
    assert body.mesh_description(panel_size=PANEL) == {
        "kind": "axisymmetric_profile", "panel_size": PANEL, "n_around": nth, "n_along": 10}
    # the polygonal mesh is inscribed in the cylinder: same volume as the 32-gon prism
    polygon = nth / 2 * A_CYL**2 * math.sin(2 * math.pi / nth)
    assert hull.volume == pytest.approx(polygon * D_CYL, rel=1e-10)
    assert lid.faces_areas.sum() == pytest.approx(polygon, rel=1e-10)
    n = body.mesh_options(n_panels=1000)["panel_size"]
    assert n == pytest.approx(math.sqrt(body.wetted_area() / 1000))


# ------------------------------------------------------------------------- BEM: three ways
DOFS = ("Surge", "Heave", "Pitch", "Yaw")
OMEGA = np.array([0.8, 1.6, 2.4])  # kR < 0.6: far below the first irregular frequency


def _capytaine_plain(mesh, lid_mesh, body: Body) -> xr.Dataset:
    """Capytaine alone on a plain (merged) mesh: the reference."""
    import capytaine as cpt

    cbody = cpt.FloatingBody(mesh=mesh, lid_mesh=lid_mesh,
                             dofs=cpt.rigid_body_dofs(only=list(DOFS),
                                                      rotation_center=body.reference_point),
                             center_of_mass=body.cog, mass=body.mass)
    grid = xr.Dataset(coords={"omega": OMEGA, "radiating_dof": list(DOFS),
                              "wave_direction": [0.0], "water_depth": [np.inf], "rho": [RHO],
                              "g": [G]})
    with bem.blas_single_thread():
        return cpt.BEMSolver(method="direct").fill_dataset(grid, cbody, hydrostatics=False,
                                                           progress_bar=False)


def _matrices(ds: xr.Dataset, name: str) -> np.ndarray:
    da = ds[name]
    da = da.isel({d: 0 for d in da.dims if d not in ("omega", "radiating_dof", "influenced_dof")})
    return da.sel(radiating_dof=list(DOFS), influenced_dof=list(DOFS)).transpose(
        "omega", "radiating_dof", "influenced_dof").values


def _agree(a: xr.Dataset, b: xr.Dataset, rtol: float) -> float:
    """Largest relative difference of A and B over the significant entries; asserts rtol."""
    worst = 0.0
    for name in ("added_mass", "radiation_damping"):
        va, vb = _matrices(a, name), _matrices(b, name)
        scale = np.abs(vb).max(axis=0)
        sig = scale > 1e-6 * scale.max()  # yaw of a body of revolution radiates nothing
        rel = np.abs(va - vb)[:, sig] / np.abs(vb)[:, sig]
        worst = max(worst, float(rel.max()))
        np.testing.assert_allclose(va[:, sig], vb[:, sig], rtol=rtol, err_msg=name)
        np.testing.assert_allclose(va[:, ~sig], 0.0, atol=1e-6 * scale.max())
    return worst


@pytest.fixture(scope="module")
def three_cylinders(cylinder_mesh_file):
    """The cylinder (off-axis centre of mass, DOF origin on the axis at the waterline) as a
    profile body and as a mesh-file body, with and without lid."""
    prof = cylinder(cog=(0.0, 0.1, -0.4), reference_point=(0.0, 0.0, 0.0))
    mesh = MeshBody(cylinder_mesh_file, mass=prof.mass, cog=prof.cog, inertia=prof.inertia,
                    reference_point=prof.reference_point, rho=RHO, g=G)
    kw = dict(dofs=DOFS, use_cache=False, progress=False, include_zero=False, include_inf=False)
    out = {}
    for lid in (False, True):
        out["profile", lid] = bem.compute(prof, OMEGA, panel_size=PANEL, lid=lid, **kw)
        out["mesh", lid] = bem.compute(mesh, OMEGA, lid=lid, **kw)
    return prof, mesh, out


def test_profile_and_mesh_file_equal_capytaine_plain_mesh(three_cylinders):
    import capytaine as cpt

    prof, mesh, out = three_cylinders
    plain = cpt.mesh_vertical_cylinder(length=2 * D_CYL, radius=A_CYL, resolution=CYL_RES
                                       ).immersed_part()
    ref = _capytaine_plain(plain, None, prof)
    # same panels (the profile's are Capytaine's rotated by a quarter turn): same numbers
    _agree(out["profile", False], ref, rtol=1e-8)
    _agree(out["mesh", False], ref, rtol=1e-8)
    # with lids: the profile's disc lid is Capytaine's mesh_disk; the mesh file's lid is
    # Capytaine's generate_lid; the two lids differ, so profile and mesh agree within 0.5 %
    disc = cpt.mesh_disk(radius=A_CYL, center=(0, 0, 0), normal=(0, 0, -1),
                         resolution=CYL_RES[:2])
    _agree(out["profile", True], _capytaine_plain(plain, disc, prof), rtol=1e-8)
    _agree(out["mesh", True], _capytaine_plain(plain, plain.generate_lid(z=0.0), prof),
           rtol=1e-8)
    _agree(out["profile", True], out["mesh", True], rtol=5e-3)


def test_bem_dataset_carries_body_matrices_about_the_reference_point(three_cylinders):
    prof, _, out = three_cylinders
    ds = out["profile", True]
    assert ds.attrs["reference_point"] == [0.0, 0.0, 0.0]
    np.testing.assert_allclose(coefficients.matrix(ds, "mass"), prof.mass_matrix(DOFS))
    stiff = coefficients.matrix(ds, "hydrostatic_stiffness")
    np.testing.assert_allclose(stiff, prof.hydrostatic_stiffness(DOFS))
    # off-axis G: pitch-yaw coupling in one orientation only (C56 = m g y_G, C65 = 0)
    assert stiff[2, 3] == pytest.approx(prof.mass * G * 0.1, rel=1e-12) and stiff[3, 2] == 0
    # Capytaine on the 32-gon mesh: heave and pitch within the polygon's 1-2 %
    np.testing.assert_allclose(np.diag(coefficients.matrix(ds, "hydrostatic_stiffness_mesh"))[1:3],
                               np.diag(stiff)[1:3], rtol=0.03)
    assert ds["added_mass"].attrs["units"].startswith("per DOF pair")
    assert ds["mass"].attrs["units"].startswith("per DOF pair")
    desc = json.loads(ds.attrs["mesh"])
    assert desc["kind"] == "axisymmetric_profile" and desc["panel_size"] == PANEL
    assert ds.attrs["n_panels"] == 320 and ds.attrs["n_lid_panels"] == 160
