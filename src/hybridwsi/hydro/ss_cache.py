"""Fitted radiation state spaces kept by content: the last few in memory, every one on disk.

A study simulates one body many times (a decay per DOF, an RAO per frequency, every command of
a case), and the radiation kernel and its state-space fit cost 0.3-3 s each time. The key is
the coefficients' content (every variable's name, dims, dtype and bytes), the fit's options
and the source of the code that fits (this package's ``hydro/irf.py``, ``hydro/statespace.py``
and the caller's module), so an edited fit never reads an old model. On disk:
``$HYBRIDWSI_CACHE/radiation_ss/<key>.npz`` (:func:`hybridwsi.files.cache_dir`), written
atomically; an unreadable entry is fitted again, an unwritable folder only costs the refit.
The fit's warnings are kept with the model and repeated on every use.
"""

from __future__ import annotations

import copy
import functools
import hashlib
import json
import warnings
import zipfile
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.files import atomic_write, cache_dir
from hybridwsi.hydro.statespace import RadiationSS

#: models kept in memory (least recently used dropped first)
MEMORY_SIZE = 8
#: warning categories a disk entry may carry (the fits warn with these)
_CATEGORIES = {c.__name__: c for c in (UserWarning, RuntimeWarning)}
_SCALARS = ("radiating_dof", "influenced_dof", "fit_error", "n_reflected", "converged",
            "dt_fit", "low_frequency", "passivity_min")

_memory: OrderedDict[str, tuple[RadiationSS, list[tuple[str, str]]]] = OrderedDict()


def cached_radiation_ss(coeffs: xr.Dataset, options: Any,
                        fit: Callable[[], RadiationSS]) -> RadiationSS:
    """``fit()`` (the radiation state space of ``coeffs`` with ``options``), or its kept copy.

    ``options`` must hold everything ``fit`` reads besides ``coeffs`` (DOFs, kernel length,
    tolerance, step ...): it enters the key with its ``repr``.
    """
    digest = content_key(coeffs, options, fit.__code__.co_filename)
    hit = _memory.get(digest) or _read(digest)
    if hit is None:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ss = fit()
        hit = (ss, [(w.category.__name__, str(w.message)) for w in caught])
        if all(name in _CATEGORIES for name, _ in hit[1]):
            _write(digest, hit)
    _memory[digest] = hit
    _memory.move_to_end(digest)
    while len(_memory) > MEMORY_SIZE:
        _memory.popitem(last=False)
    for name, message in hit[1]:
        warnings.warn(message, _CATEGORIES.get(name, UserWarning), stacklevel=3)
    return copy.deepcopy(hit[0])


def content_key(coeffs: xr.Dataset, options: Any, caller: str) -> str:
    """SHA-256 of the coefficients' content, ``options`` and the fitting code's source."""
    key = hashlib.sha256(repr(options).encode())
    key.update(_source_digest(caller).encode())
    for name in sorted(coeffs.variables, key=str):
        v = coeffs.variables[name]
        key.update(repr((name, v.dims, v.dtype.str, v.shape)).encode())
        key.update(np.ascontiguousarray(v.values).tobytes() if v.dtype != object
                   else repr(v.values.tolist()).encode())
    return key.hexdigest()


@functools.cache
def _source_digest(caller: str) -> str:
    here = Path(__file__).parent
    files = (here / "irf.py", here / "statespace.py", Path(caller))
    return hashlib.sha256(b"".join(f.read_bytes() for f in files)).hexdigest()


def _path(digest: str) -> Path:
    return cache_dir("radiation_ss") / f"{digest}.npz"


def _read(digest: str) -> tuple[RadiationSS, list[tuple[str, str]]] | None:
    """The disk entry, or None when there is none or it cannot be read (it is refitted)."""
    try:  # a missing, unreadable or corrupt entry (or folder) is fitted again
        with np.load(_path(digest), allow_pickle=False) as f:
            meta = json.loads(str(f["meta"]))
            ss = RadiationSS(*(np.array(f[k]) for k in "ABCD"),
                             **{k: meta[k] for k in _SCALARS})
        return ss, [tuple(w) for w in meta["warnings"]]
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile):
        return None


def _write(digest: str, hit: tuple[RadiationSS, list[tuple[str, str]]]) -> None:
    ss, caught = hit
    meta = {**{k: getattr(ss, k) for k in _SCALARS}, "warnings": caught}

    def writer(tmp: str) -> None:
        with open(tmp, "wb") as fh:
            np.savez(fh, A=ss.A, B=ss.B, C=ss.C, D=ss.D, meta=np.array(json.dumps(meta)))

    try:
        atomic_write(_path(digest), writer)
    except OSError:  # a read-only cache folder: the model is fitted again next time
        pass
