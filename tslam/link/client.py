"""A monitor's side of the link: one robot's state, map and events, kept whole.

The map is rebuilt from a full snapshot (the robot's ``map`` queryable) and then kept by the
numbered changes that follow it. A snapshot is fetched at start, after any gap (a change whose
seq is not the next one, or a miss reported by zenoh's advanced subscriber), when the robot
comes back online, and when its epoch changes (the daemon restarted); changes that arrive
during the fetch are buffered and those newer than the snapshot applied after it. The fetch
runs in a worker thread, never in a zenoh callback, which must not block.

Everything reaches this object from zenoh's threads; one lock guards the view, and
``view()`` hands out a copy, so callers never see a half-applied change.
"""

from __future__ import annotations

import itertools
import logging
import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from types import TracebackType
from typing import Any

from tslam.link import keys
from tslam.link.config import LinkConfig
from tslam.link.errors import LinkError
from tslam.link.schemas import (
    Command,
    CommandReply,
    EdgeMsg,
    EventMsg,
    MapChange,
    MapSnapshot,
    NodeMsg,
    RobotState,
    ScanMsg,
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

EVENTS_KEPT = 50
#: Changes held while a snapshot is on its way; past this the fetch is simply redone.
BUFFER_LIMIT = 20_000
SNAPSHOT_TIMEOUT_S = 5.0
#: How often the worker retries a snapshot while the map is not in step with the robot.
RETRY_S = 0.5

NO_REPLY = "no reply within {t:g} s: not authorised, or the robot is unreachable"


@dataclass(frozen=True)
class MonitorView:
    """A consistent copy of what the monitor knows of one robot."""

    robot: str
    online: bool
    state: RobotState | None
    nodes: dict[int, NodeMsg]
    edges: dict[int, EdgeMsg]
    epoch: str | None  # of the map held, None before the first snapshot
    seq: int  # the map version held
    synced: bool  # the map is the robot's as of seq (False while a gap is being repaired)
    events: list[EventMsg]  # the last EVENTS_KEPT, oldest first
    last_scan: ScanMsg | None
    gaps: int  # gaps detected and repaired by a fresh snapshot
    snapshots: int  # snapshots fetched (one at start, one per gap, restart or return)
    malformed: int  # samples that did not decode (dropped)
    last_error: str | None = None
    robots_alive: list[str] = field(default_factory=list)


class MonitorClient:
    """Follows one robot over zenoh; ``view()`` any time, ``on_update`` after each change.

    ``on_event`` (optional) receives each new event once, in arrival order, before
    ``on_update``; both run on zenoh's or the worker's thread and must not block.
    """

    def __init__(
        self,
        robot: str,
        cfg: LinkConfig,
        on_update: Callable[[], None] | None = None,
        *,
        on_event: Callable[[EventMsg], None] | None = None,
    ) -> None:
        import zenoh.ext as zext

        self.robot = keys.check_robot(robot)
        self._cfg = cfg
        self._on_update = on_update
        self._on_event_cb = on_event
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._closing = False
        self._closed = False
        # -- the view, guarded by _lock
        self._alive: set[str] = set()
        self._state: RobotState | None = None
        self._nodes: dict[int, NodeMsg] = {}
        self._edges: dict[int, EdgeMsg] = {}
        self._epoch: str | None = None
        self._seq = 0
        self._synced = False
        self._need_sync = True
        self._gap_pending = False
        self._buffer: list[tuple[int, MapChange]] = []
        self._arrivals = itertools.count()
        self._events: deque[EventMsg] = deque(maxlen=EVENTS_KEPT)
        self._event_ids: deque[tuple[str, int]] = deque(maxlen=4 * EVENTS_KEPT)
        self._scan: ScanMsg | None = None
        self._gaps = 0
        self._snapshots = 0
        self._malformed = 0
        self._last_error: str | None = None
        self._entities: list[Any] = []
        self._listeners: list[Any] = []
        self._session: Any = None
        self._worker: threading.Thread | None = None

        self._session = open_session(cfg)
        try:
            s = self._session
            self._entities.append(
                s.liveliness().declare_subscriber(keys.ALL_ALIVE, self._on_alive, history=True)
            )

            def advanced(leaf: str, history: int, fn: Callable[[Any], None]) -> Any:
                sub = zext.declare_advanced_subscriber(
                    s,
                    keys.key(robot, leaf),
                    fn,
                    history=zext.HistoryConfig(detect_late_publishers=True, max_samples=history),
                    recovery=zext.RecoveryConfig(heartbeat=True, periodic_queries=None),
                    subscriber_detection=True,
                )
                self._listeners.append(sub.sample_miss_listener(self._on_miss))
                self._entities.append(sub)
                return sub

            advanced(keys.STATE, 1, self._on_state)
            advanced(keys.EVENTS, EVENTS_KEPT, self._on_event)
            advanced(keys.MAP_CHANGES, 1000, self._on_change)
            self._entities.append(s.declare_subscriber(keys.key(robot, keys.SCAN), self._on_scan))
        except Exception as e:
            self.close()
            raise LinkError(f"cannot follow robot {robot!r}: {e}") from None
        self._worker = threading.Thread(
            target=self._run, name=f"tslam-monitor-{robot}", daemon=True
        )
        self._worker.start()
        self._wake.set()

    # -- the public side ----------------------------------------------------------------------

    def view(self) -> MonitorView:
        with self._lock:
            return MonitorView(
                robot=self.robot,
                online=self.robot in self._alive,
                state=self._state,
                nodes=dict(self._nodes),
                edges=dict(self._edges),
                epoch=self._epoch,
                seq=self._seq,
                synced=self._synced and not self._need_sync,
                events=list(self._events),
                last_scan=self._scan,
                gaps=self._gaps,
                snapshots=self._snapshots,
                malformed=self._malformed,
                last_error=self._last_error,
                robots_alive=sorted(self._alive),
            )

    def robots(self) -> list[str]:
        """Robots whose liveliness token is up, seen through this session."""
        with self._lock:
            return sorted(self._alive)

    def command(self, cmd: Command, timeout_s: float = 2.0) -> CommandReply:
        """Send ``cmd`` and wait for the robot's acknowledgement or refusal.

        Never raises for the network's sake: no reply (the ACL dropped the query, or the robot
        is unreachable), an error reply or an undecodable reply come back as a refusal.
        """
        reply = self.command_bytes(encode(cmd), timeout_s)
        if reply.id not in ("", cmd.id) and reply.accepted:
            return CommandReply(cmd.id, False, f"reply was for command {reply.id!r}")
        return reply

    def command_bytes(self, payload: bytes, timeout_s: float = 2.0) -> CommandReply:
        """Send raw bytes as a command (what a faulty or hostile sender would): for tests."""
        if self._closed:
            return CommandReply("", False, "monitor closed")
        try:
            replies = self._session.get(
                keys.key(self.robot, keys.CMD),
                payload=payload,
                encoding=ENCODING,
                timeout=timeout_s,
            )
            for reply in replies:
                if reply.ok is not None:
                    try:
                        return decode(reply.ok.payload.to_bytes(), CommandReply)
                    except LinkError as e:
                        return CommandReply("", False, f"unreadable reply: {e}")
                err = reply.err
                text = err.payload.to_string() if err is not None else "unknown error"
                return CommandReply("", False, f"refused by the network: {text}")
        except Exception as e:
            return CommandReply("", False, f"not sent: {e}")
        return CommandReply("", False, NO_REPLY.format(t=timeout_s))

    def fetch_snapshot(self, timeout_s: float = SNAPSHOT_TIMEOUT_S) -> MapSnapshot:
        """The robot's full map now; raises ``LinkError`` saying why there is none."""
        try:
            replies = self._session.get(keys.key(self.robot, keys.MAP), timeout=timeout_s)
            problem = f"no map from robot {self.robot!r} within {timeout_s:g} s"
            # The first reply settles it: zenoh 1.10 keeps the query open until its timeout
            # after an error reply, so waiting for the end of the replies would stall.
            for reply in replies:
                if reply.ok is None:
                    err = reply.err
                    problem = "map refused: " + (err.payload.to_string() if err else "?")
                    break
                snap = decode(reply.ok.payload.to_bytes(), MapSnapshot)
                if snap.robot != self.robot:
                    problem = f"map snapshot names robot {snap.robot!r}, not {self.robot!r}"
                    break
                return snap
        except LinkError:
            raise
        except Exception as e:
            raise LinkError(f"map fetch failed: {e}") from None
        raise LinkError(problem)

    def resync(self) -> None:
        """Ask for a fresh snapshot soon (the worker fetches it)."""
        with self._lock:
            self._need_sync = True
        self._wake.set()

    def close(self) -> None:
        if self._closed:
            return
        self._closed = self._closing = True
        self._wake.set()
        undeclare_quietly(*self._listeners, *self._entities)
        if self._worker is not None and self._worker is not threading.current_thread():
            self._worker.join(timeout=SNAPSHOT_TIMEOUT_S + 1)
        if self._session is not None:
            close_session(self._session, self._cfg.open_timeout_s + 1.0)

    def __enter__(self) -> MonitorClient:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    # -- zenoh callbacks (zenoh threads: quick, never blocking) ---------------------------------

    def _decode(self, sample: Any, cls: type) -> Any:
        try:
            return decode(sample.payload.to_bytes(), cls)
        except LinkError as e:
            with self._lock:
                self._malformed += 1
                self._last_error = f"{sample.key_expr}: {e}"
            return None

    def _on_alive(self, sample: Any) -> None:
        import zenoh

        robot = keys.robot_of(str(sample.key_expr))
        if robot is None:
            return
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                back = robot == self.robot and robot not in self._alive
                self._alive.add(robot)
                if back and self._epoch is not None:
                    # Back after an absence (our link or the robot went away): whatever
                    # happened meanwhile may be lost, so it counts as a gap, repaired by
                    # a snapshot (a restart shows as a new epoch and is not counted).
                    self._need_sync = True
                    self._gap_pending = True
            else:
                self._alive.discard(robot)
        self._wake.set()
        self._notify()

    def _on_state(self, sample: Any) -> None:
        s = self._decode(sample, RobotState)
        if s is None or s.robot != self.robot:
            return
        with self._lock:
            old = self._state
            if old is not None and old.epoch == s.epoch and s.stamp_s < old.stamp_s:
                return  # a cached sample replayed after a newer live one
            self._state = s
            if self._epoch is not None and s.epoch != self._epoch:
                self._need_sync = True  # the daemon restarted
                self._wake.set()
        self._notify()

    def _on_event(self, sample: Any) -> None:
        e = self._decode(sample, EventMsg)
        if e is None or e.robot != self.robot:
            return
        with self._lock:
            ident = (e.epoch, e.seq)
            if ident in self._event_ids:
                return
            self._event_ids.append(ident)
            self._events.append(e)
        if self._on_event_cb is not None and not self._closing:
            try:
                self._on_event_cb(e)
            except Exception:
                log_failure("on_event failed")
        self._notify()

    def _on_scan(self, sample: Any) -> None:
        s = self._decode(sample, ScanMsg)
        if s is None or s.robot != self.robot:
            return
        with self._lock:
            self._scan = s
        self._notify()

    def _on_miss(self, miss: Any) -> None:
        log.info("robot %s: %s samples missed", self.robot, getattr(miss, "nb", "?"))
        with self._lock:
            self._gap_pending = True
            self._need_sync = True
        self._wake.set()

    def _on_change(self, sample: Any) -> None:
        c = self._decode(sample, MapChange)
        if c is None or c.robot != self.robot:
            return
        with self._lock:
            if self._need_sync or not self._synced:
                if len(self._buffer) < BUFFER_LIMIT:
                    self._buffer.append((next(self._arrivals), c))
                return
            if c.epoch != self._epoch:
                self._need_sync = True
                self._buffer.append((next(self._arrivals), c))
            elif c.seq <= self._seq:
                return  # already in the map (a replay from the publisher's cache)
            elif c.seq == self._seq + 1:
                self._apply(c)
            else:
                self._gap_pending = True
                self._need_sync = True
                self._buffer.append((next(self._arrivals), c))
        if self._need_sync:
            self._wake.set()
        self._notify()

    # -- the worker ------------------------------------------------------------------------

    def _run(self) -> None:
        while not self._closing:
            self._wake.wait(RETRY_S)
            self._wake.clear()
            if self._closing:
                break
            with self._lock:
                need = self._need_sync or not self._synced
            if need:
                self._sync_once()

    def _sync_once(self) -> None:
        with self._lock:
            self._synced = False
            self._need_sync = False
            started = next(self._arrivals)
        try:
            snap = self.fetch_snapshot()
        except LinkError as e:
            with self._lock:
                self._last_error = str(e)
                self._need_sync = True
            return
        with self._lock:
            had_map = self._epoch is not None
            if had_map and snap.epoch == self._epoch and snap.seq > self._seq:
                # The robot moved on while we held an older map: that is a gap, now repaired.
                self._gap_pending = True
            if snap.epoch != self._epoch:
                self._gap_pending = False  # a new daemon: a fresh map, not a repair
            self._nodes = {n.id: n for n in snap.nodes}
            self._edges = {e.id: e for e in snap.edges}
            self._epoch, self._seq = snap.epoch, snap.seq
            self._snapshots += 1
            pending = sorted(
                (c for _, c in self._buffer if c.epoch == snap.epoch and c.seq > snap.seq),
                key=lambda c: c.seq,
            )
            foreign = [c for n, c in self._buffer if c.epoch != snap.epoch and n > started]
            self._buffer = []
            ok = not foreign  # a newer epoch began during the fetch: fetch again
            for c in pending:
                if c.seq <= self._seq:
                    continue
                if c.seq != self._seq + 1:
                    ok = False
                    break
                self._apply(c)
            if ok and not self._need_sync:
                self._synced = True
                self._last_error = None
                if self._gap_pending:
                    self._gaps += 1
                    self._gap_pending = False
            else:
                self._need_sync = True
                self._wake.set()
        self._notify()

    def _apply(self, c: MapChange) -> None:
        for nid in c.remove_nodes:
            self._nodes.pop(nid, None)
        for eid in c.remove_edges:
            self._edges.pop(eid, None)
        for n in c.upsert_nodes:
            self._nodes[n.id] = n
        for e in c.upsert_edges:
            self._edges[e.id] = e
        self._seq = c.seq

    def _notify(self) -> None:
        if self._on_update is None or self._closing:
            return
        try:
            self._on_update()
        except Exception:
            log_failure("on_update failed")
