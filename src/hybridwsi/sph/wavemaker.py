"""Piston wavemaker theory (Biésel transfer function) and the paddle motion.

A piston paddle of stroke ``S`` (peak-to-peak displacement) in water of depth ``d`` makes
progressive linear waves of height ``H`` with (Biésel 1951; Dean & Dalrymple 1991, Eq. 6.25)

    H / S = 2 (cosh 2kd - 1) / (sinh 2kd + 2kd),

where ``k`` solves the linear dispersion relation ``omega^2 = g k tanh(kd)``. In shallow water
(kd -> 0) this tends to ``H/S = kd``; in deep water to 2.

NumPy/SciPy and the history package only: usable without PySPH.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.optimize import brentq

from hybridwsi.errors import InputError
from hybridwsi.history.signal import crossings

G = 9.81


def _positive(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0:
        raise InputError(f"{name} must be a positive finite number, got {value!r}")
    return v


def wavenumber(period: float, depth: float, g: float = G) -> float:
    """Wavenumber k [rad/m] from the linear dispersion relation omega^2 = g k tanh(k d).

    Parameters
    ----------
    period : float
        Wave period T [s].
    depth : float
        Water depth d [m].
    g : float
        Gravity [m/s^2].
    """
    T, d, g = _positive("period", period), _positive("depth", depth), _positive("g", g)
    omega2 = (2.0 * math.pi / T) ** 2
    k_deep = omega2 / g
    # f is increasing in k; the root lies between the deep-water and shallow-water guesses
    def f(k: float) -> float:
        return g * k * math.tanh(k * d) - omega2

    hi = max(k_deep, math.sqrt(omega2 / (g * d))) * 2.0
    return float(brentq(f, 1e-12, hi, xtol=1e-14, rtol=1e-13))


def biesel_ratio(kd: float | np.ndarray) -> float | np.ndarray:
    """Piston wavemaker height-to-stroke ratio H/S [-] at relative depth kd [-]."""
    kd = np.asarray(kd, dtype=float)
    if np.any(~np.isfinite(kd)) or np.any(kd <= 0):
        raise InputError("kd must be positive and finite")
    two = 2.0 * kd
    # cosh(2kd) - 1 = 2 sinh^2(kd): no cancellation at small kd (shallow-water limit H/S -> kd)
    ratio = 2.0 * (2.0 * np.sinh(kd) ** 2) / (np.sinh(two) + two)
    return float(ratio) if ratio.ndim == 0 else ratio


def piston_stroke(height: float, period: float, depth: float, g: float = G) -> float:
    """Piston stroke S [m] (peak to peak) that makes linear waves of height H [m]."""
    H = _positive("wave height", height)
    k = wavenumber(period, depth, g)
    return H / biesel_ratio(k * depth)


def ramp(t: float, t_ramp: float) -> float:
    """Smooth start-up factor in [0, 1]: 0.5 (1 - cos(pi t / t_ramp)) for t < t_ramp."""
    if t_ramp <= 0 or t >= t_ramp:
        return 1.0 if t >= 0 else 0.0
    if t <= 0:
        return 0.0
    return 0.5 * (1.0 - math.cos(math.pi * t / t_ramp))


def piston_motion(t: float, stroke: float, period: float, t_ramp: float) -> tuple[float, float, float]:
    """Paddle displacement X [m], velocity [m/s] and acceleration [m/s^2] at time t [s].

    ``X(t) = r(t) (S/2) sin(omega t)`` with the ramp ``r`` of :func:`ramp` (its derivatives
    are included so that the paddle acceleration used by the wall boundary condition is exact).
    """
    w = 2.0 * math.pi / period
    a = 0.5 * stroke
    s, c = math.sin(w * t), math.cos(w * t)
    if t_ramp > 0 and 0 < t < t_ramp:
        q = math.pi / t_ramp
        r = 0.5 * (1.0 - math.cos(q * t))
        dr = 0.5 * q * math.sin(q * t)
        ddr = 0.5 * q * q * math.cos(q * t)
    else:
        r, dr, ddr = (1.0 if t >= t_ramp else 0.0), 0.0, 0.0
    x = r * a * s
    v = a * (dr * s + r * w * c)
    acc = a * (ddr * s + 2.0 * dr * w * c - r * w * w * s)
    return x, v, acc


def zero_upcrossing(t: np.ndarray, eta: np.ndarray, t_start: float = 0.0,
                    t_end: float | None = None) -> tuple[float, float, int]:
    """Mean wave height H [m] and period T [s] of a record by zero up-crossing analysis.

    The record (minus its mean over the window) is cut at up-crossings (linearly interpolated,
    :func:`hybridwsi.history.crossings`); each complete wave contributes crest - trough and its
    duration. Returns (H, T, n_waves).
    """
    t = np.asarray(t, dtype=float)
    eta = np.asarray(eta, dtype=float)
    if t.shape != eta.shape or t.ndim != 1:
        raise InputError("t and eta must be 1-D arrays of the same length")
    sel = (t >= t_start) & (t <= (t[-1] if t_end is None else t_end)) & np.isfinite(eta)
    t, e = t[sel], eta[sel] - np.mean(eta[sel]) if np.any(sel) else eta[sel]
    up, tc = crossings(t, e, 0.0, direction="up")  # e is already about its mean
    if len(up) < 2:
        raise InputError("fewer than two zero up-crossings in the window: no waves measured")
    heights = [e[i0:i1 + 1].max() - e[i0:i1 + 1].min() for i0, i1 in itertools.pairwise(up)]
    return float(np.mean(heights)), float(np.mean(np.diff(tc))), len(heights)


def group_velocity(period: float, depth: float, g: float = G) -> float:
    """Linear group velocity c_g [m/s] of waves of ``period`` [s] in water of ``depth`` [m]."""
    k = wavenumber(period, depth, g)
    kd2 = 2.0 * k * depth
    ratio = kd2 / math.sinh(kd2) if kd2 < 100.0 else 0.0  # (< 1e-41; sinh overflows later)
    return 0.5 * (1.0 + ratio) * (2.0 * math.pi / period) / k


def probe_waves(time: np.ndarray, eta: np.ndarray, probe_x: np.ndarray, period: float,
                depth: float, t_ramp: float, g: float = G) -> list[dict[str, float]]:
    """Mean height and period at each probe of a flume record, once steady.

    Each probe's window starts when the end of the paddle's ramp-up has travelled to it at
    the group velocity, plus one period; the rest of the record is analysed by
    :func:`zero_upcrossing`.

    Parameters
    ----------
    time : array (n,)
        Sample times [s].
    eta : array (n, n_probes)
        Free-surface elevation at the probes [m].
    probe_x : array (n_probes,)
        Probe distances from the paddle's mean position [m].
    period, depth, t_ramp : float
        Paddle period [s], still-water depth [m] and ramp-up duration [s].

    Returns
    -------
    list of dict with ``x`` [m], ``t_start`` [s], ``H`` [m], ``T`` [s] and ``n_waves``.
    """
    eta = np.asarray(eta, dtype=float)
    probe_x = np.atleast_1d(np.asarray(probe_x, dtype=float))
    if eta.ndim != 2 or eta.shape[1] != len(probe_x):
        raise InputError(f"eta must be (time, probe) with {len(probe_x)} probes, "
                         f"got shape {eta.shape}")
    cg = group_velocity(period, depth, g)
    out = []
    for i, x in enumerate(probe_x):
        t0 = t_ramp + x / cg + period
        H, T, n = zero_upcrossing(time, eta[:, i], t_start=t0)
        out.append({"x": float(x), "t_start": t0, "H": H, "T": T, "n_waves": n})
    return out
