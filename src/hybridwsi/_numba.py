"""The optional Numba accelerator, imported in one place: ``numba`` (None without it) and
``HAVE_NUMBA``. Compiled paths (``forces._compiled``, ``cummins.compiled``, ``surrogate.fast``)
check the flag and keep a NumPy path for when it is False."""

try:  # optional accelerator (a core dependency, but the code runs without it)
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None
    HAVE_NUMBA = False

__all__ = ["HAVE_NUMBA", "numba"]
