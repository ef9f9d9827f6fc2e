"""Localization's decisions: merge a proven hypothesis, record an ambiguity no move can settle,
pick the move that separates the rest, place the fragments left unattached.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import replace

import networkx as nx

from tslam.core.explorer_state import MAX_CUTS
from tslam.core.localize import Hypotheses, Hypothesis, separating_port
from tslam.core.merge_grow import MAX_GROWS, MergeGrow, current_grows
from tslam.core.placements import Placement, other_placements, placements
from tslam.core.portmap import PortMap, turned_onto
from tslam.core.topomap import DegreeConflictError, EdgeConflictError, MapError, TopoMap
from tslam.core.tracer import MeetPointReached
from tslam.core.zipmerge import implies, merge_mapping

# Folding tries each proven hypothesis's merge on a copy of the map. A copy made after losing
# the way is tested by a few; fig15's aisles are fitted by dozens at once, none of which
# implies the rest, and trying them all at every arrival took seconds per arrival.
FOLD_MAX = 4
# Confirmations one hypothesis needs over its rivals to go ahead of them: a loop over the
# placements or a placement over the loops, and a lead with no move here to test the rest.
LOOP_MARGIN = 2


def support(h: Hypothesis) -> float:
    """A hypothesis's evidence: its confirmations, each dead end half of one."""
    return h.confirmed + 0.5 * h.dead_ends


class Resolving(MergeGrow):
    """Testing, merging and giving up on localization hypotheses."""

    def _age(self, hyps: list[Hypothesis], spoke: set[int]) -> list[Hypothesis]:
        out = []
        for h in hyps:
            h.silent_arrivals = 0 if id(h) in spoke else h.silent_arrivals + 1
            if h.silent_arrivals <= self.p.silent_life:
                out.append(h)
        return out

    def _resolve(self, node: int) -> dict[int, tuple[int, int]]:
        """Merge a proven hypothesis; record an ambiguity no move here can settle. Returns
        the nodes a merge renamed: old id -> (id, port shift)."""
        if not self.hyps.live:
            self.hyps.clear()
            return {}
        # A hypothesis no prediction has tested yet is in the same position as "all of it is
        # new": possible, unrefuted, unsupported. Only tested hypotheses compete.
        tested = self._tested()
        evidence = self.p.merge_evidence
        if len(tested) > 1:
            # A hypothesis whose merge would be refused below for its heading is no rival
            # either, as in ``_other_placements``: it only kept the right one waiting, while
            # the fragment grew round a loop onto itself (fig12 seed 5). But the one left
            # is not the more likely for it: where places repeat, the fragment may be new
            # and both wrong (fig15 without drift, seed 2: a column of crossings merged
            # onto the one beside it, 3.5 m away). It needs one confirmation more.
            plausible = [h for h in tested if not self._heading_misfits(h)]
            # But a rival with as much support is set aside only if it is turned well beyond
            # the bound: under severe drift the heading drifts to the bound and past it. At
            # fig15 (severe, seed 2) a placement true but for its newest node, turned 60
            # degrees where 60 were allowed, was set aside, and one a block over, with the
            # same six confirmations, merged nine places falsely.
            best = max((h.confirmed for h in plausible), default=0)
            kept = [
                h
                for h in tested
                if any(h is q for q in plausible)
                or (h.confirmed >= best and not self._turned_well_beyond(h))
            ]
            if plausible and len(plausible) < len(tested):
                evidence += 1
            tested = kept if plausible else tested
        aside: list[Hypothesis] = []
        held_up = False
        if self.p.close_fragment:
            tested, aside, held_up = self._loops_apart(tested, evidence)
        if 1 < len(tested) <= FOLD_MAX and self.p.fold_implied:
            tested = self._fold_implied(tested)
        if len(tested) > 1 and not held_up and self.p.merge_compatible:
            tested, aside = self._lead_apart(tested, aside)
        if len(tested) == 1 and tested[0].proven(evidence, self.p.weigh_crowd) and not held_up:
            h = tested[0]
            far = self._drifted_apart(h)
            if far is not None:
                x, c, gap, driven = far
                self.hyps.live.remove(h)
                self._note(
                    f"node {node}: a place that fits the evidence puts node {x} on node {c}, "
                    f"{gap:.1f} m apart by dead reckoning after {driven:.0f} m: not merged"
                )
                return self._resolve(node)
            turned = self._heading_misfits(h)
            if turned:
                # Proven by topology, refuted by dead reckoning: a mirror image (fig15). Only
                # here, at the merge: a hypothesis on its way to proof is left to predictions.
                self.hyps.live.remove(h)
                self._note(
                    f"node {node}: a place that fits the evidence is turned further than dead "
                    f"reckoning drifts (nodes {', '.join(map(str, turned))}): not merged"
                )
                return self._resolve(node)
            search = self._other_placements(h)
            if search is None:
                self._note(f"node {node}: too many places fit the evidence to check: not merged")
                self._abandon_hypotheses()
                return {}
            rivals, own_fits = search
            if not rivals and own_fits:
                untraced = [] if h.resumed else self._untraced_rivals(h)
                if untraced == []:
                    return self._merge(h, keep=aside)
                # Not rivals to test: they inherit no evidence (their edges are untraced),
                # and one merged when ``h`` fell would be a guess. ``h`` waits for them to go.
                if id(h) not in self._held:
                    self._held.add(id(h))
                    what = "too many places" if untraced is None else f"{len(untraced)} place(s)"
                    self._note(
                        f"node {node}: the evidence also fits {what} whose edges there are "
                        "untraced: not merged"
                    )
                return {}
            # The evidence fits elsewhere as well: those places are hypotheses too, with the
            # same support, for the next moves to separate, or the ambiguity to record.
            for placement in rivals:
                self.hyps.live.append(
                    replace(h, mapping=dict(placement), silent_arrivals=0, cuts=set(h.cuts))
                )
            if rivals:
                self._note(
                    f"node {node}: the evidence also fits {len(rivals)} other place(s): "
                    + "; ".join(
                        ", ".join(f"{x}={c}" for x, (c, _) in sorted(pl.items())) for pl in rivals
                    )
                )
            tested = self._tested()
        if len(tested) == 1 and tested[0].resumed:
            # Only a move that tests it is worth waiting for. Rivals no prediction has tested
            # are unsupported, and a stored map of a few nodes can never confirm its
            # placement twice: waiting on moves that test only them, the robot resumed in
            # fig12 (seed 1, killed after one edge) let its placement age out and went round
            # the room for hours, mapping it anew each time (tests/test_explorer_resume.py).
            tests_it = Hypotheses(self.hyps.fragment, [tested[0]])
            if separating_port(self.map, tests_it, node) is not None:
                return {}
            return self._merge(tested[0])
        too_big = 0 < self.p.fragment_max <= len(self.hyps.fragment)
        if len(tested) > 1 and too_big:
            self._note(
                f"node {node}: {len(self.hyps.fragment)} nodes mapped since the hypotheses "
                f"began and no move has told {len(tested)} placements apart"
            )
        elif node in self.hyps.fragment and self._separating_port(node) is not None:
            return {}
        if len(tested) == 1:
            # Not proven, and nothing to test from here: keep it open for a later edge to
            # test; it ages out if none does. Never merge on a guess.
            return {}
        if len(tested) > 1 and self.p.lead_waits and not too_big and self._clear_lead(tested):
            return {}
        self._abandon_hypotheses()
        return {}

    def _clear_lead(self, tested: list[Hypothesis]) -> bool:
        """Whether one hypothesis leads every rival by ``LOOP_MARGIN`` confirmations. Then
        no ambiguity is recorded for want of a move here: the rivals age out unless a later
        edge tests them, as a lone unproven hypothesis would."""
        ranked = sorted(tested, key=support, reverse=True)
        lead = ranked[0]
        return lead.confirmed >= 1 and all(
            support(lead) >= support(r) + LOOP_MARGIN for r in ranked[1:]
        )

    def _loops_apart(
        self, tested: list[Hypothesis], evidence: int
    ) -> tuple[list[Hypothesis], list[Hypothesis], bool]:
        """The tested hypotheses that compete, those set aside to keep open after a merge,
        and whether a rival of the other kind holds any merge up. Hypotheses that close the
        fragment onto itself (the robot came round to where it had been since it left the
        map) and hypotheses that place it on old nodes are rivals, but evidence tells them
        apart as it does any: the proven one of either kind goes ahead of the other kind
        when it has ``LOOP_MARGIN`` confirmations more than each of them. A loop merged
        keeps the placements open (they may yet be true, the fragment one place fewer); a
        placement merged ends the loops, as any merge ends the fragment. Restarted after
        fig12's first edge (seed 2), the placement on the stored pair refuted and each
        lap's new nodes bringing new look-alikes among the stored two, the robot went round
        the room for ever; now the second lap closes onto the first."""
        loops: list[Hypothesis] = []
        others: list[Hypothesis] = []
        for h in tested:
            (loops if self._closes_on_itself(h) else others).append(h)
        if 1 < len(loops) <= 2 * FOLD_MAX and self.p.fold_implied:
            loops = self._fold_implied(loops)  # each lap onto each before: one merge
        if not loops or not others:
            return loops or others, [], False
        if 1 < len(others) <= FOLD_MAX and self.p.fold_implied:
            others = self._fold_implied(others)
        weigh = self.p.weigh_crowd

        def ahead(lead: list[Hypothesis], rest: list[Hypothesis]) -> bool:
            if len(lead) != 1 or not lead[0].proven(evidence, weigh):
                return False
            return all(support(lead[0]) >= support(r) + LOOP_MARGIN for r in rest)

        if ahead(others, loops):
            return others, [], False
        if ahead(loops, others):
            return loops, others, False
        return others, [], True  # the placements, as if alone, for the ambiguity they make

    def _lead_apart(
        self, tested: list[Hypothesis], aside: list[Hypothesis]
    ) -> tuple[list[Hypothesis], list[Hypothesis]]:
        """The best-supported proven hypothesis alone, the rest set aside to keep open, if
        every one of them is compatible with it (``_compatible``); else as they were. In
        fig14 (seed 4 at drift paper, 6000 s) the robot went round one loop of the lab three
        times: a placement proven ten times over put the second lap on the mapped places and
        the third on the first, and a rival proven five times put the third lap on the
        mapped places. Both are true at once, yet as rivals they left 30 nodes unmerged, and
        each lap after brought one look-alike more."""
        weigh = self.p.weigh_crowd
        ranked = sorted(tested, key=support, reverse=True)
        lead = ranked[0]
        if support(ranked[1]) >= support(lead) or not lead.proven(self.p.merge_evidence, weigh):
            return tested, aside
        if not all(self._compatible(lead, o) for o in ranked[1:]):
            return tested, aside
        return [lead], [*aside, *ranked[1:]]

    def _compatible(self, h: Hypothesis, o: Hypothesis) -> bool:
        """Whether ``o`` says nothing against ``h``: each node ``o`` places, ``h`` does not
        place, places as ``o`` does, or places on another node of the fragment, so that
        after ``h``'s merge ``o`` is about the nodes that are left."""
        for x, image in o.mapping.items():
            mine = h.mapping.get(x)
            # Through the nodes of the fragment ``h`` closes onto and places in turn: to
            # where ``h`` puts ``x`` in the end.
            seen = {x}
            while mine is not None and mine[0] in h.mapping and mine[0] not in seen:
                seen.add(mine[0])
                mine = h.mapping[mine[0]]
            if mine is None or mine == image:
                continue
            if len(seen) > 1 and mine[0] == image[0]:
                continue  # the same place, its ports turned through a lap: the map judges
            if mine[0] in self.hyps.fragment and mine[0] not in h.mapping:
                continue
            return False
        return True

    def _closes_on_itself(self, h: Hypothesis) -> bool:
        return all(c in self.hyps.fragment for c, _ in h.mapping.values())

    def _renamed_hypothesis(
        self, h: Hypothesis, renamed: dict[int, tuple[int, int]]
    ) -> Hypothesis | None:
        """``h`` in the map after a merge renamed nodes; None if it no longer says anything
        the map can hold (two of its nodes became one, or one became its old node)."""
        mapping: dict[int, tuple[int, int]] = {}
        for x, (c, k) in h.mapping.items():
            rx, sx = renamed.get(x, (x, 0))
            rc, sc = renamed.get(c, (c, 0))
            if rx == rc or rx in mapping or not (self.map.has_node(rx) and self.map.has_node(rc)):
                return None
            mapping[rx] = (rc, (k - sx + sc) % self.map.node(rc).degree)
        images = [c for c, _ in mapping.values()]
        if len(set(images)) < len(images) or any(not self.map.has_edge(e) for e in h.cuts):
            return None
        return replace(h, mapping=mapping, cuts=set(h.cuts))

    def _tested(self) -> list[Hypothesis]:
        """The hypotheses that compete for a merge: those some prediction has tested."""
        return [h for h in self._contenders() if h.tested]

    def _contenders(self) -> list[Hypothesis]:
        """The live hypotheses, but for those set aside. One that says an edge went past a
        junction starts less likely than one that needs no such slip, so it contends only
        once it has more confirmations than any of those; until then it waits: it neither
        blocks a merge nor makes an ambiguity, and no move is made to test it (in fig14's
        lab, a dozen junctions alike, such tests sent the robot round and round)."""
        live = self.hyps.live
        plain = [h for h in live if not h.cuts]
        if not plain:
            return list(live)
        best = max(h.confirmed for h in plain)
        return plain + [h for h in live if h.cuts and h.confirmed > best]

    def _separating_port(self, node: int) -> int | None:
        """The move that separates the contenders fastest. A loop of the fragment onto
        itself is tested by the moves made anyway, as a slip is (``_contenders``): moves
        made to test loops sent the robot round fig14's lab (7 of its 9 default bench runs
        held every place and edge at the end without loops, 4 with those moves)."""
        testable = [h for h in self._contenders() if not self._closes_on_itself(h)]
        return separating_port(self.map, Hypotheses(self.hyps.fragment, testable), node)

    def _untraced_rivals(self, h: Hypothesis) -> list[Placement] | None:
        """With ``open_rivals``, the placements of ``h``'s fragment that fit the map only
        with some of its edges between two untraced departures; None if the search ran out
        of steps (it ruled none out)."""
        if not self.p.open_rivals:
            return []
        search = self._other_placements(h, open_edges=True)
        return search[0] if search is not None else None

    def _other_placements(
        self, h: Hypothesis, open_edges: bool = False
    ) -> tuple[list[Placement], bool] | None:
        """``other_placements`` of ``h``'s fragment, in the map as ``h``'s claims about old
        nodes (a lead-in: an old node is a copy of another) would make it: there the copies
        are one place, and a placement on a copy is no rival. A fragment that closes onto
        itself round a loop maps each lap onto the one before: the first lap is placed,
        onto the nodes the robot first found (the laps after it say the same again)."""
        if any(c in h.mapping for c, _ in h.mapping.values()):
            h = replace(h, mapping={x: ck for x, ck in h.mapping.items() if ck[0] not in h.mapping})
        view = self._view(h)
        old = {x: ck for x, ck in h.mapping.items() if x not in self.hyps.fragment}
        if not old:
            return other_placements(
                view,
                h,
                self.p.tol,
                fits=self._heading_fits,
                open_edges=open_edges,
                dead_end_depth=self.p.dead_end_depth,
            )
        merged = self._merged_copy(old, view)
        if merged is None:
            return [], False
        trial, renamed = merged
        mapping = {}
        for x, (c, k) in h.mapping.items():
            if x in old or renamed.get(x, (x, 0))[0] != x:
                continue  # an old node, or made one with one by the claims themselves
            rc, sc = renamed.get(c, (c, 0))
            mapping[x] = (rc, (k + sc) % trial.node(rc).degree)
        return other_placements(
            trial,
            replace(h, mapping=mapping),
            self.p.tol,
            fits=self._heading_fits,
            open_edges=open_edges,
            dead_end_depth=self.p.dead_end_depth,
        )

    def _fold_implied(self, tested: list[Hypothesis]) -> list[Hypothesis]:
        """The one proven hypothesis whose merge makes every other tested one true as well,
        if there is one (``tslam.core.zipmerge``); else all of them, still rivals."""
        proven = [h for h in tested if h.proven(self.p.merge_evidence, self.p.weigh_crowd)]
        for h in sorted(proven, key=lambda h: -(h.confirmed + 0.5 * h.dead_ends)):
            merged = self._merged_copy(h.mapping, self._view(h))
            if merged is not None and all(
                implies(*merged, o.mapping) for o in tested if o is not h
            ):
                return [h]
        return tested

    def _merged_copy(
        self, mapping: dict[int, tuple[int, int]], base: TopoMap | None = None
    ) -> tuple[TopoMap, dict[int, tuple[int, int]]] | None:
        """A copy of the map (or of ``base``) with ``mapping`` merged, and the renames; None
        if the map refuses the merge."""
        trial = (self.map if base is None else base).copy()
        try:
            return trial, merge_mapping(trial, mapping, self._likeness())
        except MapError:
            return None

    def _stand(
        self, ev: MeetPointReached, node: int, pm: PortMap, renamed: dict[int, tuple[int, int]]
    ) -> tuple[int, PortMap]:
        """The robot stands at ``node``, as a merge may have renamed it."""
        if node in renamed:
            node, shift = renamed[node]
            pm = pm.renamed(shift)
        n = self.map.node(node)
        if len(pm.index) != n.degree:
            # The merge grew the node (``_grow_merged``): to this very reading, read as its
            # predicted place with an edge fewer (fig14 seed 15, in a variant of the
            # arbiter), or to a reading with an edge more taken here before (fig14 seed 30
            # with the switch ``vertex``). The port map was the smaller place's, a port
            # short, and a robot sent out by the new port met an index out of range.
            pm = turned_onto(n.departures_rad, ev.departures_rad, ev.arrival_index)
        self.here = node
        self._last_visit = (node, ev.departures_rad, pm, ev.x_m, ev.y_m)
        if len(set(pm.index)) == len(pm.index) == ev.degree:
            self.port_bearings[node] = tuple(ev.departures_rad[i] for i in pm.index)
        self._at = (ev, node, pm)
        return node, pm

    def _place_orphans(self, here: int) -> dict[int, tuple[int, int]]:
        """Merge the pieces of map the robot cannot reach that fit one place only.

        A fragment begun when the robot was lost, whose hypotheses went when it was lost
        again, is left unattached: no path leads to it, so its departures are never explored
        and the map is never complete. It holds what the robot traced there, though, and that
        is evidence like any hypothesis's: placed on the rest of the map everywhere it fits
        (``placements``, the test every merge passes), it is merged if it fits exactly one
        place and holds the edges a proven hypothesis needs (each edge between two of its
        meet points a confirmation, each dead end half of one). Returns the merge's renames
        (empty if nothing merged): a merge may rename the node the robot stands at too.
        """
        for comp in sorted(nx.connected_components(self.map.graph), key=min):
            if here in comp or not any(None in self.map.node(n).ports for n in comp):
                continue
            nodes = sorted(comp)
            kinds = [{self.map.node(e.u).kind, self.map.node(e.v).kind} for e in self.map.edges()
                     if e.u in comp]  # fmt: skip
            h = Hypothesis({}, kinds.count({"meet"}), len(kinds) - kinds.count({"meet"}))
            # A piece of the stored map: the robot was restarted in that building, so the one
            # place it fits in a map with nothing left to explore is where it is, as for a
            # resumed hypothesis (a stored map of one edge can never confirm twice).
            prior = self.p.place_stored and comp <= self.stored
            evidence = self.p.merge_evidence - (1 if prior else 0)
            if not h.proven(evidence, self.p.weigh_crowd):
                continue
            found = placements(
                self.map,
                nodes,
                self.p.tol,
                2,
                fits=self._heading_fits,
                dead_end_depth=self.p.dead_end_depth,
            )
            if found is None or len(found) != 1:
                continue
            h.mapping = dict(found[0])
            if self._drifted_apart(h) is not None:
                continue
            self._note(f"nodes {', '.join(map(str, nodes))}, out of reach, fit one place only")
            renamed = self._merge(h)
            if renamed:
                return renamed  # the components have changed: the next arrival looks again
        if self.p.drop_detached:
            self._drop_detached(here)
        return {}

    def _drop_detached(self, here: int) -> None:
        """Once the piece of map the robot is in has nothing left to explore, the pieces it
        cannot reach are copies of its places: the GVG is connected, so a piece whose every
        departure was traced holds every place the robot has been. They go from the map,
        but what a live hypothesis names and what a stored map held. fig16 (seeds 12, 25,
        36, 40 and 44) finished so with a junction first read at its weak point with three
        edges, unattached, its departures unexplored for good; fig1 seed 41 with a node
        whose only edge had gone past a junction, a look and four departures. Each piece
        that fits one place only was merged there first (``_place_orphans``), and a piece
        with a junction read more fully than its look-alikes here stays
        (``_read_as_fully``)."""
        own = nx.node_connected_component(self.map.graph, here)
        if any(None in self.map.node(n).ports for n in own):
            return
        named = set().union(*(h.named for h in self.hyps.live))
        for comp in sorted(nx.connected_components(self.map.graph), key=min):
            if comp & (own | named | self.stored):
                continue  # a stored map is an earlier run's: kept, whatever it duplicates
            if not all(self._read_as_fully(n, own) for n in comp):
                continue
            for n in sorted(comp):
                self.map.remove_node(n)
                self.hyps.fragment.discard(n)
            self._note(
                f"nodes {', '.join(map(str, sorted(comp)))}, out of reach of a map with nothing "
                "left to explore: copies of its places, dropped"
            )

    def _read_as_fully(self, n: int, piece: set[int]) -> bool:
        """Whether ``piece`` holds a meet point like ``n`` (its clearance) with as many
        edges or more; any boundary point is like another. A piece out of reach holding a
        junction read with an edge more than anything like it in the robot's finished piece
        holds what that piece lacks: fig16 seed 20 finished with its corridor place read
        with three edges, and the one piece out of reach held it with four, both dead ends
        of the indent. Angles cannot tell more: read with three edges, that place shows one
        dead end or the other at the same bearing (seed 75)."""
        x = self.map.node(n)
        if x.kind != "meet":
            return True
        tol = self.p.tol.clearance_m
        return any(
            (m := self.map.node(c)).kind == "meet"
            and m.degree >= x.degree
            and abs(m.clearance_m - x.clearance_m) <= tol + self.span.get(c, 0.0)
            for c in piece
        )

    def _abandon_hypotheses(self, lost: bool = False) -> None:
        """Nothing can tell the fragment from its look-alikes: keep its nodes as new places,
        say so in the map, and do not re-explore through them what the look-alikes already
        explored (that would unroll a symmetric building for ever).

        ``lost``: the robot no longer knows where it is, so the hypotheses can make no more
        predictions. The map still says where the evidence so far fits two places or more,
        but nothing showed that no move could tell them apart (there was simply no move left
        to make): no departure is frozen, and a node that fits one place only is not called
        ambiguous. A frozen departure is never explored, even once its piece of map is
        merged back (tests/test_explorer_graph.py)."""
        # Only hypotheses some prediction has confirmed count: a look-alike whose departures
        # are all unexplored could not be tested yet, which is no ambiguity.
        tested = self._tested()
        self.doubtful |= self.hyps.fragment
        for x in sorted(self.hyps.fragment):
            if not self.map.has_node(x):
                continue
            others = {h.mapping[x][0] for h in tested if x in h.mapping}
            if len(others) < (2 if lost else 1):
                continue
            self.map.set_ambiguous(x, others)
            for p, e in enumerate(self.map.node(x).ports):
                if not lost and e is None and all(
                    (img := h.image_port(self.map, x, p)) is not None
                    and self.map.node(img[0]).ports[img[1]] is not None
                    for h in tested
                    if x in h.mapping
                ):
                    self.frozen.add((x, p))
            self._note(f"node {x} is ambiguous with {sorted(others)}: not merged")
        self.hyps.clear()

    def _view(self, h: Hypothesis) -> TopoMap:
        """The map as ``h`` says it is: without the edges it found went past a junction,
        and with the nodes its merge reads with an edge more so (``Hypothesis.grows``)."""
        cuts = sorted(e for e in h.cuts if self.map.has_edge(e))
        if not cuts and not h.grows:
            return self.map
        view = self.map.copy()
        for n, deps, clearance, carry in current_grows(view, h):
            view.reread(n, deps, clearance, carry)
        for e in cuts:
            view.remove_edge(e)
        return view

    def _cut_conflicts(self, h: Hypothesis, keep: Sequence[Hypothesis] = ()) -> TopoMap | None:
        """The map ``h`` merges into: without the edges it says went past a junction and,
        with ``cut_past``, without any edge its merge would make one with a shorter edge
        between two meet points (the first tracing went past one: fig13's meet point 0,
        whose third wall the ring rarely resolves, joined meet points 1 and 2 by one 4.3 m
        edge). None, with a note, if the map refuses the merge. It is tried on a copy, so a
        refused merge leaves the map as it was (merging the real one could stop halfway).
        With ``merge_grows``, two readings of one place an edge apart in degree are read
        as the one with more edges (merge_grow.py)."""
        h.grows = {}
        while True:
            view = self._view(h)
            try:
                merge_mapping(view.copy(), h.mapping, self._likeness())
                return view
            except EdgeConflictError as exc:
                e = self._went_past(view, exc.edges) if self.p.cut_past else None
                if e is None or len(h.cuts) >= MAX_CUTS:
                    self._note(f"merge refused by the map ({exc}): keeping both")
                    return None
                h.cuts.add(e)
            except DegreeConflictError as exc:
                grow = None
                if self.p.merge_grows and len(h.grows) < MAX_GROWS:
                    grow = self._grow(view, exc.ends, h, keep)
                if grow is None or grow[0] in h.grows:
                    self._note(f"merge refused by the map ({exc}): keeping both")
                    return None
                h.grows[grow[0]] = grow[1:]
            except MapError as exc:
                self._note(f"merge refused by the map ({exc}): keeping both")
                return None

    def _went_past(self, view: TopoMap, edges: tuple[int, int]) -> int | None:
        """Of two edges a merge makes one, the longer, if it is longer than the length
        tolerance allows and the shorter joins two meet points: it went past a junction."""
        a, b = (view.edge(e) for e in edges)
        long, short = (a, b) if a.length_m > b.length_m else (b, a)
        tol = self._tol()
        if long.length_m - short.length_m <= tol.length_slack(long.length_m):
            return None
        if any(view.node(n).kind != "meet" for n in (short.u, short.v)):
            return None
        return long.id

    def _merge(self, h: Hypothesis, keep: Sequence[Hypothesis] = ()) -> dict[int, tuple[int, int]]:
        """Merge ``h``; ``keep``: hypotheses the merge does not settle, kept open."""
        view = self._cut_conflicts(h, keep)
        if view is None:
            self._abandon_hypotheses()
            return {}
        loop = self._false_loop(h, view)
        if loop is not None:
            e, gap = loop
            self._note(
                f"merge refused: it makes edge {e} a loop, but dead reckoning put its ends "
                f"{gap:.1f} m apart: keeping both"
            )
            self._abandon_hypotheses()
            return {}
        self._apply_grows(h)
        if any(self.map.has_edge(e) for e in h.cuts):
            self._remove_cuts(h)
        misfit = self._zipped_misfit(h.mapping, self._likeness())
        if misfit is not None:
            self._note(
                f"merge refused: it makes node {misfit[0]} one with node {misfit[1]}, "
                f"{misfit[2]}: keeping both"
            )
            self._abandon_hypotheses()
            return {}
        try:
            renamed, merged = self._merge_recorded(h.mapping, self._likeness())
        except MapError as exc:
            self._note(f"merge refused by the map ({exc}): keeping both")
            self._abandon_hypotheses()
            return {}
        self._note(
            "loop closed: "
            + ", ".join(f"{d}={r}" for d, r, _, _ in merged.pairs)
            + f"; {self._size()}"
        )
        self._apply_renames(renamed)
        fragment = {renamed.get(x, (x, 0))[0] for x in self.hyps.fragment}
        # The nodes merged onto old places leave the fragment (a loop's images were in it).
        old = {c for c, _ in h.mapping.values()} - self.hyps.fragment
        fragment -= {renamed.get(c, (c, 0))[0] for c in old}
        if self.p.keep_apart:
            keep = [*keep, *self._apart_from(h, keep)]
        self.hyps.clear()
        for o in keep:
            kept = self._renamed_hypothesis(o, renamed)
            if kept is not None:
                self.hyps.live.append(kept)
        if self.hyps.live:
            self.hyps.fragment = {x for x in fragment if self.map.has_node(x)}
        self._grow_merged(renamed)
        return renamed

    def _apart_from(self, h: Hypothesis, keep: Sequence[Hypothesis]) -> list[Hypothesis]:
        """The tested hypotheses about other nodes of the fragment than ``h``'s, onto other
        old nodes: merging ``h`` neither proves nor refutes them, and dropped with it their
        evidence would go and their nodes stay copies for good. (Made for a case that turned
        out to be an ageing one, ``Explorer._test_path``; kept as the sound thing to do, and
        not measured on its own.)"""
        mine = h.named
        return [
            o
            for o in self.hyps.live
            if o is not h
            and o.tested
            and all(o is not k for k in keep)
            and not o.named & mine
        ]

    def _remove_cuts(self, h: Hypothesis) -> None:
        """Take out the edges ``h`` says went past a junction. A node left with no edge at
        all (the first one the robot mapped, its only edge the one that went past) holds
        nothing but a look: the place is mapped elsewhere, and its departures lead nowhere
        the robot could go, so it goes too."""
        cuts = sorted(e for e in h.cuts if self.map.has_edge(e))
        ends = set()
        for e in cuts:
            edge = self.map.edge(e)
            ends |= {edge.u, edge.v}
            self.map.remove_edge(e)
            self.edge_gap.pop(e, None)
        self._note(f"edge(s) {', '.join(map(str, cuts))} went past a junction: removed")
        busy = {self.here, self.goal, None if self.leaving is None else self.leaving[0]}
        busy |= h.named
        for n in sorted(ends - busy):
            if self.map.has_node(n) and all(e is None for e in self.map.node(n).ports):
                self.map.remove_node(n)
                self.hyps.fragment.discard(n)
                self._note(f"node {n}, left with no edge, removed")

    def _false_loop(self, h: Hypothesis, view: TopoMap | None = None) -> tuple[int, float] | None:
        """An edge the merge of ``h`` would make a loop although dead reckoning, good over
        one edge, put its two ends apart; None if there is none. ``view``: the map ``h``
        merges into (``_view``)."""
        p = self.p
        view = self._view(h) if view is None else view
        far = {
            e: gap
            for e, gap in self.edge_gap.items()
            if view.has_edge(e) and gap > p.loop_gap_m + p.loop_gap_rel * view.edge(e).length_m
        }
        if not far:
            return None
        trial = copy.deepcopy(view)
        try:
            renamed = merge_mapping(trial, h.mapping, self._likeness())
        except MapError:
            return None  # the map refuses it anyway, and says why
        for e, gap in sorted(far.items()):
            ends = view.edge(e)
            if renamed.get(ends.u, (ends.u, 0))[0] == renamed.get(ends.v, (ends.v, 0))[0]:
                return e, gap
        return None

    def _renamed_port(
        self, renamed: dict[int, tuple[int, int]], x: tuple[int, int]
    ) -> tuple[int, int]:
        """(node, port) ``x`` after a merge's renames."""
        n, p = x
        if n not in renamed:
            return x
        r, shift = renamed[n]
        return r, (p + shift) % self.map.node(r).degree

    def _apply_renames(self, renamed: dict[int, tuple[int, int]]) -> None:
        if self.leaving is not None:
            self.leaving = self._renamed_port(renamed, self.leaving)
        self.frozen = {self._renamed_port(renamed, x) for x in self.frozen}
        # What was tried at a port goes with it: a departure given up before its node was
        # merged is still given up, and retried as such (shut_in.py).
        self.rechecked = {self._renamed_port(renamed, x) for x in self.rechecked}
        self.went_along_another = {self._renamed_port(renamed, x) for x in self.went_along_another}
        bounces: dict[tuple[int, int], int] = {}
        for x, k in self.bounces.items():
            y = self._renamed_port(renamed, x)
            bounces[y] = max(k, bounces.get(y, 0))
        self.bounces = bounces
        if self.goal in renamed:
            self.goal = renamed[self.goal][0]
        self.plan = []
        for n, (r, shift) in renamed.items():
            self.stored.discard(n)
            self.stands.rename(n, r)
            fix = self.fixes.pop(n, None)
            if fix is not None and (r not in self.fixes or fix[2] > self.fixes[r][2]):
                self.fixes[r] = fix
            old = self.port_bearings.pop(n, None)
            if old is not None and r not in self.port_bearings:
                n_ports = len(old)
                self.port_bearings[r] = tuple(old[(p - shift) % n_ports] for p in range(n_ports))
