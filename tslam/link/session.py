"""Opening and closing zenoh sessions so that neither can hang a daemon or a monitor."""

from __future__ import annotations

import logging
import threading
import traceback
from typing import Any

from tslam.link.config import LinkConfig, zenoh_config
from tslam.link.errors import LinkError, one_line

log = logging.getLogger("tslam.link")

#: Every tslam payload is MessagePack; the schema's name follows the ';' (docs/link.md).
ENCODING = "application/msgpack"


def log_failure(what: str) -> None:
    """Log the exception being handled, as text only.

    ``log.exception`` would keep the traceback, whose frames hold the zenoh ``Query`` or
    ``Sample`` being handled; a query kept alive is never finalised, and closing the session
    then waits for it (seen with pytest's log capture holding the record).
    """
    log.error("%s\n%s", what, traceback.format_exc())


def open_session(cfg: LinkConfig) -> Any:
    """A ``zenoh.Session`` for ``cfg``; failing to open is a ``LinkError`` naming the endpoints."""
    import zenoh

    zenoh.init_log_from_env_or("error")
    conf = zenoh_config(cfg)
    try:
        return zenoh.open(conf)
    except Exception as e:
        where = ", ".join(cfg.connect or cfg.listen) or "no endpoints"
        raise LinkError(
            f"cannot open a zenoh {cfg.mode} session ({where}): {one_line(e)}"
        ) from None


def undeclare_quietly(*entities: Any) -> None:
    """Undeclare each entity, ignoring the ones already gone with their session."""
    for ent in entities:
        if ent is None:
            continue
        try:
            ent.undeclare()
        except Exception as e:  # already undeclared, or the session is closed
            log.debug("undeclare %r: %s", ent, e)


def close_session(session: Any, limit_s: float) -> bool:
    """Close ``session``, waiting at most ``limit_s``; True if it closed in time.

    zenoh's ``close()`` can block for the open timeout while it is reconnecting to a frozen
    peer (zenoh-notes pitfall 2). A daemon stopping under systemd must not wait on that, so
    the close runs in a helper thread that is abandoned (it finishes on its own) past the limit.
    """
    done = threading.Event()

    def run() -> None:
        try:
            session.close()
        except Exception as e:
            log.debug("session close: %s", e)
        finally:
            done.set()

    threading.Thread(target=run, name="zenoh-close", daemon=True).start()
    return done.wait(limit_s)
