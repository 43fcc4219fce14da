"""OC4-DeepCwind semi: the shipped BEM coefficients (found by input hash, against WAMIT), the
natural frequencies of the six rigid-body modes, decays and RAOs in six DOFs at three headings
(issue 30 items 2, 5).

References: WAMIT's solution of the definition (OpenFAST r-test ``marin_semi``, trimmed rows in
tests/data/oc4_wamit), the OC4 phase II code comparison's natural frequencies as quoted in
``cases/oc4_semi.toml``, and the frequency-domain solution of the same linear system.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from hybridwsi.cases import bem_arguments, load_case
from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.history import read_netcdf
from hybridwsi.hydro import bem
from hybridwsi.hydro import coefficients as co
from hybridwsi.hydro.formats.wamit import read_radiation
from hybridwsi.hydro.modal import natural_frequencies
from hybridwsi.hydro.strip import case_elements, with_slender_members
from hybridwsi.report.fowt_semi import SemiSystem, linearised_drag, semi_modes, semi_raos

CASE = load_case("oc4_semi")
SHIPPED = bem.PAPER_COEFFS.parent / "bem_oc4_semi.nc"
WAMIT = Path(__file__).parent / "data" / "oc4_wamit" / "marin_semi_trimmed.1"


@pytest.fixture(scope="module")
def shipped():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the known A(0) flag (finite depth)
        return read_netcdf(SHIPPED)


@pytest.fixture(scope="module")
def system(shipped) -> SemiSystem:
    pytest.importorskip("moorpy")
    from hybridwsi.forces import MooringSystem

    return SemiSystem(coeffs=with_slender_members(shipped, case_elements(CASE)),
                      mooring=MooringSystem.from_case(CASE).stiffness(),
                      drag=linearised_drag(CASE))


# ------------------------------------------------------------------------- the shipped file
def test_shipped_file_is_found_by_its_inputs(shipped):
    plan = bem.plan(**bem_arguments(CASE))
    assert shipped.attrs["input_hash"] == plan.input_hash
    assert list(co.dofs(shipped)) == list(RIGID_DOFS)
    assert shipped["wave_direction"].values == pytest.approx(np.radians([0.0, 30.0, 60.0]))
    assert shipped.attrs["reference_point"] == [0.0, 0.0, 0.0]
    assert shipped.sizes["omega"] == CASE["bem"]["n_omega"]
    assert np.all(np.isfinite(co.matrix(shipped, "added_mass_inf")))
    # no negative diagonal damping, excitation finite at every heading
    b = co.matrix_omega(shipped, "radiation_damping")
    assert np.all(np.diagonal(b, axis1=1, axis2=2) >= -1e-6 * np.abs(b).max())
    assert np.all(np.isfinite(shipped["excitation_force"].values))


def test_compute_returns_the_shipped_file_without_solving(tmp_path, monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("BEM solve attempted")

    monkeypatch.setattr(bem, "_solve_missing", refuse)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = bem.compute(**bem_arguments(CASE), cache_dir=tmp_path, progress=False)
    assert ds.attrs["input_hash"] == bem.plan(**bem_arguments(CASE)).input_hash


def test_symmetry_of_the_coefficients(shipped):
    """Three-fold symmetry with a mirror: A11 = A22, A44 = A55, A15 = -A24; at heading 0 the
    sway, roll, yaw excitation vanishes; heading 60° is heading 0 seen from the rotated
    platform (|F_heave| equal)."""
    a = co.matrix(shipped, "added_mass_inf")
    assert a[0, 0] == pytest.approx(a[1, 1], rel=1e-6)
    assert a[3, 3] == pytest.approx(a[4, 4], rel=1e-6)
    assert a[0, 4] == pytest.approx(-a[1, 3], rel=1e-6)
    fe = shipped["excitation_force"].transpose("omega", "wave_direction", "influenced_dof").values
    scale = np.abs(fe[:, 0, :]).max(axis=0)
    assert np.all(np.abs(fe[:, 0, [1, 3, 5]]) <= 1e-6 * scale[[0, 4, 4]])
    assert np.abs(fe[:, 2, 2]) == pytest.approx(np.abs(fe[:, 0, 2]), rel=1e-4)


def test_added_mass_and_damping_against_wamit(shipped):
    """WAMIT (marin_semi: columns, heave plates, pontoons, braces) at its three finite periods
    against the shipped Capytaine columns + the slender members by strip theory (added mass
    only: their radiation damping is negligible). Tolerances from the measured differences and
    the panel convergence (docs/OC4_SEMI.md, "Against WAMIT")."""
    ref = read_radiation(WAMIT, rho=1025.0)
    ours = with_slender_members(shipped, case_elements(CASE))
    for k, w in enumerate(ref["omega"].values):
        a = co.at_frequency(ours, "added_mass", w)
        b = co.at_frequency(ours, "radiation_damping", w)
        ra = ref["added_mass"].values[k]
        rb = ref["radiation_damping"].values[k]
        for i in (0, 2, 4, 5):
            assert a[i, i] == pytest.approx(ra[i, i], rel=0.05), (w, i)
        for i in (0, 2, 4):
            assert b[i, i] == pytest.approx(rb[i, i], rel=0.10), (w, i)


# ------------------------------------------------------------------------- natural frequencies
def test_natural_frequencies_of_the_six_modes(system):
    modes = {m.dominant_dof: m for m in semi_modes(system)}
    assert set(modes) == set(RIGID_DOFS)
    ref = CASE["reference_natural_frequencies"]
    # heave against the code comparison; surge/sway and roll/pitch: see the next test
    assert modes["Heave"].frequency == pytest.approx(ref["heave"], rel=0.03)
    assert modes["Surge"].frequency == pytest.approx(modes["Sway"].frequency, rel=1e-4)
    assert modes["Roll"].frequency == pytest.approx(modes["Pitch"].frequency, rel=1e-3)


def test_natural_frequencies_with_wamits_added_mass(system):
    """The same eigen-analysis (mass, hydrostatics, MoorPy mooring) with WAMIT's added mass in
    place of Capytaine's: every mode within 3 % (independent hydrodynamics)."""
    ref = read_radiation(WAMIT, rho=1025.0)
    ours = {m.dominant_dof: m.frequency for m in semi_modes(system)}
    wamit = system.coeffs.copy(deep=True)
    pair = ("radiating_dof", "influenced_dof")
    strip = co.matrix(system.coeffs, "added_mass_inf") - co.matrix(
        read_netcdf(SHIPPED), "added_mass_inf")  # the slender members' A_m
    omega = np.concatenate([[1e-6], ref["omega"].values])
    a = np.concatenate([ref["added_mass_zero"].values[None], ref["added_mass"].values]) + strip
    wamit = wamit.drop_dims("omega").assign_coords(omega=omega)
    wamit["added_mass"] = (("omega", *pair), np.transpose(a, (0, 2, 1)))
    modes = {m.dominant_dof: m.frequency
             for m in natural_frequencies(wamit, system.mooring, list(RIGID_DOFS))}
    for dof in RIGID_DOFS:
        assert ours[dof] == pytest.approx(modes[dof], rel=0.03), dof


# ------------------------------------------------------------------------- RAOs
def test_oblique_sea_moves_sway_roll_and_yaw(system):
    """At 30° the frequency-domain sway, roll and yaw responses are non-zero (at 0° they vanish
    by symmetry)."""
    from hybridwsi.report.fowt_semi import semi_rao_curves

    w = np.array([0.5, 0.8])
    curves = semi_rao_curves(system, w, [0.0, 30.0])
    head, oblique = curves
    assert np.all(head[:, [1, 3, 5]] < 1e-9 * head[:, [0, 4, 4]].max())
    assert np.all(oblique[:, 1] > 0.1 * oblique[:, 0])       # sway ~ tan 30° x surge
    assert np.all(oblique[:, 3] > 0.1 * oblique[:, 4])       # roll
    assert np.all(oblique[:, 5] > 1e-5)                      # yaw [rad/m]


@pytest.mark.slow
def test_raos_time_domain_against_frequency_domain(system):
    """Six DOFs, three headings: steady-state amplitudes of the Cummins run against the
    frequency-domain solution of the same linear system within 1 % (DOFs the wave moves)."""
    points = semi_raos(system, [7.0, 11.0, 17.0], [0.0, 30.0, 60.0], quick=True)
    for p in points:
        scale = {"m": max(p["frequency_domain"][d] for d in ("Surge", "Sway", "Heave")),
                 "rad": max(p["frequency_domain"][d] for d in ("Roll", "Pitch", "Yaw"))}
        for d in RIGID_DOFS:
            unit = "m" if d in ("Surge", "Sway", "Heave") else "rad"
            if p["frequency_domain"][d] > 1e-3 * scale[unit]:
                assert p["relative_error"][d] < 0.01, (p["heading_deg"], p["period"], d)
