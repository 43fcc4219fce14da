"""Structured-residual variants on the Kramer decays: capacity and leave-one-out (issue 14).

What limits the structured hybrid (``hybridwsi.surrogate.kramer``)? Two measurements:

- *capacity*: each variant fitted (output error, as the report) on the 0.3D drop itself — a
  diagnostic of the model class, never used to choose the shipped model: if a class cannot
  reach 0.006 at 0.3D when it is fitted there, no honest fit of it will;
- *leave one out*: fitted on two drops, scored on the third (as the report).

Variants: V0 the shipped ``−(a₁z + a₂z²) z̈ − b₁ż − b₂|ż|ż − k₁z − k₃z³`` + release lead;
V1 Capytaine's A∞(z) (physics, Lagrangian form ``M(z) z̈ + ½ M'(z) ż²``, the LPF3 class) with
b₁, b₂, k₁, k₃; V2 A∞(z) with all six terms; V3 A∞(z) with b₁, b₂, k₁.

Run: ``PYTHONPATH=src OMP_NUM_THREADS=1 python scripts/kramer_structure_variants.py``
(about 5 min on one loaded core; the A∞(z) BEM runs are cached).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridwsi.cli import run_script
from hybridwsi.hydro import bem, coefficients
from hybridwsi.importers.kramer import read_kramer_drop
from hybridwsi.surrogate import kramer as kh
from hybridwsi.surrogate import structured as st
from hybridwsi.surrogate.kramer import KramerSetup

#: heaves [m] at which A∞(z) is computed (the drops reach +0.15 m, the troughs −0.13 m) and
#: the BEM resolution there (400 panels: A∞(0) within 0.6 % of the 6400-panel value)
ADDED_MASS_HEAVES = (0.14, 0.12, 0.09, 0.06, 0.03, 0.0, -0.03, -0.06, -0.09, -0.12, -0.14)
ADDED_MASS_PANELS = 400


@dataclass(frozen=True)
class AddedMassTable:
    """Heave A∞ of the sphere as a function of its heave, from Capytaine (physics, not fitted).

    Attributes
    ----------
    z : ndarray (n,)
        Heave of the sphere from its equilibrium [m], increasing.
    a_inf : ndarray (n,)
        Infinite-frequency heave added mass at that heave [kg], scaled so that A∞(0) equals
        the Cummins model's A∞ (the coarse table then only carries the *change* with z).
    n_panels : int
        Hull panels of the BEM runs.
    """

    z: np.ndarray
    a_inf: np.ndarray
    n_panels: int

    def evaluate(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A∞(z) [kg] and dA∞/dz [kg/m] by a natural cubic spline through the table."""
        from scipy.interpolate import CubicSpline

        spline = self.__dict__.get("_spline")
        if spline is None:
            spline = CubicSpline(self.z, self.a_inf, bc_type="natural", extrapolate=True)
            object.__setattr__(self, "_spline", spline)
        return spline(z), spline(z, 1)

    def to_dict(self) -> dict[str, Any]:
        return {"z_m": self.z.tolist(), "a_inf_kg": self.a_inf.tolist(),
                "n_panels": self.n_panels}


def added_mass_table(setup: KramerSetup, heaves: Sequence[float] = ADDED_MASS_HEAVES,
                     n_panels: int = ADDED_MASS_PANELS, progress: bool = False
                     ) -> AddedMassTable:
    """A∞ of the Kramer sphere floated at each heave ``z`` (draft R − z) by Capytaine [kg].

    Each position is the same body with its equilibrium draft moved (the free surface stays
    at z = 0; ω → ∞ so the free surface is φ = 0 and the depth does not matter: deep water).
    Cached by :func:`hybridwsi.hydro.bem.compute` (about 2 s per position at 400 panels).
    """

    z = np.asarray(sorted(heaves), dtype=float)
    values = []
    for zi in z:
        body = dataclasses.replace(setup.body, draft=float(setup.body.radius - zi))
        c = bem.compute(body, [1.0], n_panels=n_panels, include_inf=True, progress=progress,
                        water_depth=math.inf)
        values.append(float(coefficients.matrix(c, "added_mass_inf")[0, 0]))
    a = np.asarray(values)
    a = a * setup.added_mass_inf / float(np.interp(0.0, z, a))
    # exact limit: a sphere touching the free surface from above has no added mass
    return AddedMassTable(np.r_[z, setup.body.radius], np.r_[a, 0.0], int(n_panels))


def score(setup: KramerSetup, curves: dict, drop: str, coef: np.ndarray, lead: float,
          added_mass: AddedMassTable | None) -> float:
    """RMS of heave/H0 over [0, 5 Te0] of one drop (the decay table's), 1-ms RK4."""
    h0 = setup.drop_heights[drop]
    t, z = st.integrate_decay(setup, h0, coef, duration=4.0, dt=0.001, added_mass=added_mass)
    return kh.decay_measures(t - lead, z / h0, setup, *curves[drop])["rms"]


def main() -> None:
    warnings.simplefilter("ignore")
    setup = kh.kramer_setup()
    table = added_mass_table(setup)
    print("A_inf(z) [kg]:", dict(zip(np.round(table.z, 3).tolist(), np.round(table.a_inf, 3).tolist())))
    exp = {d: read_kramer_drop(d, normalised=True) for d in kh.DROPS}
    curves = {d: (exp[d]["time"].values, exp[d]["z"].values[:, 0]) for d in kh.DROPS}
    zero = np.zeros(len(st.STRUCTURED_TERMS))
    print("physics + A_inf(z), no residual:",
          [round(score(setup, curves, d, zero, 0.0, table), 4) for d in kh.DROPS])
    variants = {"V0": (st.STRUCTURED_TERMS, None), "V1": (("b1", "b2", "k1", "k3"), table),
                "V2": (st.STRUCTURED_TERMS, table), "V3": (("b1", "b2", "k1"), table)}
    fits = {"capacity (fitted on 03D)": ["03D"],
            **{f"held out {h}": [d for d in kh.DROPS if d != h] for h in kh.DROPS}}
    print("| variant | fit | 01D | 03D | 05D |\n|---|---|---|---|---|")
    for name, (free, am) in variants.items():
        for label, drops in fits.items():
            coef, lead, _ = st.fit_output_error(setup, {d: curves[d] for d in drops}, zero, free,
                                                dt=kh.FIT_DT[False], fit_lead=True, added_mass=am)
            s = [score(setup, curves, d, coef, lead, am) for d in kh.DROPS]
            print(f"| {name} | {label} | " + " | ".join(f"{x:.4f}" for x in s) + " |", flush=True)


if __name__ == "__main__":
    run_script(main)
