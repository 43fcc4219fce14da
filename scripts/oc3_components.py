"""The numbers of docs/OC3_HYWIND.md "The diagnostic on the design-fidelity components" (issue 29
item 4): regression of the MoorDyn, slow-drift and operating-rotor forces in six DOFs, the
verdicts of ``assess`` (predicted), and the runs that check them (observed).

    PYTHONPATH=src nice -n 10 python scripts/oc3_components.py [--quick]

Writes ``docs/figures/oc3_components.json`` and prints the Markdown tables. About 6 minutes
(MoorDyn driven along 600 s of probe motion, MoorDyn-coupled decays); ``--quick``: the probe
and the decays shortened (for a look, not the docs).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from hybridwsi import __version__, waves  # noqa: E402
from hybridwsi.casemodel import CaseModel  # noqa: E402
from hybridwsi.cli import Parser, run_script  # noqa: E402
from hybridwsi.files import atomic_write  # noqa: E402
from hybridwsi.report import fowt_components as fc  # noqa: E402

OUT = ROOT / "docs" / "figures" / "oc3_components.json"
DOFS = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
DT = 0.1
WIND = 8.0
SEA = {"hs": 6.0, "tp": 12.0, "seed": 1}
KICK = {"Surge": 5.0, "Pitch": 0.02, "Yaw": 0.05}


def _diag(a: np.ndarray) -> str:
    return " / ".join(f"{v:.3g}" for v in np.diag(a))


def main(argv: list[str] | None = None) -> int:
    p = Parser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="short probe and decays")
    args = p.parse_args(argv)
    probe, decay = (120.0, 150.0) if args.quick else (600.0, 400.0)
    t0 = time.time()
    model = CaseModel.build("oc3_hywind", dofs=DOFS, dt=DT, mooring="moordyn", overrides={
        "rotor": {"state": "operating", "wind_speed": WIND}, "forces": {"drift": True}})
    sea = waves.JONSWAP(**SEA)
    comps = model.components(sea=sea)
    hist = fc.probe_history(model, comps, duration=probe, dt=DT)
    out: dict = {"command": "python scripts/oc3_components.py" + " --quick" * args.quick,
                 "hybridwsi_version": __version__, "dofs": DOFS, "dt": DT, "wind_speed": WIND,
                 "sea": SEA, "probe_duration": probe, "probe_rms": fc.PROBE_RMS,
                 "predicted": {}, "observed": {}}
    print("| component | α diag | β diag | γ diag | R² | continuous | lagged at Δt 0.1 s "
          "(ρ, largest stable Δt) |")
    print("|---|---|---|---|---|---|---|")
    for name in ("mooring", "rotor", "drift"):
        pr = fc.predict(model, hist, comps, name, dt=DT)
        out["predicted"][name] = {k: (v.tolist() if isinstance(v, np.ndarray) else v)
                                  for k, v in pr.items()}
        print(f"| {name} | {_diag(pr['alpha'])} | {_diag(pr['beta'])} | {_diag(pr['gamma'])} | "
              f"{' / '.join(f'{r:.2f}' for r in pr['r2'])} | {pr['continuous']} | "
              f"{pr['lagged']} ({pr['spectral_radius']:.6f}, {pr['max_stable_dt']:.3g} s) |")
    coupling = fc.predict_coupling(model, hist, comps, "mooring", dt=DT)
    out["predicted"]["moordyn_coupling"] = coupling
    print(f"\nMoorDyn held over the RK4 step: ρ = {coupling['spectral_radius']:.6f} at Δt "
          f"{DT} s, largest stable Δt {coupling['max_stable_dt']:.3g} s "
          f"({time.time() - t0:.0f} s so far)\n")
    limit = coupling["max_stable_dt"]
    alone = fc.ode_limit(model, hist, comps)
    out["predicted"]["ode_alone_max_stable_dt"] = alone
    print(f"the ODE without the mooring's dynamics (RK4, known part only): largest stable Δt "
          f"{alone:.3g} s\n")
    trials = {"rotor": [DT], "drift": [DT], "mooring": [DT, 1.0]}
    if np.isfinite(limit) and limit < 6.0:  # beyond: the ODE's own RK4 limit (yaw, 0.76 rad/s)
        trials["mooring"] += [round(0.8 * limit, 3), round(1.25 * limit, 3)]
    print("| component | Δt [s] | in the ODE: stable (decay ratios) | lagged: stable "
          "(decay ratios) | lagged − ODE / motion |")
    print("|---|---|---|---|---|")
    for name, dts in trials.items():
        for dt in dts:
            wave = sea if name == "drift" else None
            obs = fc.observe(model, name, kick=KICK, duration=decay, dt=dt, wave=wave,
                             ramp=20.0 if wave is not None else 0.0)
            out["observed"][f"{name}@{dt:g}"] = obs
            cells = []
            for label in ("in_ode", "lagged"):
                r = obs[label]
                ratios = ", ".join(f"{d} {v:.2f}" for d, v in r.get("decay_ratio", {}).items())
                cells.append(f"{r['stable']} ({ratios or r.get('error', '')})")
            diff = ", ".join(f"{d} {v:.2g}" for d, v in obs.get("difference", {}).items()
                             if d in KICK or wave is not None)
            print(f"| {name} | {dt:g} | {cells[0]} | {cells[1]} | {diff} |")
    out["wall_time_s"] = time.time() - t0
    text = json.dumps(out, indent=1, default=float)
    if not args.quick:
        atomic_write(OUT, lambda tmp: Path(tmp).write_text(text))
    print(f"\n{out['wall_time_s']:.0f} s" + ("" if args.quick else f" -> {OUT}"))
    return 0


if __name__ == "__main__":
    run_script(main)
