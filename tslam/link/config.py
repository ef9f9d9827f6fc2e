"""How a link session is opened: a small, validated ``LinkConfig`` turned into a ``zenoh.Config``.

Defaults keep a session off the LAN's multicast: scouting by multicast and gossip are turned
off unless a zenoh configuration file given as ``config_file`` sets them, because the
default configuration scouts 224.0.0.224 and two test runs (or two robots' CI jobs) on one
network would find each other. Endpoints are therefore always explicit. The lease and the
open timeout are short so that a frozen peer is noticed within about a second and ``close()``
never waits the 10 s zenoh defaults to (zenoh-notes pitfalls 2).
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tslam.link.errors import LinkError, one_line

if TYPE_CHECKING:
    import zenoh

MODES = ("peer", "client", "router")
_ENDPOINT = re.compile(r"^(tcp|udp|tls|quic|ws|unixsock-stream)/[^\s]+$")


@dataclass
class LinkConfig:
    mode: str = "peer"
    listen: list[str] = field(default_factory=list)
    connect: list[str] = field(default_factory=list)
    #: This side's credential, for zenoh's usrpwd authentication.
    user: str | None = None
    password: str | None = None
    #: The listening side's file of accepted ``user:password`` lines (zenoh's dictionary_file).
    dictionary_file: str | None = None
    #: A zenoh json5 configuration to start from (access_control lives there); the fields
    #: above override what it says, when they are set.
    config_file: str | None = None
    #: A peer silent this long is dropped: what "offline" and reconnection hinge on.
    lease_s: float = 2.0
    #: Longest wait to open a link, and so the longest ``close()`` can block.
    open_timeout_s: float = 2.0

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise ``LinkError`` naming the first bad field."""
        if self.mode not in MODES:
            raise LinkError(f"link mode {self.mode!r} is not one of {', '.join(MODES)}")
        for name in ("listen", "connect"):
            eps = getattr(self, name)
            if isinstance(eps, str) or not isinstance(eps, list):
                raise LinkError(f"link {name} must be a list of endpoints, not {eps!r}")
            for ep in eps:
                if not isinstance(ep, str) or not _ENDPOINT.match(ep):
                    raise LinkError(f"link {name} endpoint {ep!r} is not of the form tcp/HOST:PORT")
        if (self.user is None) != (self.password is None):
            raise LinkError("link user and password must be given together")
        for name in ("user", "password"):
            v = getattr(self, name)
            if v is not None and (not isinstance(v, str) or not v or ":" in v or "\n" in v):
                raise LinkError(f"link {name} must be a non-empty string without ':'")
        for name in ("dictionary_file", "config_file"):
            v = getattr(self, name)
            if v is not None and not Path(v).is_file():
                raise LinkError(f"link {name} {v!r}: no such file")
        for name in ("lease_s", "open_timeout_s"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not 0.1 <= v <= 600:
                raise LinkError(f"link {name} must be a number of seconds in 0.1-600, not {v!r}")
        if self.mode == "client" and not self.connect and self.config_file is None:
            raise LinkError("link mode 'client' needs at least one connect endpoint")

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], where: str = "[link]") -> LinkConfig:
        """Build from a parsed TOML table; unknown keys and bad values name ``where``."""
        if not isinstance(data, Mapping):
            raise LinkError(f"{where} must be a table")
        known = {f.name for f in fields(cls)}
        extra = sorted(set(data) - known)
        if extra:
            raise LinkError(
                f"{where}: unknown key {extra[0]!r} (known: {', '.join(sorted(known))})"
            )
        try:
            return cls(**dict(data))
        except LinkError as e:
            raise LinkError(f"{where}: {e}") from None

    def with_credentials_file(self, path: str | Path) -> LinkConfig:
        """A copy with user and password read from ``path`` (one ``user:password`` line)."""
        user, password = read_credentials(path)
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d.update(user=user, password=password)
        return LinkConfig(**d)


def read_credentials(path: str | Path) -> tuple[str, str]:
    """The first ``user:password`` line of a credentials file (blank and # lines skipped)."""
    p = Path(path)
    try:
        lines = p.read_text().splitlines()
    except OSError as e:
        raise LinkError(f"credentials file {str(p)!r}: {e.strerror}") from None
    for n, line in enumerate(lines, 1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        user, sep, password = s.partition(":")
        if not sep or not user or not password:
            raise LinkError(f"credentials file {str(p)!r} line {n}: expected user:password")
        if ":" in password:
            # zenoh's users file is user:password per line, so neither may hold a ':'.
            raise LinkError(f"credentials file {str(p)!r} line {n}: the password holds a ':'")
        return user, password
    raise LinkError(f"credentials file {str(p)!r}: no user:password line")


def _set(conf: zenoh.Config, path: str, value: Any) -> None:
    conf.insert_json5(path, json.dumps(value))


def _unset(conf: zenoh.Config, path: str) -> bool:
    return conf.get_json(path) in ("null", "")


def zenoh_config(cfg: LinkConfig) -> zenoh.Config:
    """The ``zenoh.Config`` for ``cfg``: the config file if any, then our fields over it."""
    import zenoh

    cfg.validate()
    if cfg.config_file is not None:
        try:
            conf = zenoh.Config.from_file(cfg.config_file)
        except Exception as e:  # zenoh raises its own ZError with the parser's message
            raise LinkError(f"zenoh config {cfg.config_file!r}: {one_line(e)}") from None
    else:
        conf = zenoh.Config()
    try:
        _set(conf, "mode", cfg.mode)
        if cfg.listen:
            _set(conf, "listen/endpoints", cfg.listen)
        elif cfg.config_file is None or _unset(conf, "listen/endpoints"):
            # zenoh's default listens on every interface: a client or monitor need not
            # listen at all, and a peer given no endpoint should not open a port on the LAN.
            _set(conf, "listen/endpoints", [])
        if cfg.connect:
            _set(conf, "connect/endpoints", cfg.connect)
        # A peer keeps retrying its connect endpoints in the background (zenoh's default for
        # peers; a client fails to open instead): retry often, so that a link that dropped
        # comes back within about a second of the other side returning.
        if _unset(conf, "connect/retry"):
            _set(
                conf,
                "connect/retry",
                {"period_init_ms": 200, "period_max_ms": 1000, "period_increase_factor": 2},
            )
        for scout in ("multicast", "gossip"):
            if _unset(conf, f"scouting/{scout}/enabled"):
                _set(conf, f"scouting/{scout}/enabled", False)
        # Advanced publishers keep a cache: it needs timestamps (zenoh-notes pitfall 3).
        _set(conf, "timestamping/enabled", True)
        _set(conf, "transport/unicast/open_timeout", int(cfg.open_timeout_s * 1000))
        _set(conf, "transport/unicast/accept_timeout", int(cfg.open_timeout_s * 1000))
        _set(conf, "transport/link/tx/lease", int(cfg.lease_s * 1000))
        if cfg.user is not None:
            _set(conf, "transport/auth/usrpwd/user", cfg.user)
            _set(conf, "transport/auth/usrpwd/password", cfg.password)
        if cfg.dictionary_file is not None:
            _set(conf, "transport/auth/usrpwd/dictionary_file", cfg.dictionary_file)
    except LinkError:
        raise
    except Exception as e:
        raise LinkError(f"zenoh config: {one_line(e)}") from None
    return conf


def loopback(port_listen: int | None, connect_ports: list[int]) -> LinkConfig:
    """A peer on 127.0.0.1 only, listening on ``port_listen`` and connecting to the others."""
    return LinkConfig(
        mode="peer",
        listen=[] if port_listen is None else [f"tcp/127.0.0.1:{port_listen}"],
        connect=[f"tcp/127.0.0.1:{p}" for p in connect_ports],
        lease_s=1.0,
        open_timeout_s=1.0,
    )


def free_port() -> int:
    """A TCP port on 127.0.0.1 that was free a moment ago (for tests and benchmarks)."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])
