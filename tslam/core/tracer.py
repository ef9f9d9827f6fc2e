"""Access the GVG, trace its edges, home onto meet points, turn back at boundary points.

A hybrid controller (the paper's term) over the laws of ``tslam.core.laws``. It is pure:
each ``step`` takes the latest scan, odometry, drive status and the time, and returns a
drive command and the events the map needs. Which edge to take next at a meet point is
asked of a ``choose`` callback, so the exploration arbiter can decide later; the default
takes the first edge counter-clockwise from the one the robot arrived by.
"""

from __future__ import annotations

import enum
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from hal.interfaces import DriveLimits
from hal.types import DriveStatus, Odometry, SonarScan, Twist
from tslam.core import laws
from tslam.core.edgelength import EdgeOdometer
from tslam.core.place import place_obstacles
from tslam.core.sensing import Obstacle, RingSensor, SensingParams
from tslam.core.sweep import BENT_WALL_MERGE_RAD, WIDE_BEND_MERGE_RAD, Sweep, at_minimum_range

TAU = 2.0 * math.pi
# A room's door junction (``room_entry_m``): the door's edge, and the room's two across it,
# square to the way in (the ring's bearings of walls 4 m off swing by a transducer's spacing).
_ACROSS = (0.0, 0.5 * math.pi, 1.5 * math.pi)


class Behaviour(enum.Enum):
    ACCESS = "access"
    TRACE = "trace"
    HOME = "home"
    SETTLE = "settle"
    DEPART = "depart"
    BACKOFF = "backoff"


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
    # (``RingSensor.apart``), just past a door (``_past_door``), is homed onto as any, on
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
    backoff_m: float = 0.25  # reverse this far from a contact before re-accessing ...
    backoff_mps: float = 0.1  # ... at this speed, for at most four times as long as it takes


@dataclass(frozen=True)
class MeetPointReached:
    stamp_s: float
    x_m: float  # dead-reckoned
    y_m: float
    clearance_m: float
    degree: int
    departures_rad: tuple[float, ...]  # odometry frame, counter-clockwise
    arrival_index: int | None  # which departure the robot came in by
    relative_rad: tuple[float, ...]  # departure angles measured from the arrival edge
    edge_length_m: float | None = None  # length of the edge that ended here
    # How the point was found where not by homing: "entry", access into a room stopped
    # between the door behind and the far wall (``room_entry_m``); "length", a junction
    # the ring does not show from this side, stood at once the edge's known length was
    # traced (``Tracer.arrive_after``: the departures are the map's, not read).
    found_by: str = "homing"


@dataclass(frozen=True)
class BoundaryReached:
    stamp_s: float
    x_m: float
    y_m: float
    clearance_m: float
    edge_length_m: float | None = None


@dataclass(frozen=True)
class EdgeTraversed:
    stamp_s: float
    length_m: float  # the edge's own, from dead reckoning over this edge only (edgelength.py)
    start: str  # "meet" or "boundary"
    end: str


Event = MeetPointReached | BoundaryReached | EdgeTraversed
Chooser = Callable[[MeetPointReached], int]


def counter_clockwise_next(ev: MeetPointReached) -> int:
    """The first departure counter-clockwise from the arrival edge."""
    if ev.arrival_index is None:
        return 0
    return (ev.arrival_index + 1) % ev.degree


@dataclass
class _State:
    behaviour: Behaviour = Behaviour.ACCESS
    tangent: tuple[float, float] | None = None  # odometry frame, unit
    armed: bool = False
    boundary_armed: bool = True
    since: float = 0.0
    settle_tries: int = 0
    sweep: Sweep | None = None
    swept_again: bool = False  # the sweep was doubtful and the turret has turned once more
    home_target: tuple[float, float] | None = None  # homing's last estimate, odometry frame
    # The sweep's nearest obstacle (odometry frame) when homing goes to the sweep's estimate.
    home_swept: tuple[float, float] | None = None
    home_seen: float = 0.0  # when the ring last gave that estimate
    depart_dir: float = 0.0
    depart_from: tuple[float, float] = (0.0, 0.0)
    escape: tuple[float, float] | None = None  # backing off pressed: away from it (odometry)
    depart_m: float = 0.0
    # Control cycles the departure's two obstacles have straddled it, once they did not at
    # first (-1: not looked yet).
    sides_seen: int = -1
    node_distance: float | None = None  # encoder distance at the last node
    node_kind: str = ""
    last_meet: tuple[float, float] | None = None  # odometry frame
    # The last sweep found no meet point there, on a ring that fires fast. Where three
    # obstacles stay nearly equidistant along the edge (a bent wall's two faces and the far
    # side, as at fig12's cut corner), such a ring proposes one close by afresh every cycle,
    # and the robot would sweep there for minutes: the next try must be clear of it.
    rejected: bool = False
    # On any ring: where a sweep last rejected a point (odometry frame). Homing does not
    # hold on through a lost echo (``home_hold_m``) near it: it came back to fig12's cut
    # corner every few seconds for minutes, each time to be rejected again.
    rejected_at: tuple[float, float] | None = None
    left_meet: tuple[float, float] | None = None  # the meet point reported last, left by an edge
    # Where homing began and the edge's tangent there: near a junction the two closest
    # obstacles may belong to another of its edges, so the tangent the trace law keeps while
    # homing wanders can point along the wrong edge. The arrival edge is the one traced in.
    approach: tuple[float, float, float, float] | None = None  # x, y, tangent
    # Where the robot was while tracing (encoder distance, x, y; odometry frame), a metre's
    # worth: the way it really came in. Close to a junction the trace law's tangent can swing
    # onto another of its edges a moment before homing starts.
    trail: deque[tuple[float, float, float]] = field(default_factory=lambda: deque(maxlen=64))
    last_seen: float = 0.0
    until_sides_m: float = 0.0  # this departure's depart_until_sides_m
    sides_pair_m: float = 0.0  # ... and how much nearer one of its two sides may be (0: any)
    swung_at: float | None = None  # when the trace law's tangent swung off the course
    pair_clearance: float = 0.0  # the last pair's distance (d1) as the trace law set the tangent
    pair_far: float = 0.0  # ... and its second obstacle's (d2), and the odometer then
    pair_at_m: float = 0.0
    traced_at: float = -math.inf  # the last cycle the trace law set the tangent
    last_paired: float = -math.inf  # when the trace last had its two obstacles within off_edge_m
    # The edge's length: its own, not the weaving path's, and homing's wander left out (a
    # noisy third echo pulls the circumcentre about): see edgelength.py.
    odometer: EdgeOdometer = field(default_factory=EdgeOdometer)
    last_twist: Twist = field(default_factory=Twist)
    # Which way the base last translated: a contact that stops the robot zeroes the command,
    # and the way out is away from where it was going, not always backwards.
    last_v_sign: float = 1.0
    contacts: list[tuple[float, float, float]] = field(default_factory=list)  # x, y, when
    # A room's door junction reached by access (``room_entry_m``), or the length of an edge
    # to a junction the ring does not show (``stop_at``) traced: the two obstacles there and
    # the bearing back to the door, to report next cycle.
    entry: tuple[list[Obstacle], float | None] | None = None
    # The encoder distance when the trace last went on between two obstacles both behind the
    # robot (a door's jambs it has just passed) on this edge, None if it did not.
    behind_m: float | None = None
    # Homing onto a meet point the ring shows only with a doorway's jambs kept apart; and
    # where the sweep last found none so (odometry frame).
    home_apart: bool = False
    apart_rejected: tuple[float, float] | None = None
    # ``Tracer.arrive_after``: the edge's length and the departures' angles from its end.
    stop_at: tuple[float, tuple[float, ...]] | None = None


class Tracer:
    """Runs the laws; ``step`` once per control cycle."""

    def __init__(
        self,
        limits: DriveLimits,
        params: TracerParams | None = None,
        choose: Chooser = counter_clockwise_next,
    ) -> None:
        self.limits = limits
        self.p = params or TracerParams()
        self.choose = choose
        self.sensor = RingSensor(self.p.sensing)
        self.s = _State()
        self.s.odometer.detour_ratio = self.p.edge_spike_ratio
        self.obstacles: list[Obstacle] = []
        self._scan: SonarScan | None = None

    @property
    def behaviour(self) -> Behaviour:
        return self.s.behaviour

    def step(
        self, scan: SonarScan, odo: Odometry, status: DriveStatus, now_s: float
    ) -> tuple[Twist, list[Event]]:
        obs = self._with_contacts(self.sensor.update(scan, odo), odo, now_s)
        self.obstacles = obs
        self._scan = scan
        events: list[Event] = []
        if (status.bumper or status.stall) and self.s.behaviour is not Behaviour.BACKOFF:
            if self.p.contact_hold_s > 0.0:
                self.s.contacts.append((*self._contact_point(scan, odo), now_s))
            # Touching something means the laws were fed a lie: what the robot touches is
            # inside the sonar's minimum range, invisible to the ring. Back away the way it
            # came (the base drove into it), then re-access.
            if self.s.behaviour is Behaviour.TRACE:
                # The edge ran into something the ring does not hear, so close that it
                # never read as leaving the corner (the boundary rule re-arms only beyond
                # boundary_clearance_m + 0.1): backed off, the robot would trace into it
                # again. fig16 seed 7 touched the indent's back wall eleven times so.
                self.s.boundary_armed = True
            self.s.behaviour = Behaviour.BACKOFF
            self.s.entry = None
            self.s.since = now_s
            self.s.depart_from = (odo.x_m, odo.y_m)
            self.s.depart_dir = -self.s.last_v_sign
            self.s.escape = None
        elif status.stall and self.s.behaviour is Behaviour.BACKOFF:
            # Backing off straight pressed into something too: in a corner, against one wall
            # with the wheels turned a degree into it, the base moves neither way, and
            # reversing each time it stalled wedged fig12's robot there for hours.
            away = _away_from_touch(scan)
            if away is not None:
                self.s.escape = _to_odom(away, odo)
        v = self._law(obs, odo, now_s, events)
        if v is None:
            twist = Twist(0.0, 0.0, 0.0)
        elif isinstance(v, Twist):
            twist = v
        else:
            twist = laws.to_twist(v, self.limits)
        self.s.last_twist = twist
        if twist.v_mps != 0.0:
            self.s.last_v_sign = math.copysign(1.0, twist.v_mps)
        return twist, events

    def _contact_point(self, scan: SonarScan, odo: Odometry) -> tuple[float, float]:
        """Where the base touched something (odometry frame): the echo of a transducer at its
        minimum range, the one nearest the way the base was driving; else ``contact_ahead_m``
        along that way (the bumper says that, not where)."""
        way = 0.0 if self.s.last_v_sign > 0 else math.pi
        near = np.flatnonzero(at_minimum_range(scan))
        if len(near):
            i = min(near, key=lambda k: abs(_angdiff(float(scan.yaw_rad[k]), way)))
            r = float(scan.ranges_m[i])
            px = float(scan.x_m[i]) + r * math.cos(float(scan.yaw_rad[i]))
            py = float(scan.y_m[i]) + r * math.sin(float(scan.yaw_rad[i]))
        else:
            px, py = self.p.contact_ahead_m * math.cos(way), 0.0
        return _add(_to_odom((px, py), odo), odo)

    def _with_contacts(self, obs: list[Obstacle], odo: Odometry, now: float) -> list[Obstacle]:
        """``obs`` and the contacts of the last ``contact_hold_s``, nearest first."""
        s = self.s
        s.contacts = [c for c in s.contacts if now - c[2] <= self.p.contact_hold_s]
        if not s.contacts:
            return obs
        out = list(obs)
        for x, y, _ in s.contacts:
            px, py = _to_robot((x - odo.x_m, y - odo.y_m), odo)
            d = math.hypot(px, py)
            if d > 1e-6:
                out.append(Obstacle(d, px, py, -px / d, -py / d, math.atan2(py, px)))
        return sorted(out, key=lambda o: o.distance_m)

    # ------------------------------------------------------------------ behaviours
    def _law(
        self, obs: list[Obstacle], odo: Odometry, now: float, events: list[Event]
    ) -> tuple[float, float] | Twist | None:
        s, p = self.s, self.p
        if len(obs) >= 2:
            s.last_seen = now
        b = s.behaviour
        if b is Behaviour.ACCESS:
            if not obs:
                return None
            if laws.equidistant(obs, 2, p.on_edge_tol_m):
                # Keep going the way the robot was tracing, if it was; else along the heading.
                prev = _to_robot(s.tangent, odo) if s.tangent else (1.0, 0.0)
                t = laws.edge_tangent(obs[0], obs[1], prev)
                if t is not None:
                    back = self._room_entry(obs, odo)
                    if back is not None:
                        # Reported next cycle, stopped here: the arbiter first sees the
                        # robot back on the graph (its excursion straight on, the same edge).
                        s.entry = (obs[:2], back)
                        s.behaviour = Behaviour.TRACE
                        return Twist(0.0, 0.0, 0.0)
                    course, s.tangent = s.tangent, _to_odom(t, odo)
                    s.behaviour = Behaviour.TRACE
                    # Re-accessed straight on beside a meet point other than the last (off
                    # the graph where a room's door went out of hearing, office:1's 94 lay
                    # 0.75 m on), the three stand equidistant already: armed, or it is
                    # passed unhomed. Not after turning back: fig12's robot, over m0 and
                    # back, homed onto it naming the edge it had overshot along.
                    s.armed = not laws.equidistant(obs, 3, p.arm_tol_m) or (
                        p.arm_on_access
                        and self._accessed_straight_on(odo, course)
                        and self._new_meet_ahead(obs, odo, anywhere=True)
                    )
                    return self._law(obs, odo, now, events)
            entering = self._entering(obs, odo)
            if entering is not None:
                # On along the door's edge, not away from the ring's bearing of the merged
                # jambs, which swings a transducer's spacing: the junction stood at is then
                # on the door's line, and the way back out leads through the door.
                v = (p.access_mps * entering[0], p.access_mps * entering[1])
                return laws.to_twist(v, self.limits, reverse_ok=True)
            v = laws.access_velocity(obs, p.access_mps)
            # Backing away is as good as driving away, and spares a half turn.
            return laws.to_twist(v, self.limits, reverse_ok=True)
        if b is Behaviour.DEPART:
            return self._depart(obs, odo, now)
        if b is Behaviour.BACKOFF:
            gone = math.hypot(odo.x_m - s.depart_from[0], odo.y_m - s.depart_from[1])
            # Bounded in time too: backing into something else must not hold the robot here.
            if gone >= p.backoff_m or now - s.since > 4.0 * p.backoff_m / p.backoff_mps:
                s.behaviour = Behaviour.ACCESS
                return None
            if s.escape is not None:
                ex, ey = _to_robot(s.escape, odo)
                v = (p.backoff_mps * ex, p.backoff_mps * ey)
                return laws.to_twist(v, self.limits, reverse_ok=True)
            return Twist(p.backoff_mps * s.depart_dir, 0.0, 0.0)
        if b is Behaviour.TRACE and s.entry is not None:
            (seen, back), s.entry = s.entry, None
            rel, s.stop_at = (s.stop_at[1] if s.stop_at else _ACROSS), None
            self._meet(seen, odo, now, events, way_in=back, rel=rel)
            return None
        if s.stop_at is not None and b in (Behaviour.TRACE, Behaviour.HOME) and len(obs) >= 2:
            length = s.odometer.length_to(odo.x_m, odo.y_m)
            if length is not None and length >= s.stop_at[0]:
                s.entry = (obs[:2], None)
                s.behaviour = Behaviour.TRACE
                return Twist(0.0, 0.0, 0.0)
        if b is Behaviour.TRACE:
            return self._trace(obs, odo, now, events)
        if b in (Behaviour.HOME, Behaviour.SETTLE):
            if s.home_apart:
                apart = self.sensor.apart()
                if apart is not None:
                    obs = self._with_contacts(apart, odo, now)
            return self._home(obs, odo, now, events)
        return None

    def _trace(
        self, obs: list[Obstacle], odo: Odometry, now: float, events: list[Event]
    ) -> tuple[float, float] | Twist | None:
        s, p = self.s, self.p
        if len(obs) < 2:
            if now - s.last_seen > p.lost_timeout_s:
                s.behaviour = Behaviour.ACCESS
                return None
            return s.last_twist  # coast briefly through a silent patch
        if not s.armed:
            s.armed = not laws.equidistant(obs, 3, p.arm_tol_m) or self._new_meet_ahead(obs, odo)
        if obs[0].distance_m > p.boundary_clearance_m + 0.1:
            s.boundary_armed = True
        if (
            s.boundary_armed
            and obs[0].distance_m < p.boundary_clearance_m
            and (obs[0].distance_m < p.pinch_clearance_m or self._corner_ahead(odo))
        ):
            s.boundary_armed = False  # until the robot is clear of this corner again
            self._boundary(obs[0].distance_m, odo, now, events)
            return None
        if obs[1].distance_m - obs[0].distance_m > p.off_edge_m and p.doorway_pairs:
            obs = self._doorway(obs, odo, now)
        if obs[1].distance_m - obs[0].distance_m > p.off_edge_m:
            if now - s.last_paired <= p.off_edge_coast_s:
                return s.last_twist
            s.behaviour = Behaviour.ACCESS  # these two are not the edge's obstacles
            return None
        s.last_paired = now
        near = s.armed and self._meet_near(obs, odo)
        apart = self._apart_meet(odo, now) if s.armed and not near else None
        if apart is not None:
            obs = apart
        if near or apart is not None:
            s.home_apart = apart is not None
            s.behaviour = Behaviour.HOME
            s.home_target = None
            if s.tangent is not None and self._approach(odo) is None:
                s.approach = (odo.x_m, odo.y_m, *self._came_along(odo, s.tangent))
            return self._home(obs, odo, now, events)
        # Which way along the edge: the way the robot has come over its last half metre,
        # not the last cycle's tangent alone. One cycle with a false echo nearest (a
        # diffracted corner, a side lobe) pairs the wrong two obstacles, and a tangent that
        # swung round with them once stayed round: the robot went back the way it came.
        along = self._past_rejected or p.course_sign
        course = self._came_along(odo, s.tangent) if s.tangent and along else s.tangent
        prev = _to_robot(course, odo) if course else None
        o1, o2 = self._pair(obs, odo, prev)
        out = laws.trace_velocity(o1, o2, prev, p.alpha_mps, p.beta_per_s)
        if out is None:
            return s.last_twist
        v, t = out
        tracing = now - s.traced_at <= 0.5  # the last tangent is this edge's, not a start's
        s.traced_at = now
        if p.swing_coast_s > 0.0 and prev is not None and tracing:
            swung = t[0] * prev[0] + t[1] * prev[1] < math.cos(p.swing_rad)
            # The pair's second obstacle further than the robot could have moved from the
            # last one: that one's echo was lost, and a wall behind it makes the pair.
            jumped = p.swing_jump_m > 0.0 and (
                o2.distance_m - s.pair_far > p.swing_jump_m + abs(odo.distance_m - s.pair_at_m)
            )
            wide = s.pair_clearance >= p.swing_clearance_m
            if swung and (s.swung_at is not None or wide or jumped):
                if s.swung_at is None:
                    s.swung_at = now
                if now - s.swung_at <= p.swing_coast_s:
                    return s.last_twist
            else:
                s.swung_at = None
        s.pair_clearance = o1.distance_m
        behind = all(
            math.cos(o.bearing_rad) * t[0] + math.sin(o.bearing_rad) * t[1]
            < math.cos(p.room_entry_behind_rad)
            for o in (o1, o2)
        )
        if behind:
            s.behind_m = odo.distance_m
        s.pair_far, s.pair_at_m = o2.distance_m, odo.distance_m
        s.tangent = _to_odom(t, odo)
        step = laws.step_onto_edge(o1, o2)
        if step is not None:
            s.odometer.on_edge(odo.x_m, odo.y_m, odo.distance_m, _to_odom(step, odo))
        if not s.trail or odo.distance_m - s.trail[-1][0] >= 0.02:
            s.trail.append((odo.distance_m, odo.x_m, odo.y_m))
        return v

    def _accessed_straight_on(self, odo: Odometry, course: tuple[float, float] | None) -> bool:
        """Whether the robot, accessing since it last traced along ``course``, went on the
        way it traced."""
        if not self.s.trail or course is None:
            return False
        _, x, y = self.s.trail[-1]
        dx, dy = odo.x_m - x, odo.y_m - y
        gone = math.hypot(dx, dy)
        return gone >= 0.3 and dx * course[0] + dy * course[1] >= gone * math.cos(
            math.radians(30.0)
        )

    def _entering(self, obs: list[Obstacle], odo: Odometry) -> tuple[float, float] | None:
        """The course (robot frame) if access is taking the robot on into a room, straight
        on from the door's edge with the nearest obstacle, the door, behind
        (``room_entry_m``); else None."""
        s, p = self.s, self.p
        course = s.tangent
        if p.room_entry_m <= 0.0 or course is None or not s.trail or not obs:
            return None
        # Only past a doorway (``_past_door``). Elsewhere, going on straight instead of away
        # from the nearest wall lost fig13's lab edges (seeds 1-48: 33 complete against 39).
        if not self._past_door(odo):
            return None
        if obs[0].distance_m < p.room_entry_m:
            return None
        _, x, y = s.trail[-1]
        dx, dy = odo.x_m - x, odo.y_m - y
        gone = math.hypot(dx, dy)
        cos_tol = math.cos(p.room_entry_rad)
        if gone > p.room_entry_reach_m or dx * course[0] + dy * course[1] < gone * cos_tol:
            return None
        cx, cy = _to_robot(course, odo)
        b = obs[0].bearing_rad
        if math.cos(b) * cx + math.sin(b) * cy > -cos_tol:
            return None
        return cx, cy

    def _room_entry(self, obs: list[Obstacle], odo: Odometry) -> float | None:
        """The bearing back to the door (odometry frame), toward where the robot last traced
        between its jambs, if access on its way into the room (``_entering``) has reached
        the junction where the door's edge meets the room's; else None."""
        c = self._entering(obs, odo)
        if c is None or obs[1].distance_m < self.p.room_entry_m:
            return None
        _, x, y = self.s.trail[-1]
        if math.hypot(odo.x_m - x, odo.y_m - y) < 0.3:
            return None
        b = obs[1].bearing_rad
        if math.cos(b) * c[0] + math.sin(b) * c[1] < math.cos(self.p.room_entry_rad):
            return None  # the second obstacle is not ahead: another edge
        return math.atan2(y - odo.y_m, x - odo.x_m) % TAU

    def _past_door(self, odo: Odometry) -> bool:
        """Whether the robot traced between two obstacles both behind it, the jambs of a
        door it went through, within the last ``room_entry_reach_m`` of travel."""
        s = self.s
        return s.behind_m is not None and odo.distance_m - s.behind_m <= self.p.room_entry_reach_m

    def _apart_meet(self, odo: Odometry, now: float) -> list[Obstacle] | None:
        """The obstacles with a doorway's jambs kept two (``RingSensor.apart``) if they make a
        meet point near where the ring's own obstacles do not (``home_apart``); else None. A
        door junction 1.85 m inside a room, by its side wall, heard the merged jambs and the
        wall: two obstacles, and the robot traced on into the room (a floor of six rooms,
        seed 1)."""
        s, p = self.s, self.p
        if not (p.home_apart and p.doorway_pairs and self._past_door(odo)):
            return None
        near = s.apart_rejected
        if near is not None and math.dist(near, (odo.x_m, odo.y_m)) < p.rejected_meet_m:
            return None
        apart = self.sensor.apart()
        if apart is None:
            return None
        apart = self._with_contacts(apart, odo, now)
        if not self._meet_near(apart, odo):
            return None
        # Two points closer than a door is wide are no door's jambs: a view between the
        # minima of one cabinet's corner, 11 degrees apart 1.2 m off, made fig13's meet
        # points (seeds 1-48: 28 complete against 39).
        three = apart[:3]
        for i, a in enumerate(three):
            for b in three[i + 1 :]:
                if math.hypot(a.x_m - b.x_m, a.y_m - b.y_m) < p.apart_gap_m:
                    return None
        return apart

    def _doorway(self, obs: list[Obstacle], odo: Odometry, now: float) -> list[Obstacle]:
        """``obs`` with a doorway's jambs two obstacles again, if that puts the robot on an
        edge: the nearest two equidistant where the ring had merged them (``view_ratio``)."""
        apart = self.sensor.apart()
        if apart is None:
            return obs
        apart = self._with_contacts(apart, odo, now)
        if apart[1].distance_m - apart[0].distance_m <= self.p.off_edge_m:
            return apart
        return obs

    def _corner_ahead(self, odo: Odometry) -> bool:
        """Whether the ring hears something close ahead along the edge: the corner it ends
        in, not a doorway it passes through."""
        p, pts = self.p, self.sensor.points
        if self.s.tangent is None or pts is None:
            return True
        tx, ty = _to_robot(self.s.tangent, odo)
        ok = ~np.isnan(pts[:, 0])
        x, y = pts[ok, 0], pts[ok, 1]
        r = np.hypot(x, y)
        ahead = (x * tx + y * ty) >= r * math.cos(p.corner_ahead_rad)
        return bool(np.any(ahead & (r < p.corner_ahead_m)))

    def _pair(
        self, obs: list[Obstacle], odo: Odometry, prev: tuple[float, float] | None
    ) -> tuple[Obstacle, Obstacle]:
        """The two obstacles whose edge the robot traces: the two closest, except through a
        spot the sweep has just rejected as a meet point. There three obstacles stay nearly
        equidistant, any two of them are the closest from one cycle to the next, and the
        tangent swings between the edges of every pair: at fig12's cut corner the robot spun
        on the spot for seconds, then went back the way it came. Through such a spot it
        follows the pair whose edge goes on the way it was going."""
        s, p = self.s, self.p
        if (
            not self._past_rejected
            or s.last_meet is None
            or prev is None
            or not laws.equidistant(obs, 3, p.arm_tol_m)
            or math.hypot(odo.x_m - s.last_meet[0], odo.y_m - s.last_meet[1])
            > 2.0 * p.rejected_meet_m
        ):
            return obs[0], obs[1]
        best, pair = -2.0, (obs[0], obs[1])
        for i, j in ((0, 1), (0, 2), (1, 2)):
            t = laws.edge_tangent(obs[i], obs[j], prev)
            along = -2.0 if t is None else t[0] * prev[0] + t[1] * prev[1]
            if along > best:
                best, pair = along, (obs[i], obs[j])
        return pair

    @property
    def _past_rejected(self) -> bool:
        """The last sweep rejected its point on a fast ring, and ``rejected_memory`` is on."""
        return self.s.rejected and self.p.rejected_memory

    def _meet_near(self, obs: list[Obstacle], odo: Odometry) -> bool:
        s, p = self.s, self.p
        if not laws.equidistant(obs, 3, p.meet_tol_m):
            return False
        c = laws.circumcentre(*obs[:3])
        if c is None or math.hypot(*c) > p.meet_radius_m:
            return False
        cx, cy = _to_odom(c, odo)
        if self._past_rejected and s.last_meet is not None:
            # Re-arming is not enough on a fast ring: one cycle in which the third echo drops
            # out arms detection again, and the robot homed back onto the point its sweep had
            # just rejected, for minutes (fig12's cut corner through the CAN board).
            off = math.hypot(odo.x_m + cx - s.last_meet[0], odo.y_m + cy - s.last_meet[1])
            if off < p.rejected_meet_m:
                return False
        # Leaving a wide junction, one noisy echo can re-arm detection while the three
        # obstacles are still nearly equidistant: homing then pulls the robot back onto the
        # meet point it has just left, and the departure is lost.
        gone = odo.distance_m - (s.node_distance or 0.0)
        if s.left_meet is None or gone > p.left_meet_travel_m:
            return True  # a loop edge may lead back to it: after this much travel, home
        return math.hypot(odo.x_m + cx - s.left_meet[0], odo.y_m + cy - s.left_meet[1]) > (
            p.left_meet_m
        )

    def _new_meet_ahead(self, obs: list[Obstacle], odo: Odometry, anywhere: bool = False) -> bool:
        """Right after a meet point the three closest obstacles stay nearly equidistant; the
        robot is nearing another meet point only if their circumcentre has moved on, ahead
        (or, ``anywhere``, lies within ``meet_radius_m`` and at least ``left_meet_m`` from
        the last meet point)."""
        s, p = self.s, self.p
        if len(obs) < 3 or (not anywhere and (s.last_meet is None or s.tangent is None)):
            return False
        c = laws.circumcentre(*obs[:3])
        if c is None:
            return False
        cx, cy = _to_odom(c, odo)
        far = p.rejected_meet_m if s.rejected else p.new_meet_m
        if anywhere:
            if math.hypot(cx, cy) > p.meet_radius_m:
                return False
            if s.last_meet is None:
                return True
            far = max(far, p.left_meet_m)
        elif s.tangent is None or cx * s.tangent[0] + cy * s.tangent[1] <= 0.0:
            return False  # not ahead
        last = s.last_meet
        if last is None:
            return False
        return math.hypot(odo.x_m + cx - last[0], odo.y_m + cy - last[1]) >= far

    def _home(
        self, obs: list[Obstacle], odo: Odometry, now: float, events: list[Event]
    ) -> tuple[float, float] | Twist | None:
        s, p = self.s, self.p
        if s.behaviour is Behaviour.SETTLE:
            return self._settle(odo, now, events)
        if s.home_swept is not None and s.home_target is not None:
            near = math.hypot(s.home_swept[0] - odo.x_m, s.home_swept[1] - odo.y_m)
            if not obs or obs[0].distance_m > near + p.home_unheard_m:
                held = s.home_target
                return self._home_to(_to_robot((held[0] - odo.x_m, held[1] - odo.y_m), odo), now)
        s.home_swept = None
        spread_ok = p.home_spread_m <= 0.0 or laws.equidistant(obs, 3, p.home_spread_m)
        target = laws.circumcentre(*obs[:3]) if len(obs) >= 3 and spread_ok else None
        if target is not None and self._jumped(target, odo, now):
            target = None
        if target is None or math.hypot(*target) > 1.0:
            held = s.home_target
            patient = p.centred_meet and now - s.home_seen < p.home_patience_s
            if held is not None and (patient or self._keeps(held, odo, now)):
                target = _to_robot((held[0] - odo.x_m, held[1] - odo.y_m), odo)
            elif (
                held is not None
                and math.hypot(held[0] - odo.x_m, held[1] - odo.y_m) < p.home_hold_m
                and (
                    s.rejected_at is None
                    or math.dist(held, s.rejected_at) >= p.rejected_meet_m
                )
            ):
                # One cycle without the third echo near the point is a dropout, not proof
                # that there is no meet point: go on to where it was, and let the sweep judge
                # it. Giving up here traced on through fig12's m1, never homed onto.
                target = _to_robot((held[0] - odo.x_m, held[1] - odo.y_m), odo)
            else:
                # Not a meet point after all (or a bad estimate): back to tracing.
                s.behaviour = Behaviour.TRACE
                s.armed = False
                s.home_target = None
                return None
        else:
            s.home_target = _add(_to_odom(target, odo), odo)
            s.home_seen = now
        return self._home_to(target, now)

    def _home_to(self, target: tuple[float, float], now: float) -> tuple[float, float] | Twist:
        """Home towards ``target`` (robot frame); this close, stand and sweep."""
        s, p = self.s, self.p
        if math.hypot(*target) < p.settle_tol_m:
            s.home_swept = None
            s.behaviour = Behaviour.SETTLE
            s.since = now
            s.sweep = Sweep(start_s=now)
            return Twist(0.0, 0.0, p.sweep_radps)
        return laws.homing_velocity(target, p.home_gain, p.home_max_mps)

    def _keeps(self, held: tuple[float, float], odo: Odometry, now: float) -> bool:
        """Whether homing keeps to ``held``: it was this close, and seen a moment ago."""
        p = self.p
        return (
            math.hypot(held[0] - odo.x_m, held[1] - odo.y_m) < p.home_keep_m
            and now - self.s.home_seen < p.lost_timeout_s
        )

    def _jumped(self, target: tuple[float, float], odo: Odometry, now: float) -> bool:
        """Whether the ring's estimate ``target`` (robot frame) left the point homing keeps to."""
        held = self.s.home_target
        if held is None or not self._keeps(held, odo, now):
            return False
        x, y = _add(_to_odom(target, odo), odo)
        return math.hypot(x - held[0], y - held[1]) > self.p.home_jump_m

    def _settle(self, odo: Odometry, now: float, events: list[Event]) -> Twist | None:
        """Stand still and sweep the turret, then judge the meet point on the sweep."""
        s, p = self.s, self.p
        assert s.sweep is not None and self._scan is not None
        fixed = p.sweep_fixed_frame
        s.sweep.add(self._scan, self.sensor.history.at(self._scan.stamps_s)[:, 2] if fixed else 0.0)
        if now - s.since < p.sweep_s:
            return Twist(0.0, 0.0, p.sweep_radps)
        centred = p.centred_meet
        doubts: list[float] = []
        obs = s.sweep.obstacles(
            odo.heading_rad if fixed else 0.0,
            WIDE_BEND_MERGE_RAD if centred else BENT_WALL_MERGE_RAD,
            bridge=centred,
            doubts=doubts,
            silent=p.sweep_join_pieces,
            shallow=p.sweep_shallow_bend,
            vertex=p.sweep_vertex,
            recess=p.sweep_recess,
            agree=p.sweep_view_agree,
            silent_view=p.sweep_silent_view,
        )
        if doubts and p.sweep_again and not s.swept_again:
            # One deeper reading between two walls: a stray echo, or a doorway too narrow
            # for the sweep's spacing. Another turn of the turret puts readings between.
            s.swept_again = True
            s.since = now
            return Twist(0.0, 0.0, p.sweep_radps)
        turns = 2.0 if s.swept_again else 1.0
        s.swept_again = False
        s.settle_tries += 1
        fast_ring = s.sweep.firings_per_transducer / turns > p.fast_ring_firings
        touching = s.sweep.touching
        s.sweep = None
        centre = laws.wall_centre if centred else laws.circumcentre
        swept = centre(*obs[:3]) if len(obs) >= 3 else None
        if swept is not None and math.hypot(*swept) > p.converge_tol_m and s.settle_tries < 3:
            s.behaviour = Behaviour.HOME
            # Home on the sweep's estimate: the ring may not resolve the third obstacle
            # at all (a cabinet's corner 45 degrees from a wall, fig13's meet point 0).
            s.home_target = _add(_to_odom(swept, odo), odo)
            s.home_seen = now
            # Metres off, the sweep missed one of the point's obstacles, not the ring.
            near = p.home_unheard_m > 0.0 and bool(obs) and math.hypot(*swept) <= p.meet_radius_m
            s.home_swept = _add(_to_odom((obs[0].x_m, obs[0].y_m), odo), odo) if near else None
            return None
        s.settle_tries = 0
        converged = swept is not None and math.hypot(*swept) <= p.converge_tol_m
        if converged and (centred or p.spread_at_estimate):
            at = laws.seen_from(obs, swept)
            order = sorted(range(len(obs)), key=lambda i: at[i])
            obs = [replace(obs[i], distance_m=at[i]) for i in order]
        # Something within the ring's minimum range, which the sweep's obstacles leave out
        # (too few firings hear it): the walls the point is equidistant to are not the
        # nearest. fig13 seed 9 homed onto three walls 1.7 m off with a cabinet's corner
        # 0.27 m from its centre, and reported that as a meet point 0.99 m from any.
        if swept is None or touching or not laws.equidistant(obs, 3, p.meet_spread_m):
            # Three obstacles came close to equidistant but never met: the edge goes on.
            s.behaviour = Behaviour.TRACE
            if s.home_apart:
                # Homed for the ring's finer reading only: what the ring reads as ever may
                # still be a meet point here (fig13's close pairs by a cabinet's gap), so
                # this is no rejection; only that reading is not asked here again.
                s.home_apart = False
                s.apart_rejected = (odo.x_m, odo.y_m)
                return None
            s.armed = False
            # With centred_meet, where the rejected point is: the sweep's estimate if it
            # is about here, else here. An estimate metres off (three walls far from
            # equidistant) made any estimate here look new, and the robot homed and swept
            # at fig12's cut corner for minutes.
            near = swept is not None and (not centred or math.hypot(*swept) <= p.meet_radius_m)
            s.last_meet = _add(_to_odom(swept, odo), odo) if near else (odo.x_m, odo.y_m)
            s.rejected = fast_ring
            s.rejected_at = (odo.x_m, odo.y_m)
            # On the way it came in: while homing, the trace law's tangent swings between
            # the pairs of nearly equidistant walls, and at fig12's cut corner it had swung
            # round, so the robot went back down the edge it had come up. At fig16's weak
            # meet point (seed 5) that turned the robot back mid-corridor, and the explorer
            # called a third of the corridor the whole map.
            a = self._approach(odo)
            if a is not None:
                s.tangent = (a[2], a[3])
            return None
        point = _add(_to_odom(swept, odo), odo) if converged and p.length_at_estimate else None
        self._meet(obs, odo, now, events, point)
        return None

    def _meet(
        self,
        obs: list[Obstacle],
        odo: Odometry,
        now: float,
        events: list[Event],
        point: tuple[float, float] | None = None,
        way_in: float | None = None,
        rel: tuple[float, ...] | None = None,
    ) -> None:
        """Report the meet point the robot stands at and set off along the departure the
        arbiter chooses (``way_in``: the bearing of the way in, known, else from the trail;
        ``rel``: the departures' angles from the way in, as the map has them, not read)."""
        s, p = self.s, self.p
        s.rejected_at = None
        found_by = "entry" if way_in is not None else "homing" if rel is None else "length"
        near = [o for o in obs if o.distance_m - obs[0].distance_m <= p.degree_tol_m]
        around = place_obstacles(obs, near, p.place_radius_m, p.place_tol_m, p.place_corners)
        bearings = laws.departure_bearings(around)
        deps = sorted((odo.heading_rad + b) % TAU for b in bearings)
        arrival = None
        tangent = s.tangent
        a = self._approach(odo)
        if a is not None:
            tangent = (a[2], a[3])
        if tangent is not None:
            back = math.atan2(-tangent[1], -tangent[0]) % TAU
            arrival = min(range(len(deps)), key=lambda k: _angdiff(deps[k], back))
        if way_in is None and p.unseen_way_in_rad > 0.0 and rel is None:
            way_in = self._way_in(odo)
        if way_in is not None and min(_angdiff(d, way_in) for d in deps) > p.unseen_way_in_rad:
            deps = sorted((*deps, way_in))
            arrival = deps.index(way_in)
        if rel is not None:
            # Not homed: the way back is the door's line, or the chord to where the edge
            # began (the trace law's tangent swings by a transducer's spacing); the rest
            # are given.
            back = way_in if way_in is not None else self._way_back(odo)
            deps = sorted((back + r) % TAU for r in rel)
            arrival = min(range(len(deps)), key=lambda k: _angdiff(deps[k], back))
        base = deps[arrival] if arrival is not None else 0.0
        rel = tuple(sorted((d - base) % TAU for d in deps))
        clearance = sum(o.distance_m for o in near) / len(near)
        length = self._edge_done(odo, now, "meet", events, point)
        ev = MeetPointReached(
            now, odo.x_m, odo.y_m, clearance, len(deps), tuple(deps), arrival, rel, length,
            found_by,
        )  # fmt: skip
        events.append(ev)
        s.last_meet = s.left_meet = (odo.x_m, odo.y_m)
        s.rejected = False
        k = self.choose(ev)
        self._start_depart(deps[k], odo)

    def _boundary(self, clearance: float, odo: Odometry, now: float, events: list[Event]) -> None:
        s = self.s
        length = self._edge_done(odo, now, "boundary", events)
        events.append(BoundaryReached(now, odo.x_m, odo.y_m, clearance, length))
        assert s.tangent is not None
        s.left_meet = None  # the way back leads to it: homing onto it is wanted now
        back = math.atan2(-s.tangent[1], -s.tangent[0])
        self._start_depart(back, odo, distance=0.0)

    def _edge_done(
        self,
        odo: Odometry,
        now: float,
        kind: str,
        events: list[Event],
        point: tuple[float, float] | None = None,
    ) -> float | None:
        s = self.s
        x, y = point if point is not None else (odo.x_m, odo.y_m)
        length = s.odometer.length_to(x, y)  # None before the first node
        if length is not None:
            events.append(EdgeTraversed(now, length, s.node_kind, kind))
        s.odometer.start(x, y)
        s.node_distance = odo.distance_m
        s.node_kind = kind
        return length

    def _came_along(self, odo: Odometry, tangent: tuple[float, float]) -> tuple[float, float]:
        """The direction the robot came in along: from where it traced ``approach_look_m``
        of travel ago (dead reckoning is good over that), on a shorter edge from where it
        departed (``approach_short_m``), else the trace law's tangent."""
        s, p = self.s, self.p
        back = [q for q in s.trail if q[0] <= odo.distance_m - p.approach_look_m]
        if not back and s.trail and p.approach_short_m > 0.0:
            # A short edge: the way since the departure is all there is behind. The trace
            # law's tangent is no guide here: between a close pair's nearly equidistant
            # walls it swings round (fig13 seed 3: 0.35 m west from one point of its 0.53 m
            # pair to the other with the tangent pointing east, and the edge was mapped on
            # the departure opposite the one it came in by).
            dx, dy = odo.x_m - s.depart_from[0], odo.y_m - s.depart_from[1]
            n = math.hypot(dx, dy)
            if n >= p.approach_short_m and odo.distance_m - s.trail[0][0] < p.approach_look_m:
                return dx / n, dy / n
        if not back or odo.distance_m - back[-1][0] > 2.0 * p.approach_look_m:
            return tangent  # a detour or a fresh start since: no straight stretch behind
        _, x, y = back[-1]
        dx, dy = odo.x_m - x, odo.y_m - y
        n = math.hypot(dx, dy)
        if n < 0.5 * p.approach_look_m:
            return tangent
        return dx / n, dy / n

    def _way_in(self, odo: Odometry) -> float | None:
        """The bearing (odometry frame) from here back along the traced way in to a point
        ``way_in_m`` off, if the robot traced it lately; None if not."""
        p = self.p
        for d, x, y in reversed(self.s.trail):
            if odo.distance_m - d > 2.5 * p.way_in_m:
                return None
            if math.hypot(x - odo.x_m, y - odo.y_m) >= p.way_in_m:
                return math.atan2(y - odo.y_m, x - odo.x_m) % TAU
        return None

    def _way_back(self, odo: Odometry) -> float:
        """The bearing (odometry frame) back to the node this edge began at, else to where
        its trail began, or against the trace law's tangent if that is under 0.3 m off.
        The node was homed onto, good to centimetres: over the 1 m edges of a floor of two
        rooms (8 stands) that was within 3.3 degrees of the edge's true bearing, the
        edge's own points by the sonar within 8.2 (about a junction the two nearest walls
        are often another edge's pair) and the trail's start within 5.4."""
        s = self.s
        ends = [s.odometer.origin]
        if s.trail:
            ends.append((s.trail[0][1], s.trail[0][2]))
        for end in ends:
            if end is not None and math.hypot(end[0] - odo.x_m, end[1] - odo.y_m) >= 0.3:
                return math.atan2(end[1] - odo.y_m, end[0] - odo.x_m) % TAU
        t = s.tangent or (math.cos(odo.heading_rad), math.sin(odo.heading_rad))
        return math.atan2(-t[1], -t[0]) % TAU

    def arrive_after(self, length_m: float, rel_rad: tuple[float, ...]) -> None:
        """On the edge just departed along, stand at the junction at its end once
        ``length_m`` of it is traced, and report it with departures at ``rel_rad`` from the
        way in: a junction the ring does not show from this side (a room's door junction
        seen along the room's edge, ``room_entry_m``)."""
        self.s.stop_at = (length_m, tuple(rel_rad))

    def _approach(self, odo: Odometry) -> tuple[float, float, float, float] | None:
        """Where homing onto this meet point began, if it began close enough to count."""
        a = self.s.approach
        if a is None or math.hypot(odo.x_m - a[0], odo.y_m - a[1]) > self.p.approach_keep_m:
            return None
        return a

    def depart(
        self,
        direction_rad: float,
        odo: Odometry,
        until_sides_m: float | None = None,
        sides_pair_m: float = 0.0,
    ) -> None:
        """Leave the meet point the robot stands at along ``direction_rad`` (odometry frame):
        for an arbiter that held the robot there and has since decided where to go. Going on
        straight until the edge's two obstacles straddle the way, up to ``until_sides_m``
        (None: ``depart_until_sides_m``), and with ``sides_pair_m`` the two no further apart
        than that in distance: the sweep did not show this departure, and the two nearest may
        be no edge's pair yet."""
        self._start_depart(direction_rad, odo)
        if until_sides_m is not None:
            self.s.until_sides_m = until_sides_m
        self.s.sides_pair_m = sides_pair_m

    def go_straight(self, distance_m: float) -> None:
        """On a departure just begun, go on straight along it at least ``distance_m`` from the
        meet point before tracing."""
        if self.s.behaviour is Behaviour.DEPART:
            self.s.depart_m = max(self.s.depart_m, distance_m)

    def _start_depart(self, direction: float, odo: Odometry, distance: float | None = None) -> None:
        s = self.s
        s.behaviour = Behaviour.DEPART
        s.depart_dir = direction
        s.depart_from = (odo.x_m, odo.y_m)
        s.trail.clear()  # a new edge: the way in is measured along it alone
        s.tangent = (math.cos(direction), math.sin(direction))
        s.armed = False
        s.depart_m = self.p.depart_m if distance is None else distance
        s.sides_seen = -1
        s.until_sides_m = self.p.depart_until_sides_m
        s.sides_pair_m = 0.0
        s.approach = None
        s.stop_at = None
        s.home_apart = False
        s.apart_rejected = None
        s.behind_m = None

    def _depart(
        self, obs: list[Obstacle], odo: Odometry, now: float
    ) -> tuple[float, float] | Twist | None:
        s, p = self.s, self.p
        err = (s.depart_dir - odo.heading_rad + math.pi) % TAU - math.pi
        gone = math.hypot(odo.x_m - s.depart_from[0], odo.y_m - s.depart_from[1])
        if s.sides_pair_m > 0.0 and p.door_steer_m > 0.0:
            # Out toward a door the ring merged from afar (``door_steer_m``): its jambs are
            # two as soon as the view between them shows (``RingSensor.apart``).
            apart = self.sensor.apart()
            gap = None if apart is None else self._door_ahead(apart, err)
            if gap is not None:
                s.depart_dir = (odo.heading_rad + gap[0]) % TAU
                err = gap[0]
                if gap[1] > p.door_steer_m:
                    return (p.alpha_mps * math.cos(err), p.alpha_mps * math.sin(err))
        if gone >= s.depart_m and abs(err) < math.radians(15) and self._sides_seen(obs, err, gone):
            s.behaviour = Behaviour.TRACE
            return None
        if abs(err) > math.radians(10) and gone < 0.02:
            return Twist(0.0, laws.steer_rate(err, self.limits), 0.0)
        return (p.alpha_mps * math.cos(err), p.alpha_mps * math.sin(err))

    def _door_ahead(self, obs: list[Obstacle], err: float) -> tuple[float, float] | None:
        """The bearing (robot frame) of the middle between the nearest obstacle either side
        of the way ``err`` off the heading, each within ``door_steer_rad`` of it, and the
        nearer one's distance, if the two are about as far (a door's jambs ahead); else
        None."""
        p = self.p
        sides: dict[bool, Obstacle] = {}
        for o in obs:  # nearest first
            off = (o.bearing_rad - err + math.pi) % TAU - math.pi
            if abs(off) <= p.door_steer_rad:
                sides.setdefault(off > 0.0, o)
        if len(sides) < 2:
            return None
        a, b = sides[True], sides[False]
        if abs(a.distance_m - b.distance_m) > self.s.sides_pair_m:
            return None
        mid = math.atan2(0.5 * (a.y_m + b.y_m), 0.5 * (a.x_m + b.x_m))
        return mid, min(a.distance_m, b.distance_m)

    def _sides_seen(self, obs: list[Obstacle], err: float, gone: float) -> bool:
        """Whether tracing may begin this far out along a departure ``err`` off the heading.

        A departure leaves between two obstacles, so the edge's pair lies one on each side of
        it. From a junction by a doorway the ring's transducers, 22.5 degrees apart, do not
        see between the jambs: it merges them into one obstacle, and the two closest it
        reports, a jamb and the wall beside it, lie on one side; tracing them leads along the
        wall, not through the door. Going on straight until the pair straddles the way (the
        jambs a few decimetres off are far apart in bearing) takes the robot into the door."""
        p = self.p
        if gone >= self.s.until_sides_m or len(obs) < 2:
            return True
        if obs[0].distance_m < p.boundary_clearance_m + 0.1:
            return True  # something close ahead: the trace law and its boundary rule decide
        a, b = ((o.bearing_rad - err + math.pi) % TAU - math.pi for o in obs[:2])
        way = (math.cos(err), math.sin(err))
        t = laws.edge_tangent(obs[0], obs[1], way)
        # Their edge must also run along the way: a wall behind on the other side (the
        # table beside fig14's door) makes a pair that straddles it, of another edge.
        within = p.sides_along_rad
        if self.s.sides_pair_m > 0.0 and p.own_sides_along_rad > 0.0:
            within = min(within, p.own_sides_along_rad)
        along = t is not None and t[0] * way[0] + t[1] * way[1] >= math.cos(within)
        # The ring glimpses the far jamb now and then before it holds it: a glimpse
        # traced from is the jamb-and-wall edge again a cycle later.
        # And neither lies dead ahead: that is what the robot is driving at, not a side. Out
        # of office:1's room toward its door, 2.4 m off, the ring merged the jambs into one
        # obstacle 6 degrees off the way, paired it with a side wall, and traced into the
        # room's corner.
        ahead = min(abs(a), abs(b)) < p.sides_ahead_rad
        ok = along and (a > 0.0) != (b > 0.0) and not ahead
        if self.s.sides_pair_m > 0.0:
            # And, on a departure the arbiter asked that of, about as far (``depart``).
            ok = ok and obs[1].distance_m - obs[0].distance_m <= self.s.sides_pair_m
        if self.s.sides_seen < 0 and ok:
            return True  # as almost everywhere: the pair is there at ``depart_m``
        self.s.sides_seen = self.s.sides_seen + 1 if ok else 0
        return self.s.sides_seen >= p.sides_cycles


def _to_odom(t: tuple[float, float], odo: Odometry) -> tuple[float, float]:
    c, s = math.cos(odo.heading_rad), math.sin(odo.heading_rad)
    return c * t[0] - s * t[1], s * t[0] + c * t[1]


def _add(v: tuple[float, float], odo: Odometry) -> tuple[float, float]:
    return odo.x_m + v[0], odo.y_m + v[1]


def _to_robot(t: tuple[float, float], odo: Odometry) -> tuple[float, float]:
    c, s = math.cos(odo.heading_rad), math.sin(odo.heading_rad)
    return c * t[0] + s * t[1], -s * t[0] + c * t[1]


def _away_from_touch(scan: SonarScan) -> tuple[float, float] | None:
    """The unit vector (robot frame) away from every transducer that reads its minimum
    range (something nearer than it can measure), or None if none does or they cancel."""
    near = at_minimum_range(scan)
    if not near.any():
        return None
    x = -float(np.sum(np.cos(scan.yaw_rad[near])))
    y = -float(np.sum(np.sin(scan.yaw_rad[near])))
    norm = math.hypot(x, y)
    return (x / norm, y / norm) if norm > 1e-6 else None


def _angdiff(a: float, b: float) -> float:
    return abs((a - b + math.pi) % TAU - math.pi)
