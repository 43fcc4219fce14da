"""Linearisation of a force network: alpha_s, beta_s, gamma_s by autograd (docs/THEORY.md §4b).

For ``F_net(x)`` with ``x`` containing the current (lag-0) ``zddot``, ``zdot`` and ``z``, the
surrogate's sensitivities are exactly

``alpha_s = dF/dzddot`` [kg], ``beta_s = dF/dzdot`` [N s/m], ``gamma_s = dF/dz`` [N/m],

evaluated at any state. A kinematic the network does not see contributes zero. The matrices
(n_dof x n_dof, row = force dof, column = kinematic dof) are what the stability checks of
:mod:`hybridwsi.diagnostic.stability` take in place of the regression's alpha, beta, gamma.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.surrogate.features import build_features
from hybridwsi.surrogate.network import ForceNetwork, torch


@dataclass
class SurrogateLinearisation:
    """Sensitivities of a network, per state and averaged.

    Attributes
    ----------
    alpha, beta, gamma : ndarray, shape (n_dof, n_dof)
        Trajectory-averaged sensitivities [kg, N s/m, N/m].
    alpha_t, beta_t, gamma_t : ndarray, shape (n_states, n_dof, n_dof)
        Sensitivities at each evaluated state.
    """

    alpha: np.ndarray
    beta: np.ndarray
    gamma: np.ndarray
    alpha_t: np.ndarray
    beta_t: np.ndarray
    gamma_t: np.ndarray

    def to_dict(self) -> dict:
        out = {k: getattr(self, k).tolist() for k in ("alpha", "beta", "gamma")}
        for k in ("alpha", "beta", "gamma"):
            v = getattr(self, k + "_t")
            out[k + "_range"] = [v.min(0).tolist(), v.max(0).tolist()]
        return out


def feature_jacobian(net: ForceNetwork, x: np.ndarray) -> np.ndarray:
    """dF/dx of the physical-unit network at each row of ``x``, shape (n, n_dof, n_features).

    Rows are independent (no batch coupling), so one backward pass per output dof gives the
    exact per-row Jacobian.
    """
    net._check_fitted()
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or x.shape[1] != net.spec_.n_features:
        raise InputError(f"features have shape {x.shape}; expected (n, {net.spec_.n_features})")
    xt = torch.tensor(x, device=net.device, requires_grad=True)
    y = net.forward(xt)
    jac = np.empty((x.shape[0], y.shape[1], x.shape[1]))
    for j in range(y.shape[1]):
        (g,) = torch.autograd.grad(y[:, j].sum(), xt, retain_graph=j + 1 < y.shape[1])
        jac[:, j, :] = g.detach().cpu().numpy()
    return jac


def linearise_features(net: ForceNetwork, x: np.ndarray) -> SurrogateLinearisation:
    """alpha_s, beta_s, gamma_s at the states given as feature rows ``x`` (n, n_features)."""
    jac = feature_jacobian(net, np.atleast_2d(x))
    n, nd = jac.shape[0], jac.shape[1]
    mats = []
    for name in ("zddot", "zdot", "z"):
        cols = net.spec_.current_columns(name)
        mats.append(np.zeros((n, nd, nd)) if cols is None else jac[:, :, cols])
    a, b, c = mats
    return SurrogateLinearisation(a.mean(0), b.mean(0), c.mean(0), a, b, c)


def linearise(net: ForceNetwork, hist: xr.Dataset, *, stride: int = 1) -> SurrogateLinearisation:
    """alpha_s, beta_s, gamma_s along a trajectory (every ``stride``-th sample) and averaged."""
    x = build_features(hist, net.spec_)[:: max(1, int(stride))]
    return linearise_features(net, x)


def linearise_at(net: ForceNetwork, z, zdot, zddot, eta=None) -> SurrogateLinearisation:
    """Sensitivities at one steady state: every lag equal to the given (z, zdot, zddot, eta)."""
    spec = net.spec_
    values = {"z": z, "zdot": zdot, "zddot": zddot, "eta": eta if eta is not None else 0.0}
    chan = []
    for name in spec.inputs:
        width = spec.n_probe if name == "eta" else spec.n_dof
        chan.append(np.broadcast_to(np.asarray(values[name], dtype=float), (width,)))
    row = np.tile(np.concatenate(chan), spec.window)
    return linearise_features(net, row[None, :])
