"""One robot from two backends: drive and encoders from one, the sonar ring from another.

A Nomad 200 retrofitted with a CAN ultrasonic board is configured as ::

    {"backend": "composed",
     "drive": {"backend": "nomad200", "port": "/dev/ttyS0"},
     "sonar": {"backend": "can-sonar", "interface": "socketcan", "channel": "can0"},
     "sonar_mount": "turret"}

``drive`` and ``sonar`` are any specs ``create_backend`` accepts. The lifecycle is forwarded to
both: configure drive then sonar; activate sonar then drive (nothing moves before the ring is
up); deactivate and close stop the drive first, and close releases both even if one fails.

Time. ``clock.now()`` is the drive's clock, and every scan's stamps are re-expressed on it (by
the offset between the two clocks at the moment of the scan), so odometry and sonar stamps can
be compared. ``clock.sleep(s)`` lets ``s`` pass on both clocks: on a robot both are the host's
monotonic clock and this is one sleep; with a simulated drive (whose sleep steps the simulation)
and a real-time sonar, the sleep also waits out the sonar's real time, so scans keep coming.

Geometry. With ``sonar_mount = "turret"`` (default, where a Nomad's ring sits) the ring's poses
are turned by the turret's angle relative to the heading, read from the drive's odometry when
the scan is taken; with ``"body"`` they are used as the sonar backend gives them.

Safety. If the sonar fails (``scan`` raises a hal error, e.g. the board was lost), the drive is
told to stop before the error is passed on.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from hal.clock import Clock
from hal.config import Options
from hal.errors import ConfigurationError, HalError
from hal.interfaces import Backend, Drive, DriveLimits, Encoders, SonarRing
from hal.lifecycle import State
from hal.types import DriveStatus, Odometry, SonarScan, Twist

MOUNTS = ("turret", "body")


class ComposedClock:
    """The drive's time; a sleep lets the time pass on the sonar's clock as well."""

    def __init__(self, drive: Clock, sonar: Clock) -> None:
        self.drive = drive
        self.sonar = sonar

    def now(self) -> float:
        return self.drive.now()

    def sleep(self, seconds: float) -> None:
        if seconds <= 0:
            return
        start = self.sonar.now()
        self.drive.sleep(seconds)
        remaining = seconds - (self.sonar.now() - start)
        if remaining > 0:
            self.sonar.sleep(remaining)

    def sonar_to_drive(self) -> float:
        """Offset to add to a sonar stamp to put it on the drive's clock."""
        return self.drive.now() - self.sonar.now()


class ComposedBackend(Drive, Encoders, SonarRing):
    """Drive and encoders of one backend, the sonar ring of another."""

    backend_name = "composed"

    def __init__(self, drive: Backend, sonar: Backend, *, sonar_mount: str = "turret") -> None:
        super().__init__()
        if not (isinstance(drive, Drive) and isinstance(drive, Encoders)):
            raise ConfigurationError(
                f"composed: the drive backend '{drive.backend_name}' must provide Drive and"
                " Encoders"
            )
        if not isinstance(sonar, SonarRing):
            raise ConfigurationError(
                f"composed: the sonar backend '{sonar.backend_name}' does not provide a SonarRing"
            )
        if sonar_mount not in MOUNTS:
            raise ConfigurationError(
                f"composed: option 'sonar_mount' must be one of {', '.join(MOUNTS)},"
                f" got {sonar_mount!r}"
            )
        self.drive: Any = drive  # Drive and Encoders; Any keeps both interfaces visible
        self.sonar: SonarRing = sonar
        self.sonar_mount = sonar_mount
        self.backend_name = f"composed({drive.backend_name}+{sonar.backend_name})"
        same = drive.clock is sonar.clock
        self._clock: Clock = drive.clock if same else ComposedClock(drive.clock, sonar.clock)

    @classmethod
    def from_config(cls, options: Mapping[str, Any]) -> ComposedBackend:
        from hal.registry import create_backend

        raw = dict(options)
        specs = {}
        for key in ("drive", "sonar"):
            spec = raw.pop(key, None)
            if spec is None:
                raise ConfigurationError(f"composed: option '{key}' (a backend spec) is required")
            specs[key] = spec
        opts = Options("composed", raw)
        mount = opts.choice("sonar_mount", MOUNTS, "turret")
        opts.finish()
        drive = create_backend(specs["drive"])
        try:
            sonar = create_backend(specs["sonar"])
        except BaseException:
            drive.close()
            raise
        try:
            return cls(drive, sonar, sonar_mount=mount)
        except BaseException:
            drive.close()
            sonar.close()
            raise

    # ------------------------------------------------------------------ Backend
    @property
    def clock(self) -> Clock:
        return self._clock

    @property
    def limits(self) -> DriveLimits:
        return self.drive.limits

    @property
    def n_transducers(self) -> int:
        return self.sonar.n_transducers

    def _on_configure(self) -> None:
        self.drive.configure()
        self.sonar.configure()  # on failure the lifecycle calls _on_close, which closes both

    def _on_activate(self) -> None:
        self.sonar.activate()
        try:
            self.drive.activate()
        except BaseException:
            self.sonar.deactivate()
            raise

    def _on_deactivate(self) -> None:
        try:
            if self.drive.state is State.ACTIVE:
                self.drive.deactivate()
        finally:
            if self.sonar.state is State.ACTIVE:
                self.sonar.deactivate()

    def _on_close(self) -> None:
        try:
            self.drive.close()
        finally:
            self.sonar.close()

    def close(self) -> None:
        try:
            super().close()
        finally:
            # Also when never configured: the parts own resources of their own to release.
            try:
                self.drive.close()
            finally:
                self.sonar.close()

    # ------------------------------------------------------------------ Drive
    def _command(self, twist: Twist) -> None:
        self.drive.command(twist)

    def _stop(self) -> None:
        self.drive.stop()

    def _status(self) -> DriveStatus:
        return self.drive.status()

    # ------------------------------------------------------------------ Encoders
    def _odometry(self) -> Odometry:
        return self.drive.odometry()

    # ------------------------------------------------------------------ SonarRing
    def _scan(self) -> SonarScan:
        try:
            scan = self.sonar.scan()
        except HalError:
            self.drive.stop()  # a blind robot must not keep moving
            raise
        x, y, yaw = scan.x_m, scan.y_m, scan.yaw_rad
        if self.sonar_mount == "turret":
            odo = self.drive.odometry()
            turn = odo.turret_rad - odo.heading_rad
            c, s = math.cos(turn), math.sin(turn)
            x, y = c * x - s * y, s * x + c * y
            yaw = np.angle(np.exp(1j * (yaw + turn)))
        stamps = scan.stamps_s
        if isinstance(self._clock, ComposedClock):
            stamps = stamps + self._clock.sonar_to_drive()
        return SonarScan(
            ranges_m=scan.ranges_m,
            x_m=np.asarray(x, dtype=float),
            y_m=np.asarray(y, dtype=float),
            yaw_rad=np.asarray(yaw, dtype=float),
            stamps_s=np.asarray(stamps, dtype=float),
            min_range_m=scan.min_range_m,
            max_range_m=scan.max_range_m,
            half_beam_rad=scan.half_beam_rad,
        )
