"""What the tracer reports to the map as the robot traces: meet points, boundary points and
the edges between them; and how the next edge is chosen at a meet point."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass


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
