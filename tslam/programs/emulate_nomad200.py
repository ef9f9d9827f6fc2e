"""``tslam emulate nomad200``: the simulated robot behind the Nomad 200's serial protocol.

Serves on a pseudo-terminal (default) or a TCP socket on loopback and prints one JSON line on
stdout as soon as it is ready, e.g. ``{"port": "/dev/pts/7", "transport": "pty", ...}``: give
``port`` to the driver (``nomad200://`` + port, or the option ``port``), or the whole ``backend``
configuration to ``create_backend``. Runs until SIGTERM or SIGINT, then exits 0.

``--with-can-sonar`` adds the CAN sonar board (``tslam emulate can-sonar``, its options prefixed
``--can-``) on an SLCAN pty, firing the same simulated robot's ring: a Nomad 200 retrofitted
with the board. The line then also carries ``can_sonar`` (the pty and the ``can-sonar``
configuration) and ``backend`` is the ``composed`` configuration of the two.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
from types import FrameType
from typing import TYPE_CHECKING

from sim_backend.odometry_model import DRIFT_LEVELS
from tslam.programs.cli import UserError
from tslam.programs.emulate_can_sonar import add_board_arguments, make_can_sonar_device

if TYPE_CHECKING:
    from sim_backend.emulators.can_sonar import CanSonarDevice
    from sim_backend.emulators.host import EmulatedDevice
    from sim_backend.emulators.nomad200_faults import FaultConfig

CAN_PREFIX = "can-"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "nomad200",
        help="serve the Nomad 200 serial protocol from the simulated robot",
        description="Serve the Nomad 200 host protocol on a pty or TCP socket, backed by the "
        "simulator. Prints one JSON line (the port to give the driver) and serves until "
        "SIGTERM or SIGINT.",
    )
    p.add_argument("--world", required=True, help="built-in world name or world file")
    p.add_argument("--seed", type=int, default=0, help="simulator seed (0)")
    p.add_argument("--drift", choices=DRIFT_LEVELS, default="paper", help="odometry drift")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--pty", action="store_true", help="serve on a pseudo-terminal (default)")
    where.add_argument(
        "--listen", metavar="tcp:HOST:PORT", help="serve on a TCP socket, e.g. tcp:127.0.0.1:0"
    )
    p.add_argument("--link", metavar="PATH", help="keep a symlink to the current pty here")
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="simulated time passes only when the driver asks (reproducible runs)",
    )
    p.add_argument(
        "--time-scale", type=float, default=1.0, help="simulated seconds per second (1.0)"
    )
    f = p.add_argument_group("fault injection (replies; the requests are still carried out)")
    for name in ("drop", "corrupt", "truncate", "garbage", "delay"):
        f.add_argument(f"--{name}", type=float, default=0.0, metavar="P", help="probability")
    f.add_argument("--delay-s", type=float, default=0.5, help="delay of a delayed reply (0.5)")
    f.add_argument("--fault-seed", type=int, default=None, help="fault RNG seed (--seed)")
    f.add_argument("--faults-after", type=int, default=0, metavar="N", help="N clean replies")
    f.add_argument("--disappear-after-s", type=float, default=None, metavar="S", help="sim s")
    f.add_argument("--disappear-after-requests", type=int, default=None, metavar="N")
    f.add_argument(
        "--reappear-after-s", type=float, default=None, metavar="S", help="host s (never)"
    )
    p.add_argument(
        "--with-can-sonar", action="store_true",
        help="also serve the CAN sonar board (SLCAN on a second pty) on the same robot",
    )  # fmt: skip
    add_board_arguments(p, CAN_PREFIX)
    p.set_defaults(run=_run)


def _listen_address(spec: str) -> tuple[str, int]:
    scheme, _, rest = spec.partition(":")
    host, _, port = rest.rpartition(":")
    if scheme != "tcp" or not host or not port.isdigit() or int(port) > 65535:
        raise UserError(f"--listen must look like tcp:127.0.0.1:PORT, got {spec!r}")
    return host, int(port)


def _faults(args: argparse.Namespace) -> FaultConfig:
    # Imported here, as the simulator is: ``tslam --help`` should not load it.
    from sim_backend.emulators.nomad200_faults import FaultConfig

    try:
        return FaultConfig(
            drop=args.drop,
            corrupt=args.corrupt,
            truncate=args.truncate,
            garbage=args.garbage,
            delay=args.delay,
            delay_s=args.delay_s,
            after_requests=args.faults_after,
            disappear_after_s=(
                math.inf if args.disappear_after_s is None else args.disappear_after_s
            ),
            disappear_after_requests=args.disappear_after_requests,
            reappear_after_s=args.reappear_after_s,
            seed=args.seed if args.fault_seed is None else args.fault_seed,
        )
    except ValueError as exc:
        raise UserError(str(exc)) from None


def _run(args: argparse.Namespace) -> int:
    from sim_backend.emulators.host import EmulatorHost
    from sim_backend.emulators.nomad200 import Nomad200Emulator
    from sim_backend.emulators.nomad200_transport import PtyTransport, TcpTransport
    from sim_backend.simulator import SimParams, SimRobot
    from sim_backend.world_files import load_world

    if not (math.isfinite(args.time_scale) and args.time_scale > 0):
        raise UserError(f"--time-scale must be a positive number, got {args.time_scale}")
    if args.link and args.listen:
        raise UserError("--link only applies to --pty")
    faults = _faults(args)
    _check_board_options(args)
    world = load_world(args.world)
    robot = SimRobot(world, SimParams(drift=args.drift), args.seed)
    board = make_can_sonar_device(robot, args, CAN_PREFIX) if args.with_can_sonar else None
    try:
        if args.listen:
            transport = TcpTransport(*_listen_address(args.listen))
        else:
            transport = PtyTransport(args.link)
    except (OSError, UserError) as exc:
        if board is not None:
            board.close()
        if isinstance(exc, UserError):
            raise
        raise UserError(f"cannot serve: {exc}") from None
    device = Nomad200Emulator(robot, transport, lockstep=args.lockstep, faults=faults)
    devices: list[EmulatedDevice] = [device] if board is None else [device, board]
    host = EmulatorHost(robot, devices, time_scale=args.time_scale, lockstep=args.lockstep)

    def _stop(signum: int, frame: FrameType | None) -> None:
        host.stop()

    signal.signal(signal.SIGTERM, _stop)
    signal.signal(signal.SIGINT, _stop)
    ready = {
        **transport.describe(),
        "world": world.name,
        "seed": args.seed,
        "drift": args.drift,
        "lockstep": args.lockstep,
        "pid": os.getpid(),
        **_backend_specs(str(transport.describe()["port"]), args, board),
    }
    print(json.dumps(ready), flush=True)
    where = f"emulate: Nomad 200 on {ready['port']}"
    if board is not None:
        where += f", CAN sonar board on slcan {board.channel}"
    print(where, file=sys.stderr, flush=True)
    host.run()
    return 0


def _check_board_options(args: argparse.Namespace) -> None:
    """Board options without the board are a mistake, not something to ignore silently."""
    if args.with_can_sonar:
        return
    probe = argparse.ArgumentParser(add_help=False)
    add_board_arguments(probe, CAN_PREFIX)
    for name, default in vars(probe.parse_args([])).items():
        if getattr(args, name) != default:
            flag = "--" + name.replace("_", "-")
            raise UserError(f"{flag} applies to the CAN sonar board: add --with-can-sonar")


def _backend_specs(
    port: str, args: argparse.Namespace, board: CanSonarDevice | None
) -> dict[str, object]:
    """Ready-made configurations for ``create_backend`` that reach what is served."""
    drive: dict[str, object] = {"backend": "nomad200", "port": port, "lockstep": args.lockstep}
    if args.time_scale != 1.0:
        drive["time_scale"] = args.time_scale
    if board is None:
        return {"backend": drive}
    sonar = board.backend_options()
    return {
        "can_sonar": {"pty": board.channel, "backend": sonar},
        "backend": {"backend": "composed", "drive": drive, "sonar": sonar},
    }
