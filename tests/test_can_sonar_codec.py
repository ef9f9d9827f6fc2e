"""The CAN sonar codec against frames built by hand from the reference notes.

Golden frames here are computed with plain bit arithmetic from the protocol facts (command code in
byte 0, LSB-first bit numbering, 12-bit readings = low + 256 x high), never with cantools, so an
error in the DBC cannot hide behind the same error in the expectation.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drivers.can_sonar import codec
from drivers.can_sonar.codec import (
    AnalogIn,
    CanSonarError,
    CommandCode,
    Connect,
    ConnectReply,
    EncodeError,
    Frame,
    FrameError,
    GetAnalogIn,
    GetData,
    GetLegacyData,
    GroupData,
    LegacyData,
    ParameterSet,
    ParasetChunk,
    ParasetData,
    Reading,
    ReadingStatus,
    ReadParaset,
    Resolution,
    SetChannelActive,
    UnknownIdentifierError,
    UsBoardCodec,
    WriteAck,
    WriteParaset,
    paraset_byte_sum,
    paraset_from_chunks,
    paraset_to_chunks,
)

# Seeded, no example database: the same cases on every machine.
FUZZ = settings(max_examples=150, derandomize=True, database=None, deadline=None)

BASE = 0x400
CODEC = UsBoardCodec()
CM_PER_COUNT = {0: 1.0, 1: 0.5, 2: 0.25, 3: 0.125}  # the reference's resolution codes
INVALID = Reading(ReadingStatus.INVALID)
TOO_CLOSE = Reading(ReadingStatus.TOO_CLOSE)
NO_ECHO = Reading(ReadingStatus.NO_ECHO)


def command_bytes(code: int, arg: int = 0, arg_bytes: int = 0) -> bytes:
    """Byte 0 = command, then ``arg`` LSB-first from bit 8, zero-padded to 8 bytes."""
    return bytes([code, *((arg >> (8 * i)) & 0xFF for i in range(arg_bytes))]).ljust(8, b"\0")


def group_frame_bytes(group: int, res: int, counts: list[int], source_bits: int = 0xF) -> bytes:
    """Byte 1 = group | res << 2 | source << 4; bytes 2-5 low parts; high part k at bit 48 + 4k."""
    data = [0, group | res << 2 | source_bits << 4, *(c & 0xFF for c in counts), 0, 0]
    for k, c in enumerate(counts):
        bit = 48 + 4 * k
        data[bit // 8] |= (c >> 8) << (bit % 8)
    return bytes(data)


def some_paraset() -> ParameterSet:
    return ParameterSet(
        update_interval_s=0.2,
        warning_distances_m=tuple((40 + n) / 100 for n in range(16)),
        alarm_distances_m=tuple((20 + n) / 100 for n in range(16)),
        cross_echo=True,
        fire_intervals_s=(0.02, 0.03, 0.1, 2.56),
        bitrate=500_000,
        base_id=0x520,
    )


# --- golden frames: host -> board ---------------------------------------------------------------


def test_connect_is_code_0_and_seven_zero_bytes():
    frame = CODEC.connect()
    assert frame == Frame(BASE, bytes(8))
    assert CODEC.decode(frame) == Connect()


@pytest.mark.parametrize("mask", [0x0000, 0x0001, 0x8005, 0x1234, 0xFFFF])
def test_set_channel_active_puts_the_mask_at_bits_8_to_23(mask):
    expected = bytes([1, mask & 0xFF, mask >> 8, 0, 0, 0, 0, 0])
    assert CODEC.set_channels_active(mask) == Frame(BASE, expected)
    assert CODEC.decode(Frame(BASE, expected)) == SetChannelActive(mask)


@pytest.mark.parametrize("groups", [(0,), (3,), (0, 2), (1, 3), (0, 1, 2, 3)])
def test_get_data_puts_one_bit_per_group_at_bits_8_to_11(groups):
    bits = sum(1 << g for g in groups)
    expected = command_bytes(13, bits, 1)
    assert expected[1] == bits and expected[1] < 16
    assert CODEC.get_data(reversed(groups)) == Frame(BASE, expected)
    assert CODEC.decode(Frame(BASE, expected)) == GetData(groups)


@pytest.mark.parametrize(
    ("code", "build", "command"),
    [
        (2, lambda c: c.get_legacy_data(0), GetLegacyData(0)),
        (3, lambda c: c.get_legacy_data(1), GetLegacyData(1)),
        (6, lambda c: c.read_paraset(), ReadParaset()),
        (7, lambda c: c.get_analog_in(), GetAnalogIn()),
    ],
)
def test_commands_without_arguments_are_their_code_alone(code, build, command):
    assert build(CODEC) == Frame(BASE, command_bytes(code))
    assert CODEC.decode(Frame(BASE, command_bytes(code))) == command


def test_command_codes_are_the_reference_table():
    assert {c.name: c.value for c in CommandCode} == {
        "CONNECT": 0,
        "SET_CHANNEL_ACTIVE": 1,
        "GET_DATA_1_TO_8": 2,
        "GET_DATA_9_TO_16": 3,
        "WRITE_PARASET_RAM": 4,
        "WRITE_PARASET_EEPROM": 5,
        "READ_PARASET": 6,
        "GET_ANALOG_IN": 7,
        "GET_DATA": 13,
    }


# --- golden frames: group data ------------------------------------------------------------------


@pytest.mark.parametrize("res", [0, 1, 2, 3])
def test_group_data_frame_each_resolution(res):
    counts = [564, 3, 4095, 1000]
    data = group_frame_bytes(2, res, counts)
    assert data == bytes([0, 2 | res << 2 | 0xF0, 0x34, 0x03, 0xFF, 0xE8, 0x02, 0x3F])
    frame = Frame(BASE + 13 + 2, data)
    decoded = CODEC.decode(frame)
    expected_m = [c * CM_PER_COUNT[res] / 100 for c in counts]
    assert decoded == GroupData(2, Resolution(res), tuple(Reading.ok(m) for m in expected_m))
    assert [r.range_m for r in decoded.readings] == expected_m
    assert decoded.source is None
    assert CODEC.encode_reply(GroupData(2, res, [Reading.ok(m) for m in expected_m])) == frame


def test_reading_is_low_plus_256_times_high_not_a_shift_of_4():
    """The public driver's shift of 4 would read 0x34 + (2 << 4) = 84 counts here; 564 is right."""
    frame = Frame(BASE + 13, group_frame_bytes(0, 0, [0x234, 3, 3, 3]))
    reading = CODEC.decode(frame).readings[0]
    assert reading.range_m == 5.64
    assert reading.range_m != (0x34 + (0x2 << 4)) / 100


def test_resolution_is_a_fraction_of_a_cm_not_an_integer():
    """At 0.125 cm per count 7 counts are 0.875 cm: an integer resolution would give 0 or 7 cm."""
    frame = Frame(BASE + 13, group_frame_bytes(0, 3, [7, 8, 800, 4095]))
    assert [r.range_m for r in CODEC.decode(frame).readings] == [
        0.00875,
        0.01,
        1.0,
        4095 * 0.125 / 100,
    ]


def test_reserved_reading_values_are_kinds_of_no_reading():
    frame = Frame(BASE + 16, group_frame_bytes(3, 1, [0, 1, 2, 3]))
    readings = CODEC.decode(frame).readings
    assert [r.status for r in readings] == [
        ReadingStatus.INVALID,
        ReadingStatus.TOO_CLOSE,
        ReadingStatus.NO_ECHO,
        ReadingStatus.OK,
    ]
    assert [r.range_m for r in readings] == [None, None, None, 3 * 0.5 / 100]
    assert CODEC.encode_reply(GroupData(3, 1, (INVALID, TOO_CLOSE, NO_ECHO, readings[3]))) == frame


def test_reserved_values_are_of_the_whole_12_bit_reading():
    """A low byte of 0, 1 or 2 with a non-zero high part is a distance, not a reserved value."""
    frame = Frame(BASE + 13, group_frame_bytes(0, 0, [256, 257, 258, 0x200]))
    readings = CODEC.decode(frame).readings
    assert [r.status for r in readings] == [ReadingStatus.OK] * 4
    assert [r.range_m for r in readings] == [2.56, 2.57, 2.58, 5.12]


@pytest.mark.parametrize(("bits", "source"), [(0b0001, 0), (0b0010, 1), (0b0100, 2), (0b1000, 3)])
def test_signal_source_bit_names_the_source(bits, source):
    frame = Frame(BASE + 14, group_frame_bytes(1, 0, [100, 200, 300, 400], source_bits=bits))
    decoded = CODEC.decode(frame)
    assert decoded.source == source
    assert CODEC.encode_reply(decoded) == frame


def test_group_measured_range_rounds_to_the_nearest_count():
    reply = GroupData(0, Resolution.CM_1, [Reading.ok(1.234), Reading.ok(1.236), NO_ECHO, NO_ECHO])
    low = CODEC.encode_reply(reply).data[2:4]
    assert list(low) == [123 & 0xFF, 124 & 0xFF]


# --- golden frames: the other replies -----------------------------------------------------------


def test_connect_reply_is_base_plus_1():
    frame = Frame(BASE + 1, bytes(8))
    assert CODEC.encode_reply(ConnectReply()) == frame
    assert CODEC.decode(frame) == ConnectReply()


def test_legacy_data_is_one_byte_per_sensor_in_cm_from_byte_2():
    frame = Frame(BASE + 3, bytes([0, 0, 50, 1, 2, 255, 0, 0]))
    decoded = CODEC.decode(frame)
    assert decoded == LegacyData(1, (Reading.ok(0.5), TOO_CLOSE, NO_ECHO, Reading.ok(2.55)))
    assert CODEC.encode_reply(decoded) == frame
    assert CODEC.decode(Frame(BASE + 5, bytes([0, 0, 0, 3, 4, 5, 0, 0]))).readings[0] == INVALID


def test_analog_inputs_are_four_12_bit_values():
    counts = [0x123, 0xFFF, 0x000, 0x800]
    data = bytes([0, 0, 0x23, 0xFF, 0x00, 0x00, 0x1 | 0xF << 4, 0x0 | 0x8 << 4])
    assert CODEC.encode_reply(AnalogIn(counts)) == Frame(BASE + 7, data)
    assert CODEC.decode(Frame(BASE + 7, data)) == AnalogIn(tuple(counts))


def test_parameter_set_frames_by_hand():
    params = some_paraset()
    reply = CODEC.paraset_reply(params)
    assert [f.arbitration_id for f in reply] == [BASE + 6] * 9
    # frame 0: bitrate code 1 (500k), base 0x520 LSB first, update (3 + 1) x 50 ms, cross echo on
    assert reply[0].data == bytes([0, 0, 1, 0x20, 0x05, 3, 1, 0])
    # frame 2: group 1 fire interval (2 + 1) x 10 ms, warning distances of sensors 4-7 in cm
    assert reply[2].data == bytes([0, 2, 2, 44, 45, 46, 47, 0])
    # frame 8: alarm distances of sensors 12-15 in cm
    assert reply[8].data == bytes([0, 8, 32, 33, 34, 35, 0, 0])
    assert reply[4].data[2] == 255  # 2.56 s = (255 + 1) x 10 ms
    writes = CODEC.write_paraset(params)
    assert [f.data[0] for f in writes] == [4] * 9
    assert [f.data[1:] for f in writes] == [f.data[1:] for f in reply]
    eeprom = CODEC.write_paraset(params, eeprom=True)
    assert [f.data[0] for f in eeprom] == [5] * 9
    assert paraset_from_chunks(CODEC.decode(f).chunk for f in reversed(reply)) == params
    decoded_writes = [CODEC.decode(f) for f in eeprom]
    assert all(isinstance(w, WriteParaset) and w.eeprom for w in decoded_writes)
    assert paraset_from_chunks(w.chunk for w in decoded_writes) == params


def test_write_acknowledgements_and_the_byte_sum():
    params = some_paraset()
    by_hand = sum(b for f in CODEC.paraset_reply(params) for b in f.data[2:]) % 65536
    chunks = paraset_to_chunks(params)
    assert paraset_byte_sum(chunks) == by_hand
    ram = Frame(BASE + 8, bytes([0, 3, 0, 0, 0, 0, 0, 0]))
    assert CODEC.encode_reply(WriteAck(3)) == ram
    assert CODEC.decode(ram) == WriteAck(3, eeprom=False, byte_sum=None)
    final = Frame(BASE + 9, bytes([0, 8, by_hand & 0xFF, by_hand >> 8, 0, 0, 0, 0]))
    assert CODEC.encode_reply(WriteAck(8, eeprom=True, byte_sum=by_hand)) == final
    assert CODEC.decode(final) == WriteAck(8, eeprom=True, byte_sum=by_hand)


def test_parameter_set_defaults_from_the_reference():
    params = ParameterSet(0.5, [1.0] * 16, [0.5] * 16)
    assert params.fire_intervals_s == (0.02,) * 4
    assert params.bitrate == 1_000_000 and params.base_id == 0x400
    assert paraset_to_chunks(params)[1].payload[0] == 1  # 20 ms = (1 + 1) x 10 ms


@pytest.mark.parametrize(("seconds", "n"), [(0.2, 3), (0.5, 9), (1.0, 19), (2.0, 39), (0.05, 0)])
def test_update_interval_is_n_plus_1_times_50_ms(seconds, n):
    params = ParameterSet(seconds, [1.0] * 16, [0.5] * 16)
    assert paraset_to_chunks(params)[0].payload[3] == n


# --- identifiers --------------------------------------------------------------------------------


def one_of_each(c: UsBoardCodec) -> list[Frame]:
    params = some_paraset()
    return [
        c.connect(),
        c.set_channels_active(0x00F0),
        c.get_legacy_data(0),
        c.get_legacy_data(1),
        *c.write_paraset(params)[:1],
        *c.write_paraset(params, eeprom=True)[:1],
        c.read_paraset(),
        c.get_analog_in(),
        c.get_data([0, 3]),
        c.encode_reply(ConnectReply()),
        *(c.encode_reply(LegacyData(b, [Reading.ok(0.1)] * 4)) for b in range(4)),
        *c.paraset_reply(params)[:1],
        c.encode_reply(AnalogIn((1, 2, 3, 4))),
        c.encode_reply(WriteAck(0)),
        c.encode_reply(WriteAck(8, eeprom=True, byte_sum=7)),
        *(c.encode_reply(GroupData(g, 0, [Reading.ok(1.0)] * 4)) for g in range(4)),
    ]


def test_every_identifier_is_an_offset_from_the_base():
    offsets = {f.arbitration_id - BASE for f in one_of_each(CODEC)}
    assert offsets == {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 13, 14, 15, 16}


@pytest.mark.parametrize("base", [0x500, 0x000, 0x123, codec.MAX_BASE_ID])
def test_changing_the_base_moves_every_identifier(base):
    moved = UsBoardCodec(base)
    default_frames, moved_frames = one_of_each(CODEC), one_of_each(moved)
    for default, frame in zip(default_frames, moved_frames, strict=True):
        assert frame.arbitration_id == default.arbitration_id - BASE + base
        assert frame.data == default.data
        assert moved.decode(frame) == CODEC.decode(default)
        if base != BASE:
            with pytest.raises(FrameError):
                moved.decode(default)


def test_a_frame_of_the_default_base_is_unknown_to_a_moved_board():
    with pytest.raises(
        UnknownIdentifierError, match=r"0x400 is not a frame of a board at base 0x500"
    ):
        UsBoardCodec(0x500).decode(CODEC.connect())
    assert not UsBoardCodec(0x500).owns(0x40D)
    assert UsBoardCodec(0x500).owns(0x50D)


@pytest.mark.parametrize("base", [-1, codec.MAX_BASE_ID + 1, 0x800])
def test_a_base_that_leaves_11_bits_is_refused(base):
    with pytest.raises(EncodeError, match="base identifier"):
        UsBoardCodec(base)


# --- the DBC itself -----------------------------------------------------------------------------


def test_dbc_frames_are_8_bytes_unsigned_lsb_first_at_the_default_base():
    db = codec.database()
    assert {m.frame_id - 0x400 for m in db.messages} == {
        0,
        1,
        2,
        3,
        4,
        5,
        6,
        7,
        8,
        9,
        13,
        14,
        15,
        16,
    }
    for message in db.messages:
        assert message.length == 8, message.name
        for signal in message.signals:
            assert signal.byte_order == "little_endian", signal.name
            assert not signal.is_signed, signal.name


def test_dbc_value_tables_agree_with_the_codec():
    db = codec.database()
    command = db.get_message_by_name("HostCommand").get_signal_by_name("Command")
    assert {int(k): str(v) for k, v in command.choices.items()} == {
        c.value: c.name for c in CommandCode
    }
    resolution = db.get_message_by_name("GroupData1").get_signal_by_name("Resolution")
    for code, name in resolution.choices.items():
        assert float(str(name).removesuffix(" cm")) / 100 == Resolution(code).metres_per_count
    bitrate = db.get_message_by_name("ParameterSet").get_signal_by_name("BitrateCode")
    assert {str(v): int(k) for k, v in bitrate.choices.items()} == {
        f"{b // 1000} kbit/s": c for b, c in codec.BITRATE_CODES.items()
    }
    low = db.get_message_by_name("GroupData4").get_signal_by_name("Sensor13Low")
    assert {int(k): str(v) for k, v in low.choices.items()} == {
        0: "invalid",
        1: "too close",
        2: "no echo",
    }


def test_dbc_records_the_decisions():
    db = codec.database()
    group = db.get_message_by_name("GroupData1").comment
    assert "shift of 4" in group and "low + 256 x high" in group and "fraction of a cm" in group
    assert "8 bytes" in db.get_message_by_name("HostCommand").comment
    byte_sum = db.get_message_by_name("WriteAckRam").get_signal_by_name("ByteSum").comment
    assert "54 parameter bytes" in byte_sum
    assert "(n+1) x 50 ms" in (
        db.get_message_by_name("ParameterSet").get_signal_by_name("UpdateInterval").comment
    )


def test_codec_imports_nothing_of_ours_and_no_io_library():
    tree = ast.parse(Path(codec.__file__).read_text())
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            imported.add((node.module or "").split(".")[0])
    assert imported <= {
        "__future__",
        "enum",
        "math",
        "collections",
        "dataclasses",
        "importlib",
        "typing",
        "cantools",
    }


# --- round trips --------------------------------------------------------------------------------


resolutions = st.sampled_from(list(Resolution))
reserved = st.sampled_from([INVALID, TOO_CLOSE, NO_ECHO])
bases = st.integers(0, codec.MAX_BASE_ID)


@st.composite
def group_data(draw):
    res = draw(resolutions)
    distance = st.integers(3, 4095).map(lambda c: Reading.ok(c / res.counts_per_metre))
    readings = draw(st.lists(st.one_of(reserved, distance), min_size=4, max_size=4))
    source = draw(st.one_of(st.none(), st.integers(0, 3)))
    return GroupData(draw(st.integers(0, 3)), res, tuple(readings), source)


@st.composite
def parameter_sets(draw):
    cm = st.integers(0, 255).map(lambda c: c / 100)
    return ParameterSet(
        update_interval_s=draw(st.integers(1, 256)) / 20,
        warning_distances_m=tuple(draw(st.lists(cm, min_size=16, max_size=16))),
        alarm_distances_m=tuple(draw(st.lists(cm, min_size=16, max_size=16))),
        cross_echo=draw(st.booleans()),
        fire_intervals_s=tuple(
            draw(st.lists(st.integers(1, 256).map(lambda n: n / 100), min_size=4, max_size=4))
        ),
        bitrate=draw(st.sampled_from(sorted(codec.BITRATE_CODES))),
        base_id=draw(bases),
    )


chunks = parameter_sets().flatmap(lambda p: st.sampled_from(paraset_to_chunks(p)))
commands = st.one_of(
    st.just(Connect()),
    st.integers(0, 0xFFFF).map(SetChannelActive),
    st.integers(0, 1).map(GetLegacyData),
    st.builds(WriteParaset, chunks, st.booleans()),
    st.just(ReadParaset()),
    st.just(GetAnalogIn()),
    st.sets(st.integers(0, 3), min_size=1).map(lambda g: GetData(tuple(g))),
)
legacy = st.builds(
    LegacyData,
    st.integers(0, 3),
    st.lists(
        st.one_of(reserved, st.integers(3, 255).map(lambda c: Reading.ok(c / 100))),
        min_size=4,
        max_size=4,
    ).map(tuple),
)
acks = st.one_of(
    st.builds(WriteAck, st.integers(0, 7), st.booleans()),
    st.builds(WriteAck, st.just(8), st.booleans(), st.integers(0, 0xFFFF)),
)
replies = st.one_of(
    st.just(ConnectReply()),
    legacy,
    chunks.map(ParasetData),
    st.lists(st.integers(0, 0xFFF), min_size=4, max_size=4).map(lambda c: AnalogIn(tuple(c))),
    acks,
    group_data(),
)


@FUZZ
@given(reply=group_data(), base=bases)
def test_group_data_round_trips(reply, base):
    c = UsBoardCodec(base)
    frame = c.encode_reply(reply)
    assert frame.arbitration_id == base + 13 + reply.group
    assert c.decode_reply(frame) == reply


@FUZZ
@given(
    group=st.integers(0, 3),
    res=st.integers(0, 3),
    source_bits=st.sampled_from([1, 2, 4, 8, 15]),
    counts=st.lists(st.integers(0, 0xFFF), min_size=4, max_size=4),
)
def test_every_valid_group_frame_decodes_and_encodes_back_to_its_bytes(
    group, res, source_bits, counts
):
    frame = Frame(BASE + 13 + group, group_frame_bytes(group, res, counts, source_bits))
    decoded = CODEC.decode(frame)
    for count, reading in zip(counts, decoded.readings, strict=True):
        if count > 2:
            assert math.isclose(reading.range_m, count * CM_PER_COUNT[res] / 100, rel_tol=1e-15)
    assert CODEC.encode_reply(decoded) == frame


@FUZZ
@given(command=commands, base=bases)
def test_commands_round_trip(command, base):
    c = UsBoardCodec(base)
    frame = c.encode_command(command)
    assert frame.arbitration_id == base and len(frame.data) == 8
    assert c.decode(frame) == command


@FUZZ
@given(reply=replies, base=bases)
def test_replies_round_trip(reply, base):
    c = UsBoardCodec(base)
    frame = c.encode_reply(reply)
    assert frame.arbitration_id > base and len(frame.data) == 8
    assert c.decode(frame) == reply


@FUZZ
@given(params=parameter_sets(), eeprom=st.booleans())
def test_parameter_sets_round_trip_through_writes_and_reads(params, eeprom):
    written = [CODEC.decode(f).chunk for f in CODEC.write_paraset(params, eeprom=eeprom)]
    assert paraset_from_chunks(written) == params
    read = [CODEC.decode(f).chunk for f in CODEC.paraset_reply(params)]
    assert paraset_from_chunks(reversed(read)) == params
    assert paraset_byte_sum(written) == sum(sum(c.payload) for c in read) % 65536


# --- malformed input ----------------------------------------------------------------------------


@pytest.mark.parametrize("ident", [BASE, BASE + 1, BASE + 6, BASE + 13])
@pytest.mark.parametrize("length", [0, 1, 7, 9])
def test_wrong_dlc_is_refused_naming_it(ident, length):
    with pytest.raises(
        FrameError, match=rf"has DLC {length}; every frame of this board is 8 bytes"
    ):
        CODEC.decode(Frame(ident, bytes(length)))


@pytest.mark.parametrize("ident", [BASE - 1, BASE + 10, BASE + 12, BASE + 17, 0x7FF])
def test_unknown_identifier_is_refused_naming_it(ident):
    with pytest.raises(UnknownIdentifierError, match=rf"0x{ident:03X} is not a frame of a board"):
        CODEC.decode(Frame(ident, bytes(8)))
    assert not CODEC.owns(ident)


@pytest.mark.parametrize("ident", [-1, 0x800, 0x1FFFFFFF])
def test_non_standard_identifier_is_refused(ident):
    with pytest.raises(FrameError, match="not a standard 11-bit identifier"):
        CODEC.decode(Frame(ident, bytes(8)))


@pytest.mark.parametrize("code", [8, 9, 12, 14, 255])
def test_unknown_command_code_is_refused_naming_it(code):
    with pytest.raises(FrameError, match=rf"unknown command code {code} "):
        CODEC.decode(Frame(BASE, command_bytes(code)))


def test_a_command_is_not_a_reply_and_a_reply_is_not_a_command():
    with pytest.raises(FrameError, match="host command identifier, not a board reply"):
        CODEC.decode_reply(CODEC.connect())
    with pytest.raises(FrameError, match="ConnectReply, not a host command"):
        CODEC.decode_command(CODEC.encode_reply(ConnectReply()))


@pytest.mark.parametrize(
    ("frame", "message"),
    [
        (Frame(BASE, command_bytes(13, 0, 1)), r"RequestedGroups = 0 is outside its range 1\.\.15"),
        (Frame(BASE, command_bytes(4, 9, 1)), r"ParasetFrameIndex = 9 is outside its range 0\.\.8"),
        (Frame(BASE, bytes([5, 0, 6, 0, 4, 0, 0, 0])), r"BitrateCode = 6 is outside"),
        (Frame(BASE + 6, bytes([0, 0, 0, 0, 4, 0, 2, 0])), r"CrossEchoMode = 2 is outside"),
        (Frame(BASE + 6, bytes([0, 0, 0, 0xF0, 7, 0, 0, 0])), r"BaseIdentifier = 2032 is outside"),
        (Frame(BASE + 8, bytes([0, 9, 0, 0, 0, 0, 0, 0])), r"AckFrameIndex = 9 is outside"),
        (Frame(BASE + 13, group_frame_bytes(1, 0, [9] * 4)), r"byte 1 names group 1"),
        (Frame(BASE + 13, group_frame_bytes(0, 0, [9] * 4, 0b0011)), r"signal source bits 0b0011"),
        (Frame(BASE + 13, group_frame_bytes(0, 0, [9] * 4, 0)), r"SignalSource = 0 is outside"),
    ],
)
def test_malformed_fields_are_refused_naming_the_field(frame, message):
    with pytest.raises(FrameError, match=message):
        CODEC.decode(frame)


def test_an_incomplete_or_repeated_parameter_set_is_refused():
    chunks = paraset_to_chunks(some_paraset())
    with pytest.raises(FrameError, match=r"incomplete: frame\(s\) \[4, 7\] missing"):
        paraset_from_chunks(c for c in chunks if c.index not in (4, 7))
    with pytest.raises(FrameError, match="frame 3 appears twice"):
        paraset_from_chunks([*chunks, chunks[3]])


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: CODEC.set_channels_active(0x10000), r"active sensor mask = 65536 is outside"),
        (lambda: CODEC.set_channels_active(-1), r"active sensor mask = -1 is outside"),
        (lambda: CODEC.set_channels_active(1.0), r"active sensor mask must be an int"),
        (lambda: CODEC.get_data([4]), r"group = 4 is outside 0\.\.3"),
        (lambda: CODEC.get_data([]), r"at least one group"),
        (lambda: CODEC.get_legacy_data(2), r"legacy data bank = 2 is outside"),
        (lambda: CODEC.encode_command(ConnectReply()), r"not a host command"),
        (lambda: CODEC.encode_reply(Connect()), r"not a board reply"),
        (lambda: GroupData(0, 4, [NO_ECHO] * 4), r"unknown resolution code 4"),
        (lambda: GroupData(0, 0, [NO_ECHO] * 3), r"exactly 4 Reading values"),
        (lambda: GroupData(0, 0, [NO_ECHO] * 4, source=4), r"signal source = 4 is outside"),
        (lambda: Reading.ok(-0.1), r"finite range >= 0"),
        (lambda: Reading.ok(math.nan), r"finite range >= 0"),
        (lambda: Reading(ReadingStatus.NO_ECHO, 1.0), r"'no echo' reading has no range"),
        (lambda: AnalogIn((0, 0, 0, 4096)), r"analog input 3 = 4096 is outside"),
        (lambda: WriteAck(3, byte_sum=5), r"only the acknowledgement of frame 8"),
        (lambda: WriteAck(8), r"must carry the byte sum"),
        (lambda: WriteAck(8, byte_sum=0x10000), r"byte sum = 65536 is outside"),
        (lambda: ParasetChunk(9, bytes(6)), r"frame index = 9 is outside"),
        (lambda: ParasetChunk(0, bytes(5)), r"needs 6 payload bytes"),
        (lambda: ParameterSet(0.5, [1.0] * 15, [0.5] * 16), r"warning_distances_m needs 16"),
    ],
)
def test_out_of_range_values_are_refused_naming_them(build, message):
    with pytest.raises(EncodeError, match=message):
        build()


@pytest.mark.parametrize(
    ("reading", "res", "message"),
    [
        (Reading.ok(0.02), Resolution.CM_1, r"sent as a reserved value; send .*TOO_CLOSE"),
        (Reading.ok(0.0), Resolution.CM_0_125, r"reserved value"),
        (Reading.ok(40.955), Resolution.CM_1, r"beyond 40\.95 m"),
        (Reading.ok(5.12), Resolution.CM_0_125, r"beyond 5\.11875 m"),
    ],
)
def test_a_range_that_does_not_fit_12_bits_is_refused(reading, res, message):
    with pytest.raises(EncodeError, match=message):
        CODEC.encode_reply(GroupData(0, res, [reading, NO_ECHO, NO_ECHO, NO_ECHO]))


def test_a_legacy_range_beyond_one_byte_is_refused():
    with pytest.raises(EncodeError, match=r"legacy reading of sensor 5: 2\.56 m is beyond 2\.55 m"):
        CODEC.encode_reply(LegacyData(1, [NO_ECHO, Reading.ok(2.56), NO_ECHO, NO_ECHO]))


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"update_interval_s": 0.051}, r"update interval = 0\.051 s is not a multiple of 0\.05 s"),
        ({"update_interval_s": 0.0}, r"update interval = 0\.0 s is outside 0\.05\.\.12\.8 s"),
        ({"update_interval_s": 12.85}, r"update interval = 12\.85 s is outside"),
        ({"fire_intervals_s": (0.02, 0.02, 0.0, 0.02)}, r"fire interval of group 2 = 0\.0 s"),
        ({"warning_distances_m": (2.56,) * 16}, r"warning distance of sensor 0 = 2\.56 m"),
        ({"alarm_distances_m": (0.305,) * 16}, r"alarm distance of sensor 0 = 0\.305 m is not"),
        ({"bitrate": 115_200}, r"bitrate 115200 bit/s is not one the board knows"),
        ({"base_id": 0x7F0}, r"base identifier = 2032 is outside"),
        ({"cross_echo": 1}, r"cross_echo must be a bool"),
        ({"update_interval_s": math.inf}, r"update interval must be a finite number"),
    ],
)
def test_a_parameter_set_off_its_grid_or_range_is_refused(change, message):
    params = ParameterSet(**{**vars_of(some_paraset()), **change})
    with pytest.raises(EncodeError, match=message):
        CODEC.write_paraset(params)


def test_a_hand_made_bad_chunk_is_refused_when_encoded():
    with pytest.raises(EncodeError, match="BitrateCode = 9 is outside"):
        CODEC.encode_reply(ParasetData(ParasetChunk(0, bytes([9, 0, 4, 0, 0, 0]))))


def test_every_error_is_a_can_sonar_error():
    assert issubclass(FrameError, CanSonarError)
    assert issubclass(UnknownIdentifierError, FrameError)
    assert issubclass(EncodeError, CanSonarError) and issubclass(EncodeError, ValueError)


def vars_of(params: ParameterSet) -> dict:
    return {name: getattr(params, name) for name in ParameterSet.__dataclass_fields__}
