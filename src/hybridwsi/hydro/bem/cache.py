"""Where BEM results are kept: the shipped coefficient files (matched by input hash), the
cache folder, and the resumable store of solved frequencies (read, merged, what is missing)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.files import cache_dir, read_netcdf

#: shipped result of ``compute(**paper_configuration())`` (see data/README.md)
PAPER_COEFFS = Path(__file__).resolve().parents[2] / "data" / "bem_paper_sphere.nc"


def paper_coefficients() -> xr.Dataset:
    """The paper configuration's coefficients as shipped with the package (no BEM run).

    Equal to ``compute(**paper_configuration())``; recompute with ``hybridwsi bem``.
    """
    if not PAPER_COEFFS.is_file():
        raise InputError(f"{PAPER_COEFFS} is missing; run `hybridwsi bem --out {PAPER_COEFFS}`")
    return read_netcdf(PAPER_COEFFS)


def shipped(input_hash: str) -> xr.Dataset | None:
    """A coefficient file shipped in ``hybridwsi/data/bem_*.nc`` made with exactly these inputs
    (the hash of a whole plan or of one of its finite-depth/deep-water parts).

    The paper's configurations take minutes to solve; shipping their results (with the
    command that made them, data/README.md) makes ``hybridwsi reproduce`` fast on a fresh
    machine. A file is used only when its ``input_hash`` (all inputs and versions) matches.
    """
    for path in sorted(PAPER_COEFFS.parent.glob("bem_*.nc")):
        try:
            with xr.open_dataset(path) as f:
                if f.attrs.get("input_hash") != input_hash:
                    continue
        except (OSError, ValueError):
            continue
        return read_netcdf(path)
    return None


def default_cache_dir() -> Path:
    """``$HYBRIDWSI_CACHE/bem`` if that variable is set, else ``~/.cache/hybridwsi/bem``."""
    return cache_dir("bem")


def read_cache(path: Path) -> xr.Dataset | None:
    """A cache file, or None (with a warning) when it cannot be read: it is then recomputed."""
    try:
        return read_netcdf(path)
    except InputError as exc:
        warnings.warn(f"ignoring unreadable BEM cache file ({exc})", stacklevel=3)
        return None


def missing(wanted: np.ndarray, store: xr.Dataset | None) -> np.ndarray:
    """Frequencies (incl. 0/inf) of ``wanted`` not yet in ``store``."""
    if store is None:
        return wanted
    done = np.asarray(store["omega"].values, dtype=float)
    return np.array([w for w in wanted if not np.any(same_frequency(done, w))], dtype=float)


def same_frequency(a: np.ndarray, w: float) -> np.ndarray:
    """Where the frequencies ``a`` [rad/s] equal ``w`` (to 1e-12 relative; 0 and inf exactly)."""
    return (a == w) | (np.isfinite(a) & np.isclose(a, w, rtol=1e-12, atol=0.0))


def merge_store(store: xr.Dataset, part: xr.Dataset) -> xr.Dataset:
    """``store`` with the frequencies of ``part`` added (replacing equal ones), sorted."""
    keep = ~np.isin(store["omega"].values, part["omega"].values)
    return xr.concat([store.isel(omega=keep), part], dim="omega").sortby("omega")
