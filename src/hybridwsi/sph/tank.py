"""Case builder for the SPH numerical wave tank (2D and 3D).

Every case uses the same two particle arrays (``fluid``, ``wall``) and the same equation set
(:func:`make_equations`); cases differ only in geometry, wall flags and parameter values.
PySPH therefore compiles one kernel per dimension and reuses it (compile ~1 min, cached in
``~/.pysph``).

Coordinates: x along the tank, vertical axis y in 2D and z in 3D, free surface at the still
water depth ``depth`` above the bottom (bottom at vertical coordinate 0).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hybridwsi.bodies import cap_volume
from hybridwsi.errors import InputError
from hybridwsi.sph import wavemaker
from hybridwsi.sph.mdbc import wendland_quintic
from hybridwsi.sph.packing import pack_around_body

RHO_WATER = 998.2
G = 9.81
CASES = ("hydrostatic", "dam_break", "waves2d", "waves3d", "decay3d", "regular3d", "decay2d")

# Kramer et al. (2021) sphere (see src/hybridwsi/data/kramer2021_sphere_decay/README.md)
SPHERE_D = 0.300
SPHERE_MASS = 7.056
KRAMER_G = 9.82
KRAMER_DEPTH = 0.9
# Artificial viscosity of the floating-body cases. It acts like a kinematic viscosity
# nu = alpha h c0 / (2 (dim + 2)) (Monaghan 2005, Rep. Prog. Phys. 68:1703); with c0 = 10 sqrt(g d)
# the old alpha = 0.1 gave nu ~ 0.01 m^2/s at dp = D/8 (Re = w R / nu ~ 4): the sphere's first
# trough was -0.37 H0 instead of the measured -0.85 and the period looked 26 % long. delta-SPH
# density diffusion keeps alpha = 0.005 stable (checked over 1.2 s at dp = D/8 and D/10).
BODY_ALPHA = 0.005
# Artificial viscosity between the fluid and the solids (body and tank walls) of the decay
# cases: none. Against a wall the viscosity nu = alpha h c0 / 10 has a Stokes layer of about
# half a particle spacing at every resolution (0.42 dp at D/10, 0.50 dp at D/14), so the drag it
# puts on the body, rho alpha (h/dp) c0 A U / 10, does not vanish with refinement: ~3 N s/m on
# the sphere at alpha = 0.005, ten times the laminar skin friction of water (rho sqrt(nu w / 2)
# A ~ 0.3 N s/m), a damping ratio of ~0.01-0.02 that no ladder removes. Without it the first
# trough and the damping ratio approach the experiment's from D/10 to D/12 instead of leaving
# them (docs/SPH_RUNS.md, "No artificial viscosity between the fluid and the body"; DualSPHysics
# scales the same term by its ViscoBoundFactor). The wave flumes keep alpha at their walls (their paddle
# gain was calibrated so).
BODY_ALPHA_WALL = 0.0
# h/dp of the floating-body cases. On a lattice the Wendland quintic's gradient moment
# sum_j V_j (x_j - x_i) dW/dx_i is 0.979 at h/dp = 1.3 (3D; 0.974 in 2D), so the fluid settles
# with a pressure ~2 % above hydrostatic and the body floats high; it is 1.0006 at 1.5. Measured
# on the sphere's first decay cycle (D/10, depth 0.6 m): first trough -0.755 H0 at 1.3,
# -0.803 at 1.5 (experiment -0.853).
BODY_HDX = 1.5
# Hold before release [s]: the lattice fluid around the body relaxes (acoustic period
# 4 d / c0 ~ 0.1 s) while the body is held, as the experiment holds the sphere in still water.
BODY_HOLD = 0.3
# Initial state of the body cases: the fluid near the body packed to fit it, with consistent
# masses (``"packed"``, :mod:`hybridwsi.sph.packing`), and the hold ended by a damped
# relaxation once the rms fluid speed is below BODY_RELAX sqrt(g d). Measured against the
# lattice start (``"lattice"``, the default before issue 15; docs/SPH_RUNS.md): static gate at
# D/10 buoyancy -0.35 % of the weight instead of +1.77 %; validation-tank decay at D/10 RMS of
# heave/H0 0.032 instead of 0.075, the first trough consistent across resolutions.
BODY_PACKING = "packed"
BODY_RELAX = 1e-3


@dataclass
class SPHCase:
    """Everything a run needs: particles, numerical parameters, probes and monitors."""

    name: str
    dim: int
    dp: float
    depth: float
    tf: float
    fluid: Any
    wall: Any
    rho0: float = 1000.0
    c0: float = 20.0
    gamma: float = 7.0
    g: float = G
    hdx: float = 1.3
    alpha: float = 0.1
    #: artificial viscosity between fluid and solid particles (None: ``alpha``)
    alpha_wall: float | None = None
    #: artificial viscosity between fluid and the body's particles (None: ``alpha_wall``'s)
    alpha_body: float | None = None
    delta: float = 0.1
    xsph_eps: float = 0.0
    cfl: float = 0.2
    t_ramp: float = 0.0
    damping: tuple[float, float, float] = (1e30, 2e30, 0.0)
    #: damping zone measured from the side walls of a centred tank instead of along x
    damping_radial: bool = False
    output_dt: float = 0.01
    probes: list[tuple[float, float]] = field(default_factory=list)
    monitors: dict[str, Callable[[Any, Any], float]] = field(default_factory=dict)
    body_mass: float | None = None
    #: a free body is held until this time [s]; the history starts at the release (t = 0)
    t_release: float = 0.0
    inputs: dict[str, Any] = field(default_factory=dict)
    #: axes whose zero plane is a true mirror-symmetry plane (0: x = 0, 1: y = 0; 3D only):
    #: the run adds ghost images of every particle near them (:mod:`hybridwsi.sph.symmetry`)
    mirror: tuple[int, ...] = ()
    #: body-particle pressure: ``"shepard"`` (Adami's extrapolation at the particle, the
    #: shipped runs) or ``"mdbc"`` (first order at the mirror node, :mod:`hybridwsi.sph.mdbc`)
    boundary: str = "shepard"
    #: initial fluid near a body: ``"packed"`` (:mod:`hybridwsi.sph.packing`; masses from the
    #: initial density; the body cases' default) or ``"lattice"`` (the lattice cut by the
    #: body, the runs before issue 15; the cases without a body are lattices)
    packing: str = "lattice"
    #: what the packing did (``pack_around_body``'s info), empty for ``"lattice"``
    packing_info: dict[str, float] = field(default_factory=dict)
    #: analytic body surface for mDBC: (centre at equilibrium [m], radius [m])
    body_surface: tuple[tuple[float, ...], float] | None = None
    #: pre-release relaxation (:func:`hybridwsi.sph.run.run_case`): the fluid is damped at
    #: ``relax_sigma`` [1/s] during the hold, which ends (and the body is released) at the
    #: first sample where the fluid's rms velocity is below ``relax_urms`` [m/s]; the hold
    #: ``t_release`` is then the longest hold. 0: the fixed hold of the shipped runs.
    relax_urms: float = 0.0
    relax_sigma: float = 0.0
    #: the relaxation lasts at least this long [s] (one acoustic period 4 d / c0)
    relax_tmin: float = 0.0

    @property
    def h(self) -> float:
        """Smoothing length [m]."""
        return self.hdx * self.dp

    @property
    def dt(self) -> float:
        """Fixed time step [s]: CFL on the artificial sound speed (fixed so resume is exact)."""
        return self.cfl * self.h / self.c0

    @property
    def vaxis(self) -> int:
        """Index of the vertical axis (1 = y in 2D, 2 = z in 3D)."""
        return self.dim - 1

    @property
    def gvec(self) -> tuple[float, float, float]:
        gv = [0.0, 0.0, 0.0]
        gv[self.vaxis] = -self.g
        return tuple(gv)

    @property
    def n_particles(self) -> int:
        """Real particles (fluid and solid; mirror ghosts not counted)."""
        return int(self.fluid.get_number_of_particles(real=True)
                   + self.wall.get_number_of_particles(real=True))


# --------------------------------------------------------------------------- lattices
def _grid(lo: list[float], hi: list[float], dp: float) -> np.ndarray:
    """Cell-centred lattice points (i + 1/2) dp inside the box [lo, hi] (one row per point)."""
    axes = [np.arange(a + 0.5 * dp, b - 1e-9 * dp, dp) for a, b in zip(lo, hi)]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=1)


def _tank_walls(lo: list[float], hi: list[float], dp: float, nlayers: int,
                open_sides: tuple[int, ...] = ()) -> np.ndarray:
    """Wall particles (nlayers thick) around the box [lo, hi] except its top; ``open_sides``
    lists side indices (0 = x-min, 1 = x-max, 2 = y-min, 3 = y-max in 3D) without a wall."""
    t = nlayers * dp
    dim = len(lo)
    outer_lo = [a - t for a in lo]
    outer_hi = [b + t for b in hi]
    outer_hi[-1] = hi[-1]  # no lid
    pts = _grid(outer_lo, outer_hi, dp)
    inside = np.all((pts > np.array(lo)) & (pts < np.array(hi)), axis=1)
    # the still-air region above the tank walls' interior is inside too (open top)
    keep = ~inside
    for side in open_sides:
        ax, upper = divmod(side, 2)
        if ax >= dim - 1:
            continue
        keep &= ~(pts[:, ax] > hi[ax]) if upper else ~(pts[:, ax] < lo[ax])
    return pts[keep]


def round_shell(centre: np.ndarray, radius: float, dp: float, nlayers: int,
                quarter: bool = False, half: bool = False, mirrored: bool = False
                ) -> np.ndarray:
    """Particles of a circle (2D) or sphere (3D) boundary: ``nlayers`` concentric layers at
    radii R - (k + 1/2) dp, spaced about dp along each layer, so the body surface (half a
    spacing outside the outer layer) is the true circle/sphere rather than a lattice staircase.

    In 3D, ``quarter`` keeps x > 0 and y > 0 (symmetry planes x = 0 and y = 0), ``half`` keeps
    y > 0; points are set half a spacing off those planes, like the lattice next to a wall.
    ``mirrored`` builds every 3D shell from the quarter shell and its mirror images across
    x = 0 and y = 0, so the quarter, half and full domains hold the same body (their rings
    otherwise have different particle counts, which at R/dp = 4 moved the static force by
    2 %); without it the half and full shells have rings of their own (the former layout).
    """
    if mirrored and len(centre) == 3:
        q = round_shell(np.zeros(3), radius, dp, nlayers, quarter=True)
        parts = [q] if quarter else ([q, q * [-1, 1, 1]] if half else
                                     [q, q * [-1, 1, 1], q * [1, -1, 1], q * [-1, -1, 1]])
        return np.vstack(parts) + np.asarray(centre)[None, :]
    dim = len(centre)
    out = []
    for k in range(nlayers):
        rk = radius - (k + 0.5) * dp
        if rk <= 0.25 * dp:
            break
        if dim == 2:
            n = max(1, round(2.0 * math.pi * rk / dp))
            phi = (np.arange(n) + 0.5) * 2.0 * math.pi / n
            out.append(np.stack([rk * np.cos(phi), rk * np.sin(phi)], axis=1))
            continue
        # rings of constant polar angle; each ring spans the kept azimuth range
        span = 0.5 * math.pi if quarter else (math.pi if half else 2.0 * math.pi)
        nt = max(1, round(math.pi * rk / dp))
        for th in (np.arange(nt) + 0.5) * math.pi / nt:
            rho = rk * math.sin(th)
            n = max(1, round(span * rho / dp))
            phi = (np.arange(n) + 0.5) * span / n
            out.append(np.stack([rho * np.cos(phi), rho * np.sin(phi),
                                 np.full(n, rk * math.cos(th))], axis=1))
    return np.vstack(out) + np.asarray(centre)[None, :]


def shell_volumes(points: np.ndarray, centre: np.ndarray, radius: float, dp: float,
                  domain: str = "full") -> np.ndarray:
    """Volume [m^dim] each particle of a :func:`round_shell` body stands for: its layer's
    volume (the annulus or spherical shell of width dp about radius R - (k + 1/2) dp, the
    ``domain``'s share of it in 3D) over the layer's particle count."""
    dim = points.shape[1]
    r = np.linalg.norm(points - centre, axis=1)
    k = np.rint((radius - r) / dp - 0.5).astype(int)
    rk = radius - (k + 0.5) * dp
    if dim == 2:
        layer = 2.0 * math.pi * rk * dp
    else:
        share = {"full": 1.0, "half": 0.5, "quarter": 0.25}[domain]
        layer = share * 4.0 / 3.0 * math.pi * ((rk + 0.5 * dp) ** 3 - (rk - 0.5 * dp) ** 3)
    counts = np.bincount(k - k.min())[k - k.min()]
    return layer / counts


def _nlayers(hdx: float) -> int:
    # kernel support 2h must be covered by wall particles
    return math.ceil(2.0 * hdx)


def _arrays(case_dim: int, fluid_pts: np.ndarray, wall_pts: np.ndarray, flags: np.ndarray,
            dp: float, h: float, rho0: float, c0: float, gamma: float, g: float,
            depth: float, hydrostatic: bool, consistent_mass: bool = False):
    """PySPH particle arrays with every property the equation set needs.

    ``consistent_mass``: fluid masses rho_i dp^dim from the initial (hydrostatic) density, so
    that every particle's volume m/rho is the lattice's dp^dim; otherwise rho0 dp^dim."""
    from pysph.base.utils import get_particle_array_wcsph

    from hybridwsi.sph.equations import N_BODY, N_PISTON, WALL_PROPS

    def coords(pts):
        out = {"x": pts[:, 0], "y": pts[:, 1]}
        if case_dim == 3:
            out["z"] = pts[:, 2]
        return out

    vol = dp ** case_dim
    zf = fluid_pts[:, case_dim - 1]
    B = rho0 * c0 * c0 / gamma
    if hydrostatic:
        p = rho0 * g * np.maximum(depth - zf, 0.0)
        rho = rho0 * (p / B + 1.0) ** (1.0 / gamma)
    else:
        rho = np.full(len(zf), rho0)
    # rho0 dp^dim (the shipped runs): the hydrostatic density then disagrees with the number
    # density by ~(d - z) / (100 d) at c0 = 10 sqrt(g d), and the pressure-gradient operator's
    # p_i sum_j V_j grad W_ij term holds the fluid up: 2 % of g near the bottom (SPH_RUNS.md)
    m_fluid = (rho if consistent_mass else rho0) * vol
    fluid = get_particle_array_wcsph(name="fluid", **coords(fluid_pts), h=h, m=m_fluid,
                                     rho=rho)
    wall = get_particle_array_wcsph(name="wall", **coords(wall_pts), h=h, m=rho0 * vol,
                                    rho=rho0)
    for pa in (fluid, wall):
        for prop in WALL_PROPS:
            if prop not in pa.properties:
                pa.add_property(prop)
        pa.cs[:] = c0
    # [damping rate 1/s, end time s] of the pre-release relaxation (off: zeros)
    fluid.add_constant("relax", np.zeros(2))
    wall.flag[:] = flags
    wall.xi[:], wall.yi[:], wall.zi[:] = wall.x, wall.y, wall.z
    wall.add_constant("body", np.zeros(N_BODY))
    wall.add_constant("piston", np.zeros(N_PISTON))
    wall.body[7] = 1.0  # mass placeholder (never divides by zero)
    wall.body[10] = case_dim - 1
    wall.body[11] = g
    wall.body[8] = 1.0
    wall.body[13] = 1.0
    return fluid, wall


def _c0(g: float, height: float, factor: float) -> float:
    """Artificial sound speed: factor x sqrt(g H) (10 keeps density changes near 1 %)."""
    return factor * math.sqrt(g * height)


# --------------------------------------------------------------------------- probes
def _wendland_quintic(r: np.ndarray, h: np.ndarray, dim: int) -> np.ndarray:
    """Wendland quintic kernel W(r, h) [1/m^dim], the one the solver uses (support 2h)."""
    return wendland_quintic(r, h, dim)[0]


def fluid_fraction(fluid, points: np.ndarray, dim: int) -> np.ndarray:
    """SPH-interpolated fluid fraction c(r) = sum_j (m_j / rho_j) W(|r - r_j|, h_j) [-].

    ``points`` has one row per point (x, vertical) in 2D or (x, y, z) in 3D. c is 1 inside
    the fluid, 0 in the air and 0.5 at the free surface (to O(dp) accuracy, better for a flat
    lattice); it is the standard kernel colour function used to locate a particle free surface.
    """
    pts = np.atleast_2d(np.asarray(points, dtype=float))
    # mirror ghosts included: next to a symmetry plane they are the fluid beyond it
    prop = {k: _with_ghosts(fluid, k) for k in ("x", "y", "z", "m", "rho", "h")}
    xs = [prop["x"], prop["y"]] if dim == 2 else [prop["x"], prop["y"], prop["z"]]
    supp = 2.0 * float(np.max(prop["h"])) if fluid.get_number_of_particles() else 0.0
    lo, hi = pts.min(axis=0) - supp, pts.max(axis=0) + supp
    sel = np.ones(len(xs[0]), dtype=bool)
    for ax, xa in enumerate(xs):
        sel &= (xa >= lo[ax]) & (xa <= hi[ax])
    if not np.any(sel):
        return np.zeros(len(pts))
    src = np.stack([xa[sel] for xa in xs], axis=1)
    vol = prop["m"][sel] / prop["rho"][sel]
    r = np.linalg.norm(pts[:, None, :] - src[None, :, :], axis=2)
    return _wendland_quintic(r, prop["h"][sel][None, :], dim) @ vol


def _with_ghosts(pa, name: str) -> np.ndarray:
    """A property of every particle of ``pa``, mirror ghosts included (PySPH's attribute
    access returns the real particles only); plain attribute for other particle objects."""
    if hasattr(pa, "properties"):
        return pa.get(name, only_real_particles=False)
    return getattr(pa, name)


def free_surface(fluid, x: float, dp: float, dim: int, y: float = 0.0) -> float:
    """Free-surface level [m] on the vertical line through (x[, y]): where the SPH fluid
    fraction :func:`fluid_fraction` first drops below 0.5 going up from the bottom fluid.

    Why: the highest particle plus dp/2 is quantised by the lattice and biased by which
    particle columns fall in the search window; the kernel colour function is continuous in
    the particle positions and accurate to a small fraction of dp. Starting from the bottom
    ignores detached droplets above the surface. Returns NaN if no fluid is within reach.
    """
    ax = dim - 1
    h = float(np.max(fluid.h))
    near = np.abs(fluid.x - x) < 2.0 * h
    if dim == 3:
        near &= np.abs(fluid.y - y) < 2.0 * h
    if not np.any(near):
        return float("nan")
    vert = (fluid.y, fluid.z)[ax - 1][near]
    # start one kernel support above the lowest particle (the wall has no fluid below it)
    y_lo = min(vert.min() + 2.0 * h, vert.max())
    levels = np.arange(y_lo, vert.max() + 2.0 * h, 0.1 * dp)
    pts = np.zeros((len(levels), dim))
    pts[:, 0] = x
    if dim == 3:
        pts[:, 1] = y
    pts[:, ax] = levels
    c = fluid_fraction(fluid, pts, dim)
    below = np.flatnonzero(c < 0.5)
    if len(below) == 0:
        return float("nan")
    i = below[0]
    if i == 0:
        return float(levels[0])
    # linear interpolation of the 0.5 crossing between levels i-1 and i
    return float(levels[i - 1] + (c[i - 1] - 0.5) / (c[i - 1] - c[i]) * (levels[i] - levels[i - 1]))


def free_surface_top_particle(fluid, x: float, dp: float, dim: int, y: float = 0.0) -> float:
    """Former probe, kept for comparison: highest fluid particle within one dp (horizontally)
    of the probe, plus dp/2 [m]."""
    ax = dim - 1
    sel = np.abs(fluid.x - x) < dp
    if dim == 3:
        sel &= np.abs(fluid.y - y) < dp
    if not np.any(sel):
        return float("nan")
    vert = (fluid.y, fluid.z)[ax - 1]
    return float(vert[sel].max() + 0.5 * dp)


# --------------------------------------------------------------------------- cases
def hydrostatic(dp: float = 0.02, depth: float = 0.4, length: float = 0.8,
                tf: float = 1.0, c0_factor: float = 10.0, t_ramp: float = 0.3,
                init: str = "uniform") -> SPHCase:
    """2D tank at rest. ``init="uniform"`` starts from rho0 everywhere with gravity ramped
    over ``t_ramp`` [s] (a real test of the wall BC); ``"hydrostatic"`` starts settled."""
    if init not in ("uniform", "hydrostatic"):
        raise InputError(f"init must be 'uniform' or 'hydrostatic', got {init!r}")
    _check_dp(dp, depth)
    hdx, rho0, g = 1.3, 1000.0, G
    c0 = _c0(g, depth, c0_factor)
    nl = _nlayers(hdx)
    fl = _grid([0.0, 0.0], [length, depth], dp)
    wl = _tank_walls([0.0, 0.0], [length, depth + 4 * dp], dp, nl)
    fluid, wall = _arrays(2, fl, wl, np.zeros(len(wl)), dp, hdx * dp, rho0, c0, 7.0, g, depth,
                          hydrostatic=(init == "hydrostatic"))
    case = SPHCase("hydrostatic", 2, dp, depth, tf, fluid, wall, rho0=rho0, c0=c0, g=g,
                   hdx=hdx, t_ramp=(t_ramp if init == "uniform" else 0.0))

    def p_bottom(fluid, wall):
        # mean pressure of the wall's first layer under the middle half of the tank
        sel = (wall.y > -dp) & (wall.y < 0) & (wall.x > 0.25 * length) & (wall.x < 0.75 * length)
        return float(np.mean(wall.p[sel]))

    def p_fluid_bottom(fluid, wall):
        # fluid particles of the lowest row, extrapolated by dp/2 to the bottom
        sel = (fluid.y < dp) & (fluid.x > 0.25 * length) & (fluid.x < 0.75 * length)
        return float(np.mean(fluid.p[sel]) + rho0 * g * 0.5 * dp)

    case.monitors = {"p_bottom": p_bottom, "p_fluid_bottom": p_fluid_bottom}
    case.inputs = {"case": "hydrostatic", "dp": dp, "depth": depth, "length": length, "tf": tf,
                       "c0_factor": c0_factor, "t_ramp": t_ramp, "init": init}
    return case


def dam_break(dp: float = 0.0125, a: float = 0.25, tf: float = 0.5,
              c0_factor: float = 10.0) -> SPHCase:
    """2D dam break: water column of width a [m] and height 2a (Martin & Moyce's n^2 = 2)
    at the left end of a tank 6a long, released at t = 0 (dry bed)."""
    _check_dp(dp, a)
    hdx, rho0, g = 1.3, 1000.0, G
    height = 2.0 * a
    c0 = _c0(g, height, c0_factor) * math.sqrt(2.0)  # ~10 x the dam-break front speed
    nl = _nlayers(hdx)
    L = 6.0 * a
    fl = _grid([0.0, 0.0], [a, height], dp)
    wl = _tank_walls([0.0, 0.0], [L, height + 2 * a], dp, nl)
    fluid, wall = _arrays(2, fl, wl, np.zeros(len(wl)), dp, hdx * dp, rho0, c0, 7.0, g, height,
                          hydrostatic=True)
    case = SPHCase("dam_break", 2, dp, height, tf, fluid, wall, rho0=rho0, c0=c0, g=g,
                   hdx=hdx, output_dt=0.005)

    def front(fluid, wall):
        # leading edge: the largest x among particles touching the floor, plus dp/2
        sel = fluid.y < 3 * dp
        return float(fluid.x[sel].max() + 0.5 * dp)

    case.monitors = {"front": front}
    case.inputs = {"case": "dam_break", "dp": dp, "a": a, "tf": tf, "c0_factor": c0_factor}
    return case


def waves2d(dp: float = 0.02, depth: float = 0.4, period: float = 1.0, height: float = 0.03,
            length: float | None = None, tf: float = 10.0, t_ramp: float | None = None,
            c0_factor: float = 10.0, probes: tuple[float, ...] | None = None,
            alpha: float = 0.005, hdx: float = 2.0, gain: float = 1.0) -> SPHCase:
    """2D piston wave flume with a damping zone of one wavelength at the far end.

    Paddle stroke from the Biésel transfer function; probes default to 2 and 3 depths and one
    wavelength from the paddle (the evanescent modes have decayed after ~2 depths, and the
    numerical damping of the wave grows with the distance travelled).

    ``hdx`` = h/dp defaults to 2.0 (not 1.3 as elsewhere) and ``alpha`` to 0.005: with few
    neighbours SPH over-damps gravity waves through spurious vorticity (Colagrossi et al. 2013,
    Phys. Rev. E 87:023302), and the artificial viscosity ~ alpha h c0 grows with h. Measured
    H error at 3 depths from the paddle (T = 1 s, H = 0.05 m, d = 0.4 m, dp = 0.02 m):
    hdx 1.3, alpha 0.02: -20 % (still -19 % at dp = 0.0125 m); hdx 2, alpha 0.02: -12 %;
    hdx 2, alpha 0.005: -3 % (-6 % at one wavelength). hdx = 2.5 went unstable, alpha = 0 too.
    At H/dp below 2 the optimum moves to hdx = 1.5 (see ``docs/SPH_RUNS.md``). ``gain``
    multiplies the Biésel stroke (paddle calibration).
    """
    return _flume("waves2d", 2, dp, depth, period, height, length, 0.0, tf, t_ramp, c0_factor,
                  probes, alpha, hdx, G, gain=gain)


def waves3d(dp: float = 0.0375, depth: float = 0.45, period: float = 0.75,
            height: float = 0.05, length: float | None = None, half_width: float = 0.45,
            tf: float = 6.0, t_ramp: float | None = None, c0_factor: float = 10.0,
            probes: tuple[float, ...] | None = None, alpha: float = BODY_ALPHA,
            hdx: float = BODY_HDX, alpha_wall: float | None = None,
            gain: float = 1.0, symmetry: str = "mirror") -> SPHCase:
    """3D piston wave flume without a body: :func:`regular3d`'s tank (half width with the
    symmetry plane y = 0, damping zone over the last wavelength), to measure or calibrate
    the wave that reaches the body. Probes halfway between the symmetry plane and the side
    wall, by default at 1, 1.5 and 2 wavelengths (the body of :func:`regular3d` is at 2).
    ``alpha_wall`` is the artificial viscosity between fluid and walls (default ``alpha``);
    ``gain`` multiplies the Biésel stroke; ``symmetry`` ``"mirror"`` makes y = 0 a true
    mirror plane, ``"wall"`` a fixed wall (the former set-up). Lengths in m, times in s.
    """
    _symmetry_planes(3, True, "half", symmetry)
    k = wavemaker.wavenumber(period, depth, KRAMER_G)
    lam = 2 * math.pi / k
    return _flume("waves3d", 3, dp, depth, period, height,
                  4.0 * lam if length is None else length, half_width, tf, t_ramp, c0_factor,
                  (lam, 1.5 * lam, 2.0 * lam) if probes is None else probes, alpha, hdx,
                  KRAMER_G, alpha_wall=alpha_wall, gain=gain, symmetry=symmetry)


def _flume(name: str, dim: int, dp: float, depth: float, period: float, height: float,
           length: float | None, half_width: float, tf: float, t_ramp: float | None,
           c0_factor: float, probes: tuple[float, ...] | None, alpha: float, hdx: float,
           g: float, alpha_wall: float | None = None, gain: float = 1.0,
           symmetry: str = "wall") -> SPHCase:
    """Piston flume, 2D or 3D (y in [0, half_width], the plane y = 0 a mirror plane or a
    wall as ``symmetry`` says), damping zone over the last wavelength."""
    _check_dp(dp, depth)
    if height / dp < 1.0:
        raise InputError(f"wave height {height} m is below one particle spacing dp = {dp} m")
    _check_hdx(hdx)
    _check_gain(gain)
    if dim == 3:
        _check_dp(dp, half_width)
    rho0 = 1000.0
    k = wavemaker.wavenumber(period, depth, g)
    lam = 2 * math.pi / k
    stroke = gain * wavemaker.piston_stroke(height, period, depth, g)
    L = length if length is not None else 3.0 * lam
    c0 = _c0(g, depth, c0_factor)
    nl = _nlayers(hdx)
    top = depth + 2 * height + 4 * dp
    mid = [0.0, half_width] if dim == 3 else []
    fl = _grid([0.0] + mid[:1] + [0.0], [L] + mid[1:] + [depth], dp)
    # bottom extends under the paddle's travel; the x-min wall (the paddle) is built apart
    margin = 0.5 * stroke + 2 * dp
    mirror = (1,) if dim == 3 and symmetry == "mirror" else ()
    wl = _tank_walls([-margin] + mid[:1] + [0.0], [L] + mid[1:] + [top], dp, nl,
                     open_sides=(0, 2) if mirror else (0,))
    wl = wl[wl[:, 0] > -margin]  # drop the unused x-min corner
    paddle = _grid([-nl * dp] + mid[:1] + [0.0], [0.0] + mid[1:] + [top], dp)
    pts = np.vstack([wl, paddle])
    flags = np.r_[np.zeros(len(wl)), np.ones(len(paddle))]
    fluid, wall = _arrays(dim, fl, pts, flags, dp, hdx * dp, rho0, c0, 7.0, g, depth,
                          hydrostatic=True)
    wall.piston[3:6] = stroke, period, (2.0 * period if t_ramp is None else t_ramp)
    omega = 2 * math.pi / period
    x_probes = probes if probes is not None else (2.0 * depth, 3.0 * depth, lam)
    # 3D: halfway to the side wall (the probe's fluid fraction sees no wall there)
    y_probe = 0.5 * half_width if dim == 3 else 0.0
    case = SPHCase(name, dim, dp, depth, tf, fluid, wall, rho0=rho0, c0=c0, g=g, hdx=hdx,
                   alpha=alpha, alpha_wall=alpha_wall, damping=(L - lam, L, 3.0 * omega),
                   output_dt=min(0.01, period / 40),
                   probes=[(float(x), y_probe) for x in x_probes], mirror=mirror)
    case.inputs = {"case": name, "dp": dp, "depth": depth, "period": period, "height": height,
                   "length": L, "tf": tf, "t_ramp": float(wall.piston[5]), "c0_factor": c0_factor,
                   "stroke": stroke, "wavelength": lam, "probes": list(map(float, x_probes)),
                   "alpha": alpha, "hdx": hdx}
    if gain != 1.0:
        case.inputs["gain"] = gain
    if dim == 3:
        case.inputs.update(half_width=half_width, g=g, alpha_wall=alpha_wall, gain=gain,
                           symmetry=symmetry)
    return case


@dataclass(frozen=True)
class BodyCaseSpec:
    """A half-submerged circle (2D) or sphere (3D) in a tank, released from ``z0`` [m] above
    equilibrium: what :func:`_body_case` builds (the decay and regular-wave cases).

    Geometry: ``dim`` (2 or 3), particle spacing ``dp`` [m], water ``depth`` [m], body
    ``radius`` [m] and ``mass`` [kg] (per unit length in 2D) at ``x_body`` [m], side walls at
    ``half_width`` [m] from its axis, a flume of ``length`` [m] with a ``piston`` (stroke [m],
    period [s], ramp [s]) at x = 0, a damping zone ``damping`` = (start [m], end [m],
    strength [1/s]) and wave ``probes`` (x, y) [m]. Run: end time ``tf`` [s] (from the
    release), gravity ``g`` [m/s^2], speed of sound ``c0_factor`` x the shallow-water speed,
    the body ``free`` to heave or held.

    ``domain`` (3D): ``"quarter"`` (symmetry planes x = 0 and y = 0; the default without a
    paddle), ``"half"`` (plane y = 0; the default with a paddle, which sits at x = 0) or
    ``"full"``. ``symmetry``: ``"mirror"`` makes the planes true mirror planes (ghost images
    of the fluid and of every solid, :mod:`hybridwsi.sph.symmetry`); ``"wall"`` builds them
    as fixed walls, as the runs before issue 15 did (each such plane cost ~2 % of period and
    0.5 N of static force at D/8, see ``docs/SPH_RUNS.md``).

    ``alpha`` is the artificial-viscosity coefficient (see :data:`BODY_ALPHA`), ``alpha_wall``
    the one between fluid and solid particles (``None``: ``alpha``; the decay cases default
    to :data:`BODY_ALPHA_WALL`, none), ``alpha_body`` the one between fluid and the body's
    particles alone (``None``: ``alpha_wall``'s; so a flume can keep the viscosity its paddle
    was calibrated with at its walls), ``hdx`` = h/dp. The body is
    held for ``t_release`` [s] before it is released (``tf`` counts from the release).
    ``smooth_body`` builds the body from concentric particle shells (:func:`round_shell`)
    instead of the lattice points inside it, whose staircase surface acts as roughness.
    ``boundary``: ``"shepard"`` (Adami's wall extrapolation at each body particle, the
    shipped runs) or ``"mdbc"`` (first-order extrapolation at its mirror node across the
    sphere, :mod:`hybridwsi.sph.mdbc`).
    ``relax`` (> 0, with a hold): a damped relaxation instead of a fixed hold -- the fluid's
    velocities are damped at half the tank's lowest acoustic angular frequency,
    pi c0 / (4 depth), and the body is released at the first sample where the fluid's rms
    velocity is below ``relax`` sqrt(g depth), after at least one acoustic period 4 depth / c0
    (``t_release`` is then the longest hold).
    ``sponge`` [m] (decay cases) is the width of an absorbing layer along the side walls, so that
    the waves the body radiates are not reflected back onto it.
    ``packing``: ``"packed"`` (the public cases' default, :data:`BODY_PACKING`: the fluid
    within a few dp of the body relaxed to a body-fitted packing,
    :func:`hybridwsi.sph.packing.pack_around_body`, and every fluid mass rho_i dp^dim from its
    initial density) or ``"lattice"`` (the fluid lattice cut by the body, the runs before
    issue 15; ``docs/SPH_RUNS.md``).
    """

    name: str
    dim: int
    dp: float
    depth: float
    radius: float
    mass: float
    z0: float
    half_width: float
    tf: float
    g: float
    c0_factor: float
    free: bool
    piston: tuple[float, float, float] | None = None
    length: float | None = None
    x_body: float = 0.0
    damping: tuple[float, float, float] = (1e30, 2e30, 0.0)
    probes: tuple[tuple[float, float], ...] = ()
    alpha: float = BODY_ALPHA
    alpha_wall: float | None = None
    alpha_body: float | None = None
    hdx: float = BODY_HDX
    t_release: float = 0.0
    smooth_body: bool = True
    sponge: float = 0.0
    domain: str | None = None
    symmetry: str = "mirror"
    boundary: str = "shepard"
    relax: float = 0.0
    packing: str = BODY_PACKING

    def check(self) -> None:
        """:class:`InputError` on the first value out of range."""
        _check_boundary(self.boundary)
        if self.packing not in PACKINGS:
            raise InputError(f"packing must be one of {', '.join(PACKINGS)}, "
                             f"got {self.packing!r}")
        if not (math.isfinite(self.relax) and self.relax >= 0.0):
            raise InputError("relax must be a non-negative fraction of sqrt(g d), "
                             f"got {self.relax!r}")
        if not (math.isfinite(self.t_release) and self.t_release >= 0.0):
            raise InputError(f"t_release must be a non-negative time in s, got {self.t_release!r}")
        _check_hdx(self.hdx)
        for label in ("alpha", "alpha_wall", "alpha_body"):
            value = getattr(self, label)
            if value is not None and not (math.isfinite(value) and 0.0 <= value <= 1.0):
                raise InputError(f"{label} must be in [0, 1], got {value!r}")
        _check_dp(self.dp, self.radius)
        clear = self.half_width - self.radius
        if not (math.isfinite(self.sponge) and 0.0 <= self.sponge <= clear - 4 * self.dp):
            raise InputError(f"sponge must be between 0 and the clear width {clear:.3g} m less "
                             f"4 dp, got {self.sponge!r}")
        if self.sponge > 0.0 and self.piston is not None:
            raise InputError("a sponge along the side walls is for decay cases (no paddle)")


@dataclass
class _BodyTank:
    """The particles of a body case before they become PySPH arrays: fluid points, solid
    points (walls, paddle, body) with their flags (0 wall, 1 paddle, 2 body), and the layout."""

    domain: str
    planes: tuple[int, ...]
    centre: np.ndarray
    n_box: int  # fluid lattice points below the surface before the body is cut out
    fluid: np.ndarray
    solid: np.ndarray
    flags: np.ndarray
    body: np.ndarray


def _body_case(p: BodyCaseSpec) -> SPHCase:
    """The :class:`SPHCase` of a body in a tank (see :class:`BodyCaseSpec`)."""
    p.check()
    tank = _body_tank(p)
    rho0, c0 = RHO_WATER, _c0(p.g, p.depth, p.c0_factor)
    fl, vol_solid, packing_info = tank.fluid, None, {}
    if p.packing == "packed":
        fl, vol_solid, packing_info = _pack_fluid(p, tank)
    fluid, wall = _arrays(p.dim, fl, tank.solid, tank.flags, p.dp, p.hdx * p.dp, rho0, c0, 7.0,
                          p.g, p.depth, hydrostatic=True, consistent_mass=(p.packing == "packed"))
    if vol_solid is not None:
        wall.m[:] = rho0 * vol_solid
    _set_body(p, tank, wall)
    mirror = tank.planes if p.symmetry == "mirror" else ()
    case = SPHCase(p.name, p.dim, p.dp, p.depth, p.tf, fluid, wall, rho0=rho0, c0=c0, g=p.g,
                   hdx=p.hdx, body_mass=p.mass, damping=_damping(p), probes=list(p.probes),
                   output_dt=0.005, alpha=p.alpha, alpha_wall=p.alpha_wall,
                   alpha_body=p.alpha_body, damping_radial=p.sponge > 0.0, mirror=mirror,
                   boundary=p.boundary, packing=p.packing, packing_info=packing_info)
    rest = tank.centre.copy()
    rest[p.dim - 1] = p.depth  # the stepper places the body at its equilibrium + body[B_Z]
    case.body_surface = (tuple(float(c) for c in rest), float(p.radius))
    _set_release(p, case, wall)
    return case


def _damping(p: BodyCaseSpec) -> tuple[float, float, float]:
    """The damping zone: the spec's, or with a ``sponge`` a layer along the side walls."""
    if p.sponge <= 0.0:
        return p.damping
    # strength from the heave natural frequency sqrt(C / (m + A)), A ~ m (heave, half
    # immersed): 3 omega relaxes a wave within the layer (as the flume's beach)
    c_hyd = RHO_WATER * p.g * (2.0 * p.radius if p.dim == 2 else math.pi * p.radius ** 2)
    return (p.half_width - p.sponge, p.half_width, 3.0 * math.sqrt(c_hyd / (2.0 * p.mass)))


def _body_tank(p: BodyCaseSpec) -> _BodyTank:
    """Fluid, walls, paddle and body particles on one lattice (so that the gap between fluid
    and body is one dp, as at flat walls)."""
    dim, dp, v = p.dim, p.dp, p.dim - 1
    planes = _symmetry_planes(dim, p.piston is not None, p.domain, p.symmetry)
    domain = p.domain or ("full" if dim == 2 else ("half" if p.piston is not None
                                                      else "quarter"))
    nl = _nlayers(p.hdx)
    # horizontal extent: x in [x_lo, x_hi], y in [y_lo, half_width] (3D)
    if p.piston is None:
        x_lo, x_hi = (0.0 if domain == "quarter" else -p.half_width), p.half_width
        open_sides: tuple[int, ...] = ()
    else:
        x_lo, x_hi = 0.0, float(p.length)
        open_sides = (0,)
    y_lo = -p.half_width if domain == "full" else 0.0
    if p.symmetry == "mirror":
        # no wall on a mirror plane: its ghosts stand in for the fluid and solids beyond it
        open_sides += tuple(2 * ax for ax in planes if 2 * ax not in open_sides)
    lo = [x_lo] + ([y_lo] if dim == 3 else []) + [0.0]
    top = p.depth + p.radius + 4 * dp
    hi = [x_hi] + ([p.half_width] if dim == 3 else []) + [top]
    centre = np.zeros(dim)
    centre[0] = p.x_body
    centre[v] = p.depth + p.z0  # released z0 above equilibrium (half submerged)
    pts_all = _grid(lo, hi, dp)
    r = np.linalg.norm(pts_all - centre, axis=1)
    fl = pts_all[(r >= p.radius) & (pts_all[:, v] < p.depth)]
    # body: a shell nl particles thick (inner particles never see the fluid)
    if p.smooth_body:
        body = round_shell(centre, p.radius, dp, nl, quarter=(domain == "quarter"),
                           half=(domain == "half"), mirrored=(p.symmetry == "mirror"))
    else:
        body = pts_all[(r < p.radius) & (r >= p.radius - (nl + 0.5) * dp)]
    walls, paddle = _walls_and_paddle(p, lo, hi, nl, open_sides, y_lo)
    return _BodyTank(domain=domain, planes=planes, centre=centre,
                     n_box=int(np.sum(pts_all[:, v] < p.depth)), fluid=fl,
                     solid=np.vstack([walls, paddle, body]),
                     flags=np.r_[np.zeros(len(walls)), np.ones(len(paddle)),
                                 np.full(len(body), 2.0)],
                     body=body)


def _walls_and_paddle(p: BodyCaseSpec, lo: list[float], hi: list[float], nl: int,
                      open_sides: tuple[int, ...], y_lo: float) -> tuple[np.ndarray, np.ndarray]:
    """The tank's wall particles up to ``hi`` (the top of the body's lattice) and the
    paddle's (none without a piston: an empty (0, dim) array)."""
    wlo = list(lo)
    if p.piston is not None:
        wlo[0] = -(0.5 * p.piston[0] + 2 * p.dp)
    walls = _tank_walls(wlo, hi, p.dp, nl, open_sides=open_sides)
    if p.piston is None:
        return walls, np.zeros((0, p.dim))
    walls = walls[walls[:, 0] > wlo[0]]
    plo = [-nl * p.dp] + ([y_lo] if p.dim == 3 else []) + [0.0]
    phi = [0.0] + ([p.half_width] if p.dim == 3 else []) + [hi[-1]]
    return walls, _grid(plo, phi, p.dp)


def _pack_fluid(p: BodyCaseSpec, tank: _BodyTank
                ) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    """The fluid relaxed to a body-fitted packing, the solid particles' volumes [m^dim] and
    the packing's report (:func:`hybridwsi.sph.packing.pack_around_body`)."""
    # the body's shell particles carry their layer's volume (a few % off dp^dim)
    vol_solid = np.full(len(tank.solid), p.dp ** p.dim)
    if p.smooth_body:
        vol_solid[tank.flags == 2] = shell_volumes(tank.body, tank.centre, p.radius, p.dp,
                                                   tank.domain)
    fl, info = pack_around_body(
        tank.fluid, tank.solid, tank.centre, p.radius, p.dp, p.hdx * p.dp, surface=p.depth,
        mirror_axes=tank.planes if p.symmetry == "mirror" else (),
        n_total=_fluid_count(tank.n_box, p.dp, p.radius, p.z0, p.dim, tank.domain),
        fixed_volumes=vol_solid)
    return fl, vol_solid, info


def _set_body(p: BodyCaseSpec, tank: _BodyTank, wall: Any) -> None:
    """The body's state in the wall array: drop, mass, symmetry scale, free flag, the planes
    built as walls, the particles' equilibrium positions and the paddle's motion."""
    scale = {"full": 1.0, "half": 2.0, "quarter": 4.0}[tank.domain]
    b = wall.body
    # whole-body mass [kg]; BodyForceReduce scales the simulated part's force up by ``scale``
    b[0], b[7], b[8], b[9] = p.z0, p.mass, scale, 1.0 if p.free else 0.0
    # planes built as walls: WallForce adds the images of the fluid to the body force itself
    # (bit 1 -> x = 0, bit 2 -> y = 0); mirror planes have real ghosts instead
    b[15] = 0.0 if p.symmetry == "mirror" else float(sum(1 << ax for ax in tank.planes))
    # equilibrium positions (the stepper places body particles at xi + z e_v)
    (wall.yi, wall.zi)[p.dim - 2][tank.flags == 2] -= p.z0
    if p.piston is not None:
        wall.piston[3:6] = p.piston


def _set_release(p: BodyCaseSpec, case: SPHCase, wall: Any) -> None:
    """The hold before the release (fixed, or a damped relaxation with ``relax``)."""
    if p.relax > 0.0:
        case.relax_urms = p.relax * math.sqrt(p.g * p.depth)
        case.relax_sigma = math.pi * case.c0 / (4.0 * p.depth)
        case.relax_tmin = 4.0 * p.depth / case.c0
    if p.t_release > 0.0:
        # release on an output sample; PEC evaluates forces at mid-step, so the body is free
        # from the evaluation half a step before it and the first sample has m zddot = F_tot
        every = max(1, round(case.output_dt / case.dt)) * case.dt
        case.t_release = max(1, round(p.t_release / every)) * every
        case.tf = p.tf + case.t_release
        wall.body[16] = case.t_release - 0.75 * case.dt


def _fluid_count(n_box: int, dp: float, radius: float, z0: float, dim: int, domain: str
                 ) -> int:
    """Number of particles of volume dp^dim that fill a tank of ``n_box`` lattice cells below
    the still-water level less the immersed part of the body (a circle or sphere of
    ``radius`` [m] centred z0 [m] above the level; its ``domain`` share of it in 3D)."""
    d = radius - z0  # immersed height
    if dim == 2:
        immersed = radius ** 2 * math.acos((radius - d) / radius) - (radius - d) * math.sqrt(
            max(2.0 * radius * d - d * d, 0.0))
    else:
        immersed = {"full": 1.0, "half": 0.5, "quarter": 0.25}[domain] * cap_volume(d, radius)
    return n_box - round(immersed / dp ** dim)


def decay2d(dp: float = 0.02, radius: float = 0.15, depth: float = 0.6, z0_over_d: float = 0.1,
            half_width: float = 1.5, tf: float = 3.0, c0_factor: float = 10.0,
            free: bool = True, alpha: float = BODY_ALPHA,
            alpha_wall: float | None = BODY_ALPHA_WALL, alpha_body: float | None = None,
            hdx: float = BODY_HDX, t_release: float = BODY_HOLD,
            smooth_body: bool = True, sponge: float = 0.0, boundary: str = "shepard",
            relax: float = BODY_RELAX, packing: str = BODY_PACKING) -> SPHCase:
    """2D heave decay of a half-submerged circle (mass per unit length rho pi R^2 / 2)."""
    mass = RHO_WATER * math.pi * radius ** 2 / 2.0
    case = _body_case(BodyCaseSpec(
        "decay2d", 2, dp, depth, radius, mass, z0_over_d * 2 * radius, half_width, tf, G,
        c0_factor, free, alpha=alpha, alpha_wall=alpha_wall, alpha_body=alpha_body, hdx=hdx,
        t_release=t_release, smooth_body=smooth_body, sponge=sponge, boundary=boundary,
        relax=relax, packing=packing))
    case.inputs = {"case": "decay2d", "dp": dp, "radius": radius, "depth": depth, "z0_over_d": z0_over_d,
                       "half_width": half_width, "tf": tf, "c0_factor": c0_factor, "free": free,
                       "mass_per_length": mass, "alpha": alpha, "alpha_wall": alpha_wall,
                       "hdx": hdx, "t_release": t_release, "smooth_body": smooth_body,
                       "sponge": sponge}
    _record_boundary(case, boundary, relax if t_release > 0.0 else 0.0, packing, alpha_body)
    return case


def decay3d(dp: float = 0.03, depth: float = KRAMER_DEPTH, half_width: float = 1.2,
            z0_over_d: float = 0.1, tf: float = 5 * 0.7561 + 0.05, c0_factor: float = 10.0,
            free: bool = True, alpha: float = BODY_ALPHA,
            alpha_wall: float | None = BODY_ALPHA_WALL, alpha_body: float | None = None,
            hdx: float = BODY_HDX, t_release: float = BODY_HOLD,
            smooth_body: bool = True, sponge: float = 0.0, domain: str = "quarter",
            symmetry: str = "mirror", boundary: str = "shepard",
            relax: float = BODY_RELAX, packing: str = BODY_PACKING) -> SPHCase:
    """Kramer et al. (2021) sphere decay (D = 0.3 m, m = 7.056 kg, drop 0.1D); walls at
    ``half_width`` [m] from the sphere's axis. ``domain`` ``"quarter"`` (default; symmetry
    planes x = 0 and y = 0), ``"half"`` (y = 0) or ``"full"``; ``symmetry`` ``"mirror"``
    (true mirror planes, default) or ``"wall"`` (planes as fixed walls, the former set-up).
    The default ``tf`` [s] runs a little past 5 Te0 so the sampled record covers the RMS
    window."""
    case = _body_case(BodyCaseSpec(
        "decay3d", 3, dp, depth, SPHERE_D / 2, SPHERE_MASS, z0_over_d * SPHERE_D, half_width, tf,
        KRAMER_G, c0_factor, free, alpha=alpha, alpha_wall=alpha_wall, alpha_body=alpha_body,
        hdx=hdx, t_release=t_release, smooth_body=smooth_body, sponge=sponge, domain=domain,
        symmetry=symmetry, boundary=boundary, relax=relax, packing=packing))
    case.inputs = {"case": "decay3d", "dp": dp, "depth": depth, "half_width": half_width,
                       "z0_over_d": z0_over_d, "tf": tf, "c0_factor": c0_factor, "free": free,
                       "diameter": SPHERE_D, "mass": SPHERE_MASS, "g": KRAMER_G, "alpha": alpha,
                       "alpha_wall": alpha_wall, "hdx": hdx, "t_release": t_release,
                       "smooth_body": smooth_body, "sponge": sponge, "domain": domain,
                       "symmetry": symmetry}
    _record_boundary(case, boundary, relax if t_release > 0.0 else 0.0, packing, alpha_body)
    return case


def regular3d(dp: float = 0.03, depth: float = KRAMER_DEPTH, period: float = 0.75,
              height: float = 0.05, half_width: float = 0.45, tf: float = 20.0,
              c0_factor: float = 10.0, alpha: float = BODY_ALPHA, hdx: float = BODY_HDX,
              smooth_body: bool = True, gain: float = 1.0, domain: str = "half",
              symmetry: str = "mirror", boundary: str = "shepard",
              packing: str = BODY_PACKING, alpha_body: float | None = None) -> SPHCase:
    """The paper's sphere in regular waves (T = 0.75 s, H = 0.05 m), heave-free, in a
    narrow flume (``domain`` ``"half"``: symmetry plane y = 0, or ``"full"``) with a piston
    and a damping zone. ``symmetry``: ``"mirror"`` (true mirror plane) or ``"wall"`` (the
    plane as a fixed wall, as in the shipped D/12 run).

    The body is two wavelengths from the paddle. ``gain`` multiplies the Biésel stroke: at
    coarse spacing the wave loses height on its way (numerical damping), so, as in a
    laboratory, the stroke is calibrated in the empty flume (:func:`waves3d`,
    ``scripts/sph_wave_calibration.py``) to give the target height at the body. Probes:
    one wavelength upstream of the body on the centre plane, and half a wavelength upstream
    halfway to the side wall. ``alpha_body``: the artificial viscosity between the fluid and
    the body (default ``alpha``, as at the walls and the paddle, whose gain was calibrated
    with it)."""
    g = KRAMER_G
    _check_gain(gain)
    k = wavemaker.wavenumber(period, depth, g)
    lam = 2 * math.pi / k
    stroke = gain * wavemaker.piston_stroke(height, period, depth, g)
    length = 4.0 * lam
    x_body = 2.0 * lam
    probes = [(x_body - lam, 0.5 * dp), (x_body - 0.5 * lam, 0.5 * half_width)]
    case = _body_case(BodyCaseSpec(
        "regular3d", 3, dp, depth, SPHERE_D / 2, SPHERE_MASS, 0.0, half_width, tf, g, c0_factor,
        True, piston=(stroke, period, 2 * period), length=length, x_body=x_body,
        damping=(length - lam, length, 3.0 * 2 * math.pi / period), probes=tuple(probes),
        alpha=alpha, alpha_body=alpha_body, hdx=hdx, smooth_body=smooth_body, domain=domain,
        symmetry=symmetry, boundary=boundary, packing=packing))
    case.inputs = {"case": "regular3d", "dp": dp, "depth": depth, "period": period, "height": height,
                       "half_width": half_width, "tf": tf, "c0_factor": c0_factor, "stroke": stroke,
                       "wavelength": lam, "x_body": x_body, "alpha": alpha, "hdx": hdx,
                       "smooth_body": smooth_body, "gain": gain, "domain": domain,
                       "symmetry": symmetry}
    _record_boundary(case, boundary, None, packing, alpha_body)
    return case


def _record_boundary(case: SPHCase, boundary: str, relax: float | None,
                     packing: str, alpha_body: float | None = None) -> None:
    """Record the body boundary (when not the default Shepard one; the body's own artificial
    viscosity when set), the relaxation (cases
    with a hold; 0 for a fixed hold) and the packing in the case inputs. The packing and the
    relaxation are always recorded since their defaults changed (histories made before
    carry neither: they are ``"lattice"`` with a fixed hold)."""
    if boundary != "shepard":
        case.inputs["boundary"] = boundary
    if alpha_body is not None:
        case.inputs["alpha_body"] = alpha_body
    if relax is not None:
        case.inputs["relax"] = relax
    case.inputs["packing"] = packing


def _symmetry_planes(dim: int, piston: bool, domain: str | None, symmetry: str
                     ) -> tuple[int, ...]:
    """Axes of the symmetry planes (0: x = 0, 1: y = 0) of a body case's domain."""
    if symmetry not in ("mirror", "wall"):
        raise InputError(f"symmetry must be 'mirror' or 'wall', got {symmetry!r}")
    if domain is None:
        domain = "full" if dim == 2 else ("half" if piston else "quarter")
    if domain not in ("quarter", "half", "full"):
        raise InputError(f"domain must be 'quarter', 'half' or 'full', got {domain!r}")
    if dim == 2 and domain != "full":
        raise InputError("2D body cases are full domains (domain='full')")
    if piston and domain == "quarter":
        raise InputError("a paddle case cannot be a quarter domain (the paddle is at x = 0)")
    return {"quarter": (0, 1), "half": (1,), "full": ()}[domain]


BOUNDARIES = ("shepard", "mdbc")
#: initial fluid near a body (``_body_case``'s ``packing``)
PACKINGS = ("lattice", "packed")


def _check_boundary(boundary: str) -> None:
    if boundary not in BOUNDARIES:
        raise InputError(f"boundary must be one of {', '.join(BOUNDARIES)}, got {boundary!r}")


def _check_gain(gain: float) -> None:
    if not (isinstance(gain, (int, float)) and math.isfinite(gain) and 0.0 < gain <= 3.0):
        raise InputError(f"gain (stroke factor) must be in (0, 3], got {gain!r}")


def _check_hdx(hdx: float) -> None:
    if not (isinstance(hdx, (int, float)) and 1.0 <= hdx <= 2.0):
        raise InputError(f"hdx = h/dp must be in [1, 2] (2.5 was unstable), got {hdx!r}")


def _check_dp(dp: float, size: float) -> None:
    if not (isinstance(dp, (int, float)) and math.isfinite(dp) and dp > 0):
        raise InputError(f"dp must be a positive number of metres, got {dp!r}")
    if size / dp < 4:
        raise InputError(f"dp = {dp} m is too coarse: the case needs at least 4 particles "
                         f"across {size} m")


BUILDERS: dict[str, Callable[..., SPHCase]] = {
    "hydrostatic": hydrostatic,
    "dam_break": dam_break,
    "waves2d": waves2d,
    "waves3d": waves3d,
    "decay2d": decay2d,
    "decay3d": decay3d,
    "regular3d": regular3d,
}


def build(name: str, **kwargs: Any) -> SPHCase:
    """Build a case by name with keyword overrides (``None`` values are ignored)."""
    if name not in BUILDERS:
        raise InputError(f"unknown SPH case {name!r}; choose one of {', '.join(BUILDERS)}")
    kwargs = {k: v for k, v in kwargs.items() if v is not None}
    try:
        return BUILDERS[name](**kwargs)
    except TypeError as exc:
        raise InputError(f"bad option for case {name!r}: {exc}") from None
