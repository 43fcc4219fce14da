"""Stability diagnostic of a force partition (paper Eq. 3–8, docs/THEORY.md §2–4).

- :func:`regress` — force sensitivities α, β, γ of the black-box force, with HAC uncertainty and
  identifiability (:mod:`~hybridwsi.diagnostic.regression`);
- :class:`CoupledStep` (the matrices and Δt of a coupled step), :func:`assess` (the one
  stability assessment, three settings) → :class:`StabilityReport`, :func:`max_stable_dt`
  (:mod:`~hybridwsi.diagnostic.stability`), with the shared step function :func:`lagged_step`
  (:mod:`~hybridwsi.diagnostic.integrators`);
- :func:`reconstruct` — paper Eq. 4 integration (:mod:`~hybridwsi.diagnostic.reconstruct`);
- known components in :mod:`~hybridwsi.forces`.
"""

from hybridwsi.forces import (
    AddedMass,
    Hydrostatic,
    KnownComponent,
    LinearDamping,
    QuadraticDamping,
    black_box_force,
    parse_known,
)
from hybridwsi.diagnostic.integrators import SCHEMES, lagged_step
from hybridwsi.diagnostic.reconstruct import ReconstructionResult, reconstruct
from hybridwsi.diagnostic.regression import RegressionResult, frequency_domain_split, regress
from hybridwsi.diagnostic.stability import (
    CoupledStep,
    SettingVerdict,
    StabilityReport,
    added_mass_ratio,
    amplification_matrix,
    assess,
    max_stable_dt,
)

__all__ = [
    "AddedMass", "Hydrostatic", "KnownComponent", "LinearDamping", "QuadraticDamping",
    "black_box_force", "parse_known",
    "SCHEMES", "lagged_step",
    "ReconstructionResult", "reconstruct",
    "RegressionResult", "frequency_domain_split", "regress",
    "CoupledStep", "SettingVerdict", "StabilityReport", "added_mass_ratio",
    "amplification_matrix", "assess", "max_stable_dt",
]
