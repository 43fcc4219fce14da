"""OC3-Hywind at design fidelity: the hybrid against the MoorDyn-coupled reference (issue 29
items 5-6; docs/OC3_HYWIND.md "The hybrid on the MoorDyn-coupled reference").

Reference ("high fidelity"): Cummins (Surge, Heave, Pitch) + MoorDyn + slow drift (Newman) +
Morison drag with the wave kinematics + the operating NREL 5-MW rotor (quasi-steady) in
turbulent wind (Kaimal, TI 0.1) + the additional linear damping, JONSWAP seas. The network
learns the residual of the partition the diagnostic recommends (docs/OC3_HYWIND.md "The
diagnostic on the design-fidelity components"): hydrostatics, A∞, radiation memory, excitation,
the additional damping, the quasi-static mooring (MoorPy's tabulated interpolant) and the rotor
stay in the ODE; MoorDyn minus the quasi-static mooring, the slow drift and the drag go to the
network (inputs z, ż, η), trained through :class:`hybridwsi.surrogate.pipeline.HybridPipeline`.
The rotor is known, so each history's recorded rotor force is subtracted from the force the
network's residual is taken of, and each run's rollout carries the rotor of its own wind.

Resumable: every simulated history goes to ``WORK/<model>_<sea>.nc`` (atomic) as soon as it is
computed and a rerun only computes what is missing; the network to ``WORK/network.pt/.json``.
The results (metrics, spectra, time-series excerpts) go to
``src/hybridwsi/data/oc3_moordyn_hybrid.{json,nc}``.

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src nice -n 5 python scripts/oc3_moordyn_hybrid.py \\
        --work /tmp/oc3_moordyn_hybrid

``--quick``: 300 s seas, a 600 s long run, nothing shipped (a look at the pipeline).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi._meta import provenance
from hybridwsi.casemodel import CaseModel, linear_components
from hybridwsi.cli import Parser, run_script
from hybridwsi.diagnostic.partition import build_candidates
from hybridwsi.files import read_netcdf, to_netcdf, write_json
from hybridwsi.report import fowt_moordyn_hybrid as fmh
from hybridwsi.surrogate.network import ForceNetwork
from hybridwsi.surrogate.pipeline import HybridPipeline
from hybridwsi.waves import JONSWAP

ROOT = Path(__file__).resolve().parent.parent
SHIP = ROOT / "src" / "hybridwsi" / "data" / "oc3_moordyn_hybrid"
DOFS = ("Surge", "Heave", "Pitch")
DT = 0.1
RAMP = 60.0
TI = 0.1
#: the known part of the partition besides the case's components (diagnostic candidates)
CANDIDATES = ("hydrostatic", "added_mass_inf", "radiation_memory", "excitation")
#: seas: Hs [m], Tp [s], wave seed, mean hub wind [m/s], wind seed. Training winds 7-9 m/s
#: (below rated: region 2, positive aerodynamic damping); held-out seas AND winds between them
TRAIN = {"train1": (4.0, 10.0, 1, 7.0, 1), "train2": (6.0, 12.0, 2, 9.0, 2),
         "train3": (5.0, 11.0, 3, 8.0, 3)}
HELD = {"held1": (4.5, 10.5, 101, 8.5, 101), "held2": (5.5, 11.5, 102, 7.5, 102)}
LONG = {"long": (5.0, 11.0, 201, 8.0, 201)}
#: the network: the case's [hybrid.network] (window 6 taps 0.5 s apart, η 0.5 s ahead)
MODE = "corrected"
#: epochs of the training (the case's 150 / 20 cost ~45 min here on 3 x 1800 s of data)
NETWORK_EPOCHS = {"max_epochs": 60, "patience": 10}


def case_model(sea: tuple, mooring: str, *, linear: bool = False) -> CaseModel:
    """The OC3 model of one sea's wind: operating rotor, turbulent wind, slow drift, drag
    (``linear``: no drag, no drift: the mooring is added as its linearisation)."""
    _, _, _, wind, wseed = sea
    forces = {"drift": not linear, "morison": not linear, **({"mooring": "none"} if linear
                                                              else {})}
    return CaseModel.build("oc3_hywind", dofs=DOFS, dt=DT, mooring=None if linear else mooring,
                           overrides={
                               "rotor": {"state": "operating", "wind_speed": wind,
                                         "turbulence_intensity": TI, "wind_seed": wseed},
                               "forces": forces})


def jonswap(sea: tuple) -> JONSWAP:
    hs, tp, seed = sea[:3]
    return JONSWAP(hs=hs, tp=tp, seed=seed)


def simulate(kind: str, sea: tuple, duration: float) -> xr.Dataset:
    """One run: ``moordyn`` (the reference), ``table`` (quasi-static mooring, else the same),
    ``linear`` (linearised mooring, no drag, no drift, the same rotor and wind)."""
    if kind != "linear":
        return case_model(sea, kind).simulate(duration=duration, dt=DT, wave=jonswap(sea),
                                              ramp=RAMP)
    model = case_model(sea, "none", linear=True)
    lin = linear_components(model.case, DOFS)
    z0 = fmh.linear_offset(model, lin[0].linear_coefficients(len(DOFS))[2])
    return model.simulate(duration=duration, dt=DT, wave=jonswap(sea), ramp=RAMP,
                          extra={"linear_mooring": lin[0]}, from_offset=False, z0=z0)


def cached(work: Path, kind: str, name: str, sea: tuple, duration: float) -> xr.Dataset:
    """``simulate`` once: its history from ``work`` when there (resume)."""
    path = work / f"{kind}_{name}.nc"
    if not path.is_file():
        start = time.perf_counter()
        hist = simulate(kind, sea, duration)
        hist.attrs["wall_s"] = time.perf_counter() - start
        to_netcdf(hist, path)
        print(f"{kind} {name}: {hist.attrs['wall_s']:.0f} s wall", flush=True)
    return read_netcdf(path)


def known_part(hist: xr.Dataset, sea: tuple, *, rotor: bool) -> list:
    """The partition's known components on ``hist``: the candidates, the additional damping,
    the quasi-static (tabulated) mooring and, with ``rotor``, this sea's rotor."""
    comps = case_model(sea, "table").components()
    known = [*build_candidates(hist, case_model(sea, "table").coeffs, CANDIDATES).values(),
             comps["linear_damping"], comps["mooring"]]
    return known + ([comps["rotor"]] if rotor else [])


def prepared(hist: xr.Dataset, model: CaseModel) -> xr.Dataset:
    """The history with the radiation state space its ``radiation_memory`` candidate reads
    and ``F_norotor = F_tot − F_rotor``: the force the residual is taken of when the rotor is
    known (its recorded force: each history has its own wind)."""
    hist = hist.assign(F_norotor=hist["F_tot"] - hist["F_rotor"])
    hist.attrs["radiation_ss"] = json.dumps(model.radiation_ss.to_dict())
    return hist


def train(work: Path, refs: dict[str, xr.Dataset], model: CaseModel) -> tuple[ForceNetwork, Any]:
    """The network through the pipeline (resumed from ``work/network.*`` when there)."""
    hs = [prepared(h, model) for h in refs.values()]
    known = known_part(hs[0], TRAIN["train1"], rotor=False)
    # the case's [hybrid.network] with fewer epochs: 3 x 1800 s of data make ~100 batches an
    # epoch, and the training must fit the shared 2-core machine (NETWORK_EPOCHS)
    net_cfg = {**model.case["hybrid"]["network"], **NETWORK_EPOCHS}
    pipe = HybridPipeline("moordyn-table+drift+drag", inputs=("z", "zdot", "eta"), known=known,
                          mode=MODE, network=net_cfg, force="F_norotor", allow_unstable=True,
                          progress=False)
    path = work / "network"
    if (work / "network.pt").is_file():
        net = ForceNetwork.load(path)
        pipe = HybridPipeline.from_network(net, known, mass=hs[0]["mass"].values, dt=DT,
                                           mode=MODE, corrections=2)
        pipe._predict(hs)
        return net, pipe
    start = time.perf_counter()
    pipe.fit(hs, model.coeffs)
    pipe.network_.save(path)
    print(f"trained in {time.perf_counter() - start:.0f} s", flush=True)
    return pipe.network_, pipe


def run_hybrid(pipe: HybridPipeline, ref: xr.Dataset, sea: tuple, model: CaseModel
               ) -> tuple[xr.Dataset, float]:
    """The hybrid on ``ref``'s sea and wind (its first window as initial state) and its wall
    time [s]; the quasi-static line tensions along its motion added."""
    h = prepared(ref, model)
    run = HybridPipeline.from_network(pipe.network_, known_part(h, sea, rotor=True),
                                      mass=pipe.mass_, dt=DT, mode=MODE,
                                      corrections=pipe.corrections_)
    start = time.perf_counter()
    hyb = run.rollout([h]).histories[0]
    wall = time.perf_counter() - start
    return fmh.with_tensions(hyb, case_model(sea, "table").components()["mooring"]), wall


def settings(pipe: HybridPipeline, dur: float, long_dur: float) -> dict[str, Any]:
    """What the results were computed with (seas, winds, partition, network)."""
    sea = lambda v: dict(zip(("hs", "tp", "seed", "wind_speed", "wind_seed"), v))  # noqa: E731
    return {"dofs": DOFS, "dt": DT, "ramp": RAMP, "turbulence_intensity": TI,
            "duration": dur, "long_duration": long_dur,
            "train": {k: sea(v) for k, v in TRAIN.items()},
            "held_out": {k: sea(v) for k, v in HELD.items()},
            "long": {k: sea(v) for k, v in LONG.items()},
            "partition": {"known": [*CANDIDATES, "linear_damping", "mooring (table)",
                                    "rotor (this run's wind)"],
                          "network": "MoorDyn - quasi-static mooring + slow drift + drag",
                          "inputs": list(pipe.inputs_)},
            "network": pipe.network_.get_params(), "mode": MODE}


def ship(dest: Path, out: dict[str, Any], series: dict[str, xr.Dataset]) -> None:
    """The JSON and the NetCDF of the held-out series (float32, compressed: < 2 MB)."""
    write_json(dest.with_suffix(".json"), out)
    ds = xr.concat(list(series.values()), dim="sea", combine_attrs="drop")
    ds = ds.assign_coords(sea=list(series))
    ds["most_loaded_line"] = ("sea", [s.attrs["most_loaded_line"] for s in series.values()])
    ds.attrs.update({"source": "scripts/oc3_moordyn_hybrid.py", "command": out["command"],
                     "provenance": json.dumps(out["provenance"])})
    for v in ("surge", "heave", "pitch", "tension"):
        ds[v].encoding = {"zlib": True, "complevel": 6, "dtype": "float32"}
    to_netcdf(ds, dest.with_suffix(".nc"))


def main(argv: list[str] | None = None) -> int:
    p = Parser(description=__doc__.splitlines()[0])
    p.add_argument("--work", type=Path, required=True, help="folder of the resumable runs")
    p.add_argument("--quick", action="store_true", help="300 s seas, nothing shipped")
    p.add_argument("--duration", type=float, default=1800.0, help="s per sea (default 1800)")
    p.add_argument("--long-duration", type=float, default=10800.0, help="s (default 3 h)")
    args = p.parse_args(argv)
    dur, long_dur = (300.0, 600.0) if args.quick else (args.duration, args.long_duration)
    work = args.work / ("quick" if args.quick else "full")
    work.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    model = case_model(TRAIN["train1"], "moordyn")
    refs = {n: cached(work, "moordyn", n, s, dur) for n, s in TRAIN.items()}
    _, pipe = train(work, refs, model)
    out: dict[str, Any] = {"held_out": {}, "prediction": fmh.prediction(pipe)}
    series = {}
    for name, sea in HELD.items():
        runs = {k: cached(work, k, name, sea, dur) for k in ("moordyn", "table", "linear")}
        runs["linear"] = fmh.with_tensions(runs["linear"],
                                           case_model(sea, "table").components()["mooring"])
        runs["hybrid"], wall = run_hybrid(pipe, runs["moordyn"], sea, model)
        series[name] = fmh.series(runs, ramp=RAMP)
        out["held_out"][name] = fmh.metrics(series[name])
        out["held_out"][name]["wall_s"] = {"hybrid": wall, **{
            k: float(runs[k].attrs.get("wall_s", np.nan)) for k in ("moordyn", "table",
                                                                    "linear")}}
        print(name, f"hybrid {wall:.1f} s wall", json.dumps(out["held_out"][name]["errors"]),
              flush=True)
    long_ref = cached(work, "table", "long", LONG["long"], long_dur)
    hyb, wall = run_hybrid(pipe, long_ref, LONG["long"], model)
    out["long"] = fmh.long_run(hyb, long_ref, ramp=RAMP, wall=wall)
    print(json.dumps(out["long"]), flush=True)
    out.update(settings(pipe, dur, long_dur))
    out["provenance"] = provenance("moordyn", "moorpy", "torch", "numpy")
    out["command"] = ("OPENBLAS_NUM_THREADS=1 PYTHONPATH=src nice -n 5 python "
                      "scripts/oc3_moordyn_hybrid.py --work WORK" + " --quick" * args.quick)
    out["wall_time_s"] = time.perf_counter() - t0
    dest = (work / "oc3_moordyn_hybrid") if args.quick else SHIP
    ship(dest, out, series)
    print(f"{out['wall_time_s']:.0f} s -> {dest}.json/.nc")
    return 0


if __name__ == "__main__":
    run_script(main)
