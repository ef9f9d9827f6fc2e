"""The three hal interfaces. Public methods hold the shared rules (lifecycle guards, command
validation, limits); a backend implements the underscored hooks.

A backend class inherits the interfaces it provides, e.g.
``class SimBackend(Drive, Encoders, SonarRing)``; a CAN sonar board is only a ``SonarRing``.
"""

from __future__ import annotations

import math
from abc import abstractmethod
from dataclasses import dataclass

from hal.clock import Clock
from hal.errors import CommandError
from hal.lifecycle import Lifecycle
from hal.types import DriveStatus, Odometry, SonarScan, Twist


@dataclass(frozen=True)
class DriveLimits:
    """Largest magnitudes the base accepts; commands beyond them are clamped."""

    v_mps: float
    steer_radps: float
    turret_radps: float
    accel_mps2: float
    steer_accel_radps2: float
    turret_accel_radps2: float


#: The Nomad 200's usual driver limits: 20 in/s, 45 deg/s, acceleration 30 in/s^2 and 30 deg/s^2.
NOMAD200_LIMITS = DriveLimits(
    v_mps=20 * 0.0254,
    steer_radps=math.radians(45.0),
    turret_radps=math.radians(45.0),
    accel_mps2=30 * 0.0254,
    steer_accel_radps2=math.radians(30.0),
    turret_accel_radps2=math.radians(30.0),
)


class Backend(Lifecycle):
    """Anything the registry can create: a lifecycle and a clock."""

    @property
    @abstractmethod
    def clock(self) -> Clock:
        """The clock this backend stamps its data with."""


class Drive(Backend):
    """Synchro-drive base: translation, steering and turret velocity commands."""

    @property
    @abstractmethod
    def limits(self) -> DriveLimits: ...

    def command(self, twist: Twist) -> None:
        """Send a velocity command; clamped to ``limits``. Only while active."""
        with self._lock:
            self._require_active("send a motion command")
            if not twist.is_finite():
                self._stop()
                raise CommandError(f"{self.backend_name}: refused non-finite command {twist}")
            lim = self.limits
            self._command(
                Twist(
                    v_mps=_clamp(twist.v_mps, lim.v_mps),
                    steer_radps=_clamp(twist.steer_radps, lim.steer_radps),
                    turret_radps=_clamp(twist.turret_radps, lim.turret_radps),
                )
            )

    def stop(self) -> None:
        """Stop all motion. Always allowed while the link is open; a no-op otherwise, since a
        backend that is not open has already stopped the robot (close and deactivate do)."""
        with self._lock:
            if self.is_open:
                self._stop()

    def status(self) -> DriveStatus:
        with self._lock:
            self._require_open("read the drive status")
            return self._status()

    def _safe_stop(self) -> None:
        self._stop()
        super()._safe_stop()

    @abstractmethod
    def _command(self, twist: Twist) -> None: ...

    @abstractmethod
    def _stop(self) -> None: ...

    @abstractmethod
    def _status(self) -> DriveStatus: ...


class Encoders(Backend):
    """The robot's dead reckoning."""

    def odometry(self) -> Odometry:
        with self._lock:
            self._require_open("read odometry")
            return self._odometry()

    @abstractmethod
    def _odometry(self) -> Odometry: ...


class SonarRing(Backend):
    """A ring of range sensors, each reading stamped and posed in the robot frame."""

    @property
    @abstractmethod
    def n_transducers(self) -> int: ...

    def scan(self) -> SonarScan:
        """The latest reading of every transducer."""
        with self._lock:
            self._require_open("read the sonar ring")
            return self._scan()

    @abstractmethod
    def _scan(self) -> SonarScan: ...


def _clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))
