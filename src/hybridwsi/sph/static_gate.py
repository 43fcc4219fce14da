"""Static gate of the SPH floating sphere (issue 15, item 4).

The Kramer sphere is held fixed at three heights z (above its half-immersed equilibrium) in a
closed tank at rest; the fluid force on it is averaged over several acoustic periods of the
tank and compared with exact hydrostatics: a spherical cap of height R - z immersed below the
still-water level (:func:`hybridwsi.bodies.cap_volume`). The gate: the buoyancy error at
equilibrium below 0.5 % of the weight, and the secant heave stiffness
[F(-a) - F(+a)] / (2a) within 1 % of the exact one.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hybridwsi.bodies import cap_volume
from hybridwsi.sph import tank
from hybridwsi.sph.run import run_case

#: heights [m] at which the sphere is held (0.1 D above and below equilibrium)
HEIGHTS = (-0.03, 0.0, 0.03)
#: the gate: buoyancy error at equilibrium [fraction of the weight], secant stiffness [fraction]
MAX_BUOYANCY_ERROR = 0.005
MAX_STIFFNESS_ERROR = 0.01


def exact_fluid_force(z: float, radius: float = tank.SPHERE_D / 2, rho: float = tank.RHO_WATER,
                      g: float = tank.KRAMER_G) -> float:
    """Hydrostatic vertical force [N] on a sphere held z [m] above its half-immersed position:
    rho g times the volume of the immersed cap of height R - z."""
    return rho * g * cap_volume(radius - z, radius)


def acoustic_period(case: tank.SPHCase) -> float:
    """Period [s] of the tank's lowest vertical acoustic mode, 4 d / c0 (rigid bottom, free
    surface): the slowest pressure oscillation the averaging must cover."""
    return 4.0 * case.depth / case.c0


def held_force(dp: float, z: float, *, depth: float = 0.45, half_width: float = 0.45,
               n_periods: float = 5.0, settle: float = 0.4, domain: str = "quarter",
               symmetry: str = "mirror", relax: float = tank.BODY_RELAX, **case_kw: Any
               ) -> dict[str, float]:
    """Run the sphere held at z [m] and return the mean and standard deviation [N] of the
    whole body's fluid force over ``n_periods`` acoustic periods after ``settle`` [s].

    With ``relax`` > 0 the settling is the damped relaxation of
    :func:`hybridwsi.sph.tank.decay3d` (``relax``: the rms fluid speed that ends it, as a
    fraction of sqrt(g depth); default the body cases') and ``settle`` is its longest
    duration; the average starts where it ends (``t_settled`` [s] in the result); with
    ``relax=0`` the fluid settles undamped for ``settle``. ``case_kw`` go to
    :func:`hybridwsi.sph.tank.decay3d` (e.g. ``hdx``, ``boundary``, ``packing``; the default
    packing is the body cases', packed)."""
    kw = dict(dp=dp, depth=depth, half_width=half_width, free=False,
              z0_over_d=z / tank.SPHERE_D, domain=domain, symmetry=symmetry, **case_kw)
    t_avg = n_periods * acoustic_period(tank.decay3d(tf=0.01, t_release=0.0, **kw))
    if relax > 0.0:
        # the history starts where the relaxation ends (the "release" of a held body)
        case = tank.decay3d(tf=t_avg, t_release=settle, relax=relax, **kw)
        hist = run_case(case, progress=False)
        t_settled = case.t_release
        f = hist["F_fluid"].values[:, 0]
    else:
        case = tank.decay3d(tf=settle + t_avg, t_release=0.0, relax=0.0, **kw)
        hist = run_case(case, progress=False)
        t_settled = settle
        f = hist["F_fluid"].values[:, 0][hist["time"].values >= settle - 1e-9]
    return {"z": z, "mean": float(np.mean(f)), "std": float(np.std(f)), "t_avg": t_avg,
            "n_samples": int(len(f)), "n_particles": case.n_particles, "t_settled": t_settled,
            "exact": exact_fluid_force(z, g=case.g)}


def gate(results: list[dict[str, float]], weight: float = tank.SPHERE_MASS * tank.KRAMER_G,
         ) -> dict[str, float]:
    """Buoyancy error at equilibrium [fraction of the weight], secant stiffness [N/m] and its
    error [fraction], the largest force standard deviation [N] and whether the gate passes,
    from :func:`held_force` results at -a, 0 and +a."""
    by_z = {r["z"]: r for r in results}
    zs = sorted(by_z)
    if len(zs) != 3 or not math.isclose(zs[1], 0.0, abs_tol=1e-12) or not math.isclose(
            -zs[0], zs[2]):
        raise ValueError(f"need the heights -a, 0, +a, got {zs}")
    a = zs[2]
    k_sim = (by_z[-a]["mean"] - by_z[a]["mean"]) / (2.0 * a)
    k_exact = (by_z[-a]["exact"] - by_z[a]["exact"]) / (2.0 * a)
    out = {"buoyancy_error": (by_z[0.0]["mean"] - by_z[0.0]["exact"]) / weight,
           "stiffness_sim": k_sim, "stiffness_exact": k_exact,
           "stiffness_error": k_sim / k_exact - 1.0,
           "max_std": max(r["std"] for r in results)}
    out["pass"] = bool(abs(out["buoyancy_error"]) < MAX_BUOYANCY_ERROR
                       and abs(out["stiffness_error"]) < MAX_STIFFNESS_ERROR)
    return out
