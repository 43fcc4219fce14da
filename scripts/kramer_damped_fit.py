#!/usr/bin/env python
"""Damped period T_d and damping ratio of the Kramer et al. (2021) decay tests and of the 11
blind-comparison codes: a damped oscillator with a free equilibrium fitted over [0, 2.5 Te0]
(``hybridwsi.history.fit_damped_oscillator``), the measure of issue 15's SPH ladder.

    PYTHONPATH=src python scripts/kramer_damped_fit.py [--drop 01D]
"""

from __future__ import annotations

import argparse

from hybridwsi.history import fit_damped_oscillator
from hybridwsi.importers.kramer import (KRAMER_TE0, kramer_numerical_files, read_kramer_drop,
                                        read_kramer_numerical)


def _fit(ds, scale: float = 1.0) -> dict[str, float]:
    t = ds["time"].values
    z = ds["z"].values.reshape(len(t), -1)[:, 0] / scale
    return fit_damped_oscillator(t, z, KRAMER_TE0, (0.0, 2.5 * KRAMER_TE0))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drop", default="01D", choices=["01D", "03D", "05D"])
    a = ap.parse_args()
    exp = read_kramer_drop(a.drop)
    h0 = float(abs(exp["z"].values.reshape(exp.sizes["time"], -1)[0, 0]))
    rows = {"experiment": _fit(exp, h0)}
    for code, path in kramer_numerical_files(a.drop).items():
        rows[code] = _fit(read_kramer_numerical(path, require_uniform=False), h0)
    print(f"| {a.drop} | T_d [s] | zeta | equilibrium / H0 |")
    print("|---|---|---|---|")
    for name, f in rows.items():
        print(f"| {name} | {f['period_d']:.4f} | {f['zeta']:.4f} | {f['z_eq']:+.4f} |")


if __name__ == "__main__":
    main()
