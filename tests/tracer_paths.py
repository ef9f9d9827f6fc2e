"""The tracer some explorer tests were found with, for the paths they need.

Several explorer tests replay one simulated run in which the explorer met a case (a departure
not held, weak meet points passed unhomed, a mirror image): the explorer's handling is what
they test, and the tracer only has to take the robot along that path. Stop 26's tracer changes
(doorways, doubtful sweeps) move the robot otherwise, so these tests keep stop 25's tracer.
"""

from __future__ import annotations

import math
from dataclasses import replace

from tslam.core.explorer import ExplorerParams
from tslam.core.tracer import TracerParams


def before_stop44(params: TracerParams) -> TracerParams:
    """``params`` as up to stop 43: homing onto a sweep's estimate by the ring whatever it
    hears, and the arrival on a short edge from the trace law's tangent."""
    return replace(params, home_unheard_m=0.0, approach_short_m=0.0)


def before_stop42(params: TracerParams) -> TracerParams:
    """``params`` as up to stop 41: no doorway's jambs kept apart as the edge's pair, no
    arming on access, no way in kept as an edge of its own, a departure's pair may have one
    obstacle dead ahead, and no swing of the trace law's tangent coasted through; and as
    ``before_stop44``."""
    return replace(
        before_stop44(params),
        doorway_pairs=False,
        arm_on_access=False,
        unseen_way_in_rad=0.0,
        sides_ahead_rad=0.0,
        swing_coast_s=0.0,
    )


def explorer_before_stop42(params: ExplorerParams) -> ExplorerParams:
    """``params`` as up to stop 41: an excursion straight on along the edge keeps it only
    within ``rejoin_m``, and a port left by its own bearing goes on straight as any other; and
    an edge that went past a junction is not repaired (``cut_past``, ``past_candidates``: on
    since stop 50)."""
    return replace(
        params,
        straight_rejoin_m=0.0,
        own_bearing_until_sides_m=1.5,
        cut_past=False,
        past_candidates=False,
    )


#: Stop 41's tracer, for runs a test was found with.
STOP41 = before_stop42(TracerParams())


def before_stop38(params: TracerParams) -> TracerParams:
    """``params`` as up to stop 37: no convex corner's echo kept while it lies in a gap
    between the beams (``SensingParams.gap_hold_s``), and homing on the ring's three nearest
    however far apart their distances (``home_spread_m``); and as ``before_stop42``."""
    return before_stop42(
        replace(params, home_spread_m=0.0, sensing=replace(params.sensing, gap_hold_s=0.0))
    )


def giving_up(params: TracerParams) -> TracerParams:
    """``params`` with ``hold_on`` off, as up to stop 36: homing gives up when the third echo
    drops out, and the sweep joins no wall's pieces and no shallow bend's faces; and as
    ``before_stop38``."""
    return before_stop38(
        replace(params, home_hold_m=0.0, sweep_join_pieces=False, sweep_shallow_bend=False)
    )


#: The default tracer with ``hold_on`` off, as up to stop 36 (but for backing off a wedge,
#: and for tracing on after a contact with the boundary rule armed).
GIVING_UP = giving_up(TracerParams())


#: Stop 25's tracer: tracing from 0.15 m out of a departure whatever the ring sees, an edge
#: ended wherever a wall comes within 0.45 m, one sweep at every meet point judged where the
#: robot stands, and an edge's length taken over its whole chain (stop 31 judges the sweep
#: at its estimate and drops the chain's spikes: edgelength.py), its sweep reading no recess
#: and its places no meet point of three corners (on since stop 36), homing giving up when
#: the third echo drops out (``hold_on``, on since stop 37), and a sweep's bent walls not held
#: to their vertex (``sweep_vertex``, on since stop 53).
STOP25 = giving_up(
    TracerParams(
        depart_until_sides_m=0.0,
        corner_ahead_m=math.inf,
        corner_ahead_rad=math.pi,
        sweep_again=False,
        edge_spike_ratio=math.inf,
        spread_at_estimate=False,
        sweep_recess=False,
        place_corners=False,
        sweep_vertex=False,
    )
)
