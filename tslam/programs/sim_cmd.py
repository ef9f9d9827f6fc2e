"""``tslam sim``: a full T-SLAM exploration of a world by the simulated robot.

The robot is driven through the hal exactly as a real one is (configure, activate, a
fixed-rate control loop on the backend's clock, close) by the exploration arbiter. Progress
goes to stderr as it happens; the report, scored against the world's ground truth, goes to
stdout and with the map and two pictures to ``--out``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hal.types import Twist
from sim_backend.backend import SimBackend
from sim_backend.explore_scoring import naive_baseline, score_exploration, true_node_of
from sim_backend.ground_truth import GroundTruthGVG, compute_gvg
from sim_backend.odometry_model import DRIFT_LEVELS
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.topomap import TopoMap
from tslam.core.tracer import MeetPointReached, TracerParams
from tslam.programs.cli import UserError
from tslam.programs.output import write_text_atomic
from tslam.programs.sim_backends import (
    BackendChoice,
    add_arguments,
    choice_from_args,
    open_backend,
)

#: Simulated seconds allowed when ``--duration`` is not given: far more than any of the
#: paper's worlds needs, so a run of one that has not finished by then is stuck and says so.
#: A generated office floor needs more: its GVG is 1.6-1.8 km, 2.2-2.6 hours to trace once.
DEFAULT_LIMIT_S = 4 * 3600.0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sim", help="explore a world with the simulated robot (T-SLAM)")
    p.add_argument("--world", default="fig14", help="built-in name or world file (default fig14)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--drift", choices=DRIFT_LEVELS, default="paper", help="encoder drift level")
    p.add_argument(
        "--duration", type=float, default=None,
        help="stop after this many simulated seconds even if exploration is not complete",
    )  # fmt: skip
    p.add_argument("--rate", type=float, default=10.0, help="control loop rate in Hz (10)")
    p.add_argument("--out", default=None, help="directory for map.json, map.svg, ... report.json")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    add_arguments(p)  # --backend: in process, or through the drivers to emulators
    p.set_defaults(run=_run)


@dataclass
class Run:
    """Everything a finished run leaves for reports and pictures."""

    backend: SimBackend
    explorer: Explorer
    gvg: GroundTruthGVG
    true_path: list[tuple[float, float]] = field(default_factory=list)
    dr_path: list[tuple[float, float]] = field(default_factory=list)
    arrivals: list[tuple[float, float, float, float]] = field(default_factory=list)
    max_odometry_error_m: float = 0.0
    wall_time_s: float = 0.0


def explore(
    world: str,
    seed: int,
    drift: str,
    duration_s: float | None = None,
    rate_hz: float = 10.0,
    progress: bool = True,
    backend_choice: BackendChoice | None = None,
    params: ExplorerParams | None = None,
    tracer_params: TracerParams | None = None,
) -> Run:
    """Explore ``world`` until the arbiter says it is done or ``duration_s`` runs out
    (``params``: the arbiter's settings, the defaults if None)."""
    limit = DEFAULT_LIMIT_S if duration_s is None else duration_s
    if not (limit > 0 and math.isfinite(limit)):
        raise UserError(f"--duration must be a positive number of seconds, got {duration_s}")
    if not (0.5 <= rate_hz <= 1000):
        raise UserError(f"--rate must be between 0.5 and 1000 Hz, got {rate_hz}")
    backend = open_backend(backend_choice or BackendChoice(), world, seed, drift)
    robot = backend.robot
    gvg = compute_gvg(backend.world)

    def truth() -> tuple[float, float]:
        tp = robot.true_pose()
        return (tp.x, tp.y)

    explorer = Explorer(backend.limits, params=params, tracer_params=tracer_params, truth=truth)
    run = Run(backend, explorer, gvg)
    period = 1.0 / rate_hz
    started = time.perf_counter()
    shown = 0
    next_status = 0.0
    with backend:
        clock = backend.clock
        t0 = clock.now()
        while not explorer.done and clock.now() - t0 < limit:
            odo = backend.odometry()
            twist, events = explorer.step(backend.scan(), odo, backend.status(), clock.now())
            backend.command(twist)
            tp = robot.true_pose()
            dx, dy = robot.odometry_to_world(odo.x_m, odo.y_m)
            run.true_path.append((tp.x, tp.y))
            run.dr_path.append((dx, dy))
            err = math.hypot(tp.x - dx, tp.y - dy)
            run.max_odometry_error_m = max(run.max_odometry_error_m, err)
            for ev in events:
                if isinstance(ev, MeetPointReached):
                    run.arrivals.append((dx, dy, tp.x, tp.y))
            if progress:
                for note in explorer.notes[shown:]:
                    _say(f"t={note.stamp_s - t0:7.1f} s  {note.text}")
                shown = len(explorer.notes)
                if clock.now() - t0 >= next_status:
                    _say(
                        f"t={clock.now() - t0:7.1f} s  {explorer.mode.value:12s} "
                        f"{len(explorer.map.nodes())} nodes {len(explorer.map.edges())} edges, "
                        f"{len(explorer.unexplored())} departures to explore, "
                        f"odometry error {err:5.2f} m"
                    )
                    next_status += 60.0
            clock.sleep(period)
        backend.command(Twist())
    run.wall_time_s = time.perf_counter() - started
    return run


def report(run: Run, world_spec: str, seed: int, drift: str) -> dict[str, Any]:
    robot = run.backend.robot
    ex = run.explorer
    tmap = ex.map
    odo_distance = ex._odo.distance_m if ex._odo is not None else 0.0
    score = score_exploration(
        run.gvg, tmap.to_dict(), [[(d, r, td, tr) for d, r, td, tr in m.pairs] for m in ex.merges]
    )
    arrivals = [
        (x, y, true_node_of(run.gvg, (tx, ty), "meet", 0.75)) for x, y, tx, ty in run.arrivals
    ]
    gvg_len = run.gvg.gvg_length_m
    return {
        "world": run.backend.world.name,
        "world_spec": world_spec,
        "seed": seed,
        "drift": drift,
        # The explorer's own "nothing left to explore" is not enough: a robot that turned
        # back mid-corridor can call a third of fig16 the whole (seed 5). Complete is that
        # and the map right against the ground truth: every place and edge, no node twice.
        "complete": bool(
            ex.done and not tmap.unexplored() and score["covered"] and not score["duplicate_nodes"]
        ),
        "finished": ex.done,
        **score,
        "unexplored_departures": len(tmap.unexplored()),
        "merges": len(ex.merges),
        "path_length_m": round(odo_distance, 2),
        "gvg_length_m": round(gvg_len, 2),
        "path_over_gvg": round(odo_distance / gvg_len, 2) if gvg_len > 0 else None,
        "max_odometry_error_m": round(run.max_odometry_error_m, 3),
        "collisions": robot.collisions,
        "sim_time_s": round(robot.t, 2),
        "wall_time_s": round(run.wall_time_s, 2),
        "realtime_factor": round(robot.t / max(run.wall_time_s, 1e-9), 1),
        "baseline": naive_baseline(arrivals),
    }


def write_outputs(run: Run, rep: dict[str, Any], out: Path) -> list[str]:
    from tslam.programs.map_files import map_to_json

    tmap = run.explorer.map
    files = {
        "map.json": map_to_json(tmap),
        "map.svg": _map_svg(run),
        "trajectory.svg": _trajectory_svg(run),
        "report.json": json.dumps(rep, indent=2) + "\n",
    }
    for name, text in files.items():
        write_text_atomic(out / name, text)
    return [str(out / n) for n in files]


def _run(args: argparse.Namespace) -> int:
    choice = choice_from_args(args)
    run = explore(
        args.world, args.seed, args.drift, args.duration, args.rate, not args.quiet, choice
    )
    rep = report(run, args.world, args.seed, args.drift)
    rep["backend"] = choice.kind
    if choice.fire_interval_s is not None:
        rep["fire_interval_s"] = choice.fire_interval_s
    if args.out:
        rep["outputs"] = write_outputs(run, rep, Path(args.out))
    print(json.dumps(rep, indent=2))
    return 0


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def _map_svg(run: Run) -> str:
    """The map over the ground truth: nodes at their dead-reckoned poses (in the world frame
    the robot started in), each joined by a thin line to where it really was."""
    from sim_backend.svg import draw_gvg, draw_world
    from tslam.programs.map_files import render_map_svg

    robot = run.backend.robot
    data = run.explorer.map.to_dict()
    for n in data["nodes"]:
        n["pose"] = list(robot.odometry_to_world(*n["pose"]))
    world = run.backend.world

    def background(canvas: Any) -> None:
        draw_world(canvas, world)
        draw_gvg(canvas, run.gvg)

    xmin, ymin, xmax, ymax = world.bounds
    poses = [n["pose"] for n in data["nodes"]] or [[xmin, ymin]]
    bounds = (
        min(xmin, *(p[0] for p in poses)) - 0.5,
        min(ymin, *(p[1] for p in poses)) - 0.5,
        max(xmax, *(p[0] for p in poses)) + 0.5,
        max(ymax, *(p[1] for p in poses)) + 0.5,
    )
    return render_map_svg(
        TopoMap.from_dict(data), background=background, bounds=bounds, show_truth=True
    )


def _trajectory_svg(run: Run) -> str:
    from tslam.programs.pictures import run_canvas

    step = max(1, len(run.true_path) // 20000)
    return run_canvas(
        run.backend.world, run.gvg, run.true_path[::step], run.dr_path[::step]
    ).to_string()
