"""The NREL 5-MW baseline controller: generator-torque law and gain-scheduled PI blade pitch.

Jonkman, Butterfield, Musial & Scott (2009), NREL/TP-500-38060, chapter 7 and Table 7-2, as
coded in its DISCON routine (names in brackets). All speeds are on the generator (high-speed)
side [rad/s], torques on the generator [N m]; the gearbox ratio N = 97 carries them to the
rotor (rotor torque = N x generator torque, generator speed = N x rotor speed).

Torque law (:class:`TorqueLaw`), regions of the generator speed w:

- 1, w <= 70.16224 [VS_CtInSp]: no torque;
- 1 1/2, up to 91.21091 [VS_Rgn2Sp]: linear ramp to the region-2 law;
- 2: K w^2, K = 2.332287 N m/(rad/s)^2 [VS_Rgn2K] (the optimal tip-speed ratio);
- 2 1/2, from the intersection with the 10 %-slip line [VS_SlPc] to 121.6805 [VS_RtGnSp]:
  the slip line, reaching the rated torque;
- 3, w >= 121.6805 or pitch >= 1 deg [VS_Rgn3MP]: constant power 5 296 610 W [VS_RtPwr]
  (``"constant_power"``, the baseline) or the rated torque 5 296 610 / 122.9096 N m
  (``"constant_torque"``, the OC3-Hywind controller: Jonkman 2010, NREL/TP-500-47535, 7.2).

Pitch (:class:`PitchPI`): a PI law on the generator-speed error e = w − 122.9096 [PC_RefSpd],
gain-scheduled with GK = 1/(1 + pitch/theta_K): pitch = GK(pitch) (KP e + KI ∫e), i.e. the
pitch solves pitch (1 + pitch/theta_K) = KP e + KI ∫e (DISCON evaluates GK on the previous
command; in steady state the same), limited below by 0 with the integral held there
(anti-windup). Baseline KP = 0.01882681 s, KI = 0.008068634, theta_K = 6.302336 deg; OC3-Hywind
detuned KP = 0.006275604 s, KI = 0.0008965149 (the controller's natural frequency below the
platform's pitch frequency, so that it does not drive the pitch mode).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from collections.abc import Mapping
from typing import Any

import numpy as np

from hybridwsi.errors import InputError

#: Table 7-2 / DISCON values of the torque law (generator side)
BASELINE_TORQUE = dict(cut_in_speed=70.16224, region2_speed=91.21091, k=2.332287,
                       rated_speed=121.6805, reference_speed=122.9096, rated_power=5296610.0,
                       slip_percent=10.0, region3_pitch=math.radians(1.0))
#: the attributes of a rotor table that hold them (DISCON names)
DISCON_NAMES = dict(cut_in_speed="VS_CtInSp", region2_speed="VS_Rgn2Sp", k="VS_Rgn2K",
                    rated_speed="VS_RtGnSp", reference_speed="PC_RefSpd",
                    rated_power="VS_RtPwr", slip_percent="VS_SlPc",
                    region3_pitch="VS_Rgn3MP")
REGION3 = ("constant_power", "constant_torque")
#: PI gains on the generator speed: (KP [s], KI [-])
PI_GAINS = {"baseline": (0.01882681, 0.008068634), "oc3_detuned": (0.006275604, 0.0008965149)}
THETA_K = math.radians(6.302336)


@dataclass(frozen=True)
class TorqueLaw:
    """The DISCON generator-torque law (module docstring); speeds [rad/s], torque [N m]."""

    cut_in_speed: float
    region2_speed: float
    k: float
    rated_speed: float
    reference_speed: float
    rated_power: float
    slip_percent: float
    region3_pitch: float
    region3: str = "constant_power"

    def __post_init__(self) -> None:
        if self.region3 not in REGION3:
            raise InputError(f"region-3 torque must be one of {list(REGION3)}, "
                             f"got {self.region3!r}")

    @classmethod
    def from_attrs(cls, attrs: Mapping[str, Any], region3: str = "constant_power") -> TorqueLaw:
        """From a rotor table's DISCON-named attributes."""
        try:
            values = {key: float(attrs[name]) for key, name in DISCON_NAMES.items()}
        except KeyError as exc:
            raise InputError(f"rotor table has no torque-law attribute {exc}") from None
        return cls(**values, region3=region3)

    @property
    def synchronous_speed(self) -> float:
        """Zero-torque speed of the slip line [rad/s] (VS_SySp)."""
        return self.rated_speed / (1.0 + 0.01 * self.slip_percent)

    @property
    def slope15(self) -> float:
        return self.k * self.region2_speed**2 / (self.region2_speed - self.cut_in_speed)

    @property
    def slope25(self) -> float:
        return (self.rated_power / self.rated_speed) / (self.rated_speed - self.synchronous_speed)

    @property
    def transition_speed(self) -> float:
        """Where the region-2 law meets the slip line [rad/s] (VS_TrGnSp)."""
        s, sy = self.slope25, self.synchronous_speed
        return (s - math.sqrt(s * (s - 4.0 * self.k * sy))) / (2.0 * self.k)

    def law(self, w: float, pitch: float = 0.0) -> tuple[float, float]:
        """(torque [N m], d torque/d speed [N m s/rad]) at generator speed ``w`` [rad/s] and
        pitch [rad] (one state, Python floats: it sits in the ODE right-hand side)."""
        if w >= self.rated_speed or pitch >= self.region3_pitch:
            if self.region3 == "constant_torque":
                return self.rated_power / self.reference_speed, 0.0
            return self.rated_power / w, -self.rated_power / (w * w)
        if w <= self.cut_in_speed:
            return 0.0, 0.0
        if w < self.region2_speed:
            return self.slope15 * (w - self.cut_in_speed), self.slope15
        if w < self.transition_speed:
            return self.k * w * w, 2.0 * self.k * w
        return self.slope25 * (w - self.synchronous_speed), self.slope25

    def torque(self, w: Any, pitch: Any = 0.0) -> Any:
        """Generator torque [N m] (floats, or arrays that broadcast)."""
        if np.ndim(w) == 0 and np.ndim(pitch) == 0:
            return self.law(float(w), float(pitch))[0]
        return np.vectorize(lambda a, b: self.law(a, b)[0], otypes=[float])(w, pitch)

    def slope(self, w: Any, pitch: Any = 0.0) -> Any:
        """d(torque)/d(speed) [N m s/rad] at fixed pitch (floats, or arrays)."""
        if np.ndim(w) == 0 and np.ndim(pitch) == 0:
            return self.law(float(w), float(pitch))[1]
        return np.vectorize(lambda a, b: self.law(a, b)[1], otypes=[float])(w, pitch)


def baseline_torque_law(region3: str = "constant_power") -> TorqueLaw:
    """The torque law of Jonkman 2009 Table 7-2."""
    return TorqueLaw(**BASELINE_TORQUE, region3=region3)


@dataclass(frozen=True)
class PitchPI:
    """Gain-scheduled PI pitch law (module docstring).

    Parameters
    ----------
    kp : float
        Proportional gain [s] on the generator-speed error.
    ki : float
        Integral gain [-].
    theta_k : float
        Pitch [rad] at which the gain has halved (gain scheduling).
    reference_speed : float
        Generator speed set point [rad/s].
    """

    kp: float
    ki: float
    theta_k: float = THETA_K
    reference_speed: float = BASELINE_TORQUE["reference_speed"]

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "theta_k", "reference_speed"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"pitch controller: {name} must be a positive number, got {v!r}")

    def command(self, error: np.ndarray, integral: np.ndarray) -> np.ndarray:
        """Pitch [rad] for speed error [rad/s] and integrated error [rad]: the root of
        pitch (1 + pitch/theta_K) = KP e + KI ∫e, and 0 when that is negative."""
        if np.ndim(error) == 0 and np.ndim(integral) == 0:  # one state: Python floats
            u = max(self.kp * float(error) + self.ki * float(integral), 0.0)
            return 0.5 * self.theta_k * (math.sqrt(1.0 + 4.0 * u / self.theta_k) - 1.0)
        u = np.maximum(self.kp * np.asarray(error) + self.ki * np.asarray(integral), 0.0)
        return 0.5 * self.theta_k * (np.sqrt(1.0 + 4.0 * u / self.theta_k) - 1.0)

    def slope(self, pitch: float) -> float:
        """d(pitch)/d(KP e + KI ∫e) at a pitch [rad] > 0: 1/(1 + 2 pitch/theta_K)."""
        return 1.0 / (1.0 + 2.0 * pitch / self.theta_k)

    def integral_for(self, pitch: float) -> float:
        """∫e [rad] that holds ``pitch`` [rad] at zero speed error (the steady state)."""
        return pitch * (1.0 + pitch / self.theta_k) / self.ki
