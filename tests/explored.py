"""A simulated exploration run for a test, with some of the arbiter's or the tracer's settings
changed: its report and its progress notes, and the run itself for anything else."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any, NamedTuple

from tslam.core.explorer_params import ExplorerParams
from tslam.core.tracer_params import TracerParams
from tslam.programs.sim_cmd import Run, explore, report


class Explored(NamedTuple):
    report: dict[str, Any]
    notes: list[str]
    run: Run


def explored(
    world: str,
    seed: int,
    drift: str,
    duration_s: float,
    params: Mapping[str, Any] | None = None,
    tracer: Mapping[str, Any] | None = None,
) -> Explored:
    """``world`` explored for ``duration_s`` simulated seconds, with ``params`` changed on
    ``ExplorerParams`` and ``tracer`` on ``TracerParams``."""
    run = explore(
        world,
        seed,
        drift,
        duration_s,
        progress=False,
        params=replace(ExplorerParams(), **(params or {})),
        tracer_params=replace(TracerParams(), **(tracer or {})),
    )
    notes = [n.text for n in run.explorer.notes]
    return Explored(report(run, world, seed, drift), notes, run)
