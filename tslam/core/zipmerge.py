"""A hypothesis made true in the map: every fragment node merged into its old node.

Each merge zips together whatever the topology forces (``TopoMap.merge``), so one pair can
rename nodes a later pair names; the renames are followed. Done on a copy of the map, the
same zipping says what else a hypothesis claims. A robot that lost its way once maps places
again, and then two hypotheses about its fragment can both be right: one says the fragment
is the original places, the other that it is their copies. If merging the first makes the
copies the originals too, the second says nothing the first does not, and is no rival.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from tslam.core.topomap import Likeness, MergePlan, TopoMap

Renames = dict[int, tuple[int, int]]  # gone node -> (surviving node, shift: port j is j + s)


def merge_mapping(
    tmap: TopoMap,
    mapping: Mapping[int, tuple[int, int]],
    alike: Likeness,
    on_plan: Callable[[MergePlan], None] | None = None,
) -> Renames:
    """Merge each node x of ``mapping`` into its old node c (port j of x is port j + k of c),
    in order of x; raises ``MapError`` (the map then holds the merges before the failing one:
    use a copy to try). Returns every node that went, with where its ports went."""
    renamed: Renames = {}
    for x, (c, k) in sorted(mapping.items()):
        x2, s = renamed.get(x, (x, 0))
        c2, s2 = renamed.get(c, (c, 0))
        if x2 == c2 or not tmap.has_node(x2):
            continue
        # Port j of x is port (j + s) of x2; port (j + k) of c is port (j + k + s2) of c2:
        # so port i of x2 is port (i - s + k + s2) of c2.
        rot = (k + s2 - s) % tmap.node(c2).degree
        plan = tmap.merge(c2, x2, rot, alike)
        if on_plan is not None:
            on_plan(plan)
        for d, (r, sh) in plan.nodes.items():
            for old, (cur, s0) in list(renamed.items()):
                if cur == d:
                    renamed[old] = (r, (s0 + sh) % tmap.node(r).degree)
            renamed.setdefault(d, (r, sh))
    return renamed


def implies(tmap: TopoMap, renamed: Renames, mapping: Mapping[int, tuple[int, int]]) -> bool:
    """Whether, in the map after the merges that gave ``renamed``, every node of ``mapping``
    already is its old node under its rotation."""
    for x, (c, k) in mapping.items():
        rx, sx = renamed.get(x, (x, 0))
        rc, sc = renamed.get(c, (c, 0))
        if rx != rc or not tmap.has_node(rx):
            return False
        if (sx - k - sc) % tmap.node(rx).degree:
            return False
    return True
