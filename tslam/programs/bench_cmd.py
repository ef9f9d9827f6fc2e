"""``tslam bench sim``: simulator throughput and memory, printed as one JSON object."""

from __future__ import annotations

import argparse
import json
import resource
import sys


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="benchmarks that print figures")
    bsub = p.add_subparsers(dest="bench_command", required=True, metavar="WHAT")
    sim = bsub.add_parser("sim", help="sonar ring scans per second, simulator speed, memory")
    sim.add_argument("--json", action="store_true", help="print one JSON object (default)")
    sim.add_argument("--office-seed", type=int, default=1, help="seed of the 50 x 50 m office")
    sim.set_defaults(run=_bench_sim)
    ctl = bsub.add_parser("control", help="time of one control step (scan to drive command)")
    ctl.add_argument("--json", action="store_true", help="print one JSON object (default)")
    ctl.add_argument("--world", default="fig14", help="world to trace in (fig14)")
    ctl.add_argument("--steps", type=int, default=3000, help="control steps to time (3000)")
    ctl.set_defaults(run=_bench_control)
    from tslam.programs import bench_can, bench_explore, bench_link, bench_serial

    bench_serial.add_parser(bsub)
    bench_can.add_parser(bsub)
    bench_link.add_parser(bsub)
    bench_explore.add_parser(bsub)


def _bench_control(args: argparse.Namespace) -> int:
    import time

    import numpy as np

    from hal.registry import create_backend
    from sim_backend.backend import SimBackend
    from tslam.core.tracer import Tracer

    backend = create_backend({"backend": "sim", "world": args.world, "seed": 1})
    assert isinstance(backend, SimBackend)
    tracer = Tracer(backend.limits)
    times = []
    with backend:
        clock = backend.clock
        for _ in range(max(1, args.steps)):
            scan, odo, status = backend.scan(), backend.odometry(), backend.status()
            t0 = time.perf_counter()
            twist, _ = tracer.step(scan, odo, status, clock.now())
            times.append(time.perf_counter() - t0)
            backend.command(twist)
            clock.sleep(0.1)
    ms = np.array(times[50:] or times) * 1000.0  # leave out the first steps (warm-up)
    result = {
        "world": args.world,
        "steps": len(ms),
        "step_ms_median": round(float(np.median(ms)), 4),
        "step_ms_p99": round(float(np.percentile(ms, 99)), 4),
        "target_step_ms_median": 0.2,
    }
    print(json.dumps(result, indent=2))
    return 0


def _bench_sim(args: argparse.Namespace) -> int:
    from sim_backend.bench import ring_scans_per_s, sim_realtime_factor
    from sim_backend.world_files import load_world

    worlds = {"fig14": "fig14", "office": f"office:{args.office_seed}"}
    result: dict[str, object] = {"target_scans_per_s": 2000}
    rates = []
    for key, spec in worlds.items():
        world = load_world(spec)
        ring_scans_per_s(world, n_poses=20, rings_per_pose=2)  # compile and warm caches
        print(f"bench: {spec} ...", file=sys.stderr, flush=True)
        rates.append(round(ring_scans_per_s(world), 1))
        result[key] = {
            "world": spec,
            "size_m": [round(world.width_m, 1), round(world.height_m, 1)],
            "walls": len(world.segments),
            "scans_per_s": rates[-1],
            "sim_realtime_factor": round(sim_realtime_factor(world), 1),
        }
    result["scans_per_s"] = min(rates)
    result["peak_rss_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)
    print(json.dumps(result, indent=2))
    return 0
