"""The floating-wind report section (``hybridwsi.report.fowt``) on OC3-Hywind.

References: Jonkman 2010 (NREL/TP-500-47535) Eq. 5-2/5-3 and the OC3 natural frequencies
(0.0080, 0.0324, 0.034 Hz); the RAOs against the frequency-domain solution of the same
linear system (an independent route: complex linear algebra at ω, no time stepping).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hybridwsi.cases import load_case
from hybridwsi.hydro import bem

pytest.importorskip("moorpy")
fowt = pytest.importorskip("hybridwsi.report.fowt")

CASE = load_case("oc3_hywind")


@pytest.fixture(scope="module")
def section(quick_results) -> tuple[Path, str]:
    """``run_fowt(quick=True)`` as ``reproduce --quick`` runs it (the session's shared run,
    tests/conftest.py): its folder and the report that holds its Markdown section."""
    return quick_results / "fowt", (quick_results / "report.md").read_text()


def _json(folder: Path, name: str):
    return json.loads((folder / name).read_text())


def test_files_and_json_shapes(section):
    folder, md = section
    for name in ("mooring.json", "natural_frequencies.json", "rao.json", "rao.png", "rao.nc",
                 "decay.png", "decay.nc"):
        assert (folder / name).stat().st_size > 0, name
    nat = _json(folder, "natural_frequencies.json")
    assert list(nat) == ["surge", "heave", "pitch"]
    for entry in nat.values():
        assert {"hz", "reference_hz", "from_decay_hz"} <= set(entry)
        assert all(isinstance(entry[k], float) for k in ("hz", "reference_hz", "from_decay_hz"))
    assert [nat[d]["reference_hz"] for d in nat] == [0.0080, 0.0324, 0.034]
    moor = _json(folder, "mooring.json")
    assert np.asarray(moor["K"]).shape == (6, 6) and len(moor["F0"]) == 6
    assert moor["dofs"] == ["Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"]
    assert "units" in moor and "reference" in moor
    assert "## Floating offshore wind" in md and "fowt/rao.png" in md


def test_natural_frequencies_within_two_percent(section):
    nat = _json(section[0], "natural_frequencies.json")
    for dof, entry in nat.items():
        assert entry["hz"] == pytest.approx(entry["reference_hz"], rel=0.02), dof
        assert entry["from_decay_hz"] == pytest.approx(entry["reference_hz"], rel=0.02), dof
        # two routes (eigen-analysis with A(ω_n), time domain with the radiation memory)
        assert entry["from_decay_hz"] == pytest.approx(entry["hz"], rel=0.01), dof
        # small offsets: the tabulated nonlinear mooring gives the linearised result
        assert entry["from_decay_tabulated_mooring_hz"] == pytest.approx(
            entry["from_decay_hz"], rel=1e-3), dof


def test_rao_time_domain_matches_frequency_domain(section):
    rao = _json(section[0], "rao.json")
    assert len(rao["points"]) >= 5
    assert rao["units"] == {"Surge": "m/m", "Heave": "m/m", "Pitch": "rad/m"}
    for p in rao["points"]:
        for dof in ("Surge", "Heave", "Pitch"):
            td, fd = p["time_domain"][dof], p["frequency_domain"][dof]
            assert td > 0 and td == pytest.approx(fd, rel=0.01), (p["period"], dof)


def test_mooring_against_eq_5_3(section):
    moor = _json(section[0], "mooring.json")
    k, ref = np.asarray(moor["K"]), CASE["mooring"]["reference"]
    kr = np.asarray(ref["K"])
    for i, j in [(0, 0), (2, 2), (4, 4), (0, 4), (1, 1), (3, 3)]:
        assert k[i, j] == pytest.approx(kr[i, j], rel=0.01), (i, j)
    assert k[5, 5] == pytest.approx(kr[5, 5] + 9.834e7, rel=0.01)  # lines + the yaw spring
    assert moor["F0"][2] == pytest.approx(ref["preload"][2], rel=0.005)


def test_coefficients_are_the_shipped_ones_without_solving(tmp_path, monkeypatch):
    monkeypatch.setattr(bem.run, "solve_missing", lambda *a, **k: pytest.fail("solved"))
    ds = fowt.oc3_coefficients(CASE, cache_dir=tmp_path)
    with xr.open_dataset(bem.PAPER_COEFFS.parent / "bem_oc3_hywind.nc") as ref:
        assert ds.attrs["input_hash"] == ref.attrs["input_hash"]


def test_harmonic_amplitude_recovers_a_phasor():
    t = np.arange(0.0, 100.0, 0.05)
    w = 2 * math.pi / 10.0
    amp = 0.7 * np.exp(0.4j)
    y = (amp * np.exp(1j * w * t)).real + 0.3
    assert fowt.harmonic_amplitude(t, y, w) == pytest.approx(amp, rel=1e-12)


def test_frequency_response_of_one_dof_oscillator():
    """1 DOF heave only, synthetic coefficients: X = F / (C + K − ω²(m + A) + iω(B + B_add))."""
    import synthetic_hydro
    ds = synthetic_hydro.coefficients()
    w, k, badd = 5.0, 300.0, 40.0
    x = fowt.frequency_response(ds, w, np.array([2.0]), np.array([[k]]), np.array([[badd]]),
                                dofs=["Heave"])
    b = float(synthetic_hydro.damping(np.array([w]))[0])  # closed form, not the Dataset
    expect = 2.0 / (synthetic_hydro.C + k - w**2 * (synthetic_hydro.M
                                                   + synthetic_hydro.added_mass(w))
                    + 1j * w * (b + badd))
    assert x[0] == pytest.approx(expect, rel=1e-3)


def test_semi_section_in_the_report(quick_results):
    """``run_fowt_semi(quick=True)`` in the shared ``reproduce --quick`` run: its files, the
    six modes (heave within 3 % of the code comparison's 0.0578 Hz; the others documented in
    docs/OC4_SEMI.md), decays within 2 % of the eigen-analysis, every RAO point's time domain
    equal to the frequency domain of the same system within 1 % (the DOFs the wave moves), and
    the diagnostic's nothing-known partition α = M (Newton) for all six DOFs."""
    folder = quick_results / "fowt_semi"
    for name in ("natural_frequencies.json", "decay.png", "decay.nc", "rao.json", "rao.png",
                 "rao.nc", "diagnostic.json"):
        assert (folder / name).stat().st_size > 0, name
    nat = _json(folder, "natural_frequencies.json")
    assert nat["Heave"]["hz"] == pytest.approx(0.0578, rel=0.03)
    for dof in ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"):
        assert nat[dof]["from_decay_hz"] == pytest.approx(nat[dof]["hz"], rel=0.02), dof
    rao = _json(folder, "rao.json")
    assert sorted({p["heading_deg"] for p in rao["points"]}) == [0.0, 30.0, 60.0]
    for p in rao["points"]:
        fd = p["frequency_domain"]
        for dof, err in p["relative_error_ss"].items():
            group = ("Surge", "Sway", "Heave") if dof in ("Surge", "Sway", "Heave") else (
                "Roll", "Pitch", "Yaw")
            if fd[dof] > 1e-3 * max(fd[g] for g in group):
                assert err < 0.01, (p["heading_deg"], p["period"], dof)
    diag = _json(folder, "diagnostic.json")
    first = next(r for r in diag["partitions"] if r["partition"] == "1")
    assert np.allclose(first["alpha"], diag["mass"], rtol=0, atol=1e-6 * np.abs(diag["mass"]).max())
    md = (quick_results / "report.md").read_text()
    assert "## Floating offshore wind: OC4-DeepCwind" in md and "fowt_semi/rao.png" in md


def test_semi_hybrid_in_the_report(quick_results):
    """The semi's hybrid in the shared ``reproduce --quick`` run (issue 30 item 5): the
    diagnostic's recommended partition (hydrostatics, A∞, radiation memory, excitation and
    MoorPy's −K q known, so the network's residual is the drag and the mooring nonlinearity),
    no inertia learned (A∞ known, no z̈ input: added-mass ratio 0), a held-out error for each
    of the six DOFs in each held-out sea, the hybrid bounded and closer to the reference than
    no motion at all (error < 100 % in every DOF) in the held-out 30° sea, the predicted and
    observed stability recorded with their agreement, the model folder that ``simulate
    --network`` reads, and the rollout on the reference's axes."""
    folder = quick_results / "fowt_semi"
    for name in ("hybrid.json", "hybrid_rollout.png", "hybrid_rollout.nc",
                 "hybrid_model/model.json", "hybrid_model/network.pt"):
        assert (folder / name).stat().st_size > 0, name
    hyb = _json(folder, "hybrid.json")
    dofs = ["Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"]
    assert hyb["partition"]["candidates"] == ["hydrostatic", "added_mass_inf",
                                              "radiation_memory", "excitation"]
    assert "zddot" not in hyb["partition"]["network_inputs"]
    assert hyb["certificate"]["added_mass_ratio"] == 0.0
    for row in hyb["held_out"]:
        assert list(row["nrms_z"]) == dofs
        for key in ("nrms_z_low", "nrms_z_wave"):  # the two bands make up the whole error
            assert all(row[key][d] <= row["nrms_z"][d] * (1 + 1e-9) for d in dofs)
    first = hyb["held_out"][0]
    assert first["sea"]["heading_deg"] == 30.0 and not first["blew_up"]
    assert all(0.0 < first["nrms_z"][d] < 1.0 for d in dofs)
    predicted = hyb["certificate"]["spectral_radius"] <= 1.0 + 1e-6
    assert hyb["predicted_stable"] == predicted
    assert hyb["agree"] == (hyb["predicted_stable"] == hyb["observed_stable"])
    # the certificate's largest stable Δt is on the side of its verdict at the model's Δt
    top = hyb["certificate"]["max_stable_dt"]
    assert (top is None or top >= hyb["settings"]["dt"]) == hyb["predicted_stable"]
    # observed: a perturbation of the hybrid decays (σ < 0) exactly when observed stable
    assert all((r["perturbation_rate"] <= 0.0) == r["observed_stable"]
               for r in hyb["held_out"] if not r["blew_up"])
    model = _json(folder / "hybrid_model", "model.json")
    assert model["case"]["sha256"] == load_case("oc4_semi").sha256 and model["dofs"] == dofs
    ds = xr.open_dataset(folder / "hybrid_rollout.nc")
    assert ds["z_reference"].shape == ds["z_hybrid"].shape and ds.sizes["dof"] == 6
    md = (quick_results / "report.md").read_text()
    assert "fowt_semi/hybrid_rollout.png" in md and "held out: Hs 5 m" in md
