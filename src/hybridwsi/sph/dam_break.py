"""2D dam-break validation against Martin & Moyce (1952).

Reference data: J. C. Martin and W. J. Moyce, "An experimental study of the collapse of liquid
columns on a rigid horizontal plane", Phil. Trans. R. Soc. Lond. A 244 (1952) 312-324,
doi:10.1098/rsta.1952.0007, Figure 3, column of height 2a on a base a (n^2 = 2), a = 2.25 in.
The table (front position Z = x/a against T = t sqrt(2g/a)) is the one PySPH ships in
``pysph/examples/db_exp_data.py`` (``mm_data_2``), copied here so that the comparison does not
need PySPH's examples.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError

# T = t sqrt(2 g / a), Z = x_front / a; Martin & Moyce (1952) Fig. 3, n^2 = 2, a = 2.25 in
MARTIN_MOYCE_N2_A225 = np.array([
    [0.832, 1.217], [1.219, 1.474], [1.997, 2.292], [2.547, 2.995], [3.345, 4.134],
    [4.034, 4.944], [4.418, 5.881], [5.091, 6.980], [5.685, 7.945], [6.306, 8.966],
    [6.822, 9.986], [7.439, 10.963], [8.031, 11.977], [8.633, 13.005], [9.237, 13.970],
])


def front_vs_experiment(hist: xr.Dataset, a: float, g: float = 9.81,
                        z_max: float = 5.5) -> dict[str, np.ndarray | float]:
    """Compare the simulated surge front with Martin & Moyce.

    Parameters
    ----------
    hist : Dataset
        History of the ``dam_break`` case (variable ``front`` [m]).
    a : float
        Column base width [m].
    g : float
        Gravity [m/s^2].
    z_max : float
        Only experimental points with Z below this (the tank is 6a long) are compared.

    Returns
    -------
    dict with ``T``, ``Z_exp``, ``Z_sph`` at the experimental times and ``max_rel_err``.
    """
    if "front" not in hist:
        raise InputError("history has no 'front' variable; run the dam_break case")
    T_sim = hist["time"].values * math.sqrt(2 * g / a)
    Z_sim = hist["front"].values / a
    exp = MARTIN_MOYCE_N2_A225[MARTIN_MOYCE_N2_A225[:, 1] < z_max]
    exp = exp[exp[:, 0] <= T_sim[-1]]
    if len(exp) == 0:
        raise InputError("the run is too short to reach the first experimental point")
    Z_at = np.interp(exp[:, 0], T_sim, Z_sim)
    rel = np.abs(Z_at - exp[:, 1]) / exp[:, 1]
    return {"T": exp[:, 0], "Z_exp": exp[:, 1], "Z_sph": Z_at, "rel_err": rel,
            "max_rel_err": float(rel.max())}
