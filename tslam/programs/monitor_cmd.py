"""``tslam monitor``: watch and steer a robot over the link, from a terminal, a script or a browser.

    tslam monitor --connect tcp/ROBOT:7447                      # live terminal view
    tslam monitor --connect E --robot R --json --once           # one snapshot as JSON
    tslam monitor --connect E --robot R --command goto --node 4 # one command, its reply
    tslam monitor --connect E --web 8080                        # http://127.0.0.1:8080/

The monitor opens a zenoh session in client mode to ENDPOINT (the robot, or a router for a
fleet) and follows one robot through ``tslam.link.client.MonitorClient``. Exit codes: 0 done
(a command accepted), 1 the robot was not seen in time or refused the command, 2 a mistake
in the options, 130 interrupted before anything was shown.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import sys
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from typing import TYPE_CHECKING, Any

from tslam.programs.cli import UserError
from tslam.programs.monitor_view import (
    CLEAR,
    events_caught_up,
    map_complete,
    render_lines,
    snapshot,
)
from tslam.programs.monitor_web import OPS, MonitorWeb, Notifier

if TYPE_CHECKING:
    from tslam.link.client import MonitorClient
    from tslam.link.config import LinkConfig

#: The terminal is redrawn at most this often: a burst of changes is one redraw.
REDRAW_S = 0.25
#: After the first robot appears, how long to listen for others before following it alone.
DISCOVERY_SETTLE_S = 0.5
#: ``tcp/HOST:PORT`` (and udp, tls, quic, ws); HOST may be a bracketed IPv6 address.
_IP_ENDPOINT = re.compile(r"^(tcp|udp|tls|quic|ws)/(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):(\d+)$")


_RUST_LOCATION = re.compile(r"\s+at /\S+\.rs:\d+\.?")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "monitor", help="watch and steer a robot over the link (terminal, JSON, web page)"
    )
    p.add_argument(
        "--connect", action="append", default=[], metavar="ENDPOINT",
        help="zenoh endpoint of the robot or router, e.g. tcp/127.0.0.1:7447 (repeatable; "
        "optional when --config names the endpoints)",
    )  # fmt: skip
    p.add_argument("--robot", help="robot name (default: the only robot online)")
    p.add_argument("--user", help="operator or viewer name (zenoh usrpwd authentication)")
    p.add_argument("--password", help="password for --user (visible to ps: prefer --credentials)")
    p.add_argument(
        "--credentials", metavar="FILE",
        help="file holding one user:password line (e.g. ~/.config/tslam/credentials, chmod 600)",
    )  # fmt: skip
    p.add_argument("--config", metavar="FILE.json5", help="zenoh configuration file to start from")
    p.add_argument(
        "--json", action="store_true",
        help="JSON instead of text (without --once: one object per line, per change)",
    )  # fmt: skip
    p.add_argument("--once", action="store_true", help="print one snapshot and exit")
    p.add_argument(
        "--timeout", type=float, default=5.0,
        help="seconds to wait for the robot (and its map, or a command reply); default 5",
    )  # fmt: skip
    p.add_argument("--command", choices=OPS, help="send one command and print the reply")
    p.add_argument("--node", type=int, help="node id for --command goto")
    p.add_argument("--web", type=int, metavar="PORT", help="serve a live web page on PORT")
    p.add_argument("--bind", default="127.0.0.1", help="address for --web (default 127.0.0.1)")
    p.set_defaults(run=_run)


# -- options ---------------------------------------------------------------------------------
def _check_args(args: argparse.Namespace) -> None:
    for ep in args.connect:
        if not _IP_ENDPOINT.match(ep) and not ep.startswith("unixsock-stream/"):
            raise UserError(f"--connect {ep!r} is not an endpoint like tcp/127.0.0.1:7447")
        m = _IP_ENDPOINT.match(ep)
        if m and not 0 < int(m.group(3)) < 65536:
            raise UserError(f"--connect {ep!r}: port must be 1-65535")
    if not 0 < args.timeout <= 3600:
        raise UserError(f"--timeout must be in (0, 3600] seconds, got {args.timeout}")
    if (args.user is None) != (args.password is None):
        raise UserError("--user and --password go together")
    if args.credentials is not None and args.user is not None:
        raise UserError("give either --user/--password or --credentials, not both")
    if not args.connect and args.config is None:
        raise UserError("--connect ENDPOINT is needed (or --config FILE.json5 naming endpoints)")
    modes = [m for m in ("--command", "--web") if getattr(args, m[2:]) is not None]
    if len(modes) > 1 or (modes and args.once):
        raise UserError(f"{' and '.join([*modes, '--once'][:2])} cannot be combined")
    if args.command == "goto" and args.node is None:
        raise UserError("--command goto needs --node N")
    if args.node is not None and args.command != "goto":
        raise UserError("--node goes with --command goto only")
    if args.node is not None and args.node < 0:
        raise UserError(f"--node must be a node id (>= 0), got {args.node}")
    if args.web is not None and not 0 <= args.web < 65536:
        raise UserError(f"--web port must be 0-65535, got {args.web}")


def link_config(args: argparse.Namespace) -> LinkConfig:
    """The monitor's session: a client of the given endpoints, listening on nothing."""
    from tslam.link.config import LinkConfig
    from tslam.link.errors import LinkError

    try:
        cfg = LinkConfig(
            mode="client", listen=[], connect=list(args.connect),
            user=args.user, password=args.password, config_file=args.config,
            lease_s=1.0, open_timeout_s=1.0,
        )  # fmt: skip
        if args.credentials is not None:
            cfg = cfg.with_credentials_file(args.credentials)
        return cfg
    except LinkError as exc:
        raise UserError(str(exc)) from None


@contextmanager
def _open_client(
    robot: str, cfg: LinkConfig, on_update: Callable[[], None] | None
) -> Iterator[MonitorClient]:
    from tslam.link.client import MonitorClient
    from tslam.link.errors import LinkError

    try:
        client = MonitorClient(robot, cfg, on_update=on_update)
    except LinkError as exc:
        raise UserError(_tidy(str(exc))) from None
    except Exception as exc:  # zenoh's own error when a session cannot be opened at all
        raise UserError(_tidy(f"cannot open a link: {exc}")) from None
    try:
        yield client
    finally:
        client.close()


def _tidy(message: str) -> str:
    """zenoh's error text without its Rust source location, and with a hint when nobody answered."""
    message = _RUST_LOCATION.sub("", message.strip())
    if "Unable to connect" in message:
        message = (
            message.rstrip("!.")
            + " (is the robot's daemon, or the router, up there? are the credentials right?)"
        )
    return message


#: After Ctrl-C or SIGTERM the monitor closes its zenoh session; should that hang (a session
#: abandoned while reconnecting to a robot that is gone hangs the process at exit, zenoh notes
#: pitfalls 1 and 2), the process ends anyway this long after the signal.
EXIT_GRACE_S = 5.0


@contextmanager
def _sigterm_as_interrupt(forced_code: int) -> Iterator[None]:
    # A monitor stopped by SIGTERM (systemd, a test harness) must close its session like one
    # stopped by Ctrl-C: a zenoh session left open can hang the process at exit.
    def interrupt(signum: int, frame: Any) -> None:
        _exit_after(EXIT_GRACE_S, forced_code)
        raise KeyboardInterrupt

    try:
        old = [(sig, signal.signal(sig, interrupt)) for sig in (signal.SIGINT, signal.SIGTERM)]
    except ValueError:  # not the main thread (embedded use): leave signals alone
        yield
        return
    try:
        yield
    finally:
        for sig, handler in old:
            signal.signal(sig, handler)


def _exit_after(delay_s: float, code: int) -> None:
    def force() -> None:
        for stream in (sys.stdout, sys.stderr):
            with suppress(OSError, ValueError):
                stream.flush()
        os._exit(code)

    timer = threading.Timer(delay_s, force)
    timer.daemon = True
    timer.start()


def _wait_for(
    client: MonitorClient, notifier: Notifier, ready: Callable[[Any], bool], timeout: float
) -> Any:
    """The client's view once ``ready(view)``, or the last view when ``timeout`` runs out."""
    deadline = time.monotonic() + timeout
    while True:
        # Read the version before the view: a change between the two wakes the wait at once.
        seen = notifier.version
        view = client.view()
        left = deadline - time.monotonic()
        if ready(view) or left <= 0:
            return view
        notifier.wait_newer(seen, min(left, 0.5))


def _seen(view: Any) -> bool:
    return bool(view.online) and view.state is not None


# -- the modes -------------------------------------------------------------------------------
def _run(args: argparse.Namespace) -> int:
    _check_args(args)
    # zenoh logs its own errors (a refused login, a lost link) in colour on stderr; they
    # would tear the redrawn view and double the one-line errors. RUST_LOG brings them back.
    os.environ.setdefault("RUST_LOG", "off")
    cfg = link_config(args)
    notifier = Notifier()
    live = args.command is None and not args.once
    with _sigterm_as_interrupt(0 if live else 130):
        try:
            robot = args.robot or _discover(cfg, args.timeout)
        except KeyboardInterrupt:
            return 130
        if robot is None:
            print(
                f"tslam monitor: no robot seen on {_where(args)} within {args.timeout:g} s",
                file=sys.stderr,
            )
            return 1
        with _open_client(robot, cfg, notifier.bump) as client:
            try:
                if args.command is not None:
                    return _send_command(args, robot, client, notifier)
                if args.web is not None:
                    return _serve_web(args, robot, client, notifier)
                if args.once:
                    return _print_once(args, robot, client, notifier)
                return _follow(args, robot, client, notifier)
            except KeyboardInterrupt:
                # The user's way to leave a live view, not an error; a one-shot cut short is.
                return 0 if live else 130


def _discover(cfg: LinkConfig, timeout: float) -> str | None:
    """The only robot alive on the link; None if none is seen in time; UserError if several."""
    notifier = Notifier()
    # Any valid name will do: only the client's liveliness watch of every robot is used.
    with _open_client("_discovery", cfg, notifier.bump) as probe:
        deadline = time.monotonic() + timeout
        first_seen: float | None = None
        while True:
            seen = notifier.version
            robots = sorted(set(probe.robots()) - {"_discovery"})
            now = time.monotonic()
            if robots and first_seen is None:
                first_seen = now
            if first_seen is not None and (
                now - first_seen >= DISCOVERY_SETTLE_S or now >= deadline
            ):
                break
            if now >= deadline:
                return None
            wait = deadline - now if first_seen is None else first_seen + DISCOVERY_SETTLE_S - now
            notifier.wait_newer(seen, min(max(wait, 0.01), 0.1))
    if len(robots) > 1:
        raise UserError(f"several robots online ({', '.join(robots)}): choose one with --robot")
    return robots[0]


def _where(args: argparse.Namespace) -> str:
    return ", ".join(args.connect) or f"the endpoints of {args.config}"


def _not_seen(args: argparse.Namespace, robot: str, view: Any) -> int:
    if view.online:
        what = "is online but sent no state"
    else:
        what = "is offline" if view.state is not None else "not seen"
    print(
        f"tslam monitor: robot {robot!r} {what} on {_where(args)} (waited {args.timeout:g} s)",
        file=sys.stderr,
    )
    return 1


def _print_once(
    args: argparse.Namespace, robot: str, client: MonitorClient, notifier: Notifier
) -> int:
    view = _wait_for(
        client, notifier, lambda v: _seen(v) and map_complete(v) and events_caught_up(v),
        args.timeout,
    )  # fmt: skip
    if not _seen(view):
        return _not_seen(args, robot, view)
    if not map_complete(view):
        print(
            f"tslam monitor: robot {robot!r} is online but its map did not arrive "
            f"within {args.timeout:g} s",
            file=sys.stderr,
        )
        return 1
    if not events_caught_up(view):
        # The map and state are whole; only the history is short. Say so rather than print
        # it as if it were all.
        held = max((e.seq for e in view.events if e.epoch == view.state.epoch), default=None)
        print(
            f"tslam monitor: robot {robot!r} announced event {view.state.event_seq} but the "
            f"history holds {'none' if held is None else f'up to {held}'} after "
            f"{args.timeout:g} s; printing what arrived",
            file=sys.stderr,
        )
    if args.json:
        print(json.dumps(snapshot(robot, view), indent=2))
    else:
        print("\n".join(render_lines(robot, view)))
    return 0


def _follow(args: argparse.Namespace, robot: str, client: MonitorClient, notifier: Notifier) -> int:
    tty = sys.stdout.isatty() and not args.json
    last = None
    while True:
        seen = notifier.version
        view = client.view()
        if args.json:
            text = json.dumps(snapshot(robot, view), separators=(",", ":"))
        else:
            text = "\n".join(render_lines(robot, view))
        if text != last:
            # A pipe gets each changed view once (a blank line between views, or one JSON
            # object per line); a terminal gets it redrawn in place.
            if tty:
                sys.stdout.write(CLEAR + text + "\n")
            else:
                sys.stdout.write(text + ("\n" if args.json else "\n\n"))
            sys.stdout.flush()
            last = text
        notifier.wait_newer(seen, 1.0)
        time.sleep(REDRAW_S)


def _send_command(
    args: argparse.Namespace, robot: str, client: MonitorClient, notifier: Notifier
) -> int:
    from tslam.link.schemas import Command

    # Wait until the robot is seen: a command sent before the session has learnt the robot's
    # routes would be lost and reported as a timeout.
    view = _wait_for(client, notifier, lambda v: bool(v.online), args.timeout)
    if not view.online:
        return _not_seen(args, robot, view)
    cmd = Command(id=uuid.uuid4().hex, op=args.command, node=args.node)
    reply = client.command(cmd, timeout_s=args.timeout)
    what = args.command if args.node is None else f"{args.command} {args.node}"
    if args.json:
        print(
            json.dumps(
                {
                    "robot": robot,
                    "op": args.command,
                    "node": args.node,
                    "id": reply.id,
                    "accepted": reply.accepted,
                    "reason": reply.reason,
                }
            )
        )
    elif reply.accepted:
        print(f"{robot}: {what}: accepted" + (f" ({reply.reason})" if reply.reason else ""))
    else:
        print(f"{robot}: {what}: refused: {reply.reason or 'no reason given'}")
    return 0 if reply.accepted else 1


def _serve_web(
    args: argparse.Namespace, robot: str, client: MonitorClient, notifier: Notifier
) -> int:
    from tslam.link.schemas import Command

    def command_fn(op: str, node: int | None) -> dict[str, Any]:
        reply = client.command(Command(id=uuid.uuid4().hex, op=op, node=node), args.timeout)
        return {
            "id": reply.id,
            "op": op,
            "node": node,
            "accepted": reply.accepted,
            "reason": reply.reason,
        }

    try:
        web = MonitorWeb(
            args.bind, args.web, lambda: snapshot(robot, client.view()), command_fn, notifier
        )
    except OSError as exc:
        raise UserError(f"cannot serve on {args.bind}:{args.web}: {exc.strerror or exc}") from None
    with web:
        # The URL on stdout is the one line a script (or a test) needs to find the page.
        print(f"tslam monitor: robot {robot}: serving {web.url}", flush=True)
        while True:
            time.sleep(1.0)
