"""hybridwsi: hybrid (physics + machine-learning) time-domain solvers of floating bodies in waves.

The package follows the pipeline of the paper "Towards ML-ready hybrid solvers for
wave-structure interaction": generators (BEM/Cummins, SPH, file import) produce a
:mod:`~hybridwsi.history` TimeHistory (an :class:`xarray.Dataset`), the
:mod:`~hybridwsi.diagnostic` regresses the black-box force on the motion and judges the
stability of a force partition, and :mod:`~hybridwsi.report` writes tables and figures.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("hybridwsi")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0+unknown"

from hybridwsi.errors import InputError, SolverError  # noqa: E402

__all__ = ["__version__", "InputError", "SolverError"]
