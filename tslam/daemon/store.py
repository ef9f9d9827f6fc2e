"""What the daemon keeps on disk, so that a daemon killed at any instant comes back knowing
its map and its orders: ``map.json`` (the settled map, ``Explorer.settled_map``, after every map
change and every question about a place opened or settled) and ``daemon_state.json`` (after
every acknowledged command). Both are written through a temporary file and a rename, so a
reader, or a restart after SIGKILL, sees either the old file or the new one, never half."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

from tslam.core.explorer import Explorer
from tslam.core.topomap import MapFormatError, TopoMap
from tslam.programs.map_files import load_map, save_map
from tslam.programs.output import write_text_atomic

STATE_VERSION = 1
HALTS = (None, "paused", "stopped")


class StoreError(ValueError):
    """A stored file the daemon will not start from; it is left as it is for a person."""


@dataclass(frozen=True)
class Orders:
    """What operators asked for and were told was done."""

    halted: str | None = None  # "paused" or "stopped": the robot stands until told otherwise
    goal: int | None = None


class Store:
    def __init__(self, directory: Path) -> None:
        self.dir = directory
        self.map_path = directory / "map.json"
        self.state_path = directory / "daemon_state.json"
        self._held_out: frozenset[int] = frozenset()  # the nodes the last saved map left out

    def prepare(self) -> None:
        try:
            self.dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise StoreError(f"storage {self.dir}: cannot create: {exc.strerror or exc}") from None
        if not self.dir.is_dir():
            raise StoreError(f"storage {self.dir}: not a directory")

    def load_map(self) -> TopoMap | None:
        if not self.map_path.exists():
            return None
        try:
            return load_map(self.map_path)
        except MapFormatError as exc:
            raise StoreError(f"{exc} (left untouched; move it away to start a new map)") from None

    def save_settled(self, explorer: Explorer, changed: bool = True) -> bool:
        """Save ``explorer``'s settled map if its map ``changed``, or if the nodes it leaves
        out did (a place's look-alikes given up on changes no node: its nodes are kept as
        new, and belong in the stored map from then on). Whether it saved."""
        held_out = explorer.unsettled()
        if not changed and held_out == self._held_out:
            return False
        save_map(self.map_path, explorer.settled_map())
        self._held_out = held_out
        return True

    def load_orders(self) -> Orders:
        if not self.state_path.exists():
            return Orders()
        where = str(self.state_path)
        try:
            data = json.loads(self.state_path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise StoreError(f"{where}: cannot be read: {exc}") from None
        if not isinstance(data, dict) or data.get("version") != STATE_VERSION:
            raise StoreError(f"{where}: not a version {STATE_VERSION} daemon state")
        halted, goal = data.get("halted"), data.get("goal")
        if halted not in HALTS:
            raise StoreError(f"{where}: halted must be one of {HALTS}, got {halted!r}")
        if goal is not None and (isinstance(goal, bool) or not isinstance(goal, int)):
            raise StoreError(f"{where}: goal must be a node id or null, got {goal!r}")
        return Orders(halted, goal)

    def save_orders(self, orders: Orders) -> None:
        data = {"version": STATE_VERSION, **asdict(orders)}
        write_text_atomic(self.state_path, json.dumps(data, indent=1) + "\n")
