"""PySPH piston wave flume (2D, tiny): waves of the paddle period appear at a probe.

Shares the compiled 2D kernel set with test_sph_tank.py. The 5 % height/period validation at
a useful resolution is scripts/sph_validate_2d.py (minutes to hours).
"""

import math

import pytest

pytest.importorskip("pysph")

from hybridwsi.sph import tank, wavemaker
from hybridwsi.sph.run import run_case

pytestmark = pytest.mark.sph


def test_piston_makes_waves_of_the_paddle_period():
    T = 0.8
    lam = 2 * math.pi / wavemaker.wavenumber(T, 0.3)
    case = tank.waves2d(dp=0.03, depth=0.3, period=T, height=0.045, length=2 * lam,
                        tf=3.6, t_ramp=T, c0_factor=6.0, probes=(0.6 * lam,))
    hist = run_case(case, progress=False)
    eta = hist["eta"].isel(probe=0).values
    H, Tm, n = wavemaker.zero_upcrossing(hist["time"].values, eta, t_start=1.2)
    assert n >= 2  # two complete waves after the ramp-up has reached the probe
    assert Tm == pytest.approx(T, rel=0.05)
    # Biésel (linear piston theory) height ~2 depths from the paddle. Coarse (H/dp = 1.5), yet
    # within 15 % with the flume's defaults h/dp = 2, alpha = 0.005 (-8.5 %); with the former
    # h/dp = 1.3, alpha = 0.02 the wave came out 22 % low (over-damped)
    assert 0.85 * 0.045 < H < 1.10 * 0.045
