"""Morison's equation on members (one closed form per member type) and the OC4 semi's mooring
(issue 30 items 3-4).

Closed forms: steady current on a cylinder (drag ½ ρ Cd D L U² and its moment), axial
heave-plate drag in harmonic heave (force history and energy per cycle), a horizontal pontoon
in heave and along its axis, an inclined brace (normal component of the velocity), the slender
members' added mass ρ Ca V and Froude-Krylov + diffraction force ρ (1 + Ca) V a_wave, and
energy dissipation. Mooring: MoorPy against the definition's linearised stiffness (Eq. 5-15 as
quoted in cases/oc4_semi.toml) and the vertical balance of the floating system.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from hybridwsi.bodies import RigidAssembly, member_elements
from hybridwsi.casemodel import body_from_case
from hybridwsi.cases import load_case
from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.errors import InputError
from hybridwsi.forces import MemberMorison, MooringLines, MooringSystem
from hybridwsi.hydro.strip import slender_coefficients
from hybridwsi.waves import Regular, dispersion_k

CASE = load_case("oc4_semi")
RHO = 1025.0


def morison(*members, element_length=0.5, dofs=RIGID_DOFS, **kwargs) -> MemberMorison:
    return MemberMorison(member_elements(members, element_length), RHO, dofs, **kwargs)


def rates(**named) -> np.ndarray:
    q = np.zeros(6)
    for name, value in named.items():
        q[RIGID_DOFS.index(name)] = value
    return q


COLUMN = {"name": "col", "ends": [[0.0, 0.0, -20.0], [0.0, 0.0, 10.0]], "diameter": 6.5,
          "cd": 0.56, "potential": True}
PLATE = {"name": "plate", "ends": [[0.0, 0.0, -20.0], [0.0, 0.0, -14.0]], "diameter": 24.0,
         "cd": 0.68, "axial_cd": [4.8, 0.0], "potential": True}
PONTOON = {"name": "p", "ends": [[-10.0, 5.0, -17.0], [10.0, 5.0, -17.0]], "diameter": 1.6,
           "cd": 0.63, "ca": 1.0, "potential": False}


# ------------------------------------------------------------------------- drag
def test_column_in_a_steady_current():
    """Moving at -U through still water = a steady current U: F = ½ ρ Cd D L U² on the wet
    20 m, acting at mid-depth (pitch moment F × (-10 m)); nothing in heave, roll, yaw."""
    u = 1.3
    f = morison(COLUMN).generalised_force(0.0, rates(Surge=-u))
    drag = 0.5 * RHO * 0.56 * 6.5 * 20.0 * u**2
    assert f[0] == pytest.approx(drag, rel=1e-12)
    assert f[4] == pytest.approx(-10.0 * drag, rel=1e-12)
    assert np.allclose(f[[1, 2, 3, 5]], 0.0, atol=1e-9 * drag)
    # a current at 30 deg: same magnitude along it, the roll moment follows
    g = morison(COLUMN).generalised_force(0.0, rates(Surge=-u * math.cos(0.5236),
                                                     Sway=-u * math.sin(0.5236)))
    assert math.hypot(g[0], g[1]) == pytest.approx(drag, rel=1e-12)
    assert g[3] == pytest.approx(10.0 * g[1], rel=1e-12)


def test_heave_plate_axial_drag_in_harmonic_heave():
    """z = Z sin ωt: the bottom disc gives F = -½ ρ Cd_ax π R² |ż| ż (no transverse drag on a
    vertical member in heave); over a period it dissipates c (Zω)³ T 4/(3π), which the
    Borgman-linearised damping (8/3π) c Z ω dissipates too."""
    amp, omega = 2.0, 2 * math.pi / 17.5
    comp = morison(PLATE)
    c = 0.5 * RHO * 4.8 * math.pi * 12.0**2
    t = np.linspace(0.0, 2 * math.pi / omega, 4001)
    zdot = amp * omega * np.cos(omega * t)
    f = np.array([comp.generalised_force(tt, rates(Heave=v)) for tt, v in zip(t, zdot)])
    assert f[:, 2] == pytest.approx(-c * np.abs(zdot) * zdot, rel=1e-12)
    assert np.allclose(f[:, [0, 1, 3, 4, 5]], 0.0, atol=1e-12 * c)
    work = np.trapezoid(f[:, 2] * zdot, t)
    closed = -c * (amp * omega) ** 3 * (2 * math.pi / omega) * 4 / (3 * math.pi)
    assert work == pytest.approx(closed, rel=1e-6)
    b = comp.linearise_at(rates(Heave=amp * omega)).linear_coefficients(6)[1]
    assert b[2, 2] == pytest.approx(8 / (3 * math.pi) * c * amp * omega, rel=1e-12)
    assert -b[2, 2] * (amp * omega) ** 2 * math.pi / omega == pytest.approx(closed, rel=1e-6)


def test_pontoon_in_heave_sway_and_along_its_axis():
    comp = morison(PONTOON)
    c = 0.5 * RHO * 0.63 * 1.6 * 20.0
    w = 0.7
    assert comp.generalised_force(0.0, rates(Heave=w))[2] == pytest.approx(-c * w * w, rel=1e-12)
    f = comp.generalised_force(0.0, rates(Sway=w))
    assert f[1] == pytest.approx(-c * w * w, rel=1e-12)
    assert f[3] == pytest.approx(-(-17.0) * f[1], rel=1e-12)  # roll moment -z F_y
    assert f[5] == pytest.approx(0.0, abs=1e-9 * c)  # centred at x = 0: no yaw moment
    assert np.allclose(comp.generalised_force(0.0, rates(Surge=w)), 0.0, atol=1e-12 * c)


def test_inclined_brace_sees_the_normal_velocity_only():
    """Brace at 45° in the x-z plane, body moving along x at -U: |u_n| = U sin 45°, the force
    is normal to the axis: ½ ρ Cd D L |u_n| u_n."""
    brace = {"name": "b", "ends": [[0.0, 0.0, -10.0], [10.0, 0.0, 0.0]], "diameter": 1.6,
             "cd": 0.63, "potential": False}
    u = 1.0
    f = morison(brace, element_length=0.1).generalised_force(0.0, rates(Surge=-u))
    length = math.sqrt(200.0)
    un = u * math.sin(math.pi / 4)
    force = 0.5 * RHO * 0.63 * 1.6 * length * un * un  # along (1, 0, -1)/√2
    assert f[0] == pytest.approx(force / math.sqrt(2), rel=1e-12)
    assert f[2] == pytest.approx(-force / math.sqrt(2), rel=1e-12)


def test_drag_dissipates_energy_for_any_motion():
    comp = MemberMorison.from_case(CASE)
    rng = np.random.default_rng(3)
    q = rng.normal(size=(200, 6)) * np.array([1, 1, 1, 0.02, 0.02, 0.02])
    power = np.sum(comp.generalised_force(0.0, q) * q, axis=1)
    assert np.all(power < 0)
    # batch = one by one
    one = np.array([comp.generalised_force(0.0, v) for v in q[:5]])
    assert np.allclose(one, comp.generalised_force(0.0, q[:5]), rtol=1e-12, atol=0)


# ------------------------------------------------------------------------- inertia
def test_slender_added_mass_and_wave_inertia():
    """Added mass ρ Ca V across the axis (nothing along it, nothing for potential-flow members);
    in a regular deep-water wave the pontoon across the waves feels ρ (1 + Ca) V ∂w/∂t in heave
    with ∂w/∂t = -a ω² e^{kz} cos(ωt - k x)."""
    vol = math.pi * 0.8**2 * 20.0
    a = morison(PONTOON, COLUMN).added_mass()
    assert a[2, 2] == pytest.approx(RHO * vol, rel=1e-12)
    assert a[1, 1] == pytest.approx(RHO * vol, rel=1e-12)
    assert a[0, 0] == pytest.approx(0.0, abs=1e-9)
    across = {**PONTOON, "ends": [[5.0, -10.0, -17.0], [5.0, 10.0, -17.0]], "cd": 0.0}
    wave = Regular(period=9.0, height=2.0)
    comp = morison(across, wave=wave, water_depth=math.inf, g=9.81)
    omega, k = wave.omega, float(dispersion_k(wave.omega, math.inf, 9.81))
    for t in (0.0, 1.3, 4.0):
        f = comp.generalised_force(t, np.zeros(6))
        dwdt = -1.0 * omega**2 * math.exp(-17.0 * k) * math.cos(omega * t - k * 5.0)
        assert f[2] == pytest.approx(RHO * 2.0 * vol * dwdt, rel=1e-9)


def test_strip_theory_coefficients_are_the_time_domain_inertia():
    """The frequency-domain slender-member excitation Re[F̂ a e^{-iωt}] equals the time-domain
    Morison wave inertia of the same wave (30° heading, finite depth), and A_m the added mass."""
    comp = MemberMorison.from_case(CASE)
    e = comp.elements
    wave = Regular(period=8.0, height=2.0, phase=0.4, direction=math.radians(30.0))
    no_drag = MemberMorison(e, RHO, RIGID_DOFS, wave=wave, water_depth=200.0, g=9.80665)
    no_drag.coef[:] = 0.0
    no_drag.coef_end[:] = 0.0
    added, exc = slender_coefficients(e, np.array([wave.omega]), np.array([wave.direction]),
                                      rho=RHO, g=9.80665, water_depth=200.0, dofs=RIGID_DOFS)
    assert np.allclose(added, comp.added_mass(), rtol=1e-12, atol=1e-6)
    amp = 1.0 * np.exp(-1j * 0.4)
    for t in (0.0, 2.1, 5.5):
        expect = np.real(exc[0, 0] * amp * np.exp(-1j * wave.omega * t))
        got = no_drag.generalised_force(t, np.zeros(6))
        assert np.allclose(got, expect, rtol=1e-9, atol=1e-9 * np.abs(expect).max())
    assert np.abs(exc[0, 0, [1, 3, 5]]).min() > 0  # oblique: sway, roll, yaw excited


def test_force_on_a_history_includes_the_added_mass():
    comp = MemberMorison.from_case(CASE)
    rng = np.random.default_rng(0)
    n = 4
    hist = xr.Dataset({"z": (("time", "dof"), rng.normal(size=(n, 6))),
                       "zdot": (("time", "dof"), rng.normal(size=(n, 6)) * 0.1),
                       "zddot": (("time", "dof"), rng.normal(size=(n, 6)) * 0.01)},
                      coords={"time": np.arange(n) * 0.1, "dof": list(RIGID_DOFS)})
    f = comp.force(hist)
    expect = comp.generalised_force(0.0, hist["zdot"].values) - \
        hist["zddot"].values @ comp.added_mass().T
    assert np.allclose(f, expect, rtol=1e-12, atol=1e-6)
    a, b, c = comp.linear_coefficients(6)
    assert np.allclose(a, comp.added_mass()) and not b.any() and not c.any()


def test_case_members_and_bad_coefficients():
    comp = MemberMorison.from_case(CASE)
    e = comp.elements
    assert e.end_cd.size == 3 and np.allclose(e.end_area, math.pi * 144.0)
    assert set(np.array(e.member)[e.inertia]) == {m["name"] for m in CASE["body"]["hull"]["members"]
                                                  if not m["potential"]}
    assert e.centre[:, 2].max() < 0.0  # nothing above the still-water level
    with pytest.raises(InputError, match="axial_cd"):
        member_elements([{**PLATE, "axial_cd": [1.0]}])
    with pytest.raises(InputError, match="cd"):
        member_elements([{**PLATE, "cd": -1.0}])
    with pytest.raises(InputError, match="below the still-water"):
        member_elements([{**PONTOON, "ends": [[0, 0, 1.0], [5, 0, 2.0]]}])


# ------------------------------------------------------------------------- mooring
@pytest.fixture(scope="module")
def mooring() -> MooringSystem:
    pytest.importorskip("moorpy")
    return MooringSystem.from_case(CASE)


def test_mooring_layout_is_the_decks(mooring):
    lines = MooringLines.from_case(CASE)
    assert lines.anchors[0] == pytest.approx([418.8, 725.383, -200.0], abs=2e-3)
    assert lines.anchors[1] == pytest.approx([-837.6, 0.0, -200.0], abs=1e-9)
    assert lines.fairleads[2] == pytest.approx([20.434, -35.393, -14.0], abs=2e-3)
    # the apparent weight from the line's own displacement (MoorDyn's)
    w = (113.35 - RHO * math.pi * 0.0766**2 / 4) * 9.80665
    assert lines.weight_in_water == pytest.approx(w, rel=1e-5)


def test_mooring_stiffness_against_the_definition(mooring):
    """Eq. 5-15 as quoted: K11 = K22 7.08e4 N/m, K33 1.91e4 N/m, K44 = K55 8.73e7 N m/rad
    (measured +0.05 %, +0.21 %, -0.07 %)."""
    k = mooring.stiffness()
    ref = CASE["mooring"]["reference"]
    assert k[0, 0] == pytest.approx(ref["K11"], rel=0.01) == k[1, 1]
    assert k[2, 2] == pytest.approx(ref["K33"], rel=0.01)
    assert k[3, 3] == pytest.approx(ref["K44"], rel=0.01)
    assert k[4, 4] == pytest.approx(k[3, 3], rel=1e-6)
    assert k[0, 4] == pytest.approx(-k[1, 3], rel=1e-6) and k[0, 4] < 0


def test_vertical_balance_with_the_mooring(mooring):
    """Buoyancy (13 919 m³) - weight (14 072 718 kg) + F0_z = 0 within 0.1 % of the weight."""
    body: RigidAssembly = body_from_case(CASE)
    f0 = mooring.preload()
    residual = (RHO * body.displaced_volume() - body.mass) * body.g + f0[2]
    assert abs(residual) < 1e-3 * body.mass * body.g
    assert np.allclose(f0[[0, 1, 3, 4, 5]], 0.0, atol=1e-3)


@pytest.mark.slow
def test_moordyn_input_of_the_same_lines(mooring, tmp_path, monkeypatch):
    """The shipped MoorDyn v2 input (cases/oc4_semi_moordyn.dat) at rest against MoorPy:
    vertical pull within 0.1 % (measured +0.01 %), K11, K44, K66 within 2 % (+1.5 %, +0.2 %,
    0.0 %), K33 within 6 % (+5.6 %: MoorDyn's discretised line with seabed contact)."""
    pytest.importorskip("moordyn")
    from hybridwsi.forces import MoorDynForce

    monkeypatch.setenv("HYBRIDWSI_CACHE", str(tmp_path))
    md = MoorDynForce.from_case(CASE)
    f0, ref = md.rest_force(), mooring.preload()
    assert f0[2] == pytest.approx(ref[2], rel=1e-3)
    k, kp = md.stiffness(), mooring.stiffness()
    for i, tol in ((0, 0.02), (2, 0.06), (3, 0.02), (5, 0.02)):
        assert k[i, i] == pytest.approx(kp[i, i], rel=tol), i
