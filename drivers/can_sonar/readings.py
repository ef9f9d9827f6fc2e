"""The latest reading of every ring position, built from group data frames.

The board's frames carry no time, so a reading is stamped when the frame carrying it arrives (on
the driver's clock). A reading keeps that stamp until a newer frame replaces it: when frames
stop arriving (dropped, corrupt, a lost board) old readings are never re-stamped as new, and
once older than ``max_age_s`` they are reported as no reading (NaN) with their old stamp.

Range rules, at the driver boundary: the reserved values (invalid, too close, no echo) are no
reading; a distance beyond ``max_range_m`` is no reading (the sensor cannot be trusted there);
a distance below ``min_range_m`` is reported as ``min_range_m`` (an echo that close means the
obstacle is at least that near, which is what a range-bounded consumer needs to know).
"""

from __future__ import annotations

import math

import numpy as np

from drivers.can_sonar.codec import SENSORS_PER_GROUP, GroupData, ReadingStatus
from drivers.can_sonar.layout import RingLayout


class ReadingTable:
    """Per ring position: range (m, NaN = none), stamp (s) and the board's reading status."""

    def __init__(
        self, layout: RingLayout, *, min_range_m: float, max_range_m: float, max_age_s: float
    ) -> None:
        if not 0.0 <= min_range_m < max_range_m:
            raise ValueError(
                f"need 0 <= min_range_m < max_range_m, got {min_range_m}, {max_range_m}"
            )
        self.layout = layout
        self.min_range_m = min_range_m
        self.max_range_m = max_range_m
        self.max_age_s = max_age_s
        n = len(layout)
        self._position = layout.position_of()
        self.ranges_m = np.full(n, np.nan)
        self.stamps_s = np.zeros(n)
        self.statuses: list[ReadingStatus] = [ReadingStatus.INVALID] * n
        self.groups_seen: set[int] = set()

    def update(self, data: GroupData, stamp_s: float) -> None:
        """Take in one group data frame received at ``stamp_s``."""
        self.groups_seen.add(data.group)
        for k, reading in enumerate(data.readings):
            pos = self._position.get(SENSORS_PER_GROUP * data.group + k)
            if pos is None:
                continue  # a channel the ring does not use
            self.ranges_m[pos] = self._range(reading.status, reading.range_m)
            self.stamps_s[pos] = stamp_s
            self.statuses[pos] = reading.status

    def _range(self, status: ReadingStatus, range_m: float | None) -> float:
        if status is not ReadingStatus.OK or range_m is None or range_m > self.max_range_m:
            return math.nan
        return max(range_m, self.min_range_m)

    def has_groups(self, groups: tuple[int, ...]) -> bool:
        return all(g in self.groups_seen for g in groups)

    def snapshot(self, now_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Copies of ranges and stamps at ``now_s``, readings older than ``max_age_s`` as NaN."""
        ranges = self.ranges_m.copy()
        stamps = self.stamps_s.copy()
        ranges[now_s - stamps > self.max_age_s] = np.nan
        return ranges, stamps
