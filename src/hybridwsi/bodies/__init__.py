"""Floating bodies: geometry, mass properties, hydrostatics and Capytaine meshes.

One interface, :class:`Body` (:mod:`hybridwsi.bodies.base`: frame, DOF origin and sign
conventions), used by the BEM (:func:`hybridwsi.hydro.bem.compute`), the Cummins solver and
the diagnostic. Implementations:

- :class:`FloatingSphere` — the paper's sphere (:mod:`~hybridwsi.bodies.sphere`);
- :class:`AxisymmetricBody` — any body of revolution from an (r, z) profile
  (:mod:`~hybridwsi.bodies.axisymmetric`);
- :class:`MeshBody` — any mesh file Capytaine reads, with given mass properties
  (:mod:`~hybridwsi.bodies.mesh`);
- :class:`RigidAssembly` — a hull plus :class:`MassItem` s (:mod:`~hybridwsi.bodies.assembly`);
- :class:`ColumnsBody` — vertical columns (panel model) and slender :class:`Member` s (strip
  theory), e.g. a semi-submersible (:mod:`~hybridwsi.bodies.columns`).

:func:`body_from_dict` rebuilds any of them from ``body.to_dict()``.
"""

from hybridwsi.bodies.assembly import MassItem, RigidAssembly
from hybridwsi.bodies.axisymmetric import AxisymmetricBody
from hybridwsi.bodies.base import Body, WaterplaneMoments, body_from_dict
from hybridwsi.bodies.columns import ColumnsBody
from hybridwsi.bodies.members import Member, MemberElements, member_elements, point_jacobians
from hybridwsi.bodies.mesh import MeshBody
from hybridwsi.bodies.sphere import FloatingSphere, cap_volume
from hybridwsi.dofs import RIGID_DOFS, check_dofs

__all__ = ["RIGID_DOFS", "AxisymmetricBody", "Body", "ColumnsBody", "FloatingSphere", "MassItem",
           "Member", "MemberElements", "MeshBody", "RigidAssembly", "WaterplaneMoments",
           "body_from_dict", "cap_volume", "check_dofs", "member_elements", "point_jacobians"]
