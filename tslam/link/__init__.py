"""The link: one robot's state, map, events and commands over Eclipse Zenoh (docs/link.md).

I/O lives here, never in ``tslam.core`` (an import-linter contract). ``keys``, ``schemas``
and ``config`` import no zenoh; ``robot`` (the daemon's side) and ``client`` (a monitor's
side) do, when used.
"""

from tslam.link.errors import LinkError

__all__ = ["LinkError"]
