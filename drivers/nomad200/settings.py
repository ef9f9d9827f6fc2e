"""The Nomad 200 driver's options, read and checked once, before anything is opened.

Options (``nomad200:///dev/ttyUSB0?baud=9600`` or a TOML table ``backend = "nomad200"``):

===================== ============ =============================================================
key                   default      meaning
===================== ============ =============================================================
``port``/``target``   (required)   anything pyserial's ``serial_for_url`` opens: ``/dev/ttyS0``,
                                   ``socket://127.0.0.1:65001``, ``loop://``
``baud``              9600         4800, 9600, 19200 (Nomad 200) or 38400 (Scout)
``sonar_order``       0,2,15,1,..  firing order, comma-separated transducer numbers (or a list)
``sonar_rate``        15           time per transducer in 4 ms units; 0 switches the ring off
``sonar_pos``         false        ask for each sonar's "pos" attachment: exact firing stamps
                                   and turret angles, at 36 bytes a sonar (too slow at 9600 baud
                                   for a 10 Hz loop; free on a pty)
``motion_timeout_s``  2            the robot's own watchdog (``conf_tm``): it stops when no
                                   motion command arrives for this long; 0 disables it
``speed_mps``         0.508        translation speed limit (also sent with ``sp``)
``steer_speed_dps``   45           steering rate limit, degrees per second
``turret_speed_dps``  45           turret rate limit, degrees per second
``accel_mps2``        0.762        translation acceleration (``ac``)
``steer_accel_dps2``  30           steering acceleration, degrees per second squared
``turret_accel_dps2`` 30           turret acceleration, degrees per second squared
``reply_timeout_s``   1.0          how long to wait for one reply
``retries``           2            retransmissions of an idempotent request after a bad reply
``reconnect_timeout_s`` 10         how long to keep reopening a vanished port; 0: never
``reconnect_backoff_s`` 0.1        first wait between reopen attempts, doubled up to 2 s
``max_state_age_s``   0.05         a state reply younger than this answers scan, odometry and
                                   status without a new ``gs`` (host seconds)
``lockstep``          false        the far end is an emulator in lockstep mode: the clock's
                                   ``sleep`` asks it to let simulated time pass (see lockstep.py)
``time_scale``        1.0          controller seconds per host second (an emulator run faster
                                   than real time); 1 on a robot
``ring_radius_m``     0.23         transducer distance from the centre
``beam_deg``          12.5         half beam width
``min_range_in``      6            shortest reading reported; closer ones are clamped to it
``max_range_in``      254          longest reading; 255 (and beyond this) means no echo
===================== ============ =============================================================
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from hal.config import Options
from hal.errors import ConfigurationError
from hal.interfaces import NOMAD200_LIMITS, DriveLimits

#: The order the Nomad 200 ring is usually fired in: opposite sides alternate.
DEFAULT_ORDER = (0, 2, 15, 1, 14, 3, 13, 4, 12, 5, 11, 6, 10, 7, 9, 8)
BAUD_RATES = (4800, 9600, 19200, 38400)
NAME = "nomad200"


@dataclass(frozen=True)
class Settings:
    port: str
    baud: int = 9600
    sonar_order: tuple[int, ...] = DEFAULT_ORDER
    sonar_rate: int = 15
    sonar_pos: bool = False
    motion_timeout_s: int = 2
    limits: DriveLimits = NOMAD200_LIMITS
    reply_timeout_s: float = 1.0
    retries: int = 2
    reconnect_timeout_s: float = 10.0
    reconnect_backoff_s: float = 0.1
    max_state_age_s: float = 0.05
    lockstep: bool = False
    time_scale: float = 1.0
    ring_radius_m: float = 0.23
    half_beam_rad: float = math.radians(12.5)
    min_range_in: int = 6
    max_range_in: int = 254

    @classmethod
    def from_options(cls, options: Mapping[str, Any]) -> Settings:
        values = dict(options)
        order = values.get("sonar_order")
        if isinstance(order, list | tuple):  # TOML gives a list, a URL a string
            values["sonar_order"] = ",".join(str(v) for v in order)
        opts = Options(NAME, values)
        port = opts.str("port", opts.str("target", "") or None)
        lim = NOMAD200_LIMITS
        deg = math.radians
        settings = cls(
            port=port,
            baud=_baud(opts.int("baud", 9600)),
            sonar_order=_order(opts.str("sonar_order", ",".join(map(str, DEFAULT_ORDER)))),
            sonar_rate=opts.int("sonar_rate", 15, lo=0, hi=255),
            sonar_pos=opts.bool("sonar_pos", False),
            motion_timeout_s=opts.int("motion_timeout_s", 2, lo=0, hi=255),
            limits=DriveLimits(
                v_mps=opts.float("speed_mps", lim.v_mps, lo=0.001, hi=3.0),
                steer_radps=deg(opts.float("steer_speed_dps", 45.0, lo=0.1, hi=360.0)),
                turret_radps=deg(opts.float("turret_speed_dps", 45.0, lo=0.1, hi=360.0)),
                accel_mps2=opts.float("accel_mps2", lim.accel_mps2, lo=0.001, hi=5.0),
                steer_accel_radps2=deg(opts.float("steer_accel_dps2", 30.0, lo=0.1, hi=720.0)),
                turret_accel_radps2=deg(opts.float("turret_accel_dps2", 30.0, lo=0.1, hi=720.0)),
            ),
            reply_timeout_s=opts.float("reply_timeout_s", 1.0, lo=0.01, hi=300.0),
            retries=opts.int("retries", 2, lo=0, hi=20),
            reconnect_timeout_s=opts.float("reconnect_timeout_s", 10.0, lo=0.0, hi=3600.0),
            reconnect_backoff_s=opts.float("reconnect_backoff_s", 0.1, lo=0.001, hi=60.0),
            max_state_age_s=opts.float("max_state_age_s", 0.05, lo=0.0, hi=10.0),
            lockstep=opts.bool("lockstep", False),
            time_scale=opts.float("time_scale", 1.0, lo=0.01, hi=1000.0),
            ring_radius_m=opts.float("ring_radius_m", 0.23, lo=0.0, hi=1.0),
            half_beam_rad=deg(opts.float("beam_deg", 12.5, lo=1.0, hi=60.0)),
            min_range_in=opts.int("min_range_in", 6, lo=0, hi=254),
            max_range_in=opts.int("max_range_in", 254, lo=1, hi=254),
        )
        opts.finish()
        if settings.min_range_in >= settings.max_range_in:
            raise ConfigurationError(
                f"{NAME}: option 'min_range_in' ({settings.min_range_in}) must be below "
                f"'max_range_in' ({settings.max_range_in})"
            )
        return settings


def _baud(value: int) -> int:
    if value not in BAUD_RATES:
        allowed = ", ".join(map(str, BAUD_RATES))
        raise ConfigurationError(f"{NAME}: option 'baud' must be one of {allowed}, got {value}")
    return value


def _order(text: str) -> tuple[int, ...]:
    try:
        order = tuple(int(part) for part in text.replace(" ", "").split(",") if part)
    except ValueError:
        raise ConfigurationError(
            f"{NAME}: option 'sonar_order' must list transducer numbers 0-15 separated by "
            f"commas, got {text!r}"
        ) from None
    bad = [i for i in order if not 0 <= i <= 15]
    if bad or len(set(order)) != len(order):
        raise ConfigurationError(
            f"{NAME}: option 'sonar_order' must list distinct transducers 0-15, got {text!r}"
        )
    return order
