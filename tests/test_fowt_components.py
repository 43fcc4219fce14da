"""Issue 29 item 4: the diagnostic on the design-fidelity components (report/fowt_components.py).
The regression's β of the operating rotor against the aerodynamic damping of its operating
curve's slope (closed form), the solver's hold coupling against the delayed-spring closed form,
and the rotor's verdict (learnable lagged) predicted and observed. MoorDyn's numbers are the
script's (scripts/oc3_components.py, docs/OC3_HYWIND.md)."""

from __future__ import annotations

import numpy as np
import pytest

from hybridwsi.casemodel import CaseModel
from hybridwsi.diagnostic.stability import CoupledStep
from hybridwsi.forces import LaggedComponent
from hybridwsi.report import fowt_components as fc

pytest.importorskip("moorpy")

DOFS = ("Surge", "Heave", "Pitch")


@pytest.fixture(scope="module")
def model() -> CaseModel:
    return CaseModel.build("oc3_hywind", dofs=DOFS, dt=0.1, overrides={
        "rotor": {"state": "operating", "wind_speed": 8.0}})


def test_a_spring_held_over_the_rk4_step_is_a_delayed_spring():
    """A spring −k z held from the step's start acts like −k z(t − Δt/2): negative damping
    k Δt/2, so m z̈ + b ż + k z = 0 loses stability at Δt = 2 b / k (ω Δt ≪ 1)."""
    for b in (0.02, 0.05, 0.1):
        step = CoupledStep(mass=1.0, known_damping=b, gamma=-1.0, dt=0.01)
        assert fc.hold_rk4_limit(step, np.geomspace(1e-3, 2.0, 2000)) == pytest.approx(
            2 * b, rel=0.01)


def test_rotor_damping_regressed_and_its_lagged_verdict_observed(model):
    """Probe motion small enough to stay in region 2 (8 m/s, 0.18 m/s above the end of region
    1½): β = −dT/dU j jᵀ within 3 % on surge and pitch (j = (1, 0, z_hub) about SWL, tilt
    5°); predicted learnable lagged at Δt 0.1 s, and the decay with the rotor coupled one step
    lagged is stable and within 1 % of the decay with it in the ODE."""
    comps = model.components()
    rotor = comps["rotor"]
    small = fc.probe_history(model, comps, duration=300.0, dt=0.1,
                             rms={"Surge": 0.1, "Heave": 0.05, "Pitch": 0.001})
    pred = fc.predict(model, small, comps, "rotor", dt=0.1)
    b_rotor = rotor.linear_coefficients(3)[1]  # dT/dU j jᵀ of the table's slope
    np.testing.assert_allclose(np.diag(pred["beta"])[[0, 2]], -np.diag(b_rotor)[[0, 2]],
                               rtol=0.03)
    assert pred["learnable_lagged"] and pred["lagged"] == "stable"
    obs = fc.observe(model, "rotor", kick={"Surge": 2.0, "Pitch": 0.01}, duration=200.0,
                     dt=0.1)
    assert obs["in_ode"]["stable"] and obs["lagged"]["stable"]
    assert max(obs["difference"][d] for d in ("Surge", "Pitch")) < 0.01
    assert isinstance(LaggedComponent(rotor).inner, type(rotor))

