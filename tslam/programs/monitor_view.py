"""What ``tslam monitor`` shows: a link ``MonitorView`` turned into JSON or terminal text.

Pure functions of a view (anything with the attributes of ``tslam.link.client.MonitorView``),
so the terminal and the web page show the same thing and are tested without a network.
"""

from __future__ import annotations

import math
from typing import Any

import msgspec

#: How many recent events the terminal shows; the web page and --json get all the view holds.
TERMINAL_EVENTS = 8


def _plain(obj: Any) -> Any:
    """Builtins (dict, list, str, numbers, None) for a msgspec Struct or a dataclass."""
    return msgspec.to_builtins(obj)


def _finite(x: Any) -> Any:
    # JSON has no NaN or infinity (the browser's JSON.parse rejects them): send null.
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def _clean(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_clean(v) for v in obj]
    return _finite(obj)


def snapshot(robot: str, view: Any) -> dict[str, Any]:
    """One JSON-ready object: robot, online, state, map {nodes, edges}, events, and bookkeeping.

    Nodes and edges are sorted by id so two snapshots of the same map compare equal.
    """
    nodes = [_plain(n) for _, n in sorted(view.nodes.items())]
    edges = [_plain(e) for _, e in sorted(view.edges.items())]
    state = view.state
    scan = getattr(view, "last_scan", None)
    return _clean(
        {
            "robot": robot,
            "online": bool(view.online),
            "state": None if state is None else _plain(state),
            "map": {"nodes": nodes, "edges": edges},
            "events": [_plain(e) for e in view.events],
            "epoch": getattr(view, "epoch", None),
            "seq": getattr(view, "seq", None),
            "synced": getattr(view, "synced", None),
            "gaps": getattr(view, "gaps", 0),
            "scan": None if scan is None else _plain(scan),
        }
    )


def map_complete(view: Any) -> bool:
    """True once the view holds the map the robot's state announces (snapshot in, no holes)."""
    state = view.state
    if state is None or not getattr(view, "synced", True):
        return False
    return view.epoch == state.epoch and view.seq >= state.map_seq


def events_caught_up(view: Any) -> bool:
    """True once the view holds the last event the robot's state announces, if it announces one."""
    state = view.state
    if state is None or state.event_seq == 0:
        return state is not None
    return any(e.epoch == state.epoch and e.seq >= state.event_seq for e in view.events)


def _heading_deg(theta: float) -> float:
    # Odometry accumulates whole turns (-287 deg); people read headings in (-180, 180].
    return math.degrees(math.remainder(theta, math.tau)) if math.isfinite(theta) else theta


def _fmt_id(x: int | None, what: str) -> str:
    return "-" if x is None else f"{what} {x}"


def _flags(state: Any) -> str:
    flags = [f for f, on in (("PAUSED", state.paused), ("DONE", state.done)) if on]
    return " ".join(flags) if flags else "running"


def render_lines(robot: str, view: Any, *, events: int = TERMINAL_EVENTS) -> list[str]:
    """The terminal view as lines of plain text (no colour, no control characters)."""
    state = view.state
    lines = [f"robot {robot}: {'ONLINE' if view.online else 'OFFLINE'}"]
    if state is None:
        lines.append("  state: not received yet")
    else:
        lines += [
            f"  behaviour {state.behaviour}   mode {state.mode}   {_flags(state)}",
            f"  at {_fmt_id(state.current_node, 'node')}   on {_fmt_id(state.current_edge, 'edge')}"
            f"   goal {_fmt_id(state.goal_node, 'node')}",
            f"  pose (dead-reckoned) x {state.x:.2f} m  y {state.y:.2f} m"
            f"  theta {_heading_deg(state.theta):.0f} deg",
            "  hypotheses: " + (", ".join(state.hypotheses) if state.hypotheses else "-"),
        ]
        if state.error:
            lines.append(f"  ERROR: {state.error}")
    n_nodes, n_edges = len(view.nodes), len(view.edges)
    unexplored = sum(1 for n in view.nodes.values() if n.unexplored > 0)
    ambiguous = sum(1 for n in view.nodes.values() if n.ambiguous_with)
    map_line = f"  map: {n_nodes} nodes, {n_edges} edges, {unexplored} with unexplored exits"
    if ambiguous:
        map_line += f", {ambiguous} ambiguous"
    if state is not None and (state.map_nodes, state.map_edges) != (n_nodes, n_edges):
        map_line += f" (robot has {state.map_nodes} nodes, {state.map_edges} edges)"
    lines.append(map_line)
    sync = "" if getattr(view, "synced", True) else "  (fetching the map)"
    lines.append(f"  epoch {view.epoch or '-'}  seq {view.seq}  gaps repaired {view.gaps}{sync}")
    if getattr(view, "malformed", 0):
        lines.append(f"  malformed messages dropped: {view.malformed}")
    recent = list(view.events)[-events:] if events > 0 else []
    lines.append("  recent events:" if recent else "  recent events: none")
    for ev in recent:
        lines.append(f"    [{ev.seq}] t={ev.stamp_s:.1f} {ev.kind}: {ev.text}")
    return lines


#: Home the cursor and clear the screen: redraw in place without curses.
CLEAR = "\x1b[H\x1b[2J"
