"""Heave-decay comparison with the Kramer et al. (2021) floating-sphere experiment.

Kramer, M.B. et al., "Highly Accurate Experimental Heave Decay Tests with a Floating Sphere: A
Public Benchmark Dataset for Model Validation of Fluid-Structure Interaction", Energies 14(2):269
(2021), doi:10.3390/en14020269; data in /work/shared/data/kramer2021_sphere_decay (see its
README: heave normalised by the measured drop height, time by Te0 = 0.7561 s).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from hybridwsi.errors import InputError

TE0 = 0.7561
DATA_DIR = Path("/work/shared/data/kramer2021_sphere_decay")


def load_experiment(drop: str = "01D", data_dir: str | Path = DATA_DIR) -> pd.DataFrame:
    """Measured mean heave/H0 against t/Te0 (columns as in the CSV)."""
    path = Path(data_dir) / f"{drop}_CI95_Normalized_every5th.csv"
    if not path.is_file():
        raise InputError(f"Kramer data not found: {path}")
    return pd.read_csv(path)


def crossing_periods(t: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Successive full-period estimates [s]: twice the spacing of zero crossings of z."""
    s = np.sign(z)
    i = np.flatnonzero(s[:-1] * s[1:] < 0)
    tc = t[i] - z[i] * (t[i + 1] - t[i]) / (z[i + 1] - z[i])
    return 2.0 * np.diff(tc)


def compare_decay(hist: xr.Dataset, z0: float, drop: str = "01D", n_periods: float = 5.0,
                  data_dir: str | Path = DATA_DIR) -> dict[str, float]:
    """Period and RMS error of z/H0 over [0, n_periods Te0] against the experiment.

    Returns a dict with the simulated and measured mean period of the first two full cycles
    [s] (from zero crossings), their relative difference, the RMS of the difference of z/H0,
    and the covered time (the comparison is cut to the shorter record).
    """
    exp = load_experiment(drop, data_dir)
    te = exp["t_over_Te0"].to_numpy() * TE0
    ze = exp["x3_over_H0m_mean"].to_numpy()
    t = hist["time"].values
    z = hist["z"].sel(dof="Heave").values / z0
    t_end = min(n_periods * TE0, t[-1])
    sel = (te >= 0) & (te <= t_end)
    if sel.sum() < 10:
        raise InputError("simulation too short to compare with the experiment")
    zs = np.interp(te[sel], t, z)
    rms = float(np.sqrt(np.mean((zs - ze[sel]) ** 2)))
    p_sim = crossing_periods(t[t <= t_end], z[t <= t_end])
    p_exp = crossing_periods(te[sel], ze[sel])
    n = min(2, len(p_sim), len(p_exp))
    out = {"rms_z_over_H0": rms, "t_compared": float(t_end)}
    if n >= 1:
        out.update(period_sim=float(np.mean(p_sim[:n])), period_exp=float(np.mean(p_exp[:n])))
        out["period_rel_err"] = out["period_sim"] / out["period_exp"] - 1.0
    return out
