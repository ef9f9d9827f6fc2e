"""Operators' commands applied to the arbiter: each accepted or refused with a reason.

Applied by the control loop's thread only (the arbiter is not thread-safe), between two
control cycles; the orders are saved before the acknowledgement goes out, so nothing an
operator was told is done is lost when the daemon dies the next instant.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

from tslam.core.explorer import Explorer, Mode
from tslam.daemon.store import Orders
from tslam.link.schemas import Command, CommandReply, command_problem


@dataclass
class _Slot:
    cmd: Command
    done: threading.Event = field(default_factory=threading.Event)
    reply: CommandReply | None = None
    abandoned: bool = False


class Inbox:
    """Hands commands from the link's threads to the control loop and waits for the answer."""

    def __init__(self, answer_within_s: float) -> None:
        self.answer_within_s = answer_within_s
        self._q: queue.Queue[_Slot] = queue.Queue(maxsize=64)
        self._lock = threading.Lock()
        self.open = False

    def submit(self, cmd: Command) -> CommandReply:
        """Called by the link for each command; never raises."""
        problem = command_problem(cmd)
        if problem is not None:
            return CommandReply(cmd.id, False, problem)
        if not self.open:
            return CommandReply(cmd.id, False, "the control loop is not running")
        slot = _Slot(cmd)
        try:
            self._q.put_nowait(slot)
        except queue.Full:
            return CommandReply(cmd.id, False, "too many commands waiting: try again")
        if not slot.done.wait(self.answer_within_s):
            with self._lock:
                if slot.reply is None:
                    slot.abandoned = True
                    return CommandReply(cmd.id, False, "the control loop did not answer in time")
        assert slot.reply is not None
        return slot.reply

    def serve(self, apply: Callable[[Command], CommandReply]) -> list[CommandReply]:
        """Apply every waiting command (control loop thread); returns the replies sent."""
        out = []
        while True:
            try:
                slot = self._q.get_nowait()
            except queue.Empty:
                return out
            with self._lock:
                if slot.abandoned:
                    continue  # its sender was told it failed: doing it now would be a lie
                try:
                    slot.reply = apply(slot.cmd)
                except Exception as exc:  # a bug must not kill the loop that drives the robot
                    slot.reply = CommandReply(slot.cmd.id, False, f"internal error: {exc}")
            slot.done.set()
            out.append(slot.reply)

    def close(self) -> None:
        self.open = False
        self.serve(lambda c: CommandReply(c.id, False, "the daemon is shutting down"))


def apply_command(cmd: Command, explorer: Explorer, orders: Orders) -> tuple[Orders, str | None]:
    """The orders after ``cmd``, and the reason it is refused (None: accepted)."""
    op = cmd.op
    if op == "pause":
        if orders.halted == "stopped":
            return orders, "the robot is stopped: send explore or goto"
        return Orders("paused", orders.goal), None
    if op == "resume":
        if orders.halted != "paused":
            what = "stopped: send explore or goto" if orders.halted else "not paused"
            return orders, f"the robot is {what}"
        return Orders(None, orders.goal), None
    if op == "stop":
        explorer.cancel()
        return Orders("stopped", None), None
    if op == "explore":
        reason = explorer.explore()
        if reason is not None:
            return orders, reason
        return Orders(None, None), None
    if op == "goto":
        if cmd.node is None:
            return orders, "goto needs a node"
        if explorer.mode is Mode.DISAMBIGUATE:
            return orders, "the robot is still telling look-alike places apart: try again soon"
        reason = explorer.goto(cmd.node)
        if reason is not None:
            return orders, reason
        return Orders(None, explorer.goal), None
    return orders, f"unknown op {op!r}"
