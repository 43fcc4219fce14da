"""The sphere and Capytaine BEM coefficients, checked against Hulme (1982) and analytic hydrostatics.

Test mesh: 1600 hull panels (axisymmetric, with lid); the paper's 6400-panel mesh is behind
``@pytest.mark.slow``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hybridwsi.bodies import FloatingSphere
from hybridwsi.errors import InputError
from hybridwsi.hydro import bem

HULME = Path(__file__).parent / "data" / "hulme1982_hemisphere_heave.csv"
R, RHO, G = 0.15, 998.2, 9.81
M_DISP = RHO * 2 / 3 * math.pi * R**3          # displaced mass of the hemisphere [kg]
TEST_PANELS = 1600


def hulme_table() -> np.ndarray:
    """Rows (KR, A_hat, B_hat) of Hulme's table, read from the CSV (comments start with #)."""
    return np.loadtxt(HULME, delimiter=",", comments="#", skiprows=3)


@pytest.fixture(scope="module")
def cache(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("bem_cache")


@pytest.fixture(scope="module")
def hulme_run(cache):
    """BEM at Hulme's KR = 0.1..5 on the test mesh (deep water)."""
    table = hulme_table()
    table = table[(table[:, 0] >= 0.1) & (table[:, 0] <= 5.0)]
    omega = np.sqrt(table[:, 0] * G / R)
    ds = bem.compute(FloatingSphere.paper(), omega, n_panels=TEST_PANELS, cache_dir=cache,
                     progress=False)
    return table, ds


# ------------------------------------------------------------------------- bodies
def test_sphere_defaults_and_presets():
    s = FloatingSphere()
    assert s.draft == R and s.mass == pytest.approx(M_DISP, rel=1e-12)
    assert s.displaced_volume() == pytest.approx(2 / 3 * math.pi * R**3, rel=1e-12)
    p = FloatingSphere.paper()
    assert (p.radius, p.mass, p.rho, p.g) == (0.15, 7.06, 998.2, 9.81)
    k = FloatingSphere.kramer2021()
    assert k.g == 9.82 and k.mass == 7.056 and k.cog == pytest.approx((0, 0, -0.0348))
    assert np.allclose(np.diag(k.mass_matrix(("Roll", "Pitch", "Yaw"))),
                       (0.098252, 0.098252, 0.073052))
    assert FloatingSphere.from_dict(k.to_dict()) == k


def test_hydrostatic_stiffness_analytic_and_capytaine(hulme_run):
    _, ds = hulme_run
    c_exact = RHO * G * math.pi * R**2
    assert FloatingSphere.paper().hydrostatic_stiffness()[0, 0] == pytest.approx(c_exact, rel=1e-12)
    assert float(ds["hydrostatic_stiffness"][0, 0]) == pytest.approx(c_exact, rel=1e-12)
    # Capytaine integrates over the polygonal mesh: the inscribed polygon loses a little area
    assert float(ds["hydrostatic_stiffness_mesh"][0, 0]) == pytest.approx(c_exact, rel=3e-3)


def test_buoyancy_force_exact_cap():
    s = FloatingSphere.paper()
    # at rest: Archimedes minus weight
    assert s.buoyancy_force(0.0) == pytest.approx(RHO * G * 2 / 3 * math.pi * R**3 - 7.06 * G)
    # fully submerged (z = -R): whole sphere volume
    assert s.buoyancy_force(-R) == pytest.approx(RHO * G * 4 / 3 * math.pi * R**3 - 7.06 * G)
    # just out of the water (z = +R): weight only
    assert s.buoyancy_force(R) == pytest.approx(-7.06 * G)
    # linearisation: dF/dz = -rho g pi R^2
    h = 1e-6
    slope = (s.buoyancy_force(h) - s.buoyancy_force(-h)) / (2 * h)
    assert slope == pytest.approx(-RHO * G * math.pi * R**2, rel=1e-6)
    f = s.buoyancy_force(np.array([-0.1, 0.0, 0.1]))
    assert f.shape == (3,) and np.all(np.diff(f) < 0)
    with pytest.raises(InputError, match="outside"):
        s.buoyancy_force(0.2)
    with pytest.raises(InputError):
        s.buoyancy_force(np.nan)


def test_body_input_errors():
    with pytest.raises(InputError):
        FloatingSphere(radius=-1)
    with pytest.raises(InputError):
        FloatingSphere(draft=0.4)
    with pytest.raises(InputError):
        FloatingSphere().capytaine_body(dofs=("Bob",))


def test_symmetric_lid_is_not_empty():
    hull, lid = FloatingSphere.paper().mesh(TEST_PANELS)
    assert hull.nb_faces == TEST_PANELS and lid.nb_faces > 0
    # lid area equals the waterplane area (inscribed polygon)
    assert lid.faces_areas.sum() == pytest.approx(math.pi * R**2, rel=5e-3)


# ------------------------------------------------------------------------- BEM vs Hulme
def test_added_mass_and_damping_match_hulme(hulme_run):
    table, ds = hulme_run
    kr, a_hat, b_hat = table.T
    omega = ds["omega"].values
    a = ds["added_mass"].values[:, 0, 0] / M_DISP
    b = ds["radiation_damping"].values[:, 0, 0] / (M_DISP * omega)
    np.testing.assert_allclose(a, a_hat, rtol=0.02)
    # B within 2 % where it is significant (KR <= 2, B_hat >= 30 % of its peak); beyond, B_hat
    # falls to 0.01 and the lidded 1600-panel mesh over-predicts it by up to 8 % (0.001 in
    # B_hat, 0.3 % of the peak), converging with the mesh (see test_paper_mesh_matches_hulme)
    sig = kr <= 2.0
    np.testing.assert_allclose(b[sig], b_hat[sig], rtol=0.02)
    assert np.all(np.abs(b - b_hat) <= 0.005 * b_hat.max())


def test_limits_match_theory(hulme_run):
    _, ds = hulme_run
    # A(inf) = half the displaced mass (Hulme); the 1600-panel mesh is within 0.3 %
    assert float(ds["added_mass_inf"][0, 0]) == pytest.approx(0.5 * M_DISP, rel=3e-3)
    # A(0) = 0.8310 displaced masses (Hulme, KR = 0 row)
    assert float(ds["added_mass_zero"][0, 0]) / M_DISP == pytest.approx(0.8310, rel=0.01)


def test_dataset_schema(hulme_run):
    _, ds = hulme_run
    assert ds["added_mass"].dims == ("omega", "radiating_dof", "influenced_dof")
    assert ds["excitation_force"].dims == ("omega", "wave_direction", "influenced_dof")
    assert np.iscomplexobj(ds["excitation_force"].values)
    for name in ("added_mass_inf", "added_mass_zero", "hydrostatic_stiffness", "mass"):
        assert ds[name].dims == ("radiating_dof", "influenced_dof")
    assert ds["radiation_damping"].attrs["units"] == "N s/m"
    for key in ("rho", "g", "water_depth", "body", "n_panels", "input_hash",
                "hybridwsi_version", "capytaine_version"):
        assert key in ds.attrs
    assert ds.attrs["n_panels"] == TEST_PANELS and ds.attrs["quality_flags"] == "[]"
    # the sphere's DOF origin is its centre of mass (the centre, for the paper's sphere)
    assert ds.attrs["reference_point"] == [0.0, 0.0, 0.0]
    assert json.loads(ds.attrs["mesh"])["resolution"] == [40, 80]
    assert float(ds["mass"][0, 0]) == 7.06


def test_excitation_obeys_haskind_relation(hulme_run):
    # Haskind/Newman (deep water, axisymmetric heave): B = k |X|^2 / (4 rho g c_g), c_g = g/(2ω)
    table, ds = hulme_run
    w = ds["omega"].values
    k, cg = w**2 / G, G / (2 * w)
    x = np.abs(ds["excitation_force"].values[:, 0, 0])
    b = ds["radiation_damping"].values[:, 0, 0]
    sig = table[:, 0] <= 2.0
    np.testing.assert_allclose(k[sig] * x[sig] ** 2 / (4 * RHO * G * cg[sig]), b[sig], rtol=0.01)


def test_excitation_long_wave_limit(tmp_path):
    # a very long wave lifts the body by the hydrostatic force rho g pi R^2 per metre of wave
    ds = bem.compute(FloatingSphere.paper(), [0.3], n_panels=400, cache_dir=tmp_path,
                     progress=False, include_inf=False, include_zero=False)
    f0 = ds["excitation_force"].isel(omega=0, wave_direction=0, influenced_dof=0).item()
    assert abs(f0) == pytest.approx(RHO * G * math.pi * R**2, rel=0.01)
    assert abs(f0.imag) < 0.01 * abs(f0)


# ------------------------------------------------------------------------- cache & resume
def _counting(monkeypatch):
    solved: list[float] = []
    real = bem.solve.solve_chunk

    def spy(solver, cbody, omegas, **kw):
        solved.extend(np.asarray(omegas).tolist())
        return real(solver, cbody, omegas, **kw)

    monkeypatch.setattr(bem.solve, "solve_chunk", spy)
    return solved


def test_cache_hit_solves_nothing(hulme_run, cache, monkeypatch):
    table, ds = hulme_run

    def boom(*a, **k):
        raise AssertionError("solved again despite the cache")

    monkeypatch.setattr(bem.solve, "solve_chunk", boom)
    again = bem.compute(FloatingSphere.paper(), ds["omega"].values, n_panels=TEST_PANELS,
                        cache_dir=cache, progress=False)
    xr.testing.assert_identical(again, ds)


def test_resume_solves_only_missing_frequencies(tmp_path, monkeypatch):
    body = FloatingSphere.paper()
    full = np.array([2.0, 4.0, 6.0, 8.0, 10.0])
    kw = dict(n_panels=400, cache_dir=tmp_path, progress=False, chunk_size=1)
    solved = _counting(monkeypatch)

    # "interrupted" run: the third chunk raises; the first two must be checkpointed
    real = bem.solve.solve_chunk
    calls = {"n": 0}

    def crash(*a, **k):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(bem.solve, "solve_chunk", crash)
    with pytest.raises(KeyboardInterrupt):
        bem.compute(body, full, **kw)
    monkeypatch.setattr(bem.solve, "solve_chunk", real)  # spy again, counting the resumed run
    solved.clear()
    resumed = bem.compute(body, full, **kw)
    assert solved == [6.0, 8.0, 10.0, 0.0, math.inf]  # 2 and 4 were checkpointed

    # a subset computed first is reused by a later, larger request
    solved.clear()
    bigger = bem.compute(body, np.append(full, 12.0), **kw)
    assert solved == [12.0]
    fresh = bem.compute(body, full, **{**kw, "use_cache": False})
    for name in ("added_mass", "radiation_damping", "excitation_force", "added_mass_inf"):
        np.testing.assert_allclose(resumed[name].values, fresh[name].values, rtol=1e-10)
        np.testing.assert_allclose(bigger[name].sel(omega=full).values if "omega" in
                                   bigger[name].dims else bigger[name].values,
                                   fresh[name].values, rtol=1e-10)


def test_corrupt_cache_file_is_recomputed(tmp_path):
    kw = dict(n_panels=400, cache_dir=tmp_path, progress=False, include_zero=False)
    first = bem.compute(FloatingSphere.paper(), [3.0], **kw)
    for f in tmp_path.glob("*.nc"):
        f.write_bytes(b"not a netcdf file")
    with pytest.warns(UserWarning, match="unreadable BEM cache"):
        again = bem.compute(FloatingSphere.paper(), [3.0], **kw)
    np.testing.assert_allclose(again["added_mass"].values, first["added_mass"].values, rtol=1e-12)


# ------------------------------------------------------------------------- validation
def test_negative_damping_is_flagged(tmp_path, monkeypatch):
    real = bem.solve.solve_chunk

    def corrupt(*a, **k):
        out = real(*a, **k)
        if 5.0 in out["omega"].values:
            out["radiation_damping"].loc[{"omega": 5.0}] = -1.0
        return out

    monkeypatch.setattr(bem.solve, "solve_chunk", corrupt)
    with pytest.warns(UserWarning, match="negative diagonal radiation damping"):
        ds = bem.compute(FloatingSphere.paper(), [3.0, 5.0], n_panels=400, cache_dir=tmp_path,
                         progress=False, use_cache=False)
    assert "negative" in ds.attrs["quality_flags"]


@pytest.mark.parametrize("bad", [dict(omega=[-1.0, 2.0]), dict(omega=[1.0, 1.0]),
                                 dict(omega=[np.nan]), dict(water_depth=0.1),
                                 dict(dofs=("Heave", "Spin")), dict(method="fast")])
def test_compute_input_errors(bad, tmp_path):
    kw = dict(omega=[1.0, 2.0], n_panels=400, cache_dir=tmp_path, progress=False)
    kw.update(bad)
    with pytest.raises(InputError):
        bem.compute(FloatingSphere.paper(), **kw)


def test_finite_depth_low_kh_is_filled(tmp_path):
    # Delhommeau returns NaN for kh < 0.13 at h = 0.9 m; FinGreen3D fills those. At kh >> 1 the
    # depth no longer matters: finite and deep-water coefficients agree.
    body = FloatingSphere.paper()
    kw = dict(n_panels=400, cache_dir=tmp_path, progress=False, include_zero=False)
    fin = bem.compute(body, [0.2, 12.0], water_depth=0.9, **kw)
    deep = bem.compute(body, [12.0], **kw)
    assert np.all(np.isfinite(fin["added_mass"].values))
    assert fin.attrs["dropped_omega"] == "[]"
    assert float(fin["radiation_damping"].sel(omega=0.2)[0, 0]) > 0
    np.testing.assert_allclose(fin["added_mass"].sel(omega=[12.0]).values,
                               deep["added_mass"].values, rtol=0.01)


def test_shipped_coefficients_keep_their_input_hash():
    # the body interface must not change what goes into the sphere's cache key: the plans of
    # the paper and Kramer configurations carry the hashes of the shipped files (no solving)
    def shipped(name: str) -> str:
        with xr.open_dataset(bem.PAPER_COEFFS.parent / name) as f:
            return f.attrs["input_hash"]

    assert bem.plan(**bem.paper_configuration()).input_hash == shipped("bem_paper_sphere.nc")
    kramer = bem.plan(FloatingSphere.kramer2021(), np.geomspace(0.1, 40, 400), water_depth=0.9,
                      n_panels=6400)
    low, high = kramer.parts
    assert low.input_hash == shipped("bem_kramer2021_sphere_finite_depth_part.nc")
    assert high.input_hash == shipped("bem_kramer2021_sphere_deep_part.nc")
    assert low.config["solver"]["low_kh_resolution"] == [40, 80]


def test_sphere_panel_size_names_the_same_mesh_as_a_panel_count():
    body, w = FloatingSphere.paper(), [1.0, 2.0]
    by_count = bem.plan(body, w, n_panels=1600)
    by_size = bem.plan(body, w, panel_size=math.pi * R / 40)  # 40 panels along a half meridian
    assert by_size.mesh == by_count.mesh == {"resolution": (40, 80)}
    assert by_size.input_hash == by_count.input_hash
    with pytest.raises(InputError, match="one of"):
        bem.plan(body, w, n_panels=1600, resolution=(40, 80))


def test_paper_configuration():
    cfg = bem.paper_configuration()
    w = cfg["omega"]
    assert w.size == 400 and w[0] == pytest.approx(0.1) and w[-1] == pytest.approx(40.0)
    assert np.allclose(np.diff(np.log(w)), np.log(400) / 399)
    assert cfg["n_panels"] == 6400 and cfg["body"] == FloatingSphere.paper()


def test_cli_bem_writes_netcdf(tmp_path, capsys):
    from hybridwsi.cli import main
    from hybridwsi.history import read_netcdf

    out = tmp_path / "c.nc"
    rc = main(["bem", "--panels", "400", "--n-omega", "6", "--omega-max", "12",
               "--cache-dir", str(tmp_path / "cache"), "--out", str(out)])  # summary printed
    assert rc == 0 and out.is_file()
    text = capsys.readouterr().out
    assert "A_inf" in text and "Tn =" in text and "wall time" in text
    assert read_netcdf(out).sizes["omega"] == 6
    assert main(["bem", "--omega-min", "-1"]) == 2


def test_cli_bem_takes_any_body(tmp_path, capsys):
    from hybridwsi.bodies import AxisymmetricBody
    from hybridwsi.cli import main
    from hybridwsi.history import read_netcdf

    spar = AxisymmetricBody(profile=[(0, -2.0), (0.5, -2.0), (0.5, 1.0)], cog=(0, 0, -1.2),
                            inertia=(3.0, 3.0, 1.0))
    spec = tmp_path / "spar.json"
    spec.write_text(spar.to_json())
    out = tmp_path / "c.nc"
    rc = main(["bem", "--body", str(spec), "--panel-size", "0.25", "--dofs", "Heave,Pitch",
               "--n-omega", "3", "--omega-max", "3", "--no-cache", "--out", str(out)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "Pitch: A_inf" in text and "N m/rad" in text
    ds = read_netcdf(out)
    assert list(ds["radiating_dof"].values) == ["Heave", "Pitch"]
    assert main(["bem", "--body", "{\"type\": \"Barge\"}", "--quiet"]) == 2


def test_shipped_paper_coefficients_match_hulme():
    # the shipped 6400-panel result (hybridwsi bem, 400 ω), cubic-interpolated to Hulme's KR
    from scipy.interpolate import CubicSpline

    ds = bem.paper_coefficients()
    w = ds["omega"].values
    table = hulme_table()
    table = table[(table[:, 0] >= 0.05) & (table[:, 0] <= 10.0)]
    kr, a_hat, b_hat = table.T
    wk = np.sqrt(kr * G / R)
    a = CubicSpline(w, ds["added_mass"].values[:, 0, 0])(wk) / M_DISP
    b = CubicSpline(w, ds["radiation_damping"].values[:, 0, 0])(wk) / (M_DISP * wk)
    np.testing.assert_allclose(a, a_hat, rtol=2e-3)
    np.testing.assert_allclose(b[kr <= 3], b_hat[kr <= 3], rtol=0.01)
    np.testing.assert_allclose(b[kr <= 5], b_hat[kr <= 5], rtol=0.03)
    assert float(ds["added_mass_inf"][0, 0]) == pytest.approx(0.5 * M_DISP, rel=1e-3)


@pytest.mark.slow
def test_paper_mesh_fresh_run(tmp_path):
    table = hulme_table()
    table = table[(table[:, 0] >= 0.5) & (table[:, 0] <= 2.0)]
    ds = bem.compute(FloatingSphere.paper(), np.sqrt(table[:, 0] * G / R), n_panels=6400,
                     cache_dir=tmp_path, progress=False, include_zero=False)
    assert float(ds["added_mass_inf"][0, 0]) == pytest.approx(0.5 * M_DISP, rel=0.01)
    assert float(ds["added_mass_inf"][0, 0]) == pytest.approx(0.5 * M_DISP, rel=1e-3)
    np.testing.assert_allclose(ds["added_mass"].values[:, 0, 0] / M_DISP, table[:, 1], rtol=2e-3)


def test_parallel_workers_give_identical_coefficients(tmp_path):
    """Two worker processes solve the same problems as one: identical numbers, same cache key."""
    body = FloatingSphere(radius=1.0, mass=2094.4)
    omega = np.linspace(0.5, 2.0, 4)
    kw = dict(n_panels=64, progress=False, use_cache=False, chunk_size=2)
    one = bem.compute(body, omega, n_jobs=1, **kw)
    two = bem.compute(body, omega, n_jobs=2, **kw)
    for name in ("added_mass", "radiation_damping", "excitation_force", "added_mass_inf"):
        np.testing.assert_array_equal(one[name].values, two[name].values)
    assert one.attrs["input_hash"] == two.attrs["input_hash"]


@pytest.mark.parametrize("bad", [0, -1, "two"])
def test_bad_job_count_is_rejected(bad):
    with pytest.raises(InputError, match="n_jobs"):
        bem.compute(FloatingSphere(radius=1.0, mass=2094.4), [1.0], n_jobs=bad, n_panels=64,
                    progress=False, use_cache=False)


def test_input_hash_ignores_the_last_bits_of_the_frequencies():
    # np.geomspace differs in the last bit between CPUs; the key of the shipped files must not
    w = bem.paper_frequencies()
    ulp = np.nextafter(w, np.inf)
    body = FloatingSphere.paper()
    key = bem.plan(body, w, n_panels=400).input_hash
    assert bem.plan(body, ulp, n_panels=400).input_hash == key
    assert bem.plan(body, w * (1 + 1e-8), n_panels=400).input_hash != key
