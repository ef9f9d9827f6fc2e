"""Where the robot stands after a merge made the node it is at the very reading it took there
(``Resolving._stand``): the port map must cover every port of the node."""

from __future__ import annotations

import math

import pytest

from hal.interfaces import NOMAD200_LIMITS
from tslam.core.explorer import Explorer
from tslam.core.portmap import PortMap
from tslam.core.tracer import MeetPointReached

TAU = 2.0 * math.pi


def _reading(bearings_deg: list[float], arrival: int) -> MeetPointReached:
    deps = tuple(sorted(math.radians(b) % TAU for b in bearings_deg))
    rel = tuple(sorted((d - deps[arrival]) % TAU for d in deps))
    return MeetPointReached(0.0, 0.0, 0.0, 1.4, len(deps), deps, arrival, rel, 4.4)


@pytest.mark.parametrize("turn_deg", [0.0, 8.0, -12.0])
def test_a_place_grown_to_this_reading_gets_a_port_map_of_every_port(turn_deg):
    # fig14's junction by the right door, read with four edges (two of them only 51 degrees
    # apart); the node holds that reading turned by what the merge carried over.
    ev = _reading([3.0, 54.0, 160.0, 287.0], arrival=3)
    node_deps = [(d + math.radians(turn_deg)) % TAU for d in ev.departures_rad]
    ex = Explorer(NOMAD200_LIMITS)
    node = ex.map.add_meet(1.4, tuple(sorted(node_deps)), (0.0, 0.0))
    short = PortMap((0, 1, 2), 0)  # the reading as a place of three edges
    here, pm = ex._stand(ev, node, short, {})
    assert here == node and len(pm.index) == 4 and sorted(pm.index) == [0, 1, 2, 3]
    ports = ex.map.node(node).departures_rad
    for p, i in enumerate(pm.index):
        off = (ports[p] - ev.departures_rad[i] - math.radians(turn_deg) + math.pi) % TAU - math.pi
        assert abs(off) < 1e-9
    assert pm.index[pm.arrival] == ev.arrival_index


def test_a_port_map_that_fits_the_node_is_kept():
    ev = _reading([3.0, 54.0, 160.0, 287.0], arrival=1)
    ex = Explorer(NOMAD200_LIMITS)
    node = ex.map.add_meet(1.4, ev.departures_rad, (0.0, 0.0))
    pm = PortMap((1, 2, 3, 0), 0)
    assert ex._stand(ev, node, pm, {})[1] == pm


def test_a_place_grown_past_a_reading_with_an_edge_fewer_shares_its_departures():
    """fig14 seed 30 (switch ``vertex``): a junction read with four edges, mapped as its
    predicted place of three; back there with three, the robot was placed on it, and the
    loop closed, growing the place to the four-edge reading. Standing with the three-edge
    reading's port map, sent out by the fourth port: index out of range."""
    ev = _reading([56.0, 148.0, 264.0], arrival=1)
    ex = Explorer(NOMAD200_LIMITS)
    node = ex.map.add_meet(1.4, tuple(math.radians(b) for b in (65, 152, 257, 350)), (0.0, 0.0))
    here, pm = ex._stand(ev, node, PortMap((0, 1, 2), 1), {})
    assert here == node and len(pm.index) == 4
    # Each port on the departure nearest it; the fourth (350 degrees) shares the one at 56,
    # as near as the reading turned by the others' 3 degrees puts it.
    assert pm.index == (0, 1, 2, 0)
    assert pm.arrival == 1
    # Sent out by the fourth port, the robot leaves by its bearing when read apart (the
    # four-edge reading), turned as the ports read alone have turned since.
    ex.port_bearings[node] = tuple(math.radians(b) for b in (65, 152, 257, 350))
    along = ex._departure_bearing(ev, node, pm, 3)
    assert along is not None
    assert abs((math.degrees(along) - 350 + 180) % 360 - 180) < 6
