"""SI conversions for the Nomad 200's protocol units; the codec itself stays in protocol units.

The protocol counts 1/10 inch (and 1/10 inch/s, 1/10 inch/s^2), 1/10 degree (likewise per second
and per second squared) and, for sonar ranges, whole inches. The same functions serve positions,
velocities and accelerations, since only the length or angle unit changes. Conversions back to
protocol units round to the nearest integer, because the wire only carries integers.
"""

from __future__ import annotations

import math

#: The international inch, exact by definition.
INCH_M = 0.0254
TENTH_INCH_M = INCH_M / 10
TENTH_DEGREE_RAD = math.pi / 1800
#: Full-scale ranges of the two voltage readings: the CPU one is measured after the slip ring.
CPU_VOLTAGE_RANGE = 12.0
MOTOR_VOLTAGE_RANGE = 12.85
_RAW_FULL_SCALE = 255


def tenth_inch_to_m(value: float) -> float:
    """1/10 inch (or 1/10 inch/s, /s^2) to metres (m/s, m/s^2)."""
    return value * INCH_M / 10


def m_to_tenth_inch(metres: float) -> int:
    """Metres (m/s, m/s^2) to the nearest 1/10 inch (1/10 inch/s, /s^2)."""
    return round(metres * 10 / INCH_M)


def inch_to_m(value: float) -> float:
    """Whole inches (sonar ranges) to metres."""
    return value * INCH_M


def m_to_inch(metres: float) -> int:
    """Metres to the nearest whole inch."""
    return round(metres / INCH_M)


def tenth_deg_to_rad(value: float) -> float:
    """1/10 degree (or per s, per s^2) to radians (rad/s, rad/s^2)."""
    return math.radians(value / 10)


def rad_to_tenth_deg(radians: float) -> int:
    """Radians (rad/s, rad/s^2) to the nearest 1/10 degree; no wrapping."""
    return round(math.degrees(radians) * 10)


def raw_to_volts(raw: int, full_range: float) -> float:
    """A raw voltage byte to volts: ``(2 + 3 * raw / 255) * full_range / 5``."""
    if not 0 <= raw <= _RAW_FULL_SCALE:
        raise ValueError(f"raw voltage = {raw} is outside 0..{_RAW_FULL_SCALE}")
    return (2 + 3 * raw / _RAW_FULL_SCALE) * full_range / 5


def volts_to_raw(volts: float, full_range: float) -> int:
    """Inverse of ``raw_to_volts`` to the nearest byte (for an emulator); outside it, ValueError."""
    raw = round(((volts * 5 / full_range) - 2) * _RAW_FULL_SCALE / 3)
    if not 0 <= raw <= _RAW_FULL_SCALE:
        low, high = raw_to_volts(0, full_range), raw_to_volts(_RAW_FULL_SCALE, full_range)
        raise ValueError(f"voltage = {volts} V is outside the measurable {low:g}..{high:g} V")
    return raw


def cpu_voltage(raw: int) -> float:
    """The CPU voltage byte of a state reply, in volts."""
    return raw_to_volts(raw, CPU_VOLTAGE_RANGE)


def motor_voltage(raw: int) -> float:
    """The motor voltage byte of a state reply, in volts."""
    return raw_to_volts(raw, MOTOR_VOLTAGE_RANGE)
