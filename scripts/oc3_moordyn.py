"""OC3-Hywind in MoorDyn: the convergence check behind the shipped input, statics against MoorPy,
and the forced-surge hysteresis figure (docs/OC3_HYWIND.md "MoorDyn").

The convergence check is resumable: every variant's results go to ``OUT/convergence.json`` as
soon as they are computed (atomic writes); a rerun computes only what is missing. The
hysteresis run (1-2 min) writes ``OUT/hysteresis.json`` and the figure each time.

    # segments, dtM, coupling step and internal damping of the shipped input (~25 min wall)
    python scripts/oc3_moordyn.py convergence
    # statics of the shipped input against MoorPy (~20 s)
    python scripts/oc3_moordyn.py statics
    # forced-surge loops, Huse's reference, docs/figures/oc3_moordyn_hysteresis.{png,nc} (~2 min)
    python scripts/oc3_moordyn.py hysteresis
    # the shipped input's static solutions -> src/hybridwsi/data/moordyn_statics.json (~20 s)
    python scripts/oc3_moordyn.py ship

Run with ``OPENBLAS_NUM_THREADS=1``.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
from pathlib import Path
from typing import Any

from hybridwsi._meta import provenance
from hybridwsi.cases import load_case
from hybridwsi.cli import Parser, run_script
from hybridwsi.errors import SolverError
from hybridwsi.files import to_netcdf, write_json
from hybridwsi.forces.moordyn import (
    FD_STEP,
    SHIPPED_STATICS,
    MoorDynForce,
    fairlead_stiffness,
    rest_statics,
    set_options,
    set_segments,
    statics_key,
)
from hybridwsi.forces.mooring import MooringSystem
from hybridwsi.report.moordyn_study import (
    forced_loop,
    hysteresis_figure,
    loop_metrics,
    static_curve,
    statics_summary,
)

ROOT = Path(__file__).resolve().parent.parent
FIGURE = ROOT / "docs" / "figures" / "oc3_moordyn_hysteresis"
#: forced-surge cases (period [s], amplitude [m]): a wave period, the pitch-resonance region and
#: the surge natural period (124 s), with amplitudes of the order of the motions there
CASES = ((10.0, 2.0), (30.0, 4.0), (125.0, 10.0))
#: Huse's method needs the line hydrodynamics, which the case's [mooring] table does not hold:
#: the shipped input's (the OpenFAST deck's) transverse/axial drag coefficients and diameter
DRAG = {"cd": 1.6, "cd_axial": 0.1, "diameter": 0.09}
#: variants of the convergence check: (segments, dtM [s], coupling step [s], BA/-zeta)
#: (the shipped input: 40 segments, dtM 2 ms, coupling step 0.1 s, BA -0.8 = 80 % of the
#: critical damping of the segments' axial mode, the OpenFAST deck's value)
VARIANTS = ([(n, 0.002, 0.1, "-0.8") for n in (10, 20, 40, 80)]
            + [(40, dtm, 0.1, "-0.8") for dtm in (0.005, 0.001, 0.0005)]
            + [(40, 0.002, dt, "-0.8") for dt in (0.2, 0.05)]
            + [(40, 0.002, 0.1, ba) for ba in ("-0.4", "-1.0", "3.1179e6", "0.0")])
#: surge offsets [m] of the static force curve (segment variants)
OFFSETS = (-10.0, -6.0, -3.5, -2.0, 2.0, 3.5, 6.0, 10.0)


def _component(case: dict, segments: int | None = None, dtm: float | None = None,
               ba: str | None = None, dofs: tuple[str, ...] = ("Surge",)) -> MoorDynForce:
    base = MoorDynForce.from_case(case, list(dofs))
    text = base.text
    if segments is not None:
        text = set_segments(text, segments)
    if dtm is not None:
        text = set_options(text, {"dtM": dtm})
    if ba is not None:
        text = text.replace("  -0.8  ", f"  {ba}  ")
    return MoorDynForce(text, list(dofs), reference_point=base.reference_point,
                        yaw_spring=base.yaw_spring, source=base.source)


def _load(path: Path) -> dict[str, Any]:
    return json.loads(path.read_text()) if path.is_file() else {}


def convergence(out: Path) -> None:
    """Statics and forced-surge metrics of every variant; a markdown table at the end."""
    case = load_case("oc3_hywind")
    system = MooringSystem.from_case(case)
    path = out / "convergence.json"
    results = _load(path)
    for n, dtm, dt, ba in VARIANTS:
        key = f"segments={n} dtM={dtm:g} dt={dt:g} BA={ba}"
        if key in results:
            continue
        start = time.perf_counter()
        comp = _component(case, n, dtm, ba)
        entry: dict[str, Any] = {"statics": statics_summary(comp, system), "forced": {}}
        if (dtm, dt, ba) == (0.002, 0.1, "-0.8"):
            entry["curve"] = static_curve(comp, system, "Surge", OFFSETS)
        for period, amp in CASES:
            try:
                loop = forced_loop(comp, None, "Surge", amp, period, dt=dt)
            except SolverError as exc:  # e.g. no internal damping: the segments ring
                entry["forced"][f"T={period:g} X={amp:g}"] = {"error": str(exc)}
                continue
            entry["forced"][f"T={period:g} X={amp:g}"] = loop_metrics(loop)
        comp.close()
        entry["wall_s"] = time.perf_counter() - start
        results[key] = entry
        write_json(path, results)
        print(f"{key}: {entry['wall_s']:.0f} s", flush=True)
    _table(results)


def _table(results: dict[str, Any]) -> None:
    print("| variant | T_fair [N] | F0_z [N] | K11 [N/m] | K33 [N/m] | F(x) vs MoorPy | "
          + " | ".join(f"E {c} [MJ], φ [°]" for c in (f"T={p:g} X={a:g}" for p, a in CASES))
          + " | wall [s] |")
    print("|---|---|---|---|---|---|" + "---|" * len(CASES) + "---|")
    for key, e in results.items():
        s = e["statics"]
        cells = [f"{s['T_fairlead']['moordyn']:.0f}", f"{s['F0_z']['moordyn']:.0f}",
                 f"{s['K11']['moordyn']:.1f}", f"{s['K33']['moordyn']:.1f}",
                 f"{100 * e['curve']['max_rel_diff']:.2f} %" if "curve" in e else ""]
        cells += [f"{m['E'] / 1e6:.4f}, {m['phase_deg']:.2f}" if "E" in m else "failed"
                  for m in e["forced"].values()]
        print(f"| {key} | " + " | ".join(cells) + f" | {e['wall_s']:.0f} |")


def statics(out: Path) -> None:
    """The shipped input's statics against MoorPy (table rows)."""
    case = load_case("oc3_hywind")
    comp = MoorDynForce.from_case(case, ["Surge"])
    summary = statics_summary(comp, MooringSystem.from_case(case))
    write_json(out / "statics.json", summary)
    for name, row in summary.items():
        print(f"| {name} | {row['moordyn']:.6g} | {row['moorpy']:.6g} | "
              f"{100 * row['rel_diff']:+.3f} % |")


def hysteresis(out: Path, figure: Path) -> None:
    """Forced-surge loops of the shipped input, MoorPy's quasi-static force and Huse's loop
    area; the figure and its data."""
    case = load_case("oc3_hywind")
    system = MooringSystem.from_case(case)
    comp = MoorDynForce.from_case(case, ["Surge"])
    path = out / "hysteresis.json"
    results = _load(path)
    loops = {}
    huse = {}
    for period, amp in CASES:
        label = f"T{period:g}_X{amp:g}"
        loop = forced_loop(comp, system, "Surge", amp, period, dt=0.1)
        loops[label] = loop
        ref = system.drag_dissipation([amp, 0, 0, 0, 0, 0], period, **DRAG)
        huse[label] = ref["total"]
        results[label] = {"moordyn": loop_metrics(loop),
                          "quasi_static": loop_metrics(loop, "F_quasi_static"),
                          "huse": ref, "period": period, "amplitude": amp}
        write_json(path, results)
        m, qs = results[label]["moordyn"], results[label]["quasi_static"]
        # in-phase stiffness below the quasi-static one = an added mass (K_qs' - K')/ω²
        m["A_eq"] = (qs["K_real"] - m["K_real"]) / (2 * np.pi / period) ** 2
        write_json(path, results)
        print(f"| {period:g} | {amp:g} | {m['E'] / 1e6:.4f} | {ref['total'] / 1e6:.4f} | "
              f"{100 * (m['E'] / ref['total'] - 1):+.2f} % | {m['phase_deg']:.2f} | "
              f"{qs['phase_deg']:.1e} | {m['K_real']:.0f} | {qs['K_real']:.0f} | "
              f"{m['A_eq'] / 1e3:.1f} | {m['B_eq']:.4g} | {qs['E']:.1e} | "
              f"{m['T_fairlead_min'][0] / 1e3:.0f}–{m['T_fairlead_max'][0] / 1e3:.0f} | "
              f"{qs['T_fairlead_min'][0] / 1e3:.0f}–{qs['T_fairlead_max'][0] / 1e3:.0f} |",
              flush=True)
    fig, data = hysteresis_figure(loops, huse)
    data.attrs.update({"moordyn": comp.describe().replace(f"{ROOT}/", ""),
                       "made_by": "scripts/oc3_moordyn.py hysteresis",
                       "versions": json.dumps(provenance("moordyn", "moorpy")),
                       "huse_J_per_cycle": json.dumps(huse)})
    to_netcdf(data, figure.with_suffix(".nc"))
    fig.savefig(figure.with_suffix(".png"), dpi=120)
    print(f"-> {figure.with_suffix('.png')}, {figure.with_suffix('.nc')}")


def ship() -> None:
    """Solve the shipped input's statics (rest and fairlead stiffness, no cache) and write them
    to the package, keyed as the cache is, for a fresh install."""
    text = MoorDynForce.from_case(load_case("oc3_hywind"), ["Surge"]).text
    start = time.perf_counter()
    entries = {statics_key(text, "rest", 0.0): rest_statics(text, use_cache=False),
               statics_key(text, "stiffness", FD_STEP): {
                   "stiffness": fairlead_stiffness(text, FD_STEP, use_cache=False)}}
    path = ROOT / "src" / "hybridwsi" / "data" / SHIPPED_STATICS
    write_json(path, {k: {n: v.tolist() for n, v in e.items()} for k, e in entries.items()})
    print(f"-> {path} ({time.perf_counter() - start:.0f} s)")


def main(argv: list[str] | None = None) -> int:
    parser = Parser(description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=["convergence", "statics", "hysteresis", "ship"])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "oc3_moordyn",
                        help="directory of the JSON results (resumable)")
    parser.add_argument("--figure", type=Path, default=FIGURE, help="figure stem (.png, .nc)")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    if args.command == "convergence":
        convergence(args.out)
    elif args.command == "statics":
        statics(args.out)
    elif args.command == "ship":
        ship()
    else:
        hysteresis(args.out, args.figure)
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    run_script(main)
