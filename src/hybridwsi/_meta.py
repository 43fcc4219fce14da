"""Versions that result files carry (one place for ``hybridwsi_version`` and friends).

Every file hybridwsi writes (histories, coefficient sets, sweeps, reports, networks) records
the versions that made it, so a reader can tell which code produced which number. Modules ask
this one for them instead of each reading :mod:`importlib.metadata`.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _dist_version

from hybridwsi import __version__

#: version string recorded for a package that is not installed
NOT_INSTALLED = "unknown"


def package_version(name: str) -> str:
    """Installed version of the distribution ``name`` (e.g. ``"capytaine"``), or ``"unknown"``."""
    try:
        return _dist_version(name)
    except PackageNotFoundError:
        return NOT_INSTALLED


def version() -> str:
    """hybridwsi's own version (``hybridwsi.__version__``; ``0.0.0+unknown`` from a bare tree)."""
    return __version__


def provenance(*packages: str) -> dict[str, str]:
    """``{"hybridwsi": …, package: …}``: the versions a result file carries.

    Parameters
    ----------
    *packages : str
        Further distributions whose versions matter for the result (``"capytaine"``,
        ``"torch"``, ``"pysph"``…).

    Returns
    -------
    dict of str to str
        Installed versions from the package metadata, ``"unknown"`` for a missing one. The
        values are the ones the BEM input hash has always used (same lookup, same fallback),
        so switching a module to this function does not change a hash.
    """
    return {name: package_version(name) for name in ("hybridwsi", *packages)}
