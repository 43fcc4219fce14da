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
import scipy.linalg

from hybridwsi.casemodel import bem_arguments
from hybridwsi.cases import load_case
from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.history import read_netcdf
from hybridwsi.hydro import bem
from hybridwsi.hydro import coefficients as co
from hybridwsi.hydro.formats.wamit import read_radiation
from hybridwsi.hydro.modal import natural_frequencies
from hybridwsi.hydro.strip import case_elements, with_slender_members
from hybridwsi.report.fowt_semi import (SemiSystem, semi_decays, semi_modes, semi_raos,
                                       semi_system)

CASE = load_case("oc4_semi")
SHIPPED = bem.PAPER_COEFFS.parent / "bem_oc4_semi.nc"
WAMIT = Path(__file__).parent / "data" / "oc4_wamit" / "marin_semi_trimmed.1"


@pytest.fixture(scope="module")
def shipped():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the known A(0) flag (finite depth)
        return read_netcdf(SHIPPED)


@pytest.fixture(scope="module")
def system() -> SemiSystem:
    pytest.importorskip("moorpy")
    return semi_system(CASE)  # the shipped coefficients (no solve) + strip theory


# ------------------------------------------------------------------------- the shipped file
def test_shipped_file_is_found_by_its_inputs(shipped):
    plan = bem.plan(**bem_arguments(CASE))
    assert shipped.attrs["input_hash"] == plan.input_hash
    assert list(co.dofs(shipped)) == list(RIGID_DOFS)
    assert shipped["wave_direction"].values == pytest.approx(np.radians([0.0, 30.0, 60.0]))
    assert np.allclose(shipped.attrs["reference_point"], 0.0)
    assert shipped.sizes["omega"] == CASE["bem"]["n_omega"]
    assert np.all(np.isfinite(co.matrix(shipped, "added_mass_inf")))
    # diagonal damping >= 0 but for values at round-off level, flagged by compute: finite-depth
    # yaw at 0.16-0.35 rad/s (down to -1.66e4 N m s/rad, 3e-6 of the yaw peak 5.2e9) and
    # heave above 2.2 rad/s (-16 N s/m, 2e-5 of its peak); excitation finite everywhere
    diag = np.diagonal(co.matrix_omega(shipped, "radiation_damping"), axis1=1, axis2=2)
    assert np.all(diag >= -1e-4 * np.abs(diag).max(axis=0))
    assert "negative diagonal radiation damping" in shipped.attrs["quality_flags"]
    assert np.all(np.isfinite(shipped["excitation_force"].values))


def test_compute_returns_the_shipped_file_without_solving(tmp_path, monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("BEM solve attempted")

    monkeypatch.setattr(bem.run, "solve_missing", refuse)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = bem.compute(**bem_arguments(CASE), cache_dir=tmp_path, progress=False)
    assert ds.attrs["input_hash"] == bem.plan(**bem_arguments(CASE)).input_hash


def test_symmetry_of_the_coefficients(shipped):
    """Three-fold symmetry with mirror lines at 0°, 60°, 120°: A11 = A22, A44 = A55,
    A15 = -A24; waves along a mirror line (headings 0° and 60°) push along it and neither
    yaw nor heel the platform about it; at 30° everything is excited."""
    a = co.matrix(shipped, "added_mass_inf")
    assert a[0, 0] == pytest.approx(a[1, 1], rel=1e-6)
    assert a[3, 3] == pytest.approx(a[4, 4], rel=1e-6)
    assert a[0, 4] == pytest.approx(-a[1, 3], rel=1e-6)
    fe = shipped["excitation_force"].transpose("omega", "wave_direction", "influenced_dof").values
    force = np.abs(fe[..., :2]).max()
    moment = np.abs(fe[..., 3:5]).max()
    for j, beta in ((0, 0.0), (2, math.radians(60.0))):
        c, s = math.cos(beta), math.sin(beta)
        assert np.all(np.abs(-fe[:, j, 0] * s + fe[:, j, 1] * c) <= 1e-5 * force)  # across
        assert np.all(np.abs(fe[:, j, 3] * c + fe[:, j, 4] * s) <= 1e-5 * moment)  # heel about
        assert np.all(np.abs(fe[:, j, 5]) <= 1e-5 * moment)  # yaw
    assert np.all(np.abs(fe[:, 1, [1, 3, 5]]) > 0)


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
        for i in (0, 2, 4, 5):  # measured within 3.2 %
            assert a[i, i] == pytest.approx(ra[i, i], rel=0.04), (w, i)
        # damping from the shipped grid interpolated linearly across steep peaks (measured
        # within 13 %; at WAMIT's exact frequencies: docs/OC4_SEMI.md)
        for i in (0, 2, 4, 5):
            assert b[i, i] == pytest.approx(rb[i, i], rel=0.15), (w, i)


# ------------------------------------------------------------------------- natural frequencies
def test_natural_frequencies_of_the_six_modes(system):
    """Heave within 3 % of the code comparison (measured +0.2 %). Surge/sway (-4.9 %) and
    roll/pitch (+5 %) are not: the quoted values follow simpler estimates of the same
    system — surge with the infinite-frequency added mass is the quoted 0.0093 Hz, pitch with
    surge held is within 3 % of the quoted 0.0373 Hz (docs/OC4_SEMI.md, which also shows that
    a 60 s radiation kernel does carry A(ω) to the surge mode)."""
    modes = {m.dominant_dof: m for m in semi_modes(system)}
    assert set(modes) == set(RIGID_DOFS)
    ref = CASE["reference_natural_frequencies"]
    assert modes["Heave"].frequency == pytest.approx(ref["heave"], rel=0.03)
    assert modes["Surge"].frequency == pytest.approx(modes["Sway"].frequency, rel=1e-4)
    assert modes["Roll"].frequency == pytest.approx(modes["Pitch"].frequency, rel=1e-3)
    m = co.matrix(system.coeffs, "mass") + co.matrix(system.coeffs, "added_mass_inf")
    c = co.matrix(system.coeffs, "hydrostatic_stiffness") + system.mooring
    held = np.sort(np.sqrt(scipy.linalg.eigvals(c, m).real)) / (2 * math.pi)
    assert held[0] == pytest.approx(ref["surge"], rel=0.03)
    pitch_alone = natural_frequencies(system.coeffs, system.mooring[4:5, 4:5], ["Pitch"])[0]
    assert pitch_alone.frequency == pytest.approx(ref["pitch"], rel=0.03)


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


def test_radiation_state_space_is_stable_and_close_to_the_bem(system):
    """The 6-DOF radiation model of the time domain: balanced fit (every DOF weighed alike),
    stable and passive coupled system, B(ω) within 2 % RMS of the BEM's; A(ω) of heave and
    pitch within 0.5 %, surge and yaw within 4 % (the kernel's low-frequency A11 sits 1.3 %
    above the BEM's; docs/THEORY.md, radiation state space)."""
    ss = system.radiation_ss
    assert ss.fit_error["frequency_bem"] < 0.02
    assert np.all(ss.poles.real < 0)
    # passive (the radiation force absorbs energy at every ω) on a grid of the test's own,
    # through every pole's resonance, and no damping at ω = 0
    omega = np.unique(np.concatenate([np.geomspace(1e-5, 1e3, 4000), np.abs(ss.poles.imag)]))
    assert ss.passivity(omega).min() >= -1e-6
    b_peak = np.diag(co.matrix_omega(system.coeffs, "radiation_damping", ss.radiating_dof
                                     ).max(axis=0))
    # the case leaves K̂(0) free (cases/oc4_semi.toml [radiation]: imposing 0 bends the
    # surge-pitch coupling); B(0) then stays small against the damping peak
    k0 = np.real(ss.frequency_response([0.0])[0])
    assert ss.low_frequency == "free"
    assert np.all(np.abs(np.diag(k0)) <= 0.05 * b_peak)
    ainf = co.matrix(system.coeffs, "added_mass_inf")
    for w in np.linspace(0.3, 1.3, 21):
        a = np.diag(ainf + ss.equivalent_added_mass(w))
        ref = np.diag(co.at_frequency(system.coeffs, "added_mass", w))
        assert np.abs(a / ref - 1)[[2, 4]].max() < 0.005
        assert np.abs(a / ref - 1)[[0, 5]].max() < 0.04


def test_decays_follow_the_eigen_analysis(system):
    """Free decays in all six DOFs (linear mooring, linearised drag, radiation state space):
    zero-crossing frequencies within 2 % of the eigen-analysis (the surge decay sees the
    state-space model's A11, 1.3 % above the BEM's at low frequency)."""
    decays = semi_decays(system)
    modes = {m.dominant_dof: m.frequency for m in semi_modes(system)}
    for dof, d in decays.items():
        assert d["hz"] == pytest.approx(modes[dof], rel=0.02), dof


@pytest.mark.slow
def test_raos_time_domain_against_frequency_domain(system):
    """Six DOFs, three headings: the Cummins run's steady-state amplitudes equal the frequency
    domain of the same linear system (its radiation state space) within 1 %; against the
    BEM's A(ω), B(ω) heave within 0.2 %, surge and sway 2 %, the rotations 8 % (their small
    responses near 17-30 s magnify the radiation model's 1-3 % in A11, A15; docs)."""
    points = semi_raos(system, [7.0, 11.0, 17.0, 22.0], [0.0, 30.0, 60.0], quick=True)
    bound = {"Surge": 0.02, "Sway": 0.02, "Heave": 0.002, "Roll": 0.08, "Pitch": 0.08,
             "Yaw": 0.08}
    for p in points:
        scale = {"m": max(p["frequency_domain"][d] for d in ("Surge", "Sway", "Heave")),
                 "rad": max(p["frequency_domain"][d] for d in ("Roll", "Pitch", "Yaw"))}
        for d in RIGID_DOFS:
            unit = "m" if d in ("Surge", "Sway", "Heave") else "rad"
            if p["frequency_domain"][d] > 1e-3 * scale[unit]:
                where = (p["heading_deg"], p["period"], d)
                assert p["relative_error_ss"][d] < 0.01, where
                assert p["relative_error"][d] < bound[d], where


def test_raos_six_dofs_three_headings_in_seconds(system):
    """The fast companion of the slow RAO table: one period (12 s, the sea states' peak) at
    0°, 30°, 60°, all six DOFs moved by the wave: the Cummins run's
    steady-state amplitude equals the frequency domain of the same linear system within 1 %
    (the closed-form steady state of that system: the time integration, the excitation at
    the heading and the coupling are right); at 30° sway, roll and yaw move."""
    points = semi_raos(system, [12.0], [0.0, 30.0, 60.0], quick=True)
    for p in points:
        fd = p["frequency_domain"]
        scale = {"m": max(fd[d] for d in ("Surge", "Sway", "Heave")),
                 "rad": max(fd[d] for d in ("Roll", "Pitch", "Yaw"))}
        for d in RIGID_DOFS:
            unit = "m" if d in ("Surge", "Sway", "Heave") else "rad"
            if fd[d] > 1e-3 * scale[unit]:
                assert p["relative_error_ss"][d] < 0.01, (p["heading_deg"], p["period"], d)
        if p["heading_deg"] == 30.0:
            assert min(fd["Sway"], fd["Roll"], fd["Yaw"]) > 1e-4


def test_six_dof_diagnostic_in_an_oblique_sea(system):
    """The 6×6 diagnostic on a linear six-DOF run in a 30° sea (linear mooring and drag, so
    Newton gives the answers): nothing known → α = M of the case's mass items (M15 = m z_G,
    M24 = −m z_G); C, K, A∞ known → α = M + A∞; the sway–roll coupling a 30° sea excites is
    identifiable at 1e-4; leaving A∞ to the network is the added-mass instability,
    ρ((M+A_k)⁻¹α) ≈ ρ(M⁻¹A∞) (> 1 for the semi's 6×6 matrices)."""
    from hybridwsi.cummins import simulate
    from hybridwsi.report.fowt_semi import semi_diagnostic
    from hybridwsi.waves import JONSWAP

    wave = JONSWAP(hs=4.0, tp=11.0, seed=1, n_components=60, direction=math.radians(30.0))
    hist = simulate(system.coeffs, dofs=list(RIGID_DOFS), duration=300.0, dt=0.2, wave=wave,
                    ramp=20.0, forces=system.forces(), radiation_ss=system.radiation_ss)
    diag = semi_diagnostic(system, hist)
    rows = {r["partition"]: r for r in diag["partitions"]}
    mass = np.asarray(hist["mass"].values, dtype=float)  # what the run integrated
    by_hand = np.zeros((6, 6))  # Σ of the case's items: ½ m |u − r × θ̇|² + ½ θ̇ᵀ I θ̇
    for item in CASE["body"]["items"]:
        mi, r = float(item["mass"]), np.asarray(item["cm"], dtype=float)
        skew = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        by_hand[:3, :3] += mi * np.eye(3)
        by_hand[:3, 3:] -= mi * skew
        by_hand[3:, :3] += mi * skew
        by_hand[3:, 3:] += np.diag(item["inertia"]) + mi * skew.T @ skew
    # 1e-3: the rotor's inertia is about its 5°-tilted shaft in the body, about x here
    assert np.allclose(mass, by_hand, rtol=0, atol=1e-3 * np.abs(by_hand).max())
    m, zg = mass[0, 0], mass[0, 4] / mass[0, 0]
    assert m == pytest.approx(14_072_718.0, rel=1e-6) and zg == pytest.approx(-9.889, abs=2e-3)
    assert mass[1, 3] == pytest.approx(-m * zg, rel=1e-9)
    assert np.allclose(rows["1"]["alpha"], mass, rtol=0, atol=1e-6 * np.abs(mass).max())
    a_inf = np.asarray(hist["added_mass_inf"].values)
    assert np.allclose(rows["3"]["alpha"], mass + a_inf, rtol=0, atol=1e-5 * np.abs(mass).max())
    assert "Sway-Roll" in rows["3"]["couplings_identifiable"]["0.0001"]
    rho = float(np.abs(np.linalg.eigvals(np.linalg.solve(mass, a_inf))).max())
    assert diag["rho_M_inv_A_inf"] == pytest.approx(rho, rel=1e-9) and rho > 1.0
    assert rows["A_inf_to_network"]["added_mass_ratio"] == pytest.approx(rho, rel=0.03)
    assert rows["A_inf_to_network"]["lagged_verdict"] == "unstable"
    assert rows["1"]["observed"]["observed_stable"] is False  # the lagged run of α = M diverges


# ----------------------------------------------------------------------- the hybrid (item 5)
def test_semi_hybrid_learns_only_drag_and_mooring_nonlinearity(system):
    """The semi's hybrid on a small configuration (two 120 s seas at 30°, a tiny network):
    the partition's known components are the four candidates, MoorPy's −K q and the member
    drag's Borgman linearisation −B_lin ż (``[hybrid] known_linear_drag``), so the residual
    the network learns is the drag's departure from −B_lin ż plus the mooring's from −K q,
    exactly up to the known radiation memory's re-integration of the recorded ż (checked
    against the recorded F_rad_mem); A∞ is known and z̈ is no input, so the learned force
    carries no inertia (added-mass ratio 0: no added-mass instability of the lagged
    coupling); the held-out rollout reports an error for each of the six DOFs."""
    pytest.importorskip("torch")
    from hybridwsi.casemodel import linearised_member_drag
    from hybridwsi.diagnostic.partition import build_candidates
    from hybridwsi.forces import MooringSystem
    from hybridwsi.report import fowt_semi_hybrid as fsh
    from hybridwsi.surrogate.certified import prepare_histories
    from hybridwsi.surrogate.network import target_force

    model = fsh.semi_case_model(system, CASE, 0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        refs = [model.simulate(duration=120.0, dt=0.2, wave=fsh.semi_sea(s), ramp=20.0)
                for s in (*fsh.SEMI_HYBRID_TRAIN, fsh.SEMI_HYBRID_TEST[0])]
    net = {**CASE["hybrid"]["network"], "hidden": (8,), "max_epochs": 5}
    cm = fsh.train_semi_hybrid(model, refs[:2], net)
    assert cm.doc["partition"]["known"] == fsh.SEMI_HYBRID_PARTITION.split("+")
    assert "z" in cm.doc["partition"]["network_inputs"]
    assert "zddot" not in cm.doc["partition"]["network_inputs"]

    hist = prepare_histories(refs[:1], ["sea 1"], model)[0]
    f_bb = target_force(hist, "F_bb", known=cm.pipeline.known_, force="F_tot")
    memory = build_candidates(hist, model.coeffs, ("radiation_memory",))["radiation_memory"]
    re_integration = memory.force(hist) - hist["F_rad_mem"].values
    k = MooringSystem.from_case(CASE).stiffness()
    b_lin = linearised_member_drag(CASE)
    assert np.all(np.diag(b_lin) > 0)  # a damping in every DOF
    drag = hist["F_morison"].values
    learned = (drag + hist["F_mooring"].values + hist["z"].values @ k.T
               + hist["zdot"].values @ b_lin.T)
    assert np.abs(drag).max(0).min() > 0  # the drag acts on every DOF in a 30° sea
    assert np.allclose(f_bb + re_integration, learned, rtol=0,
                       atol=1e-8 * np.abs(learned).max())

    assert cm.doc["certificate"]["added_mass_ratio"] == 0.0
    rows, hybs = fsh.held_out(cm, model, refs[2:], fsh.SEMI_HYBRID_TEST[:1])
    assert list(rows[0]["nrms_z"]) == list(RIGID_DOFS)
    assert all(np.isfinite(v) or rows[0]["blew_up"] for v in rows[0]["nrms_z"].values())
    assert hybs[0]["z"].shape[1] == 6
