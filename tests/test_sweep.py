"""Dask sweep: one atomic part per case, resume after a kill, consolidated Zarr store."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

pytest.importorskip("distributed")
pytest.importorskip("zarr")

import synthetic_hydro

from hybridwsi import cummins, waves
from hybridwsi.errors import InputError
from hybridwsi.history import to_netcdf
from hybridwsi.sweep import (
    SweepConfig,
    case_grid,
    case_history,
    finished_cases,
    open_sweep,
    run_sweep,
)

DURATION, DT = 3.0, 0.02
HS, TP, SEEDS = [0.03, 0.05], [0.7, 0.8], 5  # 20 cases


@pytest.fixture(scope="module")
def coeff_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("coeffs") / "synthetic.nc"
    to_netcdf(synthetic_hydro.coefficients(np.linspace(0.1, 40.0, 200)), path)
    return path


def _config(coeff_file: Path) -> SweepConfig:
    return SweepConfig(duration=DURATION, dt=DT, coeffs=str(coeff_file), ramp=0.5)


def test_case_grid_ids_are_stable_and_unique():
    cases = case_grid(HS, TP, SEEDS)
    assert len(cases) == 20 and len({c["case_id"] for c in cases}) == 20
    assert case_grid([0.05], [0.8], [3])[0]["case_id"] in {c["case_id"] for c in
                                                           case_grid([0.05, 0.1], [0.8], 4)}
    with pytest.raises(InputError):
        case_grid([], TP, 1)
    with pytest.raises(InputError):
        case_grid([-1.0], TP, 1)


def test_sweep_resumes_after_kill(tmp_path, coeff_file):
    out = tmp_path / "sweep"
    script = (
        f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
        "from hybridwsi.sweep import SweepConfig, case_grid, run_sweep\n"
        f"run_sweep(case_grid({HS!r}, {TP!r}, {SEEDS}), {str(out)!r}, SweepConfig(duration="
        f"{DURATION!r}, dt={DT!r}, coeffs={str(coeff_file)!r}, ramp=0.5), progress=False,"
        " n_workers=1)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", script], start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:  # kill the whole sweep (client + workers) once some cases are finished
        deadline = time.time() + 40
        while len(finished_cases(out)) < 3 and time.time() < deadline and proc.poll() is None:
            time.sleep(0.2)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    done_before = finished_cases(out)
    assert 3 <= len(done_before) < 20, "the sweep should have been killed mid-way"
    assert not (out / "sweep.zarr").exists()
    stamps = {c: (out / "parts" / f"{c}.nc").stat().st_mtime_ns for c in done_before}

    with pytest.raises(InputError, match="resume"):
        run_sweep(case_grid(HS, TP, SEEDS), out, _config(coeff_file), resume=False, progress=False)
    # resuming with other settings (the issue: --ramp 5 after a kill) is refused in one line,
    # before any case runs
    changed = SweepConfig(duration=DURATION, dt=DT, coeffs=str(coeff_file), ramp=5.0)
    with pytest.raises(InputError, match=r"settings differ \(ramp 0.5 -> 5.0\)") as err:
        run_sweep(case_grid(HS, TP, SEEDS), out, changed, progress=False)
    assert "\n" not in str(err.value)
    assert finished_cases(out) == done_before
    # a kill during consolidation leaves a partial store folder: the next run removes it
    # (resumed on a LocalCluster of one worker process: each worker costs a few seconds)
    (out / ".sweep.killed" / "sweep.zarr").mkdir(parents=True)
    store = run_sweep(case_grid(HS, TP, SEEDS), out, _config(coeff_file), progress=False,
                      n_workers=1)
    assert not list(out.glob(".sweep.*"))

    # finished parts were skipped, not recomputed
    assert {c: (out / "parts" / f"{c}.nc").stat().st_mtime_ns for c in done_before} == stamps
    assert not list((out / "parts").glob(".*.tmp"))  # no half-written part left behind
    ds = open_sweep(store)
    assert ds.sizes["case"] == 20 and ds["z"].chunks[0] == (1,) * 20
    assert sorted(ds["case"].values.tolist()) == sorted(c["case_id"] for c in case_grid(HS, TP, SEEDS))
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "complete" and manifest["n_cases"] == 20
    assert manifest["settings"]["ramp"] == 0.5 and len(manifest["settings_hash"]) == 64

    # the resumed store holds exactly what an uninterrupted sweep writes (run in this process:
    # the same numbers as on the workers, bit for bit, and no second cluster to start)
    ref = open_sweep(run_sweep(case_grid(HS, TP, SEEDS), tmp_path / "ref", _config(coeff_file),
                               scheduler="synchronous", progress=False))
    xr.testing.assert_identical(ds.load(), ref.load())

    # a case in the store equals an independent direct Cummins run of the same sea
    case = case_grid(HS, TP, SEEDS)[7]
    direct = cummins.simulate(synthetic_hydro.coefficients(np.linspace(0.1, 40.0, 200)),
                              duration=DURATION, dt=DT, ramp=0.5,
                              wave=waves.JONSWAP(hs=case["hs"], tp=case["tp"], seed=case["seed"]))
    got = case_history(ds, case["case_id"])
    np.testing.assert_allclose(got["z"].values, direct["z"].values, rtol=1e-10, atol=1e-12)
    assert float(got["eta"].std()) == pytest.approx(case["hs"] / 4, rel=0.35)  # Hs ≈ 4 std(eta)


def test_bad_config_raises():
    with pytest.raises(InputError, match="dt"):
        SweepConfig(duration=1.0, dt=2.0).check()
    with pytest.raises(InputError, match="not found"):
        SweepConfig(coeffs="/nonexistent/c.nc").check()


def test_resume_without_a_settings_manifest_is_refused(tmp_path, coeff_file):
    out = tmp_path / "old"
    (out / "parts").mkdir(parents=True)
    to_netcdf(synthetic_hydro.coefficients(np.linspace(0.1, 1.0, 3)), out / "parts" / "x.nc")
    with pytest.raises(InputError, match="no readable manifest"):
        run_sweep(case_grid([0.03], [0.7], 1), out, _config(coeff_file), progress=False)


def test_settings_hash_follows_the_coefficient_file_content(tmp_path, coeff_file):
    from hybridwsi.sweep import settings_hash

    copy = tmp_path / "c.nc"
    copy.write_bytes(coeff_file.read_bytes())
    cfg = SweepConfig(duration=DURATION, dt=DT, coeffs=str(copy), ramp=0.5)
    before = settings_hash(cfg)
    assert settings_hash(SweepConfig(duration=DURATION, dt=DT, coeffs=str(copy), ramp=0.5)) == before
    assert settings_hash(SweepConfig(duration=DURATION, dt=DT, coeffs=str(copy), ramp=0.6)) != before
    to_netcdf(synthetic_hydro.coefficients(np.linspace(0.1, 30.0, 50)), copy)  # replaced in place
    assert settings_hash(cfg) != before
