"""The ``tslam`` command line. Every user mistake ends in one line on stderr and exit code 2;
a robot that had to be stopped on a hardware or link failure, in one line and exit code 1."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from hal.errors import ConfigurationError, HalError
from sim_backend.world import WorldError


class UserError(Exception):
    """A mistake in what the user asked for; printed as one line."""


def build_parser() -> argparse.ArgumentParser:
    from tslam.programs import (
        bench_cmd,
        daemon_cmd,
        emulate_cmd,
        sim_cmd,
        trace_cmd,
        world_cmds,
    )

    parser = argparse.ArgumentParser(
        prog="tslam", description="Topological SLAM on the generalized Voronoi graph."
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    world_cmds.add_parsers(sub)
    sim_cmd.add_parser(sub)
    trace_cmd.add_parser(sub)
    bench_cmd.add_parser(sub)
    emulate_cmd.add_parser(sub)
    daemon_cmd.add_parser(sub)
    from tslam.programs import monitor_cmd

    monitor_cmd.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.run(args) or 0)
    except (UserError, WorldError, ConfigurationError) as exc:
        print(f"tslam: error: {exc}", file=sys.stderr)
        return 2
    except HalError as exc:  # not the user's doing: the device or its link failed
        print(f"tslam: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("tslam: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader went away (``tslam world info ... | head``): what is left of the output
        # has nowhere to go, and the interpreter's last flush must not fail on it again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141  # as a shell reports a command ended by SIGPIPE


if __name__ == "__main__":
    # Run as ``python -m``, this file is ``__main__``; the commands raise the ``UserError`` of
    # ``tslam.programs.cli``, a different class object, so call that module's ``main``.
    from tslam.programs.cli import main as _main

    sys.exit(_main())
