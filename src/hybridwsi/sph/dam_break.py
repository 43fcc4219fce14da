"""2D dam-break validation against Martin & Moyce (1952).

Reference data: J. C. Martin and W. J. Moyce, "An experimental study of the collapse of liquid
columns on a rigid horizontal plane", Phil. Trans. R. Soc. Lond. A 244 (1952) 312-324,
doi:10.1098/rsta.1952.0007, Figure 3, column of height 2a on a base a (n^2 = 2), a = 2.25 in.
The table (front position Z = x/a against T = t sqrt(2g/a)) is the one PySPH ships in
``pysph/examples/db_exp_data.py`` (``mm_data_2``), copied here so that the comparison does not
need PySPH's examples.

Early times: particle-method fronts lead the experiments at T < ~1.5 (the gate is not removed
instantaneously; the wet floor and the real fluid's friction slow the tip). Koshizuka & Oka
(1996) report their own MPS front ahead of their own experiment by 7 % at T = 0.77 and 13 % at
T = 1.15 (tables below, from PySPH's ``db_exp_data``), the same sign and size as ours. The
validation therefore quotes the error at every experimental point, and separately for T >= 1.5,
and compares with the MPS computation as an independent numerical reference.
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

# Koshizuka & Oka (1996), Nucl. Sci. Eng. 123:421, n^2 = 2 (a = 0.146 m): experiment and their
# MPS computation, same (T, Z) scaling; PySPH's ``ko_data`` and ``ko_mps_data``
KOSHIZUKA_OKA_EXP = np.array([
    [0.0, 1.000], [0.381, 1.111], [0.769, 1.252], [1.153, 1.505], [1.537, 1.892],
    [1.935, 2.241], [2.323, 2.615], [2.719, 3.003], [3.096, 3.624],
])
KOSHIZUKA_OKA_MPS = np.array([
    [0.000, 1.002], [0.227, 1.019], [0.416, 1.091], [0.591, 1.205], [0.778, 1.351],
    [0.958, 1.512], [1.095, 1.637], [1.226, 1.771], [1.381, 1.931], [1.536, 2.100],
    [1.684, 2.268], [1.858, 2.480], [2.043, 2.707], [2.278, 3.004], [2.451, 3.251],
    [2.604, 3.481], [2.752, 3.700], [2.943, 3.997],
])


def front_vs_experiment(hist: xr.Dataset, a: float, g: float = 9.81,
                        z_max: float = 5.5, data: np.ndarray | None = None,
                        ) -> dict[str, np.ndarray | float]:
    """Compare the simulated surge front with Martin & Moyce (or another (T, Z) table).

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
    data : array (n, 2), optional
        Reference (T, Z) points; default :data:`MARTIN_MOYCE_N2_A225`. Points at T = 0 are
        skipped (Z = 1 there by construction).

    Returns
    -------
    dict with ``T``, ``Z_exp``, ``Z_sph`` at the experimental times and ``max_rel_err``.
    """
    if "front" not in hist:
        raise InputError("history has no 'front' variable; run the dam_break case")
    T_sim = hist["time"].values * math.sqrt(2 * g / a)
    Z_sim = hist["front"].values / a
    ref = MARTIN_MOYCE_N2_A225 if data is None else np.asarray(data, dtype=float)
    exp = ref[(ref[:, 1] < z_max) & (ref[:, 0] > 0)]
    exp = exp[exp[:, 0] <= T_sim[-1]]
    if len(exp) == 0:
        raise InputError("the run is too short to reach the first experimental point")
    Z_at = np.interp(exp[:, 0], T_sim, Z_sim)
    rel = np.abs(Z_at - exp[:, 1]) / exp[:, 1]
    return {"T": exp[:, 0], "Z_exp": exp[:, 1], "Z_sph": Z_at, "rel_err": rel,
            "max_rel_err": float(rel.max())}
