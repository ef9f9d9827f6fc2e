"""Keys, messages and configuration of the link: no network needed."""

from __future__ import annotations

import msgspec
import pytest

from tests.link_rig import DEPLOY
from tslam.link import LinkError
from tslam.link.config import LinkConfig, loopback, read_credentials, zenoh_config
from tslam.link.keys import ALL_ALIVE, LEAVES, key, robot_of
from tslam.link.schemas import (
    Command,
    CommandReply,
    EdgeMsg,
    EventMsg,
    MapChange,
    MapSnapshot,
    NodeMsg,
    RobotState,
    ScanMsg,
    command_problem,
    decode,
    encode,
    to_builtins,
)

NODE = NodeMsg(id=3, kind="meet", x=1.0, y=-2.5, clearance_m=0.8, degree=3, unexplored=1)
EDGE = EdgeMsg(id=0, u=3, v=4, length_m=2.25)
STATE = RobotState(
    robot="r1", epoch="e", stamp_s=12.5, behaviour="trace", mode="exploring", paused=False,
    done=False, current_node=None, current_edge=0, goal_node=None, x=1.0, y=2.0, theta=0.5,
    hypotheses=["3=7"], map_seq=4, map_nodes=2, map_edges=1, unexplored=3, error=None,
)  # fmt: skip
MESSAGES = [
    NODE,
    EDGE,
    MapSnapshot(robot="r1", epoch="e", seq=4, nodes=[NODE], edges=[EDGE]),
    MapChange(robot="r1", epoch="e", seq=5, op="merge", upsert_nodes=[NODE], remove_nodes=[7]),
    STATE,
    EventMsg(robot="r1", epoch="e", seq=1, stamp_s=1.0, kind="node", text="new node 3"),
    ScanMsg(robot="r1", stamp_s=1.0, ranges_m=[1.5, None, 6.5]),
    Command(id="c1", op="goto", node=4),
    CommandReply(id="c1", accepted=False, reason="no node 4"),
]


def test_keys_are_versioned_per_robot():
    assert key("robot-1_a", "state") == "tslam/v1/robot-1_a/state"
    assert key("r", "map/changes") == "tslam/v1/r/map/changes"
    assert set(LEAVES) == {"state", "scan", "map/changes", "map", "events", "cmd", "alive"}
    assert ALL_ALIVE == "tslam/v1/*/alive"
    assert robot_of("tslam/v1/r9/alive") == "r9" and robot_of("other/v1/r9/alive") is None


@pytest.mark.parametrize("bad", ["", "a/b", "a*", "a b", "ü", "**", "$x"])
def test_bad_robot_names_are_refused(bad):
    with pytest.raises(LinkError, match="robot name"):
        key(bad, "state")


def test_an_unknown_leaf_is_refused():
    with pytest.raises(LinkError, match="unknown key leaf 'status'"):
        key("r", "status")


@pytest.mark.parametrize("msg", MESSAGES, ids=lambda m: type(m).__name__)
def test_every_message_round_trips(msg):
    data = encode(msg)
    assert isinstance(data, bytes)
    assert decode(data, type(msg)) == msg
    assert isinstance(to_builtins(msg), dict)


def test_messages_are_frozen():
    with pytest.raises(AttributeError):
        NODE.x = 2.0  # type: ignore[misc]


@pytest.mark.parametrize(
    ("data", "cls", "expect"),
    [
        (b"\xc1", Command, "malformed command: MessagePack data is malformed"),
        (msgspec.msgpack.encode({"id": 1, "op": "pause"}), Command, "at `$.id`"),
        (msgspec.msgpack.encode({"id": "a"}), Command, "missing required field `op`"),
        (msgspec.msgpack.encode({"id": "", "op": "pause"}), Command, "at `$.id`"),
        (encode(NODE).replace(b"meet", b"mold"), NodeMsg, "malformed node: Invalid enum"),
        (encode(NODE).replace(b"\x03", b"\xff", 1), NodeMsg, "at `$.id`"),
        (
            msgspec.msgpack.encode(msgspec.structs.asdict(STATE) | {"robot": "a/b"}),
            RobotState,
            "malformed robot state",
        ),
        (
            msgspec.msgpack.encode({"robot": "r", "stamp_s": 1.0, "ranges_m": [1.0, "x"]}),
            ScanMsg,
            "at `$.ranges_m[1]`",
        ),
    ],
)
def test_malformed_payloads_name_the_message_and_field(data, cls, expect):
    with pytest.raises(LinkError) as e:
        decode(data, cls)
    assert str(e.value).startswith("malformed ") and expect in str(e.value)


def test_unknown_fields_are_ignored_for_forward_compatibility():
    data = msgspec.msgpack.encode({"id": "a", "op": "pause", "priority": 3})
    assert decode(data, Command) == Command(id="a", op="pause")


@pytest.mark.parametrize(
    ("cmd", "problem"),
    [
        (Command(id="a", op="pause"), None),
        (Command(id="a", op="goto", node=2), None),
        (Command(id="a", op="fly"), "unknown op 'fly'"),
        (Command(id="a", op="goto"), "goto needs a node"),
        (Command(id="a", op="goto", node=-1), "not a node id"),
        (Command(id="a", op="stop", node=1), "stop takes no node"),
    ],
)
def test_command_problems(cmd, problem):
    got = command_problem(cmd)
    assert got is None if problem is None else problem in got


def test_link_config_validation_names_the_field():
    with pytest.raises(LinkError, match="mode 'server'"):
        LinkConfig(mode="server")
    with pytest.raises(LinkError, match=r"listen endpoint '127\.0\.0\.1:7447'"):
        LinkConfig(listen=["127.0.0.1:7447"])
    with pytest.raises(LinkError, match="connect must be a list"):
        LinkConfig(connect="tcp/1.2.3.4:7447")  # type: ignore[arg-type]
    with pytest.raises(LinkError, match="user and password"):
        LinkConfig(user="alice")
    with pytest.raises(LinkError, match="lease_s"):
        LinkConfig(lease_s=0)
    with pytest.raises(LinkError, match="config_file"):
        LinkConfig(config_file="/nonexistent.json5")
    with pytest.raises(LinkError, match="client' needs at least one connect"):
        LinkConfig(mode="client")
    with pytest.raises(LinkError, match=r"\[daemon.link\]: unknown key 'endpoint'"):
        LinkConfig.from_mapping({"endpoint": "x"}, where="[daemon.link]")
    with pytest.raises(LinkError, match=r"\[link\]: link mode"):
        LinkConfig.from_mapping({"mode": 3})


def test_credentials_files(tmp_path):
    p = tmp_path / "c"
    p.write_text("# mine\n\nbob:s3cret\n")
    assert read_credentials(p) == ("bob", "s3cret")
    cfg = loopback(None, [7447]).with_credentials_file(p)
    assert (cfg.user, cfg.password) == ("bob", "s3cret")
    p.write_text("bob:pw:with:colons\n")
    with pytest.raises(LinkError, match="password holds a ':'"):
        read_credentials(p)
    p.write_text("bob\n")
    with pytest.raises(LinkError, match="line 1: expected user:password"):
        read_credentials(p)
    with pytest.raises(LinkError, match="credentials file"):
        read_credentials(tmp_path / "missing")


def test_zenoh_config_stays_on_loopback_without_multicast():
    conf = zenoh_config(loopback(7000, [7001, 7002]))
    assert conf.get_json("mode") == '"peer"'
    assert conf.get_json("listen/endpoints") == '["tcp/127.0.0.1:7000"]'
    assert conf.get_json("connect/endpoints") == '["tcp/127.0.0.1:7001","tcp/127.0.0.1:7002"]'
    assert conf.get_json("scouting/multicast/enabled") == "false"
    assert conf.get_json("scouting/gossip/enabled") == "false"
    assert conf.get_json("timestamping/enabled") == "true"
    assert conf.get_json("transport/link/tx/lease") == "1000"
    # No listen endpoint given: listen nowhere (zenoh's default is every interface).
    assert (
        zenoh_config(LinkConfig(connect=["tcp/127.0.0.1:1"])).get_json("listen/endpoints") == "[]"
    )


def test_a_config_file_may_turn_multicast_on_and_fields_override_it(tmp_path):
    f = tmp_path / "z.json5"
    f.write_text(
        '{ scouting: { multicast: { enabled: true } }, listen: { endpoints: ["tcp/0.0.0.0:9"] } }'
    )
    conf = zenoh_config(LinkConfig(config_file=str(f), user="u", password="p"))
    assert conf.get_json("scouting/multicast/enabled") == "true"
    assert conf.get_json("listen/endpoints") == '["tcp/0.0.0.0:9"]'
    assert conf.get_json("transport/auth/usrpwd/user") == '"u"'
    conf = zenoh_config(LinkConfig(config_file=str(f), listen=["tcp/127.0.0.1:5"]))
    assert conf.get_json("listen/endpoints") == '["tcp/127.0.0.1:5"]'


@pytest.mark.parametrize(
    ("name", "mode"),
    [
        ("loopback", "peer"),
        ("robot-peer", "peer"),
        ("laptop-client", "client"),
        ("fleet-router", "router"),
    ],
)
def test_the_deployed_zenoh_configs_load(name, mode):
    conf = zenoh_config(LinkConfig(mode=mode, config_file=str(DEPLOY / f"{name}.json5")))
    assert conf.get_json("mode") == f'"{mode}"'
    assert conf.get_json("scouting/multicast/enabled") == "false"
    if name in ("robot-peer", "fleet-router"):
        assert conf.get_json("access_control/enabled") == "true"
        assert conf.get_json("access_control/default_permission") == '"deny"'


def test_the_example_credentials_parse():
    assert read_credentials(DEPLOY / "credentials.example")[0] == "bob"
    users = (DEPLOY / "users.example.txt").read_text().split()
    assert all(u.count(":") >= 1 for u in users) and len(users) >= 3
