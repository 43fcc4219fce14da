"""First-order (mDBC) boundary density of a floating body with an analytic surface.

Modified dynamic boundary conditions (English, Domínguez, Vacondio, Crespo, Stansby, Lind,
Chiapponi & Gómez-Gesteira 2022, Comp. Part. Mech. 9:911, "Modified dynamic boundary conditions
(mDBC) for general-purpose smoothed particle hydrodynamics (SPH)"; the CPU kernel is
``JSphCpu::InteractionMdbcCorrectionT2`` in DualSPHysics 5.0, ``src/source/JSphCpu.cpp``):

1. each boundary particle b has a ghost node g, its mirror point across the body surface along
   the surface normal (here the sphere/circle is analytic: g = c + (2R - |b - c|) n,
   n = (b - c)/|b - c|);
2. at g, the density and its gradient are interpolated from the fluid with the first-order
   (Liu & Liu 2006) kernel correction: with r_gj = x_g - x_j and V_j = m_j / rho_j,

       A = sum_j V_j [[W_gj, r_gj^T W_gj], [grad W_gj, grad W_gj r_gj^T]]  ((dim+1)^2),
       [rho_g, -grad rho_g] = A^-1 sum_j m_j [W_gj, grad W_gj]

   (``a_corr3`` and ``rhopp1``/``gradrhopp1`` there; grad W_gj is the gradient with respect to
   x_g, so the second block solves for minus the density gradient, as DualSPHysics' sign);
3. if |det A| < 1e-3 (DualSPHysics' ``determlimit``: the node lacks fluid on some side, near
   the free surface) the Shepard value rho_g = sum_j m_j W_gj / sum_j V_j W_gj is used;
4. the boundary particle's density is rho_b = rho_g + grad rho_g . (x_b - x_g); its pressure
   follows from the fluid's Tait EOS (negative pressure of a wet particle is kept);
5. a node with no fluid in its support is dry: rho_b = rho0, so p_b = 0 and the particle
   exerts no pressure of its own (DualSPHysics keeps ``RhopZero`` for it).

The extrapolation is done with NumPy and SciPy's k-d tree (the ghost node of an inner body
layer lies ~2.5 spacings into the fluid, beyond the particle's own neighbour search radius),
as the ``post`` callable of the wall-pressure group: it overwrites the density and pressure of
the body particles (real and mirror ghosts) after the Adami extrapolation of every wall.
Fixed tank walls keep Adami's extrapolation, which includes the hydrostatic term and is
already exact for a linear (hydrostatic) pressure field.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

#: DualSPHysics' ``determlimit`` (first-order correction when |det A| is at least this)
DET_LIMIT = 1e-3


def wendland_quintic(r: np.ndarray, h: float | np.ndarray, dim: int
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Wendland quintic W(r, h) [1/m^dim] and dW/dr [1/m^(dim+1)] (support 2h), the kernel of
    the solver (PySPH ``WendlandQuintic``: W = fac (1 - q/2)^4 (2q + 1), q = r/h); ``h`` [m]
    may be an array broadcast against ``r``."""
    q = np.asarray(r, dtype=float) / h
    fac = (7.0 / (4.0 * math.pi) if dim == 2 else 21.0 / (16.0 * math.pi)) / h ** dim
    t = np.clip(1.0 - 0.5 * q, 0.0, None)
    w = fac * t ** 4 * (2.0 * q + 1.0)
    dwdr = -5.0 * fac * q * t ** 3 / h
    return w, dwdr


def sphere_ghost_nodes(pos: np.ndarray, centre: np.ndarray, radius: float) -> np.ndarray:
    """Mirror points [m] of ``pos`` (one row per particle, inside the body) across the surface
    of the sphere (3D) or circle (2D) of ``radius`` [m] about ``centre``, along its normal."""
    d = pos - centre[None, :]
    r = np.linalg.norm(d, axis=1)
    # a particle at the centre has no normal; never the case for shells (r >= R - n dp > 0)
    n = d / np.maximum(r, 1e-12)[:, None]
    return centre[None, :] + (2.0 * radius - r)[:, None] * n


def extrapolated_density(nodes: np.ndarray, targets: np.ndarray, fluid_pos: np.ndarray,
                         fluid_m: np.ndarray, fluid_rho: np.ndarray, h: float, rho0: float,
                         det_limit: float = DET_LIMIT) -> tuple[np.ndarray, np.ndarray]:
    """Density [kg/m^3] at ``targets`` extrapolated from the fluid at ``nodes`` (mDBC).

    Returns the densities and a code per target: 1 first-order, 0 Shepard (ill-conditioned
    correction matrix), -1 dry (no fluid within 2h of the node: rho0)."""
    n_t, dim = nodes.shape
    rho_out = np.full(n_t, float(rho0))
    mode = np.full(n_t, -1, dtype=int)
    if n_t == 0 or len(fluid_pos) == 0:
        return rho_out, mode
    # the fluid near the nodes only (a k-d tree of the whole tank would cost more)
    lo, hi = nodes.min(axis=0) - 2.0 * h, nodes.max(axis=0) + 2.0 * h
    near = np.all((fluid_pos >= lo) & (fluid_pos <= hi), axis=1)
    fp, fm, frho = fluid_pos[near], fluid_m[near], fluid_rho[near]
    if len(fp) == 0:
        return rho_out, mode
    pairs = cKDTree(nodes).sparse_distance_matrix(cKDTree(fp), 2.0 * h,
                                                  output_type="ndarray")
    g, j, r = pairs["i"], pairs["j"], pairs["v"]
    keep = r < 2.0 * h
    g, j, r = g[keep], j[keep], r[keep]
    rgj = nodes[g] - fp[j]
    w, dwdr = wendland_quintic(r, h, dim)
    gradw = (dwdr / np.maximum(r, 1e-12))[:, None] * rgj  # gradient with respect to x_g
    vol = fm[j] / frho[j]
    # rows of the correction: [W, grad W]; columns: [1, r_gj]
    rows = np.concatenate([w[:, None], gradw], axis=1)  # (pairs, dim+1)
    cols = np.concatenate([np.ones((len(r), 1)), rgj], axis=1)
    amat = np.zeros((n_t, dim + 1, dim + 1))
    np.add.at(amat, g, vol[:, None, None] * rows[:, :, None] * cols[:, None, :])
    rhs = np.zeros((n_t, dim + 1))
    np.add.at(rhs, g, fm[j][:, None] * rows)
    wet = amat[:, 0, 0] > 0.0
    det = np.linalg.det(amat)
    first = wet & (np.abs(det) >= det_limit)
    if np.any(first):
        sol = np.linalg.solve(amat[first], rhs[first][:, :, None])[:, :, 0]
        grad = -sol[:, 1:]  # the gradient block solves for -grad rho (r_gj = x_g - x_j)
        rho_out[first] = sol[:, 0] + np.sum(grad * (targets[first] - nodes[first]), axis=1)
        mode[first] = 1
    shep = wet & ~first
    rho_out[shep] = rhs[shep, 0] / amat[shep, 0, 0]
    mode[shep] = 0
    return rho_out, mode


def tait_pressure(rho: np.ndarray, rho0: float, c0: float, gamma: float = 7.0) -> np.ndarray:
    """Tait equation of state p = rho0 c0^2 / gamma ((rho / rho0)^gamma - 1) [Pa] (PySPH's
    ``TaitEOS``, the fluid's)."""
    return rho0 * c0 * c0 / gamma * ((rho / rho0) ** gamma - 1.0)


def body_boundary_post(case: Any) -> Any:
    """The ``post`` callable of the wall-pressure group for an mDBC body: sets the density and
    pressure of every body particle (real and mirror ghosts) from :func:`extrapolated_density`
    at its ghost node across the case's analytic body surface (``case.body_surface``)."""
    from hybridwsi.sph.equations import B_Z, FLAG_BODY

    centre_eq, radius = case.body_surface
    centre_eq = np.asarray(centre_eq, dtype=float)
    fluid, wall, v = case.fluid, case.wall, case.vaxis
    axes = "xyz"[:case.dim]

    def post() -> None:
        sel = np.flatnonzero(wall.get("flag", only_real_particles=False) == FLAG_BODY)
        if len(sel) == 0:
            return
        centre = centre_eq.copy()
        centre[v] += wall.body[B_Z]
        pos = np.stack([wall.get(a, only_real_particles=False)[sel] for a in axes], axis=1)
        fpos = np.stack([fluid.get(a, only_real_particles=False) for a in axes], axis=1)
        nodes = sphere_ghost_nodes(pos, centre, radius)
        rho, mode = extrapolated_density(
            nodes, pos, fpos, fluid.get("m", only_real_particles=False),
            fluid.get("rho", only_real_particles=False), case.h, case.rho0)
        # the EOS clamp of the Adami extrapolation: strong suction stays finite
        rho = np.maximum(rho, case.rho0 * 0.5 ** (1.0 / case.gamma))
        wall.get("rho", only_real_particles=False)[sel] = rho
        wall.get("p", only_real_particles=False)[sel] = tait_pressure(
            rho, case.rho0, case.c0, case.gamma)
        post.last_mode = mode  # for diagnostics and tests

    post.last_mode = np.zeros(0, dtype=int)
    return post
