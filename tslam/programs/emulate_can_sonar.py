"""``tslam emulate can-sonar``: the CAN sonar board, answering from the simulated robot's ring.

Standing alone, the robot stands at the world's start pose and simulated time runs in real time.
The first line on stdout is one JSON object: the link (``pty`` or ``virtual``) and a ready
``backend`` configuration for the host driver; then the board serves until SIGTERM or SIGINT
and exits 0.

Another emulator command adds this board to its own host with ``add_board_arguments`` (fault
and link options, optionally prefixed) and ``make_can_sonar_device``.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
from collections.abc import Mapping
from typing import Any

from drivers.can_sonar.codec import BITRATE_CODES, MAX_BASE_ID, Resolution
from sim_backend.emulators.can_sonar import CanSonarDevice, make_device
from sim_backend.emulators.can_sonar_faults import BoardFaults
from sim_backend.emulators.host import EmulatorHost
from sim_backend.simulator import SimRobot
from tslam.programs.cli import UserError
from tslam.stopflag import StopFlag

_RESOLUTIONS_CM = {"1": Resolution.CM_1, "0.5": Resolution.CM_0_5,
                   "0.25": Resolution.CM_0_25, "0.125": Resolution.CM_0_125}  # fmt: skip


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "can-sonar",
        help="the CAN sonar board on an SLCAN pseudo-terminal or a python-can virtual channel",
    )
    p.add_argument("--world", required=True, help="built-in name or world file")
    p.add_argument("--seed", type=int, default=0, help="seed of the simulation and the faults")
    link = p.add_mutually_exclusive_group()
    link.add_argument(
        "--slcan-pty", action="store_true", help="serve SLCAN on a pseudo-terminal (default)"
    )
    link.add_argument(
        "--virtual", metavar="CHANNEL", default=None,
        help="serve on a python-can virtual channel (same process only)",
    )  # fmt: skip
    add_board_arguments(p)
    p.set_defaults(run=_run)


def add_board_arguments(parser: argparse.ArgumentParser, prefix: str = "") -> None:
    """The board's options; ``prefix`` (e.g. ``"can-"``) keeps them apart from a host's own."""
    dash = f"--{prefix}"
    g = parser.add_argument_group("CAN sonar board")
    g.add_argument(f"{dash}base-id", default="0x400", help="base identifier (0x400)")
    g.add_argument(f"{dash}bitrate", type=int, default=1_000_000, help="bit/s (1000000)")
    g.add_argument(
        f"{dash}resolution-cm", choices=list(_RESOLUTIONS_CM), default="0.5",
        help="distance per count in the data frames (0.5)",
    )  # fmt: skip
    g.add_argument(f"{dash}drop", type=float, default=0.0, help="probability a frame is lost")
    g.add_argument(f"{dash}corrupt", type=float, default=0.0, help="probability a frame is damaged")
    g.add_argument(
        f"{dash}bus-errors", type=float, default=0.0,
        help="probability a frame is destroyed by a reported bus error",
    )  # fmt: skip
    g.add_argument(
        f"{dash}stop-heartbeat-after", type=float, default=None, metavar="S",
        help="stop answering CONNECT after S simulated seconds",
    )  # fmt: skip
    g.add_argument(
        f"{dash}wrong-ack-sum", action="store_true",
        help="acknowledge parameter sets with a wrong byte sum",
    )  # fmt: skip


def make_can_sonar_device(
    robot: SimRobot, args_or_options: argparse.Namespace | Mapping[str, Any], prefix: str = ""
) -> CanSonarDevice:
    """A board on ``robot``'s ring from parsed arguments (or a mapping with the same keys:
    ``slcan_pty``, ``virtual``, ``base_id``, ``bitrate``, ``resolution_cm``, ``seed``,
    ``drop``, ``corrupt``, ``bus_errors``, ``stop_heartbeat_after``, ``wrong_ack_sum``; with
    ``prefix`` as given to ``add_board_arguments``, dashes as underscores)."""
    values = (
        vars(args_or_options)
        if isinstance(args_or_options, argparse.Namespace)
        else dict(args_or_options)
    )
    key = prefix.replace("-", "_")

    def get(name: str, default: Any = None, shared: bool = False) -> Any:
        v = values.get(key + name)
        if v is None and shared:
            v = values.get(name)  # e.g. the host command's own --seed
        return default if v is None else v

    flag = f"--{prefix}"
    base_raw = get("base_id", 0x400)
    try:
        base_id = int(base_raw, 0) if isinstance(base_raw, str) else int(base_raw)
    except ValueError:
        raise UserError(
            f"{flag}base-id must be an integer such as 0x400, got {base_raw!r}"
        ) from None
    if not 0 <= base_id <= MAX_BASE_ID:
        raise UserError(f"{flag}base-id must be 0x000-0x{MAX_BASE_ID:03X}, got {base_raw}")
    bitrate = int(get("bitrate", 1_000_000))
    if bitrate not in BITRATE_CODES:
        known = ", ".join(str(b) for b in BITRATE_CODES)
        raise UserError(f"{flag}bitrate must be one the board knows ({known}), got {bitrate}")
    res_key = str(get("resolution_cm", "0.5"))
    if res_key not in _RESOLUTIONS_CM:
        raise UserError(f"{flag}resolution-cm must be one of {', '.join(_RESOLUTIONS_CM)}")
    try:
        faults = BoardFaults(
            drop=float(get("drop", 0.0)),
            corrupt=float(get("corrupt", 0.0)),
            bus_errors=float(get("bus_errors", 0.0)),
            heartbeat_stops_after_s=(
                None if get("stop_heartbeat_after") is None else float(get("stop_heartbeat_after"))
            ),
            wrong_ack_sum=bool(get("wrong_ack_sum", False)),
        )
    except ValueError as exc:
        raise UserError(f"CAN sonar faults: {exc}") from None
    virtual = get("virtual")
    if virtual is not None and not str(virtual).strip():
        raise UserError(f"{flag}virtual must name a channel, got an empty name")
    try:
        return make_device(
            robot,
            slcan_pty=virtual is None,
            virtual_channel=virtual,
            base_id=base_id,
            bitrate=bitrate,
            resolution=_RESOLUTIONS_CM[res_key],
            faults=faults,
            seed=int(get("seed", 0, shared=True)),
        )
    except OSError as exc:
        raise UserError(f"cannot open the CAN sonar board's link: {exc}") from None


def _run(args: argparse.Namespace) -> int:
    from sim_backend.world import WorldError
    from sim_backend.world_files import load_world

    if args.seed < 0:
        raise UserError(f"--seed must be at least 0, got {args.seed}")
    world = load_world(args.world)
    try:
        robot = SimRobot(world, seed=args.seed)
    except (WorldError, ValueError) as exc:
        raise UserError(f"{args.world}: {exc}") from None
    device = make_can_sonar_device(robot, args)
    stopper = _StopOnSignal()
    host = EmulatorHost(robot, [device, stopper])
    stopper.host = host
    signal.signal(signal.SIGTERM, stopper.on_signal)
    signal.signal(signal.SIGINT, stopper.on_signal)
    line: dict[str, Any] = {"world": world.name, "backend": device.backend_options()}
    line["pty" if device.interface == "slcan" else "virtual"] = device.channel
    print(json.dumps(line), flush=True)
    print(
        f"tslam: CAN sonar board at base 0x{device.board.codec.base_id:03X} on"
        f" {device.interface} {device.channel}; SIGTERM or Ctrl-C to stop",
        file=sys.stderr,
        flush=True,
    )
    try:
        host.run()
    finally:
        stopper.close()
    return 0


class _StopOnSignal:
    """Stops the host on SIGTERM or SIGINT: the stop flag's pipe is one of the host's devices,
    so a signal that arrives before the host's loop has started still stops it."""

    def __init__(self) -> None:
        self.flag = StopFlag()
        self.host: EmulatorHost | None = None

    def on_signal(self, signum: int, frame: object) -> None:
        self.flag.set(signal.Signals(signum).name)

    def fileno(self) -> int:
        return self.flag.fileno()

    def service(self, now_s: float) -> None:
        if self.host is not None:
            self.host.stop()

    def tick(self, now_s: float) -> None:
        pass

    def close(self) -> None:
        # Idempotent: the host closes its devices, and so does the command after it.
        self.flag.close()
