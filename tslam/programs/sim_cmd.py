"""``tslam sim``: run the simulated robot in a world and report what happened.

The robot is driven through the hal exactly as a real one would be: configure, activate,
a fixed-rate control loop on the backend's clock, close. Until the exploration arbiter lands
the controller is the reactive wanderer; the report shows how far dead reckoning drifts
from the truth, which is the problem topological SLAM exists to solve.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

from hal.registry import create_backend
from hal.types import Twist
from sim_backend.backend import SimBackend
from sim_backend.odometry_model import DRIFT_LEVELS
from tslam.programs.cli import UserError
from tslam.programs.output import write_text_atomic
from tslam.programs.wander import Wanderer


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sim", help="run the simulated robot in a world")
    p.add_argument("--world", default="fig14", help="built-in name or world file (default fig14)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--drift", choices=DRIFT_LEVELS, default="paper", help="encoder drift level")
    p.add_argument("--duration", type=float, default=600.0, help="simulated seconds (600)")
    p.add_argument("--rate", type=float, default=10.0, help="control loop rate in Hz (10)")
    p.add_argument("--out", default=None, help="directory for run.json and run.svg")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(run=_run)


def run_sim(
    world: str, seed: int, drift: str, duration_s: float, rate_hz: float, progress: bool = True
) -> tuple[dict[str, Any], dict[str, list[tuple[float, float]]], SimBackend]:
    """Drive the simulated robot for ``duration_s``; return the summary and both paths."""
    if not (duration_s > 0 and math.isfinite(duration_s)):
        raise UserError(f"--duration must be a positive number of seconds, got {duration_s}")
    if not (0.5 <= rate_hz <= 1000):
        raise UserError(f"--rate must be between 0.5 and 1000 Hz, got {rate_hz}")
    backend = create_backend({"backend": "sim", "world": world, "seed": seed, "drift": drift})
    assert isinstance(backend, SimBackend)
    robot = backend.robot
    period = 1.0 / rate_hz
    true_path: list[tuple[float, float]] = []
    dr_path: list[tuple[float, float]] = []
    max_err = 0.0
    next_report = 0.0
    wanderer = Wanderer(backend.limits)
    with backend:
        clock = backend.clock
        t0 = clock.now()
        while clock.now() - t0 < duration_s:
            odo = backend.odometry()
            twist = wanderer.step(
                backend.scan(), backend.status(), odo.turret_rad - odo.heading_rad, clock.now()
            )
            backend.command(twist)
            clock.sleep(period)
            tp = robot.true_pose()
            dx, dy = robot.odometry_to_world(odo.x_m, odo.y_m)
            true_path.append((tp.x, tp.y))
            dr_path.append((dx, dy))
            err = math.hypot(tp.x - dx, tp.y - dy)
            max_err = max(max_err, err)
            if progress and clock.now() - t0 >= next_report:
                print(
                    f"t={clock.now() - t0:7.1f} s  travelled {odo.distance_m:7.1f} m  "
                    f"dead-reckoning error {err:5.2f} m  collisions {robot.collisions}",
                    flush=True,
                )
                next_report += max(30.0, duration_s / 10)
        backend.command(Twist())
        odo = backend.odometry()
    tp = robot.true_pose()
    dx, dy = robot.odometry_to_world(odo.x_m, odo.y_m)
    heading_err = math.degrees(
        math.atan2(
            math.sin(odo.heading_rad + robot.world.start.theta - tp.theta),
            math.cos(odo.heading_rad + robot.world.start.theta - tp.theta),
        )
    )
    summary = {
        "world": robot.world.name,
        "seed": seed,
        "drift": drift,
        "simulated_s": round(robot.t, 3),
        "distance_m": round(odo.distance_m, 3),
        "rings_fired": robot.ring.fired // robot.p.n_sonars,
        "collisions": robot.collisions,
        "final_position_error_m": round(math.hypot(tp.x - dx, tp.y - dy), 3),
        "max_position_error_m": round(max_err, 3),
        "final_heading_error_deg": round(heading_err, 2),
    }
    return summary, {"true": true_path, "dead_reckoned": dr_path}, backend


def _run(args: argparse.Namespace) -> int:
    import time

    started = time.perf_counter()
    summary, paths, backend = run_sim(
        args.world, args.seed, args.drift, args.duration, args.rate, progress=not args.quiet
    )
    wall = time.perf_counter() - started
    summary["wall_s"] = round(wall, 3)
    summary["realtime_factor"] = round(summary["simulated_s"] / max(wall, 1e-9), 1)
    if args.out:
        out = Path(args.out)
        write_text_atomic(out / "run.json", json.dumps(summary, indent=2) + "\n")
        write_text_atomic(out / "run.svg", _render(backend, paths))
        summary["outputs"] = [str(out / "run.json"), str(out / "run.svg")]
    print(json.dumps(summary, indent=2))
    return 0


def _render(backend: SimBackend, paths: dict[str, list[tuple[float, float]]]) -> str:
    from sim_backend.ground_truth import compute_gvg
    from tslam.programs.pictures import run_canvas

    world = backend.world
    return run_canvas(world, compute_gvg(world), paths["true"], paths["dead_reckoned"]).to_string()
