"""The robot's side of the link: what the daemon publishes and serves.

One ``RobotLink`` per robot process. State, events and map changes go out through zenoh
advanced publishers that keep a cache and send heartbeats, so a monitor that joins late gets
the current state and recent events at once, and a monitor that lost samples learns of the
gap. The full map is served on request (``map`` queryable) from the ``snapshot`` callback;
commands arrive as queries on ``cmd`` and every one gets a ``CommandReply``.

Threading: ``snapshot`` and ``on_command`` are called from zenoh's threads, possibly at the
same time as the daemon's loop publishes; they must be quick and thread-safe. ``snapshot``
must return the map exactly as of its ``seq``: every change with a higher seq is published
after it (take the map's lock around both), which is what lets a monitor join the snapshot
and the change stream without a hole.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from types import TracebackType
from typing import Any

from tslam.link import keys
from tslam.link.config import LinkConfig
from tslam.link.errors import LinkError
from tslam.link.schemas import (
    Command,
    CommandReply,
    EventMsg,
    MapChange,
    MapSnapshot,
    RobotState,
    ScanMsg,
    command_problem,
    decode,
    encode,
)
from tslam.link.session import (
    ENCODING,
    close_session,
    log_failure,
    open_session,
    undeclare_quietly,
)

log = logging.getLogger("tslam.link")

#: Samples kept for late or reconnecting monitors, per stream.
STATE_HISTORY = 1
EVENT_HISTORY = 50
CHANGE_HISTORY = 200
#: Heartbeat period of the advanced publishers: how soon a monitor notices a lost last sample.
HEARTBEAT_S = 0.5


class RobotLink:
    """Publishes one robot's state, scans, map and events; serves its map and commands."""

    def __init__(
        self,
        robot: str,
        cfg: LinkConfig,
        epoch: str,
        *,
        snapshot: Callable[[], MapSnapshot],
        on_command: Callable[[Command], CommandReply],
    ) -> None:
        import zenoh
        import zenoh.ext as zext

        self.robot = keys.check_robot(robot)
        if not isinstance(epoch, str) or not epoch:
            raise LinkError(f"epoch must be a non-empty string, not {epoch!r}")
        self.epoch = epoch
        self._cfg = cfg
        self._snapshot = snapshot
        self._on_command = on_command
        self._lock = threading.Lock()
        self._closed = False
        self._entities: list[Any] = []
        self._state_pub: Any = None
        self._event_pub: Any = None
        self._change_pub: Any = None
        self._scan_pub: Any = None
        self._session: Any = None
        self._session = open_session(cfg)
        try:

            def advanced(leaf: str, history: int) -> Any:
                return zext.declare_advanced_publisher(
                    self._session,
                    keys.key(robot, leaf),
                    encoding=ENCODING,
                    # Low rate, latency-sensitive: sent at once rather than batched.
                    express=True,
                    cache=zext.CacheConfig(max_samples=history),
                    sample_miss_detection=zext.MissDetectionConfig(
                        heartbeat=HEARTBEAT_S, sporadic_heartbeat=None
                    ),
                    publisher_detection=True,
                )

            self._state_pub = advanced(keys.STATE, STATE_HISTORY)
            self._event_pub = advanced(keys.EVENTS, EVENT_HISTORY)
            self._change_pub = advanced(keys.MAP_CHANGES, CHANGE_HISTORY)
            # Scans are many and only the newest matters: drop under congestion, never block
            # the control loop for a slow monitor.
            self._scan_pub = self._session.declare_publisher(
                keys.key(robot, keys.SCAN),
                encoding=ENCODING,
                congestion_control=zenoh.CongestionControl.DROP,
                express=True,
            )
            self._map_q = self._session.declare_queryable(
                keys.key(robot, keys.MAP), self._serve_map, complete=True
            )
            self._cmd_q = self._session.declare_queryable(
                keys.key(robot, keys.CMD), self._serve_command, complete=True
            )
            # Declared last: a monitor that sees the robot online finds everything in place.
            self._token = self._session.liveliness().declare_token(keys.key(robot, keys.ALIVE))
            self._entities = [
                self._token,
                self._cmd_q,
                self._map_q,
                self._scan_pub,
                self._change_pub,
                self._event_pub,
                self._state_pub,
            ]
        except LinkError:
            self.close()
            raise
        except Exception as e:
            self.close()
            raise LinkError(f"cannot declare the link of robot {robot!r}: {e}") from None

    # -- publishing (from the daemon's loop) --------------------------------------------------

    def publish_state(self, s: RobotState) -> None:
        self._put(self._state_pub, s)

    def publish_scan(self, s: ScanMsg) -> None:
        self._put(self._scan_pub, s)

    def publish_map_change(self, c: MapChange) -> None:
        self._put(self._change_pub, c)

    def publish_event(self, e: EventMsg) -> None:
        self._put(self._event_pub, e)

    def _put(self, pub: Any, msg: Any) -> None:
        if self._closed or pub is None:
            return  # publishing while shutting down is not an error worth a crash
        data = encode(msg)
        try:
            pub.put(data)
        except Exception as e:
            if self._closed:
                return
            raise LinkError(f"cannot publish {type(msg).__name__}: {e}") from None

    # -- serving (from zenoh's threads) -------------------------------------------------------

    def _serve_map(self, query: Any) -> None:
        try:
            snap = self._snapshot()
            if not isinstance(snap, MapSnapshot):
                raise TypeError(f"snapshot() returned {type(snap).__name__}, not MapSnapshot")
            query.reply(keys.key(self.robot, keys.MAP), encode(snap), encoding=ENCODING)
        except Exception as e:
            log.warning("map snapshot failed: %s", e)
            try:
                query.reply_err(f"snapshot failed: {type(e).__name__}: {e}".encode())
            except Exception as e2:
                log.debug("reply_err: %s", e2)

    def _serve_command(self, query: Any) -> None:
        reply = self.handle_command_bytes(
            b"" if query.payload is None else query.payload.to_bytes()
        )
        try:
            query.reply(keys.key(self.robot, keys.CMD), encode(reply), encoding=ENCODING)
        except Exception as e:  # the querier gave up or went away
            log.debug("command reply: %s", e)

    def handle_command_bytes(self, data: bytes) -> CommandReply:
        """The reply to one command payload: validated here, then passed to ``on_command``.

        Never raises: a payload that does not decode, an unknown op or an exception inside
        ``on_command`` become a refusal with the reason, and ``on_command`` never sees a
        malformed command.
        """
        if not data:
            return CommandReply(id="", accepted=False, reason="malformed command: empty payload")
        try:
            cmd = decode(data, Command)
        except LinkError as e:
            return CommandReply(id="", accepted=False, reason=str(e))
        problem = command_problem(cmd)
        if problem is not None:
            return CommandReply(id=cmd.id, accepted=False, reason=problem)
        try:
            reply = self._on_command(cmd)
        except Exception as e:
            log_failure(f"on_command failed on {cmd}")
            return CommandReply(
                id=cmd.id, accepted=False, reason=f"robot error: {type(e).__name__}: {e}"
            )
        if not isinstance(reply, CommandReply):
            return CommandReply(
                id=cmd.id,
                accepted=False,
                reason=f"robot error: on_command returned {type(reply).__name__}",
            )
        return reply

    # -- lifecycle -----------------------------------------------------------------------------

    def close(self) -> None:
        """Withdraw the liveliness token and close the session; idempotent, bounded in time."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        # The token first, so monitors see the robot go offline before anything else stops.
        undeclare_quietly(*self._entities)
        session = self._session
        if session is not None and not close_session(session, self._cfg.open_timeout_s + 1.0):
            log.warning("zenoh session did not close within %.1f s", self._cfg.open_timeout_s + 1)

    def __enter__(self) -> RobotLink:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
