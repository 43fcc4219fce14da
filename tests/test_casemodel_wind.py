"""Issue 29 wiring: the slow drift as a ``[forces] drift`` switch (``F_drift``), the rotor's
state and wind as case settings with command-line overrides, and a run that starts from the
mean offset (checked against RAFT's, an independent code, and against staying put)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

from hybridwsi import waves
from hybridwsi.casemodel import CaseModel, case_components
from hybridwsi.cases import from_dict, load_case, raw_case, with_values
from hybridwsi.cli import main
from hybridwsi.commands._options import case_overrides
from hybridwsi.errors import InputError
from hybridwsi.forces import OperatingRotor
from hybridwsi.forces.drift import SlowDriftForce

pytest.importorskip("moorpy")

DOFS = ("Surge", "Heave", "Pitch")
RAFT = Path(__file__).resolve().parents[1] / "docs" / "figures" / "raft_oc3_rotor.json"


@pytest.fixture(scope="module")
def oc3():
    return load_case("oc3_hywind")


def _args(**given) -> argparse.Namespace:
    keys = ("rotor", "wind_speed", "turbulence_intensity", "wind_seed", "slow_drift")
    return argparse.Namespace(**{k: given.get(k) for k in keys})


def test_drift_is_a_forces_switch_recorded_as_F_drift(oc3):
    assert oc3["forces"]["drift"] is False  # off unless switched on: earlier runs unchanged
    sea = waves.JONSWAP(hs=6.0, tp=12.0, seed=3)
    assert "drift" not in case_components(oc3, DOFS, wave=sea)
    on = with_values(oc3, {"forces": {"drift": True}})
    assert on.sha256 != oc3.sha256 and on.name == oc3.name
    comps = case_components(on, DOFS, wave=None, sea=sea, ramp=5.0)
    assert isinstance(comps["drift"], SlowDriftForce) and comps["drift"].ramp == 5.0
    assert "drift" not in case_components(on, DOFS)  # no sea, nothing to drift in
    raw = raw_case("oc3_hywind")
    del raw["drift"]
    raw["forces"] = {"drift": True}
    with pytest.raises(InputError, match=r"forces\.drift.*no \[drift\] table"):
        from_dict(raw, label="x.toml")


def test_overrides_of_the_command_line():
    assert case_overrides(_args()) == {}
    assert case_overrides(_args(wind_speed=11.4)) == {
        "rotor": {"wind_speed": 11.4, "state": "operating"}, "forces": {"rotor": True}}
    assert case_overrides(_args(rotor="parked", slow_drift=False)) == {
        "rotor": {"state": "parked"}, "forces": {"drift": False}}
    with pytest.raises(InputError, match="--wind-speed.*not with --rotor parked"):
        case_overrides(_args(rotor="parked", wind_speed=8.0))


def test_the_run_starts_from_the_mean_offset(oc3):
    """8 m/s steady wind, quasi-steady rotor, MoorPy table mooring: the static offset within
    1.5 % (surge) and 3 % (pitch) of RAFT 2.0.4's on the same design (its own mooring statics
    and rotor model; docs/OC3_HYWIND.md "Mean offsets beside RAFT"), and a calm-water run
    started there stays there (its equilibrium is the ODE's)."""
    model = CaseModel.build(oc3, dofs=DOFS, dt=0.1,
                            overrides=case_overrides(_args(wind_speed=8.0)))
    comps = model.components()
    assert isinstance(comps["rotor"], OperatingRotor)
    offset = model.mean_offset(comps)
    raft = json.loads(RAFT.read_text())["results"]["no_control"]["8"]
    assert offset[0] == pytest.approx(raft["surge_m"], rel=0.015)
    assert offset[2] == pytest.approx(raft["pitch_rad"], rel=0.03)
    hist = model.simulate(duration=20.0, dt=0.1)
    assert json.loads(hist.attrs["mean_offset"])["Surge"] == pytest.approx(offset[0])
    np.testing.assert_allclose(hist["z"].values, np.tile(offset, (hist.sizes["time"], 1)),
                               atol=1e-6)
    rest = model.simulate(duration=1.0, dt=0.1, from_offset=False)
    assert np.all(rest["z"].values[0] == 0.0)


def test_simulate_options_need_a_case_and_agree(tmp_path, capsys):
    out = str(tmp_path / "h.nc")
    assert main(["simulate", "--panels", "40", "--wind-speed", "8", "--out", out]) == 2
    assert "--rotor/--wind-*/--slow-drift needs --case" in capsys.readouterr().err
    code = main(["simulate", "--case", "oc3_hywind", "--rotor", "thrust", "--wind-speed", "8",
                 "--out", out, "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "not with --rotor thrust" in err


def test_sweep_settings_carry_the_overrides():
    """A sweep with a wind is another set-up: its settings (and so its resume hash) differ
    from the parked one's by the overrides and the changed case's content hash."""
    from hybridwsi.sweep import SweepConfig, settings

    wind = {"rotor": {"state": "operating", "wind_speed": 11.4}, "forces": {"rotor": True}}
    parked = settings(SweepConfig.for_case("oc3_hywind"))
    operating = settings(SweepConfig.for_case("oc3_hywind", overrides=wind))
    assert "overrides" not in parked and operating["overrides"] == wind
    assert operating["case_sha256"] != parked["case_sha256"]
    assert any("11.4" in f for f in operating["forces"])
