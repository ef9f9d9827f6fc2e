"""Dead reckoning that drifts the way a synchro-drive base does: mostly in heading.

The paper (section V-C) rests on one observation about the Nomad 200: orientation error
dominates, so a retraced edge keeps its length while the whole map seems to rotate (Fig. 7).
The model integrates the true motion of each physics step through an imperfect encoder:

- translation: a per-run scale error plus a small random walk, so lengths stay good to ~1 %;
- heading: a per-run bias per metre travelled (the chassis slowly twisting), a random walk
  per square-root metre, and a per-run scale error on steering turns.

Levels: ``none`` (exact), ``paper`` (several metres of position error over a fig14-sized
exploration of a few hundred metres, as the paper reports "over 10 ft"), ``severe``.
The per-run errors are drawn from the seed, so a seed fixes the drift.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

DRIFT_LEVELS = ("none", "paper", "severe")


@dataclass(frozen=True)
class DriftParams:
    """Standard deviations of the drift terms."""

    trans_scale: float  # fraction of distance, drawn once per run
    trans_walk: float  # m per sqrt(m)
    heading_bias: float  # rad per m, drawn once per run
    heading_walk: float  # rad per sqrt(m)
    turn_scale: float  # fraction of each turn, drawn once per run
    turn_walk: float  # rad per sqrt(rad)

    @staticmethod
    def level(name: str) -> DriftParams:
        if name == "none":
            return DriftParams(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        if name == "paper":
            return DriftParams(
                trans_scale=0.003,
                trans_walk=0.002,
                heading_bias=math.radians(0.08),
                heading_walk=math.radians(0.15),
                turn_scale=0.004,
                turn_walk=math.radians(0.3),
            )
        if name == "severe":
            return DriftParams(
                trans_scale=0.008,
                trans_walk=0.005,
                heading_bias=math.radians(0.2),
                heading_walk=math.radians(0.35),
                turn_scale=0.012,
                turn_walk=math.radians(0.8),
            )
        raise ValueError(f"unknown drift level {name!r} (choose from {', '.join(DRIFT_LEVELS)})")


class DeadReckoning:
    """Integrates encoder increments into the robot's own pose estimate."""

    def __init__(self, true_heading: float, params: DriftParams, rng: np.random.Generator) -> None:
        # Like the real base after power-up, dead reckoning starts at the origin, heading 0.
        self.x = 0.0
        self.y = 0.0
        self.heading = 0.0
        self.distance = 0.0
        self._offset = -true_heading
        self._p = params
        self._rng = rng
        self._trans_scale = 1.0 + rng.normal(0.0, params.trans_scale) if params.trans_scale else 1.0
        self._bias = rng.normal(0.0, params.heading_bias) if params.heading_bias else 0.0
        self._turn_scale = 1.0 + rng.normal(0.0, params.turn_scale) if params.turn_scale else 1.0
        self._exact = params == DriftParams.level("none")

    @property
    def heading_offset(self) -> float:
        """What to add to a true angle to express it in the drifting odometry frame."""
        return self._offset

    def update(self, ds: float, dtheta: float) -> None:
        """Account for a true step: ``ds`` metres along the heading, ``dtheta`` radians turned."""
        if self._exact:
            ds_m, dth_m = ds, dtheta
        else:
            p = self._p
            a = abs(ds)
            ds_m = ds * self._trans_scale
            dth_m = dtheta * self._turn_scale + self._bias * a
            if a > 0.0:
                r = self._rng.normal(0.0, 1.0, 2)
                ds_m += p.trans_walk * math.sqrt(a) * r[0] * math.copysign(1.0, ds)
                dth_m += p.heading_walk * math.sqrt(a) * r[1]
            if dtheta != 0.0 and p.turn_walk:
                dth_m += p.turn_walk * math.sqrt(abs(dtheta)) * self._rng.normal()
        mid = self.heading + 0.5 * dth_m
        self.x += ds_m * math.cos(mid)
        self.y += ds_m * math.sin(mid)
        self.heading += dth_m
        self.distance += abs(ds_m)
        self._offset += dth_m - dtheta
