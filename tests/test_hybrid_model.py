"""The certified hybrid model: ``hybrid --case … --out MODEL`` and ``simulate --network MODEL``
(issue 28 items 3-5, 7).

Small: the paper sphere in heave (1 DOF, 10 s at Δt 0.005 s). Its reference is the linear
Cummins equation, which the partition :data:`PARTITION` knows whole, so the network's residual is
round-off and the hybrid run must reproduce an independent Cummins run of the same sea (the
solver of ``simulate`` without ``--network``). The OC3-Hywind path of the issue's "done means"
(nonlinear mooring and drag left to the network) is the slow test at the end.
"""

from __future__ import annotations

import hashlib
import json
import shutil

import numpy as np
import pytest
import xarray as xr

pytest.importorskip("torch")

from hybridwsi.cases import load_case
from hybridwsi.cli import main
from hybridwsi.history import read_netcdf, set_mass, to_netcdf

#: the case's own step: Newmark's period error at dt 0.02 s (ω dt ≈ 0.16) alone puts the
#: rollout ~10 % off the RK4 reference over 25 periods, ~16 × less at 0.005 s
SEA = ["--jonswap", "0.05", "0.8", "--duration", "10", "--dt", "0.005", "--quiet"]
#: the whole linear Cummins model known: the residual is round-off
PARTITION = "hydrostatic+added_mass_inf+radiation_memory+excitation"
TRAIN = ["--epochs", "40", "--hidden", "8", "--feature-window", "3", "--quiet"]


def _sha(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert err, "no error message"
    assert "Traceback" not in "\n".join(err)
    return err[-1]


@pytest.fixture(scope="module")
def sphere(tmp_path_factory):
    d = tmp_path_factory.mktemp("certified")
    for seed in (1, 2, 3):
        assert main(["simulate", "--case", "paper_sphere", *SEA, "--seed", str(seed),
                     "--out", str(d / f"s{seed}.nc")]) == 0
    assert main(["hybrid", str(d / "s1.nc"), str(d / "s2.nc"), "--case", "paper_sphere",
                 "--partition", PARTITION, "--out", str(d / "model"), *TRAIN]) == 0
    return d


def test_model_folder_holds_every_field_of_its_certificate(sphere):
    doc = json.loads((sphere / "model" / "model.json").read_text())
    assert doc["case"]["sha256"] == load_case("paper_sphere").sha256
    assert doc["dofs"] == ["Heave"] and doc["dt"] == pytest.approx(0.005)
    assert doc["partition"]["known"] == PARTITION.split("+")
    assert doc["coupling"]["mode"] == "lagged" and doc["features"]["window"] == 3
    assert doc["mass"][0][0] == pytest.approx(read_netcdf(sphere / "s1.nc")["mass"].item())
    for entry, name in zip(doc["training"]["files"], ("s1.nc", "s2.nc")):
        assert entry["sha256"] == _sha(sphere / name)
    assert doc["files"]["network.pt"] == _sha(sphere / "model" / "network.pt")
    # the envelope is the range of the training part (first 80 %) of the histories
    n = doc["training"]["n_samples_train"][0]
    z = [read_netcdf(sphere / f)["z"].values[:k, 0] for f, k in
         zip(("s1.nc", "s2.nc"), doc["training"]["n_samples_train"])]
    assert n == round(0.8 * 2001)
    assert doc["envelope"]["kinematics"]["z"]["Heave"] == pytest.approx(
        [min(map(np.min, z)), max(map(np.max, z))])
    cert = doc["certificate"]
    assert cert["stable"] and cert["spectral_radius"] <= 1.0 + 1e-6
    assert cert["max_stable_dt"] is None or cert["max_stable_dt"] > doc["dt"]
    for part in ("network", "diagnostic"):
        assert set(cert[part]) == {"alpha", "beta", "gamma"}
    # A∞ is known: the learned residual carries no inertia (docs/THEORY.md §4c)
    assert abs(cert["added_mass_ratio"]) < 0.05
    # a free run from t = 0 measured over the held-out tail: Newmark vs the RK4 reference
    assert all(e["Heave"] < 0.06 for e in doc["held_out"]["nrms_z"])


def test_hybrid_run_reproduces_the_cummins_run_of_a_new_sea(sphere):
    out = sphere / "hyb.nc"
    assert main(["simulate", "--case", "paper_sphere", *SEA, "--seed", "3", "--network",
                 str(sphere / "model"), "--out", str(out)]) == 0
    hyb, ref = read_netcdf(out), read_netcdf(sphere / "s3.nc")
    assert {"F_network", "F_known", "F_exc", "eta", "outside_envelope"} <= set(hyb.data_vars)
    assert hyb.sizes["time"] == ref.sizes["time"]
    z, z_ref = hyb["z"].values[:, 0], ref["z"].values[:, 0]
    assert np.sqrt(np.mean((z - z_ref) ** 2)) < 0.03 * np.sqrt(np.mean(z_ref ** 2))
    # the same sea: the excitation the hybrid solver applied is the reference's
    np.testing.assert_allclose(hyb["F_exc"].values, ref["F_exc"].values,
                               atol=1e-9 * np.abs(ref["F_exc"].values).max())
    assert 0.0 <= hyb.attrs["envelope_fraction"] <= 1.0


def test_hybrid_run_starts_with_the_motion_of_the_known_part(sphere):
    """Over the network's first window the run is the known linear part's motion, not rest:
    here that part is the whole Cummins model, so the window is the independent Cummins run's
    of the same sea (held at rest instead, the OC4 semi's slow modes rang: surge 29.2 % RMS
    off against 4.4 %)."""
    out = sphere / "hyb_start.nc"
    assert main(["simulate", "--case", "paper_sphere", *SEA, "--seed", "3", "--network",
                 str(sphere / "model"), "--out", str(out)]) == 0
    hyb, ref = read_netcdf(out), read_netcdf(sphere / "s3.nc")
    feat = json.loads((sphere / "model" / "model.json").read_text())["features"]
    span = (feat["window"] - 1) * feat["stride"] + 1  # FeatureSpec.span
    for k in ("z", "zdot"):
        head, head_ref = hyb[k].values[:span], ref[k].values[:span]
        assert np.abs(head_ref[1:]).min() > 0  # the sea moves the body from the first step
        np.testing.assert_allclose(head, head_ref, rtol=1e-6,
                                   atol=1e-9 * np.abs(ref[k].values).max())


@pytest.mark.parametrize("extra, words", [
    (["--dt", "0.01", "--quiet"], "differs from the model's"),
    (["--dofs", "Surge", "--dt", "0.005"], "certified for DOFs Heave"),
])
def test_simulate_network_refuses_another_step_or_dofs(sphere, capsys, extra, words):
    args = ["simulate", "--case", "paper_sphere", "--jonswap", "0.05", "0.8", "--duration",
            "10", "--network", str(sphere / "model"), "--out",
            str(sphere / "x.nc"), *extra]
    assert main(args) == 2
    line = _error_line(capsys)
    assert line.startswith("error:") and words in line
    assert not (sphere / "x.nc").exists()


def test_a_step_above_the_certified_largest_stable_one_is_refused(sphere):
    from hybridwsi.errors import InputError
    from hybridwsi.surrogate.certified import CertifiedModel

    model = CertifiedModel.load(sphere / "model")
    model.doc["certificate"]["max_stable_dt"] = 0.03
    with pytest.raises(InputError, match="above the model's largest stable time step 0.03"):
        model.check_run(model.doc["case"]["sha256"], "paper_sphere", ["Heave"], 0.05)
    model.check_run(model.doc["case"]["sha256"], "paper_sphere", ["Heave"], 0.005)


def test_simulate_network_refuses_another_case(sphere, capsys):
    assert main(["simulate", "--case", "kramer2021_decay", *SEA, "--network",
                 str(sphere / "model"), "--out", str(sphere / "x.nc")]) == 2
    assert "not the case this model was trained for" in _error_line(capsys)


@pytest.mark.parametrize("what", ["model.json", "network.pt", "network.json"])
def test_altered_model_folder_is_refused(sphere, tmp_path, capsys, what):
    model = tmp_path / "model"
    shutil.copytree(sphere / "model", model)
    path = model / what
    if what == "model.json":
        doc = json.loads(path.read_text())
        doc["certificate"]["max_stable_dt"] = 10.0  # a forged certificate
        path.write_text(json.dumps(doc))
    else:
        path.write_bytes(path.read_bytes() + b" ")
    assert main(["simulate", "--case", "paper_sphere", *SEA, "--network", str(model),
                 "--out", str(tmp_path / "x.nc")]) == 2
    assert "altered" in _error_line(capsys)


def _refused(args, out, capsys) -> str:
    assert main(args) == 2
    assert not out.exists()  # refused before any training: nothing written
    return _error_line(capsys)


def test_training_refuses_mixed_time_steps_and_masses(sphere, tmp_path, capsys):
    fine = tmp_path / "fine.nc"
    assert main(["simulate", "--case", "paper_sphere", "--jonswap", "0.05", "0.8",
                 "--duration", "5", "--dt", "0.01", "--quiet", "--out", str(fine)]) == 0
    out = tmp_path / "m"
    line = _refused(["hybrid", str(sphere / "s1.nc"), str(fine), "--case", "paper_sphere",
                     "--out", str(out), *TRAIN], out, capsys)
    assert "time step" in line
    heavy = tmp_path / "heavy.nc"
    h = read_netcdf(sphere / "s2.nc")
    to_netcdf(set_mass(h, 2.0 * h["mass"].values), heavy)
    line = _refused(["hybrid", str(sphere / "s1.nc"), str(heavy), "--case", "paper_sphere",
                     "--out", str(out), *TRAIN], out, capsys)
    assert "mass" in line


def test_training_refuses_histories_lacking_what_the_partition_needs(sphere, tmp_path,
                                                                      capsys):
    bare = tmp_path / "bare.nc"
    h = read_netcdf(sphere / "s1.nc")
    to_netcdf(h[["z", "zdot", "zddot", "mass"]], bare)  # no F_exc, no eta
    out = tmp_path / "m"
    line = _refused(["hybrid", str(bare), "--case", "paper_sphere", "--partition",
                     "hydrostatic+excitation", "--out", str(out), *TRAIN], out, capsys)
    assert "F_exc" in line and str(bare) in line


def _stripped(src, dst):
    """A history reduced to time, z, zdot, zddot and eta with their units alone: no file
    attribute (no ramp, no case, no radiation fit), as a record exported from elsewhere."""
    h = read_netcdf(src)[["z", "zdot", "zddot", "eta"]]
    h.attrs = {}
    for v in h.variables.values():
        v.attrs = {k: a for k, a in v.attrs.items() if k in ("units", "units_per_dof")}
    h.to_netcdf(dst)
    return str(dst)


def test_histories_with_eta_alone_train_and_run(sphere, tmp_path):
    """Motions and η only, no attributes: F_exc from η through the case's transfer function,
    F_tot = M z̈. The stored η is the elevation as applied (ramped like the force), so the
    excitation computed from it is the force the run applied, over the ramp too (before η was
    stored ramped, the stripped history lost the ramp: F_exc from it was ~100 % off over the
    first ramp, and on OC3 the network was refused as unstable, spectral radius 1.0002)."""
    from hybridwsi.casemodel import CaseModel
    from hybridwsi.surrogate.certified import prepare_histories

    names = [_stripped(sphere / f"s{k}.nc", tmp_path / f"r{k}.nc") for k in (1, 2)]
    model = CaseModel.build("paper_sphere", dofs=["Heave"])
    full = read_netcdf(sphere / "s1.nc")
    got = prepare_histories([xr.load_dataset(names[0])], names[:1], model)[0]
    t = full["time"].values
    f, f_ref = got["F_exc"].values[:, 0], full["F_exc"].values[:, 0]
    scale = np.sqrt(np.mean(f_ref ** 2))
    # the default ramp is two peak periods (1.6 s), about the impulse response's spread: the
    # excitation of the ramped η differs from the ramped excitation there (measured 14 % of
    # the force's RMS over the ramp; 33 % from an unramped η), not after it; the last 2 s
    # feel the calm after the record's end
    ramp, after = t < 1.6, (t >= 1.6) & (t < 8.0)
    assert np.sqrt(np.mean((f[ramp] - f_ref[ramp]) ** 2)) < 0.2 * scale
    assert np.sqrt(np.mean((f[after] - f_ref[after]) ** 2)) < 0.01 * scale
    np.testing.assert_allclose(got["F_tot"].values, full["F_tot"].values,
                               rtol=1e-9, atol=1e-9 * np.abs(full["F_tot"].values).max())
    out = tmp_path / "model"
    assert main(["hybrid", *names, "--case", "paper_sphere", "--out", str(out), *TRAIN]) == 0
    assert json.loads((out / "model.json").read_text())["certificate"]["stable"]
    hyb = tmp_path / "hyb.nc"
    assert main(["simulate", "--case", "paper_sphere", *SEA, "--seed", "3", "--network",
                 str(out), "--out", str(hyb)]) == 0
    # runs (its accuracy at this size is not the claim: on OC3, 2 x 1800 s, a new sea, the
    # stripped histories give surge/heave/pitch within 2.0/0.2/1.5 % RMS; docs/CLI.md)
    run = read_netcdf(hyb)
    assert run.sizes["time"] == full.sizes["time"] and np.all(np.isfinite(run["z"].values))


def test_a_history_with_unramped_eta_gets_its_recorded_ramp(sphere):
    """A history written before η was stored ramped (η without a ``ramp`` attribute, the ramp
    in ``attrs["inputs"]``): the ramp is applied to the excitation of its η."""
    from hybridwsi.casemodel import CaseModel
    from hybridwsi.surrogate.certified import prepare_histories
    from hybridwsi.waves import wave_from_dict

    full = read_netcdf(sphere / "s1.nc")
    t = full["time"].values
    wave = wave_from_dict(json.loads(full.attrs["inputs"])["wave"])
    old = full[["z", "zdot", "zddot", "eta", "mass"]].assign(
        eta=(("time", "probe"), wave.elevation(t)[:, None], {"units": "m"}))
    old.attrs = dict(full.attrs)
    model = CaseModel.build("paper_sphere", dofs=["Heave"])
    got = prepare_histories([old], ["old"], model)[0]["F_exc"].values[:, 0]
    f_ref = full["F_exc"].values[:, 0]
    head = t < 8.0
    assert np.sqrt(np.mean((got[head] - f_ref[head]) ** 2)) < 0.01 * np.sqrt(np.mean(f_ref ** 2))


@pytest.mark.slow
def test_done_means_oc3_user_case(tmp_path):
    """Issue 28 "done means": a user's copy of the OC3 case, two seas, auto partition, a third
    sea: surge and pitch within 3 % RMS of the reference run (measured 0.51 %, 0.41 %); the
    same with the training histories stripped to time, motions and η without file attributes
    (measured 2.0 %, 1.5 %)."""
    from importlib.resources import files

    src = files("hybridwsi.cases")
    for name in ("oc3_hywind.toml", "oc3_hywind_moordyn.dat"):
        (tmp_path / ("my_spar.toml" if name.endswith("toml") else name)).write_bytes(
            src.joinpath(name).read_bytes())
    case = str(tmp_path / "my_spar.toml")
    run = ["--duration", "1800", "--dt", "0.1", "--quiet"]
    for seas, out in ((["4", "10", "--seed", "1"], "a.nc"), (["6", "12", "--seed", "2"], "b.nc"),
                      (["5", "11", "--seed", "3"], "ref.nc")):
        assert main(["simulate", "--case", case, "--jonswap", *seas, *run,
                     "--out", str(tmp_path / out)]) == 0
    assert main(["hybrid", str(tmp_path / "a.nc"), str(tmp_path / "b.nc"), "--case", case,
                 "--partition", "auto", "--out", str(tmp_path / "model"), "--quiet"]) == 0
    assert main(["simulate", "--case", case, "--jonswap", "5", "11", "--seed", "3", *run,
                 "--network", str(tmp_path / "model"), "--out", str(tmp_path / "hyb.nc")]) == 0
    stripped = [_stripped(tmp_path / f"{k}.nc", tmp_path / f"{k}_stripped.nc") for k in "ab"]
    assert main(["hybrid", *stripped, "--case", case, "--partition", "auto",
                 "--out", str(tmp_path / "model_s"), "--quiet"]) == 0
    assert main(["simulate", "--case", case, "--jonswap", "5", "11", "--seed", "3", *run,
                 "--network", str(tmp_path / "model_s"), "--out", str(tmp_path / "hyb_s.nc")]) == 0
    ref = xr.open_dataset(tmp_path / "ref.nc")
    z_ref = ref["z"].values
    dofs = [str(d) for d in ref["dof"].values]
    for name in ("hyb.nc", "hyb_s.nc"):
        z = xr.open_dataset(tmp_path / name)["z"].values
        err = np.sqrt(np.mean((z - z_ref) ** 2, 0)) / np.sqrt(np.mean(z_ref ** 2, 0))
        assert err[dofs.index("Surge")] < 0.03 and err[dofs.index("Pitch")] < 0.03, (name, err)
