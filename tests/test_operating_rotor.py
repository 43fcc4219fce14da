"""The operating NREL 5-MW rotor (forces/rotor.py OperatingRotor and its shipped CCBlade table):
the steady thrust against the published curve, the kinematics of the hub and the shaft, the
aerodynamic damping as the diagnostic sees it and as free decays of OC3-Hywind show it."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hybridwsi.cases import load_case
from hybridwsi.cummins import simulate
from hybridwsi.cummins.system import build_system
from hybridwsi.diagnostic.regression import regress
from hybridwsi.dofs import RIGID_DOFS, index
from hybridwsi.errors import InputError, SolverError
from hybridwsi.forces import Hydrostatic, OperatingRotor, RotorTable, additional_damping
from hybridwsi.forces.rotor import rotor_from_case, shaft_levers
from hybridwsi.history import make_history
from hybridwsi.hydro import coefficients as co
from hybridwsi.hydro.modal import damped_modes, decay_modes
from hybridwsi.report.fowt import oc3_coefficients
from hybridwsi.wind import SteadyWind, TurbulentWind

TILT = math.radians(5.0)
HUB = (-5.0, 0.0, 90.0)
#: FAST's rotor thrust (the low-speed-shaft force) carries the rotor weight's component along
#: the 5-deg tilted shaft: 110 000 kg (Jonkman 2009 Table 1-1) x g x sin 5 deg = 94.0 kN
ROTOR_WEIGHT_ALONG_SHAFT = 110000.0 * 9.80665 * math.sin(TILT)
#: published steady thrust [N] of the NREL 5-MW turbine: NREL turbine-models repository,
#: Offshore/NREL_5MW_126_RWT.csv (commit be1ca72, "Thrust [kN]"), the steady-state curve of
#: Jonkman et al. 2009 (NREL/TP-500-38060) computed with FAST
PUBLISHED_THRUST = {3.0: 171.7e3, 8.0: 478.0e3, 11.4: 805.112e3, 18.0: 448.4e3}
#: Jonkman 2009 Table 7-1: blade pitch [deg] in region 3
PUBLISHED_PITCH = {12.0: 3.83, 18.0: 14.92, 25.0: 23.47}


@pytest.fixture(scope="module")
def table() -> RotorTable:
    return RotorTable.nrel_5mw()


def test_mean_thrust_against_the_published_curve(table):
    """CCBlade thrust + the rotor weight along the shaft within 5 % of the published FAST
    thrust at the OC3 wind speeds 8, 11.4, 18 m/s (and at cut-in, where the weight term is
    half of the published value: the evidence that it is in there)."""
    for u, published in PUBLISHED_THRUST.items():
        ours = float(table.thrust(u)) + ROTOR_WEIGHT_ALONG_SHAFT
        assert ours == pytest.approx(published, rel=0.05), u
    # the same numbers the docs quote (not a reference: a guard on the shipped file)
    assert float(table.thrust(8.0)) == pytest.approx(382.45e3, rel=1e-4)


def test_operating_points_against_jonkman_2009(table):
    """Rated wind speed within 2 % of 11.4 m/s, rated rotor speed 12.1 rpm, region-3 pitch of
    Table 7-1 within 0.35 deg, optimal tip-speed ratio 7.55 in region 2 (within 2 %), rated
    mechanical power 5.2966 MW above rated, and the slopes' signs: dT/dU > 0 below rated,
    < 0 above (the controller sheds thrust), the frozen slope > 0 everywhere above cut-in."""
    data = table.data
    assert data.attrs["rated_wind_speed"] == pytest.approx(11.4, rel=0.02)
    rpm = data["rotor_speed"].sel(wind_speed=slice(12.0, 30.0)) * 30.0 / math.pi
    np.testing.assert_allclose(rpm, 12.1, rtol=1e-6)
    for u, pitch in PUBLISHED_PITCH.items():
        assert math.degrees(float(table.value("blade_pitch", u))) == pytest.approx(pitch, abs=0.35)
    omega8 = float(table.value("rotor_speed", 8.0))
    assert omega8 * data.attrs["rotor_radius"] / 8.0 == pytest.approx(7.55, rel=0.02)
    above = data.sel(wind_speed=slice(12.0, 30.0))
    np.testing.assert_allclose(above["power"], 5296610.0, rtol=1e-6)
    rated = data.attrs["rated_wind_speed"]
    assert np.all(data["dT_dU"].sel(wind_speed=slice(3.0, rated - 0.01)) > 0)
    assert np.all(data["dT_dU"].sel(wind_speed=slice(rated + 0.01, 30.0)) < 0)
    assert np.all(data["dT_dU_frozen"].sel(wind_speed=slice(3.0, 30.0)) > 0)
    assert "wisdem_version" in data.attrs and "rotor_table.py" in data.attrs["command"]


def test_shaft_levers_are_rigid_body_kinematics():
    """j_Tᵀ ż is the hub velocity (v_O + ω × r) along the tilted shaft, and the generalised
    force does the virtual work of the thrust at the hub plus the torque on the rotation."""
    rng = np.random.default_rng(3)
    ref = (0.3, -0.2, -10.0)
    j_t, j_q = shaft_levers(HUB, ref, TILT)
    s = np.array([math.cos(TILT), 0.0, -math.sin(TILT)])
    r = np.asarray(HUB) - np.asarray(ref)
    for _ in range(10):
        qdot = rng.normal(size=6)
        v_hub = qdot[:3] + np.cross(qdot[3:], r)
        assert j_t @ qdot == pytest.approx(v_hub @ s, rel=1e-12)
        thrust, torque = rng.uniform(1e5, 1e6), rng.uniform(1e6, 5e6)
        work = thrust * s @ v_hub + torque * s @ qdot[3:]
        assert (thrust * j_t + torque * j_q) @ qdot == pytest.approx(work, rel=1e-12)
    # no tilt, reference point at the SWL: the familiar (1, 0, 0, 0, z_hub, -y_hub)
    j0, _ = shaft_levers((0.0, 2.0, 90.0), (0.0, 0.0, 0.0), 0.0, torque_reaction=False)
    np.testing.assert_allclose(j0, [1, 0, 0, 0, 90.0, -2.0], atol=1e-12)


def test_force_at_rest_and_the_relative_wind(table):
    """At rest: thrust T(U) along the shaft at the hub and the torque Q(U) about it; moving
    downwind at v the rotor sees U − v (its force is the table's at U − v), and the damping
    matrix is dT/dU j jᵀ (+ the torque row)."""
    rotor = OperatingRotor(table, SteadyWind(8.0), HUB, RIGID_DOFS, shaft_tilt=TILT)
    t8, q8 = float(table.thrust(8.0)), float(table.torque(8.0))
    c, s = math.cos(TILT), math.sin(TILT)
    expected = [t8 * c, 0.0, -t8 * s, q8 * c, t8 * (90.0 * c - 5.0 * s), -q8 * s]
    np.testing.assert_allclose(rotor.mean_force(), expected, rtol=1e-12, atol=1e-6)
    surge = np.array([0.7, 0, 0, 0, 0, 0])
    moving = rotor.ode_force(0.0, np.zeros(6), surge, None)
    u_rel = 8.0 - 0.7 * c
    assert moving[0] == pytest.approx(float(table.thrust(u_rel)) * c, rel=1e-12)
    assert moving[3] == pytest.approx(float(table.torque(u_rel)) * c, rel=1e-12)
    _, damping, stiffness = rotor.linear_coefficients(6)
    assert not stiffness.any()
    lever = rotor.lever
    np.testing.assert_allclose(damping[0], table.thrust_slope(8.0) * lever[0] * lever,
                               rtol=1e-12)
    # the linearisation is the force's slope (central differences, 1 cm/s of surge)
    fd = (rotor.ode_force(0.0, None, -0.01 * surge / 0.7, None)
          - rotor.ode_force(0.0, None, 0.01 * surge / 0.7, None)) / 0.02
    np.testing.assert_allclose(fd, damping[:, 0], rtol=0.01, atol=1e-6 * np.abs(fd).max())
    assert rotor.aero_damping == pytest.approx(95.6e3, rel=0.01)


def test_history_batch_and_compiled_kernel_agree(table):
    """force(hist) = ode_force per sample = the Numba kernel, steady and turbulent wind, all six
    DOFs shuffled; a relative wind outside the table is refused by all three."""
    dofs = ("Yaw", "Heave", "Roll", "Surge", "Pitch", "Sway")
    rng = np.random.default_rng(5)
    for wind in (SteadyWind(18.0), TurbulentWind(18.0, 0.12, seed=2, period=600.0)):
        rotor = OperatingRotor(table, wind, HUB, dofs, shaft_tilt=TILT)
        t = 13.0 + 37.3 * np.arange(40)  # spread over the wind period and beyond
        v = rng.normal(size=(40, 6)) * 0.5 * np.array([0.01, 1, 0.01, 1, 0.01, 1])
        hist = make_history(t, np.zeros((40, 6)), v, dof=list(dofs))
        f_hist = rotor.force(hist)
        k = rotor.compiled_force(6)
        out = np.empty(6)
        for i in range(40):
            single = rotor.ode_force(t[i], np.zeros(6), v[i], None)
            np.testing.assert_allclose(single, f_hist[i], rtol=1e-13)
            assert k.kernel(t[i], np.zeros(6), v[i], out, k.fdata, k.idata) == 0
            np.testing.assert_allclose(out, single, rtol=1e-12, atol=1e-9 * np.abs(single).max())
    fast = np.zeros(6)
    fast[dofs.index("Surge")] = -15.0  # 18 + 15 m/s of relative wind: past 30 m/s
    status = k.kernel(1.0, np.zeros(6), fast, out, k.fdata, k.idata)
    assert status != 0 and "outside the table" in k.messages[status]
    with pytest.raises(SolverError, match="outside the table"):
        rotor.ode_force(1.0, np.zeros(6), fast, None)


def test_diagnostic_beta_is_the_aerodynamic_damping(table):
    """Regress the rotor force of a forced surge + pitch motion (surge 0.5 m at 0.05 rad/s,
    pitch 0.002 rad at 0.21 rad/s, the OC3 natural frequencies: the relative wind moves by
    < 0.07 m/s, within one control region — 7.82 m/s ends region 1 1/2, where the slope drops
    from 95.6 to 80 kN s/m) at 8 and 18 m/s. The force is
    F ≈ F̄ + α z̈ + β ż + γ z, so a damping force −B ż has β = −B: β equals
    −dT/dU [[1, l], [l, l²]] (l the pitch lever of the tilted shaft, 89.2 m) within 1 %, and
    the rotor has no α or γ (< 1 % of β ω and β ω² at the surge frequency)."""
    dofs = ["Surge", "Pitch"]
    t = np.arange(0.0, 1200.0, 0.2)
    ws, wp = 0.05, 0.21
    a_s, a_p = 0.5, 0.002
    z = np.column_stack([a_s * np.sin(ws * t), a_p * np.sin(wp * t + 1.0)])
    zd = np.column_stack([a_s * ws * np.cos(ws * t), a_p * wp * np.cos(wp * t + 1.0)])
    zdd = np.column_stack([-a_s * ws**2 * np.sin(ws * t), -a_p * wp**2 * np.sin(wp * t + 1.0)])
    for u in (8.0, 18.0):
        rotor = OperatingRotor(table, SteadyWind(u), HUB, dofs, shaft_tilt=TILT)
        hist = make_history(t, z, zd, zdd, dof=dofs)
        hist["F_rotor"] = (("time", "dof"), rotor.force(hist))
        res = regress(hist, "F_rotor")
        lever = rotor.lever
        expected = -float(table.thrust_slope(u)) * np.outer(lever, lever)
        np.testing.assert_allclose(res.beta, expected, rtol=0.01)
        beta = abs(expected[0, 0])
        assert np.all(np.abs(res.alpha) * ws**2 < 0.01 * beta * ws * np.abs(lever[:, None]
                                                                           * lever[None, :]))
        assert np.all(np.abs(res.gamma) < 0.01 * beta * ws * np.abs(np.outer(lever, lever)))


# ------------------------------------------------------------------ free decays of OC3-Hywind
DOFS3 = ["Surge", "Heave", "Pitch"]


@pytest.fixture(scope="module")
def oc3():
    """The shipped OC3-Hywind coefficients, the published mooring stiffness (Eq. 5-3), the
    additional linear damping and one radiation state space for every decay."""
    case = load_case("oc3_hywind")
    coeffs = oc3_coefficients(case)
    idx = index(DOFS3)
    k = np.asarray(case["mooring"]["reference"]["K"])[np.ix_(idx, idx)]
    ss = build_system(coeffs, dofs=DOFS3, radiation="statespace", dt=0.25).ss
    return case, coeffs, k, ss


def _decay_zeta(oc3, rotor, dof: str, aperiodic: int = 0) -> tuple[float, np.ndarray]:
    """ζ of the released mode and the equilibrium: released 5 m (surge) or 0.02 rad (pitch)
    from the rotor's mean-offset equilibrium (C_hs + K) z_eq = F_rotor(rest); ``aperiodic``
    real exponentials join the fit (a controlled rotor's own modes)."""
    case, coeffs, k, ss = oc3
    stiffness = co.matrix(coeffs, "hydrostatic_stiffness", DOFS3) + k
    z_eq = np.linalg.solve(stiffness, rotor.mean_force())
    kick = {"Surge": [5.0, 0.0, 0.0], "Pitch": [0.0, 0.0, 0.02]}[dof]
    # Pitch: + a mode near 0.3 rad/s: the passive radiation state space's memory modes (coupled
    # eigenvalues −0.22 ± 0.30i, −0.20 ± 0.34i 1/s, ζ 0.5–0.6) show in the pitch decay under the
    # operating rotor's heavy damping (2.5 % RMS misfit of a two-mode fit; 0.1 % with it)
    duration, modes = {"Surge": (900.0, [0.0507, 0.212]),
                       "Pitch": (300.0, [0.212, 0.0507, 0.3])}[dof]
    forces = [Hydrostatic(k), additional_damping(case, DOFS3), rotor]
    hist = simulate(coeffs, dofs=DOFS3, duration=duration, dt=0.25, z0=z_eq + kick,
                    forces=forces, radiation_ss=ss)
    y = hist["z"].sel(dof=dof).values - z_eq[DOFS3.index(dof)]
    return decay_modes(hist["time"].values, y, modes, aperiodic=aperiodic)[0][0], z_eq


def _predicted_zeta(oc3, damping: np.ndarray) -> dict[str, float]:
    case, coeffs, k, _ = oc3
    b = additional_damping(case, DOFS3).linear_coefficients(3)[1] + damping
    return {m.dominant_dof: m.zeta for m in damped_modes(coeffs, k, b, DOFS3)}


@pytest.mark.parametrize("wind_speed", [8.0, pytest.param(18.0, marks=pytest.mark.slow)])
def test_decays_damped_by_what_the_thrust_slope_predicts(oc3, table, wind_speed):
    """Surge and pitch free decays of OC3-Hywind with the operating rotor against the parked
    one: the change of the damping ratio equals the closed-form prediction — the complex modes
    of the linear model with the aerodynamic damping dT/dU j jᵀ added (A, B at each mode's
    frequency) — within 10 % (+0.002). At 8 m/s the operating rotor damps surge and pitch
    more (ζ surge 6.1 → 11.9 %, pitch 4.1 → 24 %); at 18 m/s less (negative dT/dU)."""
    parked = OperatingRotor(table, SteadyWind(wind_speed), HUB, DOFS3, shaft_tilt=TILT)
    damping = parked.linear_coefficients(3)[1]
    pred_parked, pred_op = _predicted_zeta(oc3, 0.0 * damping), _predicted_zeta(oc3, damping)
    case = oc3[0]
    case_parked = {**case, "rotor": {**case["rotor"], "state": "parked"}}
    for dof in ("Surge", "Pitch"):
        z_parked, _ = _decay_zeta(oc3, rotor_from_case(case_parked, DOFS3), dof)
        z_op, z_eq = _decay_zeta(oc3, parked, dof)
        predicted = pred_op[dof] - pred_parked[dof]
        assert z_op - z_parked == pytest.approx(predicted, rel=0.1, abs=0.002), dof
        assert np.sign(z_op - z_parked) == np.sign(float(table.thrust_slope(wind_speed)))
    # the mean offset: ~12 m surge and 0.047 rad pitch at 8 m/s (C⁻¹ F, shipped numbers)
    assert z_eq[0] > 10.0 and 0.03 < z_eq[2] < 0.06


def test_rotor_from_case_operating(tmp_path):
    case = load_case("oc3_hywind")
    case["rotor"].update(state="operating", wind_speed=18.0)
    rotor = rotor_from_case(case, ["Surge", "Pitch"])
    assert isinstance(rotor, OperatingRotor) and isinstance(rotor.wind, SteadyWind)
    assert rotor.shaft_tilt == pytest.approx(TILT) and "quasi-steady" in rotor.describe()
    case["rotor"].update(turbulence_intensity=0.1, wind_seed=4, wind_period=600.0)
    turbulent = rotor_from_case(case, ["Surge", "Pitch"])
    assert isinstance(turbulent.wind, TurbulentWind) and turbulent.wind.seed == 4
    again = rotor_from_case(case, ["Surge", "Pitch"])
    np.testing.assert_array_equal(turbulent.wind.values, again.wind.values)
    # the table path is relative to the case file's folder
    src = RotorTable.nrel_5mw().data
    (tmp_path / "tables").mkdir()
    src.to_netcdf(tmp_path / "tables" / "mine.nc")
    case["rotor"]["table"] = "tables/mine.nc"
    assert rotor_from_case(case, ["Surge"], case_dir=tmp_path).table.source.endswith("mine.nc")
    with pytest.raises(InputError, match="rotor table not found"):
        rotor_from_case(case, ["Surge"])
    case["rotor"]["table"] = "rotor_nrel5mw.nc"  # the shipped one, by name
    for key, value, match in [("controller", "pid", "controller"),
                              ("wind_speed", 40.0, "outside"),
                              ("turbulence_intensity", -0.2, "turbulence")]:
        bad = {**case, "rotor": {**case["rotor"], key: value}}
        with pytest.raises(InputError, match=match):
            rotor_from_case(bad)


def test_case_schema_takes_the_rotor_keys(tmp_path):
    """The schema knows the operating rotor's keys (units converted: a tilt in rad becomes
    deg) and refuses a wrong one with one line; a case file elsewhere finds its own table."""
    from hybridwsi.cases import case_path

    text = case_path("oc3_hywind").read_text()
    text = text.replace('state = "parked"', 'state = "operating"', 1)
    text = text.replace("shaft_tilt = 5.0 ", 'shaft_tilt = "0.0872664626 rad" ', 1)
    text = text.replace('table = "rotor_nrel5mw.nc"', 'table = "mine.nc"', 1)
    RotorTable.nrel_5mw().data.to_netcdf(tmp_path / "mine.nc")
    (tmp_path / "spar.toml").write_text(text)
    case = load_case(tmp_path / "spar.toml")
    assert case["rotor"]["shaft_tilt"] == pytest.approx(5.0)
    rotor = rotor_from_case(case, ["Surge", "Pitch"])
    assert rotor.table.source == str(tmp_path / "mine.nc")
    (tmp_path / "bad.toml").write_text(text.replace('controller = "quasi-steady"',
                                                    'controller = "lqr"', 1))
    with pytest.raises(InputError, match="rotor.controller"):
        load_case(tmp_path / "bad.toml")


def test_bad_table_is_refused(tmp_path, table):
    data = table.data.copy()
    broken = data.drop_vars("dT_dU")
    with pytest.raises(InputError, match="dT_dU"):
        RotorTable(broken)
    nan = data.copy()
    nan["thrust"][3] = np.nan
    with pytest.raises(InputError, match="finite"):
        RotorTable(nan)
    unsorted = data.isel(wind_speed=np.r_[1, 0, 2:data.sizes["wind_speed"]])
    with pytest.raises(InputError, match="increasing"):
        RotorTable(unsorted)
    (tmp_path / "x.nc").write_text("not a netcdf")
    with pytest.raises(InputError, match="NetCDF"):
        RotorTable.from_file(tmp_path / "x.nc")
    assert isinstance(xr.Dataset(), xr.Dataset) and Path(tmp_path).is_dir()


# ---------------------------------------------------------- the PI-controlled rotor ("pi")
def _pi_rotor(table, u, gains="oc3_detuned", dofs=("Surge", "Pitch"), wind=None):
    from hybridwsi.forces import PIControlledRotor
    from hybridwsi.forces.controller import PI_GAINS, PitchPI, baseline_torque_law

    return PIControlledRotor(table, wind or SteadyWind(u), HUB, list(dofs),
                             pitch_control=PitchPI(*PI_GAINS[gains]),
                             torque_law=baseline_torque_law("constant_torque"),
                             drivetrain_inertia=40469564.0, shaft_tilt=TILT)


@pytest.mark.parametrize("u", [8.0, 11.4, 18.0])
def test_pi_rotor_steady_state_and_limits(table, u):
    """On its coefficient surfaces the model's steady state is the table's (rotor speed,
    pitch, thrust within 1e-4: the surfaces against the direct CCBlade solution), zero
    states do not move, and the linearised thrust response to the relative wind tends to the
    operating-curve slope for slow motion and to the frozen slope ∂T/∂U for fast motion
    (within 0.1 %)."""
    rotor = _pi_rotor(table, u)
    assert rotor.omega0 == pytest.approx(float(table.value("rotor_speed", u)), rel=1e-4)
    assert rotor.pitch0 == pytest.approx(float(table.value("blade_pitch", u)), abs=1e-4)
    assert rotor.mean_force()[0] == pytest.approx(float(table.thrust(u)) * math.cos(TILT),
                                                  rel=1e-4)
    xdot = rotor.state_derivative(0.0, None, np.zeros(2), np.zeros(3))
    assert np.all(np.abs(xdot) < 1e-9)
    h0, hinf = rotor.transfer(0.0)[0], rotor.transfer(1e4)[0]
    assert h0.real == pytest.approx(float(table.thrust_slope(u)), rel=1e-3)
    assert hinf.real == pytest.approx(float(table.value("dT_dU_frozen", u)), rel=1e-3)
    assert rotor.aero_damping == pytest.approx(h0.real)


def test_pi_rotor_forced_response_is_its_linearisation(table):
    """A small surge oscillation (relative wind ±0.04 m/s) at 0.05 and 0.21 rad/s, the
    states integrated along the history: the thrust's complex amplitude at the forcing
    frequency equals the closed-form transfer function δT/δU(iω) within 1 % — including the
    sign change of the damping between the surge and pitch frequencies at 18 m/s with the OC3
    detuned gains (the controller follows slow motion, lags fast motion)."""
    rotor = _pi_rotor(table, 18.0, dofs=("Surge",))
    lever = rotor.lever[0]
    for w in (0.05, 0.21):
        t = np.arange(0.0, 400.0, 0.1)
        amp = 0.04 / lever
        v = amp * np.sin(w * t)
        hist = make_history(t, -amp / w * np.cos(w * t), v[:, None], dof=["Surge"])
        thrust = rotor.force(hist)[:, 0] / lever
        late = t > 150.0  # the controller's transient (~0.2 rad/s, damped) has died out
        basis = np.column_stack([np.cos(w * t[late]), np.sin(w * t[late]), np.ones(late.sum())])
        a, b, _ = np.linalg.lstsq(basis, thrust[late], rcond=None)[0]
        # δU = −lever v = −0.04 sin ωt = Re[0.04 i e^{iωt}]; δT = Re[H 0.04 i e^{iωt}]
        h = rotor.transfer(w)[0]
        expected = h * 0.04j
        assert a == pytest.approx(expected.real, rel=0.01, abs=0.01 * abs(expected))
        assert -b == pytest.approx(expected.imag, rel=0.01, abs=0.01 * abs(expected))
    assert rotor.transfer(0.0507)[0].real < 0 < rotor.transfer(0.212)[0].real


def test_pi_rotor_in_a_simulation_and_from_the_case(oc3, table):
    """The case's controller = "pi" builds it; a run in turbulent wind is deterministic for a
    seed."""
    case, coeffs, k, _ = oc3
    spec = {**case, "rotor": {**case["rotor"], "state": "operating", "controller": "pi",
                              "wind_speed": 18.0, "turbulence_intensity": 0.1, "wind_seed": 5,
                              "wind_period": 600.0}}
    rotor = rotor_from_case(spec, DOFS3)
    assert rotor.n_states == 3 and "kp 0.00627" in rotor.describe()
    assert rotor.law.region3 == "constant_torque"
    forces = [Hydrostatic(k), additional_damping(case, DOFS3), rotor]
    z0 = np.linalg.solve(co.matrix(coeffs, "hydrostatic_stiffness", DOFS3) + k,
                         rotor.mean_force())
    ss01 = build_system(coeffs, dofs=DOFS3, radiation="statespace", dt=0.1).ss
    runs = [simulate(coeffs, dofs=DOFS3, duration=20.0, dt=0.1, z0=z0, forces=forces,
                     radiation_ss=ss01) for _ in range(2)]
    np.testing.assert_array_equal(runs[0]["z"].values, runs[1]["z"].values)
    assert np.isfinite(runs[0]["F_ext"].values).all()
    bad = {**spec, "rotor": {**spec["rotor"]}}
    del bad["rotor"]["drivetrain_inertia"]
    with pytest.raises(InputError, match="drivetrain_inertia"):
        rotor_from_case(bad, DOFS3)
    with pytest.raises(InputError, match="pi_gains"):
        rotor_from_case({**spec, "rotor": {**spec["rotor"], "pi_gains": "fast"}}, DOFS3)


@pytest.mark.parametrize("wind_speed", [18.0, pytest.param(8.0, marks=pytest.mark.slow)])
def test_pi_decays_match_the_coupled_linear_prediction(oc3, table, wind_speed):
    """Surge and pitch decays of OC3-Hywind with the PI-controlled rotor (OC3 detuned gains):
    the change of ζ from parked equals the prediction of the complex modes of the platform
    with the rotor's linearised states joined (within 10 % + 0.002). At 18 m/s the pitch mode
    is damped more than parked (+2 %), where the quasi-steady model (the controller following
    at once) made it 4 % less damped: the detuned controller lags the pitch motion."""
    case, coeffs, k, _ = oc3
    rotor = _pi_rotor(table, wind_speed, dofs=DOFS3)
    b_add = additional_damping(case, DOFS3).linear_coefficients(3)[1]
    pred = {m.dominant_dof: m.zeta
            for m in damped_modes(coeffs, k, b_add, DOFS3, state_force=rotor.state_space(3))}
    parked = {m.dominant_dof: m.zeta for m in damped_modes(coeffs, k, b_add, DOFS3)}
    case_parked = {**case, "rotor": {**case["rotor"], "state": "parked"}}
    for dof in ("Surge", "Pitch"):
        z_parked, _ = _decay_zeta(oc3, rotor_from_case(case_parked, DOFS3), dof)
        z_op, _ = _decay_zeta(oc3, rotor, dof, aperiodic=2)
        assert z_op - z_parked == pytest.approx(pred[dof] - parked[dof], rel=0.1, abs=0.002), dof
    if wind_speed == 18.0:
        assert z_op - z_parked > 0.01
