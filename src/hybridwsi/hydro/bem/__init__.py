"""Frequency-domain BEM coefficients with Capytaine, cached and resumable.

:func:`compute` returns the coefficient Dataset of ``docs/DATA_MODEL.md``: added mass A(ω),
radiation damping B(ω), excitation force (Froude–Krylov + diffraction), the limits A(∞) and
A(0), the hydrostatic stiffness and the rigid-body mass.

Any :class:`hybridwsi.bodies.Body` (the paper's sphere, a body of revolution from a profile,
a mesh file, a rigid assembly): the body supplies the Capytaine mesh (its symmetries and lid),
the DOF origin (``reference_point``, written to ``attrs``), the rigid-body mass matrix and the
hydrostatic stiffness. The mesh resolution is a panel size [m] (or a panel count) for every
body; the sphere also keeps its ``(n_theta, n_phi)`` resolution. :func:`plan` checks the
inputs and computes the cache keys without solving.

How the run is organised (and why):

- Frequencies are solved in chunks with ``capytaine.BEMSolver.fill_dataset``; after each chunk
  the solved frequencies are merged into a *store* NetCDF (atomic write) keyed by a SHA-256 of
  every input except the frequency list. A run that is interrupted, or a later run with more
  frequencies of the same configuration, solves only the frequencies that are missing.
  The finished result is also written under a key that includes the frequencies, so repeating
  the same call reads one file and solves nothing.
- Cache folder: ``cache_dir``, else ``$HYBRIDWSI_CACHE/bem``, else ``~/.cache/hybridwsi/bem``.
- BLAS is limited to one thread during the solve (threadpoolctl; else set
  ``OPENBLAS_NUM_THREADS=1`` yourself): multi-threaded OpenBLAS makes Capytaine's symmetric
  block products up to ~30x slower (docs/CAPYTAINE_NOTES.md pitfall 3).
- Default ``method="direct"``: it converges faster with the mesh (A(∞) within 0.01 % of the
  analytic hemisphere value at 6400 panels, pitfall 4).
- The ω = 0 and ω = ∞ limits are Capytaine radiation problems at ``omega=0`` and
  ``omega=np.inf``.
- Finite depth (pitfall 5): Capytaine's default Green function returns NaN for small kh. Those
  frequencies are re-solved with ``FinGreen3D`` on the hull *without* lid (FinGreen3D fails on
  panels lying in the free surface; irregular frequencies are far above these low
  frequencies); ``low_kh="drop"`` drops them instead. Frequencies still NaN are dropped with a
  warning and listed in ``attrs["dropped_omega"]``. A(0) is NaN in finite depth when no Green
  function can evaluate it (warned, flagged).
- Quality checks: NaN values and negative diagonal damping raise a ``UserWarning`` and are
  listed in ``attrs["quality_flags"]`` (JSON); never silent.

The package: :mod:`~hybridwsi.hydro.bem.planning` (inputs checked, cache keys),
:mod:`~hybridwsi.hydro.bem.cache` (shipped files, cache folder, resumable store),
:mod:`~hybridwsi.hydro.bem.solve` (Capytaine, workers, the low-kh fix),
:mod:`~hybridwsi.hydro.bem.assembly` (the coefficient Dataset) and
:mod:`~hybridwsi.hydro.bem.run` (:func:`compute`).
"""

from hybridwsi.hydro.bem.assembly import NEG_DAMPING_RTOL
from hybridwsi.hydro.bem.cache import PAPER_COEFFS, default_cache_dir, paper_coefficients
from hybridwsi.hydro.bem.planning import (DEFAULT_PANELS, SINK_RTOL, Plan, hashed_frequencies,
                                          paper_configuration, paper_frequencies, plan,
                                          warn_if_sinks)
from hybridwsi.hydro.bem.run import CHUNK_SIZE, compute
from hybridwsi.hydro.bem.solve import COEFF_VARS, blas_single_thread

__all__ = ["CHUNK_SIZE", "COEFF_VARS", "DEFAULT_PANELS", "NEG_DAMPING_RTOL", "PAPER_COEFFS",
           "SINK_RTOL", "Plan", "blas_single_thread", "compute", "default_cache_dir",
           "hashed_frequencies", "paper_coefficients", "paper_configuration",
           "paper_frequencies", "plan", "warn_if_sinks"]
