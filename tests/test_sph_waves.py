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


def test_3d_flume_makes_waves_and_gain_scales_the_stroke():
    T, H, d = 0.75, 0.05, 0.25
    lam = 2 * math.pi / wavemaker.wavenumber(T, d, tank.KRAMER_G)
    kw = {"dp": 0.05, "depth": d, "period": T, "height": H, "length": 2 * lam,
          "half_width": 0.2, "tf": 3.4, "t_ramp": T, "c0_factor": 6.0, "probes": (0.6 * lam,)}
    case = tank.waves3d(**kw)
    assert tank.waves3d(**kw, gain=1.5).inputs["stroke"] == pytest.approx(
        1.5 * wavemaker.piston_stroke(H, T, d, tank.KRAMER_G))
    assert case.probes == [(pytest.approx(0.6 * lam), 0.1)]  # halfway to the side wall
    hist = run_case(case, progress=False)
    eta = hist["eta"].isel(probe=0).values
    Hm, Tm, n = wavemaker.zero_upcrossing(hist["time"].values, eta, t_start=1.6)
    assert n >= 2
    assert Tm == pytest.approx(T, rel=0.05)
    # H/dp = 1 and four particles across in 3D: the wave is low (numerical damping, measured
    # 0.55 H) but of the Biésel order; at useful spacings see scripts/sph_wave_calibration.py
    assert 0.4 * H < Hm < 1.1 * H
    assert abs(eta[:20].mean()) < 0.1 * H  # at rest the probe reads the still-water level


@pytest.mark.parametrize("bad", [{"gain": 0.0}, {"gain": float("nan")}, {"gain": 5.0},
                                 {"half_width": 0.1}])
def test_3d_flume_rejects_bad_inputs(bad):
    from hybridwsi.errors import InputError

    with pytest.raises(InputError):
        tank.waves3d(**{"dp": 0.05, "depth": 0.25, **bad})
    if "gain" in bad:
        with pytest.raises(InputError, match="gain"):
            tank.regular3d(dp=0.0375, depth=0.45, **bad)
