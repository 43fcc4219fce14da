"""Input features of the force network: a window of past kinematics (and wave elevation).

Layout (shared by training, prediction, linearisation and the hybrid rollout): each sample is
a ``(window, n_channels)`` block flattened lag-major, lag 0 being the current time step:

``x = [c(t_i), c(t_{i-1}), ..., c(t_{i-window+1})]``, ``c = [z[dof...], zdot[dof...],
zddot[dof...], eta[probe...]]`` restricted to the chosen ``inputs``.

So the derivative of the network with respect to the lag-0 ``zddot``/``zdot``/``z`` columns is
the surrogate's alpha_s/beta_s/gamma_s (docs/THEORY.md §4b), and the hybrid rollout can keep a
ring buffer of ``c`` and feed it without rebuilding features.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.history import KINEMATICS

#: input names a network may use besides the kinematics
WAVE_INPUTS = ("eta",)


@dataclass(frozen=True)
class FeatureSpec:
    """Which channels, how many past samples.

    Parameters
    ----------
    inputs : tuple of str
        Subset of ``("z", "zdot", "zddot", "eta")`` in any order (stored in canonical order).
    window : int
        Number of samples per channel (1 = current sample only).
    stride : int
        Spacing of those samples [time steps]: lags ``0, stride, ..., (window-1) stride``
        (spaced taps cover a long memory with few, less collinear, features).
    lead : int
        The ``eta`` channel is the elevation ``lead`` steps ahead, ``eta(t + lead dt)``: the
        incident wave is a known input, and the excitation force is not causal in it.
    n_dof : int
        Degrees of freedom of the body.
    n_probe : int
        Wave-elevation probes (only when ``"eta"`` is an input).
    """

    inputs: tuple[str, ...] = ("z", "zdot", "zddot")
    window: int = 1
    n_dof: int = 1
    n_probe: int = 0
    stride: int = 1
    lead: int = 0
    channels: tuple[tuple[str, int], ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        unknown = [n for n in self.inputs if n not in (*KINEMATICS, *WAVE_INPUTS)]
        if unknown or not self.inputs:
            raise InputError(
                f"network inputs must be a non-empty subset of z, zdot, zddot, eta; got {unknown or '()'}"
            )
        if int(self.window) < 1 or int(self.stride) < 1 or int(self.lead) < 0:
            raise InputError(f"need window >= 1, stride >= 1, lead >= 0; got {self.window}, "
                             f"{self.stride}, {self.lead}")
        if "eta" in self.inputs and self.n_probe < 1:
            raise InputError("input 'eta' needs a wave-elevation variable 'eta' in the history")
        canon = tuple(n for n in (*KINEMATICS, *WAVE_INPUTS) if n in self.inputs)
        object.__setattr__(self, "inputs", canon)
        chans = []
        for name in canon:
            width = self.n_probe if name == "eta" else self.n_dof
            chans += [(name, k) for k in range(width)]
        object.__setattr__(self, "channels", tuple(chans))

    @property
    def span(self) -> int:
        """Samples of past history one feature row needs (current one included)."""
        return (self.window - 1) * self.stride + 1

    def rows(self, n_time: int) -> slice:
        """Time indices that get a feature row in a history of ``n_time`` samples."""
        return slice(self.span - 1, n_time - self.lead)

    @property
    def n_channels(self) -> int:
        return len(self.channels)

    @property
    def n_features(self) -> int:
        return self.window * self.n_channels

    def column(self, name: str, lag: int = 0, index: int = 0) -> int | None:
        """Feature column of ``name`` (dof/probe ``index``) at ``lag`` samples back, or None."""
        if (name, index) not in self.channels or not 0 <= lag < self.window:
            return None
        return lag * self.n_channels + self.channels.index((name, index))

    def current_columns(self, name: str) -> list[int] | None:
        """Lag-0 columns of kinematic ``name`` for every dof (None when not an input)."""
        if name not in self.inputs:
            return None
        return [self.column(name, 0, k) for k in range(self.n_dof)]

    def to_dict(self) -> dict:
        return {"inputs": list(self.inputs), "window": int(self.window),
                "n_dof": int(self.n_dof), "n_probe": int(self.n_probe),
                "stride": int(self.stride), "lead": int(self.lead)}


def spec_for(hist: xr.Dataset, inputs: Sequence[str], window: int, stride: int = 1,
             lead: int = 0) -> FeatureSpec:
    """A :class:`FeatureSpec` sized for ``hist`` (its dof and probe counts)."""
    n_probe = int(hist["eta"].shape[1]) if "eta" in hist and hist["eta"].ndim == 2 else (
        1 if "eta" in hist else 0)
    return FeatureSpec(tuple(inputs), int(window), int(hist.sizes["dof"]), n_probe,
                       int(stride), int(lead) if "eta" in inputs else 0)


def channel_array(hist: xr.Dataset, spec: FeatureSpec) -> np.ndarray:
    """The per-time channels ``c(t)``, shape (n_time - lead, n_channels) (eta shifted ahead)."""
    cols = []
    for name in spec.inputs:
        if name not in hist:
            raise InputError(f"history has no '{name}', which the network uses as an input")
        arr = np.asarray(hist[name].values, dtype=float)
        arr = arr[:, None] if arr.ndim == 1 else arr
        want = spec.n_probe if name == "eta" else spec.n_dof
        if arr.shape[1] != want:
            raise InputError(f"'{name}' has {arr.shape[1]} columns; the network expects {want}")
        n_keep = arr.shape[0] - spec.lead
        cols.append(arr[spec.lead:] if name == "eta" else arr[:n_keep])
    out = np.concatenate(cols, axis=1)
    if not np.all(np.isfinite(out)):
        raise InputError("network inputs contain NaN/inf values")
    return out


def window_features(channels: np.ndarray, window: int, stride: int = 1) -> np.ndarray:
    """Stack lags ``0, stride, ..`` of ``channels`` (n, n_ch) -> (n - span + 1, window * n_ch)."""
    n, n_ch = channels.shape
    span = (window - 1) * stride + 1
    if n < span:
        raise InputError(f"history has {n} usable samples, fewer than the network needs ({span})")
    # sliding_window_view gives (n-span+1, n_ch, span) oldest first; reverse -> lag 0 first
    view = np.lib.stride_tricks.sliding_window_view(channels, span, axis=0)[:, :, ::-1][:, :, ::stride]
    return np.ascontiguousarray(view.transpose(0, 2, 1)).reshape(n - span + 1, window * n_ch)


def build_features(hist: xr.Dataset, spec: FeatureSpec) -> np.ndarray:
    """Feature matrix of a history, one row per time index in ``spec.rows(n_time)``."""
    return window_features(channel_array(hist, spec), spec.window, spec.stride)
