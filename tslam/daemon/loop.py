"""The daemon's control loop: the hal lifecycle around a fixed-rate loop of the arbiter,
the settled map saved after every change, the state published, operators' commands applied.

Order of things in one cycle, and why:
1. commands first, so an operator's stop acts before the next motion command;
2. read the robot, step the arbiter (or stand, when paused or stopped), command the drive;
3. a changed map is saved *before* it is published: what a monitor has seen is on disk;
4. beat the watchdogs, then wait for the next cycle.
Any hal error ends the run with the robot stopped: the drive is closed, which stops it.
"""

from __future__ import annotations

import contextlib
import math
import time
import uuid
from collections.abc import Callable
from typing import Any

from hal.errors import HalError
from hal.interfaces import Drive, Encoders, SonarRing
from hal.registry import create_backend
from hal.types import Odometry, SonarScan, Twist
from tslam.core.explorer import Explorer, Mode
from tslam.daemon.config import DaemonConfig
from tslam.daemon.mirror import MapMirror
from tslam.daemon.orders import Inbox, apply_command
from tslam.daemon.store import Orders, Store
from tslam.daemon.systemd import Notifier
from tslam.daemon.watchdog import Watchdog
from tslam.link.schemas import Command, CommandReply, EventMsg, RobotState, ScanMsg
from tslam.stopflag import StopFlag
from tslam.stopflag import stop_on_signals as on_signals


class DaemonError(RuntimeError):
    """The daemon cannot run or must stop; the message says why, the robot is stopped."""


class Daemon:
    def __init__(
        self,
        cfg: DaemonConfig,
        say: Callable[[str], None],
        notifier: Notifier | None = None,
    ) -> None:
        self.cfg = cfg
        self.say = say
        self.notifier = notifier or Notifier()
        self.store = Store(cfg.storage)
        self.epoch = uuid.uuid4().hex[:12]
        self.inbox = Inbox(answer_within_s=max(2.0, 10.0 / cfg.rate_hz))
        self.orders = Orders()
        self.error: str | None = None
        self._stop = StopFlag()
        self._event_seq = 0
        self._link: Any = None
        self._backend: Any = None

    def request_stop(self, why: str) -> None:
        """End the loop at the next cycle; safe from any thread and from a signal handler
        (the loop, not this, says so)."""
        self._stop.set(why)

    # ------------------------------------------------------------------ run
    def run(self) -> int:
        """Explore until stopped (or done, with ``exit_when_done``); the exit code."""
        cfg = self.cfg
        self.store.prepare()
        tmap = self.store.load_map()
        self.orders = self.store.load_orders()
        backend = create_backend(cfg.backend)
        if not all(isinstance(backend, c) for c in (Drive, Encoders, SonarRing)):
            backend.close()
            raise DaemonError(f"{cfg.source}: backend must provide drive, encoders and sonar")
        self._backend = backend
        explorer = Explorer(backend.limits, tmap=tmap)
        if tmap is not None:
            self.say(
                f"map loaded from {self.store.map_path}: {len(tmap.nodes())} nodes, "
                f"{len(tmap.edges())} edges; localizing against it"
            )
        mirror = MapMirror(cfg.robot, self.epoch, explorer)
        with contextlib.ExitStack() as stack:
            stack.callback(self._stop.close)
            stack.callback(self._shutdown, explorer)
            if cfg.link_enabled:
                self._link = self._open_link(mirror)
            with backend:
                self.say(f"robot {cfg.robot}: {cfg.backend['backend']} backend active, "
                         f"epoch {self.epoch}")  # fmt: skip
                dog = Watchdog(cfg.watchdog_s, self._on_stall)
                stack.callback(dog.close)
                dog.start()
                self.inbox.open = True
                self.notifier.ready(f"exploring as {cfg.robot}")
                try:
                    self._loop(backend, explorer, mirror, dog)
                except HalError as exc:
                    self.error = f"{type(exc).__name__}: {exc}"
                    self._publish_event(explorer, "error", self.error)
                    backend.stop()
                    raise DaemonError(f"hardware: {exc}") from None
        return 0

    def _loop(
        self,
        backend: Any,
        explorer: Explorer,
        mirror: MapMirror,
        dog: Watchdog,
    ) -> None:
        cfg = self.cfg
        pending_goal = self.orders.goal
        clock = backend.clock
        period = 1.0 / cfg.rate_hz
        simulated = cfg.backend["backend"] == "sim"
        t0 = clock.now()
        wall0 = time.monotonic()
        next_t = t0
        next_status = t0
        next_ping = 0.0
        shown = len(explorer.notes)
        cycle = 0
        while not self._stop.is_set():
            now = clock.now()
            for reply in self.inbox.serve(lambda c: self._command(c, explorer, backend)):
                what = "accepted" if reply.accepted else f"refused: {reply.reason}"
                self._publish_event(explorer, "command", f"command {reply.id} {what}")
            if pending_goal is not None and explorer.mode not in (Mode.LOST, Mode.DISAMBIGUATE):
                # An order acknowledged before a restart is carried out once the robot knows
                # where it is again.
                reason = explorer.goto(pending_goal)
                if reason is not None:
                    self._publish_event(explorer, "command", f"goal dropped: {reason}")
                    self.orders = Orders(self.orders.halted, None)
                    self.store.save_orders(self.orders)
                pending_goal = None
            odo = backend.odometry()
            scan = backend.scan()
            status = backend.status()
            if self.orders.halted is None:
                twist, _ = explorer.step(scan, odo, status, now)
            else:
                twist = Twist()
            backend.command(twist)
            change = mirror.refresh(explorer)
            self.store.save_settled(explorer, change is not None)
            if change is not None and self._link is not None:
                self._link.publish_map_change(change)
            for note in explorer.notes[shown:]:
                self._publish_event(explorer, "note", note.text, stamp=note.stamp_s - t0)
            shown = len(explorer.notes)
            if self._link is not None:
                self._link.publish_state(self._state(explorer, mirror, odo, now))
                if cycle % cfg.scan_every == 0:
                    self._link.publish_scan(_scan_msg(cfg.robot, scan))
            if now >= next_status:
                self._status_line(explorer, now - t0)
                next_status += 60.0
            dog.beat()
            wall = time.monotonic()
            if self.notifier.watchdog_interval_s is not None and wall >= next_ping:
                self.notifier.ping()
                next_ping = wall + self.notifier.watchdog_interval_s
            if explorer.done and cfg.exit_when_done:
                self._status_line(explorer, now - t0)
                break
            cycle += 1
            next_t += period
            if simulated:
                if cfg.time_scale > 0:
                    ahead = wall0 + (next_t - t0) / cfg.time_scale - time.monotonic()
                    if ahead > 0:
                        self._stop.wait(ahead)
            elif next_t < clock.now() - period:
                next_t = clock.now()  # overran: do not try to catch up with a burst
            clock.sleep(max(0.0, next_t - clock.now()))
        if self._stop.reason is not None:
            self.say(f"{self._stop.reason}: stopping the robot and saving")

    # ------------------------------------------------------------------ commands
    def _command(self, cmd: Command, explorer: Explorer, backend: Any) -> CommandReply:
        orders, reason = apply_command(cmd, explorer, self.orders)
        if reason is not None:
            return CommandReply(cmd.id, False, reason)
        if orders.halted is not None:
            backend.stop()
        self.orders = orders
        self.store.save_orders(orders)
        desc = cmd.op if cmd.node is None else f"{cmd.op} {cmd.node}"
        self.say(f"operator: {desc}")
        return CommandReply(cmd.id, True, "")

    # ------------------------------------------------------------------ publishing
    def _open_link(self, mirror: MapMirror) -> Any:
        from tslam.link.robot import RobotLink  # zenoh loads only when the link is wanted

        return RobotLink(
            self.cfg.robot, self.cfg.link, self.epoch,
            snapshot=mirror.snapshot, on_command=self.inbox.submit,
        )  # fmt: skip

    def _publish_event(
        self, explorer: Explorer, kind: str, text: str, stamp: float | None = None
    ) -> None:
        self._event_seq += 1
        when = "" if stamp is None else f"t={stamp:7.1f} s  "
        self.say(f"{when}{text}")
        if self._link is not None:
            self._link.publish_event(
                EventMsg(self.cfg.robot, self.epoch, self._event_seq,
                         float(explorer._now if stamp is None else stamp), kind, text[:4096])
            )  # fmt: skip

    def _state(
        self, explorer: Explorer, mirror: MapMirror, odo: Odometry, now: float
    ) -> RobotState:
        tmap = explorer.map
        edge = None
        if explorer.leaving is not None and tmap.has_node(explorer.leaving[0]):
            n, p = explorer.leaving
            ports = tmap.node(n).ports
            edge = ports[p] if p < len(ports) else None
        hyps = [
            ", ".join(f"{f}={o}" for f, (o, _) in sorted(h.mapping.items()))
            for h in explorer.hyps.live
        ]
        return RobotState(
            robot=self.cfg.robot, epoch=self.epoch, stamp_s=float(now),
            behaviour=explorer.tracer.behaviour.value, mode=explorer.mode.value,
            paused=self.orders.halted is not None, done=explorer.done,
            current_node=explorer.here if explorer.mode is not Mode.LOST else None,
            current_edge=edge, goal_node=explorer.goal,
            x=float(odo.x_m), y=float(odo.y_m), theta=float(odo.heading_rad), hypotheses=hyps[:20],
            map_seq=mirror.seq, map_nodes=len(tmap.nodes()), map_edges=len(tmap.edges()),
            unexplored=len(explorer.unexplored()), error=self.error, event_seq=self._event_seq,
        )  # fmt: skip

    def _status_line(self, explorer: Explorer, t: float) -> None:
        halted = f" ({self.orders.halted})" if self.orders.halted else ""
        self.say(
            f"t={t:7.1f} s  {explorer.mode.value:12s}{halted} {len(explorer.map.nodes())} nodes "
            f"{len(explorer.map.edges())} edges, {len(explorer.unexplored())} departures to "
            "explore"
        )
        self.notifier.status(f"{explorer.mode.value}: {len(explorer.map.nodes())} nodes")

    def _on_stall(self, stalled_s: float) -> None:
        self.say(f"control loop stalled for {stalled_s:.2f} s: drive stopped")
        backend = self._backend
        if backend is not None:
            with contextlib.suppress(HalError):
                backend.stop()

    def _shutdown(self, explorer: Explorer) -> None:
        self.notifier.stopping()
        self.inbox.close()
        try:
            self.store.save_settled(explorer)
            self.store.save_orders(self.orders)
        finally:
            if self._link is not None:
                self._link.close()
                self._link = None


def _scan_msg(robot: str, scan: SonarScan) -> ScanMsg:
    ranges = [float(r) if math.isfinite(r) else None for r in scan.ranges_m]
    stamp = float(scan.stamps_s.max()) if len(scan.stamps_s) else 0.0
    return ScanMsg(robot=robot, stamp_s=stamp, ranges_m=ranges)


def stop_on_signals(daemon: Daemon) -> contextlib.AbstractContextManager[None]:
    """SIGTERM and SIGINT end the loop at the next cycle; the robot stops, the map is saved."""
    return on_signals(daemon.request_stop)
