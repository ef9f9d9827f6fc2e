"""``tslam bench explore``: T-SLAM against the naive dead-reckoning baseline, world by world.

Every (world, drift, seed) is one full ``tslam sim`` exploration (``sim_cmd.explore`` and
``sim_cmd.report``) in a worker process. The baseline is the paper's naive method replayed on
the same run's meet-point arrivals, so both methods are scored on exactly the same trajectory.
A run depends on its seed alone, so the figures are the same whatever ``--jobs`` is and in
whatever order the workers finish; rows are always listed in (world, drift, seed) order.

Progress (one line per finished run) goes to stderr; the table, or with ``--json`` one JSON
object ``{"runs", "summary", "targets"}``, goes to stdout and with ``--out`` to files.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import os
import re
import statistics
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

from tslam.programs.cli import UserError
from tslam.programs.sim_backends import BackendChoice, add_fire_interval, check_fire_interval

DEFAULT_SEEDS = (1, 2, 3)
_SEED_RE = re.compile(r"[0-9]+")

#: Where an incomplete map is accepted: fig15 is symmetric, so once the odometry drifts no
#: move can tell its look-alike meet points apart and the ambiguity is recorded instead.
COMPLETE_EXEMPT = {("fig15", "paper"), ("fig15", "severe")}
PATH_OVER_GVG_MAX = 2.5
REALTIME_WORLD = "fig14"
REALTIME_MIN = 100.0

#: The report fields a row copies for T-SLAM, in the order they appear in the JSON.
TSLAM_FIELDS = (
    "complete",
    "finished",
    "covered",
    "found_places",
    "true_places",
    "found_place_edges",
    "true_place_edges",
    "false_merges",
    "loop_closures_true",
    "loop_closures_found",
    "duplicate_nodes",
    "wrong_edges",
    "found_meet_points",
    "true_meet_points",
    "found_edges",
    "true_edges",
    "ambiguous_nodes",
    "path_over_gvg",
    "max_odometry_error_m",
    "collisions",
    "sim_time_s",
    "wall_time_s",
    "realtime_factor",
)
BASELINE_FIELDS = ("false_merges", "missed_revisits", "revisits_recognised")

Row = dict[str, Any]


class Task(NamedTuple):
    world: str
    drift: str
    seed: int
    duration_s: float
    switches: tuple[str, ...] = ()  # the tracer's, turned on (trace_cmd.SWITCHES)
    fire_interval_s: float | None = None  # the simulated ring's; None: the Nomad's


@dataclass(frozen=True)
class Selection:
    worlds: list[str]
    drifts: list[str]
    seeds: list[int]
    jobs: int
    duration_s: float

    def tasks(self) -> list[Task]:
        return [
            Task(w, d, s, self.duration_s)
            for w in self.worlds
            for d in self.drifts
            for s in self.seeds
        ]


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "explore", help="T-SLAM vs the dead-reckoning baseline over worlds, drifts and seeds"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object, not a table")
    p.add_argument("--worlds", default=None, help="comma-separated (default: every figure world)")
    p.add_argument("--drifts", default=None, help="comma-separated (default: none,paper,severe)")
    p.add_argument("--seeds", default=None, help="comma-separated integers (default: 1,2,3)")
    p.add_argument("--jobs", type=int, default=None, help="worker processes (default: CPUs)")
    p.add_argument(
        "--duration", type=float, default=None,
        help="simulated seconds allowed per run (default: the limit of tslam sim)",
    )  # fmt: skip
    p.add_argument("--out", default=None, help="also write bench_explore.json and .txt here")
    p.add_argument(
        "--switch",
        action="append",
        default=[],
        metavar="NAME",
        help="turn on one of the tracer's switches in every run (see tslam trace --help)",
    )
    add_fire_interval(p)
    p.set_defaults(run=_run)


# ---------------------------------------------------------------------------------------------
# What to run
# ---------------------------------------------------------------------------------------------


def default_worlds() -> list[str]:
    """The paper's figure worlds; the seeded generators need a seed, so they are opt-in."""
    from sim_backend.builtin_worlds import builtin_names

    return [n for n in builtin_names() if ":" not in n]


def parse_selection(
    worlds: str | None,
    drifts: str | None,
    seeds: str | None,
    jobs: int | None,
    duration_s: float | None,
) -> Selection:
    """Check what the user asked for; every mistake is a ``UserError`` naming the bad value."""
    from sim_backend.odometry_model import DRIFT_LEVELS
    from tslam.programs.sim_cmd import DEFAULT_LIMIT_S

    world_list = default_worlds() if worlds is None else _split("--worlds", worlds)
    for w in world_list:
        _check_world(w)
    drift_list = list(DRIFT_LEVELS) if drifts is None else _split("--drifts", drifts)
    for d in drift_list:
        if d not in DRIFT_LEVELS:
            raise UserError(
                f"--drifts: unknown drift level {d!r} (choose from {', '.join(DRIFT_LEVELS)})"
            )
    seed_list = (
        list(DEFAULT_SEEDS) if seeds is None else [_seed(s) for s in _split("--seeds", seeds)]
    )
    n_jobs = (os.cpu_count() or 1) if jobs is None else jobs
    if n_jobs < 1:
        raise UserError(f"--jobs must be at least 1, got {jobs}")
    limit = DEFAULT_LIMIT_S if duration_s is None else duration_s
    if not (limit > 0 and math.isfinite(limit)):
        raise UserError(f"--duration must be a positive number of seconds, got {duration_s}")
    return Selection(world_list, drift_list, seed_list, n_jobs, limit)


def _split(option: str, text: str) -> list[str]:
    items = [t.strip() for t in text.split(",")]
    if not all(items):
        raise UserError(f"{option}: empty name in {text!r}")
    return list(dict.fromkeys(items))  # a repeated name would only repeat identical runs


def _check_world(name: str) -> None:
    """Built-ins only: a bench is meant to be rerun and compared, so no ad-hoc world files."""
    from sim_backend.builtin_worlds import builtin_names, is_builtin_name

    _, sep, seed = name.partition(":")
    if is_builtin_name(name) and (not sep or _SEED_RE.fullmatch(seed)):
        return
    raise UserError(f"--worlds: unknown world {name!r} (choose from {', '.join(builtin_names())})")


def _seed(text: str) -> int:
    if not _SEED_RE.fullmatch(text):
        raise UserError(f"--seeds: a seed must be a non-negative integer, got {text!r}")
    return int(text)


# ---------------------------------------------------------------------------------------------
# Running
# ---------------------------------------------------------------------------------------------


def run_one(task: Task) -> Row:
    """One exploration and its report, reduced to a bench row (runs in a worker process)."""
    from tslam.programs.sim_cmd import explore, report
    from tslam.programs.trace_cmd import tracer_params

    tracer = tracer_params(list(task.switches))
    choice = BackendChoice(fire_interval_s=task.fire_interval_s)
    run = explore(
        task.world,
        task.seed,
        task.drift,
        task.duration_s,
        progress=False,
        backend_choice=choice,
        tracer_params=tracer,
    )
    return row_from_report(task, report(run, task.world, task.seed, task.drift))


def row_from_report(task: Task, rep: dict[str, Any]) -> Row:
    row: Row = {"world": task.world, "drift": task.drift, "seed": task.seed}
    for k in TSLAM_FIELDS:
        row[k] = rep[k]
        if k == "false_merges":  # the two failure counts side by side
            row["missed_closures"] = max(0, rep["loop_closures_true"] - rep["loop_closures_found"])
    row["baseline"] = {k: rep["baseline"][k] for k in BASELINE_FIELDS}
    return row


def error_row(task: Task, exc: BaseException) -> Row:
    message = str(exc) or type(exc).__name__
    return {"world": task.world, "drift": task.drift, "seed": task.seed, "error": message}


def collect(
    tasks: Sequence[Task],
    jobs: int,
    worker: Callable[[Task], Row] = run_one,
    say: Callable[[str], None] | None = None,
) -> list[Row]:
    """Run every task in worker processes; rows come back in the order of ``tasks``.

    A task that raises (or whose worker dies) becomes an error row, never the bench's end.
    """
    say = say or _say
    rows: list[Row | None] = [None] * len(tasks)
    # "spawn": workers start from a clean interpreter, so nothing the parent happens to hold
    # (threads, caches, a half-built world) can leak into a run and make it differ by job count.
    ctx = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(max_workers=max(1, min(jobs, len(tasks))), mp_context=ctx)
    try:
        futures: dict[Future[Row], int] = {pool.submit(worker, t): i for i, t in enumerate(tasks)}
        for done, fut in enumerate(as_completed(futures), start=1):
            i = futures[fut]
            try:
                rows[i] = fut.result()
            except Exception as exc:
                rows[i] = error_row(tasks[i], exc)
            say(progress_line(done, len(tasks), rows[i]))
    finally:
        # On Ctrl-C, do not start the runs still queued; the running ones get the signal too.
        pool.shutdown(wait=True, cancel_futures=True)
    return [r for r in rows if r is not None]


def progress_line(done: int, total: int, row: Row) -> str:
    width = len(str(total))
    head = f"[{done:{width}d}/{total}] {row['world']} {row['drift']} s{row['seed']}"
    if "error" in row:
        return f"{head}: error: {row['error']}"
    state = (
        "complete"
        if row["complete"]
        else "finished with a wrong map"
        if row["finished"]
        else "incomplete"
    )
    return (
        f"{head}: {state}, {row['false_merges']} false merges, "
        f"{row['loop_closures_found']}/{row['loop_closures_true']} loops, "
        f"{row['wall_time_s']:.1f} s wall"
    )


# ---------------------------------------------------------------------------------------------
# Summary and targets
# ---------------------------------------------------------------------------------------------


def summarize(rows: Sequence[Row]) -> dict[str, dict[str, dict[str, Any]]]:
    """Per method, per drift level (in the order first seen) and over all runs."""
    drifts = list(dict.fromkeys(r["drift"] for r in rows))
    groups = {d: [r for r in rows if r["drift"] == d] for d in drifts}
    groups["all"] = list(rows)
    return {
        "tslam": {d: _tslam_summary(g) for d, g in groups.items()},
        "baseline": {d: _baseline_summary(g) for d, g in groups.items()},
    }


def _tslam_summary(rows: Sequence[Row]) -> dict[str, Any]:
    ok = [r for r in rows if "error" not in r]
    paths = [r["path_over_gvg"] for r in ok if r["path_over_gvg"] is not None]
    rts = [r["realtime_factor"] for r in ok]
    return {
        "runs": len(ok),
        "errors": len(rows) - len(ok),
        "complete": sum(1 for r in ok if r["complete"]),
        # Runs the explorer called done on a map the ground truth says is wrong.
        "finished_wrong": sum(1 for r in ok if r["finished"] and not r["complete"]),
        "false_merges": sum(r["false_merges"] for r in ok),
        "runs_with_false_merges": sum(1 for r in ok if r["false_merges"] > 0),
        "missed_closures": sum(r["missed_closures"] for r in ok),
        "wrong_edges": sum(r["wrong_edges"] for r in ok),
        # Contacts with a wall: a ring's blind spots (a corner between two beams, or nearer
        # than a transducer reads) that the bumper, not the sonar, found.
        "collisions": sum(r["collisions"] for r in ok),
        "path_over_gvg_median": _median(paths),
        "path_over_gvg_max": max(paths, default=None),
        "realtime_factor_median": _median(rts),
        "realtime_factor_min": min(rts, default=None),
    }


def _baseline_summary(rows: Sequence[Row]) -> dict[str, Any]:
    ok = [r["baseline"] for r in rows if "error" not in r]
    return {
        "runs": len(ok),
        "errors": len(rows) - len(ok),
        "false_merges": sum(b["false_merges"] for b in ok),
        "runs_with_false_merges": sum(1 for b in ok if b["false_merges"] > 0),
        "missed_revisits": sum(b["missed_revisits"] for b in ok),
    }


def _median(values: Sequence[float]) -> float | None:
    return round(statistics.median(values), 2) if values else None


def targets(rows: Sequence[Row]) -> dict[str, dict[str, Any]]:
    """The issue's targets for T-SLAM, each judged on the runs it applies to.

    ``met`` is None when no run applies (e.g. no fig14 run was asked for); a run that errored
    counts as failing every target it applies to, since it proved nothing.
    """
    return {
        "zero_false_merges": _target(
            "no false merge in any run",
            rows,
            applies=lambda r: True,
            passes=lambda r: r["false_merges"] == 0,
        ),
        "complete": _target(
            "complete map in every run except fig15 at paper and severe drift",
            rows,
            applies=lambda r: (r["world"], r["drift"]) not in COMPLETE_EXEMPT,
            passes=lambda r: bool(r["complete"]),
        ),
        "path_over_gvg": {
            "limit": PATH_OVER_GVG_MAX,
            **_target(
                f"path length at most {PATH_OVER_GVG_MAX} x the GVG's length in every run",
                rows,
                applies=lambda r: True,
                passes=lambda r: (
                    r["path_over_gvg"] is None or r["path_over_gvg"] <= PATH_OVER_GVG_MAX
                ),
            ),
        },
        "realtime_factor": {
            "world": REALTIME_WORLD,
            "limit": REALTIME_MIN,
            **_target(
                f"real-time factor at least {REALTIME_MIN:g} on {REALTIME_WORLD}",
                rows,
                applies=lambda r: r["world"] == REALTIME_WORLD,
                passes=lambda r: r["realtime_factor"] >= REALTIME_MIN,
            ),
        },
    }


def _target(
    description: str,
    rows: Iterable[Row],
    applies: Callable[[Row], bool],
    passes: Callable[[Row], bool],
) -> dict[str, Any]:
    checked = [r for r in rows if applies(r)]
    failing = [_label(r) for r in checked if "error" in r or not passes(r)]
    return {
        "description": description,
        "met": (not failing) if checked else None,
        "runs_checked": len(checked),
        "failing": failing,
    }


def _label(row: Row) -> str:
    return f"{row['world']}/{row['drift']}/s{row['seed']}" + (" (error)" if "error" in row else "")


# ---------------------------------------------------------------------------------------------
# Output
# ---------------------------------------------------------------------------------------------


def result_of(
    rows: Sequence[Row], switches: Sequence[str] = (), fire_interval_s: float | None = None
) -> dict[str, Any]:
    return {
        "tracer_switches_on": list(switches),
        "fire_interval_s": fire_interval_s,
        "runs": list(rows),
        "summary": summarize(rows),
        "targets": targets(rows),
    }


def render_text(result: dict[str, Any]) -> str:
    switches = result.get("tracer_switches_on")
    fire = result.get("fire_interval_s")
    parts = [
        "T-SLAM vs the naive dead-reckoning baseline (FM = false merges)"
        + (f"; tracer switches on: {', '.join(switches)}" if switches else "")
        + (f"; a transducer fired every {fire * 1000:g} ms" if fire else ""),
        "",
        _runs_table(result["runs"]),
        "",
        "summary, T-SLAM",
        _table(_TSLAM_SUMMARY_COLUMNS, _summary_rows(result["summary"]["tslam"])),
        "",
        "summary, baseline",
        _table(_BASELINE_SUMMARY_COLUMNS, _summary_rows(result["summary"]["baseline"])),
        "",
        "targets",
        *_target_lines(result["targets"]),
    ]
    return "\n".join(parts) + "\n"


Column = tuple[str, Callable[[Row], str], bool]  # header, cell, left-aligned


def _fmt(value: Any, spec: str = "") -> str:
    return "-" if value is None else format(value, spec)


_RUN_COLUMNS: list[Column] = [
    ("world", lambda r: r["world"], True),
    ("drift", lambda r: r["drift"], True),
    ("seed", lambda r: str(r["seed"]), False),
    ("complete", lambda r: "yes" if r["complete"] else "no", True),
    ("done", lambda r: "yes" if r["finished"] else "no", True),
    ("places", lambda r: f"{r['found_places']}/{r['true_places']}", False),
    ("FM tslam", lambda r: str(r["false_merges"]), False),
    ("FM base", lambda r: str(r["baseline"]["false_merges"]), False),
    ("missed closures", lambda r: str(r["missed_closures"]), False),
    ("missed revisits base", lambda r: str(r["baseline"]["missed_revisits"]), False),
    ("loops", lambda r: f"{r['loop_closures_found']}/{r['loop_closures_true']}", False),
    ("wrong edges", lambda r: str(r["wrong_edges"]), False),
    ("path/GVG", lambda r: _fmt(r["path_over_gvg"], ".2f"), False),
    ("contacts", lambda r: str(r["collisions"]), False),
    ("max odo err m", lambda r: _fmt(r["max_odometry_error_m"], ".3f"), False),
    ("RT factor", lambda r: _fmt(r["realtime_factor"], ".1f"), False),
]

_GROUP_COLUMNS: list[Column] = [
    ("drift", lambda s: s["drift"], True),
    ("runs", lambda s: str(s["runs"]), False),
    ("errors", lambda s: str(s["errors"]), False),
]
_FM_COLUMNS: list[Column] = [
    ("FM", lambda s: str(s["false_merges"]), False),
    ("runs with FM", lambda s: str(s["runs_with_false_merges"]), False),
]

_TSLAM_SUMMARY_COLUMNS: list[Column] = [
    *_GROUP_COLUMNS,
    ("complete", lambda s: f"{s['complete']}/{s['runs']}", False),
    ("done, map wrong", lambda s: str(s["finished_wrong"]), False),
    *_FM_COLUMNS,
    ("missed closures", lambda s: str(s["missed_closures"]), False),
    ("wrong edges", lambda s: str(s["wrong_edges"]), False),
    ("contacts", lambda s: str(s["collisions"]), False),
    ("path/GVG median", lambda s: _fmt(s["path_over_gvg_median"], ".2f"), False),
    ("path/GVG max", lambda s: _fmt(s["path_over_gvg_max"], ".2f"), False),
    ("RT median", lambda s: _fmt(s["realtime_factor_median"], ".1f"), False),
    ("RT min", lambda s: _fmt(s["realtime_factor_min"], ".1f"), False),
]

_BASELINE_SUMMARY_COLUMNS: list[Column] = [
    *_GROUP_COLUMNS,
    *_FM_COLUMNS,
    ("missed revisits", lambda s: str(s["missed_revisits"]), False),
]


def _runs_table(rows: Sequence[Row]) -> str:
    lines = _table(_RUN_COLUMNS, [r for r in rows if "error" not in r]).splitlines()
    # An error row has no figures to align; it keeps its place in the fixed order as one line.
    ok_lines = iter(lines[1:])
    out = [lines[0]]
    for r in rows:
        out.append(
            f"{r['world']} {r['drift']} s{r['seed']}: ERROR {r['error']}"
            if "error" in r
            else next(ok_lines)
        )
    return "\n".join(out)


def _summary_rows(groups: dict[str, dict[str, Any]]) -> list[Row]:
    return [{"drift": d, **s} for d, s in groups.items()]


def _table(columns: Sequence[Column], rows: Sequence[Row]) -> str:
    cells = [[cell(r) for _, cell, _ in columns] for r in rows]
    widths = [max([len(h), *(len(c[i]) for c in cells)]) for i, (h, _, _) in enumerate(columns)]

    def line(values: Sequence[str]) -> str:
        return "  ".join(
            v.ljust(w) if left else v.rjust(w)
            for v, w, (_, _, left) in zip(values, widths, columns, strict=True)
        ).rstrip()

    return "\n".join([line([h for h, _, _ in columns]), *(line(c) for c in cells)])


def _target_lines(results: dict[str, dict[str, Any]]) -> list[str]:
    lines = []
    for t in results.values():
        state = {True: "met", False: "NOT MET", None: "n/a"}[t["met"]]
        line = f"  {state:7s}  {t['description']} ({t['runs_checked']} runs)"
        if t["failing"]:
            line += ": failing " + ", ".join(t["failing"])
        lines.append(line)
    return lines


# ---------------------------------------------------------------------------------------------
# The command
# ---------------------------------------------------------------------------------------------


def _run(args: argparse.Namespace) -> int:
    from tslam.programs.output import write_text_atomic
    from tslam.programs.trace_cmd import tracer_params

    sel = parse_selection(args.worlds, args.drifts, args.seeds, args.jobs, args.duration)
    tracer_params(args.switch)  # a bad name is the user's error, before any run starts
    switches = tuple(sorted(set(args.switch)))
    fire = check_fire_interval(args.fire_interval)
    tasks = [t._replace(switches=switches, fire_interval_s=fire) for t in sel.tasks()]
    _say(
        f"bench explore: {len(tasks)} runs ({len(sel.worlds)} worlds x {len(sel.drifts)} drifts "
        f"x {len(sel.seeds)} seeds) on {min(sel.jobs, len(tasks))} workers"
    )
    started = time.perf_counter()
    # Looked up at call time (not bound as a default) so a test can swap the worker.
    rows = collect(tasks, sel.jobs, worker=run_one)
    _say(f"bench explore: done in {time.perf_counter() - started:.1f} s")
    result = result_of(rows, switches, fire)
    as_json = json.dumps(result, indent=2) + "\n"
    as_text = render_text(result)
    if args.out:
        write_text_atomic(Path(args.out) / "bench_explore.json", as_json)
        write_text_atomic(Path(args.out) / "bench_explore.txt", as_text)
    sys.stdout.write(as_json if args.json else as_text)
    return 1 if any("error" in r for r in rows) else 0


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)
