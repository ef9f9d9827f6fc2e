"""The daemon's configuration file (TOML), checked whole before anything opens or moves.

Every fault names the key it is about, so a user fixing a robot's configuration over ssh
sees what to change without reading code::

    robot = "nomad-1"              # its name on the link: tslam/v1/<robot>/...
    storage = "/var/lib/tslam/nomad-1"   # map.json and daemon_state.json; relative to the cwd
    rate_hz = 10.0                 # control loop
    watchdog_s = 1.0               # the drive is stopped when the loop stalls this long
    exit_when_done = false         # stay up after exploring (operators may send goto)

    [backend]                      # a hal backend spec: sim, nomad200, composed, ...
    backend = "sim"
    world = "fig12"

    [sim]
    time_scale = 10.0              # simulated seconds per wall second; 0 = flat out

    [link]
    enabled = true
    mode = "peer"                  # peer, client or router
    listen = ["tcp/127.0.0.1:7447"]
    connect = []
    config_file = "deploy/zenoh/robot-peer.json5"    # optional, a zenoh config to start from
    credentials_file = "/etc/tslam/nomad-1.credentials"   # optional: one user:password line
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tslam.link.config import LinkConfig
from tslam.link.errors import LinkError


class ConfigError(ValueError):
    """The configuration cannot be used; the message names the file and the key."""


_REQUIRED = object()
ROBOT_NAME = re.compile(r"^[A-Za-z0-9_-]{1,64}$")


@dataclass(frozen=True)
class DaemonConfig:
    robot: str
    storage: Path
    backend: dict[str, Any]
    rate_hz: float = 10.0
    watchdog_s: float = 1.0
    exit_when_done: bool = False
    time_scale: float = 1.0  # simulation only
    scan_every: int = 5  # publish one scan in this many control cycles
    link_enabled: bool = True
    link: LinkConfig = field(default_factory=LinkConfig)
    source: str = "<config>"


def load_config(path: str | Path) -> DaemonConfig:
    """Read and check ``path``; any fault raises ``ConfigError`` naming the key."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{p}: cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{p}: not UTF-8 text") from None
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: not valid TOML: {exc}") from None
    return parse_config(raw, str(p))


def parse_config(raw: Mapping[str, Any], source: str = "<config>") -> DaemonConfig:
    r = _Reader(raw, source, "")
    robot = r.str("robot")
    if not ROBOT_NAME.match(robot):
        raise r.fail("robot", "must be 1-64 letters, digits, '_' or '-'", robot)
    storage = Path(r.str("storage"))
    rate = r.float("rate_hz", 10.0, 0.5, 200.0)
    watchdog = r.float("watchdog_s", 1.0, 0.05, 60.0)
    if watchdog < 2.0 / rate:
        raise r.fail("watchdog_s", f"must be at least two control periods ({2.0 / rate:g} s)",
                     watchdog)  # fmt: skip
    exit_when_done = r.bool("exit_when_done", False)
    scan_every = r.int("scan_every", 5, 1, 1000)
    backend = dict(r.table("backend"))
    if not isinstance(backend.get("backend"), str) or not backend["backend"]:
        raise ConfigError(f"{source}: [backend] needs backend = \"NAME\" (sim, nomad200, ...)")
    sim = _Reader(r.table("sim", {}), source, "sim.")
    time_scale = sim.float("time_scale", 1.0, 0.0, 100000.0)
    sim.finish()
    if "sim" in raw and backend["backend"] != "sim":
        raise ConfigError(f"{source}: [sim] applies to backend = \"sim\" only")
    link_enabled, link = _link(_Reader(r.table("link", {}), source, "link."))
    r.finish()
    return DaemonConfig(
        robot=robot, storage=storage, backend=backend, rate_hz=rate, watchdog_s=watchdog,
        exit_when_done=exit_when_done, time_scale=time_scale, scan_every=scan_every,
        link_enabled=link_enabled, link=link, source=source,
    )  # fmt: skip


def _link(r: _Reader) -> tuple[bool, LinkConfig]:
    enabled = r.bool("enabled", True)
    kw: dict[str, Any] = {
        "mode": r.str("mode", "peer"),
        "listen": r.strings("listen"),
        "connect": r.strings("connect"),
        "lease_s": r.float("lease_s", 2.0, 0.1, 60.0),
        "open_timeout_s": r.float("open_timeout_s", 2.0, 0.1, 60.0),
    }
    for key in ("user", "password", "config_file", "dictionary_file"):
        kw[key] = r.str(key, "") or None
    creds = r.str("credentials_file", "") or None
    if creds is not None and (kw["user"] or kw["password"]):
        raise r.fail("credentials_file", "give user and password or a credentials_file", creds)
    for key in ("config_file", "dictionary_file"):
        if kw[key] is not None and not Path(kw[key]).is_file():
            raise r.fail(key, "names no file", kw[key])
    r.finish()
    try:
        link = LinkConfig(**kw)
        return enabled, (link if creds is None else link.with_credentials_file(creds))
    except LinkError as exc:
        raise ConfigError(f"{r.source}: [link] {exc}") from None


class _Reader:
    """Typed reads from one table; ``finish`` refuses keys nobody read (a typo is a fault)."""

    def __init__(self, raw: Mapping[str, Any], source: str, prefix: str) -> None:
        if not isinstance(raw, Mapping):
            raise ConfigError(f"{source}: [{prefix.rstrip('.')}] must be a table")
        self.raw, self.source, self.prefix = raw, source, prefix
        self.seen: set[str] = set()

    def fail(self, key: str, what: str, got: Any) -> ConfigError:
        return ConfigError(f"{self.source}: {self.prefix}{key} {what} (got {got!r})")

    def _get(self, key: str, default: Any) -> Any:
        self.seen.add(key)
        if key in self.raw:
            return self.raw[key]
        if default is _REQUIRED:
            raise ConfigError(f"{self.source}: {self.prefix}{key} is required")
        return default

    def str(self, key: str, default: Any = None) -> str:
        v = self._get(key, _REQUIRED if default is None else default)
        if not isinstance(v, str):
            raise self.fail(key, "must be a string", v)
        return v

    def bool(self, key: str, default: bool) -> bool:
        v = self._get(key, default)
        if not isinstance(v, bool):
            raise self.fail(key, "must be true or false", v)
        return v

    def float(self, key: str, default: float, lo: float, hi: float) -> float:
        v = self._get(key, default)
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise self.fail(key, "must be a number", v)
        if not lo <= v <= hi:
            raise self.fail(key, f"must be between {lo:g} and {hi:g}", v)
        return float(v)

    def int(self, key: str, default: int, lo: int, hi: int) -> int:
        v = self._get(key, default)
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.fail(key, "must be a whole number", v)
        if not lo <= v <= hi:
            raise self.fail(key, f"must be between {lo} and {hi}", v)
        return v

    def strings(self, key: str) -> list[str]:
        v = self._get(key, [])
        if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
            raise self.fail(key, "must be a list of non-empty strings", v)
        return list(v)

    def table(self, key: str, default: Mapping[str, Any] | None = None) -> Mapping[str, Any]:
        v = self._get(key, _REQUIRED if default is None else default)
        if not isinstance(v, Mapping):
            raise self.fail(key, "must be a table", v)
        return v

    def finish(self) -> None:
        extra = sorted(set(self.raw) - self.seen)
        if extra:
            names = ", ".join(self.prefix + k for k in extra)
            raise ConfigError(f"{self.source}: unknown key(s) {names}")

