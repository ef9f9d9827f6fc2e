"""Dead reckoning as a bound only: how far the heading or position can have drifted since an
old node was read, which rules out a look-alike turned too far (fig15's mirror images).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from tslam.core.explorer_state import ExplorerState, angdiff
from tslam.core.localize import Hypothesis
from tslam.core.topomap import Likeness, MapError, MergePlan
from tslam.core.zipmerge import merge_mapping


class HeadingBounds(ExplorerState):
    """Drift bounds on hypotheses."""

    def _heading_fits(self, x: int, c: int, k: int, margin_rad: float = 0.0) -> bool:
        """Whether node ``x`` can be old node ``c`` under rotation ``k`` as far as dead
        reckoning's heading goes: their departures, each in the odometry frame of its own
        reading, are turned no more than the drift between those readings allows (and
        ``margin_rad`` more)."""
        bx = self.born.get(x)
        if bx is None or not self.map.has_node(x) or self.map.node(x).kind != "meet":
            return True
        return self._turn_fits(self.map.node(x).departures_rad, bx, c, k, margin_rad)

    def _turn_fits(
        self, deps: tuple[float, ...], read_at_m: float, c: int, k: int, margin_rad: float = 0.0
    ) -> bool:
        """``_heading_fits`` for departures ``deps`` read at encoder distance ``read_at_m``:
        departure i is port ``(i + k) % degree`` of old node ``c``."""
        turn = self._turn(deps, c, k)
        if turn is None:
            return True
        return abs(turn[0]) <= self._heading_drift(abs(read_at_m - turn[1])) + margin_rad

    def _turn(self, deps: tuple[float, ...], c: int, k: int) -> tuple[float, float] | None:
        """How far departures ``deps`` are turned from old node ``c``'s under rotation ``k``,
        and the encoder distance ``c`` was read at; None if that says nothing (not a meet
        point, another degree, no reading)."""
        bc = self.born.get(c)
        if bc is None or not self.map.has_node(c):
            return None
        nc = self.map.node(c)
        if nc.kind != "meet" or len(deps) != nc.degree:
            return None
        deg = nc.degree
        turns = [deps[j] - nc.departures_rad[(j + k) % deg] for j in range(deg)]
        return math.atan2(sum(map(math.sin, turns)), sum(map(math.cos, turns))), bc

    def _drifted_apart(self, h: Hypothesis) -> tuple[int, int, float, float] | None:
        """The first pair ``h`` makes one place that dead reckoning put further apart than
        it drifts over the metres driven between the robot's last stands at them, or over
        the chain of fewest metres its stands join them by (``drift_chain``): (node, old
        node, the distance, those metres); None if there is none."""
        p = self.p
        for x, (c, _) in sorted(h.mapping.items()):
            fx, fc = self.fixes.get(x), self.fixes.get(c)
            if fx is None or fc is None:
                continue
            gap, driven = math.hypot(fx[0] - fc[0], fx[1] - fc[1]), abs(fx[2] - fc[2])
            if gap > p.drift_base_m + p.drift_rel * driven:
                return x, c, gap, driven
        if not p.drift_chain:
            return None
        chains = self.stands.chains(sorted((x, c) for x, (c, _) in h.mapping.items()))
        for (x, c), (gap, driven) in sorted(chains.items()):
            if gap > p.drift_base_m + p.drift_rel * driven:
                return x, c, gap, driven
        return None

    def _heading_misfits(self, h: Hypothesis) -> list[int]:
        """The nodes ``h`` maps turned further than dead reckoning drifts: from their old
        nodes, or, failing that, the first two turned apart from each other."""
        misfits = [x for x, (c, k) in sorted(h.mapping.items()) if not self._heading_fits(x, c, k)]
        return misfits or self._turned_apart(h)

    def _zipped_misfit(
        self, mapping: Mapping[int, tuple[int, int]], alike: Likeness
    ) -> tuple[int, int, str] | None:
        """The first pair of places that merging ``mapping`` makes one beyond the pairs it
        names (the merge zips along the edges they share) that dead reckoning rules out, as
        (node, node, why); None if there is none, or if the map refuses the merge (it says
        why when the merge is made).

        Ruled out: meet points turned from each other further than it drifts between their
        readings, by ``heading_base_rad`` more (``zip_turns``), or places it put further
        apart than it drifts over the metres between the robot's last stands at them
        (``zip_drift``, ``_drifted_apart``). fig13 seed 8 at drift paper (stop 62, with a
        sweep change not kept): a close pair's two readings, their ports matched one edge
        round, made the edges to its north and east neighbours one (4.05 m and 3.49 m,
        within the length's slack) and the neighbours one place, 5.2 m apart and turned 93
        degrees where 34 were allowed: a false merge. A port matched one round turns a
        neighbour by about a departure's spacing, but drift alone may pass the bound a
        little: under drift ``severe`` the pairs of one true merge were turned 19 to 43
        degrees where 41 were allowed (fig1 seed 14 at 1754 s), hence the margin."""
        if not (self.p.zip_turns or self.p.zip_drift):
            return None
        trial = self.map.copy()
        zipped: list[tuple[int, int, int]] = []

        def record(plan: MergePlan) -> None:
            zipped.extend((d, r, k) for d, (r, k) in plan.nodes.items() if d not in mapping)

        try:
            merge_mapping(trial, mapping, alike, record)
        except MapError:
            return None
        for d, r, k in sorted(zipped):
            if self.p.zip_turns and not self._heading_fits(d, r, k, self.p.heading_base_rad):
                return d, r, "turned further than dead reckoning drifts"
            far = self._drifted_apart(Hypothesis({d: (r, k)})) if self.p.zip_drift else None
            if far is not None:
                return d, r, f"{far[2]:.1f} m apart by dead reckoning after {far[3]:.0f} m"
        return None

    def _turned_well_beyond(self, h: Hypothesis) -> bool:
        """Whether some node ``h`` maps is turned from its old node further than dead
        reckoning drifts by ``heading_base_rad`` more: a mirror image, not drift past its
        bound (fig12 seed 5's rival, 60 degrees where 29 were allowed)."""
        margin = self.p.heading_base_rad
        return any(not self._heading_fits(x, c, k, margin) for x, (c, k) in h.mapping.items())

    def _turned_apart(self, h: Hypothesis) -> list[int]:
        """The first two meet points ``h`` maps whose turns from their old nodes differ by
        more than ``heading_pair_rad`` and the drift between their readings; else none."""
        turned = []  # node, turn, read at, old node read at
        for x, (c, k) in sorted(h.mapping.items()):
            bx = self.born.get(x)
            if bx is None or not self.map.has_node(x) or self.map.node(x).kind != "meet":
                continue
            turn = self._turn(self.map.node(x).departures_rad, c, k)
            if turn is not None:
                turned.append((x, turn[0], bx, turn[1]))
        p = self.p
        for i, (x, t, bx, bc) in enumerate(turned):
            for y, u, by, bd in turned[i + 1 :]:
                drift = p.heading_drift_rad_per_m * (abs(bx - by) + abs(bc - bd))
                if angdiff(t, u) > p.heading_pair_rad + drift:
                    return [x, y]
        return []
