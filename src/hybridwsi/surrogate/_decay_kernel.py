"""Compiled free decays of the heave hybrid and their discrete adjoint (Numba).

The same RK4 rollout as :func:`hybridwsi.surrogate.multistep.torch_decays`,
``ẏ = L y + c + e_ż (N(z, ż) + z²(p₃ z + p₂))`` on the state ``y = (z, ż, x)``, with the
network ``N`` a tanh MLP; :func:`forward` records every stage's input and hidden activations,
:func:`adjoint` walks the steps back and returns the gradient of a loss with respect to the
network's (physical) weights and biases, given the loss's gradient with respect to the heave
at every step. The torch rollout records ~50 autograd operations per step and is bound by
their count (130 ms for a forward and backward of two 3.8-s decays); these loops take ~1 ms.

Layers are flat (``w`` the row-major weights, ``b`` the biases, ``sizes`` the widths
``(2, n_1, ..., 1)``), so that one compiled function serves every depth and width.
"""

from __future__ import annotations

import numpy as np

from hybridwsi._numba import HAVE_NUMBA, numba

#: RK4's stage offsets (in steps) and weights
_C = (0.0, 0.5, 0.5, 1.0)
_W = (1.0 / 6.0, 2.0 / 6.0, 2.0 / 6.0, 1.0 / 6.0)


def _jit(fn):
    return numba.njit(cache=True)(fn) if HAVE_NUMBA else fn


@_jit
def _mlp(w, b, sizes, x0, x1, act, buf_in, buf_out):
    """The MLP on the input ``(x0, x1)``, its hidden activations written into ``act``
    (concatenated); returns the scalar output. ``buf_in``, ``buf_out``: scratch of the
    largest width."""
    n_layer = sizes.shape[0] - 1
    buf_in[0], buf_in[1] = x0, x1
    ow, ob, oa = 0, 0, 0
    for k in range(n_layer):
        n_in, n_out = sizes[k], sizes[k + 1]
        for j in range(n_out):
            s = b[ob + j]
            for i in range(n_in):
                s += w[ow + j * n_in + i] * buf_in[i]
            buf_out[j] = s
        ow += n_in * n_out
        ob += n_out
        if k < n_layer - 1:
            for j in range(n_out):
                buf_in[j] = np.tanh(buf_out[j])
                act[oa + j] = buf_in[j]
            oa += n_out
    return buf_out[0]


@_jit
def _rhs(lin, bias, p3, p2, w, b, sizes, u, d, act, scratch):
    """``d = f(u)`` of one case (the state derivative), ``act`` the network's activations."""
    n = u.shape[0]
    for i in range(n):
        s = bias[i]
        for j in range(n):
            s += lin[i, j] * u[j]
        d[i] = s
    z = u[0]
    d[1] += _mlp(w, b, sizes, z, u[1], act, scratch[0], scratch[1]) + z * z * (z * p3 + p2)


@_jit
def forward(lin, bias, p3, p2, w, b, sizes, y0, steps):
    """Heave ``Z`` (n_case, n_step + 1) [m] of the decays from ``y0`` (n_case, n), RK4 with
    step lengths ``steps`` [s]; with the tape (stage inputs ``U``, activations ``A``)."""
    nc, n = y0.shape
    ns = steps.shape[0]
    n_act = 0
    for k in range(1, sizes.shape[0] - 1):
        n_act += sizes[k]
    z_out = np.empty((nc, ns + 1))
    tape_u = np.empty((ns, 4, nc, n))
    tape_a = np.empty((ns, 4, nc, max(n_act, 1)))
    y = y0.copy()
    u = np.empty(n)
    d = np.empty((4, n))
    scratch = np.empty((2, sizes.max()))
    for c in range(nc):
        z_out[c, 0] = y[c, 0]
        for k in range(ns):
            h = steps[k]
            for s in range(4):
                for i in range(n):
                    u[i] = y[c, i] + (_C[s] * h * d[s - 1, i] if s > 0 else 0.0)
                    tape_u[k, s, c, i] = u[i]
                _rhs(lin, bias, p3, p2, w, b, sizes, u, d[s], tape_a[k, s, c], scratch)
            for i in range(n):
                y[c, i] += h * (_W[0] * d[0, i] + _W[1] * d[1, i] + _W[2] * d[2, i]
                                + _W[3] * d[3, i])
            z_out[c, k + 1] = y[c, 0]
    return z_out, tape_u, tape_a


@_jit
def _rhs_vjp(lin, p3, p2, w, b, sizes, u, act, a, out, gw, gb, delta, prev):
    """``out = J(u)ᵀ a`` of :func:`_rhs`, and the weights' share ``a_ż ∂N/∂θ`` added to
    ``gw``, ``gb`` (the activations ``act`` of the forward pass at ``u``); ``delta``,
    ``prev``: scratch of the largest width."""
    n = u.shape[0]
    for j in range(n):
        s = 0.0
        for i in range(n):
            s += lin[i, j] * a[i]
        out[j] = s
    g = a[1]  # the network and the cubic enter ż's equation only
    z = u[0]
    out[0] += g * (3.0 * p3 * z * z + 2.0 * p2 * z)
    n_layer = sizes.shape[0] - 1
    delta[:] = 0.0  # gradient at the current layer's output
    delta[0] = g
    ow, ob, oa = w.shape[0], b.shape[0], 0  # offsets, walked back from the ends
    for k in range(1, n_layer):
        oa += sizes[k]
    for k in range(n_layer - 1, -1, -1):
        n_in, n_out = sizes[k], sizes[k + 1]
        ow -= n_in * n_out
        ob -= n_out
        if k > 0:
            oa -= n_in
        for j in range(n_out):
            gb[ob + j] += delta[j]
        for i in range(n_in):
            x_i = act[oa + i] if k > 0 else u[i]
            s = 0.0
            for j in range(n_out):
                gw[ow + j * n_in + i] += delta[j] * x_i
                s += w[ow + j * n_in + i] * delta[j]
            prev[i] = s * (1.0 - x_i * x_i) if k > 0 else s  # tanh' = 1 - tanh²
        for i in range(n_in):
            delta[i] = prev[i]
    out[0] += delta[0]
    out[1] += delta[1]


@_jit
def adjoint(lin, p3, p2, w, b, sizes, steps, tape_u, tape_a, grad_z):
    """Gradient ``(∂L/∂w, ∂L/∂b)`` of a loss whose gradient with respect to :func:`forward`'s
    ``Z`` is ``grad_z`` (n_case, n_step + 1): RK4's discrete adjoint, step by step back."""
    ns, _, nc, n = tape_u.shape
    gw, gb = np.zeros(w.shape[0]), np.zeros(b.shape[0])
    lam = np.empty(n)
    abar = np.empty((4, n))
    ubar = np.empty(n)
    delta, prev = np.empty(sizes.max()), np.empty(sizes.max())
    for c in range(nc):
        lam[:] = 0.0
        lam[0] = grad_z[c, ns]
        for k in range(ns - 1, -1, -1):
            h = steps[k]
            for s in range(4):
                for i in range(n):
                    abar[s, i] = _W[s] * h * lam[i]
            for s in range(3, -1, -1):
                _rhs_vjp(lin, p3, p2, w, b, sizes, tape_u[k, s, c], tape_a[k, s, c],
                         abar[s], ubar, gw, gb, delta, prev)
                for i in range(n):
                    lam[i] += ubar[i]
                    if s > 0:
                        abar[s - 1, i] += _C[s] * h * ubar[i]
            lam[0] += grad_z[c, k]
    return gw, gb


def flat_layers(layers: list[tuple[np.ndarray, np.ndarray]]
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(w, b, sizes)`` of a list of ``(weight (n_out, n_in), bias (n_out,))`` pairs."""
    sizes = np.array([layers[0][0].shape[1]] + [wk.shape[0] for wk, _ in layers], dtype=np.int64)
    w = np.concatenate([np.ascontiguousarray(wk, dtype=float).ravel() for wk, _ in layers])
    b = np.concatenate([np.asarray(bk, dtype=float).ravel() for _, bk in layers])
    return w, b, sizes


@_jit
def structured_decays(z_tab, f_tab, ar, br, cr, m0, coef, h0, dt, n_steps, radius):
    """Heave (n_run, n_steps + 1) [m] of the structured decays of
    :func:`hybridwsi.surrogate.structured.integrate_decay` (constant A∞): RK4 in the same
    arithmetic, one run after the other; NaN from where a run leaves ``|z| <= radius``."""
    n_run, ns = h0.shape[0], ar.shape[0]
    nst = 2 + ns
    zs = np.full((n_run, n_steps + 1), np.nan)
    y, u = np.empty(nst), np.empty(nst)
    d = np.empty((4, nst))
    for c in range(n_run):
        a1, a2, b1, b2, k1, k3 = coef[c, 0], coef[c, 1], coef[c, 2], coef[c, 3], coef[c, 4], \
            coef[c, 5]
        y[:] = 0.0
        y[0] = h0[c]
        zs[c, 0] = h0[c]
        for k in range(n_steps):
            for s in range(4):
                for i in range(nst):
                    u[i] = y[i] + (_C[s] * dt) * d[s - 1, i] if s > 0 else y[i]
                z, v = u[0], u[1]
                xc = 0.0
                for j in range(ns):
                    xc += u[2 + j] * cr[j]
                f = np.interp(z, z_tab, f_tab) - xc - b1 * v - b2 * abs(v) * v - k1 * z \
                    - k3 * z ** 3
                d[s, 0] = v
                d[s, 1] = f / (m0 + a1 * z + a2 * z * z)
                for i in range(ns):
                    acc = 0.0
                    for j in range(ns):
                        acc += u[2 + j] * ar[i, j]
                    d[s, 2 + i] = acc + v * br[i]
            for i in range(nst):
                y[i] = y[i] + (dt / 6.0) * (d[0, i] + 2 * d[1, i] + 2 * d[2, i] + d[3, i])
            if not (np.isfinite(y[0]) and abs(y[0]) <= radius):
                break  # left the water / diverged: NaN from here
            zs[c, k + 1] = y[0]
    return zs
