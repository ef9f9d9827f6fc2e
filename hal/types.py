"""SI-unit data exchanged through the hal: metres, radians, seconds, metres per second.

Frames: the *odometry frame* is where the robot's dead reckoning started; the *robot frame*
has its origin at the robot's centre and its x axis along the heading (the synchro drive's
steering angle). Angles are counter-clockwise. Stamps are seconds on the backend's clock.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Odometry:
    """The robot's own dead-reckoned pose in the odometry frame.

    ``heading_rad`` is the steering angle (direction of travel); ``turret_rad`` is the turret's
    angle in the same frame, independent of steering on a synchro drive. Both drift: that is
    what topological localization exists to survive.
    """

    x_m: float
    y_m: float
    heading_rad: float
    turret_rad: float
    stamp_s: float
    distance_m: float = 0.0  # total path length travelled, from the translation encoder


@dataclass(frozen=True)
class Twist:
    """A synchro-drive velocity command: translation along the heading, steering and turret
    rates."""

    v_mps: float = 0.0
    steer_radps: float = 0.0
    turret_radps: float = 0.0

    def is_finite(self) -> bool:
        return all(math.isfinite(v) for v in (self.v_mps, self.steer_radps, self.turret_radps))


@dataclass(frozen=True)
class DriveStatus:
    """What the base reports about itself."""

    bumper: bool
    stall: bool
    motors_on: bool
    stamp_s: float


@dataclass(frozen=True)
class SonarReading:
    """One transducer's latest reading. ``range_m`` is None when no echo came back."""

    range_m: float | None
    x_m: float
    y_m: float
    yaw_rad: float
    stamp_s: float


@dataclass(frozen=True, eq=False)
class SonarScan:
    """The latest reading of every transducer of a ring.

    Arrays have one entry per transducer, in ring order. ``ranges_m`` holds NaN where there was
    no echo. Ranges are measured from the transducer along its axis; its pose (``x_m``, ``y_m``,
    ``yaw_rad``) is in the robot frame with the turret angle applied at the moment it fired, so
    a reading's obstacle point in the robot frame is ``(x + r cos yaw, y + r sin yaw)``.
    Transducers fire one after another, hence a stamp each.
    """

    ranges_m: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    yaw_rad: np.ndarray
    stamps_s: np.ndarray
    min_range_m: float
    max_range_m: float
    half_beam_rad: float

    def __len__(self) -> int:
        return len(self.ranges_m)

    @property
    def echo(self) -> np.ndarray:
        """True where the transducer heard an echo."""
        return ~np.isnan(self.ranges_m)

    @property
    def stamp_s(self) -> float:
        """Stamp of the most recent reading in the scan."""
        return float(np.max(self.stamps_s)) if len(self.stamps_s) else 0.0

    def reading(self, i: int) -> SonarReading:
        r = float(self.ranges_m[i])
        return SonarReading(
            range_m=None if math.isnan(r) else r,
            x_m=float(self.x_m[i]),
            y_m=float(self.y_m[i]),
            yaw_rad=float(self.yaw_rad[i]),
            stamp_s=float(self.stamps_s[i]),
        )

    def readings(self) -> list[SonarReading]:
        return [self.reading(i) for i in range(len(self))]

    def points_robot_frame(self) -> np.ndarray:
        """Echo points ``(K, 2)`` in the robot frame, for the transducers that heard one."""
        m = self.echo
        r = self.ranges_m[m]
        return np.column_stack(
            [self.x_m[m] + r * np.cos(self.yaw_rad[m]), self.y_m[m] + r * np.sin(self.yaw_rad[m])]
        )
