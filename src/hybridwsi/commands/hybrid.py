"""``hybridwsi hybrid``: train a force network, check stability, roll out, report."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from hybridwsi.errors import InputError

HELP = "train the residual-force network of a partition, check stability, roll out on held-out runs"
DESCRIPTION = (
    "DATA is a sweep folder (hybridwsi sweep) or NetCDF histories with F_tot, F_exc, z, zdot, "
    "zddot. The last --test-fraction of the cases is held out. The network learns the residual "
    "of --partition; its linearisation predicts the stability of the --mode rollout (a "
    "predicted-unstable partition is refused unless --force); the rollout error on the held-out "
    "cases is written to OUT/report.json with the network (OUT/network.pt/.json)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", nargs="+", help="sweep folder / sweep.zarr, or history NetCDF files")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--coeffs", help="BEM coefficients NetCDF (default: from the sweep manifest "
                   "or the paper sphere)")
    p.add_argument("--partition", default="recommended",
                   choices=["recommended", "added_mass_to_network"])
    p.add_argument("--mode", default="lagged", choices=["lagged", "implicit"])
    p.add_argument("--test-fraction", type=float, default=0.2)
    p.add_argument("--max-cases", type=int, default=20, help="use at most this many cases")
    p.add_argument("--window", type=int, default=11)
    p.add_argument("--stride", type=int, default=None, help="tap spacing (default ≈ 0.1 s)")
    p.add_argument("--hidden", default="32", help="hidden widths, comma-separated")
    p.add_argument("--epochs", type=int, default=300)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--force", action="store_true", help="roll out even if predicted unstable")


def _load(data: list[str]):
    from hybridwsi.history import read_netcdf
    from hybridwsi.sweep import STORE, case_history, open_sweep

    hists, manifest = [], None
    for item in data:
        path = Path(item)
        if path.is_dir() and ((path / STORE).exists() or path.suffix == ".zarr"):
            sw = open_sweep(path)
            hists += [case_history(sw, i) for i in range(sw.sizes["case"])]
            mf = (path if path.suffix != ".zarr" else path.parent) / "manifest.json"
            manifest = json.loads(mf.read_text()) if mf.is_file() else manifest
        else:
            hists.append(read_netcdf(path))
    return hists, manifest


def run(args: argparse.Namespace) -> int:
    import torch

    from hybridwsi import __version__
    from hybridwsi.forces.linear import mass_from
    from hybridwsi.history import atomic_write, read_netcdf, time_step
    from hybridwsi.surrogate.demo import partitions
    from hybridwsi.surrogate.network import ForceNetwork
    from hybridwsi.surrogate.rollout import rollout

    torch.set_num_threads(1)
    if not 0 < args.test_fraction < 1:
        raise InputError("--test-fraction must be in (0, 1)")
    hists, manifest = _load(args.data)
    hists = hists[: args.max_cases]
    if len(hists) < 2:
        raise InputError("need at least two histories (one to train, one held out)")
    if args.coeffs:
        coeffs = read_netcdf(args.coeffs)
    elif manifest and manifest["config"].get("coeffs"):
        coeffs = read_netcdf(manifest["config"]["coeffs"])
    else:
        from hybridwsi.sweep import load_coefficients

        coeffs = load_coefficients()
    mass = mass_from(hists[0], coeffs)
    if mass is None:
        raise InputError("neither the histories nor the coefficients carry a 'mass'")
    part = partitions(coeffs, hists[0])[args.partition]
    n_test = max(1, round(args.test_fraction * len(hists)))
    train, test = hists[:-n_test], hists[-n_test:]
    dt = time_step(train[0])
    net = ForceNetwork(inputs=part["inputs"], window=args.window,
                       stride=args.stride or max(1, round(0.1 / dt)),
                       hidden=tuple(int(h) for h in args.hidden.split(",") if h),
                       max_epochs=args.epochs, lr=3e-3, patience=30, batch_size=128,
                       seed=args.seed).fit(train, "F_bb", known=part["known"], progress=True)
    out = Path(args.out)
    net.save(out / "network")
    res = rollout(net, test, mass=mass, known=part["known"], mode=args.mode, force=args.force,
                  reference_for_check=train, progress=True)
    errors = res.errors(test)
    report = {
        "hybridwsi_version": __version__,
        "inputs": {"data": args.data, "partition": args.partition, "mode": args.mode,
                   "n_train": len(train), "n_test": n_test, "network": net.get_params()},
        "known": [k.describe() for k in part["known"]],
        "stability": res.prediction.to_dict() if res.prediction else None,
        "held_out_rms_error_z": errors.tolist(),
        "held_out_r2_force": [net.score(h, "F_bb", known=part["known"]) for h in test],
        "observed_unstable": res.blew_up.tolist(),
    }
    text = json.dumps(report, indent=1, default=str)
    atomic_write(out / "report.json", lambda tmp: Path(tmp).write_text(text))
    pred = res.prediction
    print(f"partition {args.partition} ({args.mode}): spectral radius "
          f"{pred.spectral_radius:.5f}, |alpha_s|/(m+A_k) = {pred.added_mass_ratio:.3f}; "
          f"held-out rms error of z: {', '.join(f'{e:.3f}' for e in errors)}")
    return 0
