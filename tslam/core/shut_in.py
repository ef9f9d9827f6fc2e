"""Before the robot stops: nodes of its piece of map read again, departures given up tried
again, each from another way in.

A meet point is read from where homing put the robot, and that depends on the way in: at a
place of two close meet points the robot homes onto the one it comes to first, and from
there the sweep may not hear every obstacle of the other. So a reading that closed the map
on itself, or a departure that could not be held from one point, may come right from
another side.
"""

from __future__ import annotations

from tslam.core.explorer_state import ExplorerState
from tslam.core.topomap import Step


class ShutIn(ExplorerState):
    """Going back to a node by another edge, once nothing else is left to do."""

    def _shut_in_port(self, node: int) -> int | None:
        """The departure to take on the way back to a node to read it again
        (``_recheck_path``) or to try a departure given up there (``_retry_path``); None
        to stop."""
        self.plan = self._recheck_path(node) or self._retry_path(node)
        return self.plan.pop(0).port if self.plan else None

    def _recheck_path(self, node: int) -> list[Step]:
        """Shut in (nothing left to explore in the piece of map the robot is in, departures
        left in pieces it cannot reach): the way to a meet node of this piece by an edge it
        has not been sent in by yet, the nearest such arrival first. The GVG is connected,
        so a node here was read without an edge it has; come at from another side, the
        robot may home onto its place's other point or hear the obstacle it missed, and the
        node is read again with the edge (``grow_place``). office:2 seed 1 stopped after
        1285 s with 10 of its 402 places mapped: a room's junction by the door, read from
        its lower point with the door's edge and a corner's as one, closed the room on
        itself. Each arrival is made once."""
        if not self.p.recheck_shut_in or not self.unexplored():
            return []
        found = self._arrival(node, None)
        if found is None:
            return []
        n, e, path = found
        self._note(
            f"nothing left to explore from here, {len(self.unexplored())} departure(s) left in "
            f"pieces out of reach: back to node {n} by edge {e} to read it again"
        )
        return path

    def _retry_path(self, node: int) -> list[Step]:
        """With nothing else left to explore: the way to a node with a departure given up
        (not held when tried, ``bounce_retries`` times over) by an edge it has not been sent
        in by yet, the nearest such arrival first; its departures given up get one more try.
        fig16 seed 68 came back from the indent's dead end each time, homed onto the
        indent's weak meet point, and leaving from there for the corridor south it went into
        the dead end again: it called exploration complete with two of the three places."""
        if not self.p.retry_given_up:
            return []
        given_up = self._given_up()
        if not given_up:
            return []
        found = self._arrival(node, {n for n, _ in given_up})
        if found is None:
            return []
        n, e, path = found
        ports = sorted(p for m, p in given_up if m == n)
        for p in ports:
            self.frozen.discard((n, p))
            self.bounces[(n, p)] = self.p.bounce_retries
        self._note(
            f"departure(s) {', '.join(map(str, ports))} of node {n} given up: back to it by "
            f"edge {e} to try again"
        )
        return path

    def _arrival(self, node: int, among: set[int] | None) -> tuple[int, int, list[Step]] | None:
        """The nearest arrival from ``node`` at a meet node (of ``among``, if given) by an
        edge the robot has not been sent back in by: that node, the edge, and the way."""
        dist = self._distances(node)
        best: tuple[float, int, int, int] | None = None
        for e in self.map.edges():
            for n, q in ((e.u, e.port_u), (e.v, e.port_v)):
                w = e.other_end(n, q)[0]
                if self.map.node(n).kind != "meet" or (n, q) in self.rechecked or w not in dist:
                    continue
                if among is not None and n not in among:
                    continue
                if best is None or (dist[w] + e.length_m, e.id, n, q) < best:
                    best = (dist[w] + e.length_m, e.id, n, q)
        if best is None:
            return None
        _, e, n, q = best
        w, p = self.map.edge(e).other_end(n, q)
        self.rechecked.add((n, q))
        path = self._path(node, w) if w != node else []
        return n, e, [*path, Step(w, p, e, n, q)]
