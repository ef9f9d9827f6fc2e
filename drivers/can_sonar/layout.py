"""Where the board's channels sit on the robot: the mapping from board channels to ring positions.

A board numbers its 16 channels by connector, not by where the transducer was mounted, so the
ring order, the angle and the mounting radius of each transducer are configuration. Ring
position ``i`` (the order of ``SonarScan`` arrays) is fed by board channel ``channels[i]``,
looks out along ``angles_rad[i]`` (counter-clockwise from the robot's x axis) and sits
``radii_m[i]`` from the robot's centre. Only mapped channels are activated on the board.

Options (all optional; lists may be given as lists or as comma-separated strings, as a URL
carries them):

- ``channels``: board channels 0-15 in ring order (default 0, 1, ..., 15);
- ``angles_deg``: one angle per ring position (default: evenly spaced, 360/n apart, from 0,
  which for 16 channels is a Nomad 200 ring, 22.5 degrees apart);
- ``radius_m``: one mounting radius for all, or one per ring position (default 0.23 m).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from drivers.can_sonar.codec import GROUP_COUNT, SENSOR_COUNT, SENSORS_PER_GROUP
from hal.errors import ConfigurationError

DEFAULT_RADIUS_M = 0.23


@dataclass(frozen=True)
class RingLayout:
    """Board channel, axis angle (rad) and mounting radius (m) of every ring position."""

    channels: tuple[int, ...]
    angles_rad: tuple[float, ...]
    radii_m: tuple[float, ...]

    def __post_init__(self) -> None:
        n = len(self.channels)
        if n == 0:
            raise ConfigurationError("can-sonar: the ring needs at least one channel")
        if len(self.angles_rad) != n or len(self.radii_m) != n:
            raise ConfigurationError(
                f"can-sonar: {n} channels need {n} angles and radii, got"
                f" {len(self.angles_rad)} and {len(self.radii_m)}"
            )
        if len(set(self.channels)) != n:
            raise ConfigurationError(
                f"can-sonar: option 'channels' repeats a channel: {self.channels}"
            )
        for c in self.channels:
            if not 0 <= c < SENSOR_COUNT:
                raise ConfigurationError(
                    f"can-sonar: option 'channels' must hold board channels 0-{SENSOR_COUNT - 1},"
                    f" got {c}"
                )
        for r in self.radii_m:
            if not (math.isfinite(r) and 0.0 <= r <= 2.0):
                raise ConfigurationError(f"can-sonar: a mounting radius must be 0-2 m, got {r}")
        # Ring order is what the algorithm's local-minimum rules walk: the positions must go
        # once around counter-clockwise, or neighbours in the array would not be neighbours.
        turns = [(a - self.angles_rad[0]) % (2 * math.pi) for a in self.angles_rad]
        if any(not math.isfinite(a) for a in self.angles_rad) or any(
            b <= a for a, b in itertools.pairwise(turns)
        ):
            degs = ", ".join(f"{math.degrees(a):g}" for a in self.angles_rad)
            raise ConfigurationError(
                "can-sonar: option 'angles_deg' must go once around the ring counter-clockwise"
                f" in ring order, with distinct angles; got {degs}"
            )

    @classmethod
    def nomad_ring(cls, n: int = SENSOR_COUNT, radius_m: float = DEFAULT_RADIUS_M) -> RingLayout:
        """``n`` transducers evenly spaced from the robot's x axis, channel i at position i."""
        return cls(
            tuple(range(n)),
            tuple(i * 2 * math.pi / n for i in range(n)),
            (radius_m,) * n,
        )

    def __len__(self) -> int:
        return len(self.channels)

    @property
    def active_mask(self) -> int:
        """Bit n set = board channel n is mapped (and so activated)."""
        mask = 0
        for c in self.channels:
            mask |= 1 << c
        return mask

    @property
    def groups(self) -> tuple[int, ...]:
        """The board groups (0-3) holding at least one mapped channel: what to ask data for."""
        return tuple(
            g for g in range(GROUP_COUNT) if any(c // SENSORS_PER_GROUP == g for c in self.channels)
        )

    def position_of(self) -> dict[int, int]:
        """Board channel -> ring position."""
        return {c: i for i, c in enumerate(self.channels)}


def layout_from_values(
    channels: Any = None, angles_deg: Any = None, radius_m: Any = None
) -> RingLayout:
    """The layout from raw option values (lists, comma lists or numbers; None = default)."""
    chans = (
        tuple(range(SENSOR_COUNT))
        if channels is None
        else tuple(_int(v, "channels") for v in _items(channels, "channels"))
    )
    n = len(chans)
    if angles_deg is None:
        angles = tuple(i * 2 * math.pi / max(n, 1) for i in range(n))
    else:
        angles = tuple(
            math.radians(_num(v, "angles_deg")) for v in _items(angles_deg, "angles_deg")
        )
    radii = tuple(
        _num(v, "radius_m")
        for v in _items(DEFAULT_RADIUS_M if radius_m is None else radius_m, "radius_m")
    )
    if len(radii) == 1:
        radii = radii * n
    return RingLayout(chans, angles, radii)


def _items(value: Any, key: str) -> Sequence[Any]:
    if isinstance(value, str):
        parts = [p.strip() for p in value.split(",")]
        if any(not p for p in parts):
            raise ConfigurationError(f"can-sonar: option '{key}' has an empty item: {value!r}")
        return parts
    if isinstance(value, int | float) and not isinstance(value, bool):
        return [value]
    if isinstance(value, Sequence):
        return list(value)
    raise ConfigurationError(
        f"can-sonar: option '{key}' must be a list or comma list, got {value!r}"
    )


def _num(value: Any, key: str) -> float:
    try:
        if isinstance(value, bool):
            raise ValueError
        out = float(value)
    except (TypeError, ValueError):
        raise ConfigurationError(
            f"can-sonar: option '{key}' must hold numbers, got {value!r}"
        ) from None
    if not math.isfinite(out):
        raise ConfigurationError(
            f"can-sonar: option '{key}' must hold finite numbers, got {value!r}"
        )
    return out


def _int(value: Any, key: str) -> int:
    out = _num(value, key)
    if not out.is_integer():
        raise ConfigurationError(f"can-sonar: option '{key}' must hold integers, got {value!r}")
    return int(out)
