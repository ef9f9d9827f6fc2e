"""Versioned key expressions: everything of one robot lives under ``tslam/v1/<robot>/``.

The version is in the key, not in the payload, so a monitor of a later protocol can still
list which robots speak v1 (and an ACL rule can name a version). docs/link.md describes
what each leaf carries.
"""

from __future__ import annotations

import re

from tslam.link.errors import LinkError

PREFIX = "tslam/v1"

#: Published with an advanced publisher (history, miss detection).
STATE = "state"
EVENTS = "events"
MAP_CHANGES = "map/changes"
#: Plain publisher: a late monitor needs only the newest scan, which comes within a second.
SCAN = "scan"
#: Queryables.
MAP = "map"
CMD = "cmd"
#: Liveliness token.
ALIVE = "alive"

LEAVES = (STATE, SCAN, MAP_CHANGES, MAP, EVENTS, CMD, ALIVE)

_ROBOT = re.compile(r"[A-Za-z0-9_-]+")

#: Every robot's liveliness token: what ``MonitorClient.robots()`` watches.
ALL_ALIVE = f"{PREFIX}/*/{ALIVE}"


def check_robot(robot: str) -> str:
    """Return ``robot`` if it is a valid name (letters, digits, ``_``, ``-``), else raise."""
    if not isinstance(robot, str) or not _ROBOT.fullmatch(robot):
        raise LinkError(f"robot name {robot!r} is not valid: use letters, digits, '_' and '-' only")
    return robot


def key(robot: str, leaf: str) -> str:
    """The key expression of ``leaf`` (one of ``LEAVES``) for ``robot``."""
    check_robot(robot)
    if leaf not in LEAVES:
        raise LinkError(f"unknown key leaf {leaf!r}: one of {', '.join(LEAVES)}")
    return f"{PREFIX}/{robot}/{leaf}"


def robot_of(key_expr: str) -> str | None:
    """The robot named in a ``tslam/v1/<robot>/...`` key, or None if it is not one of ours."""
    parts = str(key_expr).split("/")
    if len(parts) < 4 or "/".join(parts[:2]) != PREFIX or not _ROBOT.fullmatch(parts[2]):
        return None
    return parts[2]
