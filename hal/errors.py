"""The hal error tree, in one place.

::

    HalError                      anything a backend raises on purpose
    ├── ConfigurationError        bad or missing configuration; raised before anything moves
    ├── BackendNotFoundError      the registry has no backend of that name or URL scheme
    ├── LifecycleError            a call made in the wrong lifecycle state (e.g. a motion
    │                             command while not active); nothing was sent to the robot
    ├── CommandError              a command no robot should obey (not finite); the drive
    │                             has been told to stop before this is raised
    ├── CommunicationError        the link to the device failed
    │   ├── DeviceTimeoutError    no reply in time
    │   ├── ProtocolError         a reply that does not parse (bad checksum, truncated, garbage)
    │   └── LinkLostError         the port or bus vanished
    └── DeviceFaultError          the device reports a fault (stall, sensor board lost)

Callers that only want to stop the robot safely catch ``HalError``.
"""

from __future__ import annotations


class HalError(Exception):
    """Base of every error a hal backend raises on purpose."""


class ConfigurationError(HalError):
    """Configuration is invalid; the message names the key and what is wrong."""


class BackendNotFoundError(ConfigurationError):
    """No backend is registered under the requested name or URL scheme."""


class LifecycleError(HalError):
    """A call was made in a lifecycle state that does not allow it."""


class CommandError(HalError):
    """A command was refused as malformed; the robot was stopped."""


class CommunicationError(HalError):
    """The link to the device failed."""


class DeviceTimeoutError(CommunicationError):
    """The device did not answer in time."""


class ProtocolError(CommunicationError):
    """The device's reply was malformed."""


class LinkLostError(CommunicationError):
    """The port, socket or bus went away."""


class DeviceFaultError(HalError):
    """The device reports a fault it cannot recover from by itself."""
