"""``tslam bench explore``: argument checks, rows equal to ``tslam sim``'s report, the summary
and targets computed from the rows, and a failing run that does not end the bench.

Only tiny runs here (fig12, two simulated minutes); the full bench takes many minutes.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tslam.programs import bench_explore
from tslam.programs.bench_explore import (
    Task,
    collect,
    parse_selection,
    render_text,
    result_of,
    row_from_report,
    summarize,
    targets,
)
from tslam.programs.cli import UserError, main
from tslam.programs.sim_backends import BackendChoice
from tslam.programs.sim_cmd import explore, report
from tslam.programs.trace_cmd import tracer_params

TSLAM = Path(sys.executable).with_name("tslam")
TINY = ["--worlds", "fig12", "--drifts", "none", "--seeds", "1", "--duration", "120"]


def _row(world="fig12", drift="paper", seed=1, **over):
    """A hand-made row shaped like ``row_from_report``'s."""
    row = {
        "world": world,
        "drift": drift,
        "seed": seed,
        "complete": True,
        "finished": True,
        "covered": True,
        "found_places": 3,
        "true_places": 3,
        "found_place_edges": 6,
        "true_place_edges": 6,
        "false_merges": 0,
        "loop_closures_true": 2,
        "loop_closures_found": 2,
        "duplicate_nodes": 0,
        "wrong_edges": 0,
        "found_meet_points": 3,
        "true_meet_points": 3,
        "found_edges": 6,
        "true_edges": 6,
        "ambiguous_nodes": 0,
        "path_over_gvg": 2.0,
        "max_odometry_error_m": 0.5,
        "collisions": 0,
        "sim_time_s": 500.0,
        "wall_time_s": 2.0,
        "realtime_factor": 250.0,
        "missed_closures": 0,
        "baseline": {"false_merges": 0, "missed_revisits": 0, "revisits_recognised": 4},
    }
    row.update(over)
    return row


def _fake_worker(task: Task) -> dict:
    """Stands in for ``run_one`` in the worker processes: seed 2 fails, the rest succeed."""
    if task.seed == 2:
        raise RuntimeError(f"boom in {task.world} seed {task.seed}")
    return _row(task.world, task.drift, task.seed)


# --- arguments -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "needle"),
    [
        ({"worlds": "fig12,fig99"}, "fig99"),
        ({"worlds": "office:x"}, "office:x"),
        ({"worlds": "fig12,,fig1"}, "--worlds"),
        ({"drifts": "none,wild"}, "wild"),
        ({"seeds": "1,two"}, "two"),
        ({"seeds": "-3"}, "-3"),
        ({"jobs": 0}, "--jobs"),
        ({"duration_s": 0.0}, "--duration"),
        ({"duration_s": float("nan")}, "nan"),
    ],
)
def test_bad_arguments_name_the_bad_value(kwargs, needle):
    args = {"worlds": None, "drifts": None, "seeds": None, "jobs": None, "duration_s": None}
    with pytest.raises(UserError, match=needle):
        parse_selection(**{**args, **kwargs})


def test_defaults_cover_every_figure_world_drift_and_three_seeds():
    sel = parse_selection(None, None, None, None, None)
    assert sel.worlds == ["fig1", "fig12", "fig13", "fig14", "fig15", "fig16"]
    assert sel.drifts == ["none", "paper", "severe"] and sel.seeds == [1, 2, 3]
    assert sel.jobs >= 1 and sel.duration_s > 0
    tasks = sel.tasks()
    assert len(tasks) == 54 and tasks[0][:3] == ("fig1", "none", 1)
    assert tasks[-1][:3] == ("fig16", "severe", 3)
    assert parse_selection("office:3", None, "7", 2, 60.0).worlds == ["office:3"]


def test_a_bad_argument_is_one_line_and_exit_2(capsys):
    assert main(["bench", "explore", "--drifts", "wild"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "wild" in err


# --- a real run ------------------------------------------------------------------------------


def test_a_row_equals_the_report_of_the_same_run_in_process(capsys, tmp_path):
    code = main(["bench", "explore", "--json", *TINY, "--jobs", "1", "--out", str(tmp_path)])
    out, err = capsys.readouterr()
    assert code == 0, err
    result = json.loads(out)
    assert set(result) == {"tracer_switches_on", "fire_interval_s", "runs", "summary", "targets"}
    assert result["tracer_switches_on"] == [] and result["fire_interval_s"] is None
    [row] = result["runs"]

    task = Task("fig12", "none", 1, 120.0)
    run = explore(task.world, task.seed, task.drift, task.duration_s, progress=False)
    here = row_from_report(task, report(run, task.world, task.seed, task.drift))
    timing = {"wall_time_s", "realtime_factor"}  # the only figures a seed does not fix
    assert {k: v for k, v in row.items() if k not in timing} == {
        k: v for k, v in here.items() if k not in timing
    }
    assert "[1/1] fig12 none s1: " in err
    assert json.loads((tmp_path / "bench_explore.json").read_text()) == result
    assert "fig12" in (tmp_path / "bench_explore.txt").read_text()


def test_a_tracer_switch_reaches_the_workers_and_the_result(capsys):
    code = main(["bench", "explore", "--json", *TINY, "--jobs", "1", "--switch", "course_sign"])
    out, err = capsys.readouterr()
    assert code == 0, err
    result = json.loads(out)
    assert result["tracer_switches_on"] == ["course_sign"]
    [row] = result["runs"]
    task = Task("fig12", "none", 1, 120.0, ("course_sign",))
    params = tracer_params(["course_sign"])
    run = explore("fig12", 1, "none", 120.0, progress=False, tracer_params=params)
    here = row_from_report(task, report(run, "fig12", 1, "none"))
    moves = ("path_over_gvg", "max_odometry_error_m")
    assert [row[k] for k in moves] == [here[k] for k in moves]
    plain = explore("fig12", 1, "none", 120.0, progress=False)
    assert [report(plain, "fig12", 1, "none")[k] for k in moves] != [row[k] for k in moves]


def test_a_firing_interval_reaches_the_workers_and_the_result(capsys):
    code = main(["bench", "explore", "--json", *TINY, "--jobs", "1", "--fire-interval", "0.004"])
    out, err = capsys.readouterr()
    assert code == 0, err
    result = json.loads(out)
    assert result["fire_interval_s"] == 0.004
    [row] = result["runs"]
    choice = BackendChoice(fire_interval_s=0.004)
    run = explore("fig12", 1, "none", 120.0, progress=False, backend_choice=choice)
    here = report(run, "fig12", 1, "none")
    moves = ("path_over_gvg", "max_odometry_error_m")
    assert [row[k] for k in moves] == [here[k] for k in moves]
    plain = explore("fig12", 1, "none", 120.0, progress=False)
    assert [report(plain, "fig12", 1, "none")[k] for k in moves] != [row[k] for k in moves]
    assert "a transducer fired every 4 ms" in render_text(result)


@pytest.mark.parametrize("value", ["0.001", "2", "nan"])
def test_a_firing_interval_out_of_range_is_one_line(capsys, value):
    assert main(["bench", "explore", *TINY, "--fire-interval", value]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "--fire-interval" in err and value in err


def test_a_failing_worker_becomes_an_error_row():
    # A world no validation would let through, so the real worker really raises.
    lines: list[str] = []
    tasks = [Task("fig99", "none", 1, 60.0)]
    [row] = collect(tasks, jobs=1, say=lines.append)
    assert row["world"] == "fig99" and "fig99" in row["error"]
    assert lines == [f"[1/1] fig99 none s1: error: {row['error']}"]


def test_an_error_keeps_its_place_and_makes_exit_1(capsys, monkeypatch):
    monkeypatch.setattr(bench_explore, "run_one", _fake_worker)
    argv = ["bench", "explore", "--json", "--worlds", "fig12", "--drifts", "none,paper"]
    code = main([*argv, "--seeds", "1,2,3", "--jobs", "2"])
    out, err = capsys.readouterr()
    assert code == 1
    runs = json.loads(out)["runs"]
    assert [(r["drift"], r["seed"]) for r in runs] == [
        (d, s) for d in ("none", "paper") for s in (1, 2, 3)
    ]
    assert [("error" in r) for r in runs] == [False, True, False] * 2
    assert "boom in fig12 seed 2" in runs[1]["error"]
    assert err.count("error: boom") == 2 and "[6/6]" in err


# --- summary, targets and table from hand-made rows ------------------------------------------


def test_missed_closures_never_go_negative():
    rep = {**_row(loop_closures_true=4, loop_closures_found=1), "baseline": {
        "false_merges": 1, "missed_revisits": 2, "revisits_recognised": 3, "nodes": 5,
        "radius_m": 1.0,
    }}  # fmt: skip
    task = Task("fig14", "paper", 2, 60.0)
    assert row_from_report(task, rep)["missed_closures"] == 3
    assert row_from_report(task, {**rep, "loop_closures_found": 6})["missed_closures"] == 0
    assert row_from_report(task, rep)["baseline"] == {
        "false_merges": 1, "missed_revisits": 2, "revisits_recognised": 3,
    }  # fmt: skip


def test_targets_are_met_by_good_runs_and_broken_by_one_bad_one():
    good = [_row("fig14", d, s) for d in ("none", "paper") for s in (1, 2)]
    assert all(t["met"] for t in targets(good).values())

    bad = targets([*good, _row("fig12", "severe", 3, false_merges=1)])
    assert bad["zero_false_merges"]["met"] is False
    assert bad["zero_false_merges"]["failing"] == ["fig12/severe/s3"]
    assert bad["complete"]["met"] and bad["path_over_gvg"]["met"]

    slow = targets([*good, _row("fig14", "none", 3, realtime_factor=99.9, path_over_gvg=2.6)])
    assert slow["realtime_factor"]["met"] is False and slow["path_over_gvg"]["met"] is False


def test_fig15_may_stay_incomplete_under_drift_only():
    rows = [_row("fig15", "paper", 1, complete=False), _row("fig15", "severe", 1, complete=False)]
    t = targets(rows)
    assert t["complete"]["met"] is None  # no run the target applies to
    assert t["realtime_factor"]["met"] is None  # no fig14 run asked for
    assert targets([*rows, _row("fig15", "none", 1, complete=False)])["complete"]["met"] is False


def test_an_error_row_fails_the_targets_it_applies_to():
    rows = [_row("fig14", "none", 1), {"world": "fig14", "drift": "none", "seed": 2, "error": "x"}]
    t = targets(rows)
    assert t["zero_false_merges"]["failing"] == ["fig14/none/s2 (error)"]
    assert not any(v["met"] for v in t.values())
    s = summarize(rows)
    assert s["tslam"]["none"]["runs"] == 1 and s["tslam"]["none"]["errors"] == 1


def test_summary_per_method_and_drift():
    rows = [
        _row(drift="none", false_merges=0, path_over_gvg=1.0, realtime_factor=300.0),
        _row(drift="paper", seed=1, false_merges=2, missed_closures=1, complete=False,
             path_over_gvg=3.0, realtime_factor=100.0, collisions=2,
             baseline={"false_merges": 3, "missed_revisits": 1, "revisits_recognised": 0}),
        _row(drift="paper", seed=2, path_over_gvg=2.0, realtime_factor=200.0,
             baseline={"false_merges": 1, "missed_revisits": 4, "revisits_recognised": 2}),
    ]  # fmt: skip
    s = summarize(rows)
    paper = s["tslam"]["paper"]
    assert paper["runs"] == 2 and paper["complete"] == 1
    # The incomplete one still says it finished: its map is wrong, and the summary says so.
    assert paper["finished_wrong"] == 1 and s["tslam"]["none"]["finished_wrong"] == 0
    assert paper["false_merges"] == 2 and paper["runs_with_false_merges"] == 1
    assert paper["missed_closures"] == 1
    assert paper["collisions"] == 2 and s["tslam"]["none"]["collisions"] == 0
    assert paper["path_over_gvg_median"] == 2.5 and paper["path_over_gvg_max"] == 3.0
    assert paper["realtime_factor_median"] == 150.0 and paper["realtime_factor_min"] == 100.0
    base = s["baseline"]["paper"]
    assert base == {
        "runs": 2, "errors": 0, "false_merges": 4, "runs_with_false_merges": 2,
        "missed_revisits": 5,
    }  # fmt: skip
    assert s["tslam"]["all"]["runs"] == 3 and s["baseline"]["none"]["false_merges"] == 0


def test_the_table_lists_every_run_with_both_methods():
    rows = [
        _row("fig1", "none", 1),
        _row("fig14", "severe", 7, baseline={
            "false_merges": 5, "missed_revisits": 0, "revisits_recognised": 0,
        }),
        {"world": "fig16", "drift": "paper", "seed": 3, "error": "it broke"},
    ]  # fmt: skip
    text = render_text(result_of(rows))
    lines = text.splitlines()
    assert any(ln.split()[:3] == ["fig1", "none", "1"] for ln in lines)
    fig14 = next(ln for ln in lines if ln.startswith("fig14"))
    assert fig14.split()[:8] == ["fig14", "severe", "7", "yes", "yes", "3/3", "0", "5"]
    assert "fig16 paper s3: ERROR it broke" in text
    assert "NOT MET" in text


# --- the installed command -------------------------------------------------------------------


def test_help_and_a_tiny_bench_from_the_command_line():
    helped = subprocess.run(
        [str(TSLAM), "bench", "explore", "--help"], capture_output=True, text=True, timeout=60
    )
    assert helped.returncode == 0 and "--worlds" in helped.stdout
    cmd = [sys.executable, "-m", "tslam.programs.cli", "bench", "explore", *TINY[:6]]
    proc = subprocess.run(
        [*cmd, "--duration", "60", "--jobs", "1"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[2].split()[:3] == ["world", "drift", "seed"]
    assert any(ln.split()[:3] == ["fig12", "none", "1"] for ln in proc.stdout.splitlines())
    assert "targets" in proc.stdout and "[1/1] fig12 none s1" in proc.stderr
