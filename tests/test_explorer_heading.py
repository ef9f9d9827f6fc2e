"""Dead reckoning turns slowly: a look-alike whose departures are turned much further than
the drift between the two readings allows is not the same place (fig15's mirror images)."""

from __future__ import annotations

import math

from hal.interfaces import NOMAD200_LIMITS
from tests.tracer_paths import GIVING_UP, STOP25
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.localize import Hypothesis
from tslam.programs.sim_backends import BackendChoice
from tslam.programs.sim_cmd import explore, report


def rad(deg: float) -> float:
    return math.radians(deg) % (2 * math.pi)


def test_a_look_alike_turned_by_half_a_turn_is_refused_unless_the_readings_are_far_apart():
    ex = Explorer(NOMAD200_LIMITS)
    a = ex.map.add_meet(1.0, [rad(0), rad(90), rad(200)], (0.0, 0.0))
    b = ex.map.add_meet(1.0, [rad(20), rad(180), rad(270)], (5.0, 0.0))  # a turned 180 deg
    c = ex.map.add_meet(1.0, [rad(10), rad(100), rad(210)], (5.0, 0.0))  # a turned 10 deg
    ex.born = {a: 0.0, b: 50.0, c: 50.0}
    # b's port 0 (20 deg) is a's port 2 (200 deg): rotation 2. 25 + 0.25 x 50 = 37.5 deg allowed.
    assert not ex._heading_fits(b, a, 2)
    assert ex._heading_fits(c, a, 0)
    assert ex._heading_misfits(Hypothesis({b: (a, 2), c: (a, 0)})) == [b]
    ex.born[b] = 800.0  # 212.5 deg allowed: dead reckoning says nothing any more
    assert ex._heading_fits(b, a, 2)
    del ex.born[b]  # read before a restart, say: no reading to compare
    assert ex._heading_fits(b, a, 2)


def test_two_places_of_one_merge_turned_apart_are_refused_unless_read_far_apart():
    ex = Explorer(NOMAD200_LIMITS)
    a = ex.map.add_meet(1.7, [rad(27), rad(172), rad(295)], (1.7, 2.5))
    b = ex.map.add_meet(1.7, [rad(90), rad(140), rad(270)], (1.7, 1.7))
    x = ex.map.add_meet(1.7, [rad(59), rad(204), rad(327)], (5.3, 2.5))  # a turned 32 deg
    y = ex.map.add_meet(1.7, [rad(90), rad(140), rad(270)], (5.3, 1.7))  # b not turned
    ex.born = {a: 10.0, b: 11.0, x: 52.0, y: 53.0}
    h = Hypothesis({x: (a, 0), y: (b, 0)})
    # Each alone is within 25 + 0.25 x 42 = 35.5 degrees of its old node...
    assert ex._heading_fits(x, a, 0) and ex._heading_fits(y, b, 0)
    # ... but read 1 m apart they turned 32 degrees apart: more than 28 + 0.25 x 2.
    assert ex._heading_misfits(h) == [x, y]
    ex.born[y] = 100.0  # 48 m on, dead reckoning may have turned that far in between
    assert ex._heading_misfits(h) == []


def test_fig1s_mirrored_bays_are_not_merged_on_a_fast_ring():
    """fig1's two bays are mirror images. On a ring that fires every 4 ms (seed 6, drift
    paper) the right bay's junction matched the left one's turned 32 degrees, within the
    35 degrees its heading allowed, the junction beside it turned 0 degrees, and at 517 s
    the bays were merged: 4 false merges, and 4 more at 1225 s. With the tracer of then
    (``hold_on`` off; on since stop 37, and the robot goes otherwise)."""
    fast = BackendChoice(fire_interval_s=0.004)
    run = explore("fig1", 6, "paper", duration_s=700.0, progress=False, backend_choice=fast,
                  tracer_params=GIVING_UP)  # fmt: skip
    assert any("turned further than dead reckoning drifts" in n.text for n in run.explorer.notes)
    assert report(run, "fig1", 6, "paper")["false_merges"] == 0


def test_fig15_mirror_image_is_not_merged():
    """fig15 seed 1 merged a corner of the room onto the opposite corner at 2284 s, its
    departures turned 169 deg from the old ones after 150 m of driving. Since edges measure
    their own length (edgelength.py) that run goes otherwise; seed 4 now meets such a mirror
    image at 868 s, and with the heading check off it makes 5 false merges in 2400 s. (With
    the crowd of look-alikes weighed, that hypothesis is not proven so soon; the heading check
    is tested here alone: without lead-in hypotheses too, which compete with it there.) With
    stop 25's tracer (``tests.tracer_paths``), and re-joins as strict as they were then (a
    re-access counted as lost after driving 1 m more than it was off)."""
    params = ExplorerParams(weigh_crowd=False, lead_ins=False, rejoin_drive_m=1.0)
    run = explore(
        "fig15", 4, "paper", duration_s=2400.0, progress=False, params=params, tracer_params=STOP25
    )
    assert any("turned further than dead reckoning drifts" in n.text for n in run.explorer.notes)
    assert report(run, "fig15", 4, "paper")["false_merges"] == 0


def _zipped_pair(turn_deg: float) -> tuple[Explorer, int, int, int, int]:
    """Old node c with a neighbour d along its port 0, and new node x, taken for c, with a
    neighbour y the same way: merging x into c makes y one with d too (the merge zips along
    the edge), and y's departures are d's turned ``turn_deg``."""
    ex = Explorer(NOMAD200_LIMITS)
    deps = [rad(0), rad(120), rad(240)]
    c = ex.map.add_meet(1.2, deps, (0.0, 0.0))
    d = ex.map.add_meet(1.3, deps, (3.0, 0.0))
    x = ex.map.add_meet(1.2, deps, (0.0, 0.0))
    y = ex.map.add_meet(1.3, [rad(a + turn_deg) for a in (0, 120, 240)], (3.0, 0.0))
    ex.map.connect(c, 0, d, 1, 3.0)
    ex.map.connect(x, 0, y, 1, 3.1)
    ex.born = {c: 0.0, d: 1.0, x: 50.0, y: 52.0}  # 25 + 0.25 x 51 = 37.75 deg, 25 more zipped
    return ex, c, d, x, y


def test_a_merge_that_zips_two_neighbours_turned_apart_is_refused():
    """fig13 seed 8 at drift paper (stop 62, with a sweep change not kept): a close pair's two
    readings, their ports matched one edge round, zipped its north and east neighbours
    into one place, 5.2 m apart and turned 93 degrees where 34 were allowed. The pair the
    hypothesis names fits; the one the merge makes on the way must fit too."""
    ex, c, d, x, y = _zipped_pair(90.0)
    assert ex._heading_fits(x, c, 0)
    assert ex.map.signature_rotations(y, d, 0.15, math.radians(25.0))  # alike but for heading
    misfit = ex._zipped_misfit({x: (c, 0)}, ex._likeness())
    assert misfit == (y, d, "turned further than dead reckoning drifts")
    assert ex._merge(Hypothesis({x: (c, 0)}, confirmed=2)) == {}
    assert ex.notes[-1].text.startswith(f"merge refused: it makes node {y} one with node {d},")
    assert sorted(n.id for n in ex.map.nodes()) == [c, d, x, y]
    off = Explorer(NOMAD200_LIMITS, params=ExplorerParams(zip_turns=False))
    off.map, off.born = ex.map, ex.born
    assert off._zipped_misfit({x: (c, 0)}, off._likeness()) is None
    ex.map.connect(c, 1, x, 1, 40.0)  # the merge would make this edge come back by one port
    assert ex._zipped_misfit({x: (c, 0)}, ex._likeness()) is None  # the map refuses; not here
    ex, c, d, x, y = _zipped_pair(10.0)
    assert ex._zipped_misfit({x: (c, 0)}, ex._likeness()) is None
    ex, c, d, x, y = _zipped_pair(50.0)  # past the bound, within the margin: drift may do that
    assert not ex._heading_fits(y, d, 0)
    assert ex._zipped_misfit({x: (c, 0)}, ex._likeness()) is None
    ex, c, d, x, y = _zipped_pair(90.0)
    ex.born[y] = 300.0  # 125 deg allowed: read far apart, dead reckoning says little
    assert ex._zipped_misfit({x: (c, 0)}, ex._likeness()) is None
    del ex.born[y]  # read before a restart: no reading to compare
    assert ex._zipped_misfit({x: (c, 0)}, ex._likeness()) is None


def test_a_merge_that_zips_two_places_further_apart_than_dead_reckoning_drifts_is_refused():
    ex, c, d, x, y = _zipped_pair(10.0)
    ex.fixes = {c: (0.0, 0.0, 0.0), d: (3.0, 0.0, 1.0), x: (0.5, 0.0, 50.0), y: (9.0, 0.0, 52.0)}
    assert ex._drifted_apart(Hypothesis({x: (c, 0)})) is None  # the pair it names is near
    # 1.5 + 0.15 x 51 = 9.15 m allowed
    assert ex._zipped_misfit({x: (c, 0)}, ex._likeness()) is None
    ex.fixes[y] = (13.0, 0.0, 52.0)
    misfit = ex._zipped_misfit({x: (c, 0)}, ex._likeness())
    assert misfit == (y, d, "10.0 m apart by dead reckoning after 51 m")
    ex.p = ExplorerParams(zip_drift=False)
    assert ex._zipped_misfit({x: (c, 0)}, ex._likeness()) is None
