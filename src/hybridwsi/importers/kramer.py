"""Kramer et al. (2021) floating-sphere heave decay data: where it is and how to read it.

Kramer, M.B. et al., "Highly Accurate Experimental Heave Decay Tests with a Floating Sphere: A
Public Benchmark Dataset for Model Validation of Fluid-Structure Interaction", Energies 14(2):269
(2021), doi:10.3390/en14020269. A copy of the data ships in ``hybridwsi/data/
kramer2021_sphere_decay`` (see its README: heave normalised by the measured drop height H0,
time by Te0 = 0.7561 s). Formats ``kramer`` (measured mean with its 95 % band,
:func:`read_kramer_decay`) and ``kramer-numerical`` (the blind comparison's codes,
:func:`read_kramer_numerical`).
"""

from __future__ import annotations

import os
import re
from importlib import resources
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.history import TextTable, finalize_import, make_history

#: sphere diameter [m], undamped natural period Te0 [s] and mass [kg] (data README)
KRAMER_DIAMETER = 0.300
KRAMER_TE0 = 0.7561
KRAMER_MASS = 7.056
#: the three drop tests: H0 = 0.1 D, 0.3 D, 0.5 D
KRAMER_DROPS = ("01D", "03D", "05D")
_KRAMER_DIRNAME = "kramer2021_sphere_decay"


def kramer_data_dir() -> Path:
    """Folder holding the Kramer et al. (2021) decay data.

    The environment variable ``HYBRIDWSI_KRAMER_DIR`` when set (another copy of the data);
    otherwise the copy packaged in ``hybridwsi/data/kramer2021_sphere_decay`` (always installed
    with the package).
    """
    env = os.environ.get("HYBRIDWSI_KRAMER_DIR")
    if env:
        path = Path(env)
        if not path.is_dir():
            raise InputError(f"HYBRIDWSI_KRAMER_DIR={env} is not a folder")
        return path
    packaged = Path(str(resources.files("hybridwsi") / "data" / _KRAMER_DIRNAME))
    if packaged.is_dir():
        return packaged
    raise InputError(  # pragma: no cover - the packaged copy ships with hybridwsi
        "Kramer 2021 data not found: set HYBRIDWSI_KRAMER_DIR to the folder holding "
        "01D_CI95_Normalized_every5th.csv"
    )


def _check_drop(drop: str) -> str:
    if drop not in KRAMER_DROPS:
        raise InputError(f"unknown Kramer drop '{drop}' (choose {', '.join(KRAMER_DROPS)})")
    return drop


def kramer_drop_height(drop: str) -> float:
    """Nominal drop height H0 [m] of a drop tag: ``"01D"`` -> 0.1 D = 0.03 m, ``"5D"`` -> 0.15 m."""
    m = re.fullmatch(r"0?([0-9])D", drop)
    if not m:
        raise InputError(f"'{drop}' is not a drop tag like 01D/03D/05D")
    return int(m.group(1)) / 10 * KRAMER_DIAMETER


def kramer_decay_file(drop: str) -> Path:
    """Measured-mean file of a drop test (``01D_CI95_Normalized_every5th.csv``)."""
    path = kramer_data_dir() / f"{_check_drop(drop)}_CI95_Normalized_every5th.csv"
    if not path.is_file():
        raise InputError(f"Kramer data not found: {path}")
    return path


def kramer_numerical_files(drop: str) -> dict[str, Path]:
    """``{code: path}`` of the blind comparison's published results for one drop test."""
    folder = kramer_data_dir() / "numerical"
    return {p.name.split("_")[0]: p for p in sorted(folder.glob(f"*_{_check_drop(drop)}.csv"))}


def read_kramer_drop(drop: str, normalised: bool = False) -> xr.Dataset:
    """Measured heave decay of one drop test: :func:`read_kramer_decay` of its file.

    ``normalised=True`` keeps heave as z/H0 (drop height 1), the scale of the data files.
    """
    return read_kramer_decay(kramer_decay_file(drop), drop_height=1.0 if normalised else None)


def _kramer_drop_height(path: Path, drop_height: float | None) -> float:
    """Drop height [m]: given, or from the ``01D``/``03D``/``05D`` tag in the file name."""
    if drop_height is not None:
        if not np.isfinite(drop_height) or drop_height <= 0:
            raise InputError(f"drop height must be a positive length in m, got {drop_height}")
        return float(drop_height)
    m = re.search(r"(?<![0-9])0?([0-9])D(?![a-zA-Z])", path.stem)
    if not m:
        raise InputError(
            f"cannot tell the drop height from the name {path.name} (expected 01D/03D/05D); "
            "pass drop_height (--drop-height) in m"
        )
    return kramer_drop_height(m.group(0))


def read_kramer_decay(
    path: str | os.PathLike,
    drop_height: float | None = None,
    te0: float = KRAMER_TE0,
    *,
    mass: float | None = KRAMER_MASS,
) -> xr.Dataset:
    """Measured heave decay of Kramer et al. (2021) as a TimeHistory.

    Parameters
    ----------
    path : path-like
        ``01D_CI95_Normalized_every5th.csv`` (or 03D/05D), columns ``t_over_Te0,
        x3_over_H0m_mean, ci95_lower, ci95_upper[, t_s_derived]``.
    drop_height : float, optional
        Drop height H0 [m] that un-normalises x3; default from the file name: 01D -> 0.1 D =
        0.03 m, 03D -> 0.09 m, 05D -> 0.15 m (D = 0.300 m).
    te0 : float
        Natural period Te0 [s] that un-normalises time (0.7561 s, see the data README).
    mass : float, optional
        Sphere mass [kg] stored in the history (7.056 kg); None to leave it out.

    Returns
    -------
    xarray.Dataset
        ``time`` = t/Te0 x te0 [s] (t = 0 at release; the held phase t < 0 is kept),
        ``z`` = x3/H0 x drop_height [m], and ``ci95_lower``/``ci95_upper`` [m] as extra
        ``(time, dof)`` variables. No velocity, acceleration or force is measured.
    """
    table = TextTable(path)
    h0 = _kramer_drop_height(table.path, drop_height)
    if not np.isfinite(te0) or te0 <= 0:
        raise InputError(f"te0 must be a positive period in s, got {te0}")
    t = table.numeric(table.require("t_over_Te0")) * te0
    table.check_time(t)
    z = table.numeric(table.require("x3_over_H0m_mean")) * h0
    ds = make_history(
        t, z, dof=["Heave"], mass=mass, source=f"kramer2021:{table.path.name}",
        inputs={"file": str(table.path), "drop_height_m": h0, "te0_s": te0},
        check=False,
    )
    for name in ("ci95_lower", "ci95_upper"):
        col = table.find(name)
        if col is not None:
            ds[name] = (("time", "dof"), table.numeric(col)[:, None] * h0,
                        {"units": "m", "description": "95 % confidence bound of the mean z"})
    ds["z"].attrs["description"] = "heave from equilibrium, positive up (mean of 4 repetitions)"
    ds.attrs["reference"] = "Kramer et al. (2021), Energies 14(2):269, doi:10.3390/en14020269"
    return finalize_import(ds)


def read_kramer_numerical(
    path: str | os.PathLike,
    *,
    resample: bool = False,
    require_uniform: bool = True,
    mass: float | None = KRAMER_MASS,
) -> xr.Dataset:
    """One of the blind-comparison results of Kramer et al. (2021) as a TimeHistory.

    Parameters
    ----------
    path : path-like
        ``numerical/<CODE>_<DROP>.csv`` with columns ``t_s,x3_m`` (time [s], heave [m]).
    resample : bool
        Several codes (LPF1-3, the RANS ones) were saved with an adaptive step, so their kept
        rows are only approximately 0.01 s apart. ``resample=True`` interpolates them (cubic)
        onto the median step.
    require_uniform : bool
        With False, an irregular file is returned as sampled (for plotting/comparison).
        Otherwise (the default) an irregular file raises :class:`InputError`, because the
        diagnostic's derivative estimation needs a uniform step.
    mass : float, optional
        Sphere mass [kg] stored in the history (7.056 kg); None to leave it out.
    """
    table = TextTable(path)
    t = table.numeric(table.require("t_s"), "time")
    table.check_time(t)
    z = table.numeric(table.require("x3_m"), "length")
    code = table.path.stem
    ds = make_history(
        t, z, dof=["Heave"], mass=mass, source=f"kramer2021-numerical:{code}",
        inputs={"file": str(table.path), "code": code.split("_")[0]}, check=False,
    )
    ds["z"].attrs["description"] = "heave x3 from equilibrium as computed by the code"
    return finalize_import(ds, resample_to_uniform=resample, require_uniform=require_uniform)
