"""Write ``dsph_floatinginfo_jittered.csv`` and ``dsph_floatingace_jittered.csv``.

DualSPHysics files as they come: the output is written at the first solver step on or after
each output instant, so the times are ``k * 0.01 s`` plus up to one solver step (here
< 1.4e-4 s: steps from about 0.00986 to 0.01014 s, as in a real ``FloatingAce`` file). The
motion is the steady state of the paper's forced sphere in heave (the analytic oscillator of
``hybridwsi diagnose --example``: m = 7.06 kg, A = 3.5 kg, B = 5 N s/m, C = 692.2 N/m, three
harmonics), so every column is known exactly at every written time (``heave`` is, as in
DualSPHysics, the displacement from the initial position: z - z(0)). Columns and layout follow
``dsph_floatinginfo.csv`` / ``dsph_floatingace.csv`` (``;``-separated, trailing ``;``).

Run ``python tests/data/make_dsph_jittered.py`` to regenerate (seeded, deterministic).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
M, A, B, C, G = 7.06, 3.5, 5.0, 692.2, 9.81
PERIODS, AMPS, PHASES = (0.6, 0.75, 1.1), (4.0, 3.0, 5.0), (0.0, 1.3, 2.1)
DT_OUT, DURATION, MAX_LAG = 0.01, 4.0, 1.4e-4
Z0 = 0.72  # centre height [m] at rest


def motion(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Heave z [m], velocity [m/s] and acceleration [m/s^2] of the forced oscillator."""
    z = np.zeros_like(t, dtype=complex)
    zd = np.zeros_like(z)
    zdd = np.zeros_like(z)
    for period, amp, phase in zip(PERIODS, AMPS, PHASES):
        w = 2 * np.pi / period
        zk = amp * np.exp(1j * phase) / (C - (M + A) * w**2 + 1j * B * w) * np.exp(1j * w * t)
        z, zd, zdd = z + zk, zd + 1j * w * zk, zdd - w**2 * zk
    return z.real, zd.real, zdd.real


def jittered_times(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    k = np.arange(int(round(DURATION / DT_OUT)) + 1)
    lag = rng.uniform(0.0, MAX_LAG, k.size)
    lag[0] = 0.0  # the first output is the initial state
    return k * DT_OUT + lag


def g(x: float) -> str:
    return f"{x:.10g}"


def write_floatinginfo(path: Path) -> None:
    t = jittered_times(1)
    z, zd, zdd = motion(t)
    head = ("part;time [s];fvel.x [m/s];fvel.y [m/s];fvel.z [m/s];fomega.x [rad/s];"
            "fomega.y [rad/s];fomega.z [rad/s];center.x [m];center.y [m];center.z [m];"
            "surge [m];sway [m];heave [m];roll [deg];pitch [deg];yaw [deg];face.x [m/s^2];"
            "face.y [m/s^2];face.z [m/s^2];faceomega.x [rad/s^2];faceomega.y [rad/s^2];"
            "faceomega.z [rad/s^2];fluidforcelin.x [N];fluidforcelin.y [N];fluidforcelin.z [N];"
            "fluidforceang.x [Nm];fluidforceang.y [Nm];fluidforceang.z [Nm];")
    rows = [head]
    for k in range(t.size):
        vals = [str(k), g(t[k]), "0", "0", g(zd[k]), "0", "0", "0", "2", "1", g(Z0 + z[k]),
                "0", "0", g(z[k] - z[0]), "0", "0", "0", "0", "0", g(zdd[k]), "0", "0", "0", "0", "0",
                g(M * (zdd[k] + G)), "0", "0", "0"]
        rows.append(";".join(vals) + ";")
    path.write_text("\n".join(rows) + "\n")


def write_floatingace(path: Path) -> None:
    t = jittered_times(2)
    _, _, zdd = motion(t)
    rows = ["nstep;time [s];dt [s];predictor;acelin.x [m/s^2];acelin.y [m/s^2];"
            "acelin.z [m/s^2];aceang.x [rad/s^2];aceang.y [rad/s^2];aceang.z [rad/s^2];"]
    for k in range(t.size - 1):
        dt = t[k + 1] - t[k]
        # the predictor half-step's value differs from the corrected one (dropped on reading)
        for flag, a in (("True", zdd[k] + 0.5), ("False", zdd[k])):
            rows.append(f"{k};{g(t[k])};{g(dt)};{flag};0;0;{g(a)};0;0;0;")
    path.write_text("\n".join(rows) + "\n")


if __name__ == "__main__":
    write_floatinginfo(HERE / "dsph_floatinginfo_jittered.csv")
    write_floatingace(HERE / "dsph_floatingace_jittered.csv")
