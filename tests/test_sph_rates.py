"""The fused fluid rates (``FluidRates``) against a brute-force NumPy evaluation of the SPH sums.

Independent reference: continuity, hydrostatic-corrected delta-SPH density diffusion and
Monaghan momentum written out pair by pair over all particles (O(N^2)), with the pressures and
densities the solver's own EOS and wall groups produced. Uses the production kernel set
(no extra compile).
"""

import numpy as np
import pytest

pytest.importorskip("pysph")

from hybridwsi.sph import tank
from hybridwsi.sph.mdbc import wendland_quintic
from hybridwsi.sph.run import make_solver

pytestmark = pytest.mark.sph


def _pair_sums(xd, vd, rhod, pd, csd, xs, vs, rhos, ps, css, ms, h, c0, alpha, delta, rho0, g, dim):
    """d rho/dt and acceleration of each dest particle from every source (brute force)."""
    xij = xd[:, None, :] - xs[None, :, :]
    vij = vd[:, None, :] - vs[None, :, :]
    r2 = np.sum(xij ** 2, axis=2)
    r = np.sqrt(r2)
    _, dwdr = wendland_quintic(r, h, dim)
    with np.errstate(invalid="ignore", divide="ignore"):
        dw = np.where(r[..., None] > 1e-12, dwdr[..., None] * xij / r[..., None], 0.0)
    eps = 0.01 * h * h
    cont = np.sum(ms * np.sum(vij * dw, axis=2), axis=1)
    drho = rhod[:, None] - rhos[None, :] - rho0 * (xij @ g) / c0 ** 2
    diff = np.sum(delta * h * c0 * 2.0 * drho * np.sum(xij * dw, axis=2) / (r2 + eps)
                  * ms / rhos, axis=1)
    vx = np.sum(vij * xij, axis=2)
    rhoij = 0.5 * (rhod[:, None] + rhos[None, :])
    cij = 0.5 * (csd[:, None] + css[None, :])  # sound speeds from the EOS
    alpha = np.broadcast_to(alpha, (len(xs),))[None, :]  # one per source particle
    pi = np.where(vx < 0, -alpha * cij * (h * vx / (r2 + eps)) / rhoij, 0.0)
    tmp = pd[:, None] / rhod[:, None] ** 2 + ps[None, :] / rhos[None, :] ** 2
    acc = -np.sum((ms * (tmp + pi))[..., None] * dw, axis=1)
    return cont + diff, acc


@pytest.mark.parametrize("alpha_wall, alpha_body", [(None, None), (0.3, 0.02)])
def test_fused_rates_match_the_sph_sums(alpha_wall, alpha_body):
    case = tank.hydrostatic(dp=0.04, depth=0.4, length=0.6, init="hydrostatic")
    f, w = case.fluid, case.wall
    if alpha_body is not None:
        # the bottom's left half stands in for a body (flag 2): its own viscosity there
        w.flag[(w.y < 0.0) & (w.x < 0.3)] = 2.0
        case.alpha_wall, case.alpha_body = alpha_wall, alpha_body
    rng = np.random.default_rng(1)
    # a disturbed state so that every term (viscosity, diffusion, wall pairs) is non-zero
    f.u[:] = 0.05 * rng.standard_normal(len(f.u))
    f.v[:] = 0.05 * rng.standard_normal(len(f.v))
    f.rho[:] *= 1.0 + 2e-3 * rng.standard_normal(len(f.rho))
    solver = make_solver(case)
    solver.integrator.initial_acceleration(0.0, case.dt)

    pos = lambda pa: np.stack([pa.x, pa.y, pa.z], axis=1)  # noqa: E731
    vel = lambda pa: np.stack([pa.u, pa.v, pa.w], axis=1)  # noqa: E731
    g = np.array(case.gvec)
    common = dict(h=case.h, c0=case.c0, rho0=case.rho0, g=g, dim=2)
    arho_f, acc_f = _pair_sums(pos(f), vel(f), f.rho, f.p, f.cs, pos(f), vel(f), f.rho, f.p,
                               f.cs, f.m, alpha=case.alpha, delta=case.delta, **common)
    alpha_w = np.full(len(w.x), case.alpha if case.alpha_wall is None else case.alpha_wall)
    if alpha_body is not None:
        assert 0 < np.sum(w.flag == 2) < len(w.x)
        alpha_w[w.flag == 2] = alpha_body
    arho_w, acc_w = _pair_sums(pos(f), vel(f), f.rho, f.p, f.cs, pos(w), vel(w), w.rho, w.p,
                               w.cs, w.m, alpha=alpha_w, delta=0.0, **common)
    arho = arho_f + arho_w
    acc = acc_f + acc_w + g  # gravity (no ramp in a hydrostatic start)
    assert np.max(np.abs(arho)) > 1.0 and np.max(np.abs(acc[:, 0])) > 0.1  # not trivial
    np.testing.assert_allclose(f.arho, arho, rtol=0, atol=1e-9 * np.max(np.abs(arho)))
    for k, name in enumerate(("au", "av")):
        np.testing.assert_allclose(f.get(name), acc[:, k], rtol=0,
                                   atol=1e-9 * np.max(np.abs(acc)))
    # the integrator advects with the particle velocity (XSPH off)
    np.testing.assert_array_equal(f.ax, f.u)
    # the force on the body's particles (WallForce): the same pairs seen from the body
    body = w.flag == 2
    if np.any(body):
        pick = lambda a: a[body]  # noqa: E731
        _, acc_b = _pair_sums(pick(pos(w)), pick(vel(w)), pick(w.rho), pick(w.p), pick(w.cs),
                              pos(f), vel(f), f.rho, f.p, f.cs, f.m,
                              alpha=np.full(len(f.x), alpha_w[body][0]), delta=0.0, **common)
        force = w.m[body][:, None] * acc_b
        assert np.max(np.abs(force[:, 1])) > 0.0
        np.testing.assert_allclose(w.fy[body], force[:, 1], rtol=0,
                                   atol=1e-9 * np.max(np.abs(force)))
