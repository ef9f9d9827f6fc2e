"""One process, one simulated robot, any number of emulated devices on it.

A Nomad 200 with a CAN sonar board is one robot with two links: the serial emulator drives the
simulated base and the CAN emulator fires its sonar ring, so both must share one ``SimRobot``.
The host owns the robot and the passage of time; each device owns its link.

Time: in *real-time* mode simulated time follows the host's monotonic clock times
``time_scale``. In *lockstep* mode it passes only when a device says so (``advance``), e.g.
the serial emulator steps the robot by a fixed period per motion command, which makes a run
through the emulator as reproducible as one in process.
"""

from __future__ import annotations

import select
import time
from collections.abc import Callable, Sequence
from typing import Protocol

from sim_backend.simulator import SimRobot


class EmulatedDevice(Protocol):
    """A device served by the host. All methods are called from the host's one thread."""

    def fileno(self) -> int:
        """The descriptor to wait on for incoming bytes (a pty master, a socket)."""
        ...

    def service(self, now_s: float) -> None:
        """Read what has arrived and answer it; must not block."""
        ...

    def tick(self, now_s: float) -> None:
        """Periodic duties at simulated time ``now_s`` (watchdogs, heartbeats, data)."""
        ...

    def close(self) -> None: ...


class EmulatorHost:
    """Runs devices against one robot until ``stop`` is called or a device raises."""

    def __init__(
        self,
        robot: SimRobot,
        devices: Sequence[EmulatedDevice],
        *,
        time_scale: float = 1.0,
        lockstep: bool = False,
        tick_s: float = 0.01,
        monotonic: Callable[[], float] = time.monotonic,
    ) -> None:
        if not time_scale > 0:
            raise ValueError(f"time_scale must be positive, got {time_scale}")
        self.robot = robot
        self.devices = list(devices)
        self.time_scale = time_scale
        self.lockstep = lockstep
        self.tick_s = tick_s
        self._monotonic = monotonic
        # Set here, not in run: a stop() from a signal handler that lands before run() starts
        # must still be honoured.
        self._running = True

    def advance(self, dt_s: float) -> None:
        """Let ``dt_s`` of simulated time pass (lockstep mode's only source of time)."""
        self.robot.step(dt_s)

    def stop(self) -> None:
        self._running = False

    def run(self, max_wall_s: float | None = None) -> None:
        """Serve until ``stop``; ``max_wall_s`` bounds the run (tests)."""
        start = last = self._monotonic()
        try:
            while self._running:
                now = self._monotonic()
                if max_wall_s is not None and now - start > max_wall_s:
                    break
                if not self.lockstep:
                    self.robot.step((now - last) * self.time_scale)
                last = now
                fds = [d.fileno() for d in self.devices]
                ready, _, _ = select.select(fds, [], [], self.tick_s)
                for dev in self.devices:
                    if dev.fileno() in ready:
                        dev.service(self.robot.t)
                for dev in self.devices:
                    dev.tick(self.robot.t)
        finally:
            for dev in self.devices:
                dev.close()
