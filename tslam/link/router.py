"""A zenoh router in a Python process, for a fleet hub where zenohd is not installed.

``python -m tslam.link.router --config deploy/zenoh/fleet-router.json5``

The configuration file holds the listen endpoints, the accepted credentials
(``transport/auth/usrpwd/dictionary_file``) and the access control; ``--listen`` and
``--dictionary-file`` override it (tests, or a quick start). Prints ``ready`` on stdout once
listening; SIGTERM or SIGINT closes it and exits 0. A bad option or file: one line, exit 2.
"""

from __future__ import annotations

import argparse
import sys

from tslam.link.config import LinkConfig
from tslam.link.errors import LinkError
from tslam.link.session import close_session, open_session
from tslam.stopflag import StopFlag, stop_on_signals


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m tslam.link.router", description=__doc__)
    p.add_argument("--config", default=None, help="zenoh json5 configuration")
    p.add_argument("--listen", action="append", default=[], help="endpoint, e.g. tcp/0.0.0.0:7447")
    p.add_argument("--dictionary-file", default=None, help="accepted user:password lines")
    p.add_argument("--lease", type=float, default=2.0, help="link lease, seconds (2)")
    args = p.parse_args(argv)
    try:
        cfg = LinkConfig(
            mode="router",
            listen=args.listen,
            config_file=args.config,
            dictionary_file=args.dictionary_file,
            lease_s=args.lease,
        )
        if not args.listen and args.config is None:
            raise LinkError("give --config FILE or --listen ENDPOINT")
        session = open_session(cfg)
    except LinkError as e:
        print(f"router: {e}", file=sys.stderr)
        return 2
    stop = StopFlag()
    try:
        with stop_on_signals(stop.set):
            print("ready", flush=True)
            stop.wait(None)
    finally:
        close_session(session, cfg.open_timeout_s + 1.0)
        stop.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
