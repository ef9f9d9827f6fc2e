"""One request, one reply, over whatever ``serial.serial_for_url`` opens; the driver's only I/O.

What goes wrong on a serial line and what this module does about it:

* no reply in time                    -> retransmit (idempotent requests), then DeviceTimeoutError
* checksum error, framing error,      -> the rest of the reply is awaited briefly, then the
  garbage, a truncated reply             request is retransmitted; then hal ProtocolError
* NAK, a malformed payload, an echo   -> hal ProtocolError (retransmitted like the above)
* the port vanishes (SerialException, -> the port is reopened with exponential backoff; when it
  termios.error, OSError)                is back, ``on_reconnect`` runs (the device reconfigures
                                         the robot and stops it) and the request is resent once;
                                         if it stays away, LinkLostError

Every error names the port, the request and the fault. The original client never retransmits;
this one does, but only requests that mean the same thing when received twice (the caller says
which), so a lost reply to a relative move never makes the robot move twice.
"""

from __future__ import annotations

import contextlib
import termios
import time
from collections.abc import Callable

import serial

from drivers.nomad200.codec import (
    DEFAULT_MAX_LEN,
    ChecksumError,
    Command,
    FrameDecoder,
    LengthError,
    NakReply,
    Reply,
    StateMask,
    UnexpectedReplyError,
    decode_reply,
)
from drivers.nomad200.errors import ProtocolError as CodecError
from drivers.nomad200.opcodes import describe
from hal.errors import (
    CommunicationError,
    DeviceTimeoutError,
    LinkLostError,
)
from hal.errors import (
    ProtocolError as HalProtocolError,
)

#: What pyserial and the OS raise when a port goes away: USB unplugged, pty closed, socket reset.
LINK_ERRORS: tuple[type[BaseException], ...] = (serial.SerialException, termios.error, OSError)
#: How long one blocking read may last; short, so deadlines are kept without reconfiguring the
#: port's timeout (which costs a tcsetattr) for every read.
READ_SLICE_S = 0.02
#: After bytes that are not a frame, how long the line must stay quiet before the attempt is
#: given up (a good reply may still follow line noise).
QUIET_S = 0.05
MAX_BACKOFF_S = 2.0


class _FaultError(Exception):
    """One failed exchange, and the hal error to raise if it is the last."""

    def __init__(self, kind: str, detail: str, error: type[CommunicationError]) -> None:
        super().__init__(f"{kind}: {detail}")
        self.kind = kind
        self.detail = detail
        self.error = error


class _VanishedError(Exception):
    """The port went away under an exchange."""


class Link:
    """A serial line to one robot. Not thread-safe: the backend's lock serialises callers."""

    def __init__(
        self,
        url: str,
        baud: int,
        *,
        reply_timeout_s: float = 1.0,
        retries: int = 2,
        reconnect_timeout_s: float = 10.0,
        reconnect_backoff_s: float = 0.1,
        name: str = "nomad200",
        opener: Callable[..., serial.SerialBase] = serial.serial_for_url,
        monotonic: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        self.url = url
        self.baud = baud
        self.reply_timeout_s = reply_timeout_s
        self.retries = retries
        self.reconnect_timeout_s = reconnect_timeout_s
        self.reconnect_backoff_s = reconnect_backoff_s
        self.name = name
        #: Called once the port is back after vanishing, before the request is resent.
        self.on_reconnect: Callable[[], None] | None = None
        #: Counters, for tests and benchmarks.
        self.retransmissions = 0
        self.reconnects = 0
        self._opener = opener
        self._monotonic = monotonic
        self._sleep = sleep
        self._port: serial.SerialBase | None = None
        self._reconnecting = False

    @property
    def who(self) -> str:
        return f"{self.name} {self.url}"

    @property
    def is_open(self) -> bool:
        return self._port is not None

    # ------------------------------------------------------------------ open and close
    def open(self) -> None:
        """Open the port once; a port that cannot be opened is LinkLostError, no retrying."""
        try:
            self._open()
        except LINK_ERRORS as exc:
            raise LinkLostError(f"{self.who}: cannot open the port: {exc}") from exc

    def _open(self) -> None:
        self.close()
        port = self._opener(
            self.url,
            baudrate=self.baud,
            bytesize=serial.EIGHTBITS,
            parity=serial.PARITY_NONE,
            stopbits=serial.STOPBITS_ONE,
            xonxoff=False,
            rtscts=False,
            dsrdtr=False,
            timeout=READ_SLICE_S,
            write_timeout=self.reply_timeout_s,
        )
        self._port = port

    def close(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            # Closing a port that already vanished: nothing left to release.
            with contextlib.suppress(*LINK_ERRORS):
                port.close()

    # ------------------------------------------------------------------ requests
    def request(
        self,
        command: Command,
        mask: StateMask,
        *,
        idempotent: bool = True,
        timeout_s: float | None = None,
        max_len: int = DEFAULT_MAX_LEN,
        accept: Callable[[Reply], bool] | None = None,
        retries: int | None = None,
        reconnect: bool = True,
    ) -> Reply:
        """Send ``command`` and return its reply, read with ``mask``.

        ``max_len`` bounds the reply's LEN (the caller knows how long a state reply is), so a
        corrupted length is rejected at once instead of waited for. ``accept`` may refuse a
        reply (one from before a retransmission, say); the wait then goes on. Non-idempotent
        requests are sent once, and not resent after a reconnection. ``retries`` overrides the
        link's count; ``reconnect=False`` gives up at once if the port has vanished (closing).
        """
        timeout = self.reply_timeout_s if timeout_s is None else timeout_s
        retries = self.retries if retries is None else retries
        attempts = 1 + (retries if idempotent else 0)
        tries = 0
        fault: _FaultError | None = None
        while tries < attempts:
            tries += 1
            try:
                return self._exchange(command, mask, timeout, max_len, accept)
            except _FaultError as exc:
                fault = exc
                if tries < attempts:
                    self.retransmissions += 1
            except _VanishedError as exc:
                if self._reconnecting:
                    raise
                if not reconnect:
                    raise LinkLostError(
                        f"{self.who}: the link vanished during {describe(command.OPCODE)} ({exc})"
                    ) from exc
                self._reconnect(exc, command)
                if not idempotent:
                    raise LinkLostError(
                        f"{self.who}: the link vanished during {describe(command.OPCODE)} "
                        f"({exc}); it is back and the robot was stopped, but the request was "
                        "not resent because it is not safe to repeat"
                    ) from exc
                tries -= 1  # the reconnection earns the request a fresh attempt
        assert fault is not None
        raise fault.error(
            f"{self.who}: {fault.kind} for {describe(command.OPCODE)} after {tries} "
            f"attempt(s): {fault.detail}"
        ) from fault

    def _exchange(
        self,
        command: Command,
        mask: StateMask,
        timeout: float,
        max_len: int,
        accept: Callable[[Reply], bool] | None,
    ) -> Reply:
        port = self._port
        if port is None:
            raise _VanishedError("the port is closed")
        request = command.to_frame()
        try:
            port.reset_input_buffer()  # as the original client does: a stale reply is no answer
            port.write(request.encode())
        except serial.SerialTimeoutException as exc:
            raise _FaultError("write timeout", str(exc), DeviceTimeoutError) from exc
        except LINK_ERRORS as exc:
            raise _VanishedError(str(exc) or type(exc).__name__) from exc
        decoder = FrameDecoder(max_len=max_len)
        deadline = self._monotonic() + timeout
        quiet_until: float | None = None
        received = 0
        ignored: list[str] = []
        while True:
            now = self._monotonic()
            if now >= deadline or (quiet_until is not None and now >= quiet_until):
                break
            try:
                chunk = port.read(max(1, port.in_waiting))
            except LINK_ERRORS as exc:
                raise _VanishedError(str(exc) or type(exc).__name__) from exc
            if not chunk:
                continue
            received += len(chunk)
            for frame in decoder.feed(chunk):
                try:
                    reply = decode_reply(frame, mask, request=command.OPCODE, max_len=max_len)
                except UnexpectedReplyError as exc:
                    ignored.append(str(exc))  # a late answer to an earlier request
                    continue
                except CodecError as exc:
                    if frame == request:
                        raise _FaultError(
                            "echo",
                            "the line sent our own request back (a loopback or an echoing "
                            "modem, not a robot)",
                            HalProtocolError,
                        ) from exc
                    raise _FaultError("malformed reply", str(exc), HalProtocolError) from exc
                if isinstance(reply, NakReply):
                    raise _FaultError("NAK", "the robot refused the request", HalProtocolError)
                if accept is not None and not accept(reply):
                    ignored.append("a stale reply (its clock is behind one already seen)")
                    continue
                return reply
            if decoder.error_count:
                quiet_until = self._monotonic() + QUIET_S
        raise self._classify(decoder, received, ignored, timeout)

    @staticmethod
    def _classify(
        decoder: FrameDecoder, received: int, ignored: list[str], timeout: float
    ) -> _FaultError:
        if decoder.error_count:
            first = decoder.errors[0]
            if isinstance(first, ChecksumError):
                return _FaultError("checksum error", str(first), HalProtocolError)
            if isinstance(first, LengthError):
                return _FaultError("framing error", f"impossible length: {first}", HalProtocolError)
            kind = "garbage" if "start byte" in str(first) else "framing error"
            detail = f"{decoder.discarded} byte(s) dropped: {first}"
            return _FaultError(kind, detail, HalProtocolError)
        if decoder.pending:
            return _FaultError(
                "truncated reply",
                f"{decoder.pending} byte(s) of a frame, then nothing for {timeout:g} s",
                HalProtocolError,
            )
        note = f" (ignored: {'; '.join(ignored)})" if ignored else ""
        return _FaultError(
            "reply timeout", f"no reply within {timeout:g} s{note}", DeviceTimeoutError
        )

    # ------------------------------------------------------------------ reconnecting
    def _reconnect(self, cause: _VanishedError, command: Command) -> None:
        """Reopen the port with backoff until it answers, or raise LinkLostError."""
        self.close()
        what = f"{self.who}: the link vanished during {describe(command.OPCODE)} ({cause})"
        if self.reconnect_timeout_s <= 0:
            raise LinkLostError(f"{what}; reconnecting is disabled") from cause
        deadline = self._monotonic() + self.reconnect_timeout_s
        delay = self.reconnect_backoff_s
        last: BaseException = cause
        while True:
            try:
                self._open()
                self._reconnecting = True
                try:
                    if self.on_reconnect is not None:
                        self.on_reconnect()
                finally:
                    self._reconnecting = False
                self.reconnects += 1
                return
            except (_VanishedError, CommunicationError, *LINK_ERRORS) as exc:
                last = exc
                self.close()
            if self._monotonic() + delay > deadline:
                raise LinkLostError(
                    f"{what}; still gone after {self.reconnect_timeout_s:g} s of reconnecting "
                    f"(last: {last}); the robot's own motion timeout stops it"
                ) from cause
            self._sleep(delay)
            delay = min(2 * delay, MAX_BACKOFF_S)
