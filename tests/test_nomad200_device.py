"""The Nomad 200 driver: the hal contract against the emulator (same process over a pty, and
across processes), its options, its faults, reconnection and the robot's motion watchdog."""

from __future__ import annotations

import contextlib
import math
import termios
import time

import pytest
import serial

from drivers.nomad200.codec import Gs
from drivers.nomad200.device import Nomad200Backend
from drivers.nomad200.link import Link
from drivers.nomad200.settings import DEFAULT_ORDER, Settings
from hal.contract import BackendContract
from hal.errors import (
    ConfigurationError,
    DeviceTimeoutError,
    LinkLostError,
    ProtocolError,
)
from hal.lifecycle import State
from hal.registry import create_backend
from hal.types import Twist
from sim_backend.emulators.nomad200_faults import FaultConfig
from tests.nomad200_rig import Rig
from tslam.programs.emulated import emulated_nomad200

# --------------------------------------------------------------------------- the contract


class _RigContract(BackendContract):
    free_ahead_m = 5.0
    options: dict = {}  # noqa: RUF012 - read only
    rig_options: dict = {}  # noqa: RUF012 - read only

    @pytest.fixture(autouse=True)
    def _rigs(self):
        self.rigs: list[Rig] = []
        yield
        for rig in self.rigs:
            rig.stop()

    def make_backend(self):
        rig = Rig(**self.rig_options)
        self.rigs.append(rig)
        return rig.backend(**self.options)


class TestContractLockstep(_RigContract):
    """Driver, pyserial, a pty, the emulator on a thread; time passes by lockstep steps."""


class TestContractWithoutSonarPos(_RigContract):
    """As a robot at 9600 baud would be driven: no "pos" attachments, stamps at the reply."""

    options = {"sonar_pos": False}  # noqa: RUF012


class TestContractOverTcp(_RigContract):
    """The robot's other host link: a socket (``socket://``)."""

    rig_options = {"tcp": True}  # noqa: RUF012


class TestContractAcrossProcesses(BackendContract):
    """``tslam emulate nomad200 --pty --lockstep`` in its own process, as the lead's
    ``tslam sim --backend nomad200-emulated`` will run it."""

    free_ahead_m = 0.6

    @pytest.fixture(autouse=True)
    def _processes(self):
        self.stack = contextlib.ExitStack()
        with self.stack:
            yield

    def make_backend(self):
        return self.stack.enter_context(emulated_nomad200("fig12", 5, "none"))


# --------------------------------------------------------------------------- options


def test_url_names_the_port_and_options():
    b = create_backend("nomad200:///dev/ttyUSB0?baud=19200&motion_timeout_s=3")
    assert isinstance(b, Nomad200Backend)
    assert b.settings.port == "/dev/ttyUSB0"
    assert b.settings.baud == 19200 and b.settings.motion_timeout_s == 3
    assert b.settings.sonar_order == DEFAULT_ORDER
    assert b.state is State.UNCONFIGURED  # nothing opened by the constructor
    assert not b.link.is_open
    assert create_backend("nomad200://loop://").settings.port == "loop://"
    assert create_backend("nomad200://socket://127.0.0.1:65001").settings.port == (
        "socket://127.0.0.1:65001"
    )


def test_list_options_from_a_config_file():
    s = Settings.from_options({"port": "loop://", "sonar_order": [0, 1, 2], "sonar_rate": 20})
    assert s.sonar_order == (0, 1, 2) and s.sonar_rate == 20


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({}, "'port' is required"),
        ({"port": "loop://", "baud": 9601}, "'baud' must be one of"),
        ({"port": "loop://", "sonar_order": "0,1,1"}, "distinct"),
        ({"port": "loop://", "sonar_order": "0,x"}, "transducer numbers"),
        ({"port": "loop://", "motion_timeout_s": 300}, "at most 255"),
        ({"port": "loop://", "bogus": 1}, "unknown option"),
        ({"port": "loop://", "min_range_in": 200, "max_range_in": 100}, "must be below"),
    ],
)
def test_bad_options_are_configuration_errors(options, message):
    with pytest.raises(ConfigurationError, match=message):
        Nomad200Backend.from_config(options)


def test_a_port_that_cannot_open_is_named(tmp_path):
    b = Nomad200Backend.from_config({"port": str(tmp_path / "no-such-tty")})
    with pytest.raises(LinkLostError, match="cannot open the port"):
        b.configure()
    assert b.state is State.UNCONFIGURED


def test_loop_url_is_recognised_as_an_echo_not_a_robot():
    b = Nomad200Backend.from_config({"port": "loop://", "reply_timeout_s": 0.2, "retries": 0})
    with pytest.raises(ProtocolError, match="echo"):
        b.configure()
    assert b.state is State.UNCONFIGURED


def test_configure_sends_the_settings_and_nothing_moves():
    with Rig() as rig:
        b = rig.backend(motion_timeout_s=4, sonar_rate=20, sonar_order="0,4,8,12")
        b.configure()
        try:
            served = rig.emu.served
            assert [served[k] for k in ("ct", "conf_sn", "conf_tm", "sp", "ac", "st")] == [1] * 6
            assert rig.emu.mask == b.mask
            assert rig.emu.control.motion_timeout_s == 4
            assert rig.robot.p.firing_order == (0, 4, 8, 12)
            assert rig.robot.p.fire_interval_s == pytest.approx(0.080)
            assert rig.robot.cmd_v == 0.0
        finally:
            b.close()
        assert served["st"] >= 2  # close stopped the robot before closing the port
        assert b.state is State.CLOSED and not b.link.is_open


def test_one_control_cycle_costs_two_round_trips_in_lockstep_one_step():
    with Rig() as rig, rig.backend() as b:
        before = rig.emu.requests
        b.scan(), b.odometry(), b.status()
        b.command(Twist(0.1, 0.0, 0.0))
        b.clock.sleep(0.1)
        assert rig.emu.requests - before == 2  # vm, then the step that carries the new state


def test_real_time_reads_share_one_poll():
    with Rig(lockstep=False, time_scale=2.0) as rig:
        with rig.backend(max_state_age_s=5.0) as b:
            gs = rig.emu.served["gs"]
            b.scan(), b.odometry(), b.status()
            assert rig.emu.served["gs"] - gs <= 1
        with rig.backend(max_state_age_s=0.0) as b:
            gs = rig.emu.served["gs"]
            b.scan(), b.odometry(), b.status()
            assert rig.emu.served["gs"] - gs == 3


def test_real_time_clock_follows_the_controller():
    with Rig(lockstep=False, time_scale=4.0) as rig, rig.backend() as b:
        t0 = b.clock.now()
        b.command(Twist(0.2, 0.0, 0.0))
        b.clock.sleep(1.0)  # a quarter of a second of host time at time_scale 4
        odo = b.odometry()
        scan = b.scan()
        assert odo.stamp_s > t0 and b.clock.now() >= odo.stamp_s
        assert (scan.stamps_s <= b.clock.now() + 1e-9).all()
        assert odo.x_m > 0.0


def test_quantities_arrive_in_si_units():
    with Rig(drift="none") as rig, rig.backend() as b:
        b.command(Twist(0.3, math.radians(20.0), math.radians(-10.0)))
        b.clock.sleep(1.5)  # within the default 2 s motion timeout
        odo = b.odometry()
        truth = rig.robot.true_pose()
        start = rig.robot.world.start
        assert math.hypot(odo.x_m, odo.y_m) == pytest.approx(
            math.hypot(truth.x - start.x, truth.y - start.y), abs=0.005
        )
        assert odo.heading_rad == pytest.approx(truth.theta - start.theta, abs=math.radians(0.1))
        assert odo.turret_rad == pytest.approx(truth.turret - start.theta, abs=math.radians(0.1))
        assert rig.robot.cmd_v == pytest.approx(0.3, abs=0.00254)
        scan = b.scan()
        ring = rig.robot.ring
        echo = ~(scan.ranges_m != scan.ranges_m)
        assert echo.any()
        assert abs(scan.ranges_m[echo] - ring.ranges[echo]).max() <= 0.0254 / 2 + 1e-9
        assert abs(scan.stamps_s - ring.stamps).max() < 1e-9


def test_headings_unwrap_through_full_turns():
    with Rig() as rig, rig.backend() as b:
        b.command(Twist(0.0, math.radians(45.0), 0.0))
        for _ in range(120):  # 12 s at 45 deg/s: about one and a half turns
            b.clock.sleep(0.1)
            b.command(Twist(0.0, math.radians(45.0), 0.0))
        truth = rig.robot.true_pose().theta - rig.robot.world.start.theta
        assert truth > 2 * math.pi
        assert b.odometry().heading_rad == pytest.approx(truth, abs=math.radians(0.1))


def test_sweeping_the_turret_moves_the_sonar_poses_per_firing():
    with Rig() as rig, rig.backend() as b:
        b.command(Twist(0.0, 0.0, math.radians(45.0)))
        b.clock.sleep(2.0)
        scan = b.scan()
        expected = rig.robot.ring.yaw_robot
        diff = (scan.yaw_rad - expected + math.pi) % (2 * math.pi) - math.pi
        assert abs(diff).max() < math.radians(0.2)
        assert len(set(scan.stamps_s.round(3))) == 16  # each reading stamped at its own firing


# --------------------------------------------------------------------------- the watchdog


def test_motion_timeout_stops_the_robot_in_simulated_time():
    with Rig() as rig, rig.backend(motion_timeout_s=1) as b:
        b.command(Twist(0.3, 0.0, 0.0))
        start = b.odometry().x_m
        b.clock.sleep(4.0)  # no motion command for 4 s: the robot stops after 1
        assert rig.robot.cmd_v == 0.0 and rig.robot.v == 0.0
        assert b.odometry().x_m - start < 0.3 * 1.0 + 0.1
        assert b.status().motors_on  # stopped, holding position: not limp


def test_without_motion_timeout_the_robot_drives_on():
    with Rig() as rig, rig.backend(motion_timeout_s=0) as b:
        b.command(Twist(0.3, 0.0, 0.0))
        b.clock.sleep(4.0)
        assert rig.robot.v == pytest.approx(0.3, abs=0.003)


def test_motion_timeout_in_real_time():
    with Rig(lockstep=False, time_scale=4.0) as rig, rig.backend(motion_timeout_s=1) as b:
        b.command(Twist(0.3, 0.0, 0.0))
        deadline = time.monotonic() + 30.0
        while rig.robot.cmd_v != 0.0 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert rig.robot.cmd_v == 0.0
        assert rig.emu.served["st"] == 1  # the robot stopped itself, not the driver


# --------------------------------------------------------------------------- faults


@pytest.mark.parametrize(
    ("fault", "kind", "error"),
    [
        ("drop", "reply timeout", DeviceTimeoutError),
        ("corrupt", "checksum error", ProtocolError),
        ("truncate", "truncated reply", ProtocolError),
    ],
)
def test_a_faulty_line_names_the_fault_and_leaves_the_robot_stopped(fault, kind, error):
    with Rig() as rig:
        b = rig.backend(reply_timeout_s=0.3, retries=2)
        with b:
            b.command(Twist(0.3, 0.0, 0.0))
            b.clock.sleep(1.0)
            assert rig.robot.v > 0.2
            rig.inject(**{fault: 1.0}, seed=1)
            with pytest.raises(error, match=kind) as caught:
                b.command(Twist(0.3, 0.0, 0.1))
            assert "after 3 attempt(s)" in str(caught.value)
            assert b.link.who in str(caught.value)
            # Only the replies were lost: the driver's stop reached the robot.
            assert rig.robot.cmd_v == 0.0
            # Nothing read before the fault is handed out as fresh: the poll fails again.
            with pytest.raises(error, match=kind):
                b.scan()
            rig.inject()
            b.clock.sleep(2.0)  # the line is good again: the driver recovers
            assert rig.robot.v == 0.0
            assert b.status().stamp_s == pytest.approx(b.clock.now())


def test_garbage_before_replies_is_skipped():
    with Rig() as rig, rig.backend(reply_timeout_s=0.5) as b:
        rig.inject(garbage=1.0, seed=2)
        for _ in range(20):
            b.command(Twist(0.2, 0.0, 0.0))
            b.clock.sleep(0.1)
        assert rig.emu.faults.injected["garbage"] >= 40
        assert b.odometry().x_m > 0.2


def test_occasional_faults_are_retried_away():
    with Rig() as rig, rig.backend(reply_timeout_s=0.2, retries=4) as b:
        rig.inject(drop=0.1, corrupt=0.1, truncate=0.1, seed=4)
        for _ in range(30):
            b.command(Twist(0.2, 0.0, 0.0))
            b.clock.sleep(0.1)
        assert b.link.retransmissions > 0
        assert b.odometry().stamp_s == pytest.approx(3.0)


def test_late_replies_within_the_retries_are_used():
    with Rig() as rig, rig.backend(reply_timeout_s=0.3, retries=3) as b:
        rig.inject(delay=1.0, delay_s=0.4, seed=5)
        b.command(Twist(0.2, 0.0, 0.0))
        assert rig.robot.cmd_v == pytest.approx(0.2, abs=0.003)
        assert b.link.retransmissions >= 1


# --------------------------------------------------------------------------- a vanishing link


@pytest.mark.parametrize("tcp", [False, True], ids=["pty", "tcp"])
def test_the_link_comes_back_and_the_robot_is_stopped_first(tmp_path, tcp):
    faults = FaultConfig(disappear_after_requests=12, reappear_after_s=0.3)
    link = None if tcp else tmp_path / "nomad200"
    with Rig(faults=faults, link=link, tcp=tcp) as rig:
        b = rig.backend(reconnect_backoff_s=0.05, reconnect_timeout_s=30.0)
        with b:
            for _ in range(8):  # configure took 6 requests; the line goes after 3 cycles
                b.command(Twist(0.2, 0.0, 0.0))
                b.clock.sleep(0.1)
            assert rig.emu.vanished == 1 and rig.emu.reappeared == 1
            assert b.link.reconnects == 1
            # Reconfigured (mask and all) and stopped when it came back, then driving again.
            assert rig.emu.served["ct"] == 2 and rig.emu.served["st"] == 2
            assert rig.robot.cmd_v == pytest.approx(0.2, abs=0.003)
            assert b.clock.now() == pytest.approx(0.8)


def test_a_link_that_stays_away_is_link_lost():
    faults = FaultConfig(disappear_after_requests=8)
    with Rig(faults=faults) as rig:
        b = rig.backend(reconnect_backoff_s=0.05, reconnect_timeout_s=0.4)
        with b:
            b.command(Twist(0.2, 0.0, 0.0))
            b.clock.sleep(0.1)
            with pytest.raises(LinkLostError, match=r"vanished .* still gone after 0\.4 s"):
                b.command(Twist(0.2, 0.0, 0.0))
        assert b.state is State.CLOSED and b.close_error is not None


class _VanishingPort:
    """A port that fails the way pyserial, termios or the OS do when hardware goes away."""

    def __init__(self, error: BaseException) -> None:
        self.error = error
        self.in_waiting = 0

    def reset_input_buffer(self) -> None:
        raise self.error

    def write(self, data: bytes) -> int:
        raise self.error

    def read(self, size: int = 1) -> bytes:
        raise self.error

    def close(self) -> None:
        pass


@pytest.mark.parametrize(
    "error",
    [
        serial.SerialException("device reports readiness to read but returned no data"),
        termios.error(5, "Input/output error"),
        OSError(5, "Input/output error"),
    ],
    ids=["SerialException", "termios.error", "OSError"],
)
def test_every_way_a_port_vanishes_is_link_lost(error):
    link = Link(
        "/dev/ttyFAKE", 9600, reconnect_timeout_s=0.0, opener=lambda *a, **k: _VanishingPort(error)
    )
    link.open()
    from drivers.nomad200.codec import StateMask

    with pytest.raises(LinkLostError, match="vanished during 0x07 \\(GS\\)"):
        link.request(Gs(), StateMask())


def test_position_moves_through_send_and_pr_is_never_sent_twice():
    from drivers.nomad200.codec import Pr, Ws

    with Rig() as rig, rig.backend(reply_timeout_s=0.3, motion_timeout_s=0) as b:
        b.send(Pr(1000, 0, 0))  # 100 inches ahead
        b.send(Ws(True, False, False, 30))
        assert b.odometry().x_m == pytest.approx(2.54, abs=0.01)
        rig.inject(drop=1.0)
        with pytest.raises(DeviceTimeoutError, match=r"after 1 attempt\(s\)"):
            b.send(Pr(100, 0, 0))
        assert rig.emu.served["pr"] == 2  # a lost reply never makes the robot move twice
