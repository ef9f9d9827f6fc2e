"""The board on a python-can ``virtual`` channel: the host driver in the same process opens
``can.Bus(interface="virtual", channel=NAME)`` and talks to it as to a real bus.

A virtual bus has no descriptor to wait on, so a python-can Notifier receives for it and pokes a
pipe: the emulator host then wakes on the pipe like on any other device's descriptor.
"""

from __future__ import annotations

import contextlib
import os
import threading

import can

from drivers.can_sonar.codec import Frame


class VirtualCanChannel:
    """One node on a virtual CAN channel; frames in and out as codec ``Frame`` values."""

    def __init__(self, channel: str) -> None:
        self.channel = channel
        self.path = channel
        self._bus = can.Bus(interface="virtual", channel=channel, receive_own_messages=False)
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        os.set_blocking(self._wake_w, False)
        self._inbox: list[can.Message] = []
        self._lock = threading.Lock()
        self._notifier = can.Notifier(self._bus, [self._on_message], timeout=0.05)

    def _on_message(self, msg: can.Message) -> None:
        with self._lock:
            self._inbox.append(msg)
        # A full pipe already holds wake-ups enough: one is all the host needs.
        with contextlib.suppress(BlockingIOError):
            os.write(self._wake_w, b"x")

    def fileno(self) -> int:
        return self._wake_r

    def receive(self) -> list[Frame]:
        try:
            while os.read(self._wake_r, 4096):
                pass
        except BlockingIOError:
            pass
        with self._lock:
            msgs, self._inbox = self._inbox, []
        return [
            Frame(m.arbitration_id, bytes(m.data))
            for m in msgs
            if not (m.is_extended_id or m.is_remote_frame or m.is_error_frame or m.is_fd)
        ]

    def send(self, frame: Frame) -> None:
        msg = can.Message(
            arbitration_id=frame.arbitration_id, data=frame.data, is_extended_id=False
        )
        self._bus.send(msg)

    def send_bus_error(self) -> None:
        # CAN_ERR_PROT style error frame: what an adapter reports after a bit or form error.
        self._bus.send(can.Message(arbitration_id=0x08, is_error_frame=True, dlc=8, data=bytes(8)))

    def close(self) -> None:
        self._notifier.stop(timeout=1.0)
        self._bus.shutdown()
        for fd in (self._wake_r, self._wake_w):
            with contextlib.suppress(OSError):
                os.close(fd)
