"""An emulated Nomad 200 in this process: a SimRobot, the emulator on a pty (or TCP socket) and
the emulator host on a thread, for the driver to talk to through real file descriptors."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

from drivers.nomad200.device import Nomad200Backend
from sim_backend.emulators.host import EmulatorHost
from sim_backend.emulators.nomad200 import Nomad200Emulator
from sim_backend.emulators.nomad200_faults import FaultConfig, FaultInjector
from sim_backend.emulators.nomad200_transport import PtyTransport, TcpTransport
from sim_backend.simulator import SimParams, SimRobot
from sim_backend.world import World
from tests.conftest import box_world

#: No test may keep a host running longer than this, whatever happens to the test.
HOST_WALL_LIMIT_S = 300.0


class Rig:
    def __init__(
        self,
        *,
        world: World | None = None,
        seed: int = 3,
        drift: str = "none",
        lockstep: bool = True,
        time_scale: float = 1.0,
        faults: FaultConfig | None = None,
        link: Path | None = None,
        tcp: bool = False,
    ) -> None:
        self.lockstep = lockstep
        self.time_scale = time_scale
        self.robot = SimRobot(world or box_world(), SimParams(drift=drift), seed)
        self.transport = TcpTransport() if tcp else PtyTransport(link)
        self.emu = Nomad200Emulator(self.robot, self.transport, lockstep=lockstep, faults=faults)
        self.host = EmulatorHost(
            self.robot, [self.emu], lockstep=lockstep, time_scale=time_scale, tick_s=0.005
        )
        self.thread = threading.Thread(
            target=self.host.run, kwargs={"max_wall_s": HOST_WALL_LIMIT_S}, daemon=True
        )
        self.thread.start()

    @property
    def port(self) -> str:
        return str(self.transport.describe()["port"])

    def backend(self, **options: Any) -> Nomad200Backend:
        base = {
            "port": self.port,
            "lockstep": self.lockstep,
            "time_scale": self.time_scale,
            "sonar_pos": True,
        }
        return Nomad200Backend.from_config({**base, **options})

    def inject(self, **faults: Any) -> None:
        """Change the reply faults from now on (the host thread picks them up at once)."""
        self.emu.faults = FaultInjector(FaultConfig(**faults))

    def stop(self) -> None:
        self.host.stop()
        self.thread.join(10.0)

    def __enter__(self) -> Rig:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
