"""``tslam daemon --config FILE.toml``: the onboard daemon (see ``tslam.daemon``).

Exit codes: 0 after SIGTERM/SIGINT (robot stopped, map saved) or, with ``--exit-when-done``,
after a complete exploration; 2 for a configuration that cannot be used (nothing moved);
1 when the robot had to be stopped on a hardware or link failure.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from hal.errors import ConfigurationError, HalError
from tslam.link.errors import LinkError
from tslam.programs.cli import UserError


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("daemon", help="the onboard daemon: explore, keep the map, publish")
    p.add_argument("--config", required=True, help="robot configuration (TOML)")
    p.add_argument("--storage", default=None, help="directory for the map (overrides storage)")
    p.add_argument(
        "--exit-when-done", action="store_true",
        help="exit 0 once exploration is complete instead of waiting for orders",
    )  # fmt: skip
    p.set_defaults(run=_run)


def _run(args: argparse.Namespace) -> int:
    from tslam.daemon.config import ConfigError, load_config
    from tslam.daemon.loop import Daemon, DaemonError, stop_on_signals
    from tslam.daemon.store import StoreError

    try:
        cfg = load_config(args.config)
    except ConfigError as exc:
        raise UserError(str(exc)) from None
    if args.storage:
        cfg = dataclasses.replace(cfg, storage=Path(args.storage))
    if args.exit_when_done:
        cfg = dataclasses.replace(cfg, exit_when_done=True)
    daemon = Daemon(cfg, say=_say)
    try:
        with stop_on_signals(daemon):
            code = daemon.run()
    except (ConfigurationError, StoreError) as exc:
        raise UserError(str(exc)) from None
    except LinkError as exc:
        print(f"tslam daemon: link: {exc}", file=sys.stderr)
        return 1
    except (DaemonError, HalError) as exc:
        print(f"tslam daemon: robot stopped: {exc}", file=sys.stderr)
        return 1
    _say(f"map saved to {cfg.storage / 'map.json'}")
    return code


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)
