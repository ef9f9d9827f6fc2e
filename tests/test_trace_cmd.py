"""``tslam trace`` end to end on fig14 (seeded, sonar noise on, drift paper): the robot
accesses the GVG, traces edges and homes onto meet points close to the ground truth, with
the degree the ground truth gives, the door junction's four included."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

from tslam.programs.cli import main


def test_trace_homes_onto_the_true_meet_points_with_the_true_degree(tmp_path, capsys):
    code = main(
        ["trace", "--world", "fig14", "--edges", "8", "--seed", "2", "--out", str(tmp_path)]
    )
    capsys.readouterr()
    assert code == 0
    report = json.loads((tmp_path / "trace_report.json").read_text())
    assert report["complete"] and report["edges_traced"] == 8
    assert report["meet_points_seen"] >= 3
    assert report["meet_point_error_max_m"] <= 0.10
    assert report["degree_match_ratio"] == 1.0
    assert report["edge_error_median_m"] <= 0.05
    assert report["collisions"] == 0
    ET.parse(tmp_path / "trace.svg")


def test_trace_refuses_a_bad_edge_count(capsys):
    assert main(["trace", "--world", "fig12", "--edges", "0", "--out", "/tmp/x"]) == 2
    assert "--edges must be at least 1" in capsys.readouterr().err
