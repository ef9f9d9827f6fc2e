"""``tslam trace`` scores each measured edge against the true edge the robot went along to its
end node: two junctions can be joined by a short edge and also, the long way, through a third
junction the robot went by without homing. Scored against the short edge (the one of the two
joining edges closest in length), the long way would read as a length error of the tracer's.
Tracing on past the end node and back is the tracer's error, and is scored."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from sim_backend.builtin_worlds import builtin_world
from sim_backend.ground_truth import GroundTruthGVG, GvgEdge, GvgNode, compute_gvg
from sim_backend.trace_scoring import SeenEdge, SeenNode, place_degrees, score_trace

A, B, C = (0.0, 0.0), (0.3, 0.0), (0.15, 2.0)


def triangle() -> GroundTruthGVG:
    """Meet points A and B 0.3 m apart, C 2 m away; an edge between each pair."""
    nodes = [GvgNode(i, "meet", x, y, 1.0, 3) for i, (x, y) in enumerate((A, B, C))]

    def edge(i: int, u: int, v: int) -> GvgEdge:
        pts = np.array([nodes[u].xy, nodes[v].xy])
        return GvgEdge(i, u, v, pts, float(np.linalg.norm(pts[1] - pts[0])))

    edges = [edge(0, 0, 1), edge(1, 0, 2), edge(2, 1, 2)]
    return GroundTruthGVG("triangle", nodes, edges, 0, 30.0, 0.2, 5.0, 0.05, 0.3, 0.3)


def drive(points: list[tuple[float, float]], step: float = 0.02) -> np.ndarray:
    """The true path along ``points``: rows of x, y and the distance travelled."""
    rows, travelled = [(*points[0], 0.0)], 0.0
    for p, q in itertools.pairwise(points):
        n = max(1, int(np.hypot(q[0] - p[0], q[1] - p[1]) / step))
        for k in range(1, n + 1):
            x, y = p[0] + (q[0] - p[0]) * k / n, p[1] + (q[1] - p[1]) * k / n
            travelled += np.hypot(x - rows[-1][0], y - rows[-1][1])
            rows.append((x, y, travelled))
    return np.array(rows)


def test_an_edge_driven_the_long_way_round_is_not_scored_against_the_short_edge():
    gvg = triangle()
    path = drive([A, C, B])  # through C without homing there
    total = float(path[-1, 2])
    nodes = [SeenNode("meet", *A, 3, 0.0), SeenNode("meet", *B, 3, total)]
    report = score_trace(gvg, path, nodes, [SeenEdge(0, 1, total)])
    assert report["edges_not_in_ground_truth"] == 1
    assert report["edge_length_error_max_rel"] is None


def test_an_edge_driven_along_is_scored_against_it():
    gvg = triangle()
    path = drive([A, B])
    nodes = [SeenNode("meet", *A, 3, 0.0), SeenNode("meet", *B, 3, float(path[-1, 2]))]
    report = score_trace(gvg, path, nodes, [SeenEdge(0, 1, 0.31)])
    assert report["edges_not_in_ground_truth"] == 0
    assert report["edge_length_error_max_rel"] == pytest.approx(0.01 / 0.3, abs=1e-3)


def test_tracing_on_past_the_end_node_and_back_is_a_length_error_to_score():
    """Overshooting B along its edge to C and homing back onto B lengthens the measured A-B
    edge: the tracer's error, scored against A-B (fig14 seed 4 measures 5.14 m for a 4.07 m
    edge this way)."""
    gvg = triangle()
    over = (B[0] + 0.1 * (C[0] - B[0]), B[1] + 0.4 * (C[1] - B[1]))  # 0.8 m up B-C
    path = drive([A, B, over, B])
    total = float(path[-1, 2])
    nodes = [SeenNode("meet", *A, 3, 0.0), SeenNode("meet", *B, 3, total)]
    report = score_trace(gvg, path, nodes, [SeenEdge(0, 1, total)])
    assert report["edges_not_in_ground_truth"] == 0
    assert report["edge_length_error_max_rel"] == pytest.approx((total - 0.3) / 0.3, abs=1e-4)


def test_a_meet_point_gone_through_without_homing_is_a_pass_unhomed():
    gvg = triangle()
    # From A to C, on 1 m past C (so the stay at C ends), and back to C where it homes.
    beyond = (C[0], C[1] + 1.0)
    path = drive([A, C, beyond, C, (C[0], C[1] + 0.6)])
    at_c_again = float(path[np.flatnonzero(path[:, 1] >= beyond[1])[0], 2]) + 1.0
    nodes = [SeenNode("meet", *A, 3, 0.0), SeenNode("meet", *C, 3, at_c_again)]
    report = score_trace(gvg, path, nodes, [])
    # A: the run starts there and A was reported: homed. C: passed once without a report,
    # once with one. The pass of B 0.3 m away from A's stay is not within 0.25 m of it.
    assert report["meet_point_passes"] == 3
    assert report["meet_point_passes_unhomed"] == 1


def test_a_stay_unfinished_when_the_run_ends_is_not_scored():
    gvg = triangle()
    path = drive([A, (0.15, 1.0), C])  # ends on C: it may be homing yet
    report = score_trace(gvg, path, [SeenNode("meet", *A, 3, 0.0)], [])
    assert report["meet_point_passes"] == 1 and report["meet_point_passes_unhomed"] == 0


@pytest.mark.parametrize(("degree", "ok"), [(3, 1.0), (4, 1.0), (5, 0.0), (2, 0.0)])
def test_a_meet_point_of_a_close_pair_may_be_read_alone_or_with_its_place(degree, ok):
    # fig1's meet points 6 and 7, 0.20 m apart: each has three edges, the place they make
    # four; a sweep that reads the place (TracerParams.place_radius_m) sees four.
    gvg = compute_gvg(builtin_world("fig1"))
    assert place_degrees(gvg)[6] == 4 and place_degrees(gvg)[1] == 3
    six = next(n for n in gvg.meet_points if n.id == 6)
    seen = [SeenNode("meet", six.x, six.y, degree, 0.0)]
    path = np.array([[six.x, six.y, 0.0]])
    assert score_trace(gvg, path, seen, [])["degree_match_ratio"] == ok
