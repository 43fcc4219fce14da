"""Dask sweep of a built-in case (OC3-Hywind): the case's coefficients, DOFs and forces,
resume = uninterrupted run, settings that include the case and its forces, statistics."""

from __future__ import annotations

import json
import pickle
from dataclasses import asdict, replace

import numpy as np
import pytest
import xarray as xr

pytest.importorskip("distributed")
pytest.importorskip("zarr")
pytest.importorskip("moorpy")

from hybridwsi import cummins, sweep
from hybridwsi.cases import from_dict, load_case, raw_case
from hybridwsi.casemodel import case_coefficients
from hybridwsi.cli import main
from hybridwsi.errors import InputError
from hybridwsi.forces import MooringForce, MooringSystem, MorisonDrag, additional_damping
from hybridwsi.sweep import SweepConfig
from hybridwsi.waves import JONSWAP

OC3_DOFS = ("Surge", "Heave", "Pitch")
GRID = ([3.0, 6.0], [10.0], 2)  # 4 seas
SHORT = {"duration": 40.0, "dt": 0.1, "ramp": 10.0}


@pytest.fixture(scope="module")
def config() -> SweepConfig:
    return SweepConfig.for_case("oc3_hywind", **SHORT)


@pytest.fixture(scope="module")
def shared(config) -> dict:
    return sweep.case_setup(config)


def test_case_configuration_comes_from_the_case(config):
    full = SweepConfig.for_case("oc3_hywind")
    table = load_case("oc3_hywind")["sweep"]
    assert full.dofs == OC3_DOFS and full.case == "oc3_hywind"
    assert (full.duration, full.dt, full.ramp) == (table["duration"], table["dt"], table["ramp"])
    assert (full.gamma, full.wave_components) == (table["gamma"], table["wave_components"])
    assert (config.duration, config.dt, config.ramp) == (40.0, 0.1, 10.0)  # options win
    assert SweepConfig.for_case("oc3_hywind", dofs="surge,pitch").dofs == ("Surge", "Pitch")
    for bad in ({"mass": 1e6}, {"nonlinear_hydrostatics": True}, {"gamma": 0.5}):
        with pytest.raises(InputError):
            SweepConfig.for_case("oc3_hywind", **bad).check()
    with pytest.raises(InputError, match="Heave only"):
        SweepConfig(dofs=("Surge",)).check()
    with pytest.raises(InputError, match="unknown case"):
        SweepConfig.for_case("no_such_case")
    with pytest.raises(InputError, match="needs a case"):
        SweepConfig(mooring="table").check()


def test_sphere_settings_are_those_of_before_cases():
    """A sphere sweep started by the previous version keeps its settings hash (resumable)."""
    cfg = SweepConfig(duration=3.0, dt=0.02, ramp=0.5)
    before = {"duration": 3.0, "dt": 0.02, "coeffs": None, "mass": None,
              "nonlinear_hydrostatics": False, "ramp": 0.5, "coeffs_sha256": None,
              "runner": "hybridwsi.sweep.cummins_case"}
    assert sweep.settings(cfg) == before
    assert sweep.settings_hash(cfg) == sweep._digest(before)
    assert "gamma" in sweep.settings(replace(cfg, gamma=2.0))  # set: part of the set-up


def test_settings_include_the_case_and_its_forces(config, shared):
    current = sweep.settings(config, shared=shared)
    assert current["dofs"] == list(OC3_DOFS) and current["case"] == "oc3_hywind"
    names = " ".join(current["forces"])
    for part in ("mooring(3 lines", "morison_drag(Cd 0.6", "linear_damping", "parked_rotor"):
        assert part in names
    model = shared["_model"]
    assert current["mooring_table"] == model.mooring_table.dataset.attrs["input_hash"]
    assert current["coeffs_hash"] == model.coeffs.attrs["input_hash"]
    assert current["case_sha256"] == load_case("oc3_hywind").sha256
    assert current["models"]["mooring"] == "table"
    base = sweep._digest(current)
    # a sea option, the drag's wave kinematics and the case's content all change the set-up
    for changed in (replace(config, gamma=2.0), replace(config, wave_kinematics=False)):
        assert sweep._digest(sweep.settings(changed, shared=shared)) != base
    raw = raw_case("oc3_hywind")
    raw["hydrodynamics"]["drag_cd"] = 1.0
    heavier_drag = replace(model, case=from_dict(raw))
    other = sweep.settings(config, shared={"_model": heavier_drag})
    assert other["case_sha256"] != current["case_sha256"]
    assert other["forces"] != current["forces"] and sweep._digest(other) != base
    # what is shipped to every worker: the coefficients, the state space and the table
    blob = pickle.dumps({**asdict(config), **shared})
    assert len(blob) < 2_000_000, len(blob)


def test_case_sweep_resumed_equals_uninterrupted(tmp_path, config, monkeypatch):
    cases = sweep.case_grid(*GRID)
    out = tmp_path / "oc3"
    # the interrupted run: two seas finished (in this process), the manifest still "running",
    # a half-written part and a half-built store left behind, as a kill leaves them
    tabulated = []
    monkeypatch.setenv("HYBRIDWSI_CACHE", str(tmp_path / "cache"))  # no table kept before
    original = MooringSystem.tabulate
    monkeypatch.setattr(MooringSystem, "tabulate",
                        lambda self, *a, **k: tabulated.append(1) or original(self, *a, **k))
    sweep.run_sweep(cases[:2], out, config, scheduler="synchronous", progress=False,
              consolidate_store=False)
    assert len(tabulated) == 1  # the mooring table is built once, not per sea
    monkeypatch.undo()
    # from here on build the shared objects once per set-up (they are deterministic; saves
    # ~4 s of coefficient loading, tabulation and state-space fitting per run_sweep)
    built: dict = {}
    setup = sweep.case_setup

    def once(cfg: SweepConfig) -> dict:
        key = (cfg.case, cfg.coeffs, cfg.dofs, cfg.dt, cfg.mooring)
        if key not in built:
            built[key] = setup(cfg)
        return built[key]

    monkeypatch.setattr(sweep, "case_setup", once)
    done = sweep.finished_cases(out)
    assert done == {c["case_id"] for c in cases[:2]}
    assert json.loads((out / "manifest.json").read_text())["status"] == "running"
    (out / "parts" / f".{cases[2]['case_id']}.nc.tmp").write_bytes(b"half")
    (out / ".sweep.killed" / "sweep.zarr").mkdir(parents=True)
    stamps = {c: (out / "parts" / f"{c}.nc").stat().st_mtime_ns for c in done}

    # resuming with another set-up is refused in one line, before any sea runs
    for changed, what in ((replace(config, gamma=2.0), "gamma 3.3 -> 2.0"),
                          (replace(config, wave_kinematics=False), "wave_kinematics")):
        with pytest.raises(InputError, match=f"settings differ.*{what}") as err:
            sweep.run_sweep(cases, out, changed, scheduler="synchronous", progress=False)
        assert "\n" not in str(err.value)
    assert sweep.finished_cases(out) == done

    # resume on a LocalCluster of one worker process (the shared objects are shipped)
    store = sweep.run_sweep(cases, out, config, n_workers=1, progress=False)
    assert {c: (out / "parts" / f"{c}.nc").stat().st_mtime_ns for c in done} == stamps
    assert not list(out.glob(".sweep.*")) and not list((out / "parts").glob(".*.tmp"))
    ref = sweep.run_sweep(cases, tmp_path / "ref", config, scheduler="synchronous", progress=False)
    got = sweep.open_sweep(store).load()
    xr.testing.assert_identical(got, sweep.open_sweep(ref).load())  # bit-identical
    assert [str(d) for d in got["dof"].values] == list(OC3_DOFS)

    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "complete" and manifest["n_cases"] == 4
    assert manifest["inputs"]["case"] == "oc3_hywind" and manifest["versions"]["moorpy"]
    assert manifest["hybridwsi_version"] == manifest["versions"]["hybridwsi"]

    # the statistics are those of the stored motions after the ramp
    case = cases[3]
    hist = sweep.case_history(got, case["case_id"])
    after = hist["time"].values >= config.ramp
    stats = manifest["statistics"]["cases"][case["case_id"]]
    assert manifest["statistics"]["window_s"] == [config.ramp, config.duration]
    for j, dof in enumerate(OC3_DOFS):
        z = hist["z"].values[after, j]
        assert stats[dof]["std"] == pytest.approx(z.std(), rel=1e-12)
        assert stats[dof]["max"] == z.max() and stats[dof]["min"] == z.min()
        assert stats[dof]["unit"] == ("rad" if dof == "Pitch" else "m")

    # a stored sea equals a direct Cummins run with the case's forces built independently
    spec = load_case("oc3_hywind")
    wave = JONSWAP(hs=case["hs"], tp=case["tp"], seed=case["seed"], gamma=3.3, n_components=200)
    forces = [MooringForce.from_case(spec, OC3_DOFS),
              MorisonDrag.from_case(spec, OC3_DOFS, wave=wave, ramp=config.ramp),
              additional_damping(spec, OC3_DOFS)]
    direct = cummins.simulate(case_coefficients(spec), dofs=OC3_DOFS,
                              duration=config.duration, dt=config.dt, ramp=config.ramp,
                              wave=wave, forces=forces)
    np.testing.assert_allclose(hist["z"].values, direct["z"].values, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(hist["F_ext"].values, direct["F_ext"].values, rtol=1e-9,
                               atol=1e-6 * float(np.abs(direct["F_ext"].values).max()))


def test_sweep_command_with_a_case(tmp_path, capsys):
    out = tmp_path / "cli"
    argv = ["sweep", "--case", "oc3_hywind", "--hs", "4", "--tp", "9", "--dofs", "surge,pitch",
            "--duration", "20", "--ramp", "5", "--scheduler", "synchronous", "--out", str(out)]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "1 cases ->" in printed and "Surge std" in printed and "Pitch std" in printed
    ds = sweep.open_sweep(out)
    assert [str(d) for d in ds["dof"].values] == ["Surge", "Pitch"]
    assert float(ds["time"][-1]) == pytest.approx(20.0) and float(ds["time"][1]) == 0.1
    settings = json.loads((out / "manifest.json").read_text())["settings"]
    assert settings["case"] == "oc3_hywind" and settings["wave_components"] == 200
    manifest = json.loads((out / "manifest.json").read_text())
    assert sweep.sweep_coefficients(manifest).attrs["input_hash"] == settings["coeffs_hash"]
    for bad in (["--mass", "5e6"], ["--nonlinear-hydrostatics"], ["--case", "nope"]):
        assert main(argv[:-2] + bad + ["--out", str(tmp_path / "bad")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("error:"), err
    assert not (tmp_path / "bad").exists()


def test_heave_statistics_match_the_frequency_domain(tmp_path):
    """Heave of the spar is decoupled from surge/pitch and untouched by the transverse drag:
    over one repeat period of the sea (after the ramp) the sweep's std must equal the
    frequency-domain spectral sum Σ ½ |X(ω_j) a_j|², X from A(ω), B(ω), C + K33, B_add."""
    from hybridwsi.report.fowt import frequency_response
    from hybridwsi.waves import Regular, excitation_force

    hs, tp, ramp = 6.0, 10.0, 60.0
    comp = JONSWAP(hs=hs, tp=tp, seed=0, n_components=200).components()
    repeat = 2.0 * np.pi / (comp.omega[1] - comp.omega[0])  # the sea's period, 571 s
    cfg = SweepConfig.for_case("oc3_hywind", duration=round(ramp + repeat, 1), dt=0.1,
                               ramp=ramp, dofs="heave", gamma=3.3, wave_components=200)
    sweep.run_sweep(sweep.case_grid([hs], [tp], 1), tmp_path, cfg, scheduler="synchronous",
                    progress=False)
    stats = json.loads((tmp_path / "manifest.json").read_text())["statistics"]
    std_td = stats["cases"]["hs6_tp10_s0"]["Heave"]["std"]

    spec, dofs = load_case("oc3_hywind"), ["Heave"]
    coeffs = case_coefficients(spec)
    k33 = MooringSystem.from_case(spec).stiffness()[2:3, 2:3]  # MoorPy's analytic K33
    b_add = additional_damping(spec, dofs).linear_coefficients(1)[1]
    var, t0 = 0.0, np.zeros(1)
    for w, a in zip(comp.omega, comp.amplitude):  # F̂ of a unit-amplitude wave, e^{iωt}
        unit = Regular(period=2.0 * np.pi / w, height=2.0)
        f_hat = (excitation_force(unit, coeffs, t0, dofs)[0]
                 - 1j * excitation_force(unit, coeffs, t0 + 0.5 * np.pi / w, dofs)[0])
        var += 0.5 * (abs(frequency_response(coeffs, w, f_hat, k33, b_add, dofs)[0]) * a) ** 2
    assert std_td == pytest.approx(np.sqrt(var), rel=2e-3)
    assert stats["cases"]["hs6_tp10_s0"]["eta"]["hs_4std"] == pytest.approx(hs, rel=0.02)


def test_sweep_with_the_quasi_static_mooring_records_the_tensions(tmp_path):
    """--mooring quasi-static: MoorPy solved every call, the tensions stored per sea and
    summarised per line in the manifest (mean, std, max after the ramp)."""
    cfg = SweepConfig.for_case("oc3_hywind", duration=10.0, dt=0.1, ramp=2.0,
                               mooring="quasi-static")
    store = sweep.run_sweep(sweep.case_grid([4.0], [10.0], 1), tmp_path, cfg,
                            scheduler="synchronous", progress=False)
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["settings"]["mooring"] == "quasi-static"
    assert manifest["inputs"]["models"]["mooring"] == "quasi-static"
    assert manifest["inputs"]["mooring_table"] is None
    hist = sweep.case_history(sweep.open_sweep(store), 0)
    after = hist["time"].values >= 2.0
    stats = manifest["statistics"]["cases"]["hs4_tp10_s0"]["T_fairlead"]
    for k, line in enumerate(("1", "2", "3")):
        t = hist["T_fairlead"].values[after, k]
        assert stats[line]["max"] == pytest.approx(t.max(), rel=1e-12)
        assert stats[line]["mean"] == pytest.approx(t.mean(), rel=1e-12)
    assert {"F_mooring", "F_morison", "F_damping", "F_rotor", "T_anchor"} <= set(hist.data_vars)
