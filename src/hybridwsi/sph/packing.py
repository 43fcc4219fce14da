"""Body-fitted particle packing of the fluid around a round body (issue 15, item 3).

A cubic lattice cut by a sphere leaves fluid particles 0 to 1 dp from its surface. Under
gravity the weakly compressible fluid then holds itself off the body with a thin over-pressured
layer, and the body acts about 0.03 dp too large (``docs/SPH_RUNS.md``, static gate). This
module moves the lattice points near the body, before the run, until their kernel sums are
complete: the packing relaxation of SPHinXsys (Zhu, Zhang & Hu 2021, Comput. Phys. Commun.
262:107849), i.e. particle shifting (Lind et al. 2012, J. Comput. Phys. 231:1499) iterated at
rest, each step

    dr_i = -C h^2 sum_j V_j grad W_ij,

with V_j = dp^dim for every particle (fluid, body, walls) and the step C chosen so that the
largest move is at most ``max_step`` dp. Only the fluid within ``band`` of the body surface
moves; the rest of the lattice, the body, the walls, the mirror images across the symmetry
planes and a layer of lattice points above the still-water level (so that the free surface
stays where it is) are fixed sources.

The lattice cut by the body holds the fluid volume only to within a few particles (at
R/dp = 5, 3-4 particles of the quarter tank, i.e. a still-water level 0.5 mm low and 0.5 % of
the sphere's buoyancy). Given the number of particles the exact fluid volume needs, the band
first takes or gives the difference (new particles where the band has the largest holes, or
the most crowded removed), so the packed fluid holds the exact volume to half a particle.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from hybridwsi.sph.mdbc import wendland_quintic


def _mirror(points: np.ndarray, axes: Sequence[int]) -> np.ndarray:
    """Images of ``points`` across the planes x_ax = 0 for each axis in ``axes`` (and their
    combinations)."""
    out = [points]
    for ax in axes:
        flipped = []
        for p in out:
            q = p.copy()
            q[:, ax] = -q[:, ax]
            flipped.append(q)
        out += flipped
    return np.vstack(out[1:]) if len(out) > 1 else np.zeros((0, points.shape[1]))


def kernel_gradient_sums(points: np.ndarray, sources: np.ndarray, h: float,
                         dim: int, volumes: np.ndarray | None = None) -> np.ndarray:
    """sum_j V_j grad W(x_i - x_j) [1/m] at each of ``points`` over ``sources`` of volumes
    ``volumes`` [m^dim] (default 1: the plain kernel-gradient sum; self-pairs excluded): the
    zeroth-order consistency residual, zero where the kernel support is complete."""
    tree = cKDTree(sources)
    pairs = cKDTree(points).sparse_distance_matrix(tree, 2.0 * h, output_type="coo_matrix")
    i, j, r = pairs.row, pairs.col, pairs.data
    keep = r > 1e-12
    i, j, r = i[keep], j[keep], r[keep]
    w = wendland_quintic(r, h, dim)[1] / r  # dW/dr / r
    if volumes is not None:
        w = w * volumes[j]
    d = points[i] - sources[j]
    out = np.zeros_like(points)
    for ax in range(dim):
        out[:, ax] = np.bincount(i, weights=w * d[:, ax], minlength=len(points))
    return out


def pack_around_body(fluid: np.ndarray, fixed: np.ndarray, centre: np.ndarray,
                     radius: float, dp: float, h: float, *, surface: float,
                     mirror_axes: Sequence[int] = (), band: float = 6.0,
                     iterations: int = 300, max_step: float = 0.02,
                     tol: float = 1e-3, n_total: int | None = None,
                     fixed_volumes: np.ndarray | None = None
                     ) -> tuple[np.ndarray, dict[str, float]]:
    """Relax the fluid particles near a round body to a body-fitted packing.

    Parameters
    ----------
    fluid : (n, dim) array
        Fluid particle positions [m] (a lattice cut by the body).
    fixed : (m, dim) array
        Solid particle positions [m] (body and tank walls): fixed sources.
    centre, radius : array, float
        The body's centre [m] and radius [m].
    dp, h : float
        Particle spacing and smoothing length [m].
    surface : float
        Still-water level [m] (vertical coordinate): lattice points above it, outside the body,
        are fixed sources so that the free surface keeps its place.
    mirror_axes : sequence of int
        Symmetry planes x_ax = 0: the images of every particle are sources.
    band : float
        Fluid particles within ``band`` dp of the body surface move [-].
    iterations, max_step, tol : int, float, float
        At most ``iterations`` steps of at most ``max_step`` dp; stop when the largest
        consistency residual dp |sum_j V_j grad W_ij| of the moving particles falls below
        ``tol``.
    n_total : int, optional
        The number of fluid particles the exact fluid volume needs (volume / dp^dim); the
        band gains or loses the difference before it is relaxed. None: keep the count.
    fixed_volumes : (m,) array, optional
        Volumes [m^dim] of the ``fixed`` particles (a body's shell particles hold their
        layer's volume, a few % off dp^dim); default dp^dim.

    Returns
    -------
    positions : (n, dim) array
        The packed fluid positions [m].
    info : dict
        ``residual_start``, ``residual`` (largest residual of the moving particles, [-]),
        ``iterations``, ``n_moving`` and ``n_added`` (negative: removed).
    """
    pos = fluid.copy()
    dist = np.linalg.norm(pos - centre, axis=1) - radius
    moving = dist < band * dp
    n_added = 0
    if n_total is not None and n_total != len(pos):
        n_added = int(n_total - len(pos))
        band_pts = _recount(pos[moving], pos[~moving], n_added, centre, radius, dp,
                            surface, band, (pos.min(axis=0), pos.max(axis=0)))
        pos = np.vstack([pos[~moving], band_pts])
        moving = np.r_[np.zeros(len(pos) - len(band_pts), bool), np.ones(len(band_pts), bool)]
    still, vstill = _fixed_sources(pos, moving, fixed, fixed_volumes, centre, radius, dp, h,
                                   surface, band)
    res0, res, it = _relax(pos, moving, still, vstill, centre, radius, dp, h, surface,
                           mirror_axes, iterations, max_step, tol)
    return pos, {"residual_start": res0, "residual": res, "iterations": it,
                 "n_moving": int(moving.sum()), "n_added": n_added}


def _fixed_sources(pos: np.ndarray, moving: np.ndarray, fixed: np.ndarray,
                   fixed_volumes: np.ndarray | None, centre: np.ndarray, radius: float,
                   dp: float, h: float, surface: float, band: float
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Positions [m] and volumes [m^dim] of the particles that stay put while the band moves:
    the solids, the far fluid and a lattice cap above the still-water level, those within
    reach of a moving particle only."""
    dim = pos.shape[1]
    vol = dp ** dim
    lo, hi = pos.min(axis=0) - 0.5 * dp, pos.max(axis=0) + 0.5 * dp
    cap_axes = [np.arange(lo[a] + 0.5 * dp, hi[a], dp) for a in range(dim - 1)]
    cap_axes.append(surface + (np.arange(math.ceil(2.0 * h / dp) + 1) + 0.5) * dp)
    cap = np.stack([m.ravel() for m in np.meshgrid(*cap_axes, indexing="ij")], axis=1)
    cap = cap[np.linalg.norm(cap - centre, axis=1) >= radius]
    # keep only the sources that can reach a moving particle
    reach = radius + (band + 2.0 * h / dp + 1.0) * dp
    still = np.vstack([fixed, cap, pos[~moving]])
    vstill = np.r_[np.full(len(fixed), vol) if fixed_volumes is None else fixed_volumes,
                   np.full(len(cap) + int((~moving).sum()), vol)]
    near = np.linalg.norm(still - centre, axis=1) < reach + 2.0 * h
    return still[near], vstill[near]


def _relax(pos: np.ndarray, moving: np.ndarray, still: np.ndarray, vstill: np.ndarray,
           centre: np.ndarray, radius: float, dp: float, h: float, surface: float,
           mirror_axes: Sequence[int], iterations: int, max_step: float, tol: float
           ) -> tuple[float, float, int]:
    """Move the ``moving`` particles of ``pos`` (in place) down the consistency residual
    dp |sum_j V_j grad W_ij| until it falls below ``tol``; returns the first and last
    residuals [-] and the iterations done (see :func:`pack_around_body`)."""
    dim = pos.shape[1]
    v = dim - 1
    vol = dp ** dim
    n_img = 1 + len(_mirror(np.zeros((1, dim)), mirror_axes))
    box_lo, box_hi = pos.min(axis=0), pos.max(axis=0)
    box_hi[v] = min(box_hi[v], surface - 0.5 * dp)
    res0 = res = float("nan")
    it = 0
    for it in range(1, iterations + 1):
        srcs = np.vstack([still, pos[moving]])
        srcs = np.vstack([srcs, _mirror(srcs, mirror_axes)])
        vsrc = np.tile(np.r_[vstill, np.full(int(moving.sum()), vol)], n_img)
        grad = kernel_gradient_sums(pos[moving], srcs, h, dim, vsrc)  # [1/m]
        res = float(np.max(np.linalg.norm(grad, axis=1)) * dp)
        if it == 1:
            res0 = res
        if res < tol:
            break
        step = -grad * h * h
        big = np.max(np.linalg.norm(step, axis=1))
        step *= min(1.0, max_step * dp / big)
        new = pos[moving] + step
        # stay out of the body
        d = new - centre
        r = np.linalg.norm(d, axis=1)
        inside = r < radius + 0.25 * dp
        new[inside] = centre + d[inside] * ((radius + 0.25 * dp) / r[inside])[:, None]
        # inside the lattice's box (walls, symmetry planes) and not above the lattice's top
        # layer: the fixed cap above the level has holes next to the body that would draw
        # the fluid up the body's dry side
        np.clip(new, box_lo, box_hi, out=new)
        pos[moving] = new
    return res0, res, it


def _recount(band_pts: np.ndarray, others: np.ndarray, n_add: int, centre: np.ndarray,
             radius: float, dp: float, surface: float, band: float,
             box: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """``band_pts`` with ``n_add`` points added where the band's holes are largest (on a
    half-spacing grid inside the fluid's box, clear of the body and the free surface) or,
    for ``n_add`` < 0, with the most crowded points removed."""
    dim = band_pts.shape[1]
    pts = band_pts.copy()
    if n_add < 0:
        for _ in range(-n_add):
            d, _ = cKDTree(np.vstack([pts, others])).query(pts, k=2)
            pts = np.delete(pts, int(np.argmin(d[:, 1])), axis=0)
        return pts
    lo = centre - radius - band * dp
    # half-spacing candidates: the hole finder's resolution
    axes = [np.arange(lo[a], centre[a] + radius + band * dp, 0.5 * dp) for a in range(dim)]
    cand = np.stack([m.ravel() for m in np.meshgrid(*axes, indexing="ij")], axis=1)
    r = np.linalg.norm(cand - centre, axis=1)
    ok = (r > radius + 0.5 * dp) & (r < radius + (band - 1.0) * dp)
    ok &= cand[:, dim - 1] < surface - 0.5 * dp
    ok &= np.all((cand >= box[0]) & (cand <= box[1]), axis=1)
    cand = cand[ok]
    for _ in range(n_add):
        d, _ = cKDTree(np.vstack([pts, others])).query(cand)
        k = int(np.argmax(d))
        pts = np.vstack([pts, cand[k]])
        cand = np.delete(cand, k, axis=0)
    return pts
