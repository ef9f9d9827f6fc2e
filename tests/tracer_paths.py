"""The tracer some explorer tests were found with, for the paths they need.

Several explorer tests replay one simulated run in which the explorer met a case (a departure
not held, weak meet points passed unhomed, a mirror image): the explorer's handling is what
they test, and the tracer only has to take the robot along that path. Stop 26's tracer changes
(doorways, doubtful sweeps) move the robot otherwise, so these tests keep stop 25's tracer.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from tslam.core.tracer import TracerParams
from tslam.programs import trace_cmd

#: Stop 25's tracer: tracing from 0.15 m out of a departure whatever the ring sees, an edge
#: ended wherever a wall comes within 0.45 m, one sweep at every meet point judged where the
#: robot stands, and an edge's length taken over its whole chain (stop 31 judges the sweep
#: at its estimate and drops the chain's spikes: edgelength.py).
STOP25 = TracerParams(
    depart_until_sides_m=0.0,
    corner_ahead_m=math.inf,
    corner_ahead_rad=math.pi,
    sweep_again=False,
    edge_spike_ratio=math.inf,
    spread_at_estimate=False,
    sweep_recess=False,
    place_corners=False,
)


def without_recess(monkeypatch: pytest.MonkeyPatch) -> None:
    """``tslam trace``'s tracer as it was before stop 34 turned the ``recess`` switch on: at
    fig16's indent the sweep then reads the corridor's meet point and the weak one beside it
    as one place of four edges, and the passes and short edges these tests measure are gone."""
    default = trace_cmd.tracer_params
    monkeypatch.setattr(
        trace_cmd,
        "tracer_params",
        lambda sw: replace(default(sw), sweep_recess=False, place_corners=False),
    )
