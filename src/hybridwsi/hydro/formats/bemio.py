"""WEC-Sim BEMIO ``.h5`` → the coefficient Dataset (needs ``h5py``: extra ``hybridwsi[bemio]``).

Layout as WEC-Sim's ``source/functions/BEMIO/writeBEMIOH5.m`` writes it and
``readBEMIOH5.m`` reads it back. MATLAB writes column-major, so h5py sees every array with its
MATLAB dimensions reversed; after ``writeBEMIOH5``'s own ``permute(…, [3 2 1])`` the h5py
indices are the natural ones:

- ``simulation_parameters/{rho, g, w [rad/s], wave_dir [deg], water_depth [m or 'infinite']}``;
- ``body1/hydro_coeffs/added_mass/all`` ``[i, j, ω]`` (i = the body's 6 rows, j = all 6N
  columns) normalised by ρ; ``added_mass/inf_freq`` ``[i, j]`` by ρ;
- ``body1/hydro_coeffs/radiation_damping/all`` ``[i, j, ω]`` by ρω;
- ``body1/hydro_coeffs/excitation/re`` and ``/im`` ``[i, β, ω]`` by ρg;
- ``body1/hydro_coeffs/linear_restoring_stiffness`` ``[i, j]`` by ρg;
- ``body1/properties/{dof_start, disp_vol, cg, cb}``.

Row ``i`` receives the force, column ``j`` moves (BEMIO keeps WAMIT's ``A(I, J, ω)``). BEMIO
stores WAMIT's time convention ``e^{+iωt}`` (``readCAPYTAINE.m`` negates Capytaine's imaginary
parts on the way in), so the excitation is conjugated here. No ULEN: BEMIO is ULEN = 1.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.errors import InputError
from hybridwsi.hydro.formats.common import build, content_hash

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _h5py():
    try:
        import h5py
    except ImportError:
        raise InputError("reading a BEMIO .h5 file needs h5py: pip install 'hybridwsi[bemio]'") \
            from None
    return h5py


def has_h5py() -> bool:
    """True when h5py can be imported."""
    try:
        _h5py()
    except InputError:
        return False
    return True


def is_bemio(path: Path) -> bool:
    """True for an HDF5 file with BEMIO's ``simulation_parameters`` and ``body1`` groups."""
    with open(path, "rb") as f:
        if f.read(8) != HDF5_SIGNATURE:
            return False
    h5py = _h5py()
    try:
        with h5py.File(path, "r") as f:
            return "simulation_parameters" in f and "body1" in f
    except OSError:
        return False


def _get(f, key: str, where: str) -> np.ndarray:
    if key not in f:
        raise InputError(f"{where}: BEMIO file has no '{key}'")
    return np.asarray(f[key][()])


def _depth(f, where: str) -> float:
    raw = _get(f, "simulation_parameters/water_depth", where) \
        if "simulation_parameters/water_depth" in f else np.array(b"infinite")
    flat = raw.reshape(-1)[0] if raw.shape else raw.item()
    if isinstance(flat, (bytes, str)):
        text = flat.decode() if isinstance(flat, bytes) else flat
        if text.strip().lower() in ("infinite", "inf"):
            return math.inf
        raise InputError(f"{where}: water_depth {text!r} is not a number")
    return float(flat)


def read(path: str | Path) -> xr.Dataset:
    """Read body1 of a BEMIO ``.h5`` into a coefficient Dataset (dimensional, SI).

    Returns
    -------
    xarray.Dataset
        All six rigid DOFs; ``added_mass_inf`` from ``inf_freq`` (NaN when absent),
        ``added_mass_zero`` NaN, ``hydrostatic_stiffness``; no ``mass`` (BEMIO stores only the
        displaced volume, kept in ``attrs["disp_vol"]`` [m³]).
    """
    h5py = _h5py()
    path = Path(path)
    where = path.name
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise InputError(f"cannot read {where} as HDF5: not an HDF5 file or corrupt ({exc})") \
            from None
    with f:
        bodies = [k for k in f if k.startswith("body")]
        if bodies != ["body1"]:
            raise InputError(f"{where}: BEMIO file holds bodies {bodies}; exactly one body "
                             f"(body1) is supported")
        rho = float(_get(f, "simulation_parameters/rho", where).reshape(-1)[0])
        g = float(_get(f, "simulation_parameters/g", where).reshape(-1)[0])
        omega = _get(f, "simulation_parameters/w", where).astype(float).reshape(-1)
        beta = np.deg2rad(_get(f, "simulation_parameters/wave_dir", where).astype(float)
                          .reshape(-1))
        depth = _depth(f, where)
        hc = "body1/hydro_coeffs/"
        start = int(_get(f, "body1/properties/dof_start", where).reshape(-1)[0]) \
            if "body1/properties/dof_start" in f else 1
        cols = slice(start - 1, start + 5)  # the body's own 6 rigid columns
        a = _get(f, hc + "added_mass/all", where)
        b = _get(f, hc + "radiation_damping/all", where)
        re, im = _get(f, hc + "excitation/re", where), _get(f, hc + "excitation/im", where)
        c = _get(f, hc + "linear_restoring_stiffness", where)
        inf = hc + "added_mass/inf_freq"
        added_mass_inf = _get(f, inf, where) if inf in f else None
        disp = float(_get(f, "body1/properties/disp_vol", where).reshape(-1)[0]) \
            if "body1/properties/disp_vol" in f else math.nan
    n_w, n_b = omega.size, beta.size
    expect = {"added_mass/all": (a, 3), "radiation_damping/all": (b, 3),
              "excitation/re": (re, 3), "excitation/im": (im, 3)}
    for name, (arr, nd) in expect.items():
        if arr.ndim != nd or arr.shape[0] < 6 or arr.shape[-1] != n_w:
            raise InputError(f"{where}: '{name}' has shape {arr.shape}, expected (6, …, {n_w})")
    if re.shape[1] != n_b or im.shape != re.shape:
        raise InputError(f"{where}: excitation shape {re.shape} does not match "
                         f"{n_b} wave directions")
    if a.shape[1] < start + 5 or b.shape != a.shape or c.ndim != 2 or min(c.shape) < 6:
        raise InputError(f"{where}: added_mass/radiation_damping shapes {a.shape}, {b.shape}")

    def rows_cols(m: np.ndarray) -> np.ndarray:
        return np.asarray(m, dtype=float)[:6, cols]

    added = np.moveaxis(rows_cols(a), -1, 0) * rho
    damping = np.moveaxis(rows_cols(b), -1, 0) * rho * omega[:, None, None]
    exc = np.conj(np.transpose(re[:6] + 1j * im[:6], (2, 1, 0))) * rho * g  # e^{+iωt} → e^{−iωt}
    return build(omega=omega, dofs=RIGID_DOFS, added_mass=added, radiation_damping=damping,
                 excitation=exc, directions=beta,
                 added_mass_inf=None if added_mass_inf is None else rows_cols(added_mass_inf) * rho,
                 added_mass_zero=None, hydrostatic_stiffness=np.asarray(c, float)[:6, :6] * rho * g, mass=None,
                 rho=rho, g=g, water_depth=depth, source=f"WEC-Sim BEMIO {where}",
                 input_hash=content_hash([path], {}), where=where,
                 attrs={"disp_vol": disp})
