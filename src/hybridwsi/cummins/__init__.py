"""Time-domain Cummins equation (paper Eq. 9) for any set of DOFs.

    (M + A∞) z̈ + ∫_0^t K(t − τ) ż(τ) dτ + C z = F_exc(t) + Σ_k F_k

Modules, in the order a run uses them:

- :mod:`~hybridwsi.cummins.system` — :class:`CumminsSystem` (M, A∞, C, the radiation state
  space or sampled kernel) assembled from the coefficient Dataset through
  :mod:`hybridwsi.hydro.coefficients` (:func:`build_system`);
- :mod:`~hybridwsi.cummins.forcing` — wave excitation and the time-only force components on
  the time grid;
- :mod:`~hybridwsi.cummins.result` — the solver contract: every integrator is
  ``solve(system, u, z0, v0, dt, *, progress, **options) -> SolverResult`` and returns its
  failure as data (``success``, ``message``);
- :mod:`~hybridwsi.cummins.solvers` — the exact linear state-space/FOH solver, the direct
  convolution (Newmark) reference, and RK4 for state-dependent forces (exact hydrostatics,
  drag, stateful components stepped with ``begin_step``, …), in a registry
  (``INTEGRATORS``, ``integrator_for``);
- :mod:`~hybridwsi.cummins.simulate` — :func:`simulate`, :func:`simulate_batch`, the
  TimeHistory Dataset and :func:`coeffs_hash`.

External forces are :class:`hybridwsi.forces.KnownComponent` objects (``forces=``), the same
objects the diagnostic and the hybrid rollout take.
"""

from hybridwsi.cummins.result import SolverResult
from hybridwsi.cummins.simulate import FORCES, coeffs_hash, simulate, simulate_batch
from hybridwsi.cummins.system import RADIATION, CumminsSystem, build_system

__all__ = ["simulate", "simulate_batch", "build_system", "CumminsSystem", "coeffs_hash",
           "FORCES", "RADIATION", "SolverResult"]
