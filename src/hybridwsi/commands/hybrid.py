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
    "predicted-unstable partition is refused unless --allow-unstable); the rollout error on the held-out "
    "cases is written to OUT/report.json with the network (OUT/network.pt/.json)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    from hybridwsi.commands import _options as o

    p.add_argument("data", nargs="+", metavar="DATA",
                   help="sweep folder / sweep.zarr, or history NetCDF files")
    o.add_out(p, "output folder (network.pt, network.json, report.json)", required=True,
              metavar="DIR")
    o.add_coeffs(p, "default: from the sweep manifest (its file or its case), else the "
                      "paper sphere's")
    o.add_dofs(p, "the DOFs of the histories to use (default: all of them)")
    o.add_eta(p)
    p.add_argument("--partition", default="recommended",
                   choices=["recommended", "added_mass_to_network"],
                   help="force partition whose residual the network learns (default recommended)")
    p.add_argument("--mode", default="lagged", choices=["lagged", "corrected", "implicit"],
                   help="coupling of the network in the time step: lagged (explicit, previous "
                        "step's kinematics), corrected (lagged then re-evaluated at the predicted "
                        "end of step, --corrections times) or implicit (iterated to convergence)")
    p.add_argument("--corrections", type=o.positive_int, default=None, metavar="K",
                   help="with --mode corrected: re-evaluations per step (default: the fewest "
                        "even number that cuts the added-mass error to 1 %%, from the network's "
                        "predicted added-mass ratio)")
    p.add_argument("--test-fraction", type=o.fraction, default=0.2,
                   help="fraction of the cases held out for testing, the last ones (default 0.2)")
    p.add_argument("--max-cases", type=o.positive_int, default=20,
                   help="use at most this many cases (default 20)")
    p.add_argument("--feature-window", type=o.positive_int, default=11, metavar="N",
                   help="past samples (taps) of each network input (default 11)")
    p.add_argument("--feature-stride", type=o.positive_int, default=None, metavar="N",
                   help="samples between taps (default: about 0.1 s)")
    p.add_argument("--hidden", type=o.positive_ints, default=(32,), metavar="W[,W...]",
                   help="hidden layer widths, comma-separated (default 32)")
    p.add_argument("--epochs", type=o.positive_int, default=300,
                   help="maximum training epochs (default 300)")
    p.add_argument("--learning-rate", type=o.positive_float, default=3e-3, metavar="LR",
                   help="Adam learning rate (default 3e-3)")
    p.add_argument("--patience", type=o.positive_int, default=30,
                   help="epochs without validation improvement before stopping (default 30)")
    p.add_argument("--batch-size", type=o.positive_int, default=128,
                   help="training mini-batch size [samples] (default 128)")
    p.add_argument("--train-seed", type=o.nonnegative_int, default=0,
                   help="random seed of the network initialisation and batch order (default 0)")
    p.add_argument("--allow-unstable", action="store_true",
                   help="roll out even if the partition is predicted unstable")
    o.add_quiet(p)


#: files written into --out
PRODUCTS = ("network.pt", "network.json", "report.json")

#: largest hidden width accepted (a wider layer is a typo, and its weights would not fit)
MAX_WIDTH = 65536


def _open_sweep(path: Path):
    """:func:`hybridwsi.sweep.open_sweep`, with a corrupt store as one InputError."""
    from hybridwsi.sweep import open_sweep

    try:
        return open_sweep(path)
    except InputError:
        raise
    except Exception as exc:  # zarr/xarray raise many types on a damaged or fake store
        raise InputError(f"cannot read the sweep store {path}: {type(exc).__name__}: "
                         f"{exc}") from None


def _load(data: list[str], dofs: tuple[str, ...] | None, eta: str | None = None):
    from hybridwsi.commands._options import read_dofs
    from hybridwsi.history import select_dofs
    from hybridwsi.sweep import STORE, case_history

    hists, manifest = [], None
    for item in data:
        path = Path(item)
        if path.is_dir() and ((path / STORE).exists() or path.suffix == ".zarr"):
            sw = _open_sweep(path)
            hists += [select_dofs(case_history(sw, i), dofs, what=str(path))
                      for i in range(sw.sizes["case"])]
            mf = (path if path.suffix != ".zarr" else path.parent) / "manifest.json"
            manifest = json.loads(mf.read_text()) if mf.is_file() else manifest
        else:
            # histories are NetCDF; with --eta any format the importers read (a CSV or an
            # OpenFAST record with its wave-elevation column)
            hists.append(read_dofs(str(path), dofs, format="auto" if eta else "netcdf",
                                   eta=eta))
    return hists, manifest


def run(args: argparse.Namespace) -> int:
    from hybridwsi.commands._options import require

    require("torch")
    import torch

    from hybridwsi import __version__
    from hybridwsi.files import check_output_path, write_json
    from hybridwsi.forces.linear import mass_from
    from hybridwsi.history import time_step
    from hybridwsi.hydro.formats import read_coefficients
    from hybridwsi.surrogate.demo import partitions
    from hybridwsi.surrogate.network import ForceNetwork
    from hybridwsi.surrogate.rollout import (
        UnstablePartitionError,
        check_stability,
        corrections_for,
        rollout,
    )

    torch.set_num_threads(1)
    check_output_path(args.out, [*args.data, args.coeffs], kind="dir", products=PRODUCTS)
    if max(args.hidden) > MAX_WIDTH:
        raise InputError(f"--hidden widths must be at most {MAX_WIDTH}, got "
                         f"{','.join(map(str, args.hidden))}")
    hists, manifest = _load(args.data, args.dofs, args.eta)
    hists = hists[: args.max_cases]
    if len(hists) < 2:
        raise InputError("need at least two histories (one to train, one held out)")
    if args.coeffs:
        coeffs = read_coefficients(args.coeffs, assume_seawater=True)
    elif manifest and manifest["config"].get("coeffs"):
        coeffs = read_coefficients(manifest["config"]["coeffs"], assume_seawater=True)
    else:  # a --case sweep's coefficients, else the paper sphere's
        from hybridwsi.sweep import sweep_coefficients

        coeffs = sweep_coefficients(manifest or {})
    mass = mass_from(hists[0], coeffs)
    if mass is None:
        raise InputError("neither the histories nor the coefficients carry a 'mass'")
    part = partitions(coeffs, hists[0])[args.partition]
    n_test = max(1, round(args.test_fraction * len(hists)))
    train, test = hists[:-n_test], hists[-n_test:]
    dt = time_step(train[0])
    net = ForceNetwork(inputs=part["inputs"], window=args.feature_window,
                       stride=args.feature_stride or max(1, round(0.1 / dt)),
                       hidden=tuple(args.hidden), max_epochs=args.epochs,
                       lr=args.learning_rate, patience=args.patience,
                       batch_size=args.batch_size, seed=args.train_seed,
                       ).fit(train, "F_bb", known=part["known"], progress=not args.quiet)
    try:
        n_corr = 1
        if args.mode == "corrected":
            n_corr = args.corrections or corrections_for(check_stability(
                net, train, mass=mass, known=part["known"], mode="corrected").added_mass_ratio)
        res = rollout(net, test, mass=mass, known=part["known"], mode=args.mode,
                      corrections=n_corr, force=args.allow_unstable, reference_for_check=train,
                      progress=not args.quiet)
    except UnstablePartitionError as exc:  # name this command's option, not the library's
        raise InputError(f"{exc.reason} (pass --allow-unstable to run anyway)") from None
    out = Path(args.out)
    net.save(out / "network")  # only once the rollout is accepted: no network left on refusal
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
    write_json(out / "report.json", report, indent=1)
    pred = res.prediction
    if not args.quiet:
        print(f"partition {args.partition} ({args.mode}): spectral radius "
          f"{pred.spectral_radius:.5f}, |alpha_s|/(m+A_k) = {pred.added_mass_ratio:.3f}; "
          f"held-out rms error of z: {', '.join(f'{e:.3f}' for e in errors)}")
    return 0
