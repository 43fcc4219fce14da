"""Initial state of the SPH floating-body cases (issue 15, item 3): body-fitted packing of the
fluid around the sphere, exact fluid volume, and masses consistent with the initial
hydrostatic density (the SPH hydrostatic balance holds in the initial state)."""

import functools
import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from hybridwsi.bodies import cap_volume
from hybridwsi.sph import tank
from hybridwsi.sph.mdbc import wendland_quintic

pytest.importorskip("pysph")

DP, DEPTH, HW = 0.03, 0.45, 0.3
R = tank.SPHERE_D / 2


def _case(z=0.0, packing=None):
    """The held sphere's tank at height z [m], ``packing`` None: decay3d's default (built once
    per module: the packing takes seconds and the tests only read the case)."""
    return _built(float(z), packing)


@functools.lru_cache(maxsize=None)
def _built(z, packing):
    kw = {} if packing is None else {"packing": packing}
    return tank.decay3d(dp=DP, depth=DEPTH, half_width=HW, free=False, z0_over_d=z / tank.SPHERE_D,
                        tf=0.01, t_release=0.0, **kw)


def _xyz(pa):
    return np.c_[pa.x, pa.y, pa.z]


def _surface_distance(pts, z):
    return np.linalg.norm(pts - [0.0, 0.0, DEPTH + z], axis=1) - R


@pytest.mark.parametrize("z", [-0.03, 0.0, 0.03])
def test_packed_fluid_holds_the_exact_volume(z):
    # quarter tank less a quarter of the immersed spherical cap (closed form), in particles
    exact = (HW * HW * DEPTH - cap_volume(R - z, R) / 4) / DP ** 3
    lattice = _case(z, packing="lattice")
    packed = _case(z)  # the body cases' default
    assert abs(len(packed.fluid.x) - exact) <= 0.5
    # the cut lattice misses by a few particles at R/dp = 5 (0.5 % of the buoyancy)
    assert abs(len(lattice.fluid.x) - exact) > 1.0
    assert packed.inputs["packing"] == "packed" and lattice.inputs["packing"] == "lattice"


def test_packing_fits_the_fluid_to_the_body():
    lattice, packed = _case(packing="lattice"), _case()  # packed: the default
    info = packed.packing_info
    # zeroth-order consistency residual dp |sum_j V_j grad W_ij| of the moved particles
    assert info["residual"] < 0.25 * info["residual_start"], info
    p, q = _xyz(packed.fluid), _xyz(lattice.fluid)
    sp, sq = _surface_distance(p, 0.0), _surface_distance(q, 0.0)
    # nothing inside the body, above the lattice's top layer or outside the tank
    assert sp.min() >= 0.25 * DP - 1e-12
    assert p[:, 2].max() <= DEPTH - 0.5 * DP + 1e-12
    assert p.min() >= 0.5 * DP - 1e-12 and p[:, :2].max() <= HW - 0.5 * DP + 1e-12
    # the first fluid layer: half a spacing from the surface, as at a flat wall (the cut
    # lattice leaves it anywhere from 0 to 1 dp, on average further out)
    first_p = sp[sp < 1.0 * DP]
    assert np.median(first_p) == pytest.approx(0.5 * DP, abs=0.1 * DP)
    assert np.median(sq[sq < 1.0 * DP]) > np.median(first_p) + 0.1 * DP
    # no two particles closer than half a spacing
    d, _ = cKDTree(p).query(p, k=2)
    assert d[:, 1].min() > 0.5 * DP


def _pressure_acceleration(pa, pressure, h):
    """Vertical SPH pressure acceleration -sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) dW/dz of the
    fluid on itself (PySPH's Wendland quintic) with the particles' ``pressure`` [Pa], at every
    particle [m/s^2]."""
    x = _xyz(pa)
    # mirror images across the symmetry planes x = 0 and y = 0
    imgs = [x * s for s in ([1, 1, 1], [-1, 1, 1], [1, -1, 1], [-1, -1, 1])]
    src = np.vstack(imgs)
    m, rho, p = (np.tile(a, 4) for a in (pa.m, pa.rho, pressure))
    pairs = cKDTree(x).sparse_distance_matrix(cKDTree(src), 2 * h, output_type="coo_matrix")
    i, j, r = pairs.row, pairs.col, pairs.data
    keep = r > 0
    i, j, r = i[keep], j[keep], r[keep]
    dwdz = wendland_quintic(r, h, 3)[1] / r * (x[i, 2] - src[j, 2])
    term = -m[j] * (pressure[i] / pa.rho[i] ** 2 + p[j] / rho[j] ** 2) * dwdz
    return np.bincount(i, weights=term, minlength=len(x))


@pytest.mark.parametrize("packing_mode, tol", [("packed", 0.002), ("lattice", None)])
def test_initial_hydrostatic_state_balances_gravity(packing_mode, tol):
    # The initial density is hydrostatic, rho0 (1 + p / B)^(1/7). With masses rho0 dp^3 the
    # particles' volume m / rho disagrees with the lattice's dp^3 by (d - z) / (100 d) and the
    # momentum equation's p_i sum_j V_j grad W_ij term lifts the fluid: the pressure must be
    # ~2 % steeper than hydrostatic near the bottom to hold it. With m = rho dp^3 it balances.
    case = _case(packing=None if packing_mode == "packed" else packing_mode)  # packed: default
    fl = case.fluid
    pressure = case.rho0 * case.c0 ** 2 / 7 * ((fl.rho / case.rho0) ** 7 - 1)
    a = _pressure_acceleration(fl, pressure, case.h)
    x = _xyz(fl)
    s = _surface_distance(x, 0.0)
    # interior: away from the body, the walls and the free surface (complete kernel support)
    inner = ((s > 3 * DP) & (x[:, 2] > 3 * DP) & (x[:, 2] < DEPTH / 3)
             & (x[:, 0] < HW - 3 * DP) & (x[:, 1] < HW - 3 * DP))
    # the initial pressure is rho0 g (d - z), so the continuum balance is (1/rho) dp/dz = g
    # rho0 / rho: compare with that
    ratio = float(np.mean(a[inner] * fl.rho[inner] / case.rho0) / case.g)
    if tol is not None:
        assert ratio == pytest.approx(1.0, abs=tol)
        assert np.allclose(fl.m / fl.rho, DP ** 3, rtol=1e-12)
    else:
        assert ratio < 0.99  # the former initial state: the pressure must steepen to hold it


def test_fluid_count_closed_forms():
    # half-immersed sphere, a quarter of it in the domain: (2/3 pi R^3) / 4
    n = tank._fluid_count(90_000, 0.01, 0.15, 0.0, 3, "quarter")
    assert n == 90_000 - round(math.pi * 0.15 ** 3 / 6 / 1e-6)
    # 2D: half-immersed circle, pi R^2 / 2; a circle 0.1 m above its half-immersed height
    n2 = tank._fluid_count(4_500, 0.01, 0.15, 0.0, 2, "full")
    assert n2 == 4_500 - round(math.pi * 0.15 ** 2 / 2 / 1e-4)
    seg = 0.15 ** 2 * math.acos(0.1 / 0.15) - 0.1 * math.sqrt(0.15 ** 2 - 0.1 ** 2)
    assert tank._fluid_count(4_500, 0.01, 0.15, 0.1, 2, "full") == 4_500 - round(seg / 1e-4)


@pytest.mark.parametrize("dp, domain, quarter, half", [(0.03, "quarter", True, False),
                                                       (0.025, "half", False, True),
                                                       (0.0375, "full", False, False)])
def test_shell_volumes_add_up_to_the_shell(dp, domain, quarter, half):
    # each particle of a round shell stands for its layer's share: the sum over the body is
    # the spherical shell between R - n dp and R (the domain's share of it)
    n = 3
    pts = tank.round_shell(np.zeros(3), R, dp, n, quarter=quarter, half=half, mirrored=True)
    vol = tank.shell_volumes(pts, np.zeros(3), R, dp, domain)
    share = {"quarter": 0.25, "half": 0.5, "full": 1.0}[domain]
    assert vol.sum() == pytest.approx(share * 4 / 3 * math.pi * (R ** 3 - (R - n * dp) ** 3),
                                      rel=1e-12)
    assert np.all(np.abs(vol / dp ** 3 - 1) < 0.1)
    # 2D: annuli
    ring = tank.round_shell(np.zeros(2), R, dp, n)
    v2 = tank.shell_volumes(ring, np.zeros(2), R, dp)
    assert v2.sum() == pytest.approx(math.pi * (R ** 2 - (R - n * dp) ** 2), rel=1e-12)


@pytest.mark.parametrize("h", [(1.0, 1.25, 1.5625), (1.0, 1.2, 1.5), (0.0214, 0.025, 0.03)])
def test_grid_convergence_recovers_order_and_limit(h):
    from hybridwsi.sph.decay import grid_convergence

    # f(h) = f0 + C h^p: the observed order is p, the extrapolation f0, for equal and unequal
    # refinement ratios (Celik et al. 2008)
    f0, c, p = 0.770, 0.35, 2.0
    out = grid_convergence(tuple(f0 + c * x ** p for x in h), h)
    assert out["order"] == pytest.approx(p, rel=1e-8)
    assert out["extrapolated"] == pytest.approx(f0, rel=1e-10)
    assert out["monotone"]
    # in the asymptotic range the GCI is the safety factor times f1's true relative error
    f1 = f0 + c * h[0] ** p
    assert out["gci_fine"] == pytest.approx(1.25 * abs(f1 - f0) / f1, rel=1e-8)
    # oscillating or diverging triples are flagged
    assert not grid_convergence((1.0, 1.1, 1.05), h)["monotone"]


def test_damped_oscillator_fit_recovers_period_damping_and_equilibrium():
    from hybridwsi.history import fit_damped_oscillator

    t = np.arange(0.0, 1.9, 0.005)
    td, zeta, zeq = 0.770, 0.088, 0.002
    wd = 2 * math.pi / td
    sigma = zeta * wd / math.sqrt(1 - zeta ** 2)
    z = 0.03 * np.exp(-sigma * t) * np.cos(wd * t + 0.1) + zeq
    z += np.random.default_rng(0).normal(0, 2e-5, t.size)
    fit = fit_damped_oscillator(t, z, period_guess=0.75)
    assert fit["period_d"] == pytest.approx(td, rel=1e-3)
    assert fit["zeta"] == pytest.approx(zeta, rel=1e-2)
    assert fit["z_eq"] == pytest.approx(zeq, abs=1e-4)
    assert np.isnan(fit_damped_oscillator(t[:10], z[:10], 0.75)["period_d"])
