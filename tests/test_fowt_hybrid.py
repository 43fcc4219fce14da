"""OC3-Hywind diagnostic in several DOFs and the 3-DOF hybrid (issue 13 items 7-8).

References are independent of the regression: the rigid-body mass matrix summed by hand from
the case's mass items (Table 3-1 and the deck), the waterplane C33 = ρ g π r², the published
mooring stiffness (Eq. 5-3), the BEM A∞ read from the coefficients, and Newton (F_tot = M z̈).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import xarray as xr

from hybridwsi.cases import load_case
from hybridwsi.cummins import build_system
from hybridwsi.diagnostic import stability
from hybridwsi.forces import MooringForce, MooringSystem
from hybridwsi.hydro import coefficients as co
from hybridwsi.surrogate import fowt as fd
from hybridwsi.report import fowt, fowt_hybrid as fh
from hybridwsi.casemodel import linear_components
from hybridwsi.report.fowt import oc3_coefficients

DOFS = ["Surge", "Heave", "Pitch"]


@pytest.fixture(scope="module")
def setup():
    case = load_case("oc3_hywind")
    coeffs = oc3_coefficients(case)
    cfg = fd.hybrid_settings(case, quick=True)
    k6 = MooringSystem.from_case(case).stiffness()
    klin, damp = linear_components(case, DOFS, stiffness=k6)
    moor = MooringForce.from_case(case, DOFS)
    ss = build_system(coeffs, dofs=DOFS, dt=cfg["dt"]).ss
    hist = fd.irregular_history(coeffs, case, moor, damp, cfg["train"][0], dofs=DOFS,
                                duration=200.0, dt=cfg["dt"], ramp=cfg["ramp"], radiation_ss=ss)
    parts = fd.partitions(hist, klin, damp)
    return {"case": case, "coeffs": coeffs, "cfg": cfg, "hist": hist, "parts": parts}


def _entry(setup, name: str) -> dict:
    return fd.partition_entry(name, setup["hist"], setup["parts"][name], [1e-4, 0.01],
                              dt=setup["cfg"]["dt"], perturbation=1e-3)


def _mass_by_hand(case) -> np.ndarray:
    """Surge/heave/pitch rigid-body mass about the SWL origin from the case's mass items."""
    m = mz = iyy = 0.0
    for item in case["body"]["items"]:
        mi, (x, _, z) = item["mass"], item["cm"]
        m += mi
        mz += mi * z
        iyy += item["inertia"][1] + mi * (x * x + z * z)
    # M[surge, pitch] = m z_G (a pitch rotation θ moves the CM by z_G θ in surge)
    return np.array([[m, 0.0, mz], [0.0, m, -sum(i["mass"] * i["cm"][0]
                                                  for i in case["body"]["items"])],
                     [mz, -sum(i["mass"] * i["cm"][0] for i in case["body"]["items"]), iyy]])


def test_partition1_is_newton(setup):
    """F_tot = M z̈ exactly: α = M (with the surge–pitch coupling m z_G), β = γ = 0."""
    e = _entry(setup, "1")
    m = _mass_by_hand(setup["case"])
    alpha = np.asarray(e["alpha"])
    np.testing.assert_allclose(alpha[[0, 0, 2], [0, 2, 2]], m[[0, 0, 2], [0, 2, 2]], rtol=1e-6)
    np.testing.assert_allclose(alpha[1, 1], m[1, 1], rtol=1e-6)
    scale = np.abs(alpha).max()
    assert np.abs(e["beta"]).max() < 1e-6 * scale and np.abs(e["gamma"]).max() < 1e-6 * scale
    assert min(e["r2"]) > 1 - 1e-10


def test_partition2_gamma_is_hydrostatics_plus_linear_mooring(setup):
    """F_tot − F_hs − F_moor,lin: α = M, γ = C_hs + K (C33 = ρ g π r², K from Eq. 5-3)."""
    case = setup["case"]
    e = _entry(setup, "2")
    np.testing.assert_allclose(np.asarray(e["alpha"])[0, 0], _mass_by_hand(case)[0, 0], rtol=1e-6)
    g = np.asarray(e["gamma"])
    ref_k = np.asarray(case["mooring"]["reference"]["K"])
    env = case["environment"]
    c33 = env["rho"] * env["g"] * math.pi * 3.25 ** 2
    assert g[0, 0] == pytest.approx(ref_k[0, 0], rel=0.01)
    assert g[1, 1] == pytest.approx(c33 + ref_k[2, 2], rel=0.005)
    assert g[0, 2] == pytest.approx(ref_k[0, 4], rel=0.01)
    assert g[2, 0] == pytest.approx(ref_k[4, 0], rel=0.01)


def test_partition3_alpha_is_mass_plus_a_inf(setup):
    """Also − F_A∞: α = M + A∞ (the BEM matrix, all couplings)."""
    e = _entry(setup, "3")
    expect = _mass_by_hand(setup["case"]) + co.matrix(setup["coeffs"], "added_mass_inf", DOFS)
    alpha = np.asarray(e["alpha"])
    for i, j in ((0, 0), (1, 1), (2, 2), (0, 2), (2, 0)):
        assert alpha[i, j] == pytest.approx(expect[i, j], rel=1e-5)


@pytest.mark.parametrize("name", ["1", "2", "3"])
def test_newton_partitions_cannot_be_lagged(setup, name):
    """α = M + A_k: the added-mass ratio is 1; the lagged run of that surrogate diverges."""
    e = _entry(setup, name)
    assert e["added_mass_ratio"] == pytest.approx(1.0, abs=1e-6)
    assert not e["predicted_stable"]
    assert not e["observed"]["observed_stable"]
    assert fd.verdict_line(e)[0] == "ODE"


def test_a_inf_to_network_is_the_added_mass_instability(setup):
    """Leaving A∞ to the network: α ≈ −A∞ and ρ((M)⁻¹α) ≈ ρ(M⁻¹A∞) > 1 because of the
    surge–pitch coupling (surge alone A11/M11 < 1)."""
    e = _entry(setup, "A_inf_to_network")
    m = _mass_by_hand(setup["case"])
    a_inf = co.matrix(setup["coeffs"], "added_mass_inf", DOFS)
    rho = float(np.max(np.abs(np.linalg.eigvals(np.linalg.solve(m, a_inf)))))
    assert a_inf[0, 0] / m[0, 0] < 1.0 < rho
    assert e["added_mass_ratio"] == pytest.approx(rho, rel=0.03)
    assert not e["predicted_stable"] and fd.verdict_line(e)[0] == "ODE"


def test_recommended_partition_is_lag_safe(setup):
    """Drag + mooring nonlinearity only: tiny α, the lagged step map stable."""
    e = _entry(setup, "recommended")
    assert e["added_mass_ratio"] < 0.05
    assert e["predicted_stable"] and fd.verdict_line(e)[0] == "network"
    # the same check straight from the stability module with α = 0 (no inertia in the residual)
    m = _mass_by_hand(setup["case"])
    a_inf = co.matrix(setup["coeffs"], "added_mass_inf", DOFS)
    assert stability.added_mass_ratio(m, a_inf, np.zeros((3, 3))) == 0.0


def test_diagnostic_markdown_lists_every_partition(setup):
    diag = fd.diagnostic([setup["hist"]], *linear_components(
        setup["case"], DOFS, stiffness=MooringSystem.from_case(setup["case"]).stiffness()),
        setup["cfg"])
    md = fh.diagnostic_markdown(diag)
    for name in fd.RESIDUAL:
        assert f"| {name} |" in md
    json.dumps(fh.json_safe(diag))  # strict JSON


def test_json_safe_writes_strict_json():
    out = fh.json_safe({"a": float("inf"), "b": (np.float64(1.5), np.bool_(True)), 3: np.int64(2)})
    assert out == {"a": None, "b": [1.5, True], "3": 2}


def test_run_fowt_quick_writes_items_7_and_8(quick_results):
    """The report section (quick, through ``run_fowt`` as ``reproduce --quick`` runs it: the
    session's shared run, tests/conftest.py): verdicts agree with every rollout, the
    A∞ partition is predicted unstable and is, the recommended one tracks the held-out seas
    and runs the long sea stably."""
    md = (quick_results / "report.md").read_text()
    folder = quick_results / "fowt"
    hyb = json.loads((folder / "hybrid.json").read_text())
    diag = json.loads((folder / "diagnostic.json").read_text())
    assert (folder / "hybrid_rollout.png").is_file()
    with xr.open_dataset(folder / "hybrid_rollout.nc") as ds:
        assert set(ds.data_vars) == {"z_reference", "z_hybrid"}
    parts = {p["partition"]: p for p in hyb["partitions"]}
    assert hyb["all_agree"]
    a_inf = parts["A_inf_to_network"]["lagged"]
    assert not a_inf["predicted_stable"] and not a_inf["observed_stable"]
    rec = parts["recommended"][hyb["settings"]["mode"]]
    assert rec["predicted_stable"] and rec["observed_stable"]
    for case_err in rec["rollout_error_percent_rms"]:
        assert max(case_err.values()) < 5.0
    assert hyb["long_run"]["predicted_stable"] and not hyb["long_run"]["blew_up"]
    # the diagnostic's lagged verdicts agree with the observed behaviour of every partition
    for p in diag["partitions"]:
        if p["partition"] in parts:
            assert p["predicted_stable"] == parts[p["partition"]]["lagged"]["observed_stable"]
        else:
            assert p["predicted_stable"] == p["observed"]["observed_stable"]
    assert "Hybrid (network in the loop)" in md and "Diagnostic in several DOFs" in md
