"""The daemon's parts on their own: the loop watchdog, the command inbox between the link's
threads and the control loop, and systemd's notification socket."""

from __future__ import annotations

import socket
import threading

from tslam.daemon.orders import Inbox
from tslam.daemon.systemd import Notifier
from tslam.daemon.watchdog import Watchdog
from tslam.link.schemas import Command, CommandReply


def test_watchdog_stops_the_drive_once_per_stall():
    now = [0.0]
    stops: list[float] = []
    dog = Watchdog(1.0, stops.append, monotonic=lambda: now[0])
    dog.beat()
    now[0] = 0.9
    assert not dog.check() and stops == []
    now[0] = 1.5
    assert dog.check() and stops == [1.5]
    now[0] = 3.0
    assert not dog.check() and len(stops) == 1  # one stop per stall, not one per check
    dog.beat()
    now[0] = 4.2
    assert dog.check() and dog.stalls == 2


def submit_and_serve(inbox: Inbox, cmd: Command, apply) -> tuple[CommandReply, list]:
    """Submit from a thread, as the link does, and serve from this one, as the loop does."""
    inbox.open = True
    replies: list[CommandReply] = []
    t = threading.Thread(target=lambda: replies.append(inbox.submit(cmd)))
    t.start()
    served: list[CommandReply] = []
    for _ in range(1000):
        served += inbox.serve(apply)
        if served:
            break
        threading.Event().wait(0.01)
    t.join(10)
    return replies[0], served


def test_inbox_hands_commands_to_the_loop_and_returns_its_answer():
    reply, served = submit_and_serve(
        Inbox(answer_within_s=10.0),
        Command("1", "pause"),
        lambda c: CommandReply(c.id, True, "done by the loop"),
    )
    assert [reply] == [CommandReply("1", True, "done by the loop")] == served


def test_inbox_refuses_what_it_cannot_carry_out():
    inbox = Inbox(answer_within_s=0.05)
    assert inbox.submit(Command("1", "pause")).reason == "the control loop is not running"
    inbox.open = True
    assert "unknown op 'jump'" in inbox.submit(Command("2", "jump")).reason
    late = inbox.submit(Command("3", "stop"))  # nobody serves: the loop is stuck
    assert not late.accepted and "did not answer in time" in late.reason
    # The loop wakes later: it must not carry out what the operator was told had failed.
    assert inbox.serve(lambda c: CommandReply(c.id, True, "")) == []


def test_inbox_turns_a_bug_into_a_refusal():
    inbox = Inbox(answer_within_s=10.0)
    reply, _ = submit_and_serve(inbox, Command("1", "explore"), lambda c: 1 / 0)
    assert reply.accepted is False and "internal error" in reply.reason


def test_notifier_speaks_sd_notify(tmp_path):
    path = tmp_path / "notify"
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
        s.bind(str(path))
        s.settimeout(5)
        n = Notifier({"NOTIFY_SOCKET": str(path), "WATCHDOG_USEC": "4000000"})
        assert n.enabled and n.watchdog_interval_s == 2.0
        n.ready("exploring")
        assert s.recv(100).decode().split("\n") == ["READY=1", "STATUS=exploring"]
        n.ping()
        assert s.recv(100) == b"WATCHDOG=1"
    quiet = Notifier({})
    assert not quiet.enabled and quiet.watchdog_interval_s is None
    quiet.ready("nobody listens")  # no socket: nothing happens, nothing raises
