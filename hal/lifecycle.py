"""One lifecycle for every backend, enforced here once rather than in each driver.

::

    UNCONFIGURED --configure--> INACTIVE --activate--> ACTIVE
         ^                         |   <--deactivate--   |
         |                        close                 close (deactivates first)
         +---(configure failed)    v                     v
                                 CLOSED <----------------+

``configure`` opens links and sends settings (nothing moves); ``activate`` enables motion
commands; ``deactivate`` stops the robot; ``close`` stops it and releases the link. A backend
implements the ``_on_*`` hooks only. Constructors never touch hardware.
"""

from __future__ import annotations

import enum
import threading
from types import TracebackType

from hal.errors import LifecycleError


class State(enum.Enum):
    UNCONFIGURED = "unconfigured"
    INACTIVE = "inactive"
    ACTIVE = "active"
    CLOSED = "closed"


class Lifecycle:
    """Base of every backend: the state machine and its guards."""

    #: Name used in messages; backends set it.
    backend_name: str = "backend"

    def __init__(self) -> None:
        self._state = State.UNCONFIGURED
        # Re-entrant: a watchdog thread may call stop() while the loop is inside command().
        self._lock = threading.RLock()

    @property
    def state(self) -> State:
        return self._state

    @property
    def is_open(self) -> bool:
        """True while the link is up (configured, active or not)."""
        return self._state in (State.INACTIVE, State.ACTIVE)

    def configure(self) -> None:
        with self._lock:
            self._expect("configure", State.UNCONFIGURED)
            try:
                self._on_configure()
            except BaseException:
                # A half-opened link must not linger: release what the hook managed to open.
                try:
                    self._on_close()
                finally:
                    self._state = State.UNCONFIGURED
                raise
            self._state = State.INACTIVE

    def activate(self) -> None:
        with self._lock:
            self._expect("activate", State.INACTIVE)
            self._on_activate()
            self._state = State.ACTIVE

    def deactivate(self) -> None:
        with self._lock:
            self._expect("deactivate", State.ACTIVE)
            try:
                self._safe_stop()
                self._on_deactivate()
            finally:
                self._state = State.INACTIVE

    def close(self) -> None:
        """Stop and release everything; safe to call in any state and more than once."""
        with self._lock:
            if self._state is State.CLOSED:
                return
            try:
                if self._state is State.ACTIVE:
                    self.deactivate()
            finally:
                try:
                    if self._state is State.INACTIVE:
                        self._on_close()
                finally:
                    self._state = State.CLOSED

    def __enter__(self) -> Lifecycle:
        if self._state is State.UNCONFIGURED:
            self.configure()
        if self._state is State.INACTIVE:
            self.activate()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def _expect(self, what: str, *states: State) -> None:
        if self._state not in states:
            allowed = " or ".join(s.value for s in states)
            raise LifecycleError(
                f"{self.backend_name}: cannot {what} while {self._state.value} (needs {allowed})"
            )

    def _require_open(self, what: str) -> None:
        self._expect(what, State.INACTIVE, State.ACTIVE)

    def _require_active(self, what: str) -> None:
        self._expect(what, State.ACTIVE)

    # Hooks for backends. Defaults do nothing so a backend overrides only what it needs.
    def _on_configure(self) -> None:
        pass

    def _on_activate(self) -> None:
        pass

    def _on_deactivate(self) -> None:
        pass

    def _on_close(self) -> None:
        pass

    def _safe_stop(self) -> None:
        """Bring motion to a halt; the Drive interface overrides it."""
