"""The command line as a user meets it: JSON outputs, SVG files, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from tslam.programs.cli import main


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_worlds_lists_every_builtin(capsys):
    code, out, _ = run(capsys, "worlds", "--json")
    names = json.loads(out)
    assert code == 0
    for n in ("fig1", "fig12", "fig13", "fig14", "fig15", "fig16", "office:SEED", "maze:SEED"):
        assert n in names


def test_world_info_reports_ground_truth(capsys):
    code, out, _ = run(capsys, "world", "info", "fig12", "--json")
    info = json.loads(out)
    assert code == 0
    for key in ("meet_points", "boundary_points", "edges", "gvg_length_m", "free_area_m2"):
        assert key in info
    assert info["meet_point_count"] == len(info["meet_points"]) >= 3
    assert all(m["degree"] >= 3 for m in info["meet_points"])
    assert info["gvg_length_m"] > 0 and info["free_area_m2"] > 0


def test_world_info_on_a_user_polygon_file(capsys, tmp_path):
    f = tmp_path / "corridor.json"
    f.write_text(
        json.dumps(
            {
                "name": "tee",
                "boundary": [[0, 0], [10, 0], [10, 2], [6, 2], [6, 8], [4, 8], [4, 2], [0, 2]],
                "obstacles": [],
                "start": {"x": 1.0, "y": 1.0, "theta": 0.0},
            }
        )
    )
    code, out, _ = run(capsys, "world", "info", str(f), "--json")
    info = json.loads(out)
    assert code == 0 and info["name"] == "tee"
    assert info["free_area_m2"] == pytest.approx(32.0)
    # The junction, plus one meet point near each of the three flat dead ends, where the
    # corridor's edge splits into two branches that run into the end's corners.
    assert info["meet_point_count"] == 4
    assert all(m["degree"] == 3 for m in info["meet_points"])
    assert info["boundary_point_count"] == 6
    # The junction is equidistant to the bottom wall and the two corners (4, 2), (6, 2):
    # x = 5, y = 1.25.
    junction = min(info["meet_points"], key=lambda m: (m["x"] - 5) ** 2 + (m["y"] - 1.25) ** 2)
    assert (junction["x"], junction["y"]) == pytest.approx((5.0, 1.25), abs=0.02)
    assert junction["clearance_m"] == pytest.approx(1.25, abs=0.01)


def test_world_render_writes_svg(capsys, tmp_path):
    out_file = tmp_path / "sub" / "fig12.svg"
    code, stdout, _ = run(capsys, "world", "render", "fig12", "--out", str(out_file))
    assert code == 0 and out_file.exists() and str(out_file) in stdout
    root = ET.parse(out_file).getroot()
    assert root.tag.endswith("svg")


@pytest.mark.parametrize(
    ("content", "needle"),
    [
        ("{not json", "invalid JSON"),
        ('{"name": "x", "boundary": [[0,0],[1,0]], "start": {"x":0,"y":0}}', "boundary"),
        ('{"name": "x", "boundary": [[0,0],[5,0],[5,5],[0,5]], "start": {"x":9,"y":9}}', "start"),
    ],
)
def test_malformed_world_file_gives_one_line(capsys, tmp_path, content, needle):
    f = tmp_path / "bad.json"
    f.write_text(content)
    code, stdout, err = run(capsys, "world", "info", str(f))
    assert code == 2 and stdout == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "bad.json" in lines[0] and needle in lines[0]
    assert "Traceback" not in err


def test_unknown_world_gives_one_line(capsys):
    code, _, err = run(capsys, "world", "info", "fig99")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "fig99" in err


def test_sim_with_a_ring_fired_fast_says_so_and_refuses_it_on_the_drivers(capsys):
    code, out, _ = run(
        capsys, "sim", "--world", "fig12", "--duration", "30", "--seed", "2", "--quiet",
        "--fire-interval", "0.004",
    )  # fmt: skip
    assert code == 0 and json.loads(out)["fire_interval_s"] == 0.004
    code, out, err = run(
        capsys, "sim", "--world", "fig12", "--backend", "nomad200-emulated",
        "--fire-interval", "0.004",
    )  # fmt: skip
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "--fire-interval" in err and "--backend sim" in err


def test_sim_runs_and_writes_its_outputs(capsys, tmp_path):
    code, out, _ = run(
        capsys, "sim", "--world", "fig12", "--duration", "60", "--seed", "2",
        "--out", str(tmp_path), "--quiet",
    )  # fmt: skip
    assert code == 0
    report = json.loads((tmp_path / "report.json").read_text())
    assert json.loads(out)["sim_time_s"] == report["sim_time_s"]
    # 60 s is too short to finish: the report says so rather than claiming completeness.
    assert report["sim_time_s"] >= 60 and report["path_length_m"] > 3.0
    assert report["complete"] is False and report["finished"] is False
    saved = json.loads((tmp_path / "map.json").read_text())
    assert len(saved["nodes"]) == report["map_meet_nodes"] + report["map_boundary_nodes"]
    for name in ("map.svg", "trajectory.svg"):
        ET.parse(tmp_path / name)


def test_console_script_reports_bad_option_without_traceback(tmp_path):
    exe = Path(sys.executable).with_name("tslam")
    r = subprocess.run(
        [str(exe), "sim", "--world", "fig12", "--duration", "-5"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "--duration must be a positive number" in r.stderr


def test_output_cut_short_by_its_reader_ends_quietly():
    # ``tslam world info office:1 --json | head``: far more than a pipe's buffer, and the
    # reader closes after the first line.
    p = subprocess.Popen(
        [sys.executable, "-m", "tslam.programs.cli", "world", "info", "office:1", "--json"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
    )  # fmt: skip
    try:
        assert p.stdout is not None and p.stdout.readline().strip() == b"{"
        p.stdout.close()
        _, err = p.communicate(timeout=120)
    finally:
        p.kill()
        p.wait()
    assert p.returncode == 141
    assert err == b""


def test_bench_control_prints_step_times(capsys):
    code, out, _ = run(capsys, "bench", "control", "--json", "--steps", "120")
    result = json.loads(out)
    assert code == 0 and result["steps"] == 70
    assert 0 < result["step_ms_median"] <= result["step_ms_p99"]
