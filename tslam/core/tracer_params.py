"""The tracer's gains, tolerances and switches (``tslam.core.tracer``), with why each is set so."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from tslam.core.sensing import SensingParams


@dataclass(frozen=True)
class TracerParams:
    alpha_mps: float = 0.2  # speed along an edge
    beta_per_s: float = 0.8  # pull back onto the edge
    access_mps: float = 0.2
    on_edge_tol_m: float = 0.06  # |d1 - d2| that counts as being on the GVG
    # The robot passes a meet point some centimetres off it and each distance is good to a few
    # centimetres, so d3 - d1 rarely falls below 0.15 m while tracing: detection is loose
    # and the equidistance is checked again once homing has put the robot on the point.
    meet_tol_m: float = 0.25  # d3 - d1 that starts homing ...
    meet_radius_m: float = 0.6  # ... when the circumcentre of the three is this close
    meet_spread_m: float = 0.10  # d3 - d1 at the settled point that makes it a meet point
    arm_tol_m: float = 0.35  # d3 - d1 that re-arms meet detection after leaving a node
    degree_tol_m: float = 0.10  # d_k - d1 that counts obstacle k at a homed meet point
    # A homed meet point reads its place: the meet points this close that the sweep's
    # obstacles define count as one junction, with the edges of all of them (place.py; 0:
    # the point alone). It finds the edges that leave from the other point of a close pair
    # (fig1's 0.20 m pair, fig14's lab door). The sweep does not hear every obstacle of a
    # place from each of its points, but the explorer now recognises a junction read with an
    # edge more or fewer (``_read_otherwise``): on since stop 30 (README).
    place_radius_m: float = 0.4
    place_tol_m: float = 0.05  # ... each equidistant to its three obstacles within this
    settle_tol_m: float = 0.03  # homing stops this close to the estimate
    converge_tol_m: float = 0.06  # ... and has converged if the sweep agrees this well
    # Standing on a meet point the turret turns through one sonar spacing (22.5 degrees)
    # while each transducer fires four times (5.6 degrees apart): bearings to a few degrees,
    # and every obstacle answers over four or five samples (see sweep.py).
    sweep_s: float = 3.9
    sweep_again: bool = True  # a doubtful sweep turns the turret once more (sweep.py)
    sweep_radps: float = math.radians(22.5) / 3.9
    home_gain: float = 1.0
    # Homing this close to its point keeps to it when the ring's estimate jumps more than
    # ``home_jump_m`` away: one echo changed, not the point. At fig16's weak meet point (seed 5)
    # the robot stood 6 cm off it, one wall's echo dropped out, and the three left defined the
    # corridor's meet point 0.4 m away, where the sweep then rejected it (0: off).
    home_keep_m: float = 0.0
    # Homing onto a sweep's estimate goes there by dead reckoning while the ring's nearest
    # echo is this much further than the sweep's nearest obstacle: the ring does not hear
    # the obstacle that put the point there. fig13's meet point 9 (seed 3): a cabinet's
    # corner 0.78 m off, heard by the sweep, now and then by the ring; the ring's three (two
    # walls and a table's corner) were equidistant where the robot stood, 0.44 m off the
    # point, and it settled there three times and traced on (0: the ring's estimate).
    home_unheard_m: float = 0.15
    home_jump_m: float = 0.2
    # The ring's three nearest define the point homing goes to only while they are nearly
    # equidistant (d3 - d1 within this; 0: always). When one of the point's echoes drops out,
    # the next nearest is some far wall, and the circumcentre with it lies anywhere: at
    # fig16's weak meet point the robot lost one corner of the indent, took the corridor's
    # far wall 1.57 m off for the third, and homed 0.4 m back onto the corridor's meet point,
    # so the indent's departures "could not be held". Such a cycle counts as a lost echo,
    # which ``home_hold_m`` rides through. Above ``meet_tol_m``, at which homing starts.
    home_spread_m: float = 0.3
    home_max_mps: float = 0.15
    # Five switches, the four below and SensingParams.held_no_support, each fix a failure found
    # in the composed run through both emulators, fig12 seed 6 without drift, which with all
    # five on maps fig12 whole (7 duplicate nodes without). They are off by default: they
    # move the robot differently elsewhere, which re-rolls the seeds the exploration scenario
    # tests are pinned to, and on the 36-run paper bench all five on complete 7 runs against
    # 9 off (0 false merges both), so nothing shows them better yet on the whole.
    # tests/test_tracer_switches.py checks two of them on cases of their own.
    # Homing this close sweeps even if the third echo drops out (0: give up and trace on).
    # 0.6 since stop 37, with ``hold_on`` (below).
    home_hold_m: float = 0.6
    # The side of the edge's null space: the robot's course over its last half metre (True)
    # or the last cycle's tangent (False; with rejected_memory, the course past a rejected
    # meet point all the same).
    course_sign: bool = False
    # The sweep's bearings in the odometry frame, so a body still turning as it starts does
    # not smear them (False: the body's frame, as if it stood still).
    sweep_fixed_frame: bool = False
    # On a fast ring, a point the sweep rejected is not homed onto again and is traced through
    # on the pair of obstacles whose edge goes on the robot's course. (That the robot leaves a
    # rejected point the way it came in, once part of this switch, is always so now.) On
    # since stop 34, with the sweep reading a fast ring's dense sweeps in sectors: fig12,
    # seeds 1-10 at 4 and 6.25 ms a firing, 19 of 20 explored, in 513 s on average, against
    # 17 in 588 s without it (it homed back and forth at the cut corner). A Nomad ring's
    # sweep never marks a point so.
    rejected_memory: bool = True
    # A sixth: the meet point judged where it is. Of the true meet points the robot came
    # within 0.25 m of, 14 % went unhomed, most because the sweep rejected a point the robot
    # stood 1-6 cm off (a spread of twice the offset is geometry, not evidence; one reading
    # off a plateau cut a wall out) or homing gave up on one missing echo. With it, the
    # sweep's meet point is the three walls' equidistant point (laws.wall_centre) and the
    # spread, degree and clearance are read there; a sweep's run bridges one reading off its
    # plateau and bent walls join up to 70 degrees (sweep.py); homing keeps to its estimate
    # for ``home_patience_s`` without the third echo; a rejected point is placed where the
    # robot stands when the sweep's estimate is far off. 6-7 % unhomed then, but the
    # explorations' outcomes no better (README, tracing): off for now.
    centred_meet: bool = False
    home_patience_s: float = 1.0  # with centred_meet
    # The sweep's obstacles judged at the meet point it estimates, when homing has converged
    # onto it, not where the robot stands: 6 cm off fig1's meet point 3 the three spread by
    # 0.10 m, and the sweep rejected it (seed 2, 490 s); at the estimate they agree to 2 mm.
    spread_at_estimate: bool = True
    # An edge's length measured from and to the meet point the sweep estimates, when homing
    # has converged onto it, not where the robot stands: fig16's 0.36 m edge across the
    # indent measured 0.42 m with the robot 7 cm off its far end (seed 2). Over issue 3's 30
    # traces the worst edge of a trace was off by 4.6 % at most, against 18.6 %.
    length_at_estimate: bool = True
    # An eighth, the switch ``hold_on`` (stop 27): homing holds on through a lost third echo up
    # to ``home_hold_m`` 0.6, a sweep joins a wall's pieces that dropouts cut too short to
    # count, and it takes two faces up to 90 degrees apart for one bent wall where the
    # readings between show a shallow bend (sweep.py). It homes onto junctions the ring does
    # not resolve (fig13's meet points 0 and 5). On since stop 37: the ring loses a convex
    # corner at a meet point as the robot slows onto it (the corner falls between two beams
    # and stays there), and giving up homing then passed fig13's and fig14's junctions
    # unhomed in 18 % and 21 % of the passes of 40-edge traces (seeds 1-12, no drift),
    # against 11 % and 8 % with it; on the three benches 39 runs of 130 complete against
    # 32, with half the wrong edges and no false merge (README, stop 37).
    sweep_join_pieces: bool = True
    sweep_shallow_bend: bool = True
    # The switch ``vertex`` (on since stop 53): two runs of a sweep are one bent wall only if
    # no two readings between them lie beyond the vertex their faces would make, nor beyond a
    # shallow bend's (sweep.py). At fig16's indent a corner and the wall behind it were
    # joined so, and the corridor's meet point rejected; at fig13's junction (5.57, 1.55) a
    # cabinet's corner and the wall it stands on, and the junction 0.29 m on with its dead
    # end was never mapped (seeds 8, 14). Seeds 1-96 complete 305 of 480 against 290
    # (README, stop 53).
    sweep_vertex: bool = True
    # ``recess`` (on since stop 36): a wall set back between two nearer obstacles is one of
    # its own (sweep.py), and a place's meet points are sought as three corners' too
    # (place.py). At fig16's indent the corridor's meet point then finds the weak meet point
    # 0.36 m off in its place, and the indent's second edge, which the ring never shows on the
    # move. Not on every arrival (dropouts cut a corner or the wall too short to count), and
    # a place read with 3 edges on one visit and 4 on the next is hard to keep as one node;
    # stop 35's dead-end reads (explorer.py) removed the false merge that kept it off. Over
    # issue 3's 30 traces it meets the edge-length target in 25 against 23 (README, stop 36).
    sweep_recess: bool = True
    # ``agree``: a view between two runs of a sweep is deeper readings that see about as far;
    # strays at unlike ranges are no view (sweep.py). fig12's cut corner read as a meet point
    # so in seeds 29 and 76; seeds 1-120 complete 357 of 600 against 350 (README, stop 52).
    sweep_view_agree: bool = True
    # ... and a stretch with no echo between two runs is a view past them, a doorway onto a
    # room beyond the sonar's range (``sweep.SILENT_VIEW_READINGS``).
    sweep_silent_view: bool = True
    place_corners: bool = True
    sensing: SensingParams = field(default_factory=SensingParams)
    boundary_clearance_m: float = 0.45  # the edge has run into its corner ...
    # ... if the corner is there: an echo this close ahead, within this angle of the way. A
    # corner's vertex is 0.64 m ahead of a robot 0.45 m off both its walls (0.9 m for a
    # 60-degree corner). A doorway is open ahead: each jamb of a 1 m door is 0.5 m off, so
    # sonar noise read fig14's doors as dead ends, and the ring could not tell by the two
    # jambs' bearings (124 degrees apart 8 cm short of the door, a square corner's walls up
    # to 112 with the ring's +/-11 degrees each).
    corner_ahead_m: float = 1.0
    corner_ahead_rad: float = math.radians(25.0)
    # ... or the gap is too narrow to pass anyway (a Nomad ring reads nothing under 0.38 m, so
    # there the bumper answers first; a ring that reads closer ends the edge here).
    pinch_clearance_m: float = 0.3
    # ... or a transducer within this of the way ahead reads its minimum range (0: no; the
    # switch ``touch_pinch`` sets 80 degrees). The ring reads nothing under 0.38 m from the
    # centre, so closing walls read 0.38 m and the pinch rule above never saw them; where the
    # corner between them fell between two beams (a desk's side and the wall behind it), the
    # base touched them: 33 contacts in 240 runs (fig1-fig16, seeds 1-48), 18 with the rule
    # at 80 degrees. Off: those runs completed 167 maps against 179 (fig13 28 against 33, the
    # five lost to copies multiplying; fig14 2 against 9, mostly out of time). At 50 degrees
    # fig13 completed 29 with 2 contacts against 11, fig14 5 with 12 against 14
    # (tests/test_tracer_pinch.py).
    pinch_touch_rad: float = 0.0
    depart_m: float = 0.15  # leave a meet point along its departure before tracing
    # ... and on along it, up to this far, until the ring sees the edge's two obstacles on
    # either side of the way: through a doorway the ring's first view merges the two jambs
    # into one obstacle (0: trace from ``depart_m`` on whatever the ring sees).
    depart_until_sides_m: float = 1.5
    sides_cycles: int = 5  # ... seen so in this many control cycles running
    sides_along_rad: float = math.radians(45.0)  # ... their edge this close to the way
    # ... or this close, leaving by a port's own bearing (``depart``'s ``sides_pair_m``; 0:
    # as any): from office:1's room meet point 94 the jambs 2.5 m ahead, one obstacle 18
    # degrees off the way, and a side wall abeam made a pair whose edge ran 38 degrees off
    # it, and the robot traced them into the room's corner.
    own_sides_along_rad: float = math.radians(25.0)
    sides_ahead_rad: float = math.radians(15.0)  # ... neither this close to it (0: off)
    lost_timeout_s: float = 1.5
    off_edge_m: float = 0.6  # d2 - d1 beyond which the robot is not on an edge any more
    # ... unless it was on one this recently: it coasts. Distance to an obstacle cannot jump
    # faster than the robot moves, so a jump of d2 - d1 in a second is the ring losing a
    # wall's echo (six to ten of sixteen transducers fall silent in a corridor), and the
    # re-access it used to set off disturbed the edge's length. 0: re-access at once.
    off_edge_coast_s: float = 0.0
    # Tracing away from a doorway, its jambs close in bearing as the robot leaves them, and
    # the ring joins them into one obstacle under 50 degrees apart (SensingParams.merge_rad):
    # the edge's pair is gone and the robot went off the graph 1.1 m into office:1's rooms,
    # re-accessed, and homed onto the room's meet point as a place of a new fragment. Where
    # the pair is lost so, the jambs the view between keeps apart go on as the pair.
    doorway_pairs: bool = True
    arm_on_access: bool = True  # see Behaviour.ACCESS in ``_law``
    # An edge turns gradually; a tangent that swings this far from the last in one cycle is
    # a new pair of obstacles, not the edge: in office:1's 5.8 m room one side wall fell
    # silent for 2 s, the side wall and the far wall behind made the pair, and the robot
    # spun round and went back the way it came. Such a swing is coasted through on the last
    # command for up to ``swing_coast_s`` (0: never).
    swing_rad: float = math.radians(45.0)
    swing_coast_s: float = 1.5
    # ... on an edge this far from its walls: a wall 2.9 m off falls silent for seconds, one
    # at fig-sized clearances for a cycle or two, and there coasting cost more than it
    # saved (the three benches: 44 runs of 130 complete coasting everywhere, 49 without).
    swing_clearance_m: float = 2.0
    # The switch ``jump`` (stop 48; on by default since stop 49): a swing is coasted through
    # at any clearance where the pair's second obstacle is this much further than the last
    # cycle's, beyond what the robot moved: that obstacle's echo was lost and a wall behind
    # makes the pair (fig12 seed 4 restarted with ``vertex``: 0.3 m out of a junction toward
    # its dead-end corner the ring read the corner's two walls as one for a cycle, the
    # tangent swung round with the block's corner 1.7 m off, and the corner's departure was
    # given up). 0: off.
    swing_jump_m: float = 0.15
    # An edge's length drops the points its chain goes out to and comes back from, at this
    # ratio of chords (edgelength.py; inf: none dropped, as up to stop 30).
    edge_spike_ratio: float = 1.5
    # ... and begins again where the way came back within this of the node it left, from
    # half a metre to 1.5 m out (edgelength.py; 0: never).
    edge_back_m: float = 0.3
    new_meet_m: float = 0.15  # a meet point estimate this far from the last is a new one
    rejected_meet_m: float = 0.5  # ... or this far, from one the sweep rejected ...
    fast_ring_firings: float = 8.0  # ... on a ring whose transducers each fired this often
    left_meet_m: float = 0.35  # ... and one this close is the meet point just left: no homing
    left_meet_travel_m: float = 2.0  # ... unless the robot has travelled this far since
    approach_keep_m: float = 1.0  # homing that began this close still arrives by that edge
    approach_look_m: float = 0.5  # the arrival direction: from where the robot was this far back
    # ... or, less far from the departure, from where it departed if this far (0: the trace
    # law's tangent)
    approach_short_m: float = 0.15
    # The edge the robot came in by is one of the meet point's edges even where the sweep does
    # not show it: a room's meet point 2.9 m from its 1 m door hears the jambs 19 degrees apart,
    # inside one beam, and read office:1's degree-4 meet point 94 with three edges, none
    # within 39 degrees of the way in; the robot, sent back out along the nearest, went into
    # a corner of the room. So a way in (the bearing back to where the robot traced
    # ``way_in_m`` off, the last 2.5 times that of travel) farther than this from every
    # departure seen is a departure of its own. Over 20 explorations of fig1-fig16 (1500 s,
    # drift paper) the way in was never more than 30 degrees off a departure (0: off).
    unseen_way_in_rad: float = math.radians(35.0)
    way_in_m: float = 1.0
    # ... read only from a trail about straight: no longer than this times the chord. Where
    # the trail bent (fig14 seed 1, 1.41 times the chord, passing the 0.53 m pair of meet
    # points 6 and 7) the chord was 41 degrees off the edge the robot came by, and the rule
    # added a fourth edge to a meet point of three: a copy of it, never recognised. Into
    # office:1's room (seeds 1-6) the trail was at most 1.12 times the chord.
    way_in_bent: float = 1.25
    # Into a room through a door in the middle of a wall: past the door the ring merges its
    # jambs behind the robot into one obstacle, the pair is lost, and access drives on
    # straight away from them until the far wall ahead is as far. There the door's edge
    # meets the room's, at a junction whose door edge no sweep resolves (1 m jambs 3.9 m off
    # are 15 degrees apart, inside one 25-degree beam), and the trace law went left or right
    # as noise had it: the door's edge was mapped ending at one of the room's two other
    # junctions on one pass and the other on the next, and a floor of two rooms off a
    # corridor came out in pieces. So an access that went on straight along the course,
    # within ``room_entry_rad``, no more than ``room_entry_reach_m``, to stand between one
    # obstacle behind and one ahead, both at least this far (0: off), is at a junction: the
    # way in and the two edges across. (Reach as far as the arbiter holds an excursion
    # straight on to be on the edge, ``ExplorerParams.straight_rejoin_m``.) Nearer, the sweep
    # resolves a door (0.8 m jambs 1.8 m off are 25 degrees apart, one beam's width) and
    # the junction is homed onto as any: at 1.2 m, in fig13's lab the rule stood 0.41 m off
    # the meet point past the gap between a cabinet and the wall (seed 13).
    room_entry_m: float = 1.8
    room_entry_rad: float = math.radians(30.0)
    room_entry_reach_m: float = 3.0
    # ... and only past a door: the trace's last pair both behind the robot, each more than
    # this off the way.
    room_entry_behind_rad: float = math.radians(100.0)
    # A meet point near in the obstacles with a doorway's jambs kept two by the view between
    # (``RingSensor.apart``), just past a door (``doors.past_door``), is homed onto as any, on
    # those obstacles (``_apart_meet``; with ``doorway_pairs`` only). Anywhere, it homed onto
    # points in fig13's lab the sweep then rejected, and seeds 35 and 36 went wrong.
    home_apart: bool = True
    apart_gap_m: float = 0.6  # ... each two of its three obstacles at least this far apart
    # Leaving by a port's own bearing (``depart``'s ``sides_pair_m``) toward the nearest
    # obstacle either side of the way within this angle of it, the two about as far (a
    # door's jambs, the view between them showing): steer for their middle, straight on
    # until one is this near (0: off). The bearing the port was read at is good to some
    # degrees, and 3 m on that put a jamb in the robot's way: out of a room of a floor of
    # two rooms off a corridor, the robot drove at a jamb the ring did not hear.
    door_steer_rad: float = math.radians(60.0)
    door_steer_m: float = 0.9
    # A contact is an obstacle the ring did not hear (a convex corner in the gap between two
    # beams, which driving straight at it keeps there): it is kept for this long as a point
    # where a transducer read its minimum range, else this far ahead of the centre along the
    # way the base was driving (0: not kept).
    contact_hold_s: float = 0.0
    contact_ahead_m: float = 0.25
    # ... but a contact where the base touched ``repeat_contacts`` - 1 times already within
    # ``repeat_window_s`` is kept for ``repeat_hold_s`` whatever ``contact_hold_s`` says (0
    # contacts: never). Re-accessing away from the wall behind it, fig1's robot (seed 10 at
    # drift paper, with a sweep change not kept, stop 64) drove back into a wall's end it
    # did not hear 157 times over 850 s.
    repeat_contacts: int = 3
    repeat_contact_m: float = 0.4
    repeat_window_s: float = 120.0
    repeat_hold_s: float = 60.0
    backoff_m: float = 0.25  # reverse this far from a contact before re-accessing ...
    backoff_mps: float = 0.1  # ... at this speed, for at most four times as long as it takes
