"""Heave-decay comparison of SPH runs with the Kramer et al. (2021) floating-sphere experiment.

The experiment is read through :mod:`hybridwsi.importers.kramer` (the copy shipped with the
package, or ``HYBRIDWSI_KRAMER_DIR``); periods come from the package's one crossing analysis,
:func:`hybridwsi.history.crossing_periods`, taken about the run's own equilibrium.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import xarray as xr

from hybridwsi.bodies import cap_volume
from hybridwsi.errors import InputError
from hybridwsi.history import crossing_periods
from hybridwsi.importers.kramer import KRAMER_TE0, read_kramer_drop

TE0 = KRAMER_TE0

__all__ = ["TE0", "compare_decay", "equilibrium_shift", "first_extrema", "grid_convergence",
           "load_experiment"]


def load_experiment(drop: str = "01D") -> pd.DataFrame:
    """Measured mean heave/H0 against t/Te0 of one drop test, as a table.

    Columns ``t_over_Te0``, ``x3_over_H0m_mean``, ``ci95_lower``, ``ci95_upper`` (the names
    of the data files), read by :func:`hybridwsi.importers.kramer.read_kramer_drop`.
    """
    exp = read_kramer_drop(drop, normalised=True)
    return pd.DataFrame({
        "t_over_Te0": exp["time"].values / TE0,
        "x3_over_H0m_mean": exp["z"].values[:, 0],
        "ci95_lower": exp["ci95_lower"].values[:, 0],
        "ci95_upper": exp["ci95_upper"].values[:, 0],
    })


def equilibrium_shift(z0: float, radius: float, tank_area: float) -> float:
    """Rise [m] of the heave equilibrium of a sphere released z0 [m] above its half-submerged
    equilibrium in a closed tank of still-water area ``tank_area`` [m^2] (whole tank).

    The sphere's immersed volume grows from the cap of height R - z0 to (2/3) pi R^3 as it
    settles; that water raises the free surface and the sphere floats up with it. Small in the
    wave basin (0.4 % of z0 there), 1-3 % of z0 in the SPH tanks.
    """
    if not (0.0 <= z0 < radius) or tank_area <= math.pi * radius ** 2:
        raise InputError(f"need 0 <= z0 < R and a tank wider than the sphere (z0 = {z0}, "
                         f"R = {radius}, area = {tank_area})")

    dv = cap_volume(radius, radius) - cap_volume(radius - z0, radius)
    return dv / (tank_area - math.pi * radius ** 2)


def _sim_equilibrium(hist: xr.Dataset, z0: float) -> float:
    """Equilibrium shift [m] of an SPH decay3d history from its recorded inputs (else 0)."""
    try:
        inp = json.loads(hist.attrs.get("inputs", "{}"))
    except (TypeError, ValueError):
        return 0.0
    if inp.get("case") != "decay3d":
        return 0.0
    # quarter domain: the whole tank is (2 half_width)^2
    return equilibrium_shift(z0, 0.5 * float(inp["diameter"]), 4.0 * float(inp["half_width"]) ** 2)


def first_extrema(t: np.ndarray, z: np.ndarray) -> tuple[float, float, float, float]:
    """Time [s] and value of the first trough after release, then of the next crest."""
    i1 = int(np.argmax(np.diff(z) > 0)) if np.any(np.diff(z) > 0) else len(z) - 1
    after = np.flatnonzero(np.diff(z[i1:]) < 0)
    i2 = i1 + (int(after[0]) if len(after) else len(z) - 1 - i1)
    return float(t[i1]), float(z[i1]), float(t[i2]), float(z[i2])


def compare_decay(hist: xr.Dataset, z0: float, drop: str = "01D", n_periods: float = 5.0,
                  z_eq: float | None = None) -> dict[str, float]:
    """Period, first extrema and RMS error of z/H0 over [0, n_periods Te0] against the experiment.

    Returns a dict with the simulated and measured mean period of the first two full cycles
    [s] (from crossings of the equilibrium; ``z_eq`` [m] is the simulated one, by default
    :func:`equilibrium_shift` for a decay3d history), their relative difference, the first
    trough and crest (time [s], z/H0) of both, the period from them (2 x trough-to-crest time,
    robust to the mean level and to heavy damping), the RMS of the difference of z/H0 and the
    covered time (the comparison is cut to the shorter record).
    """
    exp = read_kramer_drop(drop, normalised=True)
    te = exp["time"].values
    ze = exp["z"].values[:, 0]
    t = hist["time"].values
    z = hist["z"].sel(dof="Heave").values / z0
    t_end = min(n_periods * TE0, t[-1])
    sel = (te >= 0) & (te <= t_end)
    if sel.sum() < 10:
        raise InputError("simulation too short to compare with the experiment")
    zs = np.interp(te[sel], t, z)
    rms = float(np.sqrt(np.mean((zs - ze[sel]) ** 2)))
    zq = (_sim_equilibrium(hist, z0) if z_eq is None else z_eq) / z0
    p_sim = crossing_periods(t[t <= t_end], z[t <= t_end], zq)
    p_exp = crossing_periods(te[sel], ze[sel])
    n = min(2, len(p_sim), len(p_exp))
    out = {"rms_z_over_H0": rms, "t_compared": float(t_end), "z_eq_over_H0": zq}
    for name, (tt, zz) in {"sim": (t[t <= t_end], z[t <= t_end]),
                           "exp": (te[sel], ze[sel])}.items():
        t1, z1, t2, z2 = first_extrema(tt, zz)
        out.update({f"trough_t_{name}": t1, f"trough_{name}": z1, f"crest_t_{name}": t2,
                    f"crest_{name}": z2, f"period_extrema_{name}": 2.0 * (t2 - t1)})
    out["period_extrema_rel_err"] = out["period_extrema_sim"] / out["period_extrema_exp"] - 1.0
    if n >= 1:
        out.update(period_sim=float(np.mean(p_sim[:n])), period_exp=float(np.mean(p_exp[:n])))
        out["period_rel_err"] = out["period_sim"] / out["period_exp"] - 1.0
    return out


def grid_convergence(values: tuple[float, float, float], spacings: tuple[float, float, float],
                     safety: float = 1.25, iterations: int = 50) -> dict[str, float | bool]:
    """Observed order, Richardson extrapolation and grid convergence index of a quantity
    computed at three particle spacings (Roache's GCI in the form of Celik et al. 2008, J.
    Fluids Eng. 130:078001, which allows unequal refinement ratios).

    Parameters
    ----------
    values : (f1, f2, f3)
        The quantity on the finest, middle and coarsest spacing (any unit).
    spacings : (h1, h2, h3)
        The spacings [m], h1 < h2 < h3.
    safety : float
        Safety factor of the GCI (1.25 for three grids).

    Returns
    -------
    dict
        ``order`` p, ``extrapolated`` f at h = 0 (unit of f), ``gci_fine`` (relative error
        band of f1, [-]) and ``monotone`` (0 < (f2 - f1)/(f3 - f2) < 1: the three are in the
        asymptotic range only then; otherwise the numbers are reported, not trusted).
    """
    f1, f2, f3 = (float(v) for v in values)
    h1, h2, h3 = (float(h) for h in spacings)
    if not 0.0 < h1 < h2 < h3:
        raise InputError(f"spacings must be increasing and positive, got {spacings}")
    r21, r32 = h2 / h1, h3 / h2
    e21, e32 = f2 - f1, f3 - f2
    if e21 == 0.0 or e32 == 0.0:
        return {"order": float("nan"), "extrapolated": f1, "gci_fine": 0.0,
                "monotone": False}
    sgn = math.copysign(1.0, e32 / e21)
    p = abs(math.log(abs(e32 / e21))) / math.log(r21)
    for _ in range(iterations):  # fixed point of Celik's Eq. (3)
        q = math.log((r21 ** p - sgn) / (r32 ** p - sgn)) if p > 0 else 0.0
        p_new = abs(math.log(abs(e32 / e21)) + q) / math.log(r21)
        if abs(p_new - p) < 1e-12:
            break
        p = p_new
    ext = (r21 ** p * f1 - f2) / (r21 ** p - 1.0)
    gci = safety * abs(e21 / f1) / (r21 ** p - 1.0)
    return {"order": p, "extrapolated": ext, "gci_fine": gci,
            "monotone": bool(0.0 < e21 / e32 < 1.0)}
