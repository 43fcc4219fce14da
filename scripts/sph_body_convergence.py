#!/usr/bin/env python
"""Convergence study of the floating body's first decay cycle (issues 5 and 15).

Runs the 0.1 D heave decay of the Kramer sphere in a small tank (depth 0.6 m, half width
0.75 m, 1 s after release) and of a half-immersed circle in 2D, for the body built from
lattice points (staircase surface) or from smooth concentric shells, h/dp = 1.3 or 1.5, and
a 0.3 s hold before release. The 3D tank is a quarter, half or full domain (``--domain``)
whose symmetry planes are true mirror planes or, as before issue 15, fixed walls
(``--symmetry``). Each case's result is one JSON line in ``<out>/results.jsonl``; cases
already there are skipped, so the study resumes after an interruption.

    OMP_NUM_THREADS=1 python scripts/sph_body_convergence.py --out results/sph_body
    python scripts/sph_body_convergence.py --out results/sph_body --only 3d --dp 0.0375 \
        --smooth smooth --hdx 1.5 --domain quarter half full --symmetry mirror

About 2 min per 3D quarter-domain case at dp = D/8 and 6 min at D/10 on one core (the full
domain has about three times the particles); the 2D cases take 10 s to 3 min.
"""

from __future__ import annotations

import itertools
import json
import math
import time
from pathlib import Path

from hybridwsi.cli import Parser, run_script
from hybridwsi.bodies import cap_volume
from hybridwsi.history import atomic_write
from hybridwsi.sph import tank
from hybridwsi.history import fit_damped_oscillator
from hybridwsi.sph.decay import (TE0, compare_decay, crossing_periods, first_extrema,
                                 grid_convergence)
from hybridwsi.sph.run import run_case

R = 0.15
Z0 = 0.03


def exact_hold_force(dim: int, g: float) -> float:
    """Hydrostatic restoring force [N, or N/m in 2D] of the body held Z0 above equilibrium."""
    if dim == 2:
        a_seg = R * R * math.acos(Z0 / R) - Z0 * math.sqrt(R * R - Z0 * Z0)
        return -tank.RHO_WATER * g * (math.pi * R * R / 2 - a_seg)
    return -tank.RHO_WATER * g * (cap_volume(R, R) - cap_volume(R - Z0, R))


def run_one(dim: int, dp: float, smooth: bool, hdx: float, domain: str = "quarter",
            symmetry: str = "mirror", boundary: str = "shepard",
            packing: str = tank.BODY_PACKING, relax: float = tank.BODY_RELAX,
            tf: float = 1.0) -> dict:
    if dim == 3:
        case = tank.decay3d(dp=dp, depth=0.6, half_width=0.75, tf=tf, hdx=hdx,
                            smooth_body=smooth, t_release=0.3, domain=domain,
                            symmetry=symmetry, boundary=boundary, packing=packing,
                            relax=relax)
    else:
        case = tank.decay2d(dp=dp, depth=0.6, half_width=0.75, tf=tf, hdx=hdx,
                            smooth_body=smooth, t_release=0.3, boundary=boundary,
                            packing=packing, relax=relax)
    t0 = time.monotonic()
    hist = run_case(case, progress=False)
    res = {"dim": dim, "dp": dp, "R_over_dp": R / dp, "smooth_body": smooth, "hdx": hdx,
           "n_particles": case.n_particles, "wall_s": round(time.monotonic() - t0, 1),
           "hold_force": hist["F_tot"].attrs["hold_mean"],
           "hold_force_exact": exact_hold_force(dim, case.g)}
    if boundary != "shepard":  # the records before the option stay valid
        res["boundary"] = boundary
    if packing != "lattice":
        res["packing"] = packing
    if relax > 0.0:
        res.update(relax=relax, t_release=case.t_release)
    if tf != 1.0:
        res["tf"] = tf
    # damped period, damping ratio and equilibrium over [0, 2.5 Te0] (or the record), free
    # equilibrium (issue 15, item 5)
    t = hist["time"].values
    fit = fit_damped_oscillator(t, hist["z"].values[:, 0] / Z0, TE0,
                                (0.0, min(2.5 * TE0, float(t[-1]))))
    res.update(T_d=fit["period_d"], zeta=fit["zeta"], z_eq_fit=fit["z_eq"],
               fit_window=min(2.5 * TE0, float(t[-1])))
    if dim == 3:
        res.update(domain=domain, symmetry=symmetry)
        cmp = compare_decay(hist, Z0, z_eq=0.0)
        res.update({k: v for k, v in cmp.items() if k.startswith(("trough", "crest", "period"))})
        # first full cycle from the first two crossings of the equilibrium
        p = crossing_periods(hist["time"].values, hist["z"].values[:, 0] / Z0)
        res["period_first_cycle"] = float(p[0]) if len(p) else float("nan")
    else:
        t1, z1, t2, z2 = first_extrema(hist["time"].values, hist["z"].values[:, 0] / Z0)
        res.update(trough_t_sim=t1, trough_sim=z1, crest_t_sim=t2, crest_sim=z2)
    return res


def _key(r: dict) -> tuple:
    # results written before issue 15 were quarter domains with wall planes
    return (r["dim"], r["dp"], r["smooth_body"], r["hdx"],
            r.get("domain", "quarter") if r["dim"] == 3 else "full",
            r.get("symmetry", "wall") if r["dim"] == 3 else "none",
            r.get("boundary", "shepard"), r.get("packing", "lattice"), r.get("relax", 0.0),
            r.get("tf", 1.0))


def main() -> None:
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/sph_body")
    ap.add_argument("--only", choices=["2d", "3d"], default=None)
    ap.add_argument("--dp", type=float, nargs="*", default=None, help="subset of spacings [m]")
    ap.add_argument("--hdx", type=float, nargs="*", default=[1.3, 1.5], help="h/dp values")
    ap.add_argument("--smooth", choices=["both", "smooth", "lattice"], default="both",
                    help="body from smooth shells, lattice points, or both")
    ap.add_argument("--domain", nargs="*", choices=["quarter", "half", "full"],
                    default=["quarter"], help="3D domains (default quarter)")
    ap.add_argument("--symmetry", nargs="*", choices=["mirror", "wall"], default=["mirror"],
                    help="3D symmetry planes: true mirror planes or fixed walls")
    ap.add_argument("--boundary", choices=["shepard", "mdbc"], default="shepard",
                    help="body-particle pressure (hybridwsi.sph.mdbc for mdbc)")
    ap.add_argument("--packing", choices=["lattice", "packed"], default=tank.BODY_PACKING,
                    help="initial fluid near the body (default packed: hybridwsi.sph.packing)")
    ap.add_argument("--relax", type=float, default=tank.BODY_RELAX,
                    help="damped relaxation during the 0.3 s hold, released once the rms fluid "
                         "speed is below RELAX sqrt(g d) (default %(default)s; 0: a fixed "
                         "hold)")
    ap.add_argument("--tf", type=float, default=1.0,
                    help="simulated time after release [s] (2.5 Te0 = 1.89 s for the T_d, zeta "
                         "fit over its whole window)")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "results.jsonl"
    done = [json.loads(s) for s in path.read_text().splitlines()] if path.exists() else []
    grid = {2: [0.03, 0.015, 0.01], 3: [0.0375, 0.03]}
    smooth = {"both": (False, True), "smooth": (True,), "lattice": (False,)}[a.smooth]
    for dim in (2, 3):
        if a.only and a.only != f"{dim}d":
            continue
        extra = (list(itertools.product(a.domain, a.symmetry)) if dim == 3
                 else [("full", "none")])
        for dp, sm, hdx, (dom, sym) in itertools.product(a.dp or grid[dim], smooth, a.hdx,
                                                         extra):
            if dim == 3 and dom == "full" and sym == "wall":
                continue  # a full domain has no planes: one run covers both
            key = (dim, dp, sm, hdx, dom, sym, a.boundary, a.packing, a.relax, a.tf)
            if any(_key(r) == key for r in done):
                continue
            print(f"running dim={dim} dp={dp} smooth={sm} hdx={hdx} domain={dom} "
                  f"symmetry={sym}", flush=True)
            done.append(run_one(dim, dp, sm, hdx, *((dom, sym) if dim == 3 else ()),
                                boundary=a.boundary, packing=a.packing, relax=a.relax,
                                tf=a.tf))
            print(json.dumps(done[-1]), flush=True)
            text = "".join(json.dumps(r) + "\n" for r in done)
            atomic_write(path, lambda tmp, text=text: Path(tmp).write_text(text))
    report_gci(done)


def report_gci(done: list[dict]) -> None:
    """Observed order, extrapolation and GCI of each set-up's three finest 3D runs."""
    groups: dict[tuple, list[dict]] = {}
    for r in done:
        if r["dim"] == 3:
            groups.setdefault(_key(r)[2:], []).append(r)
    for key, runs in groups.items():
        runs = sorted(runs, key=lambda r: r["dp"])[:3]
        if len(runs) < 3:
            continue
        hs = tuple(r["dp"] for r in runs)
        for q in ("T_d", "zeta", "trough_sim", "period_extrema_sim", "hold_force"):
            if all(q in r for r in runs):
                g = grid_convergence(tuple(r[q] for r in runs), hs)
                print(f"{key} {q}: values {[round(r[q], 5) for r in runs]} at dp {hs}: "
                      f"order {g['order']:.2f}, extrapolated {g['extrapolated']:.5g}, "
                      f"GCI {100 * g['gci_fine']:.2f} %, monotone {g['monotone']}")


if __name__ == "__main__":
    run_script(main)
