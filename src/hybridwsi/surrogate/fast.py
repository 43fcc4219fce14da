"""Fast inference of the force network and a compiled loop of the explicit hybrid rollout.

A tiny network evaluated once or twice per time step is dominated by per-call overhead
(torch dispatch, NumPy temporaries, the Python step), not by its ~10³ multiply-adds. So:

- :func:`folded_layers` folds the input/output standardisation into the first and last
  layers (``W x_n + b`` with ``x_n = (x - m)/s`` is ``(W/s) x + (b - W m/s)``), once;
- :func:`numpy_forward` evaluates them in NumPy (the same arithmetic as
  :meth:`ForceNetwork.forward` up to rounding, ~1e-15 relative);
- :func:`run_explicit` runs the whole ``lagged``/``corrected`` rollout of
  :mod:`hybridwsi.surrogate.coupled` in one Numba-compiled loop (when Numba is installed):
  preallocated scratch vectors, the feature window as a ring buffer, the trapezoidal
  radiation-state update as precomputed transition matrices, no allocation per step.
  It runs the arithmetic of ``coupled.CoupledStepper._lagged`` (tests compare both to 1e-12).
  Nonlinear known components with a Numba kernel (``KnownComponent.compiled_force``, the
  kernels of :mod:`hybridwsi.forces._compiled` the compiled Cummins loop calls: the tabulated
  mooring, the operating rotor, Morison drag...) are evaluated inside the loop, where the
  stepper evaluates their ``ode_force``.

Without Numba, :data:`HAVE_NUMBA` is False and the rollout uses its NumPy stepper.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybridwsi._numba import HAVE_NUMBA, numba
from hybridwsi.errors import SolverError
from hybridwsi.surrogate._decay_kernel import flat_layers
from hybridwsi.forces._compiled import CompiledForce, available, force_rows, packed, quiet, \
    sum_forces

#: batches of at least this many cases run the kernel with the cases inner (vectorised over
#: the batch); smaller ones one case after the other (vectorised over the hidden units)
BATCH_MIN = 8
#: activation name -> code used by the compiled loop
ACTIVATION_CODES = {"tanh": 0, "relu": 1, "silu": 2, "gelu": 3}


@dataclass(frozen=True)
class FoldedLayers:
    """Physical-unit network ``x [features] -> F [N]`` as plain arrays.

    ``weights[k]`` has shape (n_in, n_out) (applied as ``h @ W + b``); the activation follows
    every layer but the last.
    """

    weights: tuple[np.ndarray, ...]
    biases: tuple[np.ndarray, ...]
    activation: str


def folded_layers(net: Any) -> FoldedLayers:
    """The fitted ``ForceNetwork`` with its normalisation folded into the end layers
    (:meth:`~hybridwsi.surrogate.network.ForceNetwork.physical_layers`, as arrays)."""
    import torch

    with torch.no_grad():
        pairs = net.physical_layers()
    ws = [w.detach().cpu().numpy().astype(float) for w, _ in pairs]
    bs = [b.detach().cpu().numpy().astype(float).copy() for _, b in pairs]
    return FoldedLayers(tuple(np.ascontiguousarray(w.T) for w in ws), tuple(bs), net.activation)


def _np_activation(name: str):
    if name == "tanh":
        return np.tanh
    if name == "relu":
        return lambda h: np.maximum(h, 0.0)
    if name == "silu":
        return lambda h: h / (1.0 + np.exp(-h))
    from scipy.special import erf

    return lambda h: 0.5 * h * (1.0 + erf(h / math.sqrt(2.0)))


def numpy_forward(layers: FoldedLayers, x: np.ndarray) -> np.ndarray:
    """Force [N] of feature rows ``x`` (n, n_features) -> (n, n_dof), in NumPy."""
    act = _np_activation(layers.activation)
    h = x @ layers.weights[0] + layers.biases[0]
    for w, b in zip(layers.weights[1:], layers.biases[1:]):
        h = act(h) @ w + b
    return h


def padded_layers(layers: FoldedLayers) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Layers as ``W (n_layer, width, width)`` indexed ``[layer, in, out]``, ``b (n_layer,
    width)`` and the widths ``(n_in, n_1, ..., n_out)`` (zero padded) for the compiled loop."""
    sizes = np.array([layers.weights[0].shape[0]] + [w.shape[1] for w in layers.weights],
                     dtype=np.int64)
    width = int(sizes.max())
    w_all = np.zeros((len(layers.weights), width, width))
    b_all = np.zeros((len(layers.weights), width))
    for k, (w, b) in enumerate(zip(layers.weights, layers.biases)):
        w_all[k, :w.shape[0], :w.shape[1]] = w
        b_all[k, :b.shape[0]] = b
    return w_all, b_all, sizes


@dataclass
class ExplicitProblem:
    """Everything the compiled loop needs, as arrays (see :func:`run_explicit`).

    Integrator (``LaggedIntegrator``): ``scheme`` 0 = Newmark, 1 = semi-implicit Euler,
    ``lhs_inv``, ``damping``, ``stiffness`` (n_dof, n_dof) and the Newmark coefficients
    ``coef = (dt, c_v, c_z, c_z1, c_v1)``. Known remainder: ``quad`` (n_dof,) quadratic
    damping [N s²/m²], radiation states ``x1 = P x + Q (v + v1)`` with ``P`` (n_s, n_s),
    ``Q`` (n_s, n_dof) and force ``-C_out x`` (``C_out`` (n_dof, n_s)). Channels: positions of
    z, zdot, zddot per dof and of eta per probe in the feature row (-1 = not an input).
    ``forces``: the kernels of the other known components (their force added to the
    explicit part at the state and time the stepper evaluates them, at most
    :data:`hybridwsi.forces._compiled.MAX_KERNELS`).
    """

    scheme: int
    lhs_inv: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    coef: np.ndarray
    quad: np.ndarray
    p_ss: np.ndarray
    q_ss: np.ndarray
    c_out: np.ndarray
    chan_pos: np.ndarray  # (3, n_dof): z, zdot, zddot
    eta_pos: np.ndarray  # (n_probe,)
    window: int
    stride: int
    corrections: int
    forces: tuple[CompiledForce, ...] = ()


def run_explicit(prob: ExplicitProblem, layers: FoldedLayers, z0, v0, a0, x0, buf0,
                 pre: np.ndarray, eta: np.ndarray, k0: int, lead: int, n_steps: int,
                 ref_amp: np.ndarray, blowup: float, t: np.ndarray | None = None):
    """Compiled ``lagged``/``corrected`` rollout of a batch of cases.

    Parameters
    ----------
    prob : ExplicitProblem
    layers : FoldedLayers
    z0, v0, a0 : ndarray, shape (n_cases, n_dof)
        Start state [m, m/s, m/s²] (sample ``k0``).
    x0 : ndarray, shape (n_cases, n_states)
        Radiation states at ``k0``.
    buf0 : ndarray, shape (n_cases, span, n_channels)
        Feature channels of samples ``k0, k0 - 1, ...`` (lag 0 first).
    pre : ndarray, shape (n_cases, n_time, n_dof)
        Prescribed force [N] per sample; ``eta`` (n_cases, n_time, n_probe) [m].
    k0, lead, n_steps : int
    ref_amp : ndarray, shape (n_cases,)
        Reference max |z| per case; ``blowup`` the factor beyond which a case diverged.
    t : ndarray, shape (n_time,), optional
        The time grid [s] of ``pre`` (the kernels of ``prob.forces`` read it; default
        ``k dt``).

    Returns
    -------
    zs, vs, as_ : ndarray, shape (n_cases, n_steps + 1, n_dof)
    xs : ndarray, shape (n_cases, n_steps + 1, n_states)
    blew : ndarray of bool, (n_cases,)
    n_done : int
        Steps integrated (fewer than ``n_steps`` when every case diverged; NaN after).

    Raises
    ------
    SolverError
        A kernel of ``prob.forces`` failed (e.g. a fairlead left the mooring table), as the
        component's ``ode_force`` raises in the NumPy stepper.
    """
    nc, span, nch = buf0.shape
    as_c = lambda arr: np.ascontiguousarray(arr, dtype=float)  # noqa: E731
    times = as_c(np.arange(pre.shape[1]) * prob.coef[0] if t is None else t)
    physics = (prob.scheme, prob.lhs_inv, prob.damping, prob.stiffness, prob.coef, prob.quad,
               prob.p_ss, prob.q_ss, prob.c_out, prob.chan_pos, prob.eta_pos,
               int(prob.window), int(prob.stride), int(prob.corrections))
    kind = ACTIVATION_CODES[layers.activation]
    tail = (int(k0), int(lead), int(n_steps), as_c(ref_amp), float(blowup))
    with quiet():
        # None without kernels: a call through a function pointer in the loop, even one never
        # taken, keeps LLVM from optimising the loop (1.8x the cost per step of one case,
        # measured); the kernels' `comps is not None` branches are pruned for None
        known = packed(prob.forces) if prob.forces else None
        if nc >= BATCH_MIN:  # cases inner: the batch axis last, contiguous
            last = lambda arr: as_c(np.moveaxis(np.asarray(arr, dtype=float), 0, -1))  # noqa
            # flat layers (n_out, n_in) row-major: one compiled kernel for every depth
            w_flat, b_flat, sizes = flat_layers(list(zip((w.T for w in layers.weights),
                                                         layers.biases)))
            out = _kernel_batch(*physics, known, w_flat, b_flat, sizes, kind, last(z0), last(v0),
                                last(a0), last(x0), last(buf0[:, ::-1, :]), as_c(pre),
                                as_c(eta), times, *tail)
        else:  # ring buffer: row `head` is lag 0, row (head - l) % span is lag l
            ring = np.ascontiguousarray(buf0[:, ::-1, :])
            out = _kernel(*physics, known, *padded_layers(layers), kind, as_c(z0), as_c(v0),
                          as_c(a0), as_c(x0), ring, as_c(pre), as_c(eta), times, *tail)
    _raise_failed(prob.forces, out[-2], out[-1])
    return out[:-2]


def _raise_failed(forces: Sequence[CompiledForce], status: int, comp: int) -> None:
    """:class:`SolverError` with the message of kernel ``comp``'s nonzero ``status``."""
    if status != 0:
        raise SolverError(forces[comp].messages.get(
            status, f"force kernel {comp} failed with status {status}"))


def known_forces(forces: Sequence[CompiledForce], t: np.ndarray, z: np.ndarray,
                 v: np.ndarray) -> np.ndarray:
    """The summed force [N, N m] of the kernels ``forces`` on the rows of ``t`` (n,) [s],
    ``z``, ``v`` (n, n_dof) — what their ``ode_force`` gives row by row; NaN on rows whose
    state is not finite (a diverged case)."""
    out = np.empty(np.shape(z))
    with quiet():
        status, comp, _ = force_rows(packed(forces), np.ascontiguousarray(t, dtype=float),
                                     np.ascontiguousarray(z, dtype=float),
                                     np.ascontiguousarray(v, dtype=float), out)
    _raise_failed(forces, status, comp)
    return out


def supported(activation: str, known: Sequence[CompiledForce] | None, mode: str,
              scheme: str) -> bool:
    """Whether :func:`run_explicit` can run this rollout: ``known`` the kernels of the
    nonlinear known components (``BatchedPhysics.compiled_forces``; None when one has none)."""
    return (HAVE_NUMBA and activation in ACTIVATION_CODES and known is not None
            and available(known) and mode in ("lagged", "corrected")
            and scheme in ("newmark", "semi_implicit_euler"))


# ------------------------------------------------------------------------- compiled kernel
#: reassociation lets LLVM vectorise the dot products (rounding differs by ~1e-16 relative);
#: no "nnan"/"ninf": the divergence watch tests for non-finite values
_FASTMATH = {"reassoc", "contract", "nsz"}


#: NumPy's division semantics (inf/NaN, no ZeroDivisionError check): a checked division is a
#: branch, which stops LLVM from vectorising the loop around it
_ERRORS = "numpy"


def _jit(fn):
    return numba.njit(cache=True, fastmath=_FASTMATH, nogil=True,
                      error_model=_ERRORS)(fn) if HAVE_NUMBA else fn


def _inline(fn):
    """A helper of the kernel, inlined into it (no call overhead, arrays passed by value)."""
    return numba.njit(cache=True, fastmath=_FASTMATH, inline="always",
                      error_model=_ERRORS)(fn) if HAVE_NUMBA else fn


#: |x| beyond which tanh(x) is 1 in double precision (1 - tanh(20) = 8e-18)
_TANH_SAT = 20.0


@_inline
def _tanh(x):
    """tanh(x) from arithmetic only, so that LLVM vectorises a loop of it (a libm call stops
    vectorisation): ``tanh|x| = q/(q + 2)`` with ``q = e^{2|x|} - 1``, found from
    ``q_0 = e^{2|x|/256} - 1`` (Taylor series to degree 10, truncation < 1e-17 relative) by
    8 doublings ``e^{2y} - 1 = q (2 + q)``, which keep the relative accuracy near 0 (no
    ``1 - ...`` cancellation); error < 1e-15 relative (tests: against np.tanh)."""
    y = abs(x)
    y = (_TANH_SAT if y > _TANH_SAT else y) * (2.0 / 256.0)  # NaN stays NaN
    q = y * (1.0 + y * (1.0 / 2 + y * (1.0 / 6 + y * (1.0 / 24 + y * (1.0 / 120 + y * (
        1.0 / 720 + y * (1.0 / 5040 + y * (1.0 / 40320 + y * (1.0 / 362880 + y * (
            1.0 / 3628800))))))))))
    for _ in range(8):
        q = q * (2.0 + q)
    t = q / (q + 2.0)
    return t if x >= 0.0 else -t


@_inline
def _activate(h, n, kind, out):
    """out[:n] = activation(h[:n]) (``out`` may be ``h``)."""
    # the branch outside the loops: each loop is branch-free (tanh vectorises)
    if kind == 0:
        for j in range(n):
            out[j] = _tanh(h[j])
    elif kind == 1:
        for j in range(n):
            out[j] = h[j] if h[j] > 0.0 else 0.0
    elif kind == 2:
        for j in range(n):
            out[j] = h[j] / (1.0 + math.exp(-h[j]))
    else:
        for j in range(n):
            out[j] = 0.5 * h[j] * (1.0 + math.erf(h[j] / math.sqrt(2.0)))


#: layers with fewer outputs than this run as dot products (vectorised over the inputs),
#: wider ones as a sum of scaled weight rows (vectorised over the outputs)
_NARROW = 8


@_inline
def _forward_case(ring, case, head, new_row, use_new, window, stride, w_all, wt_all, b_all,
                  sizes, kind, h0, h1, out):
    """out[:n_out] = network(features of one case) with two scratch vectors h0, h1 (no
    allocation). The features are read from the ring (lags 0, stride, ... of ``case``; with
    ``use_new`` the new row is lag 0 and the ring's lag-0 row becomes lag 1), not gathered.
    ``wt_all`` is ``w_all`` with the last two axes swapped ([layer, out, in]).

    The newest row (lag 0: the state the step before produced) is added last: the older
    lags' share of the first layer, stored steps ago, does not wait for it, and no copy of
    the window is made (one case: ~10 % of the step, measured)."""
    span, nch = ring.shape[1], ring.shape[2]
    n_layer = w_all.shape[0]
    n_h = sizes[1]
    for j in range(n_h):
        h1[j] = b_all[0, j]
    for lag in range(1, window):
        back = lag * stride - (1 if use_new else 0)
        r = head - back  # back < span: one wrap at most (no integer division)
        if r < 0:
            r += span
        for ch in range(nch):
            x = ring[case, r, ch]
            i = lag * nch + ch
            for j in range(n_h):  # contiguous outputs: vectorised
                h1[j] += x * w_all[0, i, j]
    for ch in range(nch):  # the newest row
        x = new_row[ch] if use_new else ring[case, head, ch]
        for j in range(n_h):
            h1[j] += x * w_all[0, ch, j]
    for k in range(1, n_layer):
        _activate(h1, sizes[k], kind, h0)
        n_in, n_out = sizes[k], sizes[k + 1]
        if n_out < _NARROW:  # e.g. the output layer: one reduction per output
            for j in range(n_out):
                acc = b_all[k, j]
                for i in range(n_in):
                    acc += wt_all[k, j, i] * h0[i]
                h1[j] = acc
        else:
            for j in range(n_out):
                h1[j] = b_all[k, j]
            for i in range(n_in):  # inner loop over contiguous outputs: vectorised
                hi = h0[i]
                for j in range(n_out):
                    h1[j] += hi * w_all[k, i, j]
    for j in range(sizes[n_layer]):
        out[j] = h1[j]


# the helpers take whole arrays and indices, not views: a view costs two atomic reference
# count updates, as much as the arithmetic of a step


@_inline
def _row(z, v, a, eta, case, k, chan_pos, eta_pos, row):
    """Feature channels of the state (z, v, a) and of eta[case, k]."""
    nd = z.shape[0]
    for d in range(nd):
        if chan_pos[0, d] >= 0:
            row[chan_pos[0, d]] = z[d]
        if chan_pos[1, d] >= 0:
            row[chan_pos[1, d]] = v[d]
        if chan_pos[2, d] >= 0:
            row[chan_pos[2, d]] = a[d]
    for p in range(eta_pos.shape[0]):
        row[eta_pos[p]] = eta[case, k, p]


@_inline
def _remainder(pre, case, k1, v, x, quad, c_out, f):
    """f += prescribed ``pre[case, k1]`` and the known force beyond the linear part:
    -quad |v| v - C_out x."""
    nd, ns = c_out.shape
    for d in range(nd):
        acc = f[d] + pre[case, k1, d] - quad[d] * abs(v[d]) * v[d]
        for s in range(ns):
            acc -= c_out[d, s] * x[s]
        f[d] = acc


@_inline
def _known(comps, t, z, v, f, fs, tmp, fail):
    """f += the packed kernels' force at (t, z, v) (scratch fs, tmp); a failing kernel's
    (status, index) into ``fail`` (the first one kept)."""
    status, m = sum_forces(comps, t, z, v, fs, tmp)
    for d in range(f.shape[0]):
        f[d] += fs[d]
    if status != 0 and fail[0] == 0:
        fail[0], fail[1] = status, m


@_inline
def _integrate(scheme, lhs_inv, damping, stiffness, coef, z, v, a, f, p_ss, q_ss, x,
               z1, v1, a1, x1, r):
    """One LaggedIntegrator step with explicit force f, then the radiation states."""
    nd = z.shape[0]
    dt, c_v, c_z, c_z1, c_v1 = coef[0], coef[1], coef[2], coef[3], coef[4]
    if scheme == 0:  # Newmark: predictors in z1, v1
        for d in range(nd):
            v1[d] = v[d] + c_v * a[d]
            z1[d] = z[d] + dt * v[d] + c_z * a[d]
    else:
        for d in range(nd):
            v1[d] = v[d]
            z1[d] = z[d]
    for d in range(nd):
        acc = f[d]
        for e in range(nd):
            acc -= damping[d, e] * v1[e] + stiffness[d, e] * z1[e]
        r[d] = acc
    for d in range(nd):
        acc = 0.0
        for e in range(nd):
            acc += lhs_inv[d, e] * r[e]
        a1[d] = acc
    if scheme == 0:
        for d in range(nd):
            z1[d] += c_z1 * a1[d]
            v1[d] += c_v1 * a1[d]
    else:
        for d in range(nd):
            v1[d] = v[d] + dt * a1[d]
            z1[d] = z[d] + dt * v1[d]
    ns = x.shape[0]
    for s in range(ns):
        acc = 0.0
        for t in range(ns):
            acc += p_ss[s, t] * x[t]
        for d in range(nd):
            acc += q_ss[s, d] * (v[d] + v1[d])
        x1[s] = acc


@_inline
def _trajectories(nc, n_steps, nd, ns):
    """Output arrays z, ż, z̈ (nc, n_steps + 1, nd) and x (nc, n_steps + 1, ns)."""
    shape = (nc, n_steps + 1, nd)
    return np.empty(shape), np.empty(shape), np.empty(shape), np.empty((nc, n_steps + 1, ns))


@_jit
def _kernel(scheme, lhs_inv, damping, stiffness, coef, quad, p_ss, q_ss, c_out, chan_pos,
            eta_pos, window, stride, corrections, comps, w_all, b_all, sizes, kind, z0, v0, a0,
            x0, ring, pre, eta, t, k0, lead, n_steps, ref_amp, blowup):
    nc, nd = z0.shape
    ns = x0.shape[1]
    span, nch = ring.shape[1], ring.shape[2]
    zs, vs, as_, xs = _trajectories(nc, n_steps, nd, ns)
    zs[:, 0], vs[:, 0], as_[:, 0], xs[:, 0] = z0, v0, a0, x0
    width = w_all.shape[1]
    wt_all = np.empty_like(w_all)  # [layer, out, in] for the dot-product layers
    for k in range(w_all.shape[0]):
        for i in range(width):
            for j in range(width):
                wt_all[k, j, i] = w_all[k, i, j]
    row = np.zeros(nch)
    h0, h1 = np.empty(width), np.empty(width)
    f, r, fs, tmp = np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd)
    fail = np.zeros(2, dtype=np.int64)
    z, v, a, x = np.empty(nd), np.empty(nd), np.empty(nd), np.empty(ns)
    z1, v1, a1, x1 = np.empty(nd), np.empty(nd), np.empty(nd), np.empty(ns)
    blew = np.zeros(nc, dtype=np.bool_)
    n_done = 0
    # cases are independent: each runs to its end (or divergence) with its arrays in cache
    for c in range(nc):
        head = span - 1
        for d in range(nd):
            z[d], v[d], a[d] = z0[c, d], v0[c, d], a0[c, d]
        for s in range(ns):
            x[s] = x0[c, s]
        n_case = n_steps
        for n in range(n_steps):
            k1 = k0 + n + 1
            # predictor: network on the start-of-step window, the known explicit forces on
            # the start state at t[k1] - dt (as the stepper's t0)
            _forward_case(ring, c, head, row, False, window, stride, w_all, wt_all, b_all,
                          sizes, kind, h0, h1, f)
            _remainder(pre, c, k1, v, x, quad, c_out, f)
            if comps is not None:
                _known(comps, t[k1] - coef[0], z, v, f, fs, tmp, fail)
            _integrate(scheme, lhs_inv, damping, stiffness, coef, z, v, a, f, p_ss, q_ss, x,
                       z1, v1, a1, x1, r)
            for _ in range(corrections):  # again on the predicted end-of-step state, at t[k1]
                _row(z1, v1, a1, eta, c, k1 + lead, chan_pos, eta_pos, row)
                _forward_case(ring, c, head, row, True, window, stride, w_all, wt_all,
                              b_all, sizes, kind, h0, h1, f)
                _remainder(pre, c, k1, v1, x1, quad, c_out, f)
                if comps is not None:
                    _known(comps, t[k1], z1, v1, f, fs, tmp, fail)
                _integrate(scheme, lhs_inv, damping, stiffness, coef, z, v, a, f, p_ss, q_ss,
                           x, z1, v1, a1, x1, r)
            if fail[0] != 0:  # a kernel failed: as ode_force raising in the stepper
                return zs, vs, as_, xs, blew, n_done, fail[0], fail[1]
            _row(z1, v1, a1, eta, c, k1 + lead, chan_pos, eta_pos, row)
            head = head + 1 if head + 1 < span else 0
            for ch in range(nch):
                ring[c, head, ch] = row[ch]
            for d in range(nd):
                z[d], v[d], a[d] = z1[d], v1[d], a1[d]
                zs[c, n + 1, d], vs[c, n + 1, d], as_[c, n + 1, d] = z1[d], v1[d], a1[d]
            for s in range(ns):
                x[s] = x1[s]
                xs[c, n + 1, s] = x1[s]
            if n % 50 == 49 or n == n_steps - 1:  # divergence watch (as the NumPy loop)
                zmax = 0.0
                for k in range(n - min(n, 49), n + 2):
                    for d in range(nd):
                        val = abs(zs[c, k, d])
                        # branch-free: NaN fails every comparison, made explicit as inf
                        zmax = val if val > zmax else (zmax if val == val else np.inf)
                if not (zmax <= blowup * ref_amp[c]):
                    blew[c] = True
                    n_case = n + 1  # diverged: stop this case, NaN after
                    zs[c, n + 2:], vs[c, n + 2:], as_[c, n + 2:] = np.nan, np.nan, np.nan
                    xs[c, n + 2:] = np.nan
                    break
        n_done = max(n_done, n_case)
    return zs, vs, as_, xs, blew, n_done, 0, -1


# ------------------------------------------------------------ batch kernel (cases inner)
# Arrays carry the case as their LAST (contiguous) axis: every inner loop runs over the
# cases, so the MLP of a step is a small matrix-matrix product and the integration, the
# activation and the output writes are vector operations over the batch.


@_inline
def _gather_b(ring, head, new_row, use_new, window, stride, feat):
    """:func:`_gather` for all cases: ``feat (n_feat, nc)`` from ``ring (span, nch, nc)``."""
    span, nch, nc = ring.shape
    for lag in range(window):
        back = lag * stride
        if use_new:
            if back == 0:
                for ch in range(nch):
                    for c in range(nc):
                        feat[ch, c] = new_row[ch, c]
                continue
            back -= 1
        r = head - back
        if r < 0:
            r += span
        for ch in range(nch):
            for c in range(nc):
                feat[lag * nch + ch, c] = ring[r, ch, c]


@_inline
def _forward_b(feat, w_flat, b_flat, sizes, kind):
    """All cases through the network: per layer one matrix product ``W (n_out, n_in) @ h
    (n_in, nc)`` (BLAS, ~2x the loops' speed at 32 cases), then bias and activation in one
    contiguous pass; returns the output (n_out, nc). The layers are flat
    (:func:`~hybridwsi.surrogate._decay_kernel.flat_layers`)."""
    h = feat
    n_layer = sizes.shape[0] - 1
    ow, ob = 0, 0
    for k in range(n_layer):
        n_in, n_out = sizes[k], sizes[k + 1]
        g = np.dot(w_flat[ow:ow + n_out * n_in].reshape((n_out, n_in)), h)
        nc = g.shape[1]
        for j in range(n_out):
            bj = b_flat[ob + j]
            if k == n_layer - 1:
                for c in range(nc):
                    g[j, c] += bj
            elif kind == 0:
                for c in range(nc):
                    g[j, c] = _tanh(g[j, c] + bj)
            elif kind == 1:
                for c in range(nc):
                    x = g[j, c] + bj
                    g[j, c] = x if x > 0.0 else 0.0
            elif kind == 2:
                for c in range(nc):
                    x = g[j, c] + bj
                    g[j, c] = x / (1.0 + math.exp(-x))
            else:
                for c in range(nc):
                    x = g[j, c] + bj
                    g[j, c] = 0.5 * x * (1.0 + math.erf(x / math.sqrt(2.0)))
        ow += n_in * n_out
        ob += n_out
        h = g
    return h


@_inline
def _explicit_force_b(fnet, pre, k1, v, x, quad, c_out, f):
    """f = network + prescribed ``pre[case, k1]`` - quad |v| v - C_out x, (nd, nc)."""
    nd, nc = f.shape
    ns = x.shape[0]
    for d in range(nd):
        qd = quad[d]
        for c in range(nc):
            f[d, c] = fnet[d, c] + pre[c, k1, d] - qd * abs(v[d, c]) * v[d, c]
        for s in range(ns):
            cds = c_out[d, s]
            for c in range(nc):
                f[d, c] -= cds * x[s, c]


@_inline
def _known_b(comps, t, z, v, f, scratch, fail):
    """:func:`_known` for all cases, arrays (nd, nc); ``scratch`` four vectors (nd,)."""
    nd, nc = f.shape
    zc, vc, fs, tmp = scratch
    for c in range(nc):  # the kernels take one contiguous state
        for d in range(nd):
            zc[d], vc[d] = z[d, c], v[d, c]
        status, m = sum_forces(comps, t, zc, vc, fs, tmp)
        if status != 0 and fail[0] == 0:
            fail[0], fail[1] = status, m
        for d in range(nd):
            f[d, c] += fs[d]


@_inline
def _matvec_b(m, x, out):
    """out = m @ x for all cases, ``x`` and ``out`` (n, nc)."""
    nc = out.shape[1]
    for i in range(m.shape[0]):
        for c in range(nc):
            out[i, c] = 0.0
        for j in range(m.shape[1]):
            mij = m[i, j]
            for c in range(nc):
                out[i, c] += mij * x[j, c]


@_inline
def _integrate_b(scheme, lhs_inv, damping, stiffness, coef, z, v, a, f, p_ss, q_ss, x,
                 z1, v1, a1, x1, r):
    """:func:`_integrate` for all cases, arrays (n, nc)."""
    nd, nc = z.shape
    ns = x.shape[0]
    dt, c_v, c_z, c_z1, c_v1 = coef[0], coef[1], coef[2], coef[3], coef[4]
    for d in range(nd):
        for c in range(nc):
            if scheme == 0:  # Newmark predictors
                v1[d, c] = v[d, c] + c_v * a[d, c]
                z1[d, c] = z[d, c] + dt * v[d, c] + c_z * a[d, c]
            else:
                v1[d, c] = v[d, c]
                z1[d, c] = z[d, c]
    for d in range(nd):
        for c in range(nc):
            r[d, c] = f[d, c]
        for e in range(nd):
            bde, cde = damping[d, e], stiffness[d, e]
            for c in range(nc):
                r[d, c] -= bde * v1[e, c] + cde * z1[e, c]
    _matvec_b(lhs_inv, r, a1)
    for d in range(nd):
        for c in range(nc):
            if scheme == 0:
                z1[d, c] += c_z1 * a1[d, c]
                v1[d, c] += c_v1 * a1[d, c]
            else:
                v1[d, c] = v[d, c] + dt * a1[d, c]
                z1[d, c] = z[d, c] + dt * v1[d, c]
    _matvec_b(p_ss, x, x1)
    for s in range(ns):
        for d in range(nd):
            qsd = q_ss[s, d]
            for c in range(nc):
                x1[s, c] += qsd * (v[d, c] + v1[d, c])


@_inline
def _row_b(z, v, a, eta, k, chan_pos, eta_pos, row):
    """:func:`_row` for all cases: ``row (nch, nc)``, ``eta`` (nc, n_time, n_probe)."""
    nd, nc = z.shape
    for d in range(nd):
        for c in range(nc):
            if chan_pos[0, d] >= 0:
                row[chan_pos[0, d], c] = z[d, c]
            if chan_pos[1, d] >= 0:
                row[chan_pos[1, d], c] = v[d, c]
            if chan_pos[2, d] >= 0:
                row[chan_pos[2, d], c] = a[d, c]
    for p in range(eta_pos.shape[0]):
        for c in range(nc):
            row[eta_pos[p], c] = eta[c, k, p]


@_jit
def _kernel_batch(scheme, lhs_inv, damping, stiffness, coef, quad, p_ss, q_ss, c_out,
                  chan_pos, eta_pos, window, stride, corrections, comps, w_flat, b_flat, sizes,
                  kind, z0, v0, a0, x0, ring, pre, eta, t, k0, lead, n_steps, ref_amp, blowup):
    """:func:`_kernel` with the cases inner in the state: ``z0`` (nd, nc), ``x0`` (ns, nc),
    ``ring`` (span, nch, nc); ``pre``, ``eta`` and the outputs as :func:`_kernel`'s, (nc,
    n_time, n) (a step reads/writes one element per case: a few cache lines, reused by the
    next steps, cheaper than transposing whole series). A diverged case runs on (its values
    are replaced by NaN at the end); the loop stops when every case has diverged."""
    nd, nc = z0.shape
    ns = x0.shape[0]
    span, nch = ring.shape[0], ring.shape[1]
    zs, vs, as_, xs = _trajectories(nc, n_steps, nd, ns)
    zs[:, 0], vs[:, 0], as_[:, 0], xs[:, 0] = z0.T, v0.T, a0.T, x0.T
    feat = np.empty((window * nch, nc))
    row = np.zeros((nch, nc))
    f, r = np.empty((nd, nc)), np.empty((nd, nc))
    scratch = (np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd))
    fail = np.zeros(2, dtype=np.int64)
    z, v, a, x = z0.copy(), v0.copy(), a0.copy(), x0.copy()
    z1, v1, a1, x1 = np.empty((nd, nc)), np.empty((nd, nc)), np.empty((nd, nc)), np.empty((ns, nc))
    blew = np.zeros(nc, dtype=np.bool_)
    n_case = np.full(nc, n_steps, dtype=np.int64)
    zmax = np.empty(nc)
    n_blew = 0
    head = span - 1
    n_done = n_steps
    for n in range(n_steps):
        k1 = k0 + n + 1
        for p in range(1 + corrections):
            # p = 0: network on the start-of-step window, known explicit forces on the start
            # state at t[k1] - dt; p > 0: again on the predicted end-of-step state at t[k1]
            if p > 0:
                _row_b(z1, v1, a1, eta, k1 + lead, chan_pos, eta_pos, row)
            _gather_b(ring, head, row, p > 0, window, stride, feat)
            _explicit_force_b(_forward_b(feat, w_flat, b_flat, sizes, kind), pre, k1,
                              v if p == 0 else v1, x if p == 0 else x1, quad, c_out, f)
            if comps is not None:  # None: pruned at compile time (see run_explicit)
                _known_b(comps, t[k1] - coef[0] if p == 0 else t[k1], z if p == 0 else z1,
                         v if p == 0 else v1, f, scratch, fail)
            _integrate_b(scheme, lhs_inv, damping, stiffness, coef, z, v, a, f, p_ss, q_ss, x,
                         z1, v1, a1, x1, r)
        if fail[0] != 0:  # a kernel failed: as ode_force raising in the stepper
            return zs, vs, as_, xs, blew, n_done, fail[0], fail[1]
        head = head + 1 if head + 1 < span else 0
        _row_b(z1, v1, a1, eta, k1 + lead, chan_pos, eta_pos, row)
        for ch in range(nch):
            for c in range(nc):
                ring[head, ch, c] = row[ch, c]
        for d in range(nd):
            for c in range(nc):
                z[d, c], v[d, c], a[d, c] = z1[d, c], v1[d, c], a1[d, c]
                zs[c, n + 1, d], vs[c, n + 1, d], as_[c, n + 1, d] = z1[d, c], v1[d, c], a1[d, c]
        for s in range(ns):
            for c in range(nc):
                x[s, c] = x1[s, c]
                xs[c, n + 1, s] = x1[s, c]
        if n % 50 == 49 or n == n_steps - 1:  # divergence watch (as the NumPy loop)
            for c in range(nc):
                zmax[c] = 0.0
            for c in range(nc):
                for k in range(n - min(n, 49), n + 2):
                    for d in range(nd):
                        val = abs(zs[c, k, d])
                        # NaN fails every comparison: max(NaN, ...) made explicit as inf
                        zmax[c] = val if val > zmax[c] else (zmax[c] if val == val else np.inf)
            for c in range(nc):
                if not blew[c] and not (zmax[c] <= blowup * ref_amp[c]):
                    blew[c] = True
                    n_case[c] = n + 1
                    n_blew += 1
            if n_blew == nc:  # every case diverged: stop
                n_done = n + 1
                break
    for c in range(nc):  # a diverged case is NaN after the step its divergence was seen
        if blew[c]:
            zs[c, n_case[c] + 1:], vs[c, n_case[c] + 1:] = np.nan, np.nan
            as_[c, n_case[c] + 1:], xs[c, n_case[c] + 1:] = np.nan, np.nan
    return zs, vs, as_, xs, blew, n_done, 0, -1
