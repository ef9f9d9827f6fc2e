"""The zero-dimensional test of section V-A: could two nodes be the same place?

Only stable features count: the kind of node, its clearance (the homing law converges, so the
distance to the closest obstacles repeats), its number of edges (Fig. 10), which of its edges
end at boundary points (Fig. 9) and the *relative* departure angles of its edges (Fig. 11).

Absolute departure angles are useless between visits: they are measured in the odometry frame,
and heading drift rotates that frame. A rotation cannot change the gaps between consecutive
departures or their cyclic order, so the test compares gaps, trying every cyclic shift of one
node's ports against the other's. A shift that fits is how a later merge learns which
departure of one visit is which departure of the other.

Convention used everywhere in the map: shift ``k`` says that port ``j`` of the first node is
port ``(j + k) % degree`` of the second.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from tslam.core.frames import TAU


@dataclass(frozen=True)
class Signature:
    """What the robot can sense of a node, ready to compare.

    ``to_boundary`` has one entry per departure: True if that edge is known to end at a
    boundary point, False if known to end at a meet point, None while it is unexplored. A
    localizer can build one for a node it has just homed onto before adding it to the map.
    """

    kind: str
    clearance_m: float
    departures_rad: tuple[float, ...]
    to_boundary: tuple[bool | None, ...] = ()

    @property
    def degree(self) -> int:
        return len(self.departures_rad)


def cyclic_gaps(departures_rad: Sequence[float]) -> tuple[float, ...]:
    """Angle from each departure counter-clockwise to the next one (the last wraps round).

    A single departure has the whole turn as its gap, so degree-1 nodes compare equal.
    """
    n = len(departures_rad)
    if n == 1:
        return (TAU,)
    return tuple((departures_rad[(j + 1) % n] - departures_rad[j]) % TAU for j in range(n))


def rotations(
    a: Signature, b: Signature, clearance_tol_m: float, angle_tol_rad: float
) -> list[int]:
    """Every shift ``k`` under which ``a`` could be ``b``; empty means different places.

    Several shifts fit when a node is symmetric (three edges 120 degrees apart): the
    zero-dimensional test cannot choose, and the map's topology must (section V-C).
    """
    if a.kind != b.kind or a.degree != b.degree or a.degree == 0:
        return []
    # A dead end's clearance is where the boundary rule stopped the robot (0.45 m with the
    # corner ahead, nearer where the gap pinches), not a feature of the place: fig1's corner
    # read 0.44 m and 0.29 m kept a restarted robot's proven placement from merging, and its
    # copies stayed as ambiguities (seed 1); fig12's read 0.45 m and 0.29 m kept a whole
    # stored map from fitting the robot's new one (seed 2 restarted at (4.0, 1.2)).
    if a.kind != "boundary" and abs(a.clearance_m - b.clearance_m) > clearance_tol_m:
        return []
    n = a.degree
    ga, gb = cyclic_gaps(a.departures_rad), cyclic_gaps(b.departures_rad)
    ba = a.to_boundary or (None,) * n
    bb = b.to_boundary or (None,) * n
    out = []
    for k in range(n):
        if any(abs(ga[j] - gb[(j + k) % n]) > angle_tol_rad for j in range(n)):
            continue
        if any(
            ba[j] is not None and bb[(j + k) % n] is not None and ba[j] != bb[(j + k) % n]
            for j in range(n)
        ):
            continue
        out.append(k)
    return out
