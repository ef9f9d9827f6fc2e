"""The emulated CAN sonar board: its answers frame by frame, its fault injection, the SLCAN
pseudo-terminal it speaks on, and ``tslam emulate can-sonar`` as a user runs it."""

from __future__ import annotations

import argparse
import json
import math
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from drivers.can_sonar.codec import (
    AnalogIn,
    ConnectReply,
    FrameError,
    GroupData,
    LegacyData,
    ParameterSet,
    ReadingStatus,
    Resolution,
    UsBoardCodec,
    WriteAck,
    paraset_byte_sum,
    paraset_from_chunks,
    paraset_to_chunks,
)
from sim_backend.emulators.can_sonar import UsBoardEmulator, default_parameters, make_device
from sim_backend.emulators.can_sonar_faults import BoardFaults, BusError, FaultInjector
from sim_backend.emulators.can_sonar_slcan import SlcanPty
from sim_backend.emulators.host import EmulatorHost
from sim_backend.simulator import SimRobot
from tests.conftest import box_world
from tslam.programs.emulate_can_sonar import add_board_arguments, make_can_sonar_device

TSLAM = Path(sys.executable).with_name("tslam")
CODEC = UsBoardCodec()


def board(values: np.ndarray | None = None, **kwargs) -> UsBoardEmulator:
    v = np.arange(16) * 0.25 + 0.5 if values is None else values
    return UsBoardEmulator(lambda: v, **kwargs)


def replies(b: UsBoardEmulator, frame) -> list:
    return [CODEC.decode_reply(f) for f in b.handle(frame)]


# ---------------------------------------------------------------------- the board


def test_connect_is_answered_unless_the_heartbeat_is_stopped():
    b = board()
    assert replies(b, CODEC.connect()) == [ConnectReply()]
    b.answer_connect = False
    assert replies(b, CODEC.connect()) == [] and b.counts.connects_ignored == 1


def test_group_data_carries_the_transducers_with_reserved_values():
    values = np.array([math.nan, 0.01, 1.0, 50.0] + [2.0] * 12)
    b = board(values, resolution=Resolution.CM_1)
    (g0,) = replies(b, CODEC.get_data([0]))
    assert isinstance(g0, GroupData) and g0.resolution is Resolution.CM_1
    statuses = [r.status for r in g0.readings]
    assert statuses == [
        ReadingStatus.NO_ECHO,  # NaN
        ReadingStatus.TOO_CLOSE,  # below three counts
        ReadingStatus.OK,
        ReadingStatus.NO_ECHO,  # beyond 12 bits of counts
    ]
    assert g0.readings[2].range_m == 1.0
    assert [r.group for r in replies(b, CODEC.get_data([1, 3]))] == [1, 3]


def test_inactive_channels_read_invalid():
    b = board()
    assert replies(b, CODEC.set_channels_active(0b0101)) == []
    (g0,) = replies(b, CODEC.get_data([0]))
    assert [r.status for r in g0.readings] == [
        ReadingStatus.OK, ReadingStatus.INVALID, ReadingStatus.OK, ReadingStatus.INVALID
    ]  # fmt: skip


def test_transducer_order_is_configurable():
    values = np.arange(16) * 0.25 + 0.5
    b = board(values, transducers=list(reversed(range(16))))
    (g0,) = replies(b, CODEC.get_data([0]))
    assert [r.range_m for r in g0.readings] == list(values[15:11:-1])


def test_legacy_and_analog_requests():
    b = board()
    legacy = replies(b, CODEC.get_legacy_data(1))
    assert [frame.block for frame in legacy] == [2, 3]
    assert all(isinstance(f, LegacyData) for f in legacy)
    # Sensor 8 reads 2.5 m, which fits a byte of cm; 9..15 read 2.75..4.25 m, which do not.
    statuses = [r.status for f in legacy for r in f.readings]
    assert statuses == [ReadingStatus.OK] + [ReadingStatus.NO_ECHO] * 7
    assert legacy[0].readings[0].range_m == 2.5
    assert replies(b, CODEC.get_legacy_data(0))[0].readings[0].range_m == 0.5
    assert replies(b, CODEC.get_analog_in()) == [AnalogIn((2048, 1024, 3072, 4095))]


def test_parameter_set_write_acknowledged_with_byte_sum_and_read_back():
    b = board()
    new = ParameterSet(0.5, (1.0,) * 16, (0.4,) * 16, cross_echo=True)
    frames = CODEC.write_paraset(new, eeprom=True)
    acks = [r for f in frames for r in replies(b, f)]
    assert [a.index for a in acks] == list(range(9))
    assert all(isinstance(a, WriteAck) and a.eeprom for a in acks)
    assert acks[-1].byte_sum == paraset_byte_sum(paraset_to_chunks(new))
    assert b.params == new and b.eeprom == new
    read = replies(b, CODEC.read_paraset())
    assert paraset_from_chunks(r.chunk for r in read) == new


def test_a_resent_frame_does_not_spoil_the_byte_sum():
    b = board()
    new = ParameterSet(0.5, (1.0,) * 16, (0.4,) * 16)
    frames = CODEC.write_paraset(new)
    for f in [*frames[:4], frames[3], *frames[4:], frames[8]]:
        last = replies(b, f)[-1]
    assert last.byte_sum == paraset_byte_sum(paraset_to_chunks(new)) and b.params == new


def test_wrong_ack_sum_fault_keeps_the_old_parameters():
    b = board()
    b.wrong_ack_sum = True
    new = ParameterSet(0.5, (1.0,) * 16, (0.4,) * 16)
    last = [r for f in CODEC.write_paraset(new) for r in replies(b, f)][-1]
    assert last.byte_sum != paraset_byte_sum(paraset_to_chunks(new))
    assert b.params == default_parameters()


def test_other_identifiers_and_bad_commands_are_ignored():
    from drivers.can_sonar.codec import Frame

    b = board()
    assert b.handle(Frame(0x123, bytes(8))) == []
    assert b.handle(Frame(0x400, bytes([9]) + bytes(7))) == []  # no command 9
    assert b.handle(Frame(0x400, bytes(3))) == []  # short frame
    assert b.counts.foreign_frames == 1 and b.counts.bad_commands == 2


def test_board_at_another_base_identifier():
    codec = UsBoardCodec(0x500)
    b = board(base_id=0x500)
    (reply,) = b.handle(codec.connect())
    assert reply.arbitration_id == 0x501
    assert b.handle(CODEC.connect()) == []


# ---------------------------------------------------------------------- faults


def frames_through(injector: FaultInjector, n: int = 400) -> list:
    b = board()
    out = []
    for _ in range(n):
        out.extend(injector.outgoing(f) for f in b.handle(CODEC.get_data([0, 1, 2, 3])))
    return out


def test_fault_injection_is_seeded_and_reproducible():
    faults = BoardFaults(drop=0.2, corrupt=0.2, bus_errors=0.1)
    a = frames_through(FaultInjector(faults, CODEC, seed=4))
    b = frames_through(FaultInjector(faults, CODEC, seed=4))
    c = frames_through(FaultInjector(faults, CODEC, seed=5))
    assert a == b and a != c


def test_fault_rates_and_kinds():
    injector = FaultInjector(BoardFaults(drop=0.2, corrupt=0.2, bus_errors=0.1), CODEC, seed=1)
    out = frames_through(injector)
    n = len(out)
    counts = injector.counts
    assert sum(o is None for o in out) == counts.dropped
    assert sum(isinstance(o, BusError) for o in out) == counts.bus_errors
    assert 0.05 * n < counts.bus_errors < 0.15 * n
    assert 0.1 * n < counts.dropped < 0.3 * n and 0.08 * n < counts.corrupted < 0.25 * n


def test_every_corrupted_frame_is_recognisable_by_the_codec():
    injector = FaultInjector(BoardFaults(corrupt=1.0), CODEC, seed=2)
    b = board()
    frames = [*b.handle(CODEC.get_data([0, 1, 2, 3])), *b.handle(CODEC.connect()),
              *b.handle(CODEC.read_paraset())] * 20  # fmt: skip
    for f in frames:
        damaged = injector.outgoing(f)
        with pytest.raises(FrameError):
            CODEC.decode_reply(damaged)


def test_heartbeat_stop_time():
    injector = FaultInjector(BoardFaults(heartbeat_stops_after_s=5.0), CODEC)
    assert not injector.heartbeat_stopped(4.9) and injector.heartbeat_stopped(5.0)


@pytest.mark.parametrize("bad", [{"drop": -0.1}, {"corrupt": 1.5}, {"heartbeat_stops_after_s": -1}])
def test_bad_fault_settings_are_refused(bad):
    with pytest.raises(ValueError):
        BoardFaults(**bad)


# ---------------------------------------------------------------------- SLCAN on a pty


class PtyHost:
    """Plays the host side of the pty by hand: raw SLCAN lines, no python-can."""

    def __init__(self, path: str) -> None:
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY)

    def write(self, text: str) -> None:
        os.write(self.fd, text.encode())

    def read(self, link: SlcanPty, wait_s: float = 5.0) -> tuple[bytes, list]:
        """Let the board process what was written and collect what it answers."""
        deadline = time.monotonic() + wait_s
        got_frames = []
        out = b""
        while time.monotonic() < deadline:
            got_frames.extend(link.receive())
            ready, _, _ = select.select([self.fd], [], [], 0.05)
            if ready:
                out += os.read(self.fd, 4096)
            elif out or got_frames:
                break
        return out, got_frames

    def close(self) -> None:
        os.close(self.fd)


@pytest.fixture
def pty_link():
    link = SlcanPty(1_000_000)
    host = PtyHost(link.path)
    yield link, host
    host.close()
    link.close()


def test_slcan_open_frames_and_close(pty_link):
    link, host = pty_link
    host.write("S8\rO\r")
    out, frames = host.read(link)
    assert out == b"\r\r" and frames == []
    connect = CODEC.connect()
    host.write(f"t{connect.arbitration_id:03X}8{connect.data.hex().upper()}\r")
    _, frames = host.read(link)
    assert frames == [connect]
    link.send(CODEC.encode_reply(ConnectReply()))
    out, _ = host.read(link)
    assert out == b"t4018" + b"00" * 8 + b"\r"
    host.write("C\r")
    host.read(link)
    link.send(CODEC.encode_reply(ConnectReply()))
    out, _ = host.read(link, wait_s=0.3)
    assert out == b"", "a closed channel sends nothing"


def test_slcan_wrong_bitrate_hears_nothing(pty_link):
    link, host = pty_link
    host.write("S6\rO\r")  # 500 kbit/s against a 1 Mbit/s board
    host.read(link)
    host.write("t4008" + "00" * 8 + "\r")
    _, frames = host.read(link, wait_s=0.3)
    assert frames == []


def test_slcan_refuses_garbage_with_bel(pty_link):
    link, host = pty_link
    host.write("S8\rO\rtZZZ8\rX\rV\r")
    out, frames = host.read(link)
    assert frames == [] and out == b"\r\r\a\aV1013\r"
    assert link.bad_lines == 1


# ---------------------------------------------------------------------- making a device


def test_make_can_sonar_device_with_a_prefix_for_another_command():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seed", type=int, default=0)
    add_board_arguments(parser, prefix="can-")
    args = parser.parse_args(["--seed", "9", "--can-base-id", "0x480", "--can-drop", "0.25"])
    robot = SimRobot(box_world(), seed=1)
    device = make_can_sonar_device(robot, args, prefix="can-")
    try:
        assert device.interface == "slcan" and device.channel.startswith("/dev/")
        assert device.board.codec.base_id == 0x480 and device.seed == 9
        assert device.faults.drop == 0.25
        assert device.backend_options()["base_id"] == "0x480"
    finally:
        device.close()


def test_make_can_sonar_device_from_a_mapping_on_a_virtual_channel():
    robot = SimRobot(box_world(), seed=1)
    device = make_can_sonar_device(robot, {"virtual": "map-test", "stop_heartbeat_after": 2})
    try:
        assert device.interface == "virtual" and device.channel == "map-test"
        assert device.faults.heartbeat_stops_after_s == 2.0
    finally:
        device.close()


def test_the_board_fires_the_shared_robots_ring():
    """The board reads the robot the host steps: what it sends is that ring, quantised."""
    robot = SimRobot(box_world(), seed=2)
    device = make_device(robot, virtual_channel="ring-test")
    host = EmulatorHost(robot, [device])
    try:
        host.run(max_wall_s=0.2)  # the host closes its devices when done
    finally:
        device.close()
    assert robot.t > 0
    readings = device.board.readings()
    for k, r in enumerate(readings):
        true = robot.ring.ranges[k]
        if math.isnan(true):
            assert r.status is ReadingStatus.NO_ECHO
        else:
            assert r.range_m == pytest.approx(true, abs=0.0025)


# ---------------------------------------------------------------------- the command


def start(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [str(TSLAM), "emulate", "can-sonar", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def first_line(proc: subprocess.Popen[str]) -> dict:
    ready, _, _ = select.select([proc.stdout], [], [], 60.0)
    assert ready, "no line within 60 s"
    return json.loads(proc.stdout.readline())  # type: ignore[union-attr]


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_command_prints_the_pty_and_stops_cleanly(sig):
    proc = start("--world", "fig1", "--slcan-pty", "--seed", "1")
    try:
        info = first_line(proc)
        assert info["pty"].startswith("/dev/pts/") and os.path.exists(info["pty"])
        assert info["backend"]["backend"] == "can-sonar"
        assert info["backend"]["interface"] == "slcan"
        proc.send_signal(sig)
        assert proc.wait(timeout=30) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=10)
        proc.stdout.close()  # type: ignore[union-attr]
        proc.stderr.close()  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--world", "no-such-world"], "no-such-world"),
        (["--world", "fig1", "--drop", "2"], "drop"),
        (["--world", "fig1", "--base-id", "0x7FF"], "base-id"),
        (["--world", "fig1", "--bitrate", "12345"], "bitrate"),
    ],
)
def test_command_mistakes_are_one_line_exit_2(args, message):
    proc = subprocess.run(
        [str(TSLAM), "emulate", "can-sonar", *args], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in proc.stderr
