"""The link's messages: frozen ``msgspec.Struct`` types, carried as MessagePack.

msgspec does the parsing and the type checking on decode, so no field is read by hand; a
payload that does not fit its type becomes one ``LinkError`` naming the message and the path
of the bad field (``malformed command: Expected `str`, got `int` - at `$.op```). Unknown
fields are ignored on decode, so a later version may add fields without breaking an older
monitor; removing or retyping one needs ``tslam/v2``. docs/link.md documents every field.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, TypeVar

import msgspec

from tslam.link.errors import LinkError

#: Commands the robot understands; anything else is refused with a reason.
OPS = ("pause", "resume", "stop", "goto", "explore")

NonNeg = Annotated[int, msgspec.Meta(ge=0)]
Metres = Annotated[float, msgspec.Meta(ge=0.0)]
Robot = Annotated[str, msgspec.Meta(pattern=r"^[A-Za-z0-9_-]+$")]
Text = Annotated[str, msgspec.Meta(max_length=4096)]


class NodeMsg(msgspec.Struct, frozen=True):
    id: NonNeg
    kind: Literal["meet", "boundary"]
    x: float  # dead-reckoned pose at the first visit: for drawing only
    y: float
    clearance_m: Metres
    degree: NonNeg
    unexplored: NonNeg  # departures not yet travelled
    ambiguous_with: list[int] = msgspec.field(default_factory=list)


class EdgeMsg(msgspec.Struct, frozen=True):
    id: NonNeg
    u: NonNeg
    v: NonNeg
    length_m: Metres


class MapSnapshot(msgspec.Struct, frozen=True):
    robot: Robot
    epoch: str  # one per daemon start: a new epoch means seq numbers start afresh
    seq: NonNeg  # the map version this snapshot shows: changes up to seq are in it
    nodes: list[NodeMsg]
    edges: list[EdgeMsg]


class MapChange(msgspec.Struct, frozen=True):
    robot: Robot
    epoch: str
    seq: NonNeg  # consecutive within an epoch: the map version after this change
    op: str  # what happened (the core's change op: node_added, merge, ...), for display
    upsert_nodes: list[NodeMsg] = msgspec.field(default_factory=list)
    remove_nodes: list[int] = msgspec.field(default_factory=list)
    upsert_edges: list[EdgeMsg] = msgspec.field(default_factory=list)
    remove_edges: list[int] = msgspec.field(default_factory=list)


class RobotState(msgspec.Struct, frozen=True):
    robot: Robot
    epoch: str
    stamp_s: float  # the daemon's monotonic clock: compare stamps, not with your clock
    behaviour: str
    mode: str
    paused: bool
    done: bool
    current_node: int | None
    current_edge: int | None
    goal_node: int | None
    x: float  # dead-reckoned pose
    y: float
    theta: float
    hypotheses: list[str]
    map_seq: NonNeg
    map_nodes: NonNeg
    map_edges: NonNeg
    unexplored: NonNeg
    error: str | None = None
    # The seq of the last event published before this state (0: none): a snapshot waits for it
    # because the event history arrives on its own subscription, after the state or not.
    event_seq: NonNeg = 0


class EventMsg(msgspec.Struct, frozen=True):
    robot: Robot
    epoch: str
    seq: NonNeg
    stamp_s: float
    kind: str
    text: Text


class ScanMsg(msgspec.Struct, frozen=True):
    robot: Robot
    stamp_s: float
    ranges_m: list[float | None]  # per transducer, counter-clockwise; None: no echo


class Command(msgspec.Struct, frozen=True):
    id: Annotated[str, msgspec.Meta(min_length=1, max_length=128)]
    op: str
    node: int | None = None  # goto only


class CommandReply(msgspec.Struct, frozen=True):
    id: str
    accepted: bool
    reason: str = ""


_NAMES = {
    NodeMsg: "node",
    EdgeMsg: "edge",
    MapSnapshot: "map snapshot",
    MapChange: "map change",
    RobotState: "robot state",
    EventMsg: "event",
    ScanMsg: "scan",
    Command: "command",
    CommandReply: "command reply",
}

M = TypeVar("M", bound=msgspec.Struct)

_encoder = msgspec.msgpack.Encoder()
_decoders: dict[type, msgspec.msgpack.Decoder[Any]] = {}


def encode(msg: msgspec.Struct) -> bytes:
    """MessagePack bytes of one message."""
    return _encoder.encode(msg)


def decode(data: bytes | bytearray | memoryview, cls: type[M]) -> M:
    """Decode and validate one ``cls``; raises ``LinkError("malformed <what>: ...")``."""
    dec = _decoders.get(cls)
    if dec is None:
        dec = _decoders[cls] = msgspec.msgpack.Decoder(cls)
    try:
        return dec.decode(data)
    except msgspec.DecodeError as e:  # ValidationError is a DecodeError
        raise LinkError(f"malformed {_NAMES.get(cls, cls.__name__)}: {e}") from None


def command_problem(cmd: Command) -> str | None:
    """Why the robot must refuse ``cmd`` before looking at it, or None if it is well formed."""
    if cmd.op not in OPS:
        return f"unknown op {cmd.op!r}: one of {', '.join(OPS)}"
    if cmd.op == "goto" and cmd.node is None:
        return "goto needs a node"
    if cmd.op == "goto" and cmd.node is not None and cmd.node < 0:
        return f"goto node {cmd.node} is not a node id"
    if cmd.op != "goto" and cmd.node is not None:
        return f"{cmd.op} takes no node"
    return None


def to_builtins(msg: Any) -> Any:
    """Plain dicts and lists of a message (for JSON output)."""
    return msgspec.to_builtins(msg)
