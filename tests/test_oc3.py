"""OC3-Hywind: the case as a body, its hydrostatics, the shipped BEM coefficients and the
natural frequencies (issue 13 items 1-2).

References: the definition (Jonkman 2010, NREL/TP-500-47535; numbers in
../shared/data/oc3_hywind/README.md and ``cases/oc3_hywind.toml``), slender-body strip theory
for the low-frequency added mass, and closed-form 1-DOF resonance for the eigen-analysis.
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
import scipy.optimize

from hybridwsi.bodies import AxisymmetricBody, RigidAssembly, body_from_dict
from hybridwsi.casemodel import bem_arguments, body_from_case, frequencies
from hybridwsi.cases import load_case
from hybridwsi.dofs import RIGID_DOFS, index
from hybridwsi.errors import InputError, SolverError
from hybridwsi.history import read_netcdf
from hybridwsi.hydro import bem
from hybridwsi.hydro import coefficients as co
from hybridwsi.hydro.modal import natural_frequencies

import synthetic_hydro

CASE = load_case("oc3_hywind")
SHIPPED = bem.PAPER_COEFFS.parent / "bem_oc3_hywind.nc"


@pytest.fixture(scope="module")
def body() -> RigidAssembly:
    return body_from_case(CASE)


@pytest.fixture(scope="module")
def shipped():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the known A(0) flag (finite depth)
        return read_netcdf(SHIPPED)


# ------------------------------------------------------------------------- the body
def test_case_body_is_the_assembly_of_the_definition(body):
    items = CASE["body"]["items"]
    mass = sum(it["mass"] for it in items)
    zg = sum(it["mass"] * it["cm"][2] for it in items) / mass
    assert isinstance(body, RigidAssembly) and isinstance(body.hull, AxisymmetricBody)
    assert body.mass == pytest.approx(8_066_048.0, rel=1e-12)
    assert body.cog[2] == pytest.approx(zg, rel=1e-12)
    assert tuple(body.reference_point) == (0.0, 0.0, 0.0)
    assert (body.rho, body.g, body.draft) == (1025.0, 9.80665, 120.0)
    assert body.dofs == RIGID_DOFS
    # the platform item is the hull's own structure, not counted twice
    assert body.hull.mass == 7_466_330.0 and len(body.items) == 3
    # yaw inertia about the centreline: platform + nacelle (own + offset) + rotor (about x)
    izz = 1.6423e8 + 1_741_490.0 + 240_000 * 1.9**2 + 19_379_618.0 + 110_000 * 5.0**2
    assert body.mass_matrix()[5, 5] == pytest.approx(izz, rel=1e-9)
    assert body_from_dict(json.loads(body.to_json())) == body


def test_hydrostatics_against_the_definition(body):
    """Table 4-2: V0, C33, and C44 = C55 WITHOUT the weight term (rho g (I_wp + V z_B))."""
    hyd = CASE["hydrodynamics"]
    vol = body.displaced_volume()
    assert vol == pytest.approx(8029.21, rel=0.005)
    assert body.rho * body.g * vol == pytest.approx(hyd["buoyancy"], rel=0.005)
    c = body.hydrostatic_stiffness()
    assert c[2, 2] == pytest.approx(hyd["C33"], rel=0.005)
    wp, zb = body.waterplane_moments(), body.center_of_buoyancy()[2]
    without_weight = body.rho * body.g * (wp.sxx + vol * zb)
    assert without_weight == pytest.approx(hyd["C55"], rel=0.005)
    # the total adds -m g z_G of the whole structure (8 066 048 kg, z_G = -78.0 m): +6.17e9
    weight = -body.mass * body.g * body.cog[2]
    assert c[4, 4] == pytest.approx(without_weight + weight, rel=1e-12)
    assert c[3, 3] == pytest.approx(c[4, 4], rel=1e-12)
    # total 1.1616e9 N m/rad vs 1.1707e9 from the definition's C55 + this weight term (-0.8 %):
    # the +0.18 % of the definition-comparable part, amplified by the cancellation
    assert c[4, 4] == pytest.approx(hyd["C55"] + weight, rel=0.01)


def test_case_type_names_and_structure_errors():
    hull = {"type": "axisymmetric", "profile": [[0, -2], [1, -2], [1, 1]]}
    assert isinstance(body_from_dict(hull), AxisymmetricBody)
    assert isinstance(body_from_dict({**hull, "type": "AxisymmetricBody"}), AxisymmetricBody)
    with pytest.raises(InputError, match="unknown body type"):
        body_from_dict({**hull, "type": "barge"})
    case = {"name": "x", "environment": {"rho": 1000.0, "g": 9.8},
            "body": {"type": "rigid_assembly", "hull": {**hull, "structure": "deck"},
                     "items": [{"name": "top", "mass": 10.0, "cm": [0, 0, 1]}]}}
    with pytest.raises(InputError, match="structure"):
        body_from_case(case)
    case["body"]["hull"]["structure"] = "top"
    asm = body_from_case(case)
    assert (asm.rho, asm.g, asm.mass, asm.items) == (1000.0, 9.8, 10.0, ())
    with pytest.raises(InputError, match="no \\[body\\]"):
        body_from_case({"name": "x"})


def test_frequency_grid():
    cfg = CASE["bem"]
    w = frequencies(cfg)
    assert w.size == cfg["n_omega"] >= 150
    assert (w[0], w[-1]) == (cfg["omega_min"], cfg["omega_max"]) and np.all(np.diff(w) > 0)
    dw = np.diff(w)
    assert np.sum(w < 1.0) > 0.5 * w.size  # denser below 1 rad/s
    # spacing proportional to omega + omega_blend
    np.testing.assert_allclose(dw / (w[:-1] + cfg["omega_blend"]), dw[0] / (w[0] + 0.2),
                               rtol=0.02)
    paper = load_case("paper_sphere")["bem"]
    np.testing.assert_array_equal(frequencies(paper), bem.paper_frequencies())
    with pytest.raises(InputError, match="spacing"):
        frequencies({**cfg, "spacing": "cubic"})
    with pytest.raises(InputError):
        frequencies({**cfg, "omega_min": 5.0})


def test_paper_sphere_case_is_the_paper_configuration():
    """``hybridwsi bem --case paper_sphere`` must hit the shipped sphere file (same hash)."""
    assert bem.plan(**bem_arguments(load_case("paper_sphere"))).input_hash == \
        bem.plan(**bem.paper_configuration()).input_hash


# ------------------------------------------------------------------------- BEM
def test_shipped_file_matches_the_case_configuration(shipped, tmp_path, monkeypatch):
    assert SHIPPED.stat().st_size < 5e6
    assert shipped.attrs["input_hash"] == bem.plan(**bem_arguments(CASE)).input_hash
    # compute() takes it without solving
    monkeypatch.setattr(bem.run, "solve_missing", lambda *a, **k: pytest.fail("solved"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = bem.compute(**bem_arguments(CASE), cache_dir=tmp_path, progress=False)
    assert ds.attrs["input_hash"] == shipped.attrs["input_hash"]


def test_shipped_coefficients_physics(shipped):
    """All 6 DOFs about (0, 0, 0); axisymmetry; positive damping; low-frequency added mass
    against slender-body strip theory (2-D cylinder sections, C_a = 1: A11 = rho ∫ pi r² dz,
    A15 = rho ∫ pi r² z dz, A55 = rho ∫ pi r² z² dz; 3-D end effects make the BEM lower)."""
    assert co.dofs(shipped) == list(RIGID_DOFS)
    assert list(shipped.attrs["reference_point"]) == [0.0, 0.0, 0.0]
    w = co.omega(shipped)
    assert w.size >= 150 and w[0] <= 0.03 and w[-1] >= 4.0
    a, b = co.matrix_omega(shipped, "added_mass"), co.matrix_omega(shipped, "radiation_damping")
    ainf = co.matrix(shipped, "added_mass_inf")
    assert np.all(np.isfinite(a)) and np.all(np.isfinite(b)) and np.all(np.isfinite(ainf))
    i = {d: k for k, d in enumerate(RIGID_DOFS)}
    np.testing.assert_allclose(a[:, i["Sway"], i["Sway"]], a[:, i["Surge"], i["Surge"]], rtol=1e-6)
    np.testing.assert_allclose(a[:, i["Sway"], i["Roll"]], -a[:, i["Surge"], i["Pitch"]], rtol=1e-6)
    np.testing.assert_allclose(a[:, i["Roll"], i["Roll"]], a[:, i["Pitch"], i["Pitch"]], rtol=1e-6)
    diag = np.diagonal(b, axis1=1, axis2=2)[:, :5]
    assert diag.min() >= -1e-6 * np.abs(diag).max()
    z, r = _profile_strips()
    rho = 1025.0
    strip = {k: rho * np.sum(math.pi * r**2 * z**p) * (z[1] - z[0]) for k, p in
             (("A11", 0), ("A15", 1), ("A55", 2))}
    low = a[0]
    assert low[0, 0] == pytest.approx(strip["A11"], rel=0.06)
    assert low[0, 4] == pytest.approx(strip["A15"], rel=0.06)
    assert low[4, 4] == pytest.approx(strip["A55"], rel=0.10)
    # 3-D end effects: the BEM lies below strip theory
    assert low[0, 0] < strip["A11"] and low[4, 4] < strip["A55"]


def _profile_strips(n: int = 12_000) -> tuple[np.ndarray, np.ndarray]:
    """Midpoints z [m] and radii r [m] of thin strips of the immersed spar profile."""
    prof = np.asarray(CASE["body"]["hull"]["profile"])
    edges = np.linspace(prof[0, 1], 0.0, n + 1)
    z = 0.5 * (edges[1:] + edges[:-1])
    return z, np.interp(z, prof[1:, 1], prof[1:, 0])


@pytest.mark.slow
def test_quick_configuration_solves(tmp_path):
    """The [bem_quick] table end to end through Capytaine (coarse; about 20 s)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = bem.compute(**bem_arguments(CASE, "bem_quick"), cache_dir=tmp_path, progress=False,
                         n_jobs=1)
    assert co.dofs(ds) == list(RIGID_DOFS)
    assert np.all(np.isfinite(co.matrix_omega(ds, "added_mass")))


# ------------------------------------------------------------------------- natural frequencies
def test_one_dof_natural_frequency_is_the_resonance_of_the_frequency_dependent_system():
    """1 DOF: ω² (m + A(ω)) = C, solved independently with the closed-form A(ω)."""
    ds = synthetic_hydro.coefficients()
    exact = scipy.optimize.brentq(
        lambda w: w**2 * (synthetic_hydro.M + synthetic_hydro.added_mass(w)) - synthetic_hydro.C,
        1.0, 30.0, xtol=1e-14)
    (mode,) = natural_frequencies(ds)
    assert mode.omega == pytest.approx(exact, rel=1e-4)  # A interpolated between 400 points
    assert mode.dominant_dof == "Heave" and mode.period == pytest.approx(2 * math.pi / exact, rel=1e-4)
    # an external spring adds to C
    (stiffer,) = natural_frequencies(ds, np.array([[300.0]]))
    exact2 = scipy.optimize.brentq(
        lambda w: w**2 * (synthetic_hydro.M + synthetic_hydro.added_mass(w)) - synthetic_hydro.C
        - 300.0, 1.0, 30.0, xtol=1e-14)
    assert stiffer.omega == pytest.approx(exact2, rel=1e-4)
    with pytest.raises(SolverError, match="unstable"):
        natural_frequencies(ds, np.array([[-2000.0]]))
    with pytest.raises(InputError, match="1x1"):
        natural_frequencies(ds, np.zeros((2, 2)))


def test_oc3_natural_frequencies(shipped):
    """Eigen-analysis with A at each mode's frequency, hydrostatics with the weight term plus
    MoorPy's mooring stiffness and the yaw spring: within 2 % of the OC3 references."""
    pytest.importorskip("moorpy")
    from hybridwsi.forces.mooring import MooringSystem

    k = MooringSystem.from_case(CASE).stiffness()
    modes = natural_frequencies(shipped, k, RIGID_DOFS)
    by_dof = {m.dominant_dof: m for m in modes}
    assert sorted(by_dof) == sorted(RIGID_DOFS)  # one mode per DOF
    ref = CASE["reference_natural_frequencies"]
    for dof in RIGID_DOFS:
        assert by_dof[dof].frequency == pytest.approx(ref[dof.lower()], rel=0.02), dof
    # 3 DOFs of head seas: the same surge, heave, pitch frequencies
    sub = ["Surge", "Heave", "Pitch"]
    idx = index(sub)
    three = {m.dominant_dof: m.frequency for m in natural_frequencies(shipped, k[np.ix_(idx, idx)], sub)}
    for dof in sub:
        assert three[dof] == pytest.approx(by_dof[dof].frequency, rel=1e-6)


# ------------------------------------------------------------------------- command line
def test_cli_bem_case_writes_the_shipped_coefficients(tmp_path, shipped, capsys):
    from hybridwsi.cli import main

    out = tmp_path / "oc3.nc"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["bem", "--case", "oc3_hywind", "--out", str(out),
                     "--cache-dir", str(tmp_path / "cache")]) == 0
    ds = read_netcdf(out)
    assert co.dofs(ds) == list(RIGID_DOFS)
    assert ds.attrs["input_hash"] == shipped.attrs["input_hash"]
    for name in ("added_mass", "radiation_damping", "excitation_force", "added_mass_inf",
                 "added_mass_zero", "hydrostatic_stiffness", "mass"):
        assert name in ds and ds[name].attrs["units"]
    assert co.unit_matrix("added_mass", RIGID_DOFS)[0][4] == "kg m"  # per-DOF units
    assert "Surge" in capsys.readouterr().out
    # --case is the whole problem: other problem options are refused
    assert main(["bem", "--case", "oc3_hywind", "--panels", "400", "--out", str(out)]) == 2
    assert "--panels" in capsys.readouterr().err
    assert main(["bem", "--case", "no_such_case", "--out", str(out)]) == 2
    assert main(["bem", "--quick", "--out", str(out)]) == 2
