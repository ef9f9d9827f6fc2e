"""Which departure of a meet-point event is which port of a map node.

Usually a rotation: the signature matched under a cyclic shift (``signature.rotations``).
But a junction is not always read with the same number of edges: two meet points closer
than the robot is wide are one junction on one visit and a meet point plus a short edge on
another, and a weak meet point shows on one pass and not on the next (section VII-B). When
the robot has just followed a known edge to its end, the edge already says where it is, and
the departures are matched to the node's ports by their angles from the arrival edge.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from tslam.core.frames import TAU, angdiff


@dataclass(frozen=True)
class PortMap:
    """``index[p]`` is the event's departure for port ``p``; ``arrival`` the port the robot
    came in by (None if it does not know). After an angle match two ports may share the
    departure that leads between them."""

    index: tuple[int, ...]
    arrival: int | None

    @classmethod
    def rotation(cls, k: int, degree: int, arrival_index: int | None) -> PortMap:
        """Event departure ``i`` is port ``(i + k) % degree``."""
        arrival = None if arrival_index is None else (arrival_index + k) % degree
        return cls(tuple((p - k) % degree for p in range(degree)), arrival)

    def renamed(self, shift: int) -> PortMap:
        """The same departures after a merge made port ``p`` port ``(p + shift)``."""
        n = len(self.index)
        index = [0] * n
        for p, i in enumerate(self.index):
            index[(p + shift) % n] = i
        return PortMap(tuple(index), None if self.arrival is None else (self.arrival + shift) % n)

    def shifted_events(self, shift: int, degree: int) -> PortMap:
        """The same ports for a later event of the same junction whose departure ``i`` is
        departure ``(i + shift)`` of this one."""
        return PortMap(tuple((i - shift) % degree for i in self.index), self.arrival)


def bearing_shift(
    now_rad: Sequence[float], then_rad: Sequence[float], tol_rad: float
) -> int | None:
    """The shift ``k`` under which departure ``i`` read now is departure ``i + k`` read then,
    both by absolute bearing (dead reckoning's heading is good over seconds); None unless
    every pair agrees within ``tol_rad`` under it."""
    n = len(now_rad)

    def misfit(k: int) -> float:
        return max(angdiff(now_rad[i], then_rad[(i + k) % n]) for i in range(n))

    shift = min(range(n), key=misfit)
    return shift if misfit(shift) <= tol_rad else None


def merged_by_bearing(
    now_rad: Sequence[float], then_rad: Sequence[float], tol_rad: float
) -> tuple[int, ...] | None:
    """For a reading with one departure fewer than one taken moments before at the same
    point: ``index[i]``, the departure read now that departure ``i`` read then leads along,
    by absolute bearing (dead reckoning's heading is good over seconds). Two neighbouring
    departures read then are one now, between them, however far from either (fig16's
    corridor edges, read from the weak meet point 60 to 90 degrees either side of the one
    departure they share) but more than ``tol_rad``; every other agrees within ``tol_rad``
    with one of its own. None unless exactly one pair makes the reading so."""
    n = len(then_rad)
    if len(now_rad) != n - 1 or n < 3:
        return None
    order = sorted(range(n), key=lambda i: then_rad[i] % TAU)
    nearest = [min(range(n - 1), key=lambda m: angdiff(now_rad[m], b)) for b in then_rad]
    found = []
    for k in range(n):
        lo, hi = order[k], order[(k + 1) % n]
        index = list(nearest)
        alone = [i for i in range(n) if i not in (lo, hi)]
        if any(angdiff(now_rad[index[i]], then_rad[i]) > tol_rad for i in alone):
            continue
        rest = set(range(n - 1)) - {index[i] for i in alone}
        if len(rest) != 1:
            continue
        index[lo] = index[hi] = m = rest.pop()
        # Well inside: read within ``tol_rad`` of either, that one may be read and the other
        # lost, as well as the two merged.
        inside = (now_rad[m] - then_rad[lo]) % TAU
        if tol_rad < inside < (then_rad[hi] - then_rad[lo]) % TAU - tol_rad:
            found.append(tuple(index))
    return found[0] if len(found) == 1 else None


def match_by_angle(
    seen_rad: Sequence[float],
    arrival_index: int,
    ports_rad: Sequence[float],
    arrival_port: int,
    angle_tol_rad: float,
    arrival_slack_rad: float = 0.0,
    max_turn_rad: float = math.pi,
) -> PortMap | None:
    """Match the departures seen to a node's ports by their angles from the arrival edge,
    for a reading with one departure more or fewer; None if too few of them agree (at least
    all but two of the smaller side's, and one besides the arrival).

    With ``arrival_slack_rad``, failing that, the arrival edge may be read up to that far
    off its port if every other departure of the smaller side agrees with the reading turned
    no more than ``max_turn_rad`` as a whole (``_match_turned``)."""
    ns, nm = len(seen_rad), len(ports_rad)
    if abs(ns - nm) != 1:
        return None
    # Anchored on the arrival: the reading turned by as much as its arrival edge is off.
    turn = seen_rad[arrival_index] - ports_rad[arrival_port]
    index = _nearest(seen_rad, arrival_index, ports_rad, arrival_port, turn)
    agree = sum(
        angdiff(seen_rad[i] - turn, ports_rad[p]) <= angle_tol_rad
        for p, i in enumerate(index)
        if p != arrival_port
    )
    if agree >= max(1, min(ns, nm) - 2):
        return PortMap(tuple(index), arrival_port)
    if arrival_slack_rad <= 0.0:
        return None
    return _match_turned(
        seen_rad,
        arrival_index,
        ports_rad,
        arrival_port,
        angle_tol_rad,
        arrival_slack_rad,
        max_turn_rad,
    )


def turned_onto(
    ports_rad: Sequence[float], seen_rad: Sequence[float], arrival_index: int | None
) -> PortMap:
    """The port map of a reading onto a node whose ports are a turned copy of its departures
    (a node a merge grew from some reading of the place): with as many ports as departures,
    the rotation under which the turn is the most uniform; with another number, each port
    on the departure nearest it under the turn that fits them best (two ports may share one:
    the place has an edge this reading did not resolve)."""
    d = len(seen_rad)
    if len(ports_rad) == d:

        def spread(k: int) -> float:
            turns = [ports_rad[(i + k) % d] - seen_rad[i] for i in range(d)]
            return -math.hypot(sum(map(math.cos, turns)), sum(map(math.sin, turns)))

        return PortMap.rotation(min(range(d), key=spread), d, arrival_index)

    def matched(turn: float) -> tuple[float, float, tuple[int, ...]]:
        index = tuple(
            min(range(d), key=lambda i: angdiff(seen_rad[i], b - turn)) for b in ports_rad
        )
        off = sum(angdiff(seen_rad[i], b - turn) for i, b in zip(index, ports_rad, strict=True))
        return off, turn, index

    # Every port on every departure: the turns worth trying.
    _, turn, index = min((matched(b - s) for b in ports_rad for s in seen_rad), key=lambda m: m[0])
    a = arrival_index
    mine = [p for p, i in enumerate(index) if i == a]
    if a is None or not mine:
        return PortMap(index, None)
    return PortMap(index, min(mine, key=lambda p: angdiff(ports_rad[p] - turn, seen_rad[a])))


def _match_turned(
    seen_rad: Sequence[float],
    a: int,
    ports_rad: Sequence[float],
    q: int,
    tol: float,
    slack: float,
    max_turn: float,
) -> PortMap | None:
    """The match of ``match_by_angle`` with the arrival edge read askew. At a pair of meet
    points closer than the robot is wide, the edge the robot came in by and the one the map
    has for it leave from different points of the pair: fig13's 0.29 m pair, come at from its
    east point and read with both points' edges, had its arrival 30 degrees off the port
    mapped from the west point, and every other departure turned 30 degrees with it. The
    departures are matched by one turn of the whole reading instead, taken from a pair of
    them other than the arrival's, no larger than ``max_turn`` (dead reckoning's heading
    drift since the node was read: the two readings are in one odometry frame); every other
    departure of the smaller side must agree within ``tol``, the arrival within ``slack``,
    and only one matching may do so."""
    ns, nm = len(seen_rad), len(ports_rad)
    found: set[tuple[int, ...]] = set()
    for i0 in range(ns):
        for p0 in range(nm):
            if i0 == a or p0 == q:
                continue
            turn = seen_rad[i0] - ports_rad[p0]
            if angdiff(turn, 0.0) > max_turn or angdiff(seen_rad[a] - turn, ports_rad[q]) > slack:
                continue
            index = _nearest(seen_rad, a, ports_rad, q, turn)
            if ns > nm:
                ok = len(set(index)) == nm and all(
                    angdiff(seen_rad[index[p]] - turn, ports_rad[p]) <= tol
                    for p in range(nm)
                    if p != q
                )
            else:
                ok = all(
                    any(
                        angdiff(seen_rad[i] - turn, ports_rad[p]) <= tol
                        for p in range(nm)
                        if p != q
                    )
                    for i in range(ns)
                    if i != a
                )
            if ok:
                found.add(tuple(index))
    if len(found) != 1:
        return None
    return PortMap(found.pop(), q)


def _nearest(
    seen_rad: Sequence[float], a: int, ports_rad: Sequence[float], q: int, turn: float
) -> list[int]:
    """For each port, the departure nearest it with the reading turned back by ``turn``; the
    arrival port's is the arrival departure ``a``. Read with one edge fewer, the pair seen as
    one may be the arrival's: a port beside the arrival port then leads along the arrival
    departure too (fig16's indent, arrived at from one of its two dead ends with the pair read
    as one edge)."""
    ns, nm = len(seen_rad), len(ports_rad)
    index = []
    for p in range(nm):
        if p == q:
            index.append(a)
            continue
        others = (i for i in range(ns) if ns < nm or i != a)
        index.append(min(others, key=lambda i: angdiff(seen_rad[i] - turn, ports_rad[p])))
    return index

