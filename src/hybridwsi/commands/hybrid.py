"""``hybridwsi hybrid``: train a force network, check stability, roll out, report."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from hybridwsi import __version__
from hybridwsi.casemodel import CaseModel
from hybridwsi.commands import _options as o
from hybridwsi.commands._options import read_dofs, require
from hybridwsi.errors import InputError
from hybridwsi.files import check_output_path, write_json
from hybridwsi.history import select_dofs, time_step
from hybridwsi.hydro.formats import read_coefficients
# a --case sweep's coefficients, else the paper sphere's
from hybridwsi.sweep import STORE, case_history, open_sweep, sweep_coefficients

HELP = ("train the residual-force network of a partition, check its stability, roll out; "
        "with --case: write a certified model folder for simulate --network")
DESCRIPTION = (
    "DATA is a sweep folder (hybridwsi sweep) or histories (NetCDF; with --eta any format the "
    "importers read) with z, zdot, zddot and F_tot, F_exc. The network learns the residual "
    "of --partition; its linearisation predicts the stability of the --mode rollout (a "
    "predicted-unstable partition is refused unless --allow-unstable). Without --case the "
    "last --test-fraction of the cases is held out and OUT/report.json gets the rollout error "
    "with the network (OUT/network.pt/.json). With --case NAME|FILE OUT is a model folder "
    "(model.json: the case's hash, DOFs, partition (the case's linearised mooring and "
    "linear damping known besides it), mass, dt, coupling, features, training "
    "files' SHA-256, training envelope, held-out errors, stability certificate; network.pt/"
    ".json) that simulate --case ... --network OUT runs on new seas; histories may lack "
    "F_exc (computed from eta through the case's excitation transfer function) and F_tot "
    "(M zddot), and the last --test-fraction of each history is held out."
)
#: ForceNetwork settings without --case, or when the case's [hybrid.network] lacks them
NETWORK_DEFAULTS = {"window": 11, "hidden": (32,), "max_epochs": 300, "lr": 3e-3,
                    "patience": 30, "batch_size": 128, "seed": 0}
#: option -> ForceNetwork parameter
NETWORK_OPTIONS = {"feature_window": "window", "feature_stride": "stride",
                   "feature_lead": "lead", "hidden": "hidden", "epochs": "max_epochs",
                   "learning_rate": "lr", "patience": "patience", "batch_size": "batch_size",
                   "train_seed": "seed"}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", nargs="+", metavar="DATA",
                   help="sweep folder / sweep.zarr, or history files")
    o.add_out(p, "output folder (without --case: network.pt, network.json, report.json; with "
                 "--case: the model folder, model.json, network.pt, network.json)",
              required=True, metavar="DIR")
    o.add_case(p, "write a certified model folder of this case (its coefficients and "
                  "hash; simulate --network runs it)")
    p.add_argument("--quick", action="store_true",
                   help="with --case: the coarse [bem_quick] coefficients (tests)")
    o.add_coeffs(p, "default: the case's, else from the sweep manifest (its file or its "
                    "case), else the paper sphere's")
    o.add_dofs(p, "the DOFs of the histories to use (default: all of them)")
    o.add_eta(p)
    p.add_argument("--partition", default=None, metavar="NAME|auto",
                   help="force partition whose residual the network learns: auto (the "
                        "diagnostic's recommended partition, default with --case), "
                        "recommended (default without), added_mass_to_network, or known "
                        "components joined by '+' (e.g. hydrostatic+added_mass_inf+"
                        "radiation_memory+excitation)")
    p.add_argument("--mode", default="lagged", choices=["lagged", "corrected", "implicit"],
                   help="coupling of the network in the time step: lagged (explicit, previous "
                        "step's kinematics), corrected (lagged then re-evaluated at the predicted "
                        "end of step, --corrections times) or implicit (iterated to convergence)")
    p.add_argument("--corrections", type=o.positive_int, default=None, metavar="K",
                   help="with --mode corrected: re-evaluations per step (default: the fewest "
                        "even number that cuts the added-mass error to 1 %%, from the network's "
                        "predicted added-mass ratio)")
    p.add_argument("--test-fraction", type=o.fraction, default=0.2,
                   help="fraction of the data held out for testing: the last cases, or with "
                        "--case the last part of each history (default 0.2)")
    p.add_argument("--max-cases", type=o.positive_int, default=20,
                   help="use at most this many cases (default 20)")
    _network_arguments(p, o)
    p.add_argument("--allow-unstable", action="store_true",
                   help="roll out even if the partition is predicted unstable")
    o.add_quiet(p)


def _network_arguments(p: argparse.ArgumentParser, o: Any) -> None:
    """The ForceNetwork options (default: the case's [hybrid.network], else
    :data:`NETWORK_DEFAULTS`)."""
    case = "the case's [hybrid.network], else "
    p.add_argument("--feature-window", type=o.positive_int, default=None, metavar="N",
                   help=f"past samples (taps) of each network input (default: {case}11)")
    p.add_argument("--feature-stride", type=o.positive_int, default=None, metavar="N",
                   help=f"samples between taps (default: {case}about 0.1 s)")
    p.add_argument("--feature-lead", type=o.nonnegative_int, default=None, metavar="N",
                   help=f"samples the wave elevation input is read ahead (default: {case}0)")
    p.add_argument("--hidden", type=o.positive_ints, default=None, metavar="W[,W...]",
                   help=f"hidden layer widths, comma-separated (default: {case}32)")
    p.add_argument("--epochs", type=o.positive_int, default=None,
                   help=f"maximum training epochs (default: {case}300)")
    p.add_argument("--learning-rate", type=o.positive_float, default=None, metavar="LR",
                   help=f"Adam learning rate (default: {case}3e-3)")
    p.add_argument("--patience", type=o.positive_int, default=None,
                   help="epochs without validation improvement before stopping (default: "
                        f"{case}30)")
    p.add_argument("--batch-size", type=o.positive_int, default=None,
                   help=f"training mini-batch size [samples] (default: {case}128)")
    p.add_argument("--train-seed", type=o.nonnegative_int, default=None,
                   help="random seed of the network initialisation and batch order (default: "
                        f"{case}0)")


#: files written into --out without --case
PRODUCTS = ("network.pt", "network.json", "report.json")

#: largest hidden width accepted (a wider layer is a typo, and its weights would not fit)
MAX_WIDTH = 65536


def _open_sweep(path: Path):
    """:func:`hybridwsi.sweep.open_sweep`, with a corrupt store as one InputError."""
    try:
        return open_sweep(path)
    except InputError:
        raise
    except Exception as exc:  # zarr/xarray raise many types on a damaged or fake store
        raise InputError(f"cannot read the sweep store {path}: {type(exc).__name__}: "
                         f"{exc}") from None


def _load(data: list[str], dofs: tuple[str, ...] | None, eta: str | None = None):
    """``(histories, names, manifest)`` of DATA: every case of a sweep store
    (``PATH[case i]``), every history file."""
    hists, names, manifest = [], [], None
    for item in data:
        path = Path(item)
        if path.is_dir() and ((path / STORE).exists() or path.suffix == ".zarr"):
            sw = _open_sweep(path)
            hists += [select_dofs(case_history(sw, i), dofs, what=str(path))
                      for i in range(sw.sizes["case"])]
            names += [f"{path}[case {i}]" for i in range(sw.sizes["case"])]
            mf = (path if path.suffix != ".zarr" else path.parent) / "manifest.json"
            manifest = json.loads(mf.read_text()) if mf.is_file() else manifest
        else:
            # histories are NetCDF; with --eta any format the importers read (a CSV or an
            # OpenFAST record with its wave-elevation column)
            hists.append(read_dofs(str(path), dofs, format="auto" if eta else "netcdf",
                                   eta=eta))
            names.append(str(path))
    return hists, names, manifest


def _network_settings(args: argparse.Namespace, case: Any = None, dt: float = 0.1
                      ) -> dict[str, Any]:
    """ForceNetwork settings: the options given, else the case's ``[hybrid.network]``, else
    :data:`NETWORK_DEFAULTS` (the stride: about 0.1 s)."""
    from hybridwsi.surrogate.network import ForceNetwork

    table = dict((case or {}).get("hybrid", {}).get("network", {})) if case else {}
    params = set(ForceNetwork().get_params()) - {"inputs"}
    out = {**NETWORK_DEFAULTS, "stride": max(1, round(0.1 / dt)),
           **{k: v for k, v in table.items() if k in params}}
    for opt, key in NETWORK_OPTIONS.items():
        if getattr(args, opt) is not None:
            out[key] = getattr(args, opt)
    out["hidden"] = tuple(out["hidden"])
    if max(out["hidden"]) > MAX_WIDTH:
        raise InputError(f"--hidden widths must be at most {MAX_WIDTH}, got "
                         f"{','.join(map(str, out['hidden']))}")
    return out


def _pipeline(args: argparse.Namespace, settings: dict[str, Any], default_partition: str,
              known_extra: list | tuple = ()):
    from hybridwsi.surrogate.pipeline import HybridPipeline

    return HybridPipeline(args.partition or default_partition, mode=args.mode,
                          corrections=args.corrections, network=settings,
                          known_extra=known_extra,
                          allow_unstable=args.allow_unstable, progress=not args.quiet)


def run(args: argparse.Namespace) -> int:
    from hybridwsi.surrogate.rollout import UnstablePartitionError

    require("torch")
    import torch

    torch.set_num_threads(1)
    certified = args.case is not None
    if certified:
        from hybridwsi.surrogate.certified import PRODUCTS as MODEL_FILES
    check_output_path(args.out, [*args.data, args.coeffs], kind="dir",
                      products=MODEL_FILES if certified else PRODUCTS)
    _network_settings(args)  # refuse a bad --hidden before reading any data
    try:
        return _run_certified(args) if certified else _run_histories(args)
    except UnstablePartitionError as exc:  # name this command's option, not the library's
        raise InputError(f"{exc.reason} (pass --allow-unstable to run anyway)") from None


def _run_certified(args: argparse.Namespace) -> int:
    """``--case``: train and certify a model folder (:mod:`hybridwsi.surrogate.certified`)."""
    from hybridwsi.surrogate.certified import case_linear, train_model

    hists, names, _ = _load(args.data, args.dofs, args.eta)
    hists, names = hists[: args.max_cases], names[: args.max_cases]
    dofs = args.dofs or tuple(str(d) for d in hists[0]["dof"].values)
    model = CaseModel.build(args.case, dofs=dofs, coeffs=args.coeffs, quick=args.quick,
                            progress=not args.quiet)
    settings = _network_settings(args, model.case, time_step(hists[0]))
    pipe = _pipeline(args, settings, "auto", case_linear(model))
    cm = train_model(hists, names, model, pipeline=pipe, test_fraction=args.test_fraction)
    cm.save(args.out)  # only once certified: nothing written on a refusal
    if not args.quiet:
        cert, doc = cm.doc["certificate"], cm.doc
        top = cert["max_stable_dt"]
        print(f"partition {doc['partition']['name']} ({doc['coupling']['mode']}): spectral "
              f"radius {cert['spectral_radius']:.5f} at dt {doc['dt']:g} s, "
              f"|alpha_s|/(m+A_k) = {cert['added_mass_ratio']:.3f}, largest stable dt "
              f"{'inf' if top is None else f'{top:.4g} s'}")
        for name, err in zip(names, doc["held_out"]["nrms_z"]):
            print(f"  held-out rms error of z ({name}): "
                  + ", ".join(f"{d} {100 * e:.2f} %" for d, e in err.items()))
        print(f"-> {args.out}")
    return 0


def _coefficients(args: argparse.Namespace, manifest: dict | None):

    if args.coeffs:
        return read_coefficients(args.coeffs, assume_seawater=True)
    if manifest and manifest["config"].get("coeffs"):
        return read_coefficients(manifest["config"]["coeffs"], assume_seawater=True)

    return sweep_coefficients(manifest or {})


def _run_histories(args: argparse.Namespace) -> int:
    """Without ``--case``: train on the first cases, roll out the held-out ones, report."""
    if args.quick:
        raise InputError("--quick needs --case")
    hists, _, manifest = _load(args.data, args.dofs, args.eta)
    hists = hists[: args.max_cases]
    if len(hists) < 2:
        raise InputError("need at least two histories (one to train, one held out)")
    coeffs = _coefficients(args, manifest)
    n_test = max(1, round(args.test_fraction * len(hists)))
    train, test = hists[:-n_test], hists[-n_test:]
    settings = _network_settings(args, None, time_step(train[0]))
    pipe = _pipeline(args, settings, "recommended").fit(train, coeffs)
    res = pipe.rollout(test, progress=not args.quiet)
    out = Path(args.out)
    pipe.network_.save(out / "network")  # only once accepted: no network left on refusal
    errors = res.errors(test)
    pred = pipe.stability_
    report = {
        "hybridwsi_version": __version__,
        "inputs": {"data": args.data, "partition": pipe.partition_, "mode": args.mode,
                   "n_train": len(train), "n_test": n_test,
                   "network": pipe.network_.get_params()},
        "known": [k.describe() for k in pipe.known_],
        "stability": pred.to_dict(),
        "held_out_rms_error_z": errors.tolist(),
        "held_out_r2_force": pipe.score(test),
        "observed_unstable": res.blew_up.tolist(),
    }
    write_json(out / "report.json", report, indent=1)
    if not args.quiet:
        print(f"partition {pipe.partition_} ({args.mode}): spectral radius "
              f"{pred.spectral_radius:.5f}, |alpha_s|/(m+A_k) = {pred.added_mass_ratio:.3f}; "
              f"held-out rms error of z: {', '.join(f'{e:.3f}' for e in errors)}")
    return 0
