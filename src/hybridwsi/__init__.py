"""hybridwsi: hybrid (physics + machine-learning) time-domain solvers of floating bodies in waves.

The package follows the pipeline of the paper "Towards ML-ready hybrid solvers for
wave-structure interaction": generators (BEM/Cummins, SPH, file import) produce a
:mod:`~hybridwsi.history` TimeHistory (an :class:`xarray.Dataset`; third-party files are read
by :mod:`~hybridwsi.importers`), the :mod:`~hybridwsi.diagnostic` regresses the black-box force
on the motion and judges the stability of a force partition, the :mod:`~hybridwsi.surrogate`
learns what is left, and :mod:`~hybridwsi.report` (``hybridwsi reproduce``) writes the paper's
tables and figures. Theory: docs/THEORY.md; data model: docs/DATA_MODEL.md.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("hybridwsi")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0+unknown"

from hybridwsi.errors import InputError, SolverError  # noqa: E402

__all__ = ["__version__", "InputError", "SolverError"]
