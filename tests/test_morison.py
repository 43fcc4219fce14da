"""Morison strip drag against closed-form integrals of ½ ρ Cd D |u| u along a cylinder.

References are analytic (uniform cylinder: ∫ dz, ∫ z|z| dz, ∫ |z|³ dz, the deep-water Airy
profile ∫ e^{2kz} dz), the OC3 definition (Table 3-1 geometry, Table 4-2 Cd and additional
damping, via ``cases/oc3_hywind.toml``) and the energy balance of a dissipative force.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridwsi.bodies import AxisymmetricBody, RigidAssembly
from hybridwsi.cases import load_case
from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.errors import InputError
from hybridwsi.forces.linear import LinearDamping
from hybridwsi.forces.morison import MorisonDrag, Strips, additional_damping, profile_strips
from hybridwsi.history import make_history
from hybridwsi.waves import JONSWAP, Regular, airy_depth_factor, dispersion_k

RHO, CD, D, L = 1025.0, 0.6, 9.4, 120.0
K = 0.5 * RHO * CD * D  # ½ ρ Cd D [kg/m²]


def cylinder(n_strips: int = 120) -> Strips:
    """A uniform vertical cylinder, keel at -L, through the SWL."""
    return profile_strips([[0.0, -L], [D / 2, -L], [D / 2, 10.0]], n_strips=n_strips)


def rates(**dofs: float) -> np.ndarray:
    return np.array([dofs.get(d, 0.0) for d in RIGID_DOFS])


def test_strips_follow_the_oc3_profile():
    """Σ D dz is the projected area of Table 3-1's spar below the SWL, for any strip count."""
    case = load_case("oc3_hywind")
    area = 9.4 * 108.0 + 0.5 * (9.4 + 6.5) * 8.0 + 6.5 * 4.0  # 1104.8 m²
    for n in (1, 7, 13, 120, 1000):
        strips = profile_strips(case["body"]["hull"]["profile"], n_strips=n)
        assert strips.projected_area == pytest.approx(area, rel=1e-13)
        assert strips.length.sum() == pytest.approx(120.0, rel=1e-13)
    strips = MorisonDrag.from_case(case).strips
    assert strips.z.size == 120  # [drag] strip_length = 1 m
    # strip means: 9.4 m below the taper, 6.5 m above it, in between inside the taper
    assert np.allclose(strips.diameter[strips.z < -12.0], 9.4)
    assert np.allclose(strips.diameter[strips.z > -4.0], 6.5)
    mid = strips.diameter[(strips.z > -12.0) & (strips.z < -4.0)]
    np.testing.assert_allclose(mid, 6.5 + (9.4 - 6.5) * (-4.0 - strips.z[(strips.z > -12.0)
                                                                         & (strips.z < -4.0)]) / 8.0)


def test_pure_surge_is_drag_of_the_whole_length():
    """F = -½ρ Cd D L U|U| and the pitch moment F × (-L/2) about the SWL (exact for any N)."""
    drag = MorisonDrag(cylinder(17), CD, RHO)
    for u in (1.3, -0.4):
        q = drag.ode_force(0.0, np.zeros(6), rates(Surge=u), None)
        f = -K * L * u * abs(u)
        assert q[0] == pytest.approx(f, rel=1e-12)
        assert q[4] == pytest.approx(f * (-L / 2), rel=1e-12)
        assert np.abs(q[[1, 2, 3, 5]]).max() == 0.0
    # sway: the same force along y; the roll moment is -r_z F_y
    q = drag.ode_force(0.0, np.zeros(6), rates(Sway=0.8), None)
    assert q[1] == pytest.approx(-K * L * 0.64, rel=1e-12)
    assert q[3] == pytest.approx(-q[1] * (-L / 2), rel=1e-12)


def test_pure_pitch_rate_integrates_r_abs_r():
    """v = Ω r_z: F = -K Ω|Ω| ∫ r|r| dz, M = -K Ω|Ω| ∫ |r|³ dz (midpoint error ~ 2 dz²/L²)."""
    omega = 0.02
    drag = MorisonDrag(cylinder(1200), CD, RHO)
    q = drag.ode_force(0.0, np.zeros(6), rates(Pitch=omega), None)
    assert q[0] == pytest.approx(-K * omega**2 * (-L**3 / 3), rel=1e-5)
    assert q[4] == pytest.approx(-K * omega**2 * (L**4 / 4), rel=1e-5)
    # about mid-length the lever arm changes sign: no net force, M = -K Ω|Ω| 2 (L/2)^4 / 4
    mid = MorisonDrag(cylinder(1200), CD, RHO, reference_point=(0.0, 0.0, -L / 2))
    q = mid.ode_force(0.0, np.zeros(6), rates(Pitch=-omega), None)
    assert abs(q[0]) < 1e-9 * K * omega**2 * L**3
    assert q[4] == pytest.approx(K * omega**2 * 2 * (L / 2) ** 4 / 4, rel=1e-5)
    # roll mirrors pitch: v_y = -Ω r_z, so F_y = -F_x(pitch) and M_roll = M_pitch
    r = drag.ode_force(0.0, np.zeros(6), rates(Roll=omega), None)
    p = drag.ode_force(0.0, np.zeros(6), rates(Pitch=omega), None)
    assert r[1] == pytest.approx(-p[0], rel=1e-12) and r[3] == pytest.approx(p[4], rel=1e-12)


def test_heave_and_yaw_about_the_axis_give_no_transverse_drag():
    drag = MorisonDrag(cylinder(), CD, RHO)
    q = drag.ode_force(0.0, np.zeros(6), rates(Heave=2.0, Yaw=0.3), None)
    assert np.all(q == 0.0)
    # yaw about a reference point off the axis moves the strips sideways
    off = MorisonDrag(cylinder(), CD, RHO, reference_point=(3.0, 0.0, 0.0))
    q = off.ode_force(0.0, np.zeros(6), rates(Yaw=0.1), None)
    v = 0.1 * (0.0 - 3.0)  # v_y = Yaw' r_x
    assert q[1] == pytest.approx(-K * L * v * abs(v), rel=1e-12)
    assert q[5] == pytest.approx(q[1] * (0.0 - 3.0), rel=1e-12)  # M_z = r_x F_y


def test_drag_never_feeds_energy_into_the_body():
    """Power Q·q' = -Σ coef |v|³ ≤ 0 for any 6-DOF motion (reference point off the axis)."""
    drag = MorisonDrag(profile_strips(load_case("oc3_hywind")["body"]["hull"]["profile"], 1.0),
                       CD, RHO, reference_point=(1.5, -2.0, -30.0))
    rng = np.random.default_rng(47535)
    v = rng.normal(size=(500, 6)) * np.array([2.0, 2.0, 1.0, 0.05, 0.05, 0.2])
    q = drag.ode_force(0.0, np.zeros((500, 6)), v, None)
    power = np.einsum("ij,ij->i", q, v)
    assert np.all(power <= 0.0)
    jx, jy = drag._jx, drag._jy
    speed = np.hypot(v @ jx.T, v @ jy.T)
    np.testing.assert_allclose(power, -(drag.coef * speed**3).sum(axis=1), rtol=1e-10)


def test_batch_history_and_single_calls_agree():
    case = load_case("oc3_hywind")
    wave = JONSWAP(hs=6.0, tp=12.0, seed=3, n_components=80, direction=0.4)
    drag = MorisonDrag.from_case(case, RIGID_DOFS, wave=wave, ramp=20.0)
    rng = np.random.default_rng(1)
    t = np.arange(40) * 0.7
    v = rng.normal(size=(40, 6)) * np.array([1.0, 0.5, 0.3, 0.01, 0.02, 0.05])
    single = np.array([drag.ode_force(tk, np.zeros(6), vk, None) for tk, vk in zip(t, v)])
    hist = make_history(t, np.zeros((40, 6)), v, dof=list(RIGID_DOFS))
    np.testing.assert_allclose(drag.force(hist), single, rtol=1e-9, atol=1e-6)
    batch = drag.ode_force(t[5], np.zeros((40, 6)), v, None)
    np.testing.assert_allclose(batch[7], drag.ode_force(t[5], np.zeros(6), v[7], None), rtol=1e-12)
    # a 3-DOF component equals the 6-DOF one with the other DOFs at rest
    sub = MorisonDrag.from_case(case, wave=wave, ramp=20.0)
    assert sub.dofs == ("Surge", "Heave", "Pitch")
    v3 = v[:, [0, 2, 4]]
    v6 = np.zeros((40, 6))
    v6[:, [0, 2, 4]] = v3
    full = drag.ode_force(3.0, None, v6, None)
    np.testing.assert_allclose(sub.ode_force(3.0, None, v3, None), full[:, [0, 2, 4]], rtol=1e-12)
    with pytest.raises(InputError):
        sub.ode_force(0.0, None, np.zeros(6), None)
    with pytest.raises(InputError):
        sub.force(hist)


def test_wave_velocity_drag_on_a_still_cylinder_is_the_airy_integral():
    """Deep water: u = aω e^{kz} cos θ, F = K a²ω² cos θ|cos θ| ∫ e^{2kz} dz, M = ∫ z dF."""
    wave = Regular(period=7.0, height=4.0, phase=0.3)
    g = 9.80665
    k, a, w = (2 * math.pi / 7.0) ** 2 / g, 2.0, 2 * math.pi / 7.0
    drag = MorisonDrag(cylinder(3000), CD, RHO, wave=wave, g=g)  # deep water (depth inf)
    t = np.arange(8) * 1.1
    f = drag.ode_force(t[1], np.zeros(6), np.zeros(6), None)
    hist = make_history(t, np.zeros((8, 6)), np.zeros((8, 6)), dof=list(RIGID_DOFS))
    got = drag.force(hist)
    np.testing.assert_allclose(got[1], f, rtol=1e-10)
    cos = np.cos(w * t + 0.3)
    i_f = (1 - math.exp(-2 * k * L)) / (2 * k)
    i_m = -1 / (4 * k**2) + math.exp(-2 * k * L) * (L / (2 * k) + 1 / (4 * k**2))
    scale = K * a**2 * w**2
    # midpoint rule on e^{2kz}: relative error (2k dz)^2 / 24 = 1.8e-6 with 3000 strips
    np.testing.assert_allclose(got[:, 0], scale * cos * np.abs(cos) * i_f, rtol=5e-6)
    np.testing.assert_allclose(got[:, 4], scale * cos * np.abs(cos) * i_m, rtol=5e-6)
    # 320 m depth: at this wavelength (k h = 26) it is the deep-water answer
    finite = MorisonDrag(cylinder(3000), CD, RHO, wave=wave, g=g, water_depth=320.0)
    np.testing.assert_allclose(finite.force(hist), got, rtol=1e-9, atol=1e-6)


def test_finite_depth_kinematics():
    """cosh(k(z+h))/sinh(kh) against NumPy's, and u(z=0) = ω η / tanh(kh) at the surface."""
    h, g = 40.0, 9.80665
    k = dispersion_k(np.array([0.3, 0.6, 1.2]), h, g)
    z = np.array([-40.0, -12.5, -0.3, 0.0])
    np.testing.assert_allclose(airy_depth_factor(k, z, h),
                               np.cosh(np.outer(z + h, k)) / np.sinh(k * h), rtol=1e-12)
    wave = Regular(period=2 * math.pi / 0.3, height=1.0, phase=1.0, direction=math.pi / 2)
    surface = profile_strips([[0.0, -h], [1.0, -h], [1.0, 1.0]], n_strips=4000)
    drag = MorisonDrag(surface, CD, RHO, wave=wave, g=g, water_depth=h)
    t = np.linspace(0.0, 20.0, 9)
    ux, uy = drag._wave.components(t)
    eta = wave.elevation(t)
    top = 0.3 / math.tanh(k[0] * h) * eta  # u at the top strip centre, -h/8000 below z = 0
    np.testing.assert_allclose(uy[:, -1], top, rtol=1e-4, atol=1e-6)
    assert np.abs(ux).max() < 1e-12 * np.abs(uy).max()  # waves along +y: no x velocity


def test_linearisations():
    """Energy-equivalent damping at a stated amplitude; mean tangent on a history."""
    drag = MorisonDrag(cylinder(600), CD, RHO)
    assert not drag.linear_coefficients(6)[1].any()  # zero before linearising
    u = 0.7
    b = drag.linearise_at(rates(Surge=u)).linear_coefficients(6)[1]
    assert b[0, 0] == pytest.approx(8 / (3 * math.pi) * K * L * u, rel=1e-12)
    assert b[0, 4] == pytest.approx(b[0, 0] * (-L / 2), rel=1e-12)
    # coupled surge + pitch motion: one cycle's dissipated energy equals the nonlinear one
    amp = rates(Surge=0.5, Pitch=0.006)
    b = drag.linearise_at(amp).linear_coefficients(6)[1]
    phase = np.linspace(0.0, 2 * math.pi, 4001)[:-1]
    v = np.cos(phase)[:, None] * amp
    q = drag.ode_force(0.0, None, v, None)
    e_nonlinear = -np.einsum("ij,ij->i", q, v).mean()
    e_linear = np.einsum("ij,jk,ik->i", v, b, v).mean()
    assert e_linear == pytest.approx(e_nonlinear, rel=1e-6)
    # mean tangent over a history of surge v = U sin: 2 K L U mean|sin| = 4 K L U / π
    t = np.linspace(0.0, 100.0, 20001)
    hist = make_history(t, np.zeros((t.size, 6)),
                        np.outer(np.sin(2 * math.pi * t / 10.0), rates(Surge=u)),
                        dof=list(RIGID_DOFS))
    b = drag.linearise_on(hist).linear_coefficients(6)[1]
    assert b[0, 0] == pytest.approx(4 * K * L * u / math.pi, rel=1e-3)
    assert b[4, 4] == pytest.approx(4 * K * u / math.pi * L**3 / 3, rel=1e-3)
    assert b[1, 1] == pytest.approx(0.5 * b[0, 0], rel=1e-3)  # transverse: |u| only, not 2|u|
    a, _, c = drag.linear_coefficients(6)
    assert not a.any() and not c.any()


def test_from_body_and_additional_damping():
    case = load_case("oc3_hywind")
    hull = AxisymmetricBody(case["body"]["hull"]["profile"], rho=1025.0, g=9.80665,
                            reference_point=(0.0, 0.0, 0.0))
    items = [{"name": it["name"], "mass": it["mass"], "cm": it["cm"],
              "inertia_about_cm": it["inertia"]} for it in case["body"]["items"]]
    body = RigidAssembly(hull, items=items, reference_point=(0.0, 0.0, 0.0))
    drag = MorisonDrag.from_body(body, 0.6, ["Surge", "Pitch"])
    ref = MorisonDrag.from_case(case, ["Surge", "Pitch"])
    v = np.array([0.4, -0.01])
    np.testing.assert_allclose(drag.ode_force(0.0, None, v, None), ref.ode_force(0.0, None, v, None),
                               rtol=1e-12)
    assert "120 strips" in drag.describe()
    damp = additional_damping(case)  # the case's default DOFs: Surge, Heave, Pitch
    assert isinstance(damp, LinearDamping)
    np.testing.assert_array_equal(damp.linear_coefficients(3)[1], np.diag([1e5, 1.3e5, 0.0]))
    full = additional_damping(case, RIGID_DOFS).linear_coefficients(6)[1]
    np.testing.assert_array_equal(full, np.diag([1e5, 1e5, 1.3e5, 0.0, 0.0, 1.3e7]))
    with pytest.raises(InputError):
        additional_damping({"hydrodynamics": {}})
    with pytest.raises(InputError):
        profile_strips([[0.0, 1.0], [2.0, 5.0]])  # never below the SWL
    with pytest.raises(InputError):
        MorisonDrag(cylinder(), -1.0, RHO)
    with pytest.raises(InputError):
        MorisonDrag(cylinder(), CD, RHO, wave=Regular(8.0, 1.0), ramp=-1.0)


def _surge_pitch_coefficients(mass: np.ndarray, a_inf: np.ndarray, c: np.ndarray):
    """A coefficient Dataset with only what a radiation-free run needs (stored [j, i])."""
    import xarray as xr

    pair = ("radiating_dof", "influenced_dof")
    dofs = ["Surge", "Pitch"]
    return xr.Dataset({"added_mass_inf": (pair, a_inf.T), "hydrostatic_stiffness": (pair, c.T),
                       "mass": (pair, mass.T)},
                      coords={"radiating_dof": dofs, "influenced_dof": dofs},
                      attrs={"rho": RHO, "g": 9.80665, "input_hash": "oc3-like-surge-pitch"})


def test_drag_and_rotor_in_the_cummins_solver():
    """OC3-sized surge–pitch system, no radiation memory: the thrust offset C⁻¹ T j is an exact
    equilibrium (drag vanishes at rest), and the mechanical energy lost equals the work of the
    drag and the aerodynamic damping (their power integrated over the run)."""
    from hybridwsi import cummins
    from hybridwsi.forces.rotor import RotorThrust

    case = load_case("oc3_hywind")
    dofs = ["Surge", "Pitch"]
    m, zg = 8.066e6, -78.0  # the assembly's mass and CM height (docs/OC3_HYWIND.md)
    mass = np.array([[m, m * zg], [m * zg, 6.0e10]])
    a_inf = np.array([[8.0e6, -5.0e8], [-5.0e8, 4.0e10]])
    c = np.array([[41180.0, -2.82e6], [-2.82e6, 1.4e9]])  # mooring + hydrostatics, Eq. 5-3 order
    co = _surge_pitch_coefficients(mass, a_inf, c)
    drag = MorisonDrag.from_case(case, dofs)
    rotor = RotorThrust(8.0e5, 0.0, (-5.0, 0.0, 90.0), dofs)
    z_eq = np.linalg.solve(c, rotor.ode_force(0.0, None, np.zeros(2), None))
    still = cummins.simulate(co, dofs=dofs, duration=200.0, dt=0.5, z0=z_eq,
                             forces=[drag, rotor], radiation="none")
    np.testing.assert_allclose(still.z.values, np.broadcast_to(z_eq, still.z.shape),
                               rtol=1e-9, atol=1e-12)
    damped = RotorThrust(0.0, 2.0e5, (-5.0, 0.0, 90.0), dofs)
    h = cummins.simulate(co, dofs=dofs, duration=300.0, dt=0.1, z0=[8.0, 0.03],
                         forces=[drag, damped], radiation="none")
    z, v, t = h.z.values, h.zdot.values, h.time.values
    meff = mass + a_inf
    energy = 0.5 * np.einsum("ti,ij,tj->t", v, meff, v) + 0.5 * np.einsum("ti,ij,tj->t", z, c, z)
    work = drag.force(h) + damped.force(h)  # the state-dependent forces, from the history
    np.testing.assert_allclose(h.F_ext.values, work, rtol=1e-9, atol=1e-6 * np.abs(work).max())
    power = np.einsum("ti,ti->t", work, v)
    assert np.all(power <= 0.0)
    lost = -np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(t))])
    assert energy[-1] < 0.5 * energy[0]  # the run is strongly damped
    np.testing.assert_allclose(energy + lost, energy[0], rtol=1e-4)  # trapezoid error 2e-5
    # the undamped thrust is time-only: the linear solver's equilibrium is the same
    linear = cummins.simulate(co, dofs=dofs, duration=50.0, dt=0.5, z0=z_eq, forces=[rotor],
                              radiation="none")
    np.testing.assert_allclose(linear.z.values[-1], z_eq, rtol=1e-9)
