"""MoorDyn as the dynamic mooring of OC3-Hywind (issue 29 item 1; docs/OC3_HYWIND.md "MoorDyn").

References are independent of MoorDyn: the definition (Jonkman 2010, Table 5-1), MoorPy's
continuous elastic catenary and its analytic stiffness, Huse's quasi-static-shape drag
dissipation (computed from MoorPy's catenary), and closed forms for the solver hook.
"""

from __future__ import annotations

import json
import pickle
import sys
from importlib import resources

import numpy as np
import pytest

from hybridwsi.cases import load_case
from hybridwsi.errors import InputError, SolverError
from hybridwsi.forces import Hydrostatic, KnownComponent
from hybridwsi.forces.moordyn import (
    MoorDynForce,
    assemble_stiffness,
    read_layout,
    set_options,
    set_segments,
)

SHIPPED = (resources.files("hybridwsi.cases") / "oc3_hywind_moordyn.dat").read_text()
ALL = ["Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"]


@pytest.fixture(autouse=True, scope="module")
def _private_statics_cache(tmp_path_factory):
    """Static solutions come from the shipped file or are computed here, never from the user's
    cache (the slow test checks the shipped file against a fresh computation)."""
    import hybridwsi.forces.moordyn as md

    mp = pytest.MonkeyPatch()
    mp.setenv("HYBRIDWSI_CACHE", str(tmp_path_factory.mktemp("cache")))
    mp.setattr(md, "_STATICS", {})
    yield
    mp.undo()


@pytest.fixture(scope="module")
def case():
    return load_case("oc3_hywind")


@pytest.fixture(scope="module")
def moorpy_system(case):
    pytest.importorskip("moorpy")
    from hybridwsi.forces.mooring import MooringSystem

    return MooringSystem.from_case(case)


@pytest.fixture(scope="module")
def at_rest(case):
    """One MoorDyn component solved at rest (shared: each static solve takes ~1-2 s)."""
    pytest.importorskip("moordyn")
    comp = MoorDynForce.from_case(case, ALL, dt=0.1)
    comp.rest_force()
    return comp


# ------------------------------------------------------------------- the input file (no MoorDyn)
def test_shipped_input_is_the_definitions_mooring(case):
    from hybridwsi.forces.mooring import MooringLines

    lines = MooringLines.from_case(case)
    layout = read_layout(SHIPPED)
    np.testing.assert_allclose(layout.anchors, lines.anchors, atol=1e-6)
    np.testing.assert_allclose(layout.fairleads, lines.fairleads, atol=1e-6)
    assert layout.coupled == (0, 1, 2) and layout.anchor_node == (0, 0, 0)
    # line type: Diam, Mass/m, EA; the apparent weight MoorDyn computes from them at the file's
    # rho and g is the definition's 698.094 N/m
    row = next(r for r in SHIPPED.splitlines() if r.startswith("main"))
    diam, mass, ea = (float(v) for v in row.split()[1:4])
    opts = {w[1].lower(): float(w[0]) for w in (r.split() for r in SHIPPED.splitlines()[-12:])
            if len(w) >= 2 and w[1].lower() in ("g", "rho", "wtrdpth")}
    weight = (mass - opts["rho"] * np.pi * diam**2 / 4) * opts["g"]
    assert weight == pytest.approx(case["mooring"]["weight_in_water"], rel=1e-6)
    assert mass == case["mooring"]["mass_per_length"] and ea == case["mooring"]["EA"]
    assert opts["wtrdpth"] == case["environment"]["water_depth"]
    assert opts["rho"] == case["environment"]["rho"] and opts["g"] == case["environment"]["g"]
    assert all(f"{case['mooring']['unstretched_length']}" in r for r in SHIPPED.splitlines()
               if r.split()[:2] in (["1", "main"], ["2", "main"], ["3", "main"]))


def test_input_editing_and_bad_inputs():
    text = set_segments(set_options(SHIPPED, {"dtM": 0.0005, "disableOutTime": 1}), 40)
    layout = read_layout(text)
    assert layout.segments == (40, 40, 40) and layout.dtm == 0.0005
    assert "1 disableOutTime" in text
    with pytest.raises(InputError, match="POINTS"):  # a v1 file has CONNECTION PROPERTIES
        read_layout(SHIPPED.replace("POINTS", "BODIES"))
    with pytest.raises(InputError, match="Fixed anchors to Coupled"):
        read_layout(SHIPPED.replace("4   Coupled", "4   Body1"))
    with pytest.raises(InputError, match="join a Fixed anchor"):
        read_layout(SHIPPED.replace("1   main      1        4", "1   main      1        2"))
    with pytest.raises(InputError, match="dtM"):
        read_layout(SHIPPED.replace("dtM", "dtX"))
    v1 = SHIPPED.replace("384.243E6  -0.8      0.0      1.6", "384.243E6  -0.8      1.6")
    with pytest.raises(InputError, match="v1 files"):  # a v1 line type has no EI column
        read_layout(v1)
    with pytest.raises(InputError, match="segments"):
        set_segments(SHIPPED, 0)


def test_missing_moordyn_is_one_input_error(monkeypatch, case):
    monkeypatch.setitem(sys.modules, "moordyn", None)
    comp = MoorDynForce.from_case(case, ["Surge"])
    with pytest.raises(InputError, match=r"pip install 'hybridwsi\[mooring\]'"):
        comp.begin_step(0.0, np.zeros(1), np.zeros(1), 0.1)


def test_from_case_errors(case, tmp_path):
    with pytest.raises(InputError, match="moordyn_file"):
        MoorDynForce.from_case({"mooring": {}}, ["Surge"])
    relative = {**case, "mooring": {**case["mooring"], "moordyn_file": "oc3_hywind_moordyn.dat"}}
    with pytest.raises(InputError, match="cannot read"):
        MoorDynForce.from_case(relative, ["Surge"], case_dir=tmp_path)
    # the loaded case names the file by its resolved path (the schema checks it exists)
    assert MoorDynForce.from_case(case, ["Surge"], case_dir=tmp_path).text == SHIPPED
    with pytest.raises(InputError, match="degree"):
        MoorDynForce(SHIPPED, ["Surge", "Bogus"])


def test_stiffness_assembly_reproduces_moorpys_analytic_6x6(moorpy_system):
    # MoorPy's own fairlead stiffness K_B and force of each line, assembled with the rotating
    # arms, must give MoorPy's analytic coupled 6x6 stiffness (independent formulas)
    ms = moorpy_system
    k_ref = ms.stiffness(yaw_spring=False)  # leaves the lines solved at rest
    lines = ms.moorpy.lineList
    k_pts = np.array([line.KB for line in lines])
    forces = np.array([line.fB for line in lines])  # force of each line on its fairlead
    k = assemble_stiffness(k_pts, forces, ms.lines.fairleads)
    np.testing.assert_allclose(k, k_ref, atol=1e-9 * np.abs(k_ref).max())


# ------------------------------------------------------------------- the solver hook
class _HeldSpring(KnownComponent):
    """−k z held over each step at its start value (a zero-order-hold coupled spring)."""

    name = "held_spring"

    def __init__(self, k: float) -> None:
        self.k, self.calls, self._f = k, [], None

    def begin_step(self, t, z, zdot, dt):
        self.calls.append(float(t))
        self._f = -self.k * np.asarray(z, float)

    def ode_force(self, t, z, zdot, x):
        return self._f.copy()

    def force(self, hist):
        return -self.k * hist["z"].values

    def linear_coefficients(self, n_dof):
        z = np.zeros((n_dof, n_dof))
        return z, z.copy(), self.k * np.eye(n_dof)


def test_stepping_solver_calls_begin_step_at_every_sample_and_converges_first_order():
    import synthetic_hydro as sh

    from hybridwsi.cummins import simulate

    coeffs = sh.coefficients()
    k, z0 = 300.0, 0.01
    omega = np.sqrt((sh.C + k) / (sh.M + sh.A_INF))  # the continuous spring, no radiation
    errors = []
    for dt in (0.004, 0.002):
        held = _HeldSpring(k)
        hist = simulate(coeffs, dofs=["Heave"], duration=2.0, dt=dt, z0=z0, forces=[held],
                        radiation="none")
        t = hist["time"].values
        np.testing.assert_allclose(held.calls, t, atol=1e-12)  # every sample, the last too
        # F_ext at a sample is the force the component held from that sample on: −k z_k
        np.testing.assert_allclose(hist["F_ext"].values[:, 0], -k * hist["z"].values[:, 0],
                                   rtol=1e-12, atol=1e-15)
        errors.append(np.abs(hist["z"].values[:, 0] - z0 * np.cos(omega * t)).max())
    # a force held over the step is first-order accurate: halving dt halves the error; it is
    # the spring delayed by dt/2, i.e. a negative damping −k dt/2 whose amplitude growth
    # exp(k dt t / (4 m)) is the error after t = 2 s (the phase error is second order)
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.1)
    growth = z0 * np.expm1(k * 0.002 * 2.0 / (4 * (sh.M + sh.A_INF)))
    assert errors[1] == pytest.approx(growth, rel=0.1)


# ------------------------------------------------------------------- MoorDyn statics vs MoorPy
def test_static_tensions_and_preload_against_moorpy(at_rest, moorpy_system, capfd, tmp_path):
    pytest.importorskip("moordyn")
    f0 = moorpy_system.preload()
    line = moorpy_system.moorpy.lineList[0]
    tension = at_rest.tensions()
    np.testing.assert_allclose(tension[:, 0], line.TB, rtol=0.01)  # fairlead, within 1 %
    np.testing.assert_allclose(tension[:, 1], line.TA, rtol=0.01)  # anchor
    assert at_rest.rest_force()[2] == pytest.approx(f0[2], rel=0.005)  # preload within 0.5 %
    np.testing.assert_allclose(at_rest.rest_force()[[0, 1, 3, 4, 5]], 0.0, atol=5.0)
    # silent: a new MoorDyn system prints nothing and writes nothing beside the input
    comp = MoorDynForce(SHIPPED, ["Pitch"], source=str(tmp_path / "x.dat"))
    capfd.readouterr()
    comp.begin_step(0.0, np.array([0.05]), np.zeros(1), 0.1)
    comp.begin_step(0.1, np.array([0.05]), np.zeros(1), 0.1)
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert not list(tmp_path.iterdir())
    # at a pitched pose the moments (about the displaced reference point) are MoorPy's
    q = np.array([0, 0, 0, 0, 0.05, 0])
    ref = moorpy_system.lines_force6(q) - f0
    got = comp.records()["force"].values[0]
    assert got[4] == pytest.approx(ref[4], rel=0.01)
    assert got[0] == pytest.approx(ref[0], rel=0.01)
    comp.close()


def test_statics_are_cached_on_disk_and_shipped_for_the_case(monkeypatch):
    pytest.importorskip("moordyn")
    import hybridwsi.forces.moordyn as md

    # the shipped solutions are those of the shipped input (else: scripts/oc3_moordyn.py ship)
    shipped = (resources.files("hybridwsi.data") / md.SHIPPED_STATICS).read_text()
    assert md.statics_key(SHIPPED, "rest", 0.0) in shipped
    assert md.statics_key(SHIPPED, "stiffness", md.FD_STEP) in shipped
    # another input: solved once, then read from the disk cache in a new process
    text = set_options(SHIPPED, {"threshIC": 2e-4})
    first = md.rest_statics(text)
    assert len(list(md.statics_cache_dir().glob("rest-*.json"))) == 1
    monkeypatch.setattr(md, "_STATICS", {})

    def no_solve(*args, **kwargs):
        raise AssertionError("a static solve was repeated")

    monkeypatch.setattr(md, "_System", no_solve)
    np.testing.assert_array_equal(md.rest_statics(text)["forces"], first["forces"])
    np.testing.assert_array_equal(md.rest_statics(SHIPPED)["tensions"],
                                  np.array(json.loads(shipped)[
                                      md.statics_key(SHIPPED, "rest", 0.0)]["tensions"]))


@pytest.mark.slow
def test_shipped_statics_are_a_fresh_computation():
    pytest.importorskip("moordyn")
    import hybridwsi.forces.moordyn as md

    rest = md.rest_statics(SHIPPED)
    fresh = md.rest_statics(SHIPPED, use_cache=False)
    for name in ("forces", "tensions"):
        np.testing.assert_allclose(rest[name], fresh[name], rtol=1e-7, atol=1e-3)
    np.testing.assert_allclose(md.fairlead_stiffness(SHIPPED),
                               md.fairlead_stiffness(SHIPPED, use_cache=False), rtol=1e-6,
                               atol=1e-3)


def test_linearised_stiffness_against_moorpy(at_rest, moorpy_system):
    # K = −∂F/∂q at rest from MoorDyn's static solves (±0.5 m, shipped), lines only, vs
    # MoorPy's analytic K
    k = at_rest.stiffness()
    k[5, 5] -= at_rest.yaw_spring
    ref = moorpy_system.stiffness(yaw_spring=False)
    for i, j in [(0, 0), (2, 2), (4, 4), (0, 4), (4, 0), (1, 1), (3, 3), (5, 5), (1, 3)]:
        assert k[i, j] == pytest.approx(ref[i, j], rel=0.01), (i, j)
    a, b, c = at_rest.linear_coefficients(6)
    assert not a.any() and not b.any()
    assert c[5, 5] == pytest.approx(ref[5, 5] + 9.834e7, rel=0.01)


# ------------------------------------------------------------------- stepping, records, resume
def _surge(t):
    return 2.0 * np.sin(2 * np.pi * t / 10.0) * np.minimum(t / 10.0, 1.0)


def test_resume_from_saved_state_continues_exactly(case):
    pytest.importorskip("moordyn")
    t = np.arange(0, 201) * 0.1
    x = _surge(t)
    v = np.gradient(x, t)
    whole = MoorDynForce.from_case(case, ["Surge"])
    for k, (tk, xk, vk) in enumerate(zip(t, x, v)):
        whole.begin_step(tk, [xk], [vk], 0.1)
        if k == 100:  # saved in the middle (and pickled, as a checkpoint file would be)
            state = pickle.loads(pickle.dumps(whole.get_state()))
    ref = whole.records()
    second = pickle.loads(pickle.dumps(MoorDynForce.from_case(case, ["Surge"])))
    second.set_state(state)
    for tk, xk, vk in zip(t[100:], x[100:], v[100:]):
        second.begin_step(tk, [xk], [vk], 0.1)
    got = second.records()
    np.testing.assert_allclose(got["force"].values, ref["force"].values[100:], rtol=1e-10,
                               atol=1e-6)
    np.testing.assert_allclose(got["T_fairlead"].values, ref["T_fairlead"].values[100:],
                               rtol=1e-10)
    # the line dynamics are there: the surge force is not the quasi-static −K x (phase lag)
    f = ref["force"].values[:, 0]
    assert np.corrcoef(f[100:], -x[100:])[0, 1] < 0.9
    with pytest.raises(InputError, match="saved state"):
        second.set_state({"t": 0.0})
    for comp in (whole, second):
        comp.close()


def test_ode_force_needs_begin_step(case):
    comp = MoorDynForce.from_case(case, ["Surge"])
    with pytest.raises(SolverError, match="begin_step"):
        comp.ode_force(0.0, np.zeros(1), np.zeros(1), np.zeros(0))
    with pytest.raises(InputError, match="1 DOFs"):
        comp.begin_step(0.0, np.zeros(2), np.zeros(2), 0.1)
    with pytest.raises(SolverError, match="not finite"):
        comp.begin_step(0.0, np.array([np.nan]), np.zeros(1), 0.1)
    with pytest.raises(InputError, match="increasing"):
        comp.drive([0.0, 0.0], np.zeros((2, 1)))


def test_force_on_a_history_replays_the_coupled_run(case):
    # the diagnostic's force(hist) drives MoorDyn along the history's motion: on a history that
    # simulate produced with the component coupled, it is the F_ext of that run
    pytest.importorskip("moordyn")
    from hybridwsi.cummins import simulate
    from hybridwsi.report.fowt import oc3_coefficients

    dofs = ["Surge", "Heave", "Pitch"]
    comp = MoorDynForce.from_case(case, dofs, dt=0.1)
    hist = simulate(oc3_coefficients(case), dofs=dofs, duration=10.0, dt=0.1,
                    z0=[3.0, 0.2, 0.01], forces=[comp], radiation="none")
    # its own run: the recorded forces; a fresh component drives MoorDyn along z, zdot again
    np.testing.assert_allclose(comp.force(hist), hist["F_ext"].values, rtol=1e-12, atol=1e-6)
    np.testing.assert_allclose(comp.spawn().force(hist), hist["F_ext"].values, rtol=1e-9,
                               atol=1e-3)
    from hybridwsi.forces.mooring import LineTensions

    assert isinstance(comp, LineTensions) and comp.n_lines == 3
    rec = comp.records()
    tension = comp.line_tensions(hist)
    np.testing.assert_array_equal(tension[..., 0], rec["T_fairlead"].values)
    np.testing.assert_array_equal(tension[..., 1], rec["T_anchor"].values)
    assert rec.sizes == {"time": hist.sizes["time"], "dof": 6, "line": 3}
    np.testing.assert_allclose(rec["time"], hist["time"])
    # surge +3 m moves the fairleads towards line 1's anchor: line 1 slackens, 2 and 3 tighten
    t0 = rec["T_fairlead"].values[0]
    assert t0[0] < t0[1] == pytest.approx(t0[2], rel=1e-9)
    comp.close()


def test_forced_surge_dissipation_at_a_wave_period_near_huse(case, moorpy_system):
    # T = 10 s, X = 2 m: MoorDyn's loop area against Huse's quasi-static-shape estimate, which
    # leaves out the lines' inertia and elastic waves (MoorDyn is 3-4 % above it here; at the
    # surge period the two agree within 0.5 %, the slow test below)
    pytest.importorskip("moordyn")
    from hybridwsi.report.moordyn_study import forced_loop, loop_metrics

    comp = MoorDynForce.from_case(case, ["Surge"])
    loop = forced_loop(comp, moorpy_system, "Surge", 2.0, 10.0, dt=0.1, cycles=4)
    md, qs = loop_metrics(loop), loop_metrics(loop, "F_quasi_static")
    huse = moorpy_system.drag_dissipation([2.0, 0, 0, 0, 0, 0], 10.0, cd=1.6, cd_axial=0.1,
                                          diameter=0.09)["total"]
    assert md["E"] == pytest.approx(huse, rel=0.06)
    assert md["E_first_harmonic"] == pytest.approx(md["E"], rel=0.02)
    assert abs(qs["E"]) < 1e-3 * md["E"]  # the quasi-static force has no loop
    assert 60.0 < md["phase_deg"] < 85.0 and abs(qs["phase_deg"]) < 0.1


@pytest.mark.slow
def test_forced_surge_at_the_surge_period_matches_huse(case, moorpy_system):
    pytest.importorskip("moordyn")
    from hybridwsi.report.moordyn_study import forced_loop, loop_metrics

    comp = MoorDynForce.from_case(case, ["Surge"])
    loop = forced_loop(comp, moorpy_system, "Surge", 10.0, 125.0, dt=0.1, cycles=4)
    md = loop_metrics(loop)
    huse = moorpy_system.drag_dissipation([10.0, 0, 0, 0, 0, 0], 125.0, cd=1.6, cd_axial=0.1,
                                          diameter=0.09)["total"]
    assert md["E"] == pytest.approx(huse, rel=0.015)
    # in-phase stiffness: the quasi-static secant over ±10 m (MoorPy), phase a few degrees
    k_qs = -loop_metrics(loop, "F_quasi_static")["K_real"]
    assert -md["K_real"] == pytest.approx(k_qs, rel=0.01)
    assert 5.0 < md["phase_deg"] < 10.0


@pytest.mark.slow
def test_at_rest_six_dofs_keeps_the_definitions_tensions(case, moorpy_system):
    # the library call behind `hybridwsi simulate --case oc3_hywind --mooring moordyn --dofs
    # Surge,...,Yaw --duration 120 --dt 0.1`: at rest the body stays put and the three
    # fairlead tensions are the definition's (MoorPy's continuous catenary)
    pytest.importorskip("moordyn")
    from hybridwsi.cummins import simulate
    from hybridwsi.forces import additional_damping
    from hybridwsi.report.fowt import oc3_coefficients

    comp = MoorDynForce.from_case(case, ALL, dt=0.1)
    hist = simulate(oc3_coefficients(case), dofs=ALL, duration=120.0, dt=0.1,
                    forces=[comp, additional_damping(case, ALL)])
    rec = comp.records()
    assert rec.sizes["time"] == hist.sizes["time"] == 1201
    tb = moorpy_system.moorpy.lineList[0].TB
    np.testing.assert_allclose(rec["T_fairlead"].values, tb, rtol=0.005)
    np.testing.assert_allclose(rec["T_anchor"].values, moorpy_system.moorpy.lineList[0].TA,
                               rtol=0.005)
    z = np.abs(hist["z"].values).max(axis=0)
    assert z[:3].max() < 0.01 and z[3:].max() < 1e-5  # m, rad
    comp.close()
