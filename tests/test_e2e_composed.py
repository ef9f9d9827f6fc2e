"""End to end with the CAN sonar board: drive and encoders from the Nomad 200 driver, the ring
from the CAN driver over python-can's slcan interface, both emulators on one simulated robot.

``tslam emulate nomad200 --with-can-sonar`` across processes, ``tslam sim --backend
nomad200+can-sonar-emulated`` with the board's heartbeat stopped partway through the
exploration (the robot ends stopped, one line, no traceback), and the command-line mistakes.
The topological comparison of whole explorations is in ``test_e2e_nomad200.py``.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest

from hal.composed import ComposedBackend
from hal.registry import create_backend
from hal.types import Twist
from tslam.programs import cli, sim_backends
from tslam.programs.emulated import read_ready_line, stop_process
from tslam.programs.sim_backends import COMPOSED, EmulatedRobot

#: Bounds on anything this file waits for across processes (host seconds).
STARTUP_S = 120.0
RUN_S = 300.0


def _emulate(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "tslam.programs.cli", "emulate", "nomad200", *args],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_emulate_nomad200_with_can_sonar_serves_one_robot_on_two_links():
    proc = _emulate("--world", "fig12", "--seed", "2", "--drift", "none", "--lockstep",
                    "--with-can-sonar", "--can-base-id", "0x480")  # fmt: skip
    try:
        ready = read_ready_line(proc, STARTUP_S)
        board = ready["can_sonar"]
        assert ready["port"].startswith("/dev/") and board["pty"].startswith("/dev/")
        assert ready["port"] != board["pty"]
        assert board["backend"]["channel"] == board["pty"]
        assert board["backend"]["base_id"] == "0x480"
        spec = ready["backend"]
        assert spec["backend"] == "composed" and spec["sonar"] == board["backend"]
        assert spec["drive"] == {"backend": "nomad200", "port": ready["port"], "lockstep": True}
        backend = create_backend(spec)
        assert isinstance(backend, ComposedBackend)
        with backend:
            # fig12 starts facing a wall 3.7 m ahead: what the board reads ahead must shrink
            # by what the Nomad's encoders say it drove, so both links see one robot.
            before = backend.scan().ranges_m[0]
            backend.command(Twist(0.3))
            for _ in range(30):
                backend.clock.sleep(0.1)
                backend.command(Twist(0.3))
            backend.stop()
            backend.clock.sleep(2.0)
            travelled = backend.odometry().distance_m
            after = backend.scan().ranges_m[0]
        assert 3.0 < before < 4.5 and travelled > 0.5
        # Sonar noise is 1 cm + 1 % a reading, some 5 cm at this range.
        assert before - after == pytest.approx(travelled, abs=0.15)
    finally:
        stop_process(proc)
    assert proc.returncode == 0


def test_heartbeat_loss_mid_exploration_stops_the_robot(monkeypatch, capsys):
    """The board stops answering CONNECT 20 simulated seconds in, while the robot explores:
    three beats later the run ends with one line naming the board, and the robot is left
    commanded to a standstill (then, given time, standing still)."""
    made: list[EmulatedRobot] = []

    class Recorded(EmulatedRobot):
        def __init__(self, *args: object, **kwargs: object) -> None:
            super().__init__(*args, **kwargs)  # type: ignore[arg-type]
            made.append(self)

    monkeypatch.setattr(sim_backends, "EmulatedRobot", Recorded)
    code = cli.main(["sim", "--world", "fig12", "--seed", "1", "--backend", COMPOSED,
                     "--can-stop-heartbeat-after", "20", "--quiet"])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 1 and out == ""  # a hardware failure, not a mistake in the command
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("tslam: error: CAN sonar board at 0x400")
    assert "lost" in lines[0] and "CONNECT" in lines[0]
    (emulated,) = made
    robot = emulated.robot
    assert 20.0 < robot.t < 30.0, "lost some three heartbeats after the board fell silent"
    assert emulated.can_device is not None and not emulated.can_device.board.answer_connect
    assert (robot.cmd_v, robot.cmd_w, robot.cmd_wt) == (0.0, 0.0, 0.0)
    # The emulator's host has stopped; let the simulated robot brake and check it stays put.
    robot.step(3.0)
    still = robot.true_pose()
    robot.step(2.0)
    moved = robot.true_pose()
    assert math.hypot(moved.x - still.x, moved.y - still.y) < 1e-9
    assert (robot.v, robot.w, robot.wt) == (0.0, 0.0, 0.0)


def test_heartbeat_loss_ends_the_process_with_one_line():
    """The same as a user meets it: a process that exits (no thread left hanging) with a
    nonzero code and one line on stderr, no traceback."""
    proc = subprocess.run(
        [sys.executable, "-m", "tslam.programs.cli", "sim", "--world", "fig12", "--seed", "1",
         "--backend", COMPOSED, "--can-stop-heartbeat-after", "2", "--quiet"],
        capture_output=True, text=True, timeout=RUN_S,
    )  # fmt: skip
    assert proc.returncode == 1 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "lost" in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["emulate", "can-sonar", "--world", "fig1", "--virtual", ""], "--virtual must name"),
        (["emulate", "can-sonar", "--world", "fig1", "--virtual", " "], "--virtual must name"),
        (["emulate", "nomad200", "--world", "fig1", "--can-drop", "0.1"], "--with-can-sonar"),
        (["emulate", "nomad200", "--world", "fig1", "--with-can-sonar", "--can-bitrate", "7"],
         "--can-bitrate"),
        (["sim", "--world", "fig12", "--can-stop-heartbeat-after", "3"], COMPOSED),
        (["sim", "--world", "fig12", "--backend", COMPOSED, "--can-stop-heartbeat-after", "-1"],
         "--can-stop-heartbeat-after"),
        (["sim", "--world", "no-such-world", "--backend", "nomad200-emulated"], "no-such-world"),
    ],
)  # fmt: skip
def test_mistakes_are_one_line_exit_2(argv, message, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], err


def test_the_ready_line_without_the_board_names_the_drive():
    proc = _emulate("--world", "fig12", "--lockstep")
    try:
        ready = read_ready_line(proc, STARTUP_S)
    finally:
        stop_process(proc)
    assert "can_sonar" not in ready
    assert ready["backend"] == {"backend": "nomad200", "port": ready["port"], "lockstep": True}
    assert json.dumps(ready)
