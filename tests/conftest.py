"""Shared fixtures: small worlds built in code, so tests do not depend on built-in layouts."""

from __future__ import annotations

import pytest

from sim_backend.world import PolygonWorld, StartPose


def box_world(
    w: float = 12.0, h: float = 6.0, start: StartPose | None = None, obstacles=None
) -> PolygonWorld:
    return PolygonWorld(
        "box",
        [(0, 0), (w, 0), (w, h), (0, h)],
        obstacles or [],
        start or StartPose(2.0, h / 2, 0.0),
        source="test:box",
    )


@pytest.fixture
def box():
    return box_world()
