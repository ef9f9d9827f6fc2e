"""Matching a meet point's departures to a map node's ports (tslam.core.portmap)."""

from __future__ import annotations

import math

from tslam.core.portmap import PortMap, bearing_shift, match_by_angle, merged_by_bearing

R = math.radians


def test_a_rotation_maps_ports_to_departures_and_back():
    pm = PortMap.rotation(1, 3, arrival_index=2)
    assert pm.arrival == 0  # departure 2 is port (2 + 1) % 3
    assert [pm.index[p] for p in range(3)] == [2, 0, 1]


def test_a_merge_shift_renumbers_the_ports_not_the_departures():
    pm = PortMap.rotation(0, 4, arrival_index=1).renamed(2)
    assert pm.arrival == 3
    assert pm.index[3] == 1 and pm.index[2] == 0


def test_a_later_reading_shifted_by_one_departure_keeps_the_ports():
    pm = PortMap.rotation(0, 3, arrival_index=0).shifted_events(1, 3)
    assert pm.index == (2, 0, 1)


def test_a_three_way_reading_of_a_four_way_node_matches_by_angle_from_the_arrival():
    ports = [R(a) for a in (10, 100, 190, 280)]  # mapped, arrival by port 1
    seen = [R(a) for a in (50, 140, 275)]  # arrival at 140: port 1 (100) is 40 degrees off
    # turned by +40 degrees; 190 and 280 show as one edge between them (235 + 40 = 275)
    pm = match_by_angle(seen, 1, ports, 1, R(25))
    assert pm is not None and pm.arrival == 1
    assert pm.index[1] == 1
    assert pm.index[0] == 0  # 10 + 40 = 50
    # The merged pair both lead along the departure between them.
    assert pm.index[2] == pm.index[3] == 2


def test_a_pair_read_as_one_edge_may_be_the_arrival_edge():
    ports = [R(a) for a in (90, 160, 200, 270)]  # arrived by port 2, from a dead end
    seen = [R(a) for a in (90, 180, 270)]  # the 160 and 200 ports read as one edge, at 180
    pm = match_by_angle(seen, 1, ports, 2, R(25))
    assert pm is not None and pm.arrival == 2
    # Port 1 leads along the arrival edge, not off along the corridor at 90 or 270.
    assert pm.index == (0, 1, 1, 2)


def test_readings_that_agree_on_nothing_but_the_arrival_do_not_match():
    ports = [R(a) for a in (0, 70, 180, 290)]
    seen = [R(a) for a in (0, 120, 240)]
    assert match_by_angle(seen, 0, ports, 0, R(25)) is None


def test_two_edges_more_or_fewer_is_another_place():
    ports = [R(a) for a in (0, 72, 144, 216, 288)]
    seen = [R(a) for a in (0, 120, 240)]
    assert match_by_angle(seen, 0, ports, 0, R(25)) is None


def test_a_close_pair_come_at_from_its_other_point_matches_turned_as_a_whole():
    # fig13 seed 3's 0.29 m pair: mapped from its west point with three edges, the east one
    # merged at 330; come back along that edge and read from the east point with both
    # points' four, the arrival edge (the east point's own, at 1) is 31 degrees off its port.
    ports = [R(a) for a in (72, 188, 330)]
    seen = [R(a) for a in (1, 73, 186, 295)]
    assert match_by_angle(seen, 0, ports, 2, R(25)) is None
    pm = match_by_angle(seen, 0, ports, 2, R(25), arrival_slack_rad=R(45))
    assert pm is not None and pm.arrival == 2
    assert pm.index == (1, 2, 0)


def test_a_turned_match_wants_every_other_departure_to_agree():
    ports = [R(a) for a in (72, 188, 330)]
    seen = [R(a) for a in (1, 73, 140, 295)]  # 188 has no counterpart within 25 degrees
    assert match_by_angle(seen, 0, ports, 2, R(25), arrival_slack_rad=R(45)) is None


def test_a_turned_match_keeps_the_arrival_within_its_slack_and_the_turn_within_drift():
    ports = [R(a) for a in (72, 188, 330)]
    seen = [R(a) for a in (250, 73, 186, 295)]  # the arrival 80 degrees off its port
    # Turned by -115 degrees, 73 and 295 fit 188 and 72 and the arrival falls 35 degrees off.
    assert match_by_angle(seen, 0, ports, 2, R(25), arrival_slack_rad=R(45)) is not None
    # Dead reckoning does not turn that far between two readings of one place.
    kw = {"arrival_slack_rad": R(45), "max_turn_rad": R(40)}
    assert match_by_angle(seen, 0, ports, 2, R(25), **kw) is None


def test_the_bearing_shift_pairs_departures_by_absolute_bearing():
    then = [math.radians(d) for d in (20, 162, 252, 290)]
    now = [math.radians(d) for d in (145, 235, 291, 362)]  # the first read past 360
    assert bearing_shift(now, then, math.radians(20)) == 1
    assert bearing_shift(now, then, math.radians(15)) is None  # 145 is 17 degrees off 162


def test_a_reading_with_an_edge_fewer_pairs_two_neighbours_by_absolute_bearing():
    # fig16 seed 18 at the weak meet point: read with four edges, then back from the
    # indent's dead end with three, the corridor's two seen as one between them.
    then = [math.radians(d) for d in (27, 150, 236, 293)]
    now = [math.radians(d) for d in (88, 239, 295)]
    assert merged_by_bearing(now, then, math.radians(20)) == (0, 0, 1, 2)
    # The pair may lie across north.
    then = [math.radians(d) for d in (10, 100, 200, 310)]
    assert merged_by_bearing([R(100), R(200), R(340)], then, R(20)) == (2, 0, 1, 2)
    assert merged_by_bearing([R(100), R(200), R(345)], then, R(20)) == (2, 0, 1, 2)


def test_an_edge_fewer_by_bearing_wants_the_rest_to_agree_and_the_pair_to_neighbour():
    then = [math.radians(d) for d in (27, 150, 236, 293)]

    def merged(*now: float) -> tuple[int, ...] | None:
        return merged_by_bearing([math.radians(d) for d in now], then, math.radians(20))

    assert merged(88, 262, 295) is None  # 236 read 26 degrees off
    assert merged(88, 239, 295, 30) is None  # as many edges: not a merge
    assert merged(100, 239) is None  # two fewer
    # The one read for two must lie between them, and well inside: here 150 was lost and
    # 236 read 3 degrees past itself, or 3 degrees short (236 read, either way).
    assert merged(12, 239, 295) is None
    assert merged(12, 233, 295) is None
    assert merged(12, 200, 295) == (0, 1, 1, 2)
