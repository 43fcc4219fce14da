"""The OC4-DeepCwind semi-submersible in six DOFs: its linear system, natural frequencies, free
decays and RAOs at several wave headings (library functions for the report section).

Everything comes from the case (``load_case("oc4_semi")``):

- coefficients: the shipped Capytaine solution of the columns and heave plates
  (``bem_oc4_semi.nc``, taken without solving when the inputs match) plus the slender
  members' Morison inertia (:func:`hybridwsi.casemodel.case_coefficients`);
- mooring: MoorPy's linearised stiffness K = −∂F/∂q of the three catenary lines;
- viscous damping: the members' Morison drag (columns, heave plates axially, pontoons, braces)
  linearised by energy equivalence (Borgman) at the velocity amplitudes of ``[linear_drag]``,
  one DOF at a time and summed (:func:`linearised_drag`).

The linear 6-DOF system of the decays and RAOs:

    (M + A∞) z̈ + ∫K ż + (C_hs + K_moor) z + B_drag ż = F_exc(t, β)

(radiation state space; ``B_drag`` constant). The frequency domain solves the same system with
A(ω), B(ω) (:func:`hybridwsi.report.fowt.frequency_response`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.casemodel import case_coefficients, radiation_ss
from hybridwsi.cases import Case, load_case
from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.errors import InputError
from hybridwsi.forces import Hydrostatic, KnownComponent, LinearDamping, MemberMorison, \
    MooringSystem
from hybridwsi.hydro.modal import Mode, natural_frequencies
from hybridwsi.report.fowt import decay_frequency, decay_histories, rao_curve, rao_point

#: initial offsets of the free decays [m, m, m, rad, rad, rad]: small (linear mooring)
SEMI_DECAY_OFFSET = {"Surge": 5.0, "Sway": 5.0, "Heave": 1.0, "Roll": 0.02, "Pitch": 0.02,
                     "Yaw": 0.05}
#: the solver step the radiation model is fitted for [s] (unused by a [radiation] table)
RADIATION_DT = 0.25
#: decay durations [s]: about 8 periods of each mode
SEMI_DECAY_DURATION = {"Surge": 900.0, "Sway": 900.0, "Heave": 150.0, "Roll": 220.0,
                       "Pitch": 220.0, "Yaw": 650.0}


@dataclass(frozen=True)
class SemiSystem:
    """The linear 6-DOF model of the semi.

    Attributes
    ----------
    coeffs : xarray.Dataset
        BEM + slender-member coefficients (6 DOFs, wave headings of ``[bem]``).
    mooring : ndarray (6, 6)
        K = −∂F/∂q at q = 0 [N/m, N/rad, N m/m, N m/rad], rows = force DOF.
    drag : ndarray (6, 6)
        Linearised member drag [N s/m, N s/rad, N m s/m, N m s/rad].
    radiation_ss : RadiationSS
        The radiation state space of the time domain (:func:`radiation_state_space`).
    dofs : tuple of str
        The six DOFs.
    """

    coeffs: xr.Dataset
    mooring: np.ndarray
    drag: np.ndarray
    radiation_ss: Any = None
    dofs: tuple[str, ...] = RIGID_DOFS

    @property
    def max_dt(self) -> float | None:
        """Largest RK4 step [s] for the radiation state space: 2 / max|pole| (RK4 is stable
        to |λ dt| ≈ 2.8 on the imaginary axis)."""
        if self.radiation_ss is None or not self.radiation_ss.order:
            return None
        return 2.0 / float(np.abs(self.radiation_ss.poles).max())

    def forces(self) -> list[KnownComponent]:
        """The linear components of the Cummins run: mooring stiffness and drag damping."""
        return [Hydrostatic(self.mooring), LinearDamping(self.drag)]


def linearised_drag(case: Mapping[str, Any], amplitudes: Mapping[str, float] | None = None
                    ) -> np.ndarray:
    """Σ over DOFs of the Borgman-linearised member drag for a harmonic motion of that DOF
    alone at its velocity amplitude (``[linear_drag]`` of the case, [m/s, rad/s]), (6, 6)."""
    amps = dict(case.get("linear_drag", {}) if amplitudes is None else amplitudes)
    if not amps:
        raise InputError("no velocity amplitudes for the drag linearisation ([linear_drag])")
    drag = MemberMorison.from_case(case, RIGID_DOFS, inertia=False)
    total = np.zeros((6, 6))
    for dof, value in amps.items():
        a = np.zeros(6)
        a[RIGID_DOFS.index(dof)] = float(value)
        total += drag.linearise_at(a).linear_coefficients(6)[1]
    return total


def radiation_state_space(case: Mapping[str, Any], coeffs: xr.Dataset):
    """The case's radiation state space (``[radiation]``, :func:`hybridwsi.casemodel.
    radiation_ss`) on the six DOFs.

    The default fit (a 30 s kernel, up to 20 states, the 6×6 kernel weighed by its largest
    entries) loses the semi's heave radiation and makes the coupled system unstable; the
    case's (40 s, up to 60 states, balanced) keeps B(ω) within 1.8 % RMS of the BEM's and the
    system stable (docs/OC4_SEMI.md)."""
    return radiation_ss(coeffs, RIGID_DOFS, None, RADIATION_DT, case.get("radiation"))


def semi_system(case: Case | None = None, table: str = "bem",
                cache_dir: Any = None) -> SemiSystem:
    """Coefficients (``[table]``: ``"bem"`` shipped, ``"bem_quick"`` coarse), MoorPy stiffness,
    linearised drag and radiation state space of the case (default ``oc4_semi``)."""
    case = load_case("oc4_semi") if case is None else case
    coeffs = case_coefficients(case, quick=table == "bem_quick", cache_dir=cache_dir)
    return SemiSystem(coeffs=coeffs, mooring=MooringSystem.from_case(case).stiffness(),
                      drag=linearised_drag(case),
                      radiation_ss=radiation_state_space(case, coeffs))


def semi_modes(system: SemiSystem) -> list[Mode]:
    """Undamped natural modes, A(ω) at each mode's frequency, C_hs + K_moor."""
    return natural_frequencies(system.coeffs, system.mooring, list(system.dofs))


def semi_decays(system: SemiSystem, *, dt: float = 0.2,
                offsets: Mapping[str, float] = SEMI_DECAY_OFFSET,
                durations: Mapping[str, float] = SEMI_DECAY_DURATION
                ) -> dict[str, dict[str, Any]]:
    """Free decay released in each DOF of ``offsets``: ``{dof: {"history", "hz"}}`` with the
    frequency [Hz] from the mean zero-crossing period of the released DOF."""
    hists = decay_histories(system.coeffs, system.forces(), dofs=system.dofs, dt=dt,
                            offsets=offsets, durations=durations,
                            radiation_ss=system.radiation_ss)
    return {d: {"history": h, "hz": decay_frequency(h, d)} for d, h in hists.items()}


def semi_raos(system: SemiSystem, periods: Sequence[float], headings_deg: Sequence[float], *,
              quick: bool = False) -> list[dict[str, Any]]:
    """Time-domain vs frequency-domain RAOs per heading and period
    (:func:`hybridwsi.report.fowt.rao_point`, all six DOFs)."""
    out = []
    for beta in headings_deg:
        for period in periods:
            point = rao_point(system.coeffs, system.forces(), float(period),
                              stiffness=system.mooring, damping=system.drag,
                              dofs=system.dofs, quick=quick, direction=math.radians(beta),
                              radiation_ss=system.radiation_ss, max_dt=system.max_dt)
            out.append({**point, "heading_deg": float(beta)})
    return out


def semi_rao_curves(system: SemiSystem, omegas: np.ndarray, headings_deg: Sequence[float]
                    ) -> np.ndarray:
    """|X(ω)|/a (n_heading, n_ω, 6) of the frequency-domain model."""
    return np.array([rao_curve(system.coeffs, system.mooring, system.drag, omegas,
                               system.dofs, direction=math.radians(b)) for b in headings_deg])
