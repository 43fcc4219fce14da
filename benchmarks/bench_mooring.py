"""Benchmark: the tabulated mooring interpolant against a MoorPy solve per evaluation (target ≥ 100×).

Times :meth:`hybridwsi.forces.mooring.MooringTable.force6` (the OC3-Hywind mooring, default box)
on one state and on a batch of 32 states (its Numba kernel when Numba is installed; the NumPy
float path, the fallback without Numba, is timed too), and two MoorPy baselines measured in
the same process, :meth:`MooringSystem.force6` (MoorPy placing the body and statically solving
its three catenary lines) per state:

- from random states of the box, each solve started from the previous, unrelated state;
- along a smooth time-loop path (0.1 s steps), each solve warm-started from the previous
  step's, MoorPy's fastest use. This is the fair per-evaluation baseline for the time loop
  (the interpolant replaces MoorPy inside the ODE, where consecutive states are close); the
  random-state one is what a single isolated evaluation costs.

Timing: ``benchmarks/timing.py`` (samples of >= 0.2 s, ``--repeat`` rounds alternating the
baseline and the candidates, medians and the speed-up's spread). Also prints the
largest interpolation error on the benchmark states, relative to each DOF's force scale.
Run: ``python benchmarks/bench_mooring.py`` (needs ``hybridwsi[mooring]``).

``--moordyn``: the cost of the MoorDyn-coupled time loop instead. OC3-Hywind, 6 DOFs, a
JONSWAP sea (Hs 5 m, Tp 11 s, 100 components), the additional linear damping and the mooring,
solver Δt 0.1 s, ``cummins.simulate`` with the radiation state space fitted once (outside the
timing): the candidate couples :class:`~hybridwsi.forces.MoorDynForce` (the shipped input,
MoorDyn sub-stepping at its dtM; its static initialisation at the start of every run is
inside the timing), the baseline is the same run with the tabulated quasi-static mooring
(:class:`~hybridwsi.forces.MooringForce`, compiled RK4 loop). Alternating baseline/candidate
``--repeat`` times (≥ 5); a sample repeats its run until it lasts ≥ 0.2 s. Prints the
MoorDyn-coupled wall time per simulated hour against real time (3600 s) and the median ratio to
the baseline with its spread. ``--duration`` [s] simulated per sample (default 600; 3600 for a
literal hour).

``--design``: the same comparison on the case's design-fidelity runs (issue 29):
``CaseModel.simulate`` of OC3-Hywind in 6 DOFs with every component of the case — Morison drag
on the wave kinematics, additional damping, the operating NREL 5-MW rotor at rated (11.4 m/s,
turbulence intensity 0.1, Kaimal), Newman's slow drift — in a JONSWAP sea (Hs 6 m, Tp 12 s,
200 components), starting from the mean offset; MoorDyn against the tabulated mooring.

``--hybrid``: the two hybrids of ``scripts/oc3_moordyn_hybrid.py`` (the shipped networks
``hybridwsi/data/oc3_moordyn_hybrid*_network``; ``hybrid``: the quasi-static mooring and the
rotor in the ODE, run by their Numba kernels inside the compiled loop; ``hybrid_lin``: a linear
known part; both in the compiled loop, ``corrected`` coupling) against their MoorDyn-coupled reference on the same sea and wind (the
first held-out sea: Hs 4.5 m, Tp 10.5 s, 8.5 m/s, TI 0.1; Surge, Heave, Pitch; Δt 0.1 s),
side by side, alternating ``--repeat`` times (≥ 3). A hybrid's time includes what it needs
per sea besides the rollout (the excitation and η, the mean offset, the rotor's wind force,
the known components, the quasi-static tensions); the case model and the network are loaded
once. The reference's includes MoorDyn's static initialisation. Prints the wall times, the
median ratios (target ≥ 50×) and each hybrid's RMS surge and pitch error against the
reference of the same sample.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np

from hybridwsi.cases import load_case
from hybridwsi.forces._compiled import HAVE_NUMBA
from hybridwsi.forces.mooring import MooringSystem

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import REPEAT, Figure, compare, conditions  # noqa: E402


def _compare(run_base, run_md, duration: float, repeat: int, what: str) -> None:
    """The tabulated baseline and the MoorDyn-coupled run in ``repeat`` alternating rounds
    (``benchmarks/timing.py``); print wall time per simulated hour, real-time factor and the
    median ratio with its spread."""
    last = {}
    t = compare(Figure(lambda: last.update(base=run_base())),
                {"moordyn": Figure(lambda: last.update(md=run_md()))}, repeat=repeat,
                warmup=False, baseline_label="table")
    md, base = t["moordyn"], t["table"]
    hour = 3600.0 / duration * md.median
    print(f"{duration:.0f} s simulated per sample, 6 DOF, {repeat} alternating samples; {what}")
    print(f"MoorDyn-coupled   : {md.time_text()} wall per run -> {hour:6.0f} s per simulated "
          f"hour = {3600.0 / hour:5.1f}x faster than real time (wall time: longer on a "
          f"machine shared with other jobs)")
    print(f"tabulated baseline: {base.time_text()} wall per run -> "
          f"{3600.0 / duration * base.median:6.1f} s per hour")
    print(f"ratio MoorDyn / table: {md.ratio_text()}")
    z_md, z_tab = last["md"]["z"].values, last["base"]["z"].values
    print("std surge/heave/pitch MoorDyn: "
          + ", ".join(f"{z_md[:, i].std():.4g}" for i in (0, 2, 4))
          + "; table: " + ", ".join(f"{z_tab[:, i].std():.4g}" for i in (0, 2, 4)))
    print(conditions(repeat=repeat))


def moordyn_cost(duration: float, repeat: int) -> None:
    """MoorDyn-coupled run against the tabulated-mooring baseline (module doc, ``--moordyn``)."""
    from hybridwsi.cummins import build_system, simulate
    from hybridwsi.forces import MoorDynForce, MooringForce, additional_damping
    from hybridwsi.report.fowt import oc3_coefficients
    from hybridwsi.waves import JONSWAP

    dofs = ["Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"]
    dt = 0.1
    case = load_case("oc3_hywind")
    coeffs = oc3_coefficients(case)
    wave = JONSWAP(hs=5.0, tp=11.0, gamma=3.3, seed=7, n_components=100)
    damping = additional_damping(case, dofs)
    table = MooringForce.from_case(case, dofs)
    moordyn = MoorDynForce.from_case(case, dofs, dt=dt)
    moordyn.stiffness()  # static solves cached once (simulate asks linear_coefficients)
    kw = dict(dofs=dofs, duration=duration, dt=dt, wave=wave, ramp=60.0,
              radiation_ss=build_system(coeffs, dofs=dofs, dt=dt).ss)
    simulate(coeffs, forces=[table, damping], **dict(kw, duration=10 * dt))  # Numba warm-up
    _compare(lambda: simulate(coeffs, forces=[table, damping], **kw),
             lambda: simulate(coeffs, forces=[moordyn, damping], **kw), duration, repeat,
             f"dt {dt} s; {moordyn.describe()}")


#: the design-fidelity set-up of ``--design`` (issue 29 item 5's reference): the operating
#: rotor in turbulent wind at rated, the slow drift, Morison drag on the wave kinematics
DESIGN = {"rotor": {"state": "operating", "wind_speed": 11.4, "turbulence_intensity": 0.1,
                    "wind_seed": 3},
          "forces": {"drift": True}}


def design_cost(duration: float, repeat: int) -> None:
    """``--design``: the case's own runs (``CaseModel.simulate``, every component, the mean
    offset start) with MoorDyn against the same with the tabulated mooring."""
    from hybridwsi.casemodel import CaseModel
    from hybridwsi.waves import JONSWAP

    dofs, dt = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"), 0.1
    wave = JONSWAP(hs=6.0, tp=12.0, gamma=3.3, seed=7, n_components=200)
    models = {m: CaseModel.build("oc3_hywind", dofs=dofs, dt=dt, mooring=m, overrides=DESIGN)
              for m in ("table", "moordyn")}
    kw = dict(duration=duration, dt=dt, wave=wave, ramp=60.0)
    models["table"].simulate(**dict(kw, duration=10 * dt))  # Numba warm-up
    comps = models["moordyn"].components(sea=wave)
    _compare(lambda: models["table"].simulate(**kw), lambda: models["moordyn"].simulate(**kw),
             duration, repeat, f"dt {dt} s; components {', '.join(comps)}; {DESIGN}")


def hybrid_cost(duration: float, repeat: int) -> None:
    """``--hybrid``: both hybrids against the MoorDyn-coupled reference (module doc)."""
    from hybridwsi.report import fowt_moordyn_hybrid as fmh
    from hybridwsi.surrogate.network import ForceNetwork

    shipped = fmh.load_shipped()[0]["prediction"]
    nets = {k: ForceNetwork.load(path) for k, path in fmh.NETWORKS.items()}
    name, sea = next(iter(fmh.HELD.items()))
    model = fmh.case_model(sea, "table")  # built once, like loading the network

    def run_hybrid(k: str):
        case = fmh.hybrid_case(sea, duration, nets[k], model)
        return fmh.run_hybrid(nets[k], case, model, k,
                              corrections=shipped[k]["corrections"])[0]

    out: dict[str, object] = {}

    def keep(label: str, fn):
        return Figure(lambda: out.__setitem__(label, fn()), duration)  # per simulated second

    # MoorDyn first in every round, then each hybrid (timing.compare alternates them)
    timings = compare(keep("moordyn", lambda: fmh.simulate("moordyn", sea, duration)),
                {k: keep(k, lambda k=k: run_hybrid(k)) for k in nets}, repeat=repeat,
                min_time=0.0, baseline_label="moordyn")
    print(f"{duration:.0f} s simulated, sea {name} {sea}, {', '.join(fmh.DOFS)}, dt {fmh.DT} s "
          "(MoorDyn, then each hybrid)")
    for k, v in timings.items():
        print(f"{k:10s}: {v.time_text(duration)} wall = {1.0 / v.median:8.1f}x real time")
    ref = out["moordyn"]
    for k in nets:
        ratios = 1.0 / timings[k].ratios
        t = out[k]["time"].values
        err = {d: float(np.sqrt(np.mean((out[k]["z"].sel(dof=d).values - ref["z"].sel(dof=d).sel(
            time=t, method="nearest").values) ** 2) / np.mean(ref["z"].sel(dof=d).values ** 2)))
            for d in ("Surge", "Pitch")}
        print(f"ratio MoorDyn-coupled / {k}: median {np.median(ratios):.1f}x (min "
              f"{ratios.min():.1f}, max {ratios.max():.1f}); target >= 50x: "
              f"{'met' if np.median(ratios) >= 50 else 'NOT met'}; RMS error / RMS vs the "
              "reference: " + ", ".join(f"{d} {100 * e:.2f} %" for d, e in err.items()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=REPEAT, help="alternating rounds")
    parser.add_argument("--batch", type=int, default=32, help="states per batch call")
    parser.add_argument("--moordyn", action="store_true",
                        help="time the MoorDyn-coupled loop against the tabulated mooring")
    parser.add_argument("--design", action="store_true",
                        help="the MoorDyn-coupled design-fidelity case run (rotor, drift, "
                             "drag) against the same with the tabulated mooring")
    parser.add_argument("--hybrid", action="store_true",
                        help="the hybrid of scripts/oc3_moordyn_hybrid.py against its "
                             "MoorDyn-coupled reference on the same sea")
    parser.add_argument("--duration", type=float, default=600.0,
                        help="--moordyn/--design/--hybrid: simulated time per sample [s]")
    args = parser.parse_args()
    if args.hybrid:
        hybrid_cost(args.duration, max(args.repeat, 3))
        return
    if args.moordyn or args.design:
        (design_cost if args.design else moordyn_cost)(args.duration, args.repeat)
        return

    case = load_case("oc3_hywind")
    system = MooringSystem.from_case(case)
    import hybridwsi.forces._compiled  # noqa: F401  loads (or compiles) the kernels untimed
    t0 = time.perf_counter()
    table = system.tabulate()
    t_build = time.perf_counter() - t0  # once: the table is built once per case
    half = np.array(list(table.ranges.values()))
    states = np.random.default_rng(0).uniform(-1.0, 1.0, (args.batch, 6)) * half
    # a time-loop trajectory: half the box, periods 20-125 s, 0.1 s steps (MoorPy warm-starts
    # each catenary from the previous solve, its fastest use)
    t = np.arange(20_000)[:, None] * 0.1
    path = 0.5 * half * np.sin(2 * np.pi * t / np.array([125, 110, 31, 29, 29, 8.3]) + 0.3)
    cycle, walk = itertools.cycle(states), itertools.cycle(path)

    t = compare(Figure(lambda: system.force6(next(walk))),
                {"random": Figure(lambda: system.force6(next(cycle))),
                 "single": Figure(lambda: table.force6(next(cycle))),
                 "batch": Figure(lambda: table.force6(states), args.batch),
                 "numpy": Figure(lambda: table._force6_scalar(next(cycle)))},
                repeat=args.repeat, baseline_label="moorpy")
    t_random, t_moorpy, t_single, t_numpy = (t[k].median for k in ("random", "moorpy",
                                                                    "single", "numpy"))
    t_batch = t["batch"].median * args.batch
    exact = np.array([system.force6(q) for q in states])
    scale = np.abs(exact - system.preload()).max(axis=0)
    error = np.abs(table.force6(states) - exact).max(axis=0) / scale

    print(f"table {table.dataset.sizes['l_h']} x {table.dataset.sizes['l_v']} "
          f"(l_h x l_v), built in {t_build:.2f} s; evaluation "
          f"{'Numba kernel' if HAVE_NUMBA else 'NumPy (no Numba)'}")
    print(f"MoorPy solve, random states  : {t_random * 1e6:9.1f} us   (interpolant single: "
          f"ratio {t_random / t_single:.0f}x)")
    print(f"MoorPy solve along a path    : {t_moorpy * 1e6:9.1f} us   (baseline below)")
    print(f"interpolant, single state    : {t_single * 1e6:9.1f} us   ratio "
          f"{t['single'].ratio_text(speedup=True)}")
    print(f"interpolant, batch of {args.batch:<3d}    : {t_batch * 1e6:9.1f} us   "
          f"{t_batch / args.batch * 1e6:.1f} us/state, ratio {args.batch * t_moorpy / t_batch:6.0f}x")
    print(f"interpolant, single, NumPy   : {t_numpy * 1e6:9.1f} us   ratio {t_moorpy / t_numpy:6.0f}x "
          f"(the fallback without Numba)")
    print(f"target >= 100x               : single {'met' if t_moorpy / t_single >= 100 else 'NOT met'}, "
          f"batch {'met' if args.batch * t_moorpy / t_batch >= 100 else 'NOT met'}")
    print("max error / force scale per DOF: " + ", ".join(f"{e:.1e}" for e in error))
    print(conditions(repeat=args.repeat))


if __name__ == "__main__":
    main()
