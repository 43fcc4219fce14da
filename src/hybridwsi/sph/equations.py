"""Our PySPH equations and integrator step (PySPH's documented extension mechanism).

Particle arrays (the same for every case so that PySPH compiles one kernel set per dimension):

- ``fluid``: weakly-compressible fluid (Tait EOS, continuity with density diffusion,
  Monaghan momentum with artificial viscosity, gravity with an optional start-up ramp,
  optional velocity damping zone).
- ``wall``: every solid particle. ``flag`` selects its motion: 0 fixed, 1 piston paddle
  (horizontal, prescribed), 2 floating rigid body (heave, two-way coupled). Wall pressure
  is extrapolated from the fluid (Adami, Hu & Adams 2012, JCP 231:7057, Eq. 27) including the
  wall acceleration, so moving walls feel the right pressure.

Body state lives in the wall array constant ``body`` (see ``B_*`` indices) and the paddle
state in ``piston``; both are plain arrays, so a checkpoint of the particle arrays is a
checkpoint of the whole simulation.
"""

from __future__ import annotations

from math import cos, sqrt  # also used by PySPH's transpiled kernels

import numpy
import numpy as np
from pysph.sph.equation import Equation
from pysph.sph.integrator_step import IntegratorStep

from hybridwsi.sph.wavemaker import piston_motion

# indices into the wall constant ``body``
B_Z, B_W, B_A, B_Z0, B_W0, B_FFLUID, B_FTOT, B_MASS, B_SCALE, B_FREE, B_AXIS, B_G, B_TRAMP, \
    B_USE_ACC, B_FX, B_SYM, B_TREL = range(17)
N_BODY = 17
# indices into the wall constant ``piston``: X, U, A, stroke, period, t_ramp
P_X, P_U, P_A, P_STROKE, P_PERIOD, P_TRAMP = range(6)
N_PISTON = 8

def declare(*args):
    """PySPH's type hint for its transpiler (a no-op in Python)."""


FLAG_FIXED, FLAG_PISTON, FLAG_BODY = 0, 1, 2

#: extra per-particle properties our equations need
WALL_PROPS = ("flag", "xi", "yi", "zi", "awx", "awy", "awz", "wij", "fx", "fy", "fz", "cs")


def gravity_factor(t: float, t_ramp: float) -> float:
    """Python twin of the in-kernel gravity ramp (used for the body's own weight)."""
    if t_ramp <= 0.0 or t >= t_ramp:
        return 1.0
    return 0.5 * (1.0 - np.cos(np.pi * t / t_ramp))


class GravityRamp(Equation):
    """Body force g r(t) on the fluid, r ramping from 0 to 1 over ``t_ramp`` [s] (cosine)."""

    def __init__(self, dest, sources, gx=0.0, gy=0.0, gz=0.0, t_ramp=0.0):
        self.gx, self.gy, self.gz, self.t_ramp = gx, gy, gz, t_ramp
        super().__init__(dest, sources)

    def post_loop(self, d_idx, d_au, d_av, d_aw, t):
        fac = 1.0
        if t < self.t_ramp:
            fac = 0.5 * (1.0 - cos(3.141592653589793 * t / self.t_ramp))
        d_au[d_idx] += fac * self.gx
        d_av[d_idx] += fac * self.gy
        d_aw[d_idx] += fac * self.gz


class WallPressureAdami(Equation):
    """Wall pressure extrapolated from the fluid, with gravity and wall acceleration.

    p_w = [sum_f p_f W_wf + (g r(t) - a_w) . sum_f rho_f x_wf W_wf] / sum_f W_wf,
    then rho_w from the inverse Tait EOS (Adami et al. 2012, Eq. 27-28).
    """

    def __init__(self, dest, sources, rho0, c0, gamma=7.0, gx=0.0, gy=0.0, gz=0.0, t_ramp=0.0):
        self.rho0, self.c0, self.gamma = rho0, c0, gamma
        self.gx, self.gy, self.gz, self.t_ramp = gx, gy, gz, t_ramp
        self.B = rho0 * c0 * c0 / gamma
        super().__init__(dest, sources)

    def initialize(self, d_idx, d_p, d_wij):
        d_p[d_idx] = 0.0
        d_wij[d_idx] = 0.0

    def loop(self, d_idx, s_idx, d_p, d_wij, s_p, s_rho, d_awx, d_awy, d_awz, XIJ, WIJ, t):
        fac = 1.0
        if t < self.t_ramp:
            fac = 0.5 * (1.0 - cos(3.141592653589793 * t / self.t_ramp))
        gdotx = ((fac * self.gx - d_awx[d_idx]) * XIJ[0] + (fac * self.gy - d_awy[d_idx]) * XIJ[1]
                 + (fac * self.gz - d_awz[d_idx]) * XIJ[2])
        d_p[d_idx] += s_p[s_idx] * WIJ + s_rho[s_idx] * gdotx * WIJ
        d_wij[d_idx] += WIJ

    def post_loop(self, d_idx, d_p, d_wij, d_rho, d_cs):
        d_cs[d_idx] = self.c0
        if d_wij[d_idx] > 1e-12:
            d_p[d_idx] = d_p[d_idx] / d_wij[d_idx]
        else:
            d_p[d_idx] = 0.0
        # inverse Tait; clamp so that strongly negative p (wall in suction) stays finite
        ratio = max(d_p[d_idx] / self.B + 1.0, 0.5)
        d_rho[d_idx] = self.rho0 * pow(ratio, 1.0 / self.gamma)


class FluidRates(Equation):
    """Fluid rates from one source array in one pass over each pair (speed; the arithmetic of
    PySPH's ``ContinuityEquation``, then the density diffusion, then ``MomentumEquation`` with
    beta = 0 and no tensile correction, in that order, so the result is bitwise the same).
    One instance per source array: fluid (``delta`` > 0) and solid (``delta`` = 0: no
    diffusion across the wall, ``alpha`` the fluid-solid viscosity, ``alpha_body`` that of
    the body's particles, flag 2, when it differs; default ``alpha``):

    arho_a += m_b v_ab . grad W_ab  (continuity)
             + delta h c0 sum_b 2 (rho_ab - rho_ab^H) x_ab . grad_a W_ab / |x_ab|^2 m_b / rho_b,
    rho_ab^H = rho0 (g . x_ab) / c0^2 (linearised Tait): delta-SPH density diffusion with the
    hydrostatic part removed (Molteni & Colagrossi 2009; Fourtakas et al. 2019, Comput. Fluids
    190:346: without the hydrostatic correction it drives a spurious flow near the bottom),
    a_a += -m_b (p_a/rho_a^2 + p_b/rho_b^2 + Pi_ab) grad W_ab, Pi_ab = -alpha c_ab mu_ab / rho_ab
    when v_ab . x_ab < 0 (Monaghan's artificial viscosity).

    Why: PySPH's ``MomentumEquation`` asks for ``WDP`` (a second kernel evaluation per pair,
    only used by its tensile correction) and writes ``dt_cfl`` per pair (unused: fixed dt),
    and every equation re-reads the pair's properties. Zeroes ``arho`` and the accelerations
    (PySPH runs every ``initialize`` of a group before any pair loop, so two instances can).
    """

    def __init__(self, dest, sources, c0, alpha, delta, rho0, gx=0.0, gy=0.0, gz=0.0,
                 t_ramp=0.0, alpha_body=None):
        self.c0, self.alpha, self.delta, self.rho0 = c0, alpha, delta, rho0
        self.alpha_body = alpha if alpha_body is None else alpha_body
        self.gx, self.gy, self.gz, self.t_ramp = gx, gy, gz, t_ramp
        super().__init__(dest, sources)

    def initialize(self, d_idx, d_arho, d_au, d_av, d_aw):
        d_arho[d_idx] = 0.0
        d_au[d_idx] = 0.0
        d_av[d_idx] = 0.0
        d_aw[d_idx] = 0.0

    def loop(self, d_idx, s_idx, d_rho, s_rho, d_p, s_p, d_cs, s_cs, s_m, s_flag, d_arho, d_au,
             d_av, d_aw, VIJ, XIJ, DWIJ, R2IJ, HIJ, EPS, RHOIJ1, t):
        # continuity
        vijdotdwij = DWIJ[0] * VIJ[0] + DWIJ[1] * VIJ[1] + DWIJ[2] * VIJ[2]
        d_arho[d_idx] += s_m[s_idx] * vijdotdwij
        # density diffusion (hydrostatic part removed)
        if self.delta > 0.0:
            fac = 1.0
            if t < self.t_ramp:
                fac = 0.5 * (1.0 - cos(3.141592653589793 * t / self.t_ramp))
            gdotx = fac * (self.gx * XIJ[0] + self.gy * XIJ[1] + self.gz * XIJ[2])
            drho = d_rho[d_idx] - s_rho[s_idx] - self.rho0 * gdotx / (self.c0 * self.c0)
            xdotdw = XIJ[0] * DWIJ[0] + XIJ[1] * DWIJ[1] + XIJ[2] * DWIJ[2]
            d_arho[d_idx] += (self.delta * HIJ * self.c0 * 2.0 * drho * xdotdw / (R2IJ + EPS)
                              * s_m[s_idx] / s_rho[s_idx])
        # momentum: pressure gradient and artificial viscosity
        rhoi21 = 1.0 / (d_rho[d_idx] * d_rho[d_idx])
        rhoj21 = 1.0 / (s_rho[s_idx] * s_rho[s_idx])
        vijdotxij = VIJ[0] * XIJ[0] + VIJ[1] * XIJ[1] + VIJ[2] * XIJ[2]
        piij = 0.0
        if vijdotxij < 0:
            cij = 0.5 * (d_cs[d_idx] + s_cs[s_idx])
            muij = (HIJ * vijdotxij) / (R2IJ + EPS)
            alpha = self.alpha
            # body particles (flag 2) may take their own; no flag read when they do not
            if self.alpha_body != self.alpha:
                if s_flag[s_idx] > 1.5:
                    alpha = self.alpha_body
            piij = -alpha * cij * muij
            piij = piij * RHOIJ1
        tmp = d_p[d_idx] * rhoi21 + s_p[s_idx] * rhoj21
        d_au[d_idx] += -s_m[s_idx] * (tmp + piij) * DWIJ[0]
        d_av[d_idx] += -s_m[s_idx] * (tmp + piij) * DWIJ[1]
        d_aw[d_idx] += -s_m[s_idx] * (tmp + piij) * DWIJ[2]


class AdvectionVelocity(Equation):
    """Advection velocity (``ax``, ``ay``, ``az``) = particle velocity: XSPH with eps = 0
    without its pair loop (the integrator moves particles with ``ax``)."""

    def post_loop(self, d_idx, d_ax, d_ay, d_az, d_u, d_v, d_w):
        d_ax[d_idx] = d_u[d_idx]
        d_ay[d_idx] = d_v[d_idx]
        d_az[d_idx] = d_w[d_idx]


class DampingZone(Equation):
    """Velocity relaxation a -= sigma(s) v for s in [x0, x1] (absorbing beach or sponge).

    sigma(s) = sigma_max ((s - x0)/(x1 - x0))^2 [1/s]; quadratic so waves enter without
    reflecting off the zone's start. s is x (a beach at the flume's end) or, with ``radial``,
    the distance to the nearest side wall of a tank centred on x = y = 0: max(|x|, |y|) in 3D,
    |x| in 2D (a sponge all around a body radiating waves).
    """

    def __init__(self, dest, sources, x0, x1, sigma_max, radial=0, dim=2):
        self.x0, self.x1, self.sigma_max = x0, x1, sigma_max
        self.radial, self.dim = radial, dim
        super().__init__(dest, sources)

    def post_loop(self, d_idx, d_x, d_y, d_u, d_v, d_w, d_au, d_av, d_aw):
        xs = d_x[d_idx]
        if self.radial == 1:
            xs = abs(d_x[d_idx])
            if self.dim == 3:
                xs = max(xs, abs(d_y[d_idx]))
        if xs > self.x0 and self.x1 > self.x0:
            s = min((xs - self.x0) / (self.x1 - self.x0), 1.0)
            sig = self.sigma_max * s * s
            d_au[d_idx] -= sig * d_u[d_idx]
            d_av[d_idx] -= sig * d_v[d_idx]
            d_aw[d_idx] -= sig * d_w[d_idx]


class HoldRelaxation(Equation):
    """Damped relaxation of the fluid before a body is released: a -= sigma v while
    t < ``relax[1]`` [s], with sigma = ``relax[0]`` [1/s] (fluid constant ``relax``; the run
    ends the relaxation when the fluid's kinetic energy falls below a threshold, see
    :func:`hybridwsi.sph.run.run_case`). Zero ``relax`` (every case by default) does nothing."""

    def post_loop(self, d_idx, d_u, d_v, d_w, d_au, d_av, d_aw, d_relax, t):
        if t < d_relax[1]:
            d_au[d_idx] -= d_relax[0] * d_u[d_idx]
            d_av[d_idx] -= d_relax[0] * d_v[d_idx]
            d_aw[d_idx] -= d_relax[0] * d_w[d_idx]


class WallForce(Equation):
    """Force [N] on each floating-body particle from the fluid: the exact reaction of the
    pressure + artificial-viscosity terms that the fluid feels from it in MomentumEquation,
    so the body and the fluid exchange momentum exactly.

    Symmetry planes built as walls (``symmetry="wall"``: bits 1 and 2 of ``body[B_SYM]`` for
    x = 0 and y = 0) have no fluid beyond them, so the mirror images of the fluid neighbours
    are added here (an image is never closer than its original, so looping over the real
    neighbours finds every image within the kernel support). With true mirror planes
    (:mod:`hybridwsi.sph.symmetry`) ``body[B_SYM]`` is 0: the ghost fluid particles are
    sources of this equation like the real ones, and each (real body, fluid or ghost) pair
    is counted once.
    """

    def __init__(self, dest, sources, alpha=0.1):
        self.alpha = alpha
        super().__init__(dest, sources)

    def initialize(self, d_idx, d_fx, d_fy, d_fz):
        d_fx[d_idx] = 0.0
        d_fy[d_idx] = 0.0
        d_fz[d_idx] = 0.0

    def loop(self, d_idx, s_idx, d_flag, d_m, d_rho, d_p, d_cs, d_body, d_x, d_y, d_z, d_u,
             d_v, d_w, s_x, s_y, s_z, s_u, s_v, s_w, s_m, s_rho, s_p, s_cs, d_fx, d_fy, d_fz,
             HIJ, RHOIJ1, EPS, SPH_KERNEL):
        xm = declare("matrix(3)")
        dwm = declare("matrix(3)")
        sym = declare("int")
        k = declare("int")
        if d_flag[d_idx] == 2:
            sym = int(d_body[15])
            tmpp = d_p[d_idx] / (d_rho[d_idx] * d_rho[d_idx]) + s_p[s_idx] / (
                s_rho[s_idx] * s_rho[s_idx])
            for k in range(4):
                if (k & sym) == k:
                    sx = 1.0 - 2.0 * (k & 1)
                    sy = 1.0 - 2.0 * ((k >> 1) & 1)
                    xm[0] = d_x[d_idx] - sx * s_x[s_idx]
                    xm[1] = d_y[d_idx] - sy * s_y[s_idx]
                    xm[2] = d_z[d_idx] - s_z[s_idx]
                    r2 = xm[0] * xm[0] + xm[1] * xm[1] + xm[2] * xm[2]
                    rm = sqrt(r2)
                    vdotx = ((d_u[d_idx] - sx * s_u[s_idx]) * xm[0]
                             + (d_v[d_idx] - sy * s_v[s_idx]) * xm[1]
                             + (d_w[d_idx] - s_w[s_idx]) * xm[2])
                    piij = 0.0
                    if vdotx < 0:
                        muij = HIJ * vdotx / (r2 + EPS)
                        piij = -self.alpha * 0.5 * (d_cs[d_idx] + s_cs[s_idx]) * muij * RHOIJ1
                    SPH_KERNEL.gradient(xm, rm, HIJ, dwm)
                    f = -d_m[d_idx] * s_m[s_idx] * (tmpp + piij)
                    d_fx[d_idx] += f * dwm[0]
                    d_fy[d_idx] += f * dwm[1]
                    d_fz[d_idx] += f * dwm[2]


class BodyForceReduce(Equation):
    """Sum the particle forces into the body's total force and acceleration (heave).

    A free body is held at its initial position until ``body[B_TREL]`` [s], as in a decay
    experiment the sphere is held while the water comes to rest.

    ``F_fluid`` and ``F_tot = F_fluid + m g`` are for the whole body (the simulated part times
    ``scale``, e.g. 4 with two symmetry planes), so that ``m z'' = F_tot``.
    """

    def reduce(self, dst, t, dt):
        # transpiled to Cython by PySPH: Python objects must be declared as such
        b = declare("object")
        mask = declare("object")
        fv = declare("object")
        b = dst.body
        # attribute access gives the real particles only: mirror ghosts are never summed
        mask = dst.flag == 2
        fv = dst.fz
        if b[10] < 1.5:
            fv = dst.fy
        f_vert = numpy.sum(fv[mask]) * b[8]
        b[14] = numpy.sum(dst.fx[mask]) * b[8]
        fac = 1.0
        if t < b[12]:
            fac = 0.5 * (1.0 - numpy.cos(numpy.pi * t / b[12]))
        b[5] = f_vert
        b[6] = f_vert - b[7] * b[11] * fac
        b[2] = 0.0
        # a free body is held in place until its release time b[16] (the fluid settles)
        if b[9] > 0 and t >= b[16]:
            b[2] = b[6] / b[7]


class WallStep(IntegratorStep):
    """PEC step for wall particles: fixed, prescribed piston, or heave-free floating body.

    The body is advanced in ``py_stage*`` (Python, once per stage) with the same predictor-
    corrector as the fluid: z_{n+1/2} = z_n + dt/2 w_n, w_{n+1/2} = w_n + dt/2 a, then
    w_{n+1} = w_n + dt a_{n+1/2}, z_{n+1} = z_n + dt (w_n + w_{n+1})/2. The per-particle stages
    then move flagged particles rigidly.
    """

    def py_stage1(self, dst, t, dt):
        b = dst.body
        b[3], b[4] = b[0], b[1]
        if b[9] > 0:
            b[0] = b[3] + 0.5 * dt * b[4]
            b[1] = b[4] + 0.5 * dt * b[2]
        self._move_piston(dst, t + 0.5 * dt)

    def py_stage2(self, dst, t, dt):
        # here t = t_n + dt/2 (PySPH advances the integrator time after stage 1)
        b = dst.body
        if b[9] > 0:
            b[1] = b[4] + dt * b[2]
            b[0] = b[3] + 0.5 * dt * (b[4] + b[1])
        self._move_piston(dst, t + 0.5 * dt)

    @staticmethod
    def _move_piston(dst, t):
        p = dst.piston
        if p[3] != 0.0:
            p[0], p[1], p[2] = piston_motion(t, p[3], p[4], p[5])

    def stage1(self, d_idx, d_flag, d_x, d_y, d_z, d_xi, d_yi, d_zi, d_u, d_v, d_w,
               d_awx, d_awy, d_awz, d_body, d_piston):
        if d_flag[d_idx] == 1:
            d_x[d_idx] = d_xi[d_idx] + d_piston[0]
            d_u[d_idx] = d_piston[1]
            d_awx[d_idx] = d_piston[2]
        elif d_flag[d_idx] == 2:
            if d_body[10] == 1:
                d_y[d_idx] = d_yi[d_idx] + d_body[0]
                d_v[d_idx] = d_body[1]
                d_awy[d_idx] = d_body[2] * d_body[13]
            else:
                d_z[d_idx] = d_zi[d_idx] + d_body[0]
                d_w[d_idx] = d_body[1]
                d_awz[d_idx] = d_body[2] * d_body[13]

    # stage2 repeats stage1 on purpose: PySPH translates each stage method's own source to
    # C/OpenCL, so a stage cannot delegate to a shared Python helper
    def stage2(self, d_idx, d_flag, d_x, d_y, d_z, d_xi, d_yi, d_zi, d_u, d_v, d_w,
               d_awx, d_awy, d_awz, d_body, d_piston):
        if d_flag[d_idx] == 1:
            d_x[d_idx] = d_xi[d_idx] + d_piston[0]
            d_u[d_idx] = d_piston[1]
            d_awx[d_idx] = d_piston[2]
        elif d_flag[d_idx] == 2:
            if d_body[10] == 1:
                d_y[d_idx] = d_yi[d_idx] + d_body[0]
                d_v[d_idx] = d_body[1]
                d_awy[d_idx] = d_body[2] * d_body[13]
            else:
                d_z[d_idx] = d_zi[d_idx] + d_body[0]
                d_w[d_idx] = d_body[1]
                d_awz[d_idx] = d_body[2] * d_body[13]
