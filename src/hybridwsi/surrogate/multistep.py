"""Multi-step training: a force network trained through a differentiable rollout (torch).

A network fitted on a measured residual force (one step) inherits the bias of the derivative
estimates behind that force; trained on the measured *motion* through the hybrid's own time
loop, it does not. Here the hybrid is the heave decay of a floating body with exact (cubic)
hydrostatics, constant A∞ and the radiation state space (the Kramer sphere,
:mod:`hybridwsi.surrogate.kramer`):

- :func:`rk4_step`: one classical Runge–Kutta step, written in arithmetic only so that the same
  step serves NumPy arrays and torch tensors;
- :func:`torch_decays`: batched free decays with the network in the loop, differentiable in
  its weights;
- :class:`HeaveLoss`: mean square heave error against measured decays on a lead-shifted grid;
- :func:`train_network_on_heave`: L-BFGS on that loss, with checkpoints for a nested
  selection of the training length.

The set-up (``setup``) is a :class:`~hybridwsi.surrogate.kramer.KramerSetup`: mass [kg],
``added_mass_inf`` [kg], the radiation ``memory`` state space, ``hydrostatic_table()`` and the
``drop_heights`` [m]. torch is imported where it is needed (the optional ``ml`` extra).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from hybridwsi.errors import InputError, SolverError

if TYPE_CHECKING:  # the set-up's module imports this one
    from hybridwsi.surrogate.kramer import KramerSetup


def rk4_step(rhs: Any, z: Any, v: Any, x: Any, h: float) -> tuple[Any, Any, Any]:
    """One classical Runge–Kutta step of ``(ż, v̇, ẋ) = rhs(z, v, x)`` of length ``h`` [s].

    Arithmetic only, so the same step serves NumPy arrays
    (:func:`hybridwsi.surrogate.structured.integrate_decay`) and torch tensors
    (:func:`torch_decays`, differentiable).
    """
    d1 = rhs(z, v, x)
    d2 = rhs(z + 0.5 * h * d1[0], v + 0.5 * h * d1[1], x + 0.5 * h * d1[2])
    d3 = rhs(z + 0.5 * h * d2[0], v + 0.5 * h * d2[1], x + 0.5 * h * d2[2])
    d4 = rhs(z + h * d3[0], v + h * d3[1], x + h * d3[2])
    return tuple(y + h / 6.0 * (a + 2 * b + 2 * c + d)
                 for y, a, b, c, d in zip((z, v, x), d1, d2, d3, d4))


#: multi-step (rollout) training of the network on the training drops' heave: RK4 step [s]
#: (twice the data's; 0.58 of RK4's stability limit for the fastest radiation pole) and the
#: length of the fitted record [s] (the RMS window, 5 Te0)
ROLLOUT_TRAINING = {"dt": 0.02, "duration": 3.8}


def hydrostatic_polynomial(setup: KramerSetup) -> np.ndarray:
    """Coefficients (highest power first) of the exact heave force F_hs(z) [N], z [m].

    The submerged volume of a sphere is a cubic in the draft, so a cubic through the exact
    force over the floating range ``|z| ≤ R`` reproduces it; checked here to 1e-9 of its size.
    """
    z, f = setup.hydrostatic_table()
    poly = np.polyfit(z, f, 3)
    if np.max(np.abs(np.polyval(poly, z) - f)) > 1e-9 * np.max(np.abs(f)):
        raise SolverError("the exact hydrostatic force of this body is not a cubic in heave")
    return poly


def torch_decays(net: Any, setup: KramerSetup, h0: np.ndarray, dt: float, n_steps: int,
                 first: float = 0.0) -> Any:
    """Free decays of the hybrid ``(m + A∞) z̈ = F_hs(z) − C_r x + N(z, ż)`` in torch (RK4).

    The same equation as the rollout of :func:`hybridwsi.surrogate.kramer.roll_network`
    (exact hydrostatics, constant A∞, the radiation state space), differentiable in the network's weights. With ``first``
    > 0 the first step is ``first`` [s] long (times 0, first, first + dt, ...), which puts a
    lead-shifted data grid on the steps. Returns heave [m], a tensor (len(h0), n + 1), n =
    n_steps (+ 1 with ``first``).
    """
    import torch

    as_t = lambda a: torch.as_tensor(np.asarray(a, dtype=float))  # noqa: E731
    ss = setup.memory.ss
    ar, br, cr = as_t(ss.A), as_t(ss.B[:, 0]), as_t(ss.C[0])
    poly = [float(c) for c in hydrostatic_polynomial(setup)]
    m0 = setup.mass + setup.added_mass_inf

    def rhs(z: Any, v: Any, x: Any) -> tuple[Any, Any, Any]:
        f_hs = ((poly[0] * z + poly[1]) * z + poly[2]) * z + poly[3]
        f_net = net.forward(torch.stack([z, v], dim=-1))[:, 0]
        return v, (f_hs - x @ cr + f_net) / m0, x @ ar.T + v[:, None] * br

    z = as_t(h0)
    v = torch.zeros_like(z)
    x = torch.zeros(z.shape[0], ar.shape[0], dtype=z.dtype)
    out = [z]
    for h in ([first] if first > 1e-12 else []) + [dt] * n_steps:
        z, v, x = rk4_step(rhs, z, v, x, h)
        out.append(z)
    return torch.stack(out, dim=1)


class HeaveLoss:
    """Mean square of (z_hybrid(t + δ)/H0 − z_meas(t)/H0) over t ∈ [0, 5 Te0], for some drops.

    The hybrid's steps (:func:`torch_decays`, :data:`ROLLOUT_TRAINING`) are placed on the
    lead-shifted data grid and only data samples that fall on a step (within 5 % of it) enter:
    no interpolation error.

    Parameters
    ----------
    setup : KramerSetup
    targets : dict
        ``{drop: (t [s], z / H0 [-])}``.
    lead : float
        Release lead δ [s]: the model is released δ before the data's t = 0.
    """

    def __init__(self, setup: KramerSetup, targets: dict[str, tuple[np.ndarray, np.ndarray]],
                 lead: float) -> None:
        import torch  # noqa: F401 - the optional "ml" extra, needed by __call__

        cfg = ROLLOUT_TRAINING
        self.setup, self.drops = setup, list(targets)
        self.dt, self.n_steps = float(cfg["dt"]), int(round(cfg["duration"] / cfg["dt"]))
        self.first = lead % self.dt
        self.h0 = np.array([setup.drop_heights[d] for d in self.drops])
        self.idx, self.wts, self.obs = [], [], []
        for d in self.drops:
            te, ze = targets[d]
            s = (te + lead - self.first) / self.dt + (1.0 if self.first > 1e-12 else 0.0)
            sel = (np.abs(s - np.round(s)) < 0.05) & (te >= 0.0) & (te + lead >= 0.0) \
                & (s < self.n_steps - 1)
            i = np.floor(s[sel]).astype(int)
            self.idx.append(torch.as_tensor(i))
            self.wts.append(torch.as_tensor(s[sel] - i))
            self.obs.append(torch.as_tensor(ze[sel]))

    def __call__(self, net: Any) -> Any:
        import torch

        z = torch_decays(net, self.setup, self.h0, self.dt, self.n_steps, self.first)
        z = z / torch.as_tensor(self.h0)[:, None]
        res = [z[k, i] * (1 - w) + z[k, i + 1] * w - o
               for k, (i, w, o) in enumerate(zip(self.idx, self.wts, self.obs))]
        return torch.mean(torch.cat(res) ** 2)

    def rms(self, net: Any) -> float:
        """Root of the loss, no gradient [-]."""
        import torch

        with torch.no_grad():
            return float(torch.sqrt(self(net)))


def train_network_on_heave(net: Any, setup: KramerSetup,
                           targets: dict[str, tuple[np.ndarray, np.ndarray]], lead: float, *,
                           iterations: int = 40, every: int = 10,
                           checkpoint: Callable[[int, Any], None] | None = None
                           ) -> dict[str, Any]:
    """Multi-step training: refine a fitted network on the training drops' measured heave.

    Minimises :class:`HeaveLoss` of the training drops (the hybrid rolled out from release,
    :func:`torch_decays`) by L-BFGS from the one-step fit on ``F_bb``, with the release lead
    δ [s] of the structured fit on the same drops. The one-step target carries the bias of the
    derivative estimates (the null test); the heave does not.

    Parameters
    ----------
    net : ForceNetwork
        Fitted on ``F_bb`` (inputs ``(z, zdot)``, window 1); refined in place.
    targets : dict
        ``{drop: (t [s], z / H0 [-])}`` of the *training* drops only.
    lead : float
        Release lead δ [s].
    iterations : int
        L-BFGS iterations (selected per fold by nested leave-one-out,
        :func:`hybridwsi.surrogate.kramer.select_iterations`).
    every : int
        Iterations per L-BFGS call (the curvature history is kept between calls); the
        nested selection's checkpoints are multiples of it, so a run of k iterations is the
        k-th checkpoint of a longer run.
    checkpoint : callable, optional
        ``checkpoint(done, net)`` after every call: the nested selection keeps a copy of the
        network there. The training itself never sees anything but ``targets``.

    Returns
    -------
    dict
        ``rms_start``, ``rms`` (fit RMS of heave/H0 before/after), ``iterations``, ``drops``.
    """
    import torch

    if tuple(net.inputs) != ("z", "zdot") or net.window != 1:
        raise InputError("multi-step training needs a network of (z, zdot) with window 1")
    loss = HeaveLoss(setup, targets, lead)
    opt = torch.optim.LBFGS(list(net.model_.parameters()), lr=1.0, max_iter=int(every),
                            history_size=20, line_search_fn="strong_wolfe")
    start = loss.rms(net)

    def closure() -> Any:
        opt.zero_grad()
        value = loss(net)
        value.backward()
        return value

    info: dict[str, Any] = {"rms_start": start, "drops": loss.drops, "release_lead_s": lead}
    done = 0
    net.model_.train()
    while done < iterations:
        chunk = min(int(every), iterations - done)
        opt.param_groups[0].update(max_iter=chunk, max_eval=chunk * 5 // 4)
        opt.step(closure)  # L-BFGS keeps its curvature history between calls
        done += chunk
        if checkpoint is not None:
            checkpoint(done, net)
    net.model_.eval()
    info.update(rms=loss.rms(net), iterations=int(opt.state[opt._params[0]].get("n_iter", 0)))
    return info
