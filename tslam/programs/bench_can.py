"""``tslam bench can``: the CAN sonar link's figures, printed as one JSON object.

- ``frames_decoded_per_s``: group data frames decoded by the codec alone (no bus), per second.
- latency: from the moment the emulated board takes a reading to the ``scan()`` that first
  delivers it, through an SLCAN pseudo-terminal with the board in another process. The board
  runs a probe in place of the simulated ring: its readings change every ``--probe-interval``
  seconds (1 ms) to a value that names the change, and both processes read the same system-wide
  monotonic clock, so each value seen by the driver dates itself. Only values the driver
  delivers are timed: a reading is at most one probe interval old when the board sends it, so
  the figure is the link's and the driver's share (the board's own refresh and the poll period,
  ``poll_s``, decide how often a new reading comes, not how late it arrives). It is measured at
  the driver's default poll (0.1 s) and at a fast one (0.01 s), which gives ten times the
  samples.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import select
import sys
import time
from typing import Any

import numpy as np

#: Distinct probe values before they repeat: the cycle must outlast any latency measured.
_PROBE_VALUES = 1000
_PROBE_BASE_M = 1.0
#: One count at the emulator's default resolution (0.5 cm), so every value travels exactly.
_PROBE_STEP_M = 0.005


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("can", help="CAN sonar codec throughput and reading-to-scan latency")
    p.add_argument("--json", action="store_true", help="print one JSON object (default)")
    p.add_argument("--frames", type=int, default=50_000, help="frames to decode (50000)")
    p.add_argument(
        "--seconds", type=float, default=20.0, help="latency measurement per poll rate (20 s)"
    )
    p.add_argument(
        "--probe-interval", type=float, default=0.001, help="seconds between probe readings"
    )
    p.set_defaults(run=_run)


def _run(args: argparse.Namespace) -> int:
    from tslam.programs.cli import UserError

    if args.frames < 100:
        raise UserError(f"--frames must be at least 100, got {args.frames}")
    if not 0.5 <= args.seconds <= 600:
        raise UserError(f"--seconds must be between 0.5 and 600, got {args.seconds}")
    if not 0.001 <= args.probe_interval <= 0.1:
        raise UserError(f"--probe-interval must be 0.001-0.1 s, got {args.probe_interval}")
    print(f"bench can: decoding {args.frames} frames ...", file=sys.stderr, flush=True)
    rate = decode_rate(args.frames)
    result: dict[str, Any] = {"frames_decoded_per_s": round(rate, 1)}
    runs = {}
    for name, poll_s in (("default_poll", 0.1), ("fast_poll", 0.01)):
        print(
            f"bench can: latency over slcan, poll every {poll_s} s, {args.seconds} s ...",
            file=sys.stderr,
            flush=True,
        )
        runs[name] = latency_across_processes(poll_s, args.seconds, args.probe_interval)
    result["latency_ms_median"] = runs["default_poll"]["median_ms"]
    result["latency_ms_p99"] = runs["default_poll"]["p99_ms"]
    result["latency"] = runs
    result["link"] = "slcan over a pseudo-terminal, board emulated in another process"
    print(json.dumps(result, indent=2))
    return 0


def decode_rate(n_frames: int, seed: int = 0) -> float:
    """Group data frames decoded per second by the codec alone."""
    from drivers.can_sonar.codec import GroupData, Reading, ReadingStatus, Resolution, UsBoardCodec

    codec = UsBoardCodec()
    rng = np.random.default_rng(seed)
    frames = []
    for i in range(256):
        readings = tuple(
            Reading(ReadingStatus.NO_ECHO) if u < 0.1 else Reading.ok(round(r, 2))
            for u, r in zip(rng.random(4), rng.uniform(0.15, 6.5, 4), strict=True)
        )
        frames.append(codec.encode_reply(GroupData(i % 4, Resolution.CM_0_5, readings)))
    for f in frames:  # warm caches
        codec.decode_reply(f)
    start = time.perf_counter()
    for i in range(n_frames):
        codec.decode_reply(frames[i & 255])
    return n_frames / (time.perf_counter() - start)


def _probe_board(t0: float, interval_s: float, conn: Any) -> None:
    """The board process: SLCAN on a pty, readings from the probe; runs until terminated."""
    from sim_backend.emulators.can_sonar import make_device

    def ranges() -> np.ndarray:
        k = int((time.monotonic() - t0) / interval_s)
        return np.full(16, _PROBE_BASE_M + (k % _PROBE_VALUES) * _PROBE_STEP_M)

    device = make_device(None, slcan_pty=True, ranges=ranges)
    conn.send(device.backend_options())
    conn.close()
    while True:
        ready, _, _ = select.select([device.fileno()], [], [], 0.05)
        if ready:
            device.service(0.0)


def latency_across_processes(poll_s: float, seconds: float, interval_s: float) -> dict[str, Any]:
    """Reading-to-scan latency (ms) through an slcan pty, the board in a child process."""
    from hal.registry import create_backend

    ctx = multiprocessing.get_context("spawn")
    parent, child = ctx.Pipe(duplex=False)
    t0 = time.monotonic()
    proc = ctx.Process(target=_probe_board, args=(t0, interval_s, child), daemon=True)
    proc.start()
    try:
        if not parent.poll(60.0):
            raise RuntimeError("the probe board did not start within 60 s")
        options = parent.recv()
        backend = create_backend(
            {**options, "poll_s": poll_s, "max_age_s": 5.0, "max_range_m": 10.0}
        )
        samples: list[float] = []
        with backend:
            last = math.nan
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                value = float(backend.scan().ranges_m[0])  # type: ignore[attr-defined]
                seen = time.monotonic()
                if not math.isnan(value) and value != last:
                    if not math.isnan(last):  # the first value may predate the run
                        samples.append(_age(value, seen, t0, interval_s))
                    last = value
                time.sleep(0.0005)
    finally:
        proc.terminate()
        proc.join(10.0)
        if proc.is_alive():
            proc.kill()
            proc.join(10.0)
    ms = np.array(samples) * 1000.0
    if len(ms) == 0:
        raise RuntimeError("no readings came through the link")
    return {
        "poll_s": poll_s,
        "samples": len(ms),
        "median_ms": round(float(np.median(ms)), 2),
        "p99_ms": round(float(np.percentile(ms, 99)), 2),
        "max_ms": round(float(np.max(ms)), 2),
    }


def _age(value: float, seen: float, t0: float, interval_s: float) -> float:
    """How long ago the board took the reading whose probe value is ``value``."""
    index = round((value - _PROBE_BASE_M) / _PROBE_STEP_M)
    latest = math.floor((seen - t0) / interval_s)
    k = latest - ((latest - index) % _PROBE_VALUES)
    return seen - (t0 + k * interval_s)
