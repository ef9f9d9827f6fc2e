"""The robot ``tslam sim`` explores (``--backend``): in process, or behind its wire protocols.

* ``sim`` (default): the simulator behind the hal, in process (``sim_backend.backend``).
* ``nomad200-emulated``: the Nomad 200 driver (``drivers.nomad200``) over pyserial and a
  pseudo-terminal to the Nomad 200 emulator, which drives the simulated robot.
* ``nomad200+can-sonar-emulated``: drive and encoders from that driver, the sonar ring from the
  CAN board driver (``drivers.can_sonar``) over python-can's ``slcan`` interface on a second
  pseudo-terminal, answered by the CAN board emulator firing the same simulated robot's ring.
  Both emulators sit on one ``EmulatorHost``, as in ``tslam emulate nomad200 --with-can-sonar``.

Why the emulators run in this process, on a thread, rather than as ``tslam emulate`` in another:
the report and pictures score the run against where the robot really was, and only the
``SimRobot`` knows that. Hosting it here keeps the true pose one attribute away without adding
a side channel to either protocol (a real robot has none, and a channel only tests use is one
more thing to keep honest). Nothing is short-cut on the way: every request and reply is bytes
through pyserial, termios and a pty, or through python-can, the SLCAN adapter protocol and a
pty, and the emulators are the very ones ``tslam emulate`` serves; that they also work across
processes is tested there (``tests/test_nomad200_device.py``, ``test_can_sonar_emulator.py``).

Time is lockstep, so a run repeats seed for seed: simulated time passes only when the loop's
``clock.sleep`` asks the Nomad 200 emulator to step. The CAN board has no such request (its
driver polls on its own), so with it the ring's clock is the drive's simulated time and, after
each step, the ring polls the board once and waits for every group (``CanSonarRing.refresh``):
the readings the next scan returns were taken after the step, never a poll in flight across it.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import threading
import time
from dataclasses import dataclass

from drivers.can_sonar.device import CanSonarRing
from drivers.can_sonar.link import BusSettings
from drivers.nomad200.clock import ControllerClock
from drivers.nomad200.device import Nomad200Backend
from hal.composed import ComposedBackend
from hal.errors import HalError
from hal.interfaces import DriveLimits
from hal.registry import create_backend
from hal.types import DriveStatus, Odometry, SonarScan, Twist
from sim_backend.backend import FIRE_INTERVAL_MAX_S, FIRE_INTERVAL_MIN_S, SimBackend
from sim_backend.emulators.can_sonar import CanSonarDevice, make_device
from sim_backend.emulators.can_sonar_faults import BoardFaults
from sim_backend.emulators.host import EmulatedDevice, EmulatorHost
from sim_backend.emulators.nomad200 import Nomad200Emulator
from sim_backend.emulators.nomad200_transport import PtyTransport
from sim_backend.simulator import SimParams, SimRobot
from sim_backend.world import World
from sim_backend.world_files import load_world
from tslam.programs.cli import UserError

BACKENDS = ("sim", "nomad200-emulated", "nomad200+can-sonar-emulated")
COMPOSED = "nomad200+can-sonar-emulated"
#: The board fires its whole ring within one update (groups 20 ms apart, data every 100 ms),
#: not one transducer every 60 ms as the Nomad's own electronics do. The emulator's board
#: reports the simulated ring, which fires as the Nomad's ``conf_sn`` says; in the composed
#: run the drive sets it to a transducer every 4 ms (a ring in 64 ms), so a reading the board
#: sends is never older than one update, as on the real board. (Its bytes are not read: the
#: scan comes from the board.) In process the explorer copes with a ring fired this fast
#: (``tests/test_fast_ring.py``), and the composed run maps fig12 as the in-process one does,
#: as often (``tests/test_e2e_nomad200.py``).
CAN_BOARD_SONAR_RATE = 1
#: Host seconds the ring may wait for the board after a step before the run fails.
REFRESH_TIMEOUT_S = 5.0
#: Host seconds to wait for the emulator thread after it was told to stop.
JOIN_TIMEOUT_S = 10.0


@dataclass(frozen=True)
class BackendChoice:
    """What ``--backend`` and its fault option asked for."""

    kind: str = "sim"
    #: The emulated CAN board stops answering CONNECT after this many simulated seconds.
    can_stop_heartbeat_after_s: float | None = None
    #: (sim) Seconds between two transducers' firings; None: the Nomad's 60 ms.
    fire_interval_s: float | None = None


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--backend", choices=BACKENDS, default="sim",
        help="sim: in process (default); the others run the drivers over ptys to emulators",
    )  # fmt: skip
    parser.add_argument(
        "--can-stop-heartbeat-after", type=float, default=None, metavar="S",
        help=f"({COMPOSED}) the board stops answering CONNECT after S simulated seconds",
    )  # fmt: skip
    add_fire_interval(parser)


def add_fire_interval(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--fire-interval", type=float, default=None, metavar="S",
        help="(sim) seconds between two transducers' firings, 0.004 to 1 (default 0.06, the "
        "Nomad's own electronics; 0.004 fires the ring as the CAN sonar board does)",
    )  # fmt: skip


def check_fire_interval(value: float | None) -> float | None:
    """``--fire-interval`` checked: a UserError naming it if out of range."""
    if value is not None and not (FIRE_INTERVAL_MIN_S <= value <= FIRE_INTERVAL_MAX_S):
        raise UserError(
            f"--fire-interval must be between {FIRE_INTERVAL_MIN_S} and {FIRE_INTERVAL_MAX_S} "
            f"seconds, got {value}"
        )
    return value


def choice_from_args(args: argparse.Namespace) -> BackendChoice:
    """The backend asked for, checked: one line for the user if it makes no sense."""
    stop = args.can_stop_heartbeat_after
    if stop is not None:
        if args.backend != COMPOSED:
            raise UserError(f"--can-stop-heartbeat-after needs --backend {COMPOSED}")
        if not (math.isfinite(stop) and stop >= 0):
            raise UserError(f"--can-stop-heartbeat-after must be seconds >= 0, got {stop}")
    fire = check_fire_interval(args.fire_interval)
    if fire is not None and args.backend != "sim":
        raise UserError("--fire-interval needs --backend sim (the drivers set their own rate)")
    return BackendChoice(args.backend, stop, fire)


def open_backend(
    choice: BackendChoice, world: str, seed: int, drift: str
) -> SimBackend | EmulatedRobot:
    """An unconfigured backend; both kinds have ``robot`` and ``world`` for scoring."""
    if choice.kind == "sim":
        config: dict[str, object] = {"backend": "sim", "world": world, "seed": seed, "drift": drift}
        if choice.fire_interval_s is not None:
            config["fire_interval_s"] = choice.fire_interval_s
        backend = create_backend(config)
        assert isinstance(backend, SimBackend)
        return backend
    if choice.kind not in BACKENDS:
        raise UserError(f"--backend must be one of {', '.join(BACKENDS)}, got {choice.kind!r}")
    if seed < 0:
        raise UserError(f"--seed must be at least 0, got {seed}")
    loaded = load_world(world)
    # The robot SimBackend would build for the same world, seed and drift.
    robot = SimRobot(loaded, SimParams(drift=drift), seed)
    return EmulatedRobot(
        loaded, robot, with_can_sonar=choice.kind == COMPOSED,
        can_faults=BoardFaults(heartbeat_stops_after_s=choice.can_stop_heartbeat_after_s),
        seed=seed,
    )  # fmt: skip


class EmulatedRobot:
    """Emulators on a thread over one simulated robot, and the drivers that reach them.

    It offers what ``tslam sim`` uses of a ``SimBackend``: the hal calls, ``clock``,
    ``limits``, a context manager that configures, activates and finally closes, and
    ``robot`` and ``world`` for scoring, which the drivers never see.
    """

    def __init__(
        self,
        world: World,
        robot: SimRobot,
        *,
        with_can_sonar: bool = False,
        can_faults: BoardFaults | None = None,
        seed: int = 0,
    ) -> None:
        self.world = world
        self.robot = robot
        transport = PtyTransport()
        self.nomad_emulator = Nomad200Emulator(robot, transport, lockstep=True)
        devices: list[EmulatedDevice] = [self.nomad_emulator]
        self.can_device: CanSonarDevice | None = None
        options: dict[str, object] = {"port": transport.describe()["port"], "lockstep": True}
        if with_can_sonar:
            options["sonar_rate"] = CAN_BOARD_SONAR_RATE
        else:
            options["sonar_pos"] = True  # each reading stamped and posed at its firing
        self.drive = Nomad200Backend.from_config(options)
        self.ring: CanSonarRing | None = None
        self._ring_time: RingTime | None = None
        self.backend: Nomad200Backend | ComposedBackend = self.drive
        self._clock: ControllerClock | SteppedClock = self.drive.clock
        try:
            if with_can_sonar:
                self.can_device = make_device(robot, faults=can_faults, seed=seed)
                devices.append(self.can_device)
                self._ring_time = RingTime(self.drive.clock)
                opts = self.can_device.backend_options()
                self.ring = CanSonarRing(
                    BusSettings(opts["interface"], opts["channel"], opts["bitrate"], 0.0),
                    base_id=self.can_device.board.codec.base_id,
                    poll_s=math.inf,
                    clock=self._ring_time,
                )
                self.backend = ComposedBackend(self.drive, self.ring, sonar_mount="turret")
                self._clock = SteppedClock(self.drive, self.ring)
        except BaseException:
            for dev in devices:
                dev.close()
            raise
        self.host = EmulatorHost(robot, devices, lockstep=True, tick_s=0.005)
        self._thread: threading.Thread | None = None

    # ------------------------------------------------------------------ lifecycle
    def __enter__(self) -> EmulatedRobot:
        self._thread = threading.Thread(target=self.host.run, name="emulators", daemon=True)
        self._thread.start()
        try:
            self.backend.configure()
            if self._ring_time is not None:
                self._ring_time.follow_drive()
            self.backend.activate()
            if self.ring is not None:
                self.ring.refresh(REFRESH_TIMEOUT_S)  # the first scan, like every later one
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Stop the robot and release the drivers, then the emulators."""
        try:
            self.backend.close()
        finally:
            self.host.stop()
            if self._thread is None:
                for dev in self.host.devices:
                    dev.close()
            else:
                self._thread.join(JOIN_TIMEOUT_S)

    # ------------------------------------------------------------------ the hal, forwarded
    @property
    def clock(self) -> ControllerClock | SteppedClock:
        return self._clock

    @property
    def limits(self) -> DriveLimits:
        return self.backend.limits

    def command(self, twist: Twist) -> None:
        self.backend.command(twist)

    def stop(self) -> None:
        self.backend.stop()

    def status(self) -> DriveStatus:
        return self.backend.status()

    def odometry(self) -> Odometry:
        return self.backend.odometry()

    def scan(self) -> SonarScan:
        return self.backend.scan()


class RingTime:
    """The CAN ring's clock in a lockstep run.

    Once the run is under way it is the drive's simulated time, so heartbeat and stamps follow
    the simulation. While the ring is configured no simulated time passes, and its timeouts (a
    board that never answers) would never expire; until ``follow_drive`` it therefore counts
    host seconds, from an origin an hour before the drive's time, so that nothing stamped then
    can pass for a reading of the run (it is older than any ``max_age_s``).
    """

    BEFORE_S = 3600.0

    def __init__(self, drive: ControllerClock) -> None:
        self.drive = drive
        self._host_origin = time.monotonic()
        self._origin = drive.now() - self.BEFORE_S
        self._following = False

    def follow_drive(self) -> None:
        self._following = True

    def now(self) -> float:
        if self._following:
            return self.drive.now()
        return min(self._origin + time.monotonic() - self._host_origin, self.drive.now())

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            time.sleep(seconds)


class SteppedClock:
    """The composed run's clock: the drive's simulated time; ``sleep`` steps the emulator and
    then has the ring read the board afresh."""

    def __init__(self, drive: Nomad200Backend, ring: CanSonarRing) -> None:
        self.drive = drive
        self.ring = ring

    def now(self) -> float:
        return self.drive.clock.now()

    def sleep(self, seconds: float) -> None:
        if not seconds > 0:
            return
        self.drive.clock.sleep(seconds)
        try:
            self.ring.refresh(REFRESH_TIMEOUT_S)
        except HalError:
            with contextlib.suppress(HalError):
                self.drive.stop()  # a blind robot must not keep moving
            raise
