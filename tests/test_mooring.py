"""OC3-Hywind mooring: MoorPy model against the definition, tabulated interpolant against MoorPy.

References: Jonkman (2010), NREL/TP-500-47535, Eq. 5-2 (preload), Eq. 5-3 (stiffness), Table 4-2
(buoyancy), Table 3-1 (masses) — the numbers of ``cases/oc3_hywind.toml``.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

pytest.importorskip("moorpy", reason="MoorPy not installed (optional extra hybridwsi[mooring])")

from hybridwsi.cases import load_case  # noqa: E402
from hybridwsi.dofs import RIGID_DOFS  # noqa: E402
from hybridwsi.errors import InputError, SolverError  # noqa: E402
from hybridwsi.forces.mooring import (  # noqa: E402
    MooringForce,
    MooringLines,
    MooringSystem,
    MooringTable,
    rotation_matrix,
)
from hybridwsi.history import make_history  # noqa: E402


@pytest.fixture(scope="module")
def case() -> dict:
    return load_case("oc3_hywind")


@pytest.fixture(scope="module")
def system(case) -> MooringSystem:
    return MooringSystem.from_case(case)


@pytest.fixture(scope="module")
def component(case) -> MooringForce:
    return MooringForce.from_case(case)  # the case's default DOFs and tabulation box


@pytest.fixture(scope="module")
def table(component) -> MooringTable:
    return component.table


def _reference_k(case) -> np.ndarray:
    return np.array(case["mooring"]["reference"]["K"])


# Eq. 5-3's nonzero entries (0-based row = force DOF, column = displacement DOF)
EQ_5_3 = [(0, 0), (1, 1), (2, 2), (3, 3), (4, 4), (5, 5), (0, 4), (4, 0), (1, 3), (3, 1)]


def test_linearised_stiffness_matches_eq_5_3(system, case):
    k_ref = _reference_k(case)
    k = system.stiffness(yaw_spring=False)
    for i, j in EQ_5_3:
        assert k[i, j] == pytest.approx(k_ref[i, j], rel=0.01), (RIGID_DOFS[i], RIGID_DOFS[j])
    off = np.ones((6, 6), bool)
    off[tuple(zip(*EQ_5_3))] = False
    # every other coupling vanishes for the symmetric layout (relative to the diagonal scale)
    scale = np.sqrt(np.outer(np.diag(k), np.diag(k)))
    assert np.all(np.abs(k[off]) < 1e-6 * scale[off])
    # the yaw spring is a separate linear term on K66 only
    k_all = system.stiffness()
    spring = np.zeros((6, 6))
    spring[5, 5] = case["mooring"]["yaw_spring"]
    np.testing.assert_allclose(k_all - k, spring, atol=1e-6)


def test_interpolant_stiffness_matches_eq_5_3(table, system, case):
    """The component's C (the interpolant's own linearisation) is Eq. 5-3 plus the yaw spring."""
    k_ref = _reference_k(case)
    k_ref[5, 5] += case["mooring"]["yaw_spring"]
    k = table.stiffness()
    for i, j in EQ_5_3:
        assert k[i, j] == pytest.approx(k_ref[i, j], rel=0.01)
    np.testing.assert_allclose(k, system.stiffness(), rtol=0, atol=1e-4 * np.abs(k).max())


def test_preload_and_static_balance(system, table, case):
    f0 = system.preload()
    ref = np.array(case["mooring"]["reference"]["preload"])
    assert f0[2] == pytest.approx(ref[2], rel=0.005)
    assert np.all(np.abs(f0[[0, 1]]) < 1.0) and np.all(np.abs(f0[3:]) < 1.0)
    np.testing.assert_allclose(table.preload(), f0, rtol=0, atol=1e-5 * abs(f0[2]))
    # static balance at q = 0: buoyancy (Table 4-2) - total weight (Table 3-1 + turbine) + F0_z
    mass = sum(item["mass"] for item in case["body"]["items"])
    weight = mass * case["environment"]["g"]
    residual = case["hydrodynamics"]["buoyancy"] - weight + f0[2]
    assert abs(residual) < 1000.0  # the published preload is rounded to 1 kN
    rho, g = case["environment"]["rho"], case["environment"]["g"]
    buoyancy = rho * g * case["hydrodynamics"]["displaced_volume"]
    assert buoyancy == pytest.approx(case["hydrodynamics"]["buoyancy"], rel=1e-5)


def test_rotation_matches_moorpy():
    from moorpy.helpers import rotationMatrix

    for angles in [(0.1, -0.05, 0.2), (-0.3, 0.15, -0.07)]:
        np.testing.assert_allclose(np.array(rotation_matrix(*angles, xp=np)),
                                   rotationMatrix(*angles), atol=1e-15)


def test_interpolant_matches_moorpy_over_the_box(system, table):
    """60 random states and the 64 corners of the box: error < 0.5 % of each DOF's force scale."""
    half = np.array([table.ranges[d] for d in RIGID_DOFS])
    rng = np.random.default_rng(20100201)
    corners = np.array(list(itertools.product((-1.0, 1.0), repeat=6)))
    q = np.vstack([rng.uniform(-1.0, 1.0, (60, 6)), corners]) * half
    exact = np.array([system.force6(s) for s in q])
    scale = np.abs(exact - system.preload()).max(axis=0)  # force excursion per DOF
    batch = table.force6(q)
    single = np.array([table.force6(s) for s in q])
    np.testing.assert_allclose(single, batch, rtol=1e-12, atol=1e-6 * scale.max())
    assert np.all(np.abs(batch - exact).max(axis=0) < 0.005 * scale)


def test_mirror_and_rotation_symmetry(system, table):
    """y -> -y mirror (exact for line 1 on +X) and the 120 deg symmetry of the 3-line layout."""
    k = system.stiffness(yaw_spring=False)
    assert k[1, 1] == pytest.approx(k[0, 0], rel=1e-6)  # catenary tolerance
    assert k[3, 3] == pytest.approx(k[4, 4], rel=1e-6)
    assert k[1, 3] == pytest.approx(-k[0, 4], rel=1e-6)
    assert k[3, 1] == pytest.approx(-k[4, 0], rel=1e-6)
    q = np.array([12.0, 7.0, -2.0, 0.04, -0.06, 0.05])
    flip_q = np.array([1, -1, 1, -1, 1, -1])
    for model in (system, table):
        f, f_mirror = model.force6(q), model.force6(q * flip_q)
        np.testing.assert_allclose(f_mirror, f * flip_q, rtol=0, atol=1e-6 * np.abs(f).max())
    # rotating a translation (and keeping yaw) by 120 deg rotates the force and moment
    c, s = np.cos(2 * np.pi / 3), np.sin(2 * np.pi / 3)
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    q = np.array([25.0, -9.0, 3.0, 0.0, 0.0, 0.08])
    q_rot = np.concatenate([rz @ q[:3], q[3:]])
    for model in (system, table):
        f, f_rot = model.force6(q), model.force6(q_rot)
        expect = np.concatenate([rz @ f[:3], rz @ f[3:]])
        np.testing.assert_allclose(f_rot, expect, rtol=0, atol=1e-5 * np.abs(f).max())


def test_mooring_force_on_a_3dof_subset(table, component):
    dofs = ("Surge", "Heave", "Pitch")
    assert component.dofs == dofs  # the case's default_dofs
    assert table.ranges == {"Surge": 40.0, "Sway": 20.0, "Heave": 6.0, "Roll": 0.1,
                            "Pitch": 0.15, "Yaw": 0.15}
    comp = MooringForce(table, "surge,heave,pitch")
    a, b, c = comp.linear_coefficients(3)
    assert not a.any() and not b.any()
    np.testing.assert_allclose(c, table.stiffness()[np.ix_([0, 2, 4], [0, 2, 4])])
    # small motions: the force is -C z (linear regime) and zero at rest (preload excluded)
    t = np.linspace(0.0, 100.0, 201)
    z = np.column_stack([0.05 * np.sin(0.05 * t), 0.01 * np.cos(0.2 * t),
                         2e-4 * np.sin(0.2 * t + 1)])
    hist = make_history(t, z, dof=list(dofs))
    f = comp.force(hist)
    lin = -z @ c.T
    assert np.abs(f - lin).max(axis=0) == pytest.approx(0.0, abs=1e-2 * np.abs(lin).max())
    assert np.allclose(comp.ode_force(0.0, np.zeros(3), np.zeros(3), np.zeros(0)), 0.0, atol=1e-6)
    # the nonlinear force: other DOFs held at 0; ODE, history and batch evaluations agree
    big = np.array([30.0, -4.0, 0.1])
    full = table.force6(np.array([30.0, 0.0, -4.0, 0.0, 0.1, 0.0])) - table.preload()
    np.testing.assert_allclose(comp.ode_force(0.0, big, np.zeros(3), np.zeros(0)),
                               full[[0, 2, 4]], rtol=1e-12)
    np.testing.assert_allclose(comp.ode_force(0.0, np.vstack([big, big]), None, None)[1],
                               full[[0, 2, 4]], rtol=1e-12)
    np.testing.assert_allclose(f[7], comp.ode_force(t[7], z[7], None, None), rtol=1e-12)
    assert "3 lines" in comp.describe()
    with pytest.raises(InputError):
        comp.linear_coefficients(6)
    with pytest.raises(InputError):
        comp.force(make_history(t, z[:, :2], dof=["Surge", "Heave"]))


def test_out_of_range_and_bad_input(table, case):
    with pytest.raises(SolverError):
        table.force6(np.array([200.0, 0, 0, 0, 0, 0]))
    with pytest.raises(SolverError):
        table.force6(np.array([[0.0, 0, 0, 0, 0, 0], [np.nan, 0, 0, 0, 0, 0]]))
    with pytest.raises(InputError):
        table.force6(np.zeros(5))
    lines = MooringLines.from_case(case).to_dict()
    lines["anchors"] = [[853.87, 0.0, -300.0]] + lines["anchors"][1:]
    with pytest.raises(InputError, match="seabed"):
        MooringLines(**lines)
    with pytest.raises(InputError, match="mooring"):
        MooringLines.from_case({"environment": case["environment"], "mooring": {}})


def test_table_round_trip_without_moorpy(table, tmp_path):
    path = tmp_path / "oc3_mooring.nc"
    table.dataset.to_netcdf(path)
    import xarray as xr

    with xr.open_dataset(path) as ds:
        again = MooringTable.from_dataset(ds.load())
    q = np.array([[10.0, -5.0, 1.0, 0.02, 0.05, -0.1], [-30.0, 15.0, -5.0, -0.08, -0.12, 0.1]])
    np.testing.assert_array_equal(again.force6(q), table.force6(q))
    assert again.dataset.attrs["input_hash"] == table.dataset.attrs["input_hash"]


def test_case_table_is_kept_on_disk_and_a_corrupt_entry_rebuilt(case, monkeypatch, tmp_path):
    """MooringForce.from_case tabulates once per content: a second build reads the cached
    table (no MoorPy system made) and gives the same forces; a truncated entry is tabulated
    again; another line length is another entry."""
    import hybridwsi.forces.mooring as mooring

    monkeypatch.setenv("HYBRIDWSI_CACHE", str(tmp_path))
    built = []
    real = mooring.MooringSystem.__init__
    monkeypatch.setattr(mooring.MooringSystem, "__init__",
                        lambda self, lines: built.append(1) or real(self, lines))
    small = {**case, "mooring": {**case["mooring"], "table": {"Surge": 2.0, "Heave": 1.0,
                                                               "Pitch": 0.02, "spacing": 2.0}}}
    first = MooringForce.from_case(small)
    (entry,) = (tmp_path / "mooring").glob("*.nc")
    again = MooringForce.from_case(small)
    assert built == [1]
    q = np.array([[1.0, 0.5, 0.01]])
    np.testing.assert_array_equal(again.table.force6(again._full(q)),
                                  first.table.force6(first._full(q)))
    entry.write_bytes(entry.read_bytes()[:200])
    MooringForce.from_case(small)
    assert built == [1, 1]
    longer = {**small, "mooring": {**small["mooring"],
                                   "unstretched_length": small["mooring"]["unstretched_length"] + 1}}
    MooringForce.from_case(longer)
    assert built == [1, 1, 1] and len(list((tmp_path / "mooring").glob("*.nc"))) == 2
