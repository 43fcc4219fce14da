"""Static gate of the SPH floating sphere (issue 15, item 4): held at -a, 0, +a in still water,
the fluid force against exact spherical-cap hydrostatics."""

import math

import pytest

from hybridwsi.sph import static_gate, tank

R = tank.SPHERE_D / 2
RHO_G = tank.RHO_WATER * tank.KRAMER_G


def test_exact_hydrostatics_of_the_held_sphere():
    # half immersed, the Kramer sphere's buoyancy is its weight (it floats at mid-height)
    assert static_gate.exact_fluid_force(0.0) == pytest.approx(
        tank.SPHERE_MASS * tank.KRAMER_G, rel=2e-4)
    # secant stiffness of a sphere about its equator: [V(R + a) - V(R - a)] / 2a = pi (R^2 -
    # a^2 / 3) with the cap volume V(d) = pi d^2 (3R - d) / 3 (analytic)
    a = 0.03
    res = [{"z": z, "mean": static_gate.exact_fluid_force(z), "std": 0.0,
            "exact": static_gate.exact_fluid_force(z)} for z in static_gate.HEIGHTS]
    g = static_gate.gate(res)
    assert g["stiffness_exact"] == pytest.approx(RHO_G * math.pi * (R * R - a * a / 3), rel=1e-12)
    assert g["buoyancy_error"] == 0.0 and g["stiffness_error"] == 0.0 and g["pass"]


def test_gate_fails_on_a_buoyancy_or_stiffness_error():
    res = [{"z": z, "mean": static_gate.exact_fluid_force(z), "std": 0.1,
            "exact": static_gate.exact_fluid_force(z)} for z in static_gate.HEIGHTS]
    weight = tank.SPHERE_MASS * tank.KRAMER_G
    res[1]["mean"] += 0.006 * weight  # at equilibrium: 0.6 % of the weight
    g = static_gate.gate(res)
    assert g["buoyancy_error"] == pytest.approx(0.006) and not g["pass"]
    res[1]["mean"] -= 0.006 * weight
    res[0]["mean"] *= 1.02  # lower height pushed 2 % harder: stiffness too high
    assert not static_gate.gate(res)["pass"]
    with pytest.raises(ValueError, match="heights"):
        static_gate.gate(res[:2])


@pytest.mark.sph
def test_static_gate_machinery_coarse():
    # R/dp = 4 in a small quarter tank with mirror planes, from the cut lattice (the start
    # before the packed default; the packed one is the next test), each height averaged over 5
    # acoustic periods. At this resolution the body's particle boundary stands the fluid off
    # a little too far (an effective sphere ~1 mm too large), a bias of about 1.7 % of the
    # weight at equilibrium and -2.1 % of the stiffness (docs/SPH_RUNS.md: neither the
    # first-order mDBC boundary, +4.0 % / -2.3 % here, nor a damped relaxation removes it),
    # so the coarse bounds are 2.5 % of the weight and 3.5 % of the stiffness; the 0.5 % / 1 %
    # gate itself is for D/10 and finer (scripts/sph_static_gate.py) and does not pass yet
    pytest.importorskip("pysph")
    res = [static_gate.held_force(0.0375, z, depth=0.3, half_width=0.3, settle=0.05,
                                  packing="lattice", relax=0.0)
           for z in static_gate.HEIGHTS]
    for r in res:
        # the average is over >= 5 periods 4 d / c0 and its noise is small against the signal
        assert r["t_avg"] >= 5 * 4 * 0.3 / (10 * math.sqrt(tank.KRAMER_G * 0.3)) - 1e-12
        assert r["std"] < 0.05 * r["exact"]
    g = static_gate.gate(res)
    assert abs(g["buoyancy_error"]) < 0.025, g
    assert abs(g["stiffness_error"]) < 0.035, g


@pytest.mark.sph
def test_packed_initial_state_removes_the_buoyancy_bias():
    # The body-fitted packing with the exact fluid volume and consistent masses
    # (hybridwsi.sph.packing) takes the held sphere's buoyancy error at equilibrium from
    # +1.6 % of the weight (the cut lattice, D/8 in a 0.45 m tank; +1.8 % at D/10) to
    # -0.5 % (-0.3 % at D/10 and D/12, where the 0.5 % gate passes; docs/SPH_RUNS.md).
    # D/8 here for time, in the 0.3 m quarter tank of the coarse test above (where the cut
    # lattice is ~1.7 % off; the packed start measured -0.30 % here, -0.51 % in the 0.45 m
    # tank at twice the cost): one height, relaxed start, five acoustic periods.
    pytest.importorskip("pysph")
    r = static_gate.held_force(0.0375, 0.0, depth=0.3, half_width=0.3, settle=0.3, relax=1e-3,
                               packing="packed")
    weight = tank.SPHERE_MASS * tank.KRAMER_G
    assert abs(r["mean"] - r["exact"]) < 0.01 * weight, r
    assert r["std"] < 0.02 * weight
