"""Multi-step training: a force network trained through a differentiable rollout (torch).

A network fitted on a measured residual force (one step) inherits the bias of the derivative
estimates behind that force; trained on the measured *motion* through the hybrid's own time
loop, it does not. Here the hybrid is the heave decay of a floating body with exact (cubic)
hydrostatics, constant A∞ and the radiation state space (the Kramer sphere,
:mod:`hybridwsi.surrogate.kramer`):

- :func:`rk4_step`: one classical Runge–Kutta step, written in arithmetic only so that the same
  step serves NumPy arrays and torch tensors;
- :func:`torch_decays`: batched free decays with the network in the loop, differentiable in
  its weights (torch step by step, or one autograd operation over the compiled loops and
  discrete adjoint of :mod:`hybridwsi.surrogate._decay_kernel`);
- :class:`HeaveLoss`: mean square heave error against measured decays on a lead-shifted grid;
- :func:`train_network_on_heave`: L-BFGS on that loss, with checkpoints for a nested
  selection of the training length.

The set-up (``setup``) is a :class:`~hybridwsi.surrogate.kramer.KramerSetup`: mass [kg],
``added_mass_inf`` [kg], the radiation ``memory`` state space, ``hydrostatic_table()`` and the
``drop_heights`` [m]. torch is imported where it is needed (the optional ``ml`` extra).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from hybridwsi.errors import InputError, SolverError
from hybridwsi.surrogate import _decay_kernel

if TYPE_CHECKING:  # the set-up's module imports this one
    from hybridwsi.surrogate.kramer import KramerSetup


def rk4_step(rhs: Any, y: Any, h: float) -> Any:
    """One classical Runge–Kutta step of ``ẏ = rhs(y)`` of length ``h`` [s].

    Arithmetic only, so the same step serves NumPy arrays
    (:func:`hybridwsi.surrogate.structured.integrate_decay`) and torch tensors
    (:func:`torch_decays`, differentiable). ``y`` is the whole state, one array, so that a
    torch step records few operations (the rollout is bound by their count, not their size).
    """
    d1 = rhs(y)
    d2 = rhs(y + (0.5 * h) * d1)
    d3 = rhs(y + (0.5 * h) * d2)
    d4 = rhs(y + h * d3)
    return y + (h / 6.0) * (d1 + 2 * d2 + 2 * d3 + d4)


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
                 first: float = 0.0, *, compiled: bool | None = None) -> Any:
    """Free decays of the hybrid ``(m + A∞) z̈ = F_hs(z) − C_r x + N(z, ż)`` in torch (RK4).

    The same equation as the rollout of :func:`hybridwsi.surrogate.kramer.roll_network`
    (exact hydrostatics, constant A∞, the radiation state space), differentiable in the
    network's weights. With ``first`` > 0 the first step is ``first`` [s] long (times 0,
    first, first + dt, ...), which puts a lead-shifted data grid on the steps. Returns heave
    [m], a tensor (len(h0), n + 1), n = n_steps (+ 1 with ``first``).

    ``compiled`` (default: when Numba is there and the activation is tanh): the rollout and
    its gradient by the compiled loops of :mod:`hybridwsi.surrogate._decay_kernel` (one
    autograd operation, ~100x faster) instead of torch operations step by step; the two
    agree to rounding (tests).
    """
    import torch

    lin, bias, poly = _linear_part(setup)
    m0 = setup.mass + setup.added_mass_inf
    steps = np.array(([first] if first > 1e-12 else []) + [dt] * n_steps, dtype=float)
    # a ForceNetwork's layers in physical units; another (z, ż) network (a script's wrapper
    # with its own forward, scripts/kramer_ensemble.py) is called as it is
    layers = (net.physical_layers(out_scale=1.0 / m0) if hasattr(net, "physical_layers")
              else None)
    plain = layers is not None and layers[0][0].shape[1] == 2
    if compiled is None:
        compiled = _decay_kernel.HAVE_NUMBA and plain and net.activation == "tanh"
    elif compiled and not (_decay_kernel.HAVE_NUMBA and plain and net.activation == "tanh"):
        raise InputError("the compiled rollout needs Numba and a tanh ForceNetwork of (z, ż)")
    if compiled:
        y0 = np.zeros((len(h0), lin.shape[0]))
        y0[:, 0] = np.asarray(h0, dtype=float)
        consts = (lin, bias, float(poly[0]) / m0, float(poly[1]) / m0, y0, steps)
        return _compiled_decays_function().apply(consts, *[t for pair in layers for t in pair])
    n = lin.shape[0]
    lin_t, bias_t = torch.as_tensor(lin.T.copy()), torch.as_tensor(bias)
    e_v = torch.zeros(1, n, dtype=torch.float64)
    e_v[0, 1] = 1.0
    p3, p2 = float(poly[0]) / m0, float(poly[1]) / m0
    network = (_layers_force(layers, net.activation, n) if plain
               else lambda y: net.forward(y[:, :2]) / m0)

    def rhs(y: Any) -> Any:
        z = y[:, :1]
        f = torch.addcmul(network(y), z * z, z * p3 + p2)  # N/m0 + the cubic's z³, z² / m0
        return torch.addcmul(torch.addmm(bias_t, y, lin_t), f, e_v)

    y = torch.zeros(len(h0), n, dtype=torch.float64)
    y[:, 0] = torch.as_tensor(np.asarray(h0, dtype=float))
    out = [y]
    for h in steps:
        y = rk4_step(rhs, y, float(h))
        out.append(y)
    return torch.stack(out, dim=1)[:, :, 0]


def _layers_force(layers: list[tuple[Any, Any]], activation: str, n: int) -> Callable:
    """The network force / (m + A∞) on the whole state (B, n) from its physical layers: the
    first layer gets zero columns for x (no slicing of the state per evaluation)."""
    import torch

    from hybridwsi.surrogate.network import activation_function

    w, b = layers[0]
    layers = [(torch.cat([w, torch.zeros(w.shape[0], n - 2, dtype=w.dtype)], dim=1), b),
              *layers[1:]]
    act = activation_function(activation)

    def force(y: Any) -> Any:
        h = y
        for k, (w, b) in enumerate(layers):
            h = torch.nn.functional.linear(h, w, b)
            h = act(h) if k < len(layers) - 1 else h
        return h

    return force


@functools.cache
def _compiled_decays_function() -> Any:
    """The torch ``autograd.Function`` of :func:`torch_decays`' compiled path (built on first
    use: torch is the optional ``ml`` extra)."""
    import torch

    class CompiledDecays(torch.autograd.Function):
        """Heave (n_case, n_step + 1) [m] from the network's physical layers (weight, bias,
        weight, bias, ...); ``consts`` = (L, c, p₃, p₂, y0, steps) of :func:`torch_decays`."""

        @staticmethod
        def forward(ctx: Any, consts: tuple, *layers: Any) -> Any:
            arrays = [t.detach().cpu().numpy().astype(float) for t in layers]
            w, b, sizes = _decay_kernel.flat_layers(list(zip(arrays[::2], arrays[1::2])))
            lin, bias, p3, p2, y0, steps = consts
            z, tape_u, tape_a = _decay_kernel.forward(lin, bias, p3, p2, w, b, sizes, y0, steps)
            ctx.saved = (consts, w, b, sizes, tape_u, tape_a, [t.shape for t in layers],
                         layers[0].dtype)
            return torch.as_tensor(z, dtype=layers[0].dtype)

        @staticmethod
        def backward(ctx: Any, grad_z: Any) -> Any:
            (lin, _, p3, p2, _, steps), w, b, sizes, tape_u, tape_a, shapes, dtype = ctx.saved
            gw, gb = _decay_kernel.adjoint(lin, p3, p2, w, b, sizes, steps, tape_u, tape_a,
                                           np.ascontiguousarray(grad_z.numpy(), dtype=float))
            grads, iw, ib = [], 0, 0
            for shape_w, shape_b in zip(shapes[::2], shapes[1::2]):
                nw, nb = int(np.prod(shape_w)), int(np.prod(shape_b))
                grads += [torch.as_tensor(gw[iw:iw + nw].reshape(shape_w), dtype=dtype),
                          torch.as_tensor(gb[ib:ib + nb].reshape(shape_b), dtype=dtype)]
                iw, ib = iw + nw, ib + nb
            return (None, *grads)

    return CompiledDecays


def _linear_part(setup: KramerSetup) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The hybrid's right-hand side on the state ``y = (z, ż, x)`` without the network and
    the cubic's z³ and z² terms: ``ẏ = L y + c``, and the cubic (highest power first).

    ``(m + A∞) z̈ = F_hs(z) − C_r x + N``, ``ẋ = A_r x + B_r ż``; the linear and constant
    terms of F_hs(z) enter ``L`` and ``c``.
    """
    ss = setup.memory.ss
    ar, br, cr = (np.asarray(a, dtype=float) for a in (ss.A, ss.B[:, 0], ss.C[0]))
    poly = hydrostatic_polynomial(setup)
    m0 = setup.mass + setup.added_mass_inf
    n = 2 + ar.shape[0]
    lin = np.zeros((n, n))
    lin[0, 1] = 1.0
    lin[1, 0], lin[1, 2:] = poly[2] / m0, -cr / m0
    lin[2:, 1], lin[2:, 2:] = br, ar
    bias = np.zeros(n)
    bias[1] = poly[3] / m0
    return lin, bias, poly


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
