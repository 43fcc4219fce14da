#!/usr/bin/env python
"""Static gate of the SPH floating sphere (issue 15, item 4).

Holds the Kramer sphere at z = -0.03, 0 and +0.03 m (0.1 D below, at and above its
half-immersed equilibrium) in a closed tank at rest, averages the whole body's fluid force over
at least five acoustic periods 4 d / c0 (after a settling time) and reports its standard
deviation; compares with exact spherical-cap hydrostatics (``hybridwsi.bodies.cap_volume``).
The gate: buoyancy error at equilibrium below 0.5 % of the weight and secant stiffness
[F(-a) - F(+a)] / (2a) within 1 % of the exact value, at D/10 and finer.

Each held height is one JSON line in ``<out>/static_gate.jsonl`` (skipped when already there,
so the script resumes); the summary goes to ``<out>/static_gate_summary.json``.

    OMP_NUM_THREADS=1 python scripts/sph_static_gate.py --dp 0.03 --out results/sph_static

(the defaults: packed start, damped relaxation to 1e-3 sqrt(g d), at most 0.4 s; the lattice
start of the earlier records is ``--packing lattice --relax 0 --settle 0.1``.)

About 3-4 min per height at D/10 in the default 0.45 m deep, 0.9 m wide tank (quarter domain
with mirror planes) on one core.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from hybridwsi.cli import Parser, run_script
from hybridwsi.history import atomic_write
from hybridwsi.sph import static_gate, tank


def _write(path: Path, text: str) -> None:
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))


def main() -> None:
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("--dp", type=float, default=0.03, help="particle spacing [m] (D/10: 0.03)")
    ap.add_argument("--out", default="results/sph_static")
    ap.add_argument("--depth", type=float, default=0.45, help="still-water depth [m]")
    ap.add_argument("--half-width", type=float, default=0.45, help="tank half width [m]")
    ap.add_argument("--periods", type=float, default=5.0,
                    help="acoustic periods 4 d / c0 averaged over (at least 5)")
    ap.add_argument("--settle", type=float, default=0.4,
                    help="settling time [s] before the average (with --relax: its longest)")
    ap.add_argument("--domain", choices=["quarter", "half", "full"], default="quarter")
    ap.add_argument("--symmetry", choices=["mirror", "wall"], default="mirror")
    ap.add_argument("--hdx", type=float, default=None, help="h/dp (default the case's)")
    ap.add_argument("--boundary", choices=["shepard", "mdbc"], default="shepard",
                    help="body-particle pressure: Adami/Shepard at the particle or first-order "
                         "mDBC at its mirror node (hybridwsi.sph.mdbc)")
    ap.add_argument("--packing", choices=["lattice", "packed"], default=tank.BODY_PACKING,
                    help="initial fluid near the body: the body-fitted packing with consistent "
                         "masses (hybridwsi.sph.packing; default) or the cut lattice")
    ap.add_argument("--relax", type=float, default=tank.BODY_RELAX,
                    help="damped relaxation until the rms fluid speed is below RELAX sqrt(g d) "
                         "(--settle is then its longest duration; default %(default)s); 0: a fixed "
                         "settling time")
    a = ap.parse_args()
    if a.periods < 5:
        ap.error("--periods must be at least 5 (the gate averages over >= 5 acoustic periods)")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "static_gate.jsonl"
    setup = {"dp": a.dp, "depth": a.depth, "half_width": a.half_width, "periods": a.periods,
             "settle": a.settle, "domain": a.domain, "symmetry": a.symmetry, "hdx": a.hdx}
    if a.boundary != "shepard":
        setup["boundary"] = a.boundary  # the records of the shepard runs stay valid
    if a.relax > 0.0:
        setup["relax"] = a.relax
    if a.packing != "lattice":
        setup["packing"] = a.packing
    done = [json.loads(s) for s in path.read_text().splitlines()] if path.exists() else []
    kw = {"hdx": a.hdx} if a.hdx is not None else {}
    kw.update(boundary=a.boundary, relax=a.relax, packing=a.packing)
    for z in static_gate.HEIGHTS:
        if any(r["setup"] == setup and r["z"] == z for r in done):
            continue
        print(f"holding the sphere at z = {z:+.3f} m (dp = {a.dp} m)", flush=True)
        t0 = time.monotonic()
        r = static_gate.held_force(a.dp, z, depth=a.depth, half_width=a.half_width,
                                   n_periods=a.periods, settle=a.settle, domain=a.domain,
                                   symmetry=a.symmetry, **kw)
        r.update(setup=setup, wall_s=round(time.monotonic() - t0, 1))
        done.append(r)
        print(json.dumps(r), flush=True)
        _write(path, "".join(json.dumps(x) + "\n" for x in done))
    mine = [r for r in done if r["setup"] == setup]
    summary = dict(setup, **static_gate.gate(mine),
                   forces={f"{r['z']:+.3f}": [r["mean"], r["std"], r["exact"]] for r in mine})
    _write(out / "static_gate_summary.json", json.dumps(summary, indent=1) + "\n")
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    run_script(main)
