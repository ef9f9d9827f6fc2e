"""``tslam trace``: the simulated robot accesses the GVG and traces N edges, meet point to
meet point, by the paper's control laws; the run is scored against the ground truth."""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from hal.registry import create_backend
from sim_backend.backend import SimBackend
from sim_backend.ground_truth import GroundTruthGVG, compute_gvg
from sim_backend.odometry_model import DRIFT_LEVELS
from sim_backend.trace_scoring import SeenEdge, SeenNode, score_trace
from tslam.core.sensing import SensingParams
from tslam.core.tracer import (
    BoundaryReached,
    EdgeTraversed,
    MeetPointReached,
    Tracer,
    TracerParams,
)
from tslam.programs.cli import UserError
from tslam.programs.output import write_text_atomic


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("trace", help="trace GVG edges in simulation and score them")
    p.add_argument("--world", required=True, help="built-in name or world file")
    p.add_argument("--edges", type=int, required=True, help="how many edges to trace")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--drift", choices=DRIFT_LEVELS, default="paper")
    p.add_argument("--rate", type=float, default=10.0, help="control rate in Hz (10)")
    p.add_argument("--max-time", type=float, default=None, help="simulated seconds allowed")
    p.add_argument(
        "--switch",
        action="append",
        default=[],
        metavar="NAME",
        help=f"turn on one of the tracer's switches (off by default): {', '.join(SWITCHES)}",
    )
    p.add_argument("--out", required=True, help="directory for trace.svg, trace_report.json")
    p.set_defaults(run=_run)


#: The tracer's switches, each off by default: the TracerParams fields each sets (a flag set
#: True, or a distance that turns the behaviour on); ``held_no_support`` and ``gap_hold``
#: set SensingParams' (``sensing.`` fields).
_SETS: dict[str, dict[str, bool | float]] = {
    "centred_meet": {"centred_meet": True},
    "course_sign": {"course_sign": True},
    "rejected_memory": {"rejected_memory": True},  # on by default since stop 34
    "sweep_fixed_frame": {"sweep_fixed_frame": True},
    "home_hold": {"home_hold_m": 0.6},  # 0.6 by default since stop 37 (0.15 as a switch before)
    "held_no_support": {"sensing.held_no_support": True},
    "gap_hold": {"sensing.gap_hold_s": 3.0},  # on by default since stop 38
    "place": {"place_radius_m": 0.4},  # on by default since stop 30; older commands still run
    # On by default since stop 37; older commands still run.
    "hold_on": {"home_hold_m": 0.6, "sweep_join_pieces": True, "sweep_shallow_bend": True},
    "coast": {"off_edge_coast_s": 1.0},
    "keep": {"home_keep_m": 0.1},
    "vertex": {"sweep_vertex": True},  # on by default since stop 53
    "jump": {"swing_jump_m": 0.15},  # on by default since stop 49
    "recess": {"sweep_recess": True, "place_corners": True},  # on by default since stop 36
    "contact_memory": {"contact_hold_s": 60.0},
    "touch_pinch": {"pinch_touch_rad": math.radians(80.0)},  # stop 59
}
SWITCHES = tuple(_SETS)


def tracer_params(switches: list[str]) -> TracerParams:
    """TracerParams with the named switches on; a UserError names one that is not."""
    unknown = sorted(set(switches) - set(SWITCHES))
    if unknown:
        raise UserError(f"no tracer switch {unknown[0]!r}; the switches: {', '.join(SWITCHES)}")
    fields = {k: v for name in sorted(set(switches)) for k, v in _SETS[name].items()}
    sensing = {k.removeprefix("sensing."): v for k, v in fields.items() if k.startswith("sensing.")}
    tracer = {k: v for k, v in fields.items() if not k.startswith("sensing.")}
    return TracerParams(sensing=SensingParams(**sensing), **tracer)


def _run(args: argparse.Namespace) -> int:
    if args.edges < 1:
        raise UserError(f"--edges must be at least 1, got {args.edges}")
    if not 1.0 <= args.rate <= 100.0:
        raise UserError(f"--rate must be between 1 and 100 Hz, got {args.rate}")
    tracer_params(args.switch)  # a bad name is refused before the world is loaded
    backend = create_backend(
        {"backend": "sim", "world": args.world, "seed": args.seed, "drift": args.drift}
    )
    assert isinstance(backend, SimBackend)
    run = run_trace(backend, args.edges, args.rate, args.max_time, args.switch)
    out = Path(args.out)
    write_text_atomic(out / "trace_report.json", json.dumps(run.report, indent=2) + "\n")
    svg = _render(backend, run.gvg, run.path, run.dr_path, run.nodes)
    write_text_atomic(out / "trace.svg", svg)
    print(json.dumps(run.report, indent=2))
    return 0


class TraceRun(NamedTuple):
    report: dict[str, Any]
    gvg: GroundTruthGVG
    path: list[tuple[float, float, float]]  # true x, y and the encoder distance
    dr_path: list[tuple[float, float]]  # dead-reckoned, in the world's frame
    nodes: list[SeenNode]


def run_trace(
    backend: SimBackend,
    edges_wanted: int,
    rate_hz: float = 10.0,
    max_time_s: float | None = None,
    switches: Sequence[str] = (),
) -> TraceRun:
    """Trace ``edges_wanted`` edges on ``backend``, with the tracer's ``switches`` on, and
    score them against the ground truth."""
    gvg = compute_gvg(backend.world)
    robot = backend.robot
    tracer = Tracer(backend.limits, tracer_params(list(switches)))
    period = 1.0 / rate_hz
    max_time = max_time_s or 120.0 + 60.0 * edges_wanted
    path, dr_path = [], []
    nodes: list[SeenNode] = []
    edges: list[SeenEdge] = []
    started = time.perf_counter()
    with backend:
        clock = backend.clock
        while clock.now() < max_time and len(edges) < edges_wanted:
            odo = backend.odometry()
            twist, events = tracer.step(backend.scan(), odo, backend.status(), clock.now())
            backend.command(twist)
            tp = robot.true_pose()
            for ev in events:
                if isinstance(ev, MeetPointReached | BoundaryReached):
                    kind = "meet" if isinstance(ev, MeetPointReached) else "boundary"
                    degree = ev.degree if isinstance(ev, MeetPointReached) else 1
                    nodes.append(SeenNode(kind, tp.x, tp.y, degree, odo.distance_m))
                    print(f"t={clock.now():7.1f} s  {kind} point, degree {degree}", flush=True)
                elif isinstance(ev, EdgeTraversed) and nodes:
                    # The edge ends at the node reported with it (appended just after).
                    edges.append(SeenEdge(len(nodes) - 1, len(nodes), ev.length_m))
            path.append((tp.x, tp.y, odo.distance_m))
            dr_path.append(robot.odometry_to_world(odo.x_m, odo.y_m))
            clock.sleep(period)
        backend.stop()
    edges = [e for e in edges if e.end < len(nodes)]
    wall = time.perf_counter() - started
    report = {
        "world": backend.world.name,
        "seed": robot.seed,
        "drift": robot.p.drift,
        "switches_on": sorted(set(switches)),
        "edges_requested": edges_wanted,
        "edges_traced": len(edges),
        "complete": len(edges) >= edges_wanted,
        "sim_time_s": round(robot.t, 2),
        "wall_time_s": round(wall, 2),
        "collisions": robot.collisions,
        **score_trace(gvg, np.asarray(path, dtype=float).reshape(-1, 3), nodes, edges),
    }
    return TraceRun(report, gvg, path, dr_path, nodes)


def _render(
    backend: SimBackend,
    gvg: GroundTruthGVG,
    path: list[tuple[float, float, float]],
    dr_path: list[tuple[float, float]],
    nodes: list[SeenNode],
) -> str:
    from tslam.programs.pictures import run_canvas

    legend = "black: true path   red: dead reckoning   magenta: homed meet points   blue: GVG"
    true_path = [(x, y) for x, y, _ in path]
    canvas = run_canvas(backend.world, gvg, true_path, dr_path, legend)
    for n in nodes:
        canvas.circle(n.x, n.y, 0.08, fill="#ff00ff" if n.kind == "meet" else "#00aa00")
    return canvas.to_string()
