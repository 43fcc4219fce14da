"""Coefficient files users already hold: WAMIT .1/.3/.hst, Capytaine NetCDF, WEC-Sim BEMIO .h5.

References are independent of the readers: hand-written WAMIT/BEMIO files whose dimensional
values follow from the WAMIT manual's normalisation table (ch. 3; OpenFAST HydroDyn
``WAMIT.f90``) written out per DOF pair below, the time signals of both time conventions, and the
numbers a real Capytaine solve returned in memory.
"""

from __future__ import annotations

import math
import sys
from contextlib import nullcontext
from pathlib import Path

import numpy as np
import pytest

from hybridwsi.cli import main
from hybridwsi.errors import InputError
from hybridwsi.hydro import coefficients as cf
from hybridwsi.hydro.formats import read_coefficients, write_wamit

RHO, G, L = 1000.0, 9.8, 2.0
W = (1.0, 2.0)  # rad/s
BETAS = (0.0, 90.0)  # deg
DOFS = ["Surge", "Heave", "Pitch"]
MODES = (1, 3, 5)
# nondimensional Ā (limit rows and per frequency) and B̄, keyed (I, J); I != J entries differ
# so that the orientation (I receives the force, J moves) is tested
A0 = {(1, 1): 1.1, (3, 3): 2.2, (5, 5): 3.3, (1, 5): 0.4, (5, 1): 0.5, (1, 3): 0.0,
      (3, 1): 0.0, (3, 5): 0.0, (5, 3): 0.0}
AINF = {k: 0.5 * v for k, v in A0.items()}
ABAR = {w: {k: v * (1 + 0.1 * w) for k, v in A0.items()} for w in W}
BBAR = {w: {k: 0.2 * v * w for k, v in A0.items()} for w in W}
# excitation X̄ (WAMIT convention, Re[X e^{+iωt}]) per (ω, β, mode)
XBAR = {(w, b, m): complex(0.3 * m + 0.1 * w, 0.4 - 0.05 * b / 90.0 * m)
        for w in W for b in BETAS for m in MODES}
CBAR = {(3, 3): 0.7, (5, 5): 0.9, (3, 5): 0.25, (5, 3): 0.25, (1, 1): 0.0}
# length powers by hand, straight from the WAMIT normalisation table:
# added mass/damping L^3 (trans-trans), L^4 (mixed), L^5 (rot-rot); restoring L^2, L^3, L^4;
# excitation L^2 (forces), L^3 (moments)
K_RAD = {(1, 1): 3, (3, 3): 3, (1, 3): 3, (3, 1): 3, (1, 5): 4, (5, 1): 4, (3, 5): 4,
         (5, 3): 4, (5, 5): 5}
K_HST = {k: v - 1 for k, v in K_RAD.items()}
M_EXC = {1: 2, 3: 2, 5: 3}


def write_handmade(root: Path) -> Path:
    """The WAMIT set above, written as WAMIT writes it (period in the first column)."""
    lines = [f"-1.0 {i} {j} {v}" for (i, j), v in A0.items()]
    lines += [f"0.0 {i} {j} {v}" for (i, j), v in AINF.items()]
    for w in W:
        lines += [f"{2 * math.pi / w!r} {i} {j} {ABAR[w][i, j]!r} {BBAR[w][i, j]!r}"
                  for (i, j) in A0]
    root.with_name(root.name + ".1").write_text("\n".join(lines) + "\n")
    rows3 = []
    for w in W:
        for b in BETAS:
            for m in MODES:
                x = XBAR[w, b, m]
                rows3.append(f"{2 * math.pi / w!r} {b} {m} {abs(x)!r} "
                             f"{math.degrees(np.angle(x))!r} {x.real!r} {x.imag!r}")
    root.with_name(root.name + ".3").write_text("\n".join(rows3) + "\n")
    root.with_name(root.name + ".hst").write_text(
        "\n".join(f"{i} {j} {v}" for (i, j), v in CBAR.items()) + "\n")
    return root.with_name(root.name + ".1")


@pytest.fixture
def handmade(tmp_path: Path) -> Path:
    return write_handmade(tmp_path / "body")


def _m(dofs_pair):
    return [MODES[DOFS.index(d)] for d in dofs_pair]


def test_wamit_scaling_per_dof_pair(handmade):
    ds = read_coefficients(handmade, rho=RHO, g=G, ulen=L)
    assert cf.dofs(ds) == DOFS
    np.testing.assert_allclose(cf.omega(ds), W)
    a_inf, a_0 = cf.matrix(ds, "added_mass_inf"), cf.matrix(ds, "added_mass_zero")
    a_w, b_w = cf.matrix_omega(ds, "added_mass"), cf.matrix_omega(ds, "radiation_damping")
    c = cf.matrix(ds, "hydrostatic_stiffness")
    for i, di in enumerate(DOFS):
        for j, dj in enumerate(DOFS):
            key = tuple(_m((di, dj)))
            rad = RHO * L ** K_RAD[key]
            assert a_0[i, j] == pytest.approx(A0[key] * rad, rel=1e-12)  # PER = -1: ω = 0
            assert a_inf[i, j] == pytest.approx(AINF[key] * rad, rel=1e-12)  # PER = 0: ω = ∞
            for k, w in enumerate(W):
                assert a_w[k, i, j] == pytest.approx(ABAR[w][key] * rad, rel=1e-12)
                assert b_w[k, i, j] == pytest.approx(BBAR[w][key] * rad * w, rel=1e-12)
            assert c[i, j] == pytest.approx(CBAR.get(key, 0.0) * RHO * G * L ** K_HST[key],
                                            rel=1e-12)
    # surge force per pitch acceleration is kg m, pitch moment per pitch is kg m^2
    assert a_inf[0, 2] == pytest.approx(0.5 * 0.4 * RHO * L**4)
    assert a_inf[2, 0] == pytest.approx(0.5 * 0.5 * RHO * L**4)
    assert ds["added_mass"].attrs["units"].startswith("per DOF pair")


def test_wamit_excitation_magnitude_phase_and_time_convention(handmade):
    ds = read_coefficients(handmade, rho=RHO, g=G, ulen=L)
    np.testing.assert_allclose(ds["wave_direction"].values, np.deg2rad(BETAS))
    exc = ds["excitation_force"].transpose("omega", "wave_direction", "influenced_dof").values
    t = np.linspace(0.0, 10.0, 57)
    for k, w in enumerate(W):
        for ib, b in enumerate(BETAS):
            for i, m in enumerate(MODES):
                scale = RHO * G * L ** M_EXC[m]
                x = XBAR[w, b, m]
                assert abs(exc[k, ib, i]) == pytest.approx(abs(x) * scale, rel=1e-12)
                # the same physical force in both conventions, unit wave amplitude
                f_wamit = np.real(x * scale * np.exp(1j * w * t))
                f_capy = np.real(exc[k, ib, i] * np.exp(-1j * w * t))
                np.testing.assert_allclose(f_capy, f_wamit, rtol=0, atol=1e-9 * scale)
                assert np.angle(exc[k, ib, i]) == pytest.approx(-np.angle(x), abs=1e-12)


def test_wamit_frequency_input(tmp_path):
    """IPEROUT = 2: ω in the first column; 0 is ω = 0 (A(0)), negative is ω = ∞ (A(∞))."""
    root = tmp_path / "f"
    (tmp_path / "f.1").write_text("0.0 3 3 2.0\n-1.0 3 3 1.0\n1.5 3 3 1.2 0.3\n")
    (tmp_path / "f.3").write_text("1.5 0.0 3 1.0 0.0 1.0 0.0\n")
    (tmp_path / "f.hst").write_text("3 3 0.5\n")
    ds = read_coefficients(root.with_suffix(".1"), rho=RHO, g=G, frequency_input=True)
    np.testing.assert_allclose(cf.omega(ds), [1.5])
    assert cf.matrix(ds, "added_mass_zero")[0, 0] == pytest.approx(2.0 * RHO)
    assert cf.matrix(ds, "added_mass_inf")[0, 0] == pytest.approx(1.0 * RHO)
    assert cf.matrix_omega(ds, "radiation_damping")[0, 0, 0] == pytest.approx(0.3 * RHO * 1.5)


def test_wamit_export_import_identical(handmade, tmp_path):
    ds = read_coefficients(handmade, rho=RHO, g=G, ulen=L)
    write_wamit(ds, tmp_path / "out" / "again", ulen=L)
    back = read_coefficients(tmp_path / "out" / "again.1", rho=RHO, g=G, ulen=L)
    for name in ("added_mass", "radiation_damping", "excitation_force", "added_mass_inf",
                 "added_mass_zero", "hydrostatic_stiffness"):
        np.testing.assert_allclose(back[name].values, ds[name].values, rtol=1e-12, atol=1e-9)
    assert back.attrs["input_hash"] != ds.attrs["input_hash"]  # content hash of other files


def test_sphere_round_trip_through_wamit(tmp_path):
    src = Path(__file__).parents[1] / "src" / "hybridwsi" / "data" / "bem_paper_sphere.nc"
    ds = read_coefficients(src)
    paths = write_wamit(ds, tmp_path / "sphere")
    assert [p.suffix for p in paths] == [".1", ".3", ".hst"]
    back = read_coefficients(paths[0], rho=ds.attrs["rho"], g=ds.attrs["g"])
    np.testing.assert_allclose(cf.omega(back), cf.omega(ds), rtol=1e-12)
    for name in ("added_mass", "radiation_damping"):
        a, b = cf.matrix_omega(ds, name), cf.matrix_omega(back, name)
        np.testing.assert_allclose(b, a, rtol=1e-10, atol=1e-12 * np.abs(a).max())
    for name in ("added_mass_inf", "added_mass_zero", "hydrostatic_stiffness"):
        np.testing.assert_allclose(cf.matrix(back, name), cf.matrix(ds, name), rtol=1e-11)
    fa, fb = ds["excitation_force"].values, back["excitation_force"].values
    np.testing.assert_allclose(fb, fa, rtol=1e-10, atol=1e-12 * np.abs(fa).max())
    # hydrostatic heave stiffness of the sphere: rho g pi R^2 (R = 0.15 m)
    assert cf.matrix(back, "hydrostatic_stiffness")[0, 0] == pytest.approx(
        ds.attrs["rho"] * ds.attrs["g"] * math.pi * 0.15**2, rel=1e-9)


# ------------------------------------------------------------------------------ Capytaine
@pytest.fixture(scope="module")
def capytaine_solve():
    import capytaine as cpt
    import xarray as xr

    mesh = cpt.mesh_vertical_cylinder(length=1.0, radius=0.5, center=(0, 0, -0.25),
                                      resolution=(2, 8, 4)).immersed_part()
    body = cpt.FloatingBody(mesh=mesh, dofs=cpt.rigid_body_dofs(rotation_center=(0, 0, 0)),
                            center_of_mass=(0, 0, -0.3), mass=1000.0 * mesh.volume)
    grid = xr.Dataset(coords={"omega": [0.0, 1.5, 3.0, np.inf], "wave_direction": [0.0, 0.5],
                              "radiating_dof": list(body.dofs), "water_depth": [np.inf],
                              "rho": [1000.0]})
    return body, cpt.BEMSolver().fill_dataset(grid, body)


def test_capytaine_netcdf_import(capytaine_solve, tmp_path):
    import capytaine as cpt

    _, ref = capytaine_solve
    path = tmp_path / "capy.nc"
    cpt.export_dataset(path, ref)
    ds = read_coefficients(path)
    assert cf.dofs(ds) == list(ref["radiating_dof"].values)
    np.testing.assert_allclose(cf.omega(ds), [1.5, 3.0])
    a, b = cf.matrix_omega(ds, "added_mass"), cf.matrix_omega(ds, "radiation_damping")
    for k, w in enumerate((1.5, 3.0)):
        for i, di in enumerate(cf.dofs(ds)):
            for j, dj in enumerate(cf.dofs(ds)):
                sel = {"omega": w, "influenced_dof": di, "radiating_dof": dj}
                assert a[k, i, j] == pytest.approx(float(ref["added_mass"].sel(sel)), abs=1e-9)
                assert b[k, i, j] == pytest.approx(float(ref["radiation_damping"].sel(sel)),
                                                   abs=1e-9)
    for name, w in (("added_mass_inf", np.inf), ("added_mass_zero", 0.0)):
        want = ref["added_mass"].sel(omega=w).transpose("influenced_dof", "radiating_dof")
        np.testing.assert_allclose(cf.matrix(ds, name), want.values, atol=1e-9)
    exc = ds["excitation_force"].transpose("omega", "wave_direction", "influenced_dof")
    want = ref["excitation_force"].sel(omega=[1.5, 3.0]).transpose(
        "omega", "wave_direction", "influenced_dof")
    np.testing.assert_allclose(exc.values, want.values, atol=1e-9)
    np.testing.assert_allclose(ds["wave_direction"].values, [0.0, 0.5])
    np.testing.assert_allclose(cf.matrix(ds, "mass"), ref["inertia_matrix"].transpose(
        "influenced_dof", "radiating_dof").values)
    np.testing.assert_allclose(cf.matrix(ds, "hydrostatic_stiffness"),
                               ref["hydrostatic_stiffness"].transpose(
                                   "influenced_dof", "radiating_dof").values)
    assert ds.attrs["rho"] == 1000.0 and math.isinf(ds.attrs["water_depth"])


def test_capytaine_netcdf_without_hydrostatics_or_limits(capytaine_solve, tmp_path):
    import capytaine as cpt

    body, _ = capytaine_solve
    solver = cpt.BEMSolver()
    probs = [cpt.RadiationProblem(body=body, omega=2.0, radiating_dof=d) for d in body.dofs]
    probs.append(cpt.DiffractionProblem(body=body, omega=2.0, wave_direction=0.0))
    results = solver.solve_all(probs)
    ref = cpt.assemble_dataset(results, hydrostatics=False)
    cpt.export_dataset(tmp_path / "plain.nc", ref)
    ds = read_coefficients(tmp_path / "plain.nc")
    assert not cf.has(ds, "hydrostatic_stiffness") and not cf.has(ds, "mass")
    assert np.isnan(ds["added_mass_inf"].values).all()
    with pytest.raises(InputError, match="NaN"):
        cf.matrix(ds, "added_mass_inf")
    np.testing.assert_allclose(
        cf.matrix_omega(ds, "added_mass")[0],
        ref["added_mass"].isel(omega=0).transpose("influenced_dof", "radiating_dof").values)


# ------------------------------------------------------------------------------ BEMIO
def write_bemio(path: Path, *, rho=1025.0, g=9.81) -> dict:
    """A BEMIO .h5 as h5py sees WEC-Sim's writeBEMIOH5 output (MATLAB dims reversed)."""
    h5py = pytest.importorskip("h5py")
    rng = np.random.default_rng(3)
    w = np.array([0.5, 1.0, 2.0])
    beta = np.array([0.0, 45.0])
    a = rng.uniform(1, 2, (6, 6, w.size))  # [i, j, ω], deliberately non-symmetric
    b = rng.uniform(0, 1, (6, 6, w.size))
    re, im = rng.normal(size=(6, beta.size, w.size)), rng.normal(size=(6, beta.size, w.size))
    c = np.diag([0, 0, 3.0, 2.0, 2.0, 0])
    a_inf = rng.uniform(1, 2, (6, 6))
    with h5py.File(path, "w") as f:
        sp = f.create_group("simulation_parameters")
        sp["rho"], sp["g"] = np.array([[rho]]), np.array([[g]])
        sp["w"], sp["T"] = w[:, None], (2 * np.pi / w)[:, None]
        sp["wave_dir"] = beta[:, None]
        sp["water_depth"] = np.bytes_("infinite")
        sp["scaled"] = np.array([[0.0]])
        hc = f.create_group("body1/hydro_coeffs")
        hc["added_mass/all"], hc["added_mass/inf_freq"] = a, a_inf
        hc["radiation_damping/all"] = b
        hc["excitation/re"], hc["excitation/im"] = re, im
        hc["linear_restoring_stiffness"] = c
        pr = f.create_group("body1/properties")
        pr["dof_start"], pr["dof_end"], pr["disp_vol"] = [[1.0]], [[6.0]], [[0.5]]
    return {"w": w, "beta": beta, "a": a, "b": b, "x": re + 1j * im, "c": c, "a_inf": a_inf,
            "rho": rho, "g": g}


def test_bemio_import_scaling(tmp_path):
    ref = write_bemio(tmp_path / "wec.h5")
    ds = read_coefficients(tmp_path / "wec.h5")
    rho, g, w = ref["rho"], ref["g"], ref["w"]
    assert cf.dofs(ds) == ["Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"]
    np.testing.assert_allclose(cf.omega(ds), w)
    a = cf.matrix_omega(ds, "added_mass")  # [ω, influenced i, radiating j]
    np.testing.assert_allclose(a[1, 2, 4], ref["a"][2, 4, 1] * rho)
    np.testing.assert_allclose(a, np.moveaxis(ref["a"], -1, 0) * rho)
    np.testing.assert_allclose(cf.matrix_omega(ds, "radiation_damping"),
                               np.moveaxis(ref["b"], -1, 0) * rho * w[:, None, None])
    exc = ds["excitation_force"].transpose("omega", "wave_direction", "influenced_dof").values
    np.testing.assert_allclose(exc, np.conj(np.transpose(ref["x"], (2, 1, 0))) * rho * g)
    np.testing.assert_allclose(ds["wave_direction"].values, np.deg2rad(ref["beta"]))
    np.testing.assert_allclose(cf.matrix(ds, "hydrostatic_stiffness"), ref["c"] * rho * g)
    np.testing.assert_allclose(cf.matrix(ds, "added_mass_inf"), ref["a_inf"] * rho)
    assert math.isinf(ds.attrs["water_depth"]) and ds.attrs["disp_vol"] == 0.5


def test_bemio_without_h5py_names_the_extra(tmp_path, monkeypatch):
    write_bemio(tmp_path / "wec.h5")
    monkeypatch.setitem(sys.modules, "h5py", None)
    with pytest.raises(InputError, match=r"hybridwsi\[bemio\]"):
        read_coefficients(tmp_path / "wec.h5")


# ------------------------------------------------------------------------------ bad input
def _corrupt(root: Path, ext: str, text: str | None) -> Path:
    p = root.with_name(root.name + ext)
    if text is None:
        p.unlink()
    else:
        p.write_text(text)
    return root.with_name(root.name + ".1")


@pytest.mark.parametrize("ext, mutate, match", [
    (".3", lambda t: None, r"body\.3 not found"),
    (".hst", lambda t: None, r"body\.hst not found"),
    (".1", lambda t: t.rsplit(" ", 1)[0] + "\n", "columns"),  # last value cut off
    (".1", lambda t: "\n".join(t.splitlines()[:-2]) + "\n", "different"),  # block truncated
    (".1", lambda t: t.replace("1.1", "abc", 1), "not numeric"),
    (".1", lambda t: t.replace(" 1.1", " nan", 1), "NaN"),
    (".1", lambda t: t.replace("-1.0 1 1", "-1.0 7 1", 1), "outside 1-6"),
    (".3", lambda t: "\n".join(t.splitlines()[:-3]) + "\n", "heading|modes"),
    (".3", lambda t: t.replace("6.28318", "7.28318"), "periods differ"),
    (".hst", lambda t: "", "no data rows"),
    (".1", lambda t: "\x00\xff garbage", "not numeric|not a text file"),
])
def test_bad_wamit_files(handmade, ext, mutate, match):
    root = handmade.with_suffix("")
    p = root.with_name(root.name + ext)
    new = mutate(p.read_text())
    _corrupt(root, ext, new)
    with pytest.raises(InputError, match=match):
        read_coefficients(handmade, rho=RHO, g=G)


def test_bad_inputs_other(tmp_path, handmade):
    with pytest.raises(InputError, match="--rho, --g"):
        read_coefficients(handmade)
    with pytest.raises(InputError, match="unknown coefficient format"):
        read_coefficients(handmade, format="aqwa")
    (tmp_path / "notes.txt").write_text("hello\n")
    with pytest.raises(InputError, match="unknown coefficient file format"):
        read_coefficients(tmp_path / "notes.txt")
    with pytest.raises(InputError, match="not found"):
        read_coefficients(tmp_path / "missing.nc")
    (tmp_path / "fake.nc").write_bytes(b"CDF\x01" + b"\x00" * 10)
    with pytest.raises(InputError, match="NetCDF"):
        read_coefficients(tmp_path / "fake.nc")
    h5py = pytest.importorskip("h5py")
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = [1.0]
    with pytest.raises(InputError, match="not a WEC-Sim BEMIO"):
        read_coefficients(tmp_path / "other.h5")
    with pytest.warns(UserWarning, match="seawater"):
        ds = read_coefficients(handmade, assume_seawater=True)
    assert ds.attrs["rho"] == 1025.0 and ds.attrs["g"] == 9.80665


# ------------------------------------------------------------------------------ CLI
def test_cli_both_directions_and_bad_file(handmade, tmp_path, capsys):
    out = tmp_path / "c.nc"
    rc = main(["coeffs", str(handmade), "--rho", str(RHO), "--g", str(G), "--ulen", str(L),
               "--out", str(out)])
    assert rc == 0
    ref = read_coefficients(handmade, rho=RHO, g=G, ulen=L)
    got = read_coefficients(out)
    for name in ("added_mass", "radiation_damping", "excitation_force", "added_mass_inf"):
        np.testing.assert_allclose(got[name].values, ref[name].values)
    rc = main(["coeffs", str(out), "--to", "wamit", "--out", str(tmp_path / "w" / "r"),
               "--ulen", str(L), "--rho", "1"])
    assert rc == 0
    assert "--rho ignored" in capsys.readouterr().out
    back = read_coefficients(tmp_path / "w" / "r.1", rho=RHO, g=G, ulen=L)
    np.testing.assert_allclose(back["added_mass"].values, ref["added_mass"].values, rtol=1e-12)
    capsys.readouterr()
    rc = main(["coeffs", str(handmade), "--out", str(out)])  # WAMIT without --rho/--g
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error: ") and len(err.strip().splitlines()) == 1
    (tmp_path / "bad.nc").write_text("not netcdf")
    rc = main(["coeffs", str(tmp_path / "bad.nc"), "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error: ") and "Traceback" not in err


def test_cli_simulate_reads_wamit_like_netcdf(tmp_path):
    """``simulate --coeffs ROOT.1`` (seawater assumed) runs the same Cummins decay as the same
    coefficients in NetCDF: the WAMIT path changes the file, not the physics."""
    from hybridwsi.history import read_netcdf, to_netcdf

    src = Path(__file__).parents[1] / "src" / "hybridwsi" / "data" / "bem_paper_sphere.nc"
    ds = read_coefficients(src).assign_attrs(rho=1025.0, g=9.80665)  # label as seawater
    nc = to_netcdf(ds.drop_vars("mass"), tmp_path / "sea.nc")
    root = write_wamit(ds, tmp_path / "sea")[0]
    runs = {}
    for name, path in (("nc", nc), ("wamit", root)):
        out = tmp_path / f"{name}.nc"
        with pytest.warns(UserWarning, match="seawater") if name == "wamit" else nullcontext():
            rc = main(["simulate", "--coeffs", str(path), "--mass", "7.06", "--decay", "0.02",
                       "--duration", "2", "--dt", "0.01", "--radiation", "convolution",
                       "--out", str(out), "--quiet"])
        assert rc == 0
        runs[name] = read_netcdf(out)["z"].values
    np.testing.assert_allclose(runs["wamit"], runs["nc"], rtol=0, atol=1e-9 * 0.02)
