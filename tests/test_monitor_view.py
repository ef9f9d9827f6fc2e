"""What the monitor shows, from a view built in memory: terminal text and the JSON snapshot."""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass, field

from tslam.link.schemas import EdgeMsg, EventMsg, NodeMsg, RobotState, ScanMsg
from tslam.programs.monitor_cmd import _print_once
from tslam.programs.monitor_view import events_caught_up, map_complete, render_lines, snapshot
from tslam.programs.monitor_web import Notifier


@dataclass
class FakeView:
    """The shape of ``tslam.link.client.MonitorView``."""

    online: bool = True
    state: RobotState | None = None
    nodes: dict[int, NodeMsg] = field(default_factory=dict)
    edges: dict[int, EdgeMsg] = field(default_factory=dict)
    epoch: str = "e1"
    seq: int = 0
    events: list[EventMsg] = field(default_factory=list)
    last_scan: ScanMsg | None = None
    gaps: int = 0
    synced: bool = True
    malformed: int = 0


def state(**kw) -> RobotState:
    base = dict(
        robot="r1", epoch="e1", stamp_s=12.5, behaviour="trace_edge", mode="explore",
        paused=False, done=False, current_node=None, current_edge=2, goal_node=3,
        x=1.25, y=-0.5, theta=math.pi / 2, hypotheses=["h0: node 1 is new"], map_seq=7,
        map_nodes=3, map_edges=2, unexplored=2, error=None,
    )  # fmt: skip
    base.update(kw)
    return RobotState(**base)


def view(**kw) -> FakeView:
    nodes = {
        0: NodeMsg(0, "meet", 0.0, 0.0, 1.0, 3, 1),
        1: NodeMsg(1, "meet", 4.0, 0.0, 1.1, 3, 0, [2]),
        2: NodeMsg(2, "boundary", 4.0, 3.0, 0.4, 1, 1, [1]),
    }
    edges = {0: EdgeMsg(0, 0, 1, 4.0), 1: EdgeMsg(1, 1, 2, 3.0)}
    events = [EventMsg("r1", "e1", i, float(i), "node", f"new meet point {i}") for i in range(12)]
    v = FakeView(state=state(), nodes=nodes, edges=edges, seq=7, events=events, gaps=1)
    for k, val in kw.items():
        setattr(v, k, val)
    return v


def test_terminal_view_shows_what_the_robot_is_doing():
    text = "\n".join(render_lines("r1", view()))
    for expected in (
        "robot r1: ONLINE",
        "behaviour trace_edge",
        "mode explore",
        "running",
        "on edge 2",
        "goal node 3",
        "x 1.25 m",
        "y -0.50 m",
        "theta 90 deg",
        "h0: node 1 is new",
        "map: 3 nodes, 2 edges, 2 with unexplored exits, 2 ambiguous",
        "gaps repaired 1",
        "new meet point 11",
    ):
        assert expected in text, expected
    # Only the most recent events: the oldest have scrolled away.
    assert "new meet point 3" not in text and "new meet point 4" in text
    assert "\x1b" not in text  # plain text; the caller decides about clearing the screen


def test_terminal_view_offline_paused_done_and_error():
    v = view(online=False, state=state(paused=True, done=True, current_node=1, error="stalled"))
    v.synced, v.malformed = False, 2
    text = "\n".join(render_lines("r1", v))
    assert "(fetching the map)" in text and "malformed messages dropped: 2" in text
    assert "OFFLINE" in text and "PAUSED DONE" in text
    wrapped = "\n".join(render_lines("r1", view(state=state(theta=math.radians(-287)))))
    assert "theta 73 deg" in wrapped
    assert "at node 1" in text and "ERROR: stalled" in text


def test_terminal_view_before_anything_arrived():
    v = FakeView(online=False)
    lines = render_lines("r9", v)
    text = "\n".join(lines)
    assert "robot r9: OFFLINE" in text and "not received yet" in text
    assert "map: 0 nodes, 0 edges" in text and "recent events: none" in text


def test_terminal_view_says_when_the_map_is_behind_the_robot():
    v = view(state=state(map_nodes=5, map_edges=4, map_seq=9))
    text = "\n".join(render_lines("r1", v))
    assert "(robot has 5 nodes, 4 edges)" in text
    assert not map_complete(v)
    assert map_complete(view())
    assert not map_complete(FakeView())
    assert not map_complete(view(synced=False))
    assert not map_complete(view(epoch="older"))


def test_a_snapshot_waits_for_the_last_event_the_state_announces():
    # The view's events are seq 0..11 of epoch e1.
    assert events_caught_up(view(state=state(event_seq=11)))
    assert not events_caught_up(view(state=state(event_seq=12)))
    assert not events_caught_up(view(state=state(event_seq=3, epoch="e2")))
    assert events_caught_up(view(state=state(event_seq=0), events=[]))
    assert not events_caught_up(FakeView())


def test_snapshot_is_json_with_the_documented_keys():
    v = view(last_scan=ScanMsg("r1", 3.0, [1.0, None, float("nan")]))
    snap = json.loads(json.dumps(snapshot("r1", v), allow_nan=False))
    assert {"robot", "online", "state", "map", "events"} <= set(snap)
    assert snap["robot"] == "r1" and snap["online"] is True
    assert snap["state"]["behaviour"] == "trace_edge" and snap["state"]["goal_node"] == 3
    assert [n["id"] for n in snap["map"]["nodes"]] == [0, 1, 2]
    assert snap["map"]["nodes"][1]["ambiguous_with"] == [2]
    assert [(e["u"], e["v"]) for e in snap["map"]["edges"]] == [(0, 1), (1, 2)]
    assert len(snap["events"]) == 12 and snap["events"][-1]["text"] == "new meet point 11"
    assert snap["gaps"] == 1 and snap["seq"] == 7 and snap["synced"] is True
    # NaN is not JSON: a browser would reject the whole message.
    assert snap["scan"]["ranges_m"] == [1.0, None, None]


def test_snapshot_without_state():
    snap = snapshot("r1", FakeView(online=False))
    assert snap["state"] is None and snap["map"] == {"nodes": [], "edges": []}


class _StillClient:
    """A monitor client whose view never changes."""

    def __init__(self, v: FakeView) -> None:
        self._v = v

    def view(self) -> FakeView:
        return self._v


def test_a_one_shot_snapshot_says_when_the_event_history_is_short(capsys):
    # The state announces event 15; the history holds 0..11 and the rest never comes.
    args = argparse.Namespace(timeout=0.0, json=True)
    v = view(state=state(event_seq=15))
    assert _print_once(args, "r1", _StillClient(v), Notifier()) == 0
    out = capsys.readouterr()
    assert "announced event 15 but the history holds up to 11" in out.err
    assert len(json.loads(out.out)["events"]) == 12  # what arrived is still printed
    assert _print_once(args, "r1", _StillClient(view(state=state(event_seq=11))), Notifier()) == 0
    assert capsys.readouterr().err == ""
