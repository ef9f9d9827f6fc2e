"""An edge's length is the edge's, not the robot's weaving path along it.

The trace law weaves about the edge, and the encoders' distance along that path overstated
fig12's edges by up to 19 %. The odometer joins points of the edge itself (the robot's
position plus the sonar's step onto the edge, averaged over half a metre of travel).
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from hal import create_backend
from tests.tracer_paths import before_stop42
from tslam.core.edgelength import EdgeOdometer
from tslam.core.laws import step_onto_edge
from tslam.core.sensing import Obstacle
from tslam.programs import trace_cmd
from tslam.programs.cli import main
from tslam.programs.trace_cmd import run_trace


def weave(xs: np.ndarray, amplitude: float, wavelength: float) -> np.ndarray:
    return amplitude * np.sin(2.0 * math.pi * xs / wavelength)


def drive(odo: EdgeOdometer, path: np.ndarray, steps: np.ndarray, travelled: float = 0.0) -> float:
    """Feed the odometer a traced path and its steps onto the edge; the encoder distance."""
    for k in range(len(path)):
        if k:
            travelled += float(np.hypot(*(path[k] - path[k - 1])))
        odo.on_edge(float(path[k, 0]), float(path[k, 1]), travelled, tuple(steps[k]))
    return travelled


def test_a_weave_about_a_straight_edge_does_not_lengthen_it():
    xs = np.linspace(0.0, 5.0, 1001)
    ys = weave(xs, 0.1, 1.0)
    path = np.column_stack([xs, ys])
    odo = EdgeOdometer()
    odo.start(0.0, 0.0)
    travelled = drive(odo, path, np.column_stack([np.zeros_like(ys), -ys]))
    assert travelled > 5.4  # what the encoders alone would say
    assert odo.length_to(5.0, 0.0) == pytest.approx(5.0, abs=0.01)


def test_noisy_steps_average_out():
    rng = np.random.default_rng(7)
    xs = np.linspace(0.0, 6.0, 301)  # 2 cm of travel a step, as at 0.2 m/s and 10 Hz
    ys = weave(xs, 0.08, 1.2)
    path = np.column_stack([xs, ys])
    steps = np.column_stack([np.zeros_like(ys), -ys]) + rng.normal(0.0, 0.02, (len(xs), 2))
    odo = EdgeOdometer()
    odo.start(0.0, 0.0)
    drive(odo, path, steps)
    assert odo.length_to(6.0, 0.0) == pytest.approx(6.0, rel=0.02)


def test_a_curved_edge_keeps_its_length():
    radius = 3.0
    th = np.linspace(0.0, math.pi / 2, 800)
    wobble = 0.05 * np.sin(th * 40.0)  # radial weave
    r = radius + wobble
    path = np.column_stack([r * np.cos(th), r * np.sin(th)])
    steps = np.column_stack([-wobble * np.cos(th), -wobble * np.sin(th)])
    odo = EdgeOdometer()
    odo.start(radius, 0.0)
    drive(odo, path, steps)
    assert odo.length_to(0.0, radius) == pytest.approx(radius * math.pi / 2, rel=0.01)


def test_a_detour_off_the_edge_is_bridged():
    odo = EdgeOdometer()
    odo.start(0.0, 0.0)
    first = np.column_stack([np.linspace(0.0, 2.0, 101), np.zeros(101)])
    travelled = drive(odo, first, np.zeros((101, 2)))
    travelled += 2.0  # out to a false meet point a metre off and back: no points taken
    second = np.column_stack([np.linspace(2.0, 4.0, 101), np.zeros(101)])
    drive(odo, second, np.zeros((101, 2)), travelled)
    assert odo.length_to(4.0, 0.0) == pytest.approx(4.0, abs=0.01)


def line(a: tuple[float, float], b: tuple[float, float], n: int = 101) -> np.ndarray:
    return np.column_stack([np.linspace(a[0], b[0], n), np.linspace(a[1], b[1], n)])


def test_tracing_past_the_end_node_and_back_is_not_the_edge():
    """fig1 seed 1: the robot traced 0.3 m past the junction, then homed back onto it."""
    odo = EdgeOdometer()
    odo.start(0.0, 0.0)
    travelled = drive(odo, line((0.0, 0.0), (2.0, 0.0)), np.zeros((101, 2)))
    drive(odo, line((2.0, 0.0), (2.6, 0.0), 31), np.zeros((31, 2)), travelled)
    assert odo.length_to(2.0, 0.0) == pytest.approx(2.0, abs=0.05)


def test_a_stretch_along_other_walls_half_way_is_not_the_edge():
    """fig1 seed 3: half way along, the robot traced into a doorway's walls for a while."""
    odo = EdgeOdometer()
    odo.start(0.0, 0.0)
    travelled = drive(odo, line((0.0, 0.0), (3.0, 0.0)), np.zeros((101, 2)))
    travelled = drive(odo, line((3.0, 0.8), (3.3, 0.8), 26), np.zeros((26, 2)), travelled + 1)
    drive(odo, line((3.3, 0.0), (6.0, 0.0)), np.zeros((101, 2)), travelled + 1)
    assert odo.length_to(6.0, 0.0) == pytest.approx(6.0, abs=0.05)


@pytest.mark.parametrize("back_m", [0.3, 0.0])
def test_out_along_another_edge_and_back_through_the_node_is_not_the_edge(back_m):
    """fig13 seed 1 at drift none, 765-807 s: sent along one edge, the robot traced 0.8 m of
    another, came back 0.22 m past the junction it had left and went on along the first;
    with the whole way in the chain, 3.25 m was measured for an edge of 2.25."""
    odo = EdgeOdometer(back_m=back_m)
    odo.start(0.0, 0.0)
    travelled = drive(odo, line((-0.25, 0.1), (-0.8, 0.35), 41), np.zeros((41, 2)), 0.27)
    # Back by access (off the edge: no points), then along the edge sent along.
    travelled += 0.85
    drive(odo, line((0.02, 0.24), (0.7, 2.1)), np.zeros((101, 2)), travelled)
    length = odo.length_to(0.7, 2.1)
    if back_m:
        assert length == pytest.approx(math.hypot(0.7, 2.1), abs=0.05)
    else:  # the old chain: the way out and back is measured too
        assert length > math.hypot(0.7, 2.1) + 0.8


def test_a_way_that_never_went_out_is_not_restarted_near_its_start():
    """Tracing begins a few decimetres from the node it left: that is no way back."""
    odo = EdgeOdometer(back_m=0.3)
    odo.start(0.0, 0.0)
    drive(odo, line((0.0, 0.1), (0.0, 3.0)), np.zeros((101, 2)))
    assert odo.length_to(0.0, 3.0) == pytest.approx(3.0, abs=0.02)


def test_an_edge_round_to_its_own_node_is_not_restarted_at_its_end():
    """An edge that leaves a node and comes round an obstacle back to it passes close to
    its start only at its end, from far out: that is the edge, not a way back."""
    odo = EdgeOdometer(back_m=0.3)
    odo.start(0.0, 0.0)
    th = np.linspace(0.05, 2.0 * math.pi - 0.05, 400)
    loop = np.column_stack([1.2 * np.sin(th), 1.2 * (1.0 - np.cos(th))])  # a circle via (0, 2.4)
    drive(odo, loop, np.zeros((400, 2)))
    assert odo.length_to(0.0, 0.0) > 2.0 * math.pi * 1.2 * 0.95


def test_a_right_angle_bend_is_kept():
    odo = EdgeOdometer()
    odo.start(0.0, 0.0)
    travelled = drive(odo, line((0.0, 0.0), (1.0, 0.0)), np.zeros((101, 2)))
    drive(odo, line((1.0, 0.0), (1.0, 1.0)), np.zeros((101, 2)), travelled)
    # The half-metre averages cut the corner by 0.15 m; dropping the corner's point would
    # make it the diagonal, 1.41.
    assert odo.length_to(1.0, 1.0) == pytest.approx(1.85, abs=0.01)


@pytest.mark.parametrize("clear_m, longer", [(None, False), (0.0, True)])
def test_points_about_the_end_nodes_are_the_junctions_not_the_edges(clear_m, longer):
    """fig13 seed 7: leaving a meet point, the two nearest walls are another edge's pair for
    a while, and the first averaged point lay behind the start; arriving, the last one lay
    past the end. 1.24 m for an edge of 1.14."""
    odo = EdgeOdometer() if clear_m is None else EdgeOdometer(end_clear_m=clear_m)
    odo.start(0.0, 0.0)
    away = line((0.0, 0.0), (0.5, 0.0), 26)
    junction = np.array([-0.08, 0.12]) - away  # every step lands on the same point aside
    travelled = drive(odo, away, junction)
    travelled = drive(odo, line((0.5, 0.0), (3.0, 0.0)), np.zeros((101, 2)), travelled)
    past = line((3.0, 0.0), (3.2, 0.0), 11)
    drive(odo, past, np.array([3.1, -0.1]) - past, travelled)
    length = odo.length_to(3.0, 0.0)
    assert length is not None
    if longer:
        assert length > 3.15
    else:
        assert length == pytest.approx(3.0, abs=0.02)


def test_a_step_too_long_to_be_onto_this_edge_is_not_taken():
    odo = EdgeOdometer()
    odo.start(0.0, 0.0)
    odo.on_edge(1.0, 0.0, 1.0, (0.0, 1.5))  # another pair of walls
    assert odo.length_to(2.0, 0.0) == pytest.approx(2.0)


def test_no_length_before_a_node():
    odo = EdgeOdometer()
    odo.on_edge(1.0, 0.0, 1.0, (0.0, 0.0))
    assert odo.length_to(2.0, 0.0) is None


def test_the_step_onto_a_corridor_centre():
    # Walls at y = +1 and y = -1, the robot at y = 0.1: the upper wall is the closer.
    upper = Obstacle(0.9, 0.0, 0.9, 0.0, -1.0, math.pi / 2)
    lower = Obstacle(1.1, 0.0, -1.1, 0.0, 1.0, -math.pi / 2)
    step = step_onto_edge(upper, lower)
    assert step == pytest.approx((0.0, -0.1))
    same_side = Obstacle(1.1, 0.0, 1.1, 0.0, -1.0, math.pi / 2)
    assert step_onto_edge(upper, same_side) is None


def test_traced_edges_measure_within_three_percent(tmp_path, capsys):
    """fig12 at drift paper: every meet-to-meet edge within 3 % of the true one (the encoder
    distance alone: 16 % at worst, 6 % median). Seed 1 up to stop 36; with ``hold_on`` on
    (stop 37) its trace measures 9 such edges, so seed 2 (12, 1.1 % at worst); with corners
    kept in the ring's gaps (stop 38) seed 2 measures 9, so seed 10 (12, 0.8 % at worst); with a
    swing past a far jump coasted (stop 49) seed 10 measures 3, so seed 8 (12, 1.3 % at
    worst)."""
    code = main(
        ["trace", "--world", "fig12", "--edges", "12", "--seed", "8", "--out", str(tmp_path)]
    )
    capsys.readouterr()
    assert code == 0
    report = json.loads((tmp_path / "trace_report.json").read_text())
    assert report["meet_to_meet_edges"] >= 10
    assert report["edges_not_in_ground_truth"] == 0
    assert report["edge_length_error_max_rel"] <= 0.03
    assert report["edge_length_error_median_rel"] <= 0.01


def _fig16_seed5_trace() -> dict:
    backend = create_backend({"backend": "sim", "world": "fig16", "seed": 5, "drift": "paper"})
    return run_trace(backend, 12).report


def _stop41(monkeypatch) -> None:
    """Trace with stop 41's tracer, which the case below was found with."""
    default = trace_cmd.tracer_params
    monkeypatch.setattr(trace_cmd, "tracer_params", lambda sw: before_stop42(default(sw)))


def test_an_edge_is_measured_between_the_meet_points_the_sweeps_estimate(monkeypatch):
    """fig16 seed 5: measured from where the robot stood when each sweep ended, the trace's
    worst edge is 24.5 % off; from the meet points the sweeps estimate, 2.6 %. (Pinned on
    fig16 seed 2 at stop 31, on fig1 seed 1 at stop 36: the robot homed a few centimetres past
    the room's 2.03 m edge's end, 5.8 % against 1.8 %; with ``hold_on`` on, stop 37, that
    trace's worst edge is 3.0 % against 1.6 %, so fig16 seed 12, 12.8 % against 2.7 %; with
    corners kept in the ring's gaps, stop 38, seed 12 traces two such edges; traced with
    stop 41's tracer since stop 42, whose trace has three meet-to-meet edges there, not four.)"""
    _stop41(monkeypatch)
    report = _fig16_seed5_trace()
    assert report["meet_to_meet_edges"] >= 4
    assert report["edge_length_error_max_rel"] <= 0.03
    default = trace_cmd.tracer_params
    monkeypatch.setattr(
        trace_cmd, "tracer_params", lambda sw: replace(default(sw), length_at_estimate=False)
    )
    assert _fig16_seed5_trace()["edge_length_error_max_rel"] > 0.10
