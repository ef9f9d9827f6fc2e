"""Hardware abstraction layer: SI-unit data, the Drive / Encoders / SonarRing interfaces, one
lifecycle for every backend, an error tree and a registry of backends."""

from hal.clock import Clock, MonotonicClock
from hal.config import Options
from hal.errors import (
    BackendNotFoundError,
    CommandError,
    CommunicationError,
    ConfigurationError,
    DeviceFaultError,
    DeviceTimeoutError,
    HalError,
    LifecycleError,
    LinkLostError,
    ProtocolError,
)
from hal.interfaces import NOMAD200_LIMITS, Backend, Drive, DriveLimits, Encoders, SonarRing
from hal.lifecycle import Lifecycle, State
from hal.registry import available_backends, create_backend, parse_spec, register_backend
from hal.types import DriveStatus, Odometry, SonarReading, SonarScan, Twist

__all__ = [
    "NOMAD200_LIMITS",
    "Backend",
    "BackendNotFoundError",
    "Clock",
    "CommandError",
    "CommunicationError",
    "ConfigurationError",
    "DeviceFaultError",
    "DeviceTimeoutError",
    "Drive",
    "DriveLimits",
    "DriveStatus",
    "Encoders",
    "HalError",
    "Lifecycle",
    "LifecycleError",
    "LinkLostError",
    "MonotonicClock",
    "Odometry",
    "Options",
    "ProtocolError",
    "SonarReading",
    "SonarRing",
    "SonarScan",
    "State",
    "Twist",
    "available_backends",
    "create_backend",
    "parse_spec",
    "register_backend",
]
