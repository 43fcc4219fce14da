"""The panel-convergence table shared by the case BEM scripts (oc3_bem.py, oc4_bem.py).

Every solve goes through :func:`hybridwsi.hydro.bem.compute` (cached and resumable).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence

from hybridwsi.hydro import bem
from hybridwsi.hydro import coefficients as co


def convergence_table(args: dict, panel_sizes: Sequence[float], omegas: Sequence[float],
                      terms: Sequence[tuple[str, str, int, int]], *, dofs=None,
                      cache_dir: str | None = None, jobs: int = 1) -> None:
    """Print a markdown table of ``terms`` at ``omegas`` (and A(∞)) per panel size.

    ``args``: the case's :func:`hybridwsi.casemodel.bem_arguments` (body, depth, ``low_kh``);
    ``terms``: (header, ``"A"`` or ``"B"``, i, j) with 0-based indices into ``dofs``.
    """
    heads = " | ".join(h for h, *_ in terms)
    print(f"| panel size [m] | hull + lid panels | ω [rad/s] | {heads} | wall [s] |")
    print("|---|---|---|" + "---|" * len(terms) + "---|")
    extra = {} if dofs is None else {"dofs": tuple(dofs)}
    for h in panel_sizes:
        start = time.perf_counter()
        ds = bem.compute(args["body"], omegas, water_depth=args["water_depth"], panel_size=h,
                         low_kh=args["low_kh"], include_zero=False, cache_dir=cache_dir,
                         progress=False, n_jobs=jobs, **extra)
        wall = time.perf_counter() - start
        panels = f"{ds.attrs['n_panels']} + {ds.attrs['n_lid_panels']}"
        mats = {"A": co.matrix_omega(ds, "added_mass"),
                "B": co.matrix_omega(ds, "radiation_damping")}
        for k, w in enumerate(co.omega(ds)):
            cells = " | ".join(f"{mats[kind][k, i, j]:.5e}" for _, kind, i, j in terms)
            print(f"| {h:g} | {panels} | {w:g} | {cells} | {wall:.0f} |")
        ainf = co.matrix(ds, "added_mass_inf")
        cells = " | ".join(f"{ainf[i, j]:.5e}" if kind == "A" else "0"
                           for _, kind, i, j in terms)
        print(f"| {h:g} | {panels} | ∞ | {cells} | |")
        sys.stdout.flush()
