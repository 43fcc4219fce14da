"""True mirror symmetry planes (issue 15, item 1): ghosts of the fluid and of every solid.

The reference is the full domain itself: a quarter (or half) domain with mirror ghosts must
evolve exactly as the full domain does, because the full domain's solution is mirror
symmetric. With a body built from the lattice (same particles in both set-ups) the forces and
the motion agree to round-off; planes built as walls (the former set-up) do not.
"""

import numpy as np
import pytest

pytest.importorskip("pysph")

from hybridwsi.errors import InputError
from hybridwsi.sph import tank
from hybridwsi.sph.run import make_solver, run_case
from hybridwsi.sph.symmetry import ghost_tag, n_real

pytestmark = pytest.mark.sph

# a small tank: the body is 4 spacings from the side walls. The lattice start, so that the
# symmetric domains hold the full domain's particles exactly (the packing of a quarter and of
# the full tank differ by its last iterations: their forces then agree to 2e-4, measured)
KW = {"dp": 0.0375, "depth": 0.3, "half_width": 0.3, "t_release": 0.0, "smooth_body": False,
      "packing": "lattice"}


def test_no_walls_on_mirror_planes_and_ghosts_are_images():
    case = tank.decay3d(tf=0.01, **KW)
    assert case.mirror == (0, 1)
    assert np.all(case.wall.x >= 0) and np.all(case.wall.y >= 0)  # no wall on the planes
    solver = make_solver(case)
    rng = np.random.default_rng(1)
    n = n_real(case.fluid)
    for name in ("u", "v", "w"):
        getattr(case.fluid, name)[:n] = rng.normal(size=n)
    solver.nnps.update_domain()
    width = 2.0 * 2.0 * case.h  # two kernel supports of the Wendland quintic
    fl = {k: case.fluid.get(k, only_real_particles=False) for k in ("tag", *"xyzuvp")}
    real = fl["tag"] == 0
    assert np.all(fl["tag"][~real] == ghost_tag()) and real.sum() == n and n < len(real)
    # expected images: across x = 0, across y = 0 and across both (corners), same pressure
    x, y, z, u, v, p = (fl[k][real] for k in "xyzuvp")
    nx, ny = x <= width, y <= width
    exp = np.vstack([
        np.c_[-x[nx], y[nx], z[nx], -u[nx], v[nx], p[nx]],
        np.c_[x[ny], -y[ny], z[ny], u[ny], -v[ny], p[ny]],
        np.c_[-x[nx & ny], -y[nx & ny], z[nx & ny], -u[nx & ny], -v[nx & ny], p[nx & ny]],
    ])
    got = np.c_[tuple(fl[k][~real] for k in "xyzuvp")]
    key = lambda a: a[np.lexsort(np.round(a[:, :3], 9).T)]  # noqa: E731
    np.testing.assert_allclose(key(got), key(exp), atol=1e-12)
    # the body's images are there too (the fluid near a plane sees the whole sphere)
    wl = {k: case.wall.get(k, only_real_particles=False) for k in ("tag", "flag")}
    assert np.any((wl["tag"] != 0) & (wl["flag"] == 2))
    assert case.n_particles == n_real(case.fluid) + n_real(case.wall)


@pytest.mark.parametrize("domain", ["quarter", "half"])
def test_mirror_domain_reproduces_the_full_domain(domain):
    # a free body released 0.1 D above equilibrium, 15 steps: the quarter/half domain with
    # mirror ghosts and the full domain have the same particles near the body, so the whole
    # body's fluid force and motion must agree to round-off (symmetric solution)
    steps = 15
    dt = tank.decay3d(tf=0.01, **KW).dt
    res = {}
    for dom, sym in [(domain, "mirror"), ("full", "mirror"), (domain, "wall")]:
        case = tank.decay3d(tf=steps * dt, z0_over_d=0.1, domain=dom, symmetry=sym, **KW)
        case.output_dt = 5 * dt
        res[dom, sym] = run_case(case, progress=False)
    mir, full, wall = res[domain, "mirror"], res["full", "mirror"], res[domain, "wall"]
    f_full = full["F_fluid"].values[:, 0]
    np.testing.assert_allclose(mir["F_fluid"].values[:, 0], f_full, rtol=1e-8)
    np.testing.assert_allclose(mir["z"].values, full["z"].values, rtol=1e-8, atol=1e-12)
    # planes built as walls are not the full domain: the check above can fail
    assert np.max(np.abs(wall["F_fluid"].values[:, 0] / f_full - 1.0)) > 1e-3


# resume with mirror ghosts: tests/test_sph_tank.py::test_resume_gives_the_uninterrupted_result


def test_symmetry_options_are_checked():
    with pytest.raises(InputError, match="symmetry"):
        tank.decay3d(tf=0.01, symmetry="slip", **{k: v for k, v in KW.items()})
    with pytest.raises(InputError, match="domain"):
        tank.decay3d(tf=0.01, domain="eighth", **KW)
    with pytest.raises(InputError, match="quarter"):
        tank.regular3d(dp=0.0375, domain="quarter")
