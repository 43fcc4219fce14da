"""Force components: one interface (:class:`KnownComponent`) for every stage.

Generators (Cummins), reconstruction, the diagnostic, component selection and the hybrid
rollout all take the same objects. Sign convention and linearisation: docs/THEORY.md §1.
"""

from hybridwsi.forces.base import (
    KnownComponent,
    as_matrix,
    black_box_force,
    kinematic,
    summed_linear_coefficients,
    total_known_force,
)
from hybridwsi.forces.drift import SlowDriftForce
from hybridwsi.forces.external import ConstantForce, PrescribedForce
from hybridwsi.forces.hydrostatics import ExactHydrostatic
from hybridwsi.forces.lagged import LaggedComponent
from hybridwsi.forces.linear import (
    REGISTRY,
    AddedMass,
    Hydrostatic,
    LinearDamping,
    QuadraticDamping,
    known_from,
    parse_known,
)
from hybridwsi.forces.moordyn import MoorDynForce
from hybridwsi.forces.mooring import MooringForce, MooringLines, MooringSystem, MooringTable
from hybridwsi.forces.morison import (MemberMorison, MorisonDrag, Strips, additional_damping,
                                     profile_strips)
from hybridwsi.forces.radiation import RadiationMemory
from hybridwsi.forces.rotor import (
    OperatingRotor,
    ParkedRotor,
    PIControlledRotor,
    RotorTable,
    RotorThrust,
    rotor_from_case,
)

__all__ = [
    "KnownComponent", "as_matrix", "black_box_force", "kinematic", "summed_linear_coefficients",
    "total_known_force", "REGISTRY", "AddedMass", "Hydrostatic", "LinearDamping",
    "QuadraticDamping", "known_from", "parse_known", "RadiationMemory", "ConstantForce",
    "PrescribedForce",
    "ExactHydrostatic", "MoorDynForce", "MooringForce", "MooringLines", "MooringSystem",
    "MooringTable",
    "MorisonDrag", "Strips", "additional_damping", "profile_strips", "ParkedRotor", "RotorThrust",
    "OperatingRotor", "PIControlledRotor", "RotorTable", "rotor_from_case", "MemberMorison",
    "SlowDriftForce", "LaggedComponent",
]
