#!/usr/bin/env python
"""Damped period T_d, damping ratio, first trough and RMS of the Kramer et al. (2021) decay
tests and of the 11 blind-comparison codes: a damped oscillator with a free equilibrium fitted
over [0, 2.5 Te0] (``hybridwsi.history.fit_damped_oscillator``), the RMS of heave/H0 over
[0, 5 Te0] as in the decay table — the measures of issue 15's SPH ladder
(``hybridwsi.report.validation.decay_measures``).

    PYTHONPATH=src python scripts/kramer_damped_fit.py [--drop 01D]
"""

from __future__ import annotations


from hybridwsi.cli import Parser, run_script
from hybridwsi.importers.kramer import KRAMER_TE0
from hybridwsi.report.validation import decay_measures_published, decay_measures_table


def main() -> None:
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("--drop", default="01D", choices=["01D", "03D", "05D"])
    a = ap.parse_args()
    print(decay_measures_table(decay_measures_published(a.drop, KRAMER_TE0), a.drop))


if __name__ == "__main__":
    run_script(main)
