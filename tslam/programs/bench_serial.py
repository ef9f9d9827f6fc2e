"""``tslam bench serial``: the Nomad 200 link's round trip and the control rate it can carry.

Two figures side by side, because a pty is not a serial line:

* measured: request-reply round trips (``gs``) and full control cycles (``gs`` + ``vm``) through
  the driver, pyserial, a pty and the emulator in another process (real-time mode). A pty moves
  bytes at memory speed whatever baud rate is set, so this is the software's own cost;
* the physical limit: the bytes one control cycle puts on the wire (request and reply frames of
  ``gs`` and ``vm``, laid out by the driver's state mask), at 10 bits a byte (start, 8 data,
  stop), at each of the robot's baud rates: what a real cable allows at best.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

import numpy as np

from tslam.programs.cli import UserError


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("serial", help="Nomad 200 link: round trip through a pty, control rate")
    p.add_argument("--json", action="store_true", help="print one JSON object (default)")
    p.add_argument("--world", default="fig12", help="world the emulated robot stands in")
    p.add_argument("--samples", type=int, default=1000, help="gs round trips to time (1000)")
    p.add_argument("--cycles", type=int, default=500, help="control cycles to time (500)")
    p.set_defaults(run=_run)


def cycle_bytes(sonar_pos: bool) -> dict[str, int]:
    """Wire bytes of one control cycle (``gs`` and ``vm``, each request and reply)."""
    from drivers.nomad200.codec import Gs, StateLayout, Vm
    from drivers.nomad200.device import Nomad200Backend
    from drivers.nomad200.frames import MIN_LEN, OVERHEAD
    from drivers.nomad200.settings import Settings

    mask = Nomad200Backend(Settings(port="loop://", sonar_pos=sonar_pos)).mask
    size = StateLayout(mask).size
    assert size is not None
    reply = size + MIN_LEN + OVERHEAD
    out = {
        "gs_request": len(Gs().encode()),
        "gs_reply": reply,
        "vm_request": len(Vm(0, 0, 0).encode()),
        "vm_reply": reply,
    }
    out["total"] = sum(out.values())
    return out


def physical_limits(sonar_pos: bool) -> dict[str, object]:
    frames = cycle_bytes(sonar_pos)
    bits = 10 * frames["total"]
    # A leaner cycle the protocol allows: the vm's own state reply as the next cycle's reading.
    vm_bits = 10 * (frames["vm_request"] + frames["vm_reply"])
    bauds = (4800, 9600, 19200)
    return {
        "bytes_per_cycle": frames,
        "bits_per_cycle": bits,
        "control_hz_limit": {str(b): round(b / bits, 3) for b in bauds},
        "control_hz_limit_vm_only": {str(b): round(b / vm_bits, 3) for b in bauds},
    }


def _run(args: argparse.Namespace) -> int:
    if args.samples < 10 or args.cycles < 10:
        raise UserError("--samples and --cycles must be at least 10")
    from drivers.nomad200.codec import Gs
    from hal.types import Twist
    from tslam.programs.emulated import emulator_command, read_ready_line, stop_process

    def say(msg: str) -> None:
        print(f"bench serial: {msg}", file=sys.stderr, flush=True)

    say(f"starting the emulator ({args.world}, real time, pty)")
    proc = subprocess.Popen(
        emulator_command(args.world, 1, "paper", lockstep=False),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        from drivers.nomad200.device import Nomad200Backend

        port = read_ready_line(proc, 120.0)["port"]
        # max_state_age_s 0: every read polls, so a cycle is exactly one gs and one vm.
        backend = Nomad200Backend.from_config({"port": port, "max_state_age_s": 0.0})
        with backend:
            say(f"{args.samples} gs round trips on {port}")
            rtt = []
            for _ in range(args.samples):
                t0 = time.perf_counter()
                backend.send(Gs())
                rtt.append(time.perf_counter() - t0)
            say(f"{args.cycles} control cycles (gs for the readings, vm for the command)")
            t0 = time.perf_counter()
            for _ in range(args.cycles):
                backend.scan()
                backend.command(Twist(0.0, 0.0, 0.0))
            cycle_s = (time.perf_counter() - t0) / args.cycles
            retransmissions = backend.link.retransmissions
    finally:
        stop_process(proc)
    ms = np.array(rtt) * 1000.0
    result = {
        "transport": "pty, emulator in another process (real time)",
        "samples": len(ms),
        "rtt_ms_median": round(float(np.median(ms)), 3),
        "rtt_ms_p99": round(float(np.percentile(ms, 99)), 3),
        "control_hz_measured_pty": round(1.0 / cycle_s, 1),
        "cycle_ms_measured_pty": round(cycle_s * 1000.0, 3),
        "retransmissions": retransmissions,
        "baud": 9600,
        "control_hz_limit_9600": round(9600 / (10 * cycle_bytes(False)["total"]), 3),
        "physical": physical_limits(False),
        "physical_with_sonar_pos": physical_limits(True),
    }
    print(json.dumps(result, indent=2))
    return 0
