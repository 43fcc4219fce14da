"""Seed ensembles and the capacity of the Kramer hybrid's network (issue 14, the 0.3D target).

Two studies of the network residual of ``hybridwsi.surrogate.kramer`` (docs/KRAMER_HYBRID.md,
section "Ensembles and the network's capacity"):

``ensemble`` (leave one drop out, nothing chosen on the held-out drop)
    For each held-out drop H and each seed s, the network is trained exactly as shipped (one-step
    fit on the training drops' ``F_bb`` with ``seed=s``, then multi-step training on their heave
    with H's nested-LOO iteration count (``kramer.select_iterations``, as the study
    selects it) and the release lead of
    the structured fit on the same two drops) and rolled out on H alone. The ensemble's residual
    force is the mean of the K networks' forces inside ONE rollout: the K MLPs are merged into
    one block-diagonal MLP of the same inputs (normalisation folded into its end layers, output
    weights / K), so the stability prediction (``check_stability``) linearises the mean and the
    compiled rollout integrates one ODE. Seed 0 is the shipped network.

``capacity`` (diagnostic of the model class only, never used to choose what ships)
    The network trained on 0.3D's own heave (lead of the structured fit on 0.3D alone), with the
    inputs ``(z, ż)`` as shipped and with ``|ż|ż`` as a third input channel. The extra channel
    lives in this script only: the one-step fit puts ``|ż|ż`` in the history's ``zddot`` slot of
    a ``ForceNetwork(inputs=(z, zdot, zddot))``, and :class:`AbsDragInput` appends it to
    ``(z, ż)`` inside ``forward``, so the torch training/rollout (``torch_decays``) sees the
    same equation. The decay-table RMS of both comes from ``torch_decays`` (RK4, 1 ms), the
    plain network's also from the shipped lagged rollout, for comparison.

Rows are appended to ``results/kramer_ensemble/runs.jsonl`` (one per fold/seed, per ensemble,
per capacity run) and networks saved beside it, so a run can be stopped and resumed.

Run (one core): ``PYTHONPATH=src OMP_NUM_THREADS=1 python scripts/kramer_ensemble.py ensemble``
then ``... capacity --iterations 150``; ``... table`` prints the summary.
"""

from __future__ import annotations

import copy
import json
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from hybridwsi.cli import Parser, run_script
from hybridwsi.history import atomic_write
from hybridwsi.importers.kramer import read_kramer_drop
from hybridwsi.surrogate import kramer as kh
from hybridwsi.surrogate import multistep as ms
from hybridwsi.surrogate import structured as st

OUT = Path("results/kramer_ensemble")
RUNS = OUT / "runs.jsonl"


# --------------------------------------------------------------------------- bookkeeping
def load_rows() -> list[dict[str, Any]]:
    """All rows written so far."""
    if not RUNS.exists():
        return []
    return [json.loads(line) for line in RUNS.read_text().splitlines() if line.strip()]


def find(rows: list[dict[str, Any]], **key: Any) -> dict[str, Any] | None:
    """The last row whose fields equal ``key``."""
    hits = [r for r in rows if all(r.get(k) == v for k, v in key.items())]
    return hits[-1] if hits else None


def append(row: dict[str, Any]) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    # the whole file rewritten atomically: an interrupted run never leaves half a line
    text = (RUNS.read_text() if RUNS.exists() else "") + json.dumps(row) + "\n"
    atomic_write(RUNS, lambda tmp: Path(tmp).write_text(text))
    print(json.dumps({k: v for k, v in row.items() if not isinstance(v, (list, dict))}),
          flush=True)


def clock() -> tuple[float, float]:
    return time.perf_counter(), time.process_time()


def since(c: tuple[float, float]) -> dict[str, float]:
    return {"wall_s": round(time.perf_counter() - c[0], 1),
            "cpu_s": round(time.process_time() - c[1], 1)}


# --------------------------------------------------------------------------- shared data
class Data:
    """Set-up, measured histories and normalised experiment curves (built once)."""

    def __init__(self) -> None:
        self.setup = kh.kramer_setup()
        self.measured = {d: kh.measured_history(d, self.setup) for d in kh.DROPS}
        exp = {d: read_kramer_drop(d, normalised=True) for d in kh.DROPS}
        self.curves = {d: (exp[d]["time"].values, exp[d]["z"].values[:, 0]) for d in kh.DROPS}

    def lead(self, rows: list[dict[str, Any]], drops: list[str]) -> float:
        """Release lead δ [s] of the structured output-error fit on ``drops`` (cached)."""
        hit = find(rows, kind="lead", drops=drops)
        if hit:
            return float(hit["lead_s"])
        c = clock()
        _, lead, _ = st.fit_output_error(self.setup, {d: self.curves[d] for d in drops},
                                         np.zeros(len(st.STRUCTURED_TERMS)), kh.STRUCTURED_FREE,
                                         dt=kh.FIT_DT[False], fit_lead=True)
        row = {"kind": "lead", "drops": drops, "lead_s": float(lead), **since(c)}
        append(row)
        rows.append(row)
        return float(lead)

    def iterations(self, rows: list[dict[str, Any]], fold: str) -> int:
        """The fold's training length from the study's own nested selection (cached row)."""
        hit = find(rows, kind="selection", fold=fold)
        if hit:
            return int(hit["iterations"])
        c = clock()
        if not hasattr(self, "_study_data"):
            self._study_data, self._alone = kh.KramerData.load(self.setup), {}
        sel = kh.select_iterations([d for d in kh.DROPS if d != fold], self._study_data,
                                   kh.StudySettings(), self._alone)
        row = {"kind": "selection", "fold": fold, "iterations": sel["selected_iterations"],
               "inner_rms": sel["inner_rms"], "checkpoints": sel["checkpoints"], **since(c)}
        append(row)
        rows.append(row)
        return int(row["iterations"])

    def score(self, t: np.ndarray, z: np.ndarray, drop: str) -> dict[str, float]:
        """Decay-table RMS, period and decay rate of a heave run [m] released at t = 0 [s]."""
        h0 = self.setup.drop_heights[drop]
        return kh.decay_measures(t, z / h0, self.setup, *self.curves[drop])


def seeded_network(hists: list[Any], seed: int) -> Any:
    """``kramer.fit_network`` with another seed (everything else as shipped)."""
    return kh.fit_network(hists, seed=int(seed))


def mean_network(nets: list[Any]) -> Any:
    """One ``ForceNetwork`` whose force is exactly the mean of ``nets``' forces [N].

    Block-diagonal hidden layers (the K networks side by side), each network's input and
    output normalisation folded into the first and last layers (as ``surrogate.fast``
    does), output weights divided by K; the merged network's own scaler is the identity.
    """
    import torch

    from hybridwsi.surrogate.fast import folded_layers
    from hybridwsi.surrogate.network import build_mlp

    k = len(nets)
    folded = [folded_layers(n) for n in nets]  # weights (n_in, n_out), h @ W + b
    n_layers = len(folded[0].weights)
    ws, bs = [], []
    for layer in range(n_layers):
        w = [f.weights[layer] for f in folded]
        b = [f.biases[layer] for f in folded]
        if layer == 0:
            ws.append(np.concatenate(w, axis=1))
            bs.append(np.concatenate(b))
        elif layer == n_layers - 1:
            ws.append(np.concatenate(w, axis=0) / k)
            bs.append(np.mean(b, axis=0))
        else:
            out = np.zeros((sum(x.shape[0] for x in w), sum(x.shape[1] for x in w)))
            r = c = 0
            for x in w:
                out[r:r + x.shape[0], c:c + x.shape[1]] = x
                r, c = r + x.shape[0], c + x.shape[1]
            ws.append(out)
            bs.append(np.concatenate(b))
    merged = copy.deepcopy(nets[0])
    merged.hidden = tuple(k * h for h in nets[0].hidden)
    merged.model_ = build_mlp(ws[0].shape[0], ws[-1].shape[1], merged.hidden, merged.activation)
    lin = [m for m in merged.model_ if isinstance(m, torch.nn.Linear)]
    with torch.no_grad():
        for m, w, b in zip(lin, ws, bs):
            m.weight.copy_(torch.as_tensor(w.T))
            m.bias.copy_(torch.as_tensor(b))
    n_in, n_out = ws[0].shape[0], ws[-1].shape[1]
    merged.x_mean_, merged.x_std_ = np.zeros(n_in), np.ones(n_in)
    merged.y_mean_, merged.y_std_ = np.zeros(n_out), np.ones(n_out)
    merged._set_scaler()
    # the merge is exact: check it on the training drops' features
    x = np.random.default_rng(0).normal(size=(64, n_in)) * nets[0].x_std_ + nets[0].x_mean_
    want = np.mean([n.predict_features(x) for n in nets], axis=0)
    if not np.allclose(merged.predict_features(x), want, rtol=1e-10, atol=1e-10 * np.abs(want).max()):
        raise RuntimeError("merged network is not the mean of its members")
    return merged


def rolled(data: Data, net: Any, drop: str, train: list[str], lead: float) -> dict[str, Any]:
    """Shipped rollout (stability predicted first) of ``net`` on ``drop``, scored."""
    setup = data.setup
    roll = kh.roll_network(net, setup, drop, [data.measured[d] for d in train], setup.dt,
                           kh.ROLL_DURATION)
    t = roll["t"] - lead
    m = data.score(t, roll["z"], drop)
    return {"rms": m["rms"], "period_over_Te0": m["period_over_Te0"],
            "decay_rate": m["decay_rate"], "predicted_stable": roll["predicted_stable"],
            "observed_stable": roll["observed_stable"] and kh.decays(t, roll["z"], setup.te0),
            "spectral_radius": float(roll["spectral_radius"])}


# --------------------------------------------------------------------------- ensemble
def run_ensemble(folds: list[str], seeds: list[int]) -> None:
    from hybridwsi.surrogate.network import ForceNetwork

    data = Data()
    rows = load_rows()
    for fold in folds:
        train = [d for d in kh.DROPS if d != fold]
        lead = data.lead(rows, train)
        iters = data.iterations(rows, fold)
        for seed in seeds:
            if find(rows, kind="single", fold=fold, seed=seed):
                continue
            c = clock()
            net = seeded_network([data.measured[d] for d in train], seed)
            fit = ms.train_network_on_heave(net, data.setup,
                                            {d: data.curves[d] for d in train}, lead,
                                            iterations=iters)
            OUT.mkdir(parents=True, exist_ok=True)
            path, _ = net.save(OUT / f"net_{fold}_seed{seed}")
            row = {"kind": "single", "fold": fold, "seed": seed, "trained_on": train,
                   "iterations": iters, "release_lead_s": lead, "fit_rms": fit["rms"],
                   "fit_rms_start": fit["rms_start"], "epochs_one_step": net.n_epochs_,
                   **rolled(data, net, fold, train, lead), "net": path.name, **since(c)}
            append(row)
            rows.append(row)
        have = [find(rows, kind="single", fold=fold, seed=s) for s in seeds]
        if all(have) and not find(rows, kind="ensemble", fold=fold, seeds=seeds):
            c = clock()
            nets = [ForceNetwork.load(OUT / h["net"]) for h in have]
            merged = mean_network(nets)
            row = {"kind": "ensemble", "fold": fold, "seeds": seeds, "trained_on": train,
                   **rolled(data, merged, fold, train, lead),
                   "single_rms": [h["rms"] for h in have], **since(c)}
            append(row)
            rows.append(row)


# --------------------------------------------------------------------------- capacity
class AbsDragInput:
    """A ``ForceNetwork`` of ``(z, ż, |ż|ż)`` seen as a network of ``(z, ż)``.

    ``forward`` appends the channel, so :func:`multistep.torch_decays` and
    :func:`multistep.train_network_on_heave` use it unchanged (script only; the shipped
    rollout builds its channels from the history's z, ż, z̈, η).
    """

    inputs = ("z", "zdot")
    window = 1

    def __init__(self, inner: Any) -> None:
        self.inner = inner
        self.model_ = inner.model_

    def forward(self, x: Any) -> Any:
        import torch

        v = x[..., 1:2]
        return self.inner.forward(torch.cat([x, torch.abs(v) * v], dim=-1))


def abs_drag_network(hists: list[Any], seed: int) -> AbsDragInput:
    """One-step fit of the (z, ż, |ż|ż) network on ``F_bb`` (|ż|ż in the ``zddot`` slot)."""
    from hybridwsi.surrogate.network import ForceNetwork

    parts = []
    for hist in hists:
        h = kh.training_slice(hist).copy()
        v = h["zdot"].values
        h["zddot"] = (h["zdot"].dims, np.abs(v) * v)
        parts.append(h)
    inner = ForceNetwork(**{**kh.NETWORK, "seed": int(seed), "inputs": ("z", "zdot", "zddot")})
    inner.fit(parts, target=[h["F_bb"].values for h in parts])
    return AbsDragInput(inner)


def torch_scored(data: Data, net: Any, drop: str, lead: float, dt: float = 0.001
                 ) -> dict[str, float]:
    """Decay-table measures of ``net``'s hybrid on ``drop`` from :func:`torch_decays` (RK4)."""
    import torch

    n = int(round(kh.ROLL_DURATION / dt))
    with torch.no_grad():
        z = ms.torch_decays(net, data.setup, np.array([data.setup.drop_heights[drop]]), dt,
                            n).numpy()[0]
    t = np.arange(n + 1) * dt - lead
    return data.score(t, z, drop)


def run_capacity(drops: list[str], iterations: int, seeds: list[int], channels: list[str]
                 ) -> None:
    """Train on ``drops``' own heave and score each of them (no held-out drop).

    One drop: can the class reproduce that drop at all? All three: is there ONE force law of
    the class that reproduces every drop (the question a held-out score asks of two)?
    """
    data = Data()
    rows = load_rows()
    lead = data.lead(rows, drops)
    target = {d: data.curves[d] for d in drops}
    tag = {"drop": drops[0]} if len(drops) == 1 else {"drops": drops}
    for variant in channels:
        for seed in seeds:
            key = {"kind": "capacity", **tag, "channels": variant, "seed": seed,
                   "iterations": iterations}
            if find(rows, **key):
                continue
            c = clock()
            hists = [data.measured[d] for d in drops]
            net = seeded_network(hists, seed) if variant == "z,zdot" else \
                abs_drag_network(hists, seed)
            start = {d: torch_scored(data, net, d, lead)["rms"] for d in drops}
            fit = ms.train_network_on_heave(net, data.setup, target, lead,
                                            iterations=iterations, validation=target)
            row = {**key, "release_lead_s": lead, "fit_rms": fit["rms"],
                   "checkpoints": fit["checkpoints"], "fit_rms_every_10": fit["validation_rms"],
                   "rms_one_step_rk4": start,
                   "rms_rk4_1ms": {d: torch_scored(data, net, d, lead)["rms"] for d in drops}}
            if variant == "z,zdot":
                row["rms_rollout"] = {d: rolled(data, net, d, drops, lead)["rms"] for d in drops}
            row.update(since(c))
            append(row)
            rows.append(row)


# --------------------------------------------------------------------------- summary
def table() -> None:
    rows = load_rows()
    print("| held out | trained on | iterations | seeds 0..4 (single) | mean ± sd | "
          "ensemble | stable pred./obs. | wall of 5 trainings [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for fold in kh.DROPS:
        singles = sorted((r for r in rows if r["kind"] == "single" and r["fold"] == fold),
                         key=lambda r: r["seed"])
        ens = find(rows, kind="ensemble", fold=fold)
        if not singles:
            continue
        s = np.array([r["rms"] for r in singles])
        print(f"| {fold} | {', '.join(singles[0]['trained_on'])} | {singles[0]['iterations']} | "
              f"{' / '.join(f'{x:.4f}' for x in s)} | {s.mean():.4f} ± {s.std(ddof=1):.4f} | "
              f"{ens['rms']:.4f} | {ens['predicted_stable']}/{ens['observed_stable']} | "
              f"{sum(r['wall_s'] for r in singles):.0f} |" if ens else
              f"| {fold} | … | {' / '.join(f'{x:.4f}' for x in s)} | – | – |")
    caps = [r for r in rows if r["kind"] == "capacity"]
    if caps:
        print("\n| trained on (own heave) | channels | seed | iterations | scored drop | one-step "
              "(RK4) | after training (RK4 1 ms) | after training (shipped rollout) | wall [s] |")
        print("|---|---|---|---|---|---|---|---|---|")
        for r in caps:
            drops = r.get("drops", [r.get("drop")])

            def per(name: str, d: str, r: dict = r) -> float:  # scalar in one-drop rows
                v = r.get(name, float("nan"))
                return v.get(d, float("nan")) if isinstance(v, dict) else v

            for d in drops:
                print(f"| {', '.join(drops)} | {r['channels'].replace('|', chr(92) + '|')} | {r['seed']} | {r['iterations']} "
                      f"| {d} | {per('rms_one_step_rk4', d):.4f} | {per('rms_rk4_1ms', d):.4f} | "
                      f"{per('rms_rollout', d):.4f} | {r['wall_s']:.0f} |")


def main() -> None:
    import torch

    torch.set_num_threads(1)
    warnings.simplefilter("ignore")
    ap = Parser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("ensemble")
    e.add_argument("--folds", nargs="+", default=list(kh.DROPS))
    e.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2, 3, 4])
    c = sub.add_parser("capacity")
    c.add_argument("--drops", nargs="+", default=["03D"])
    c.add_argument("--iterations", type=int, default=150)
    c.add_argument("--seeds", nargs="+", type=int, default=[0])
    c.add_argument("--channels", nargs="+", default=["z,zdot", "z,zdot,|zdot|zdot"])
    sub.add_parser("table")
    args = ap.parse_args()
    if args.cmd == "ensemble":
        run_ensemble(args.folds, args.seeds)
    elif args.cmd == "capacity":
        run_capacity(args.drops, args.iterations, args.seeds, args.channels)
    table()


if __name__ == "__main__":
    run_script(main)
