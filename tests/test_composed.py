"""``composed``: drive and encoders from one backend, the sonar ring from another. The contract
with the simulated drive and the emulated CAN board (on a robot of its own), the lifecycle
forwarded to both, the clocks, the turret mount and a lost board stopping the robot."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from hal.composed import ComposedBackend, ComposedClock
from hal.contract import BackendContract
from hal.errors import ConfigurationError, DeviceFaultError, HalError
from hal.interfaces import NOMAD200_LIMITS, Drive, Encoders, SonarRing
from hal.lifecycle import State
from hal.registry import create_backend
from hal.types import DriveStatus, Odometry, SonarScan, Twist
from sim_backend.backend import SimBackend
from tests.test_can_sonar_device import PATIENCE_S, VirtualBoard

SIM_DRIVE = "sim://fig12?seed=5&drift=none"


class TestComposedSimDriveCanSonar(BackendContract):
    """Sim drive in process, CAN sonar through the emulator on a virtual channel."""

    free_ahead_m = 0.6

    @pytest.fixture(autouse=True, scope="class")
    @classmethod
    def board(cls):
        with VirtualBoard() as board:
            cls.sonar_options = board.options()
            yield board

    def make_backend(self):
        return create_backend(
            {"backend": "composed", "drive": SIM_DRIVE, "sonar": self.sonar_options}
        )


# ---------------------------------------------------------------------- fakes


class ManualClock:
    def __init__(self, t: float = 0.0) -> None:
        self.t = t

    def now(self) -> float:
        return self.t

    def sleep(self, seconds: float) -> None:
        self.t += max(seconds, 0.0)


class FakeDrive(Drive, Encoders):
    backend_name = "fake-drive"

    def __init__(self, events, clock=None, turret_rad=0.0, fail_close=False) -> None:
        super().__init__()
        self.events = events
        self._clock = clock or ManualClock()
        self.turret_rad = turret_rad
        self.fail_close = fail_close
        self.v = 0.0

    @property
    def clock(self):
        return self._clock

    @property
    def limits(self):
        return NOMAD200_LIMITS

    def _on_configure(self):
        self.events.append("drive configure")

    def _on_activate(self):
        self.events.append("drive activate")

    def _on_deactivate(self):
        self.events.append("drive deactivate")

    def _on_close(self):
        self.events.append("drive close")
        if self.fail_close:
            raise HalError("drive close failed")

    def _command(self, twist: Twist):
        self.v = twist.v_mps

    def _stop(self):
        self.v = 0.0
        self.events.append("drive stop")

    def _status(self):
        return DriveStatus(False, False, True, self._clock.now())

    def _odometry(self):
        return Odometry(0.0, 0.0, 0.3, 0.3 + self.turret_rad, self._clock.now())


class FakeSonar(SonarRing):
    backend_name = "fake-sonar"

    def __init__(self, events, clock=None, fail_configure=False) -> None:
        super().__init__()
        self.events = events
        self._clock = clock or ManualClock()
        self.fail_configure = fail_configure
        self.fail_scan = False

    @property
    def clock(self):
        return self._clock

    @property
    def n_transducers(self):
        return 1

    def _on_configure(self):
        self.events.append("sonar configure")
        if self.fail_configure:
            raise HalError("sonar configure failed")

    def _on_activate(self):
        self.events.append("sonar activate")

    def _on_deactivate(self):
        self.events.append("sonar deactivate")

    def _on_close(self):
        self.events.append("sonar close")

    def _scan(self):
        if self.fail_scan:
            raise DeviceFaultError("fake board lost")
        t = self._clock.now()
        return SonarScan(
            np.array([1.0]), np.array([0.23]), np.array([0.0]), np.array([0.0]),
            np.array([t - 0.5]), 0.15, 6.5, 0.2,
        )  # fmt: skip


# ---------------------------------------------------------------------- lifecycle


def test_lifecycle_is_forwarded_in_a_safe_order():
    events: list[str] = []
    c = ComposedBackend(FakeDrive(events), FakeSonar(events))
    with c:
        assert events == ["drive configure", "sonar configure", "sonar activate", "drive activate"]
        events.clear()
    assert events[0] == "drive stop", "the robot stops before anything is released"
    assert events.index("drive deactivate") < events.index("sonar deactivate")
    assert events.index("drive close") < events.index("sonar close")
    assert c.state is State.CLOSED


def test_close_releases_both_even_if_the_drive_fails():
    events: list[str] = []
    drive, sonar = FakeDrive(events, fail_close=True), FakeSonar(events)
    c = ComposedBackend(drive, sonar)
    c.configure()
    with pytest.raises(HalError, match="drive close failed"):
        c.close()
    assert "sonar close" in events
    assert sonar.state is State.CLOSED and c.state is State.CLOSED


def test_a_failed_sonar_configure_closes_the_drive():
    events: list[str] = []
    drive = FakeDrive(events)
    c = ComposedBackend(drive, FakeSonar(events, fail_configure=True))
    with pytest.raises(HalError, match="sonar configure failed"):
        c.configure()
    assert c.state is State.UNCONFIGURED and drive.state is State.CLOSED


def test_closing_an_unconfigured_composition_closes_its_parts():
    events: list[str] = []
    drive, sonar = FakeDrive(events), FakeSonar(events)
    ComposedBackend(drive, sonar).close()
    assert drive.state is State.CLOSED and sonar.state is State.CLOSED


def test_a_sonar_failure_stops_the_drive():
    events: list[str] = []
    drive, sonar = FakeDrive(events), FakeSonar(events)
    with ComposedBackend(drive, sonar) as c:
        c.command(Twist(0.2))
        assert drive.v == 0.2
        sonar.fail_scan = True
        with pytest.raises(DeviceFaultError):
            c.scan()
        assert drive.v == 0.0


# ---------------------------------------------------------------------- time and geometry


def test_clock_is_the_drives_and_sleep_lets_time_pass_on_both():
    events: list[str] = []
    dclock, sclock = ManualClock(10.0), ManualClock(5000.0)
    c = ComposedBackend(FakeDrive(events, dclock), FakeSonar(events, sclock))
    assert isinstance(c.clock, ComposedClock) and c.clock.now() == 10.0
    c.clock.sleep(2.0)
    assert dclock.t == 12.0 and sclock.t == 5002.0
    with c:
        s = c.scan()
    assert s.stamps_s[0] == pytest.approx(12.0 - 0.5), "sonar stamps on the drive's clock"


def test_one_shared_clock_is_used_as_it_is():
    events: list[str] = []
    clock = ManualClock()
    c = ComposedBackend(FakeDrive(events, clock), FakeSonar(events, clock))
    assert c.clock is clock


@pytest.mark.parametrize(("mount", "expected_yaw"), [("turret", math.pi / 2), ("body", 0.0)])
def test_sonar_mount(mount, expected_yaw):
    events: list[str] = []
    drive = FakeDrive(events, turret_rad=math.pi / 2)
    with ComposedBackend(drive, FakeSonar(events), sonar_mount=mount) as c:
        s = c.scan()
    assert s.yaw_rad[0] == pytest.approx(expected_yaw)
    assert s.x_m[0] == pytest.approx(0.23 * math.cos(expected_yaw), abs=1e-12)
    assert s.y_m[0] == pytest.approx(0.23 * math.sin(expected_yaw), abs=1e-12)


# ---------------------------------------------------------------------- configuration


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"drive": SIM_DRIVE}, "'sonar'"),
        ({"sonar": SIM_DRIVE}, "'drive'"),
        ({"drive": SIM_DRIVE, "sonar": SIM_DRIVE, "sonar_mount": "roof"}, "sonar_mount"),
        ({"drive": "can-sonar", "sonar": SIM_DRIVE}, "must provide Drive"),
        ({"drive": SIM_DRIVE, "sonar": SIM_DRIVE, "extra": 1}, "unknown option"),
    ],
)
def test_configuration_mistakes(options, message):
    with pytest.raises(ConfigurationError, match=message):
        create_backend({"backend": "composed", **options})


def test_two_simulations_both_advance_on_sleep():
    c = create_backend({"backend": "composed", "drive": SIM_DRIVE, "sonar": SIM_DRIVE})
    assert isinstance(c, ComposedBackend) and isinstance(c.sonar, SimBackend)
    with c:
        before = c.sonar.clock.now()
        c.clock.sleep(1.5)
        assert c.clock.now() == pytest.approx(1.5)
        assert c.sonar.clock.now() == pytest.approx(before + 1.5)
        assert np.all(c.scan().stamps_s <= c.clock.now() + 1e-9)


# ---------------------------------------------------------------------- a lost board


def test_lost_can_board_stops_the_robot_with_a_named_error():
    with VirtualBoard() as board:
        c = create_backend({"backend": "composed", "drive": SIM_DRIVE, "sonar": board.options()})
        assert isinstance(c, ComposedBackend)
        with c:
            c.command(Twist(0.15))
            c.clock.sleep(0.5)
            board.device.heartbeat_stopped = True
            error = None
            deadline = time.monotonic() + PATIENCE_S
            while error is None and time.monotonic() < deadline:
                try:
                    c.scan()
                except DeviceFaultError as exc:
                    error = exc
                c.clock.sleep(0.05)
            assert error is not None, "the lost board was never reported"
            assert "0x400" in str(error) and board.channel in str(error)
            c.clock.sleep(3.0)  # let the drive decelerate
            a = c.odometry()
            c.clock.sleep(1.0)
            b = c.odometry()
            assert math.hypot(b.x_m - a.x_m, b.y_m - a.y_m) < 1e-3, "the robot kept moving"
        assert c.state is State.CLOSED
