"""The simple rotor: a parked rotor exerts nothing; a thrusting one a constant force at hub
height (moment = T × lever arm) and the linear damping of the hub's fore-aft velocity."""

from __future__ import annotations

import numpy as np
import pytest

from hybridwsi.cases import load_case
from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.errors import InputError
from hybridwsi.forces.rotor import ParkedRotor, RotorThrust, rotor_from_case
from hybridwsi.history import make_history


def test_parked_rotor_is_no_force():
    case = load_case("oc3_hywind")
    rotor = rotor_from_case(case)  # the case default
    assert isinstance(rotor, ParkedRotor) and rotor.dofs == ("Surge", "Heave", "Pitch")
    v = np.random.default_rng(0).normal(size=(5, 3))
    assert not rotor.ode_force(0.0, None, v, None).any()
    assert not any(m.any() for m in rotor.linear_coefficients(3))
    assert "no force" in rotor.describe()
    assert rotor.time_only and not rotor.time_force(np.arange(4.0)).any()


def test_thrust_and_its_moment_about_the_reference_point():
    thrust, hub = 8.0e5, (-5.0, 0.0, 90.0)
    rotor = RotorThrust(thrust, 0.0, hub, RIGID_DOFS)
    f = rotor.ode_force(0.0, None, np.zeros(6), None)
    np.testing.assert_allclose(f, [thrust, 0, 0, 0, thrust * 90.0, 0])  # M_y = z F_x
    # about a point 78 m below the SWL (near the CM) the arm is 168 m
    low = RotorThrust(thrust, 0.0, hub, ["Surge", "Pitch"], reference_point=(0.0, 0.0, -78.0))
    np.testing.assert_allclose(low.ode_force(0.0, None, np.zeros(2), None),
                               [thrust, thrust * 168.0])
    # a hub off the x-z plane: the thrust also yaws the platform, M_z = -y F_x
    side = RotorThrust(thrust, 0.0, (0.0, 2.0, 90.0), RIGID_DOFS)
    assert side.ode_force(0.0, None, np.zeros(6), None)[5] == pytest.approx(-2.0 * thrust)
    # a constant force: evaluated once on a time grid
    assert rotor.time_only
    np.testing.assert_array_equal(rotor.time_force(np.arange(3.0), 6), np.tile(f, (3, 1)))
    with pytest.raises(InputError):
        rotor.time_force(np.arange(3.0), 2)


def test_aerodynamic_damping_on_the_hub_velocity():
    b, h = 1.5e5, 90.0
    rotor = RotorThrust(8.0e5, b, (0.0, 0.0, h), ["Surge", "Heave", "Pitch"])
    _, damping, stiffness = rotor.linear_coefficients(3)
    np.testing.assert_allclose(damping, b * np.array([[1, 0, h], [0, 0, 0], [h, 0, h * h]]))
    assert not stiffness.any()
    assert not rotor.time_only  # the damping makes it state-dependent
    with pytest.raises(InputError):
        rotor.time_force(np.arange(3.0))
    v = np.array([0.3, -1.0, 0.004])  # hub velocity 0.3 + 0.004 * 90 = 0.66 m/s
    f = rotor.ode_force(0.0, None, v, None)
    np.testing.assert_allclose(f, [8.0e5 - b * 0.66, 0.0, (8.0e5 - b * 0.66) * h])
    # the force is exactly thrust + its linear damping; the damping never adds energy
    rng = np.random.default_rng(2)
    vs = rng.normal(size=(50, 3)) * [1.0, 1.0, 0.02]
    fs = rotor.ode_force(0.0, None, vs, None)
    np.testing.assert_allclose(fs, rotor.ode_force(0.0, None, np.zeros(3), None) - vs @ damping.T,
                               rtol=1e-12, atol=1e-6)
    assert np.all(np.einsum("ij,ij->i", fs - [8.0e5, 0.0, 8.0e5 * h], vs) <= 0.0)
    # history and single calls agree
    t = np.arange(50) * 0.1
    hist = make_history(t, np.zeros((50, 3)), vs, dof=["Surge", "Heave", "Pitch"])
    np.testing.assert_allclose(rotor.force(hist), fs, rtol=1e-12)
    with pytest.raises(InputError):
        rotor.force(make_history(t, np.zeros((50, 2)), vs[:, :2], dof=["Surge", "Pitch"]))
    with pytest.raises(InputError):
        rotor.ode_force(0.0, None, np.zeros(6), None)


def test_rotor_from_case_table():
    case = load_case("oc3_hywind")
    assert case["rotor"]["state"] == "parked"
    case["rotor"]["state"] = "thrust"
    rotor = rotor_from_case(case, ["Surge", "Pitch"])
    np.testing.assert_allclose(rotor.ode_force(0.0, None, np.zeros(2), None), [8.0e5, 7.2e7])
    assert "800000 N" in rotor.describe()
    case["rotor"]["state"] = "spinning"
    with pytest.raises(InputError, match="state"):
        rotor_from_case(case)
    with pytest.raises(InputError):
        RotorThrust(float("nan"))
    assert isinstance(rotor_from_case({"dofs": ["Surge"]}, ["Surge"]), ParkedRotor)
