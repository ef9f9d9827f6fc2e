"""``tslam bench link``: the zenoh link's figures, printed as one JSON object.

- ``latency_ms_p50`` / ``latency_ms_p99``: from an event published by a robot process
  (``tslam.link.demo_robot``, through ``RobotLink``) to the ``on_event`` callback of a
  ``MonitorClient`` in this process, over TCP on 127.0.0.1. Both processes stamp with the
  system-wide monotonic clock, so each event dates itself. The robot sends ``--events`` events
  at ``--event-hz`` after an ``explore`` command (the first 10 are left out as warm-up) while it
  also publishes its state at 10 Hz, as the daemon does.
- ``snapshot``: the full map of the same robot, ``--nodes`` meet points on a grid (about two
  edges each), fetched through the ``map`` queryable ``--fetches`` times: its MessagePack size
  and the fetch time (query to decoded ``MapSnapshot``).
- ``map_changes``: the bandwidth of map changes during an exploration, from a model (no timed
  run): a depth-first exploration of the ground-truth GVG of ``--world`` (fig14 by default),
  each edge traced at the paper's 0.2 m/s, a turret sweep (4 rings, 3.84 s) on reaching each
  node, every edge travelled back once. Each step emits the ``MapChange`` the daemon would
  (a new node with its edge; at a known node the provisional node, then the merge; a new
  length measurement on the way back), encoded for real. Bytes are MessagePack payloads; zenoh
  adds a few bytes of framing to each.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import threading
import time
from typing import Any

import numpy as np

TRACE_SPEED_MPS = 0.2  # the paper's alpha in eq. 1
SWEEP_S = 4 * 0.96  # each transducer fires four times while the turret turns one spacing
WARMUP_EVENTS = 10


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("link", help="zenoh link: event latency, snapshot size, map bandwidth")
    p.add_argument("--json", action="store_true", help="print one JSON object (default)")
    p.add_argument("--events", type=int, default=2000, help="events timed (2000)")
    p.add_argument("--event-hz", type=float, default=500.0, help="events per second (500)")
    p.add_argument("--nodes", type=int, default=1000, help="nodes in the snapshot map (1000)")
    p.add_argument("--fetches", type=int, default=20, help="snapshot fetches timed (20)")
    p.add_argument("--world", default="fig14", help="world of the exploration model (fig14)")
    p.set_defaults(run=_run)


def _run(args: argparse.Namespace) -> int:
    from tslam.programs.cli import UserError

    if args.events < WARMUP_EVENTS + 10:
        raise UserError(f"--events must be at least {WARMUP_EVENTS + 10}, got {args.events}")
    if not 1 <= args.event_hz <= 20_000:
        raise UserError(f"--event-hz must be 1-20000, got {args.event_hz}")
    if not 1 <= args.nodes <= 100_000:
        raise UserError(f"--nodes must be 1-100000, got {args.nodes}")
    if not 1 <= args.fetches <= 1000:
        raise UserError(f"--fetches must be 1-1000, got {args.fetches}")
    result: dict[str, Any] = {}
    print("bench link: robot process, events and snapshots ...", file=sys.stderr, flush=True)
    result.update(measure_link(args.events, args.event_hz, args.nodes, args.fetches))
    print(f"bench link: exploration model on {args.world} ...", file=sys.stderr, flush=True)
    result["map_changes"] = change_stream_model(args.world)
    result["map_changes_bytes_per_s"] = result["map_changes"]["bytes_per_s_mean"]
    result["target_latency_ms_p99"] = 5.0
    # The tail of the latency is the scheduler's on a shared machine: say how busy it was.
    result["load_avg_1min"] = round(os.getloadavg()[0], 2)
    result["cpus"] = os.cpu_count()
    result["link"] = "zenoh peer to peer, tcp on 127.0.0.1, robot in another process"
    print(json.dumps(result, indent=2))
    return 0


def measure_link(n_events: int, event_hz: float, n_nodes: int, fetches: int) -> dict[str, Any]:
    from tslam.link.client import MonitorClient
    from tslam.link.config import free_port, loopback
    from tslam.link.schemas import Command, EventMsg, encode

    port = free_port()
    robot = subprocess.Popen(
        [
            sys.executable, "-m", "tslam.link.demo_robot",
            "--robot", "bench", "--listen", f"tcp/127.0.0.1:{port}",
            "--initial", str(n_nodes), "--nodes", str(n_nodes), "--rate", "0",
            "--scan-hz", "0", "--wait-explore",
            "--burst", str(n_events), "--burst-hz", str(event_hz),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )  # fmt: skip
    lat: list[float] = []
    done = threading.Event()

    def on_event(e: EventMsg) -> None:
        if e.kind == "bench":
            lat.append(time.monotonic() - e.stamp_s)
            if e.text == "burst 0":
                done.set()

    try:
        assert robot.stdout is not None
        if not robot.stdout.readline().startswith("ready"):
            raise RuntimeError("the bench robot did not start")
        with MonitorClient("bench", loopback(None, [port]), on_event=on_event) as mon:
            deadline = time.monotonic() + 30
            while not (mon.view().synced and mon.view().online):
                if time.monotonic() > deadline:
                    raise RuntimeError(f"no map from the bench robot: {mon.view().last_error}")
                time.sleep(0.05)
            times, size, snap = [], 0, None
            for _ in range(fetches):
                t0 = time.perf_counter()
                snap = mon.fetch_snapshot()
                times.append(time.perf_counter() - t0)
                size = len(encode(snap))
            reply = mon.command(Command(id="bench", op="explore"))
            if not reply.accepted:
                raise RuntimeError(f"the bench robot refused explore: {reply.reason}")
            done.wait(n_events / event_hz + 30)
    finally:
        robot.terminate()
        try:
            robot.wait(10)
        except subprocess.TimeoutExpired:
            robot.kill()
            robot.wait()
    ms = np.array(lat[WARMUP_EVENTS:]) * 1000.0
    fetch_ms = np.array(times) * 1000.0
    assert snap is not None
    return {
        "latency_ms_p50": round(float(np.percentile(ms, 50)), 3),
        "latency_ms_p99": round(float(np.percentile(ms, 99)), 3),
        "latency_ms_max": round(float(ms.max()), 3),
        "events_sent": n_events,
        "events_received": len(lat),
        "event_hz": event_hz,
        "snapshot": {
            "nodes": len(snap.nodes),
            "edges": len(snap.edges),
            "bytes": size,
            "fetch_ms_p50": round(float(np.percentile(fetch_ms, 50)), 3),
            "fetch_ms_max": round(float(fetch_ms.max()), 3),
            "fetches": fetches,
        },
    }


def change_stream_model(world_spec: str) -> dict[str, Any]:
    """Map changes of a modelled exploration of ``world_spec``'s true GVG (module docstring)."""
    from sim_backend.ground_truth import compute_gvg
    from sim_backend.world_files import load_world
    from tslam.link.schemas import EdgeMsg, MapChange, NodeMsg, encode

    world = load_world(world_spec)
    gvg = compute_gvg(world)
    start = world.start
    first = gvg.nearest_node(start.x, start.y)
    if first is None:
        raise RuntimeError(f"world {world_spec} has no GVG to explore")
    nodes = {n.id: n for n in gvg.nodes}
    edges = {e.id: e for e in gvg.edges}
    incident: dict[int, list[int]] = {n: [] for n in nodes}
    for e in gvg.edges:
        incident[e.u].append(e.id)
        if e.v != e.u:
            incident[e.v].append(e.id)
    travelled: set[int] = set()
    seen: set[int] = set()
    stream: list[tuple[float, int]] = []  # (time s, payload bytes)
    seq = 0
    t = 0.0
    extra_id = max(nodes) + 1  # ids for provisional nodes before a merge

    def msg(nid: int, nid_as: int | None = None) -> NodeMsg:
        n = nodes[nid]
        left = sum(1 for e in incident[nid] if e not in travelled)
        return NodeMsg(
            id=nid if nid_as is None else nid_as,
            kind="meet" if n.kind == "meet" else "boundary",
            x=n.x,
            y=n.y,
            clearance_m=n.clearance_m,
            degree=n.degree,
            unexplored=left,
            ambiguous_with=[],
        )

    def emit(op: str, up_n: list[NodeMsg], up_e: list[EdgeMsg], rm_n: list[int] = ()) -> None:
        nonlocal seq
        seq += 1
        c = MapChange("robot1", "model", seq, op, up_n, list(rm_n), up_e, [])
        stream.append((t, len(encode(c))))

    def edge(eid: int, u: int, v: int) -> EdgeMsg:
        return EdgeMsg(id=eid, u=u, v=v, length_m=edges[eid].length_m)

    seen.add(first.id)
    emit("node_added", [msg(first.id)], [])
    t += SWEEP_S
    path = [first.id]
    back: list[int] = []  # the edge that led to each node of the path
    while path:
        u = path[-1]
        todo = [e for e in incident[u] if e not in travelled]
        if not todo:
            path.pop()
            if back:
                eid = back.pop()
                t += edges[eid].length_m / TRACE_SPEED_MPS
                e = edges[eid]
                emit("measurement", [], [edge(eid, e.u, e.v)])
            continue
        eid = todo[0]
        e = edges[eid]
        v = e.v if e.u == u else e.u
        t += e.length_m / TRACE_SPEED_MPS
        travelled.add(eid)
        if v not in seen:
            seen.add(v)
            emit("node_added", [msg(u), msg(v)], [edge(eid, u, v)])
            t += SWEEP_S
            path.append(v)
            back.append(eid)
        else:
            # A known place looks new at first; the sweep and the topology then merge it.
            emit("node_added", [msg(u), msg(v, extra_id)], [edge(eid, u, extra_id)])
            t += SWEEP_S
            emit("merge", [msg(v)], [edge(eid, u, v)], [extra_id])
            extra_id += 1
            t += edges[eid].length_m / TRACE_SPEED_MPS  # and back to carry on from u
    total_bytes = sum(b for _, b in stream)
    duration = max(t, 1e-9)
    per_s = np.zeros(math.ceil(duration) + 1)
    for when, b in stream:
        per_s[int(when)] += b
    return {
        "world": world_spec,
        "gvg_nodes": len(nodes),
        "gvg_edges": len(edges),
        "gvg_length_m": round(gvg.gvg_length_m, 1),
        "exploration_s_modelled": round(duration, 1),
        "changes": len(stream),
        "bytes_total": int(total_bytes),
        "bytes_per_change_mean": round(total_bytes / max(1, len(stream)), 1),
        "bytes_per_s_mean": round(total_bytes / duration, 2),
        "bytes_per_s_peak": int(per_s.max()),
        "model": (
            f"depth-first over the true GVG, {TRACE_SPEED_MPS} m/s tracing, {SWEEP_S:.2f} s sweep"
            " per node, every edge travelled back once; loop closures as provisional node +"
            " merge; MessagePack payload bytes"
        ),
    }
