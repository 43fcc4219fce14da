"""Synthetic hydrodynamic coefficients with a closed-form radiation kernel (test helper).

The kernel ``K(t) = k0 e^{-σt} cos(νt)`` has exact transforms

    B(ω)      = ∫_0^∞ K cos ωt dt = k0/2 [σ/(σ² + (ω−ν)²) + σ/(σ² + (ω+ν)²)]
    A(ω) − A∞ = −(1/ω) ∫_0^∞ K sin ωt dt
              = −k0/(2ω) [(ω+ν)/(σ² + (ω+ν)²) + (ω−ν)/(σ² + (ω−ν)²)]

so A(ω), B(ω) are exactly Kramers–Kronig consistent. The heave excitation magnitude follows
the deep-water Haskind relation ``|F_e|² = 2 ρ g³ B(ω)/ω³`` with a smooth phase. Numbers are
of the order of the paper's sphere (m = 7.06 kg, A∞ = 3.50 kg, C = 692.2 N/m).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

M, A_INF, C = 7.06, 3.50, 692.2
K0, SIGMA, NU = 100.0, 4.0, 7.0
RHO, G = 1000.0, 9.81


def kernel(t: np.ndarray) -> np.ndarray:
    return K0 * np.exp(-SIGMA * t) * np.cos(NU * t)


def damping(w: np.ndarray) -> np.ndarray:
    s2 = SIGMA**2
    return K0 / 2 * (SIGMA / (s2 + (w - NU) ** 2) + SIGMA / (s2 + (w + NU) ** 2))


def added_mass(w: np.ndarray) -> np.ndarray:
    s2 = SIGMA**2
    return A_INF - K0 / (2 * w) * ((w + NU) / (s2 + (w + NU) ** 2) + (w - NU) / (s2 + (w - NU) ** 2))


def excitation(w: np.ndarray) -> np.ndarray:
    return np.sqrt(2 * RHO * G**3 * damping(w) / w**3) * np.exp(-0.1j * w)


def _mat(v: float) -> xr.DataArray:
    return xr.DataArray([[v]], dims=("radiating_dof", "influenced_dof"))


def coefficients(omega: np.ndarray | None = None) -> xr.Dataset:
    """Coefficient Dataset with the schema of ``hydro.bem.compute`` (1 DOF, Heave)."""
    w = np.linspace(0.1, 40.0, 400) if omega is None else np.asarray(omega, float)
    rd = ("omega", "radiating_dof", "influenced_dof")
    ds = xr.Dataset(
        {
            "added_mass": (rd, added_mass(w)[:, None, None]),
            "radiation_damping": (rd, damping(w)[:, None, None]),
            "excitation_force": (("omega", "wave_direction", "influenced_dof"),
                                 excitation(w)[:, None, None]),
            "added_mass_inf": _mat(A_INF),
            "added_mass_zero": _mat(float(added_mass(np.array([1e-9]))[0])),
            "hydrostatic_stiffness": _mat(C),
            "mass": _mat(M),
        },
        coords={"omega": w, "radiating_dof": ["Heave"], "influenced_dof": ["Heave"],
                "wave_direction": [0.0]},
        attrs={"rho": RHO, "g": G, "water_depth": np.inf, "input_hash": "synthetic-v1"},
    )
    return ds


def irf(t_max: float = 6.0, dt: float = 0.005) -> xr.DataArray:
    """The exact kernel as a DataArray K(time, radiating_dof, influenced_dof)."""
    t = np.arange(0.0, t_max + dt / 2, dt)
    return xr.DataArray(kernel(t)[:, None, None], dims=("time", "radiating_dof", "influenced_dof"),
                        coords={"time": t, "radiating_dof": ["Heave"], "influenced_dof": ["Heave"]})
