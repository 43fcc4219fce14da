"""Feed-forward force network ``F_net = N_theta(x)`` (paper Eq. 1), scikit-learn style.

``ForceNetwork(...).fit(histories, target="F_bb", known=[...])`` learns the residual force of a
partition from a window of past kinematics (see :mod:`hybridwsi.surrogate.features`);
``predict`` evaluates it; ``save``/``load`` write a ``.pt`` state dict plus JSON metadata
(architecture, normalisation, inputs, version). Learned attributes end in ``_``.

Inputs and outputs are standardised (mean/std stored with the model) so that the physical-unit
network ``x -> F`` is what :mod:`hybridwsi.surrogate.linearise` differentiates.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.forces import KnownComponent, black_box_force
from hybridwsi._meta import version
from hybridwsi.errors import InputError
from hybridwsi.history import atomic_write, check_compatible
from hybridwsi.surrogate.features import FeatureSpec, build_features, spec_for

try:  # torch is the optional "ml" extra
    import torch
    from torch import nn
except ImportError:  # pragma: no cover - exercised only without the extra
    torch = None
    nn = None

ACTIVATIONS = ("tanh", "relu", "gelu", "silu")
Target = str | Callable[[xr.Dataset], np.ndarray] | np.ndarray | Sequence[np.ndarray]


def _require_torch() -> None:
    if torch is None:
        raise InputError("the force network needs PyTorch: pip install 'hybridwsi[ml]'")


def build_mlp(n_in: int, n_out: int, hidden: Sequence[int], activation: str) -> Any:
    """``Linear -> act -> ... -> Linear`` (float64 so Jacobians match the numpy solver)."""
    _require_torch()
    act = {"tanh": nn.Tanh, "relu": nn.ReLU, "gelu": nn.GELU, "silu": nn.SiLU}[activation]
    layers: list[Any] = []
    width = n_in
    for h in hidden:
        layers += [nn.Linear(width, int(h)), act()]
        width = int(h)
    layers.append(nn.Linear(width, n_out))
    return nn.Sequential(*layers).double()


def activation_function(name: str) -> Callable[[Any], Any]:
    """The torch function of a hidden activation of :func:`build_mlp` (by its name)."""
    _require_torch()
    return {"tanh": torch.tanh, "relu": torch.relu, "gelu": nn.functional.gelu,
            "silu": nn.functional.silu}[name]


def _check_training_set(histories: Sequence[xr.Dataset], targets: Sequence[np.ndarray]) -> None:
    """Refuse a training set the network cannot learn one force law from.

    All histories must share the DOFs, the time step (the window taps are time lags in
    samples) and the rigid-body mass (the residual force depends on it):
    :func:`hybridwsi.history.check_compatible`; and every target force [N] must be finite (one
    NaN turns the loss, and R², into NaN).
    """
    check_compatible(histories)  # one time step, one body (hybridwsi.history)
    for i, y in enumerate(targets):
        _check_finite(y, f"target force of training history {i}")


def _as_list(histories: xr.Dataset | Sequence[xr.Dataset]) -> list[xr.Dataset]:
    hs = [histories] if isinstance(histories, xr.Dataset) else list(histories)
    if not hs or not all(isinstance(h, xr.Dataset) for h in hs):
        raise InputError("expected a TimeHistory (xarray.Dataset) or a list of them")
    return hs


def target_force(
    hist: xr.Dataset,
    target: Target,
    known: Sequence[KnownComponent] = (),
    force: str = "F_tot",
    index: int = 0,
) -> np.ndarray:
    """The training target of one history, shape (n_time, n_dof) [N].

    ``"F_bb"`` (unless the history has a variable of that name) means ``force`` minus the
    ``known`` components (paper Eq. 3); another string names a force variable; a callable is
    called with the history; an array (or a list of arrays, one per history) is used as is.
    NaN/inf values raise :class:`~hybridwsi.errors.InputError`.
    """
    y = _raw_target(hist, target, known, force, index)
    _check_finite(y, "target force")
    return y


def _raw_target(hist: xr.Dataset, target: Target, known: Sequence[KnownComponent], force: str,
                index: int, n_out: int | None = None) -> np.ndarray:
    """:func:`target_force` without the finiteness check, shape (n_time, n_dof) [N] (or
    (n_time, ``n_out``): an output head's target, not a force on the DOFs)."""
    if isinstance(target, str):
        if target == "F_bb" and "F_bb" not in hist:
            return black_box_force(hist, force, list(known))
        if target not in hist:
            raise InputError(f"history has no target force '{target}'")
        y = np.asarray(hist[target].values, dtype=float)
    elif callable(target):
        y = np.asarray(target(hist), dtype=float)
    else:
        arr = target[index] if isinstance(target, (list, tuple)) else target
        y = np.asarray(arr, dtype=float)
    y = y[:, None] if y.ndim == 1 else y
    width, what = (hist.sizes["dof"], "n_dof") if n_out is None else (n_out, "n_out")
    if y.shape != (hist.sizes["time"], width):
        raise InputError(f"target has shape {y.shape}; expected (n_time, {what}) = "
                         f"({hist.sizes['time']}, {width})")
    return y


def _check_finite(y: np.ndarray, what: str) -> None:
    """Raise InputError naming the first row of ``y`` (n_time, n_dof) that is NaN/inf."""
    bad = ~np.isfinite(y)
    if bad.any():
        raise InputError(f"{what} has {int(bad.sum())} NaN/inf value(s), first at row "
                         f"{int(np.argwhere(bad)[0][0])}")


class ForceNetwork:
    """Multilayer perceptron predicting a residual force from a kinematics window.

    Parameters
    ----------
    hidden : tuple of int
        Hidden-layer widths.
    activation : {"tanh", "relu", "gelu", "silu"}
        Hidden activation (smooth ones give meaningful Jacobians).
    window : int
        Past samples per input channel (lag 0 = current step).
    inputs : tuple of str
        Channels among ``"z"`` [m], ``"zdot"`` [m/s], ``"zddot"`` [m/s^2], ``"eta"`` [m].
    stride : int
        Spacing of the window's taps [time steps].
    lead : int
        ``eta`` is taken ``lead`` steps ahead (the wave is a known input; excitation is
        non-causal in it).
    lr : float
        Adam learning rate.
    max_epochs, batch_size, patience : int
        Training length, minibatch size and early-stopping patience (epochs without a
        validation improvement).
    val_fraction : float
        Fraction of each history (its last samples, so neighbours do not leak) used for
        validation.
    weight_decay : float
        Adam L2 penalty.
    input_noise : float
        Std of Gaussian noise added to the standardised inputs while training (regularises
        the collinear window taps, which keeps the network stable in closed loop).
    seed : int
        Seed of weight initialisation and shuffling (``torch.manual_seed``).
    device : str
        Torch device.
    """

    def __init__(
        self,
        hidden: Sequence[int] = (64, 64),
        activation: str = "tanh",
        window: int = 1,
        inputs: Sequence[str] = ("z", "zdot", "zddot"),
        stride: int = 1,
        lead: int = 0,
        lr: float = 1e-3,
        max_epochs: int = 500,
        batch_size: int = 256,
        patience: int = 30,
        val_fraction: float = 0.2,
        weight_decay: float = 0.0,
        input_noise: float = 0.0,
        seed: int = 0,
        device: str = "cpu",
    ) -> None:
        self.hidden = tuple(int(h) for h in hidden)
        self.activation = activation
        self.window = int(window)
        self.inputs = tuple(inputs)
        self.stride = int(stride)
        self.lead = int(lead)
        self.lr = float(lr)
        self.max_epochs = int(max_epochs)
        self.batch_size = int(batch_size)
        self.patience = int(patience)
        self.val_fraction = float(val_fraction)
        self.weight_decay = float(weight_decay)
        self.input_noise = float(input_noise)
        self.seed = int(seed)
        self.device = device

    # -- parameters ---------------------------------------------------------------------
    def get_params(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in (
            "hidden", "activation", "window", "inputs", "stride", "lead", "lr", "max_epochs",
            "batch_size", "patience", "val_fraction", "weight_decay", "input_noise", "seed",
            "device")}

    def _check_params(self) -> None:
        _require_torch()
        if self.activation not in ACTIVATIONS:
            raise InputError(f"activation must be one of {', '.join(ACTIVATIONS)}, got '{self.activation}'")
        if not 0.0 <= self.val_fraction < 0.9:
            raise InputError(f"val_fraction must be in [0, 0.9), got {self.val_fraction}")
        if self.max_epochs < 1 or self.batch_size < 1 or self.lr <= 0:
            raise InputError("max_epochs and batch_size must be >= 1 and lr > 0")

    # -- data ---------------------------------------------------------------------------
    def _dataset(self, hs: list[xr.Dataset], target: Target, known, force: str,
                 n_out: int | None = None):
        xs_tr, ys_tr, xs_va, ys_va = [], [], [], []
        targets = [_raw_target(h, target, known, force, i, n_out) for i, h in enumerate(hs)]
        _check_training_set(hs, targets)
        for h, y_all in zip(hs, targets):
            x = build_features(h, self.spec_)
            y = y_all[self.spec_.rows(h.sizes["time"])]
            n_va = round(self.val_fraction * len(x))
            cut = len(x) - n_va
            xs_tr.append(x[:cut]), ys_tr.append(y[:cut])
            xs_va.append(x[cut:]), ys_va.append(y[cut:])
        return (np.concatenate(xs_tr), np.concatenate(ys_tr),
                np.concatenate(xs_va), np.concatenate(ys_va))

    # -- training -----------------------------------------------------------------------
    def fit(
        self,
        histories: xr.Dataset | Sequence[xr.Dataset],
        target: Target = "F_bb",
        *,
        known: Sequence[KnownComponent] = (),
        force: str = "F_tot",
        progress: bool = False,
        n_out: int | None = None,
    ) -> ForceNetwork:
        """Train on one or several TimeHistories.

        Parameters
        ----------
        histories : Dataset or list of Dataset
            Reference histories (same dof; with ``eta`` when it is an input).
        target : str, callable or array
            What to learn; see :func:`target_force`. Default ``"F_bb"`` = ``force`` minus the
            ``known`` components.
        known : sequence of KnownComponent
            Known components of the partition (used only for ``target="F_bb"``).
        force : str
            Total force variable [N] the black-box force is taken from.
        progress : bool
            Show a tqdm bar over epochs.
        n_out : int, optional
            Columns of an array (or callable) target that is not a force on the DOFs: an
            output head, e.g. line tensions [N] from the same features; it is never coupled
            to the ODE (:meth:`predict` only). Default: the DOF count.

        Returns
        -------
        self
        """
        self._check_params()
        hs = _as_list(histories)
        self.spec_ = spec_for(hs[0], self.inputs, self.window, self.stride, self.lead)
        x_tr, y_tr, x_va, y_va = self._dataset(hs, target, known, force, n_out)
        if len(x_tr) < 2:
            raise InputError(f"only {len(x_tr)} training samples after windowing; need more data")
        self.x_mean_, self.x_std_ = x_tr.mean(0), _safe_std(x_tr)
        self.y_mean_, self.y_std_ = y_tr.mean(0), _safe_std(y_tr)
        self.n_dof_ = y_tr.shape[1]
        torch.manual_seed(self.seed)
        self.model_ = build_mlp(self.spec_.n_features, self.n_dof_, self.hidden,
                                self.activation).to(self.device)
        self._set_scaler()
        self.history_ = self._train(x_tr, y_tr, x_va, y_va, progress)
        return self

    def _set_scaler(self) -> None:
        as_t = lambda a: torch.tensor(np.asarray(a, dtype=float), device=self.device)
        self._xm, self._xs = as_t(self.x_mean_), as_t(self.x_std_)
        self._ym, self._ys = as_t(self.y_mean_), as_t(self.y_std_)

    def _train(self, x_tr, y_tr, x_va, y_va, progress: bool) -> dict[str, list[float]]:
        from tqdm.auto import tqdm

        xt = (torch.tensor(x_tr, device=self.device) - self._xm) / self._xs
        yt = (torch.tensor(y_tr, device=self.device) - self._ym) / self._ys
        has_val = len(x_va) > 0
        if has_val:
            xv = (torch.tensor(x_va, device=self.device) - self._xm) / self._xs
            yv = (torch.tensor(y_va, device=self.device) - self._ym) / self._ys
        opt = torch.optim.Adam(self.model_.parameters(), lr=self.lr, weight_decay=self.weight_decay)
        gen = torch.Generator().manual_seed(self.seed)  # shuffling independent of global RNG
        loss_fn = nn.MSELoss()
        hist: dict[str, list[float]] = {"train_loss": [], "val_loss": []}
        best, best_state, stale = np.inf, None, 0
        for _ in tqdm(range(self.max_epochs), disable=not progress, desc="training", unit="epoch"):
            self.model_.train()
            perm = torch.randperm(len(xt), generator=gen)
            total = 0.0
            for s in range(0, len(xt), self.batch_size):
                idx = perm[s:s + self.batch_size]
                opt.zero_grad()
                xb = xt[idx]
                if self.input_noise > 0:
                    xb = xb + self.input_noise * torch.randn(xb.shape, generator=gen, dtype=xb.dtype)
                loss = loss_fn(self.model_(xb), yt[idx])
                loss.backward()
                opt.step()
                total += float(loss.detach()) * len(idx)
            hist["train_loss"].append(total / len(xt))
            self.model_.eval()
            with torch.no_grad():
                val = float(loss_fn(self.model_(xv), yv)) if has_val else hist["train_loss"][-1]
            hist["val_loss"].append(val)
            if val < best - 1e-12:
                best, stale = val, 0
                best_state = {k: v.detach().clone() for k, v in self.model_.state_dict().items()}
            else:
                stale += 1
                if stale >= self.patience:
                    break
        if best_state is not None:  # early stopping: keep the best validation weights
            self.model_.load_state_dict(best_state)
        self.best_val_loss_ = float(best)
        self.n_epochs_ = len(hist["train_loss"])
        return hist

    # -- evaluation ---------------------------------------------------------------------
    def _check_fitted(self) -> None:
        if not hasattr(self, "model_"):
            raise InputError("this ForceNetwork is not fitted yet; call fit() or load() first")

    def forward(self, x: Any) -> Any:
        """Physical-unit network on a torch tensor of features (..., n_features) -> (..., n_dof) [N]."""
        return self.model_((x - self._xm) / self._xs) * self._ys + self._ym

    def physical_layers(self, out_scale: float = 1.0) -> list[tuple[Any, Any]]:
        """The MLP as ``(weight, bias)`` pairs in physical units, differentiable in its weights.

        The input standardisation is folded into the first layer and the output's (times
        ``out_scale``) into the last, so that ``linear -> activation -> ... -> linear``
        (:func:`activation_function` of ``activation``) over these pairs is
        ``forward(x) * out_scale``. A rollout builds them once per call instead of
        standardising at every step (:func:`hybridwsi.surrogate.multistep.torch_decays`).
        """
        self._check_fitted()
        pairs = [(m.weight, m.bias) for m in self.model_ if isinstance(m, nn.Linear)]
        w, b = pairs[0]
        w = w / self._xs
        pairs[0] = (w, b - w @ self._xm)
        w, b = pairs[-1]
        pairs[-1] = (w * (self._ys * out_scale)[:, None], (b * self._ys + self._ym) * out_scale)
        return pairs

    def predict_features(self, x: np.ndarray) -> np.ndarray:
        """Force [N] for a feature matrix (n, n_features) -> (n, n_dof)."""
        self._check_fitted()
        x = np.asarray(x, dtype=float)
        if x.ndim != 2 or x.shape[1] != self.spec_.n_features:
            raise InputError(f"features have shape {x.shape}; expected (n, {self.spec_.n_features})")
        with torch.no_grad():
            return self.forward(torch.tensor(x, device=self.device)).cpu().numpy()

    def predict(self, hist: xr.Dataset) -> np.ndarray:
        """Force [N] on a history, shape (n_time, n_dof); rows outside ``spec_.rows`` (too few
        past samples, or ``eta`` lead beyond the end) are NaN."""
        self._check_fitted()
        x = build_features(hist, self.spec_)
        out = np.full((hist.sizes["time"], self.n_dof_), np.nan)
        out[self.spec_.rows(hist.sizes["time"])] = self.predict_features(x)
        return out

    def score(self, hist: xr.Dataset, target: Target = "F_bb", *, known=(), force="F_tot") -> float:
        """Coefficient of determination R² of the prediction on a history."""
        rows = self.spec_.rows(hist.sizes["time"])
        y = target_force(hist, target, known, force)[rows]
        p = self.predict(hist)[rows]
        return float(1.0 - np.sum((y - p) ** 2) / np.sum((y - y.mean(0)) ** 2))

    # -- persistence --------------------------------------------------------------------
    def metadata(self) -> dict[str, Any]:
        self._check_fitted()
        return {
            "format": "hybridwsi.ForceNetwork/1",
            "hybridwsi_version": version(),
            "torch_version": torch.__version__,
            "params": {**self.get_params(), "hidden": list(self.hidden), "inputs": list(self.inputs)},
            "spec": self.spec_.to_dict(),
            "n_dof": int(self.n_dof_),
            "x_mean": self.x_mean_.tolist(), "x_std": self.x_std_.tolist(),
            "y_mean": self.y_mean_.tolist(), "y_std": self.y_std_.tolist(),
            "best_val_loss": getattr(self, "best_val_loss_", None),
            "n_epochs": getattr(self, "n_epochs_", None),
        }

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``<path>.pt`` (state dict only) and ``<path>.json`` (metadata), atomically."""
        base = Path(path).with_suffix("")
        meta = json.dumps(self.metadata(), indent=2)
        pt = atomic_write(base.with_suffix(".pt"), lambda tmp: torch.save(self.model_.state_dict(), tmp))
        js = atomic_write(base.with_suffix(".json"), lambda tmp: Path(tmp).write_text(meta))
        return pt, js

    @classmethod
    def load(cls, path: str | Path) -> ForceNetwork:
        """Rebuild a network written by :meth:`save` (``torch.load(weights_only=True)``)."""
        _require_torch()
        base = Path(path).with_suffix("")
        pt, js = base.with_suffix(".pt"), base.with_suffix(".json")
        if not pt.is_file() or not js.is_file():
            raise InputError(f"network files not found: need {pt} and {js}")
        try:
            meta = json.loads(js.read_text())
            params = meta["params"]
            net = cls(**{**params, "hidden": tuple(params["hidden"]), "inputs": tuple(params["inputs"])})
            sp = meta["spec"]
            net.spec_ = FeatureSpec(tuple(sp["inputs"]), sp["window"], sp["n_dof"], sp["n_probe"],
                                    sp.get("stride", 1), sp.get("lead", 0))
            net.n_dof_ = int(meta["n_dof"])
            for k in ("x_mean", "x_std", "y_mean", "y_std"):
                setattr(net, k + "_", np.asarray(meta[k], dtype=float))
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"{js} is not ForceNetwork metadata: {exc}") from None
        net.model_ = build_mlp(net.spec_.n_features, net.n_dof_, net.hidden, net.activation)
        try:
            net.model_.load_state_dict(torch.load(pt, map_location=net.device, weights_only=True))
        except Exception as exc:  # torch raises several types on bad files
            raise InputError(f"cannot load network weights {pt}: {exc}") from None
        net.model_.to(net.device).eval()
        net._set_scaler()
        return net


def _safe_std(a: np.ndarray) -> np.ndarray:
    """Column std with constant columns mapped to 1 (avoid division by zero)."""
    s = a.std(0)
    return np.where(s > 1e-12 * (np.abs(a).max(0) + 1e-300), s, 1.0)
