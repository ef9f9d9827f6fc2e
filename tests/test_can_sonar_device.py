"""The CAN sonar driver (``can-sonar``) against the emulated board: the hal contract in process
(python-can virtual) and across processes (slcan on a pseudo-terminal), the heartbeat, reading
rules, channel mapping, the parameter set and bad frames.

Policy under test for bad frames: corrupt frames are skipped and counted (``stats``), never used;
readings they would have refreshed age, and past ``max_age_s`` are reported as no reading.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import selectors
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drivers.can_sonar.codec import GroupData, Reading, ReadingStatus, Resolution
from drivers.can_sonar.device import CanSonarRing
from drivers.can_sonar.heartbeat import Heartbeat
from drivers.can_sonar.layout import RingLayout, layout_from_values
from drivers.can_sonar.link import BusSettings
from drivers.can_sonar.readings import ReadingTable
from hal.contract import BackendContract
from hal.errors import (
    ConfigurationError,
    DeviceFaultError,
    DeviceTimeoutError,
    HalError,
    LinkLostError,
    ProtocolError,
)
from hal.lifecycle import State
from hal.registry import create_backend
from sim_backend.emulators.can_sonar import CanSonarDevice, make_device
from sim_backend.emulators.can_sonar_faults import BoardFaults
from sim_backend.emulators.host import EmulatorHost
from sim_backend.simulator import SimRobot
from tests.conftest import box_world

TSLAM = Path(sys.executable).with_name("tslam")
#: Generous bound for anything that should take a fraction of a second.
PATIENCE_S = 20.0
#: Driver settings that keep the tests short without changing what is tested.
FAST = {"heartbeat_s": 0.2, "reply_timeout_s": 1.0, "poll_s": 0.05}

_channels = itertools.count()


class VirtualBoard:
    """An emulated board on a fresh python-can virtual channel, served by a host thread."""

    def __init__(
        self,
        *,
        robot: SimRobot | None = None,
        ranges: Callable[[], np.ndarray] | None = None,
        faults: BoardFaults | None = None,
        seed: int = 1,
        resolution: Resolution = Resolution.CM_0_5,
    ) -> None:
        self.channel = f"test-can-sonar-{os.getpid()}-{next(_channels)}"
        self.robot = robot or SimRobot(box_world(), seed=seed)
        self.device: CanSonarDevice = make_device(
            self.robot,
            virtual_channel=self.channel,
            ranges=ranges,
            faults=faults,
            seed=seed,
            resolution=resolution,
        )
        self.host = EmulatorHost(self.robot, [self.device], tick_s=0.005)
        self._thread = threading.Thread(target=self.host.run, daemon=True)

    def __enter__(self) -> VirtualBoard:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.host.stop()
        self._thread.join(timeout=PATIENCE_S)

    def options(self, **extra: Any) -> dict[str, Any]:
        return {**self.device.backend_options(), **FAST, **extra}

    def backend(self, **extra: Any) -> CanSonarRing:
        b = create_backend(self.options(**extra))
        assert isinstance(b, CanSonarRing)
        return b


def wait_for(condition: Callable[[], bool], what: str, timeout_s: float = PATIENCE_S) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            pytest.fail(f"timed out waiting for {what}")
        time.sleep(0.02)


def scan_error(backend: CanSonarRing) -> HalError | None:
    try:
        backend.scan()
    except HalError as exc:
        return exc
    return None


@contextmanager
def emulator_process(*args: str) -> Iterator[tuple[subprocess.Popen[str], dict[str, Any]]]:
    """``tslam emulate can-sonar ARGS`` in its own process; always killed on the way out."""
    proc = subprocess.Popen(
        [str(TSLAM), "emulate", "can-sonar", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        sel = selectors.DefaultSelector()
        sel.register(proc.stdout, selectors.EVENT_READ)  # type: ignore[arg-type]
        if not sel.select(timeout=60.0):
            pytest.fail("the emulator printed nothing within 60 s")
        line = proc.stdout.readline()  # type: ignore[union-attr]
        if not line:
            pytest.fail(f"the emulator ended: {proc.stderr.read()}")  # type: ignore[union-attr]
        yield proc, json.loads(line)
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=10.0)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=10.0)
        for stream in (proc.stdout, proc.stderr):
            if stream is not None:
                stream.close()


# ---------------------------------------------------------------------- the hal contract


class TestCanSonarContractVirtual(BackendContract):
    """The driver and the emulator in one process, over a python-can virtual channel."""

    @pytest.fixture(autouse=True, scope="class")
    @classmethod
    def board(cls):
        with VirtualBoard() as board:
            cls.board_options = board.options()
            yield board

    def make_backend(self):
        return create_backend(self.board_options)


class TestCanSonarContractSlcan(BackendContract):
    """The driver in this process, ``tslam emulate can-sonar --slcan-pty`` in another."""

    @pytest.fixture(autouse=True, scope="class")
    @classmethod
    def emulator(cls):
        with emulator_process("--world", "fig12", "--seed", "3", "--slcan-pty") as (proc, info):
            assert info["pty"] == info["backend"]["channel"]
            cls.board_options = {**info["backend"], **FAST}
            yield proc

    def make_backend(self):
        return create_backend(self.board_options)


# ---------------------------------------------------------------------- configuration


def test_constructor_touches_no_bus():
    opened = []
    ring = CanSonarRing(BusSettings("virtual", "nowhere", 1_000_000), bus_factory=opened.append)
    assert opened == [] and ring.state is State.UNCONFIGURED
    assert ring.n_transducers == 16 and isinstance(ring.clock.now(), float)


def test_from_url_and_options():
    ring = create_backend("can-sonar://slcan:/dev/ttyACM0?bitrate=500000&base_id=0x500")
    assert isinstance(ring, CanSonarRing)
    assert ring.bus_settings == BusSettings("slcan", "/dev/ttyACM0", 500_000, None)
    assert ring.codec.base_id == 0x500
    ring = create_backend(
        {"backend": "can-sonar", "interface": "virtual", "channel": "x", "base_id": 0x410,
         "channels": [3, 2, 1, 0], "angles_deg": "0, 90, 180, 270", "radius_m": 0.3}
    )  # fmt: skip
    assert ring.n_transducers == 4 and ring.layout.channels == (3, 2, 1, 0)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"interface": "nosuchcan"}, "unknown CAN interface"),
        ({"bitrate": 123}, "bitrate"),
        ({"base_id": "0x7FF"}, "base_id"),
        ({"base_id": "four"}, "base_id"),
        ({"target": "slcan"}, "INTERFACE:CHANNEL"),
        ({"channels": "0,0,1"}, "repeats"),
        ({"channels": "0,1,16"}, "0-15"),
        ({"channels": "0,1,2", "angles_deg": "0,240,120"}, "counter-clockwise"),
        ({"channels": "0,1", "angles_deg": "0"}, "angles"),
        ({"write_params": "flash"}, "write_params"),
        ({"write_params": "ram", "update_interval_s": 0.07}, "update interval"),
        ({"poll_s": 0.5, "max_age_s": 0.1}, "max_age_s"),
        ({"colour": "blue"}, "unknown option"),
    ],
)
def test_configuration_mistakes_are_one_line_errors(options, message):
    with pytest.raises(ConfigurationError, match=message) as info:
        create_backend({"backend": "can-sonar", **options})
    assert "\n" not in str(info.value)


def test_a_missing_port_is_a_clear_link_error():
    ring = create_backend("can-sonar://slcan:/dev/no-such-adapter?open_delay_s=0")
    with pytest.raises(LinkLostError, match="/dev/no-such-adapter"):
        ring.configure()
    assert ring.state is State.UNCONFIGURED


def test_no_board_on_the_bus_times_out_naming_it():
    ring = create_backend(
        {"backend": "can-sonar", "interface": "virtual", "channel": "empty-bus", **FAST}
    )
    with pytest.raises(DeviceTimeoutError, match=r"0x400 on virtual empty-bus.*CONNECT"):
        ring.configure()
    assert ring.state is State.UNCONFIGURED
    ring.close()


# ---------------------------------------------------------------------- heartbeat


def test_heartbeat_counts_missed_replies_then_latches_lost():
    hb = Heartbeat(1.0, 3)
    assert hb.due(0.0)
    hb.sent(0.0)
    hb.replied(0.01)
    for t in (1.0, 2.0, 3.0):
        assert not hb.due(t - 0.01) and hb.due(t)
        hb.sent(t)
        assert not hb.lost
    hb.sent(4.0)  # the replies to 1.0, 2.0 and 3.0 never came
    assert hb.lost and hb.missed == 3 and not hb.due(10.0)
    hb.replied(4.1)
    assert hb.lost, "a lost board stays lost until reconfigured"


def test_heartbeat_late_reply_still_counts_and_no_burst_after_a_stall():
    hb = Heartbeat(1.0, 3)
    hb.sent(0.0)
    hb.sent(1.0)
    hb.replied(1.5)
    hb.sent(2.0)
    assert hb.missed == 0 and hb.total_missed == 1
    hb.sent(60.0)  # the host was suspended for a minute
    assert hb.next_due_s == pytest.approx(61.0)


def test_lost_board_raises_a_named_device_fault_within_bounded_time():
    with VirtualBoard() as board:
        ring = board.backend()
        with ring:
            assert len(ring.scan()) == 16
            board.device.heartbeat_stopped = True
            wait_for(lambda: scan_error(ring) is not None, "the driver to notice the lost board")
            err = scan_error(ring)
            assert isinstance(err, DeviceFaultError)
            assert "0x400" in str(err) and board.channel in str(err) and "lost" in str(err)
            # Still raising later: the fault is latched, not a one-off.
            board.device.heartbeat_stopped = False
            time.sleep(0.5)
            assert isinstance(scan_error(ring), DeviceFaultError)
            assert ring.stats.heartbeats_missed >= 3
        assert ring.state is State.CLOSED


def test_lost_board_across_processes():
    with emulator_process("--world", "fig12", "--stop-heartbeat-after", "4") as (_, info):
        ring = create_backend({**info["backend"], **FAST})
        try:
            ring.configure()
        except DeviceTimeoutError as exc:
            # A very slow start: the board already went silent. Still a clear, named error.
            assert "CONNECT" in str(exc)
            return
        try:
            wait_for(lambda: scan_error(ring) is not None, "the lost board", 60.0)
            err = scan_error(ring)
            assert isinstance(err, DeviceFaultError) and info["pty"] in str(err)
        finally:
            ring.close()


# ---------------------------------------------------------------------- readings


def table(layout: RingLayout | None = None, max_age_s: float = 1.0) -> ReadingTable:
    return ReadingTable(
        layout or RingLayout.nomad_ring(), min_range_m=0.15, max_range_m=6.5, max_age_s=max_age_s
    )


def test_reserved_values_and_out_of_window_ranges_map_to_no_reading():
    t = table()
    readings = (
        Reading(ReadingStatus.INVALID),
        Reading(ReadingStatus.TOO_CLOSE),
        Reading(ReadingStatus.NO_ECHO),
        Reading.ok(1.25),
    )
    t.update(GroupData(0, Resolution.CM_1, readings), 10.0)
    t.update(GroupData(1, Resolution.CM_1, (Reading.ok(0.05), Reading.ok(7.0),
                                            Reading.ok(6.5), Reading.ok(0.15))), 10.0)  # fmt: skip
    ranges, stamps = t.snapshot(10.1)
    assert np.isnan(ranges[:3]).all() and ranges[3] == 1.25
    assert ranges[4] == 0.15, "an echo closer than the minimum range is the minimum range"
    assert np.isnan(ranges[5]), "beyond the maximum range is no reading"
    assert ranges[6] == 6.5 and ranges[7] == 0.15
    assert (stamps[:8] == 10.0).all() and (stamps[8:] == 0.0).all()
    assert t.statuses[1] is ReadingStatus.TOO_CLOSE


def test_stale_readings_are_never_reported_as_fresh():
    t = table(max_age_s=0.5)
    t.update(GroupData(0, Resolution.CM_1, (Reading.ok(1.0),) * 4), 10.0)
    ranges, stamps = t.snapshot(10.4)
    assert (ranges[:4] == 1.0).all()
    ranges, stamps = t.snapshot(10.6)
    assert np.isnan(ranges[:4]).all() and (stamps[:4] == 10.0).all()


def test_reserved_values_end_to_end():
    values = np.array([math.nan, 0.01, 1.0, 9.0] + [2.0] * 12)
    with (
        VirtualBoard(ranges=lambda: values, resolution=Resolution.CM_1) as board,
        board.backend(channels=list(range(15))) as ring,  # channel 15 unmapped, so inactive
    ):
        s = ring.scan()
        assert board.device.board.active_mask == (1 << 15) - 1
    assert np.isnan(s.ranges_m[0]), "no echo"
    assert np.isnan(s.ranges_m[1]), "too close"
    assert s.ranges_m[2] == pytest.approx(1.0)
    assert np.isnan(s.ranges_m[3]), "beyond max_range_m"
    assert len(s) == 15 and np.allclose(s.ranges_m[4:], 2.0)


def test_channel_mapping_orders_and_places_the_ring():
    values = np.arange(16) * 0.1 + 1.0  # transducer k reads 1.0 + 0.1 k
    channels = [8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3]
    angles = [i * 30.0 for i in range(12)]
    radii = [0.2 + 0.01 * i for i in range(12)]
    with (
        VirtualBoard(ranges=lambda: values) as board,
        board.backend(channels=channels, angles_deg=angles, radius_m=radii) as ring,
    ):
        s = ring.scan()
        assert board.device.board.active_mask == 0x0F0F | 0xF000 | 0x0F00
    assert np.allclose(s.ranges_m, values[channels])
    yaw = np.radians(angles)
    assert np.allclose(np.angle(np.exp(1j * (s.yaw_rad - yaw))), 0.0)
    assert np.allclose(np.hypot(s.x_m, s.y_m), radii)
    assert np.allclose(np.arctan2(s.y_m, s.x_m), np.angle(np.exp(1j * yaw)))


def test_layout_defaults_are_a_nomad_ring():
    layout = layout_from_values()
    assert layout.channels == tuple(range(16))
    assert np.allclose(np.degrees(layout.angles_rad), np.arange(16) * 22.5)
    assert layout.radii_m == (0.23,) * 16 and layout.groups == (0, 1, 2, 3)
    assert layout_from_values("4,5").groups == (1,)


def test_readings_are_stamped_on_the_driver_clock_and_refresh():
    with VirtualBoard() as board, board.backend() as ring:
        a = ring.scan()
        assert np.all(a.stamps_s <= ring.clock.now())
        wait_for(lambda: bool(np.all(ring.scan().stamps_s > a.stamps_s)), "fresh readings")


def test_readings_age_out_when_data_stops():
    with VirtualBoard() as board, board.backend(heartbeat_s=5.0, max_age_s=0.3) as ring:
        assert ring.scan().echo.any()
        board.device.injector.faults = BoardFaults(drop=1.0)
        wait_for(lambda: not ring.scan().echo.any(), "readings to age out")
        aged = ring.scan()
        time.sleep(0.5)
        later = ring.scan()
        assert np.array_equal(later.stamps_s, aged.stamps_s), "old readings were re-stamped"
        assert np.all(later.stamps_s < ring.clock.now() - 0.3)


def test_link_counts_garbage_and_reports_a_vanished_bus():
    import can

    from drivers.can_sonar.codec import UsBoardCodec
    from drivers.can_sonar.link import BoardLink
    from hal.clock import MonotonicClock

    class Bus:
        def __init__(self, error: Exception) -> None:
            self.error = error

        def recv(self, timeout=None):
            raise self.error

    link = BoardLink(Bus(ValueError("bad hex")), UsBoardCodec(), MonotonicClock(), "fake")
    assert link.receive(0.0) is None and link.stats.corrupt_frames == 1
    link = BoardLink(Bus(can.CanOperationError("EIO")), UsBoardCodec(), MonotonicClock(), "fake")
    with pytest.raises(LinkLostError, match="fake"):
        link.receive(0.0)


# ---------------------------------------------------------------------- parameter set


@pytest.mark.parametrize("where", ["ram", "eeprom"])
def test_parameter_write_is_acknowledged_and_read_back(where):
    with VirtualBoard() as board:
        ring = board.backend(write_params=where, update_interval_s=0.25, warning_m=0.8)
        with ring:
            emulated = board.device.board
            assert emulated.params.update_interval_s == 0.25
            assert emulated.params.warning_distances_m == (0.8,) * 16
            assert (emulated.eeprom == emulated.params) == (where == "eeprom")
            assert ring.board_parameters == emulated.params
            assert emulated.counts.parameter_sets_written == 1


def test_bad_acknowledgement_is_refused():
    with VirtualBoard(faults=BoardFaults(wrong_ack_sum=True)) as board:
        ring = board.backend(write_params="ram")
        with pytest.raises(ProtocolError, match=r"byte sum.*refused"):
            ring.configure()
        assert ring.state is State.UNCONFIGURED
        assert board.device.board.params.update_interval_s == 0.1  # the board kept its set
        ring.close()


# ---------------------------------------------------------------------- bad frames


def test_corrupt_frames_are_skipped_and_counted():
    with VirtualBoard(seed=7) as board, board.backend() as ring:
        board.device.injector.faults = BoardFaults(corrupt=0.3)
        wait_for(lambda: ring.stats.corrupt_frames >= 5, "corrupt frames")
        assert ring.scan().echo.any()
        assert board.device.injector.counts.corrupted >= ring.stats.corrupt_frames


def test_bus_errors_and_drops_are_survived_and_counted():
    with VirtualBoard(seed=11) as board, board.backend() as ring:
        board.device.injector.faults = BoardFaults(bus_errors=0.1, drop=0.1)
        wait_for(lambda: ring.stats.error_frames >= 3, "error frames")
        assert ring.scan().echo.any()
        assert board.device.injector.counts.dropped > 0


def test_configure_survives_lost_and_corrupt_frames():
    faults = BoardFaults(drop=0.15, corrupt=0.1, bus_errors=0.05)
    with VirtualBoard(faults=faults, seed=5) as board:
        with board.backend(write_params="ram", update_interval_s=0.2) as ring:
            assert ring.board_parameters is not None
            assert ring.board_parameters.update_interval_s == 0.2
            assert len(ring.scan()) == 16
        assert sum(vars(board.device.injector.counts).values()) > 0


def test_foreign_frames_on_a_shared_bus_are_ignored():
    import can

    with VirtualBoard() as board, board.backend() as ring:
        other = can.Bus(interface="virtual", channel=board.channel)
        try:
            for ident in (0x123, 0x40D + 0x100):
                other.send(can.Message(arbitration_id=ident, data=bytes(8), is_extended_id=False))
            other.send(can.Message(arbitration_id=0x40D, data=bytes(8), is_extended_id=True))
            wait_for(lambda: ring.stats.foreign_frames >= 3, "foreign frames")
        finally:
            other.shutdown()
        assert ring.stats.corrupt_frames == 0 and ring.scan().echo.any()
