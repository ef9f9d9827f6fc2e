"""The obstacles around a junction read as one place, from the sweep at one of its meet points.

Two meet points a few decimetres apart (fig1's pair 0.20 m apart, fig14's lab door, fig16's
weak meet point 0.36 m from the corridor's) are one junction to a sonar robot: it homes onto
whichever it reaches first, and counting only the obstacles equidistant to that one gives the
junction three edges on one pass and four on the next. Worse, the edges that leave from the
other point are never seen, so the places beyond them are never reached. (Section VII-B of
the paper meets this as the weak meet point of fig16.)

So a homed meet point can read its place: every meet point within ``radius_m`` that the swept
obstacles define, each found as the point equidistant to three of them (to first order,
``laws.wall_centre``, exact for flat walls) with no other obstacle closer. The obstacles
around the place are those of all its meet points; the place's edges leave between each two
of them adjacent in bearing, as a single meet point's do (``laws.departure_bearings``): a
junction of two meet points with four obstacles around it has four edges out whichever of the
two the robot stands on, if the sweep sees all four from there. It does not always: at fig16
the sweep from the corridor's meet point hears the indent's two corners but not its back wall
between them, so the place reads four edges from the weak meet point and three from the
corridor's (``TracerParams.place_radius_m`` says what that costs).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from tslam.core import laws
from tslam.core.sensing import Obstacle

#: The nearest obstacles a place is sought among: a sweep's others are far walls.
MAX_OBSTACLES = 8


def place_obstacles(
    obstacles: Sequence[Obstacle],
    around: Sequence[Obstacle],
    radius_m: float,
    tol_m: float,
    corners: bool = False,
) -> list[Obstacle]:
    """The obstacles around the place of the meet point the robot stands at.

    ``obstacles``: the sweep's, nearest first; ``around``: those equidistant to the point
    the robot stands at (its degree's). A further meet point of the place is equidistant,
    within ``tol_m``, to three obstacles with none closer, no more than ``radius_m`` away.
    Returns ``around`` and the obstacles of those meet points, nearest first. With
    ``corners`` a meet point is also sought as if the three were corners, not walls.
    """
    if radius_m <= 0.0:
        return list(around)
    pool = list(obstacles[:MAX_OBSTACLES])
    inside = [any(o is a for a in around) for o in pool]
    for trio in itertools.combinations(range(len(pool)), 3):
        if all(inside[i] for i in trio):
            continue
        three = [pool[i] for i in trio]
        # Equidistant to three walls, or to three corners: the sweep cannot tell which an
        # obstacle is, and a wall's first-order point lies too far for a corner's (fig16's
        # weak meet point, between the indent's two corners and its back wall: 0.53 m from
        # the corridor's meet point, against 0.36 m).
        centres = [laws.wall_centre(*three)]
        if corners:
            centres.append(laws.circumcentre(*three))
        for c in centres:
            if c is None or math.hypot(*c) > radius_m:
                continue
            seen = laws.seen_from(pool, c)
            r = max(seen[i] for i in trio)
            if r > 0.0 and min(seen) >= r - tol_m:  # no other obstacle closer there
                for i in trio:
                    inside[i] = True
                break
    out = [o for o, keep in zip(pool, inside, strict=True) if keep]
    return out + [a for a in around if not any(a is o for o in out)]
