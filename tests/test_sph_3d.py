"""PySPH wave tank in 3D: quarter-domain sphere (two symmetry planes), one compiled kernel.

The first run compiles the 3D kernel set (~1 min, cached in ~/.pysph afterwards).
"""

import math

import numpy as np
import pytest

pytest.importorskip("pysph")

from hybridwsi.sph import tank
from hybridwsi.sph.run import run_case

pytestmark = pytest.mark.sph


def test_fixed_half_submerged_sphere_buoyancy_quarter_domain():
    # quarter of the Kramer sphere held at its equilibrium draft: the particle force times 4
    # (two symmetry planes) must equal Archimedes' rho g (2/3) pi R^3 (R/dp = 4, so 10 %)
    case = tank.decay3d(dp=0.0375, depth=0.45, half_width=0.45, z0_over_d=0.0, tf=0.3,
                        free=False)
    assert case.wall.body[8] == 4.0
    hist = run_case(case, progress=False)
    f = float(hist["F_fluid"].where(hist["time"] >= 0.15, drop=True).mean())
    r = tank.SPHERE_D / 2
    assert f == pytest.approx(tank.RHO_WATER * tank.KRAMER_G * 2 / 3 * math.pi * r ** 3, rel=0.10)
    assert np.all(np.isfinite(hist["F_tot"].values))
