"""The Nomad 200 codec against the protocol reference: golden and hand-built frames, round trips.

Expected bytes are built here from the reference's rules with tiny helpers of the test's own
(``hand_frame``, ``sm16``...), never with the codec, so a shared mistake cannot hide.
"""

from __future__ import annotations

import math
import random
import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drivers.nomad200 import units
from drivers.nomad200.codec import (
    COMMANDS,
    Ac,
    BumperReply,
    ChecksumError,
    CompassCalibrationReply,
    CompassMode,
    CompassReply,
    ConfCp,
    ConfigurationReply,
    ConfIr,
    ConfLs,
    ConfSg,
    ConfSn,
    ConfTm,
    Ct,
    Da,
    Dp,
    Frame,
    FrameDecoder,
    FramingError,
    GetBp,
    GetCp,
    GetIr,
    GetLs,
    GetRa,
    GetRc,
    GetRv,
    GetSg,
    GetSn,
    Gs,
    IrReply,
    LengthError,
    Lp,
    Mv,
    MvAxis,
    MvMode,
    Nak,
    NakReply,
    Opcode,
    Pa,
    PayloadError,
    PosData,
    Pr,
    ProtocolError,
    RawReply,
    SetupLs,
    SonarReply,
    Sp,
    Special,
    St,
    State,
    StateLayout,
    StateMask,
    StateReply,
    Tk,
    UnexpectedReplyError,
    UnknownOpcodeError,
    VelocityReply,
    Vm,
    Ws,
    Zr,
    decode_frame,
    decode_reply,
    decode_request,
    encode_reply,
    encode_request,
)
from drivers.nomad200.integers import decode_s16, decode_s32, encode_s16, encode_s32, encode_u16

FUZZ = settings(derandomize=True, max_examples=200, deadline=None)

# --- the test's own reading of the reference --------------------------------------------------


def cat(*parts: list[int] | bytes) -> list[int]:
    return [b for part in parts for b in part]


def hand_frame(opcode: int, payload: list[int] | bytes) -> bytes:
    """01 | LEN lo hi | TYPE | payload | CHK | 5C, LEN = TYPE + payload + CHK."""
    length = len(payload) + 2
    head = [0x01, length % 256, length // 256, opcode, *payload]
    return bytes([*head, sum(head) % 256, 0x5C])


def sm16(n: int) -> list[int]:
    m = abs(n)
    return [m % 256, m // 256 + (128 if n < 0 else 0)]


def u16(n: int) -> list[int]:
    return [n % 256, n // 256]


def sm32(n: int) -> list[int]:
    m = abs(n)
    return [m % 256, (m >> 8) % 256, (m >> 16) % 256, (m >> 24) + (128 if n < 0 else 0)]


def u32(n: int) -> list[int]:
    return [(n >> shift) % 256 for shift in (0, 8, 16, 24)]


def pos_bytes(p: PosData) -> list[int]:
    signed = [p.x, p.y, p.steer, p.turret, p.vel_trans, p.vel_steer, p.vel_turret]
    return [b for v in signed for b in sm32(v)] + u32(p.config_time) + u32(p.sense_time)


def tail(motor: int, clock: int, cpu: int, mot_v: int) -> list[int]:
    return [motor, *u32(clock), cpu, mot_v]


# --- golden frames from the reference's worked examples ----------------------------------------

GOLDEN = [
    (Gs(), "01 02 00 07 0a 5c"),
    (Vm(100, -450, 0), "01 08 00 05 64 00 c2 81 00 00 b5 5c"),
    (ConfTm(5), "01 03 00 12 05 1b 5c"),
    (Zr(), "01 02 00 0d 10 5c"),
]


@pytest.mark.parametrize(("command", "wire"), GOLDEN, ids=[g[1] for g in GOLDEN])
def test_golden_frames_encode_byte_for_byte(command, wire):
    assert encode_request(command) == bytes.fromhex(wire)


@pytest.mark.parametrize(("command", "wire"), GOLDEN, ids=[g[1] for g in GOLDEN])
def test_golden_frames_decode(command, wire):
    assert decode_request(bytes.fromhex(wire)) == command


def test_golden_frames_agree_with_the_hand_builder():
    # Guards the test helper itself: it must reproduce the reference's own examples.
    assert hand_frame(0x07, []) == bytes.fromhex("01 02 00 07 0a 5c")
    assert hand_frame(0x05, [*sm16(100), *sm16(-450), *sm16(0)]) == bytes.fromhex(GOLDEN[1][1])
    assert hand_frame(0x12, [5]) == bytes.fromhex("01 03 00 12 05 1b 5c")


# --- requests built by hand -------------------------------------------------------------------

HAND_REQUESTS = [
    (Ac(300, 450, 450), hand_frame(1, cat(u16(300), u16(450), u16(450)))),
    (Sp(200, 65535, 0), hand_frame(2, cat(u16(200), [0xFF, 0xFF], u16(0)))),
    (Pr(-1000, 900, -32767), hand_frame(3, cat(sm16(-1000), sm16(900), [0xFF, 0xFF]))),
    (Pa(1, -1, 256), hand_frame(4, [1, 0, 1, 0x80, 0, 1])),
    (Dp(-5, 7), hand_frame(12, cat(sm16(-5), sm16(7)))),
    (Da(3600, -900), hand_frame(30, cat(sm16(3600), sm16(-900)))),
    (Tk("hi"), hand_frame(11, [ord("h"), ord("i"), 0])),
    (ConfCp(CompassMode.CALIBRATE), hand_frame(16, [2])),
    (Ws(True, False, True, 30), hand_frame(31, [1, 0, 1, 30])),
    (
        ConfSn(15, (0, 2, 15, 1, 14, 3, 13, 4, 12, 5, 11, 6, 10, 7, 9, 8)),
        hand_frame(15, [15, 0, 2, 15, 1, 14, 3, 13, 4, 12, 5, 11, 6, 10, 7, 9, 8]),
    ),
    (ConfSn(0, ()), hand_frame(15, [0, *[255] * 16])),
    (ConfIr(5, (0, 1, 15)), hand_frame(14, [5, 0, 1, 15, *[255] * 13])),
    (
        Mv(MvAxis(MvMode.VM, -200), MvAxis(MvMode.IGNORE), MvAxis(MvMode.PR, 450)),
        hand_frame(43, cat(u16(1), sm16(-200), u16(0), sm16(0), u16(2), sm16(450))),
    ),
    (
        Ct(
            StateMask(
                ir={0, 9},
                sonar={1, 15},
                bumper=True,
                turret=True,
                vel_turret=True,
                laser=True,
                compass=True,
                pos_sonar=True,
                pos_compass=True,
            )
        ),
        # bytes: IR 1-8, IR 9-16, sonar 1-8, sonar 9-16, bumper/conf/vel, laser, compass+pos bits
        hand_frame(6, [0x01, 0x02, 0x02, 0x80, 0b1001_0001, 0x01, 0b0010_0101]),
    ),
    (GetSn(), hand_frame(20, [])),
    (Special(b"\x01\x5c\x00"), hand_frame(128, [0x01, 0x5C, 0x00])),
]


@pytest.mark.parametrize(("command", "wire"), HAND_REQUESTS, ids=lambda v: type(v).__name__)
def test_requests_match_frames_built_by_hand(command, wire):
    assert encode_request(command) == wire
    assert decode_request(wire) == command


def test_lengths_are_those_of_the_reference_table():
    lengths = {
        Ac(0, 0, 0): 8,
        Ct(StateMask()): 9,
        Gs(): 2,
        Tk("abc"): 6,
        Dp(0, 0): 6,
        ConfIr(0, ()): 19,
        ConfSn(0, ()): 19,
        ConfCp(0): 3,
        ConfTm(0): 3,
        Da(0, 0): 6,
        Ws(False, False, False, 0): 6,
        Mv(): 14,
    }
    for command, length in lengths.items():
        wire = encode_request(command)
        assert wire[1] + 256 * wire[2] == length, command
        assert len(wire) == length + 4


def test_order_list_decoding_stops_at_the_first_255():
    # The original client sends whatever its array holds after the terminator; it means nothing.
    wire = hand_frame(15, [15, 3, 4, 255, 7, 7, 0, *[9] * 10])
    assert decode_request(wire) == ConfSn(15, (3, 4))


# --- replies built by hand --------------------------------------------------------------------

POS_A = PosData(10, -20, 30, -40, 50, -60, 70, 123456, 4_000_000_000)
POS_B = PosData(-(2**31 - 1), 2**31 - 1, 0, 1, -1, 2, -2, 0, 1)


def test_get_rc_and_get_rv_replies_by_hand():
    mask = StateMask()
    rc = hand_frame(21, cat(sm16(-120), sm16(340), sm16(-3599), sm16(0)))
    assert decode_reply(rc, mask, request=Opcode.GET_RC) == ConfigurationReply(-120, 340, -3599, 0)
    rv = hand_frame(22, cat(sm16(200), sm16(-450), sm16(1)))
    assert decode_reply(rv, mask, request=Opcode.GET_RV) == VelocityReply(200, -450, 1)
    assert encode_reply(VelocityReply(200, -450, 1), mask) == rv


def test_get_sn_reply_with_and_without_pos_by_hand():
    ranges = list(range(6, 22))
    plain = hand_frame(20, cat(ranges, u32(987654)))
    assert decode_reply(plain, StateMask()) == SonarReply(tuple(ranges), None, 987654)
    with_pos = hand_frame(20, cat(ranges, pos_bytes(POS_A) * 16, u32(5)))
    reply = decode_reply(with_pos, StateMask(pos_sonar=True))
    assert reply == SonarReply(tuple(ranges), (POS_A,) * 16, 5)
    assert encode_reply(reply, StateMask(pos_sonar=True)) == with_pos


def test_bumper_bytes_arrive_reversed():
    wire = hand_frame(27, [0x01, 0x02, 0x03, *u32(9)])
    reply = decode_reply(wire, StateMask())
    assert reply == BumperReply(0x03 + 256 * 0x02 + 65536 * 0x01, None, 9)
    assert encode_reply(reply, StateMask()) == wire


def test_get_ir_get_cp_and_calibration_replies_by_hand():
    readings = list(range(16))
    packed = [lo | hi << 4 for lo, hi in zip(readings[::2], readings[1::2], strict=True)]
    ir = hand_frame(19, cat(packed, u32(1)))
    assert decode_reply(ir, StateMask()) == IrReply(tuple(readings), None, 1)
    cp = hand_frame(24, cat(u16(3599), pos_bytes(POS_B), u32(2)))
    assert decode_reply(cp, StateMask(pos_compass=True)) == CompassReply(3599, POS_B, 2)
    calibration = hand_frame(16, [7, 8, 9])
    assert decode_reply(calibration, StateMask(), request=Opcode.CONF_CP) == (
        CompassCalibrationReply(7, 8, 9)
    )


def test_nak_answers_any_request():
    assert decode_reply(hand_frame(8, []), StateMask(), request=Opcode.VM) == NakReply()


# --- the state reply, laid out by the mask ----------------------------------------------------


def test_state_reply_with_sonar_configuration_and_velocities():
    mask = StateMask(
        sonar={0, 1, 15},
        x=True,
        y=True,
        steer=True,
        turret=True,
        vel_trans=True,
        vel_steer=True,
        vel_turret=True,
    )
    wire = hand_frame(
        7,
        cat(
            [17, 255, 6],  # sonars 0, 1, 15 in inches
            sm16(-1234),
            sm16(5678),
            sm16(900),
            sm16(-2700),
            sm16(200),
            sm16(-450),
            sm16(0),
            tail(0b101, 0x01020304, 200, 210),
        ),
    )
    sonar = [None] * 16
    sonar[0], sonar[1], sonar[15] = 17, 255, 6
    expected = State(
        motor_status=0b101,
        clock_ms=0x01020304,
        cpu_voltage_raw=200,
        motor_voltage_raw=210,
        sonar=tuple(sonar),
        x=-1234,
        y=5678,
        steer=900,
        turret=-2700,
        vel_trans=200,
        vel_steer=-450,
        vel_turret=0,
    )
    reply = decode_reply(wire, mask, request=Opcode.GS)
    assert reply == StateReply(Opcode.GS, expected)
    assert reply.state.motors_active == (True, False, True)
    assert encode_reply(reply, mask) == wire
    assert StateLayout(mask).size == len(wire) - 6


def test_state_reply_with_ir_nibbles_pos_attachments_bumper_compass_and_laser():
    mask = StateMask(
        ir={2, 5, 9},
        pos_ir=True,
        pos_sonar=True,  # no sonar selected, so no sonar "pos" either
        bumper=True,
        pos_bumper=True,
        compass=True,
        pos_compass=True,
        laser=True,
        pos_laser=True,
    )
    ir = [None] * 16
    ir[2], ir[5], ir[9] = 3, 12, 7
    ir_pos = [None] * 16
    ir_pos[2], ir_pos[5], ir_pos[9] = POS_A, POS_B, POS_A
    wire = hand_frame(
        5,  # the reply to VM
        cat(
            [3 | 12 << 4, 7],  # three nibbles, low first; the fourth is padding
            pos_bytes(POS_A),
            pos_bytes(POS_B),
            pos_bytes(POS_A),
            [0x0A, 0x0B, 0x0C],  # bumper, most significant byte first
            pos_bytes(POS_B),
            u16(1800),  # compass
            pos_bytes(POS_A),
            u16(2),  # laser: count, then the points
            u16(300),
            u16(65535),
            pos_bytes(POS_B),
            tail(0, 4_294_967_295, 0, 255),
        ),
    )
    expected = State(
        motor_status=0,
        clock_ms=4_294_967_295,
        cpu_voltage_raw=0,
        motor_voltage_raw=255,
        ir=tuple(ir),
        ir_pos=tuple(ir_pos),
        bumper=0x0C + 256 * 0x0B + 65536 * 0x0A,
        bumper_pos=POS_B,
        compass=1800,
        compass_pos=POS_A,
        laser=(300, 65535),
        laser_pos=POS_B,
    )
    assert decode_reply(wire, mask, request=Opcode.VM) == StateReply(Opcode.VM, expected)
    assert encode_reply(StateReply(Opcode.VM, expected), mask) == wire
    assert StateLayout(mask).size is None  # the laser makes it variable
    assert StateLayout(mask).field_names[:4] == (
        "ir",
        "state.ir_pos[2]",
        "state.ir_pos[5]",
        "state.ir_pos[9]",
    )


def test_empty_mask_leaves_only_the_tail():
    wire = hand_frame(9, tail(0, 1, 2, 3))
    assert decode_reply(wire, StateMask(), request=Opcode.ST) == StateReply(
        Opcode.ST, State(clock_ms=1, cpu_voltage_raw=2, motor_voltage_raw=3)
    )


def test_same_bytes_read_differently_under_another_mask():
    # Why the driver must track its mask: with x instead of sonar 0 the first byte pair moves.
    payload = [5, 0, *tail(0, 0, 0, 0)]
    wire = hand_frame(7, payload)
    assert decode_reply(wire, StateMask(x=True)).state.x == 5
    with pytest.raises(PayloadError, match="1 unexpected byte"):
        decode_reply(wire, StateMask(sonar={0}))


# --- numbers ----------------------------------------------------------------------------------


@FUZZ
@given(st.integers(-32767, 32767))
def test_sign_magnitude_16_round_trips_and_matches_the_rule(n):
    assert list(encode_s16(n, "n")) == sm16(n)
    assert decode_s16(encode_s16(n, "n")) == n


def test_every_16_bit_pattern_decodes_and_re_encodes_except_negative_zero():
    for word in range(65536):
        raw = word.to_bytes(2, "little")
        value = decode_s16(raw)
        expected = b"\x00\x00" if raw == b"\x00\x80" else raw
        assert encode_s16(value, "n") == expected


@FUZZ
@given(st.integers(-(2**31 - 1), 2**31 - 1))
def test_sign_magnitude_32_round_trips_and_matches_the_rule(n):
    assert list(encode_s32(n, "n")) == sm32(n)
    assert decode_s32(encode_s32(n, "n")) == n


def test_negative_zero_reads_as_zero_and_is_never_written():
    assert decode_s16(b"\x00\x80") == 0
    assert decode_s32(b"\x00\x00\x00\x80") == 0
    assert encode_s16(0, "n") == b"\x00\x00"
    assert encode_s16(-0, "n") == b"\x00\x00"
    assert encode_s32(0, "n") == b"\x00\x00\x00\x00"


@pytest.mark.parametrize(
    ("make", "pattern"),
    [
        (lambda: encode_s16(32768, "vm.trans"), r"vm\.trans = 32768 .*-32767\.\.32767"),
        (lambda: encode_s16(-32768, "x"), r"x = -32768 is outside"),
        (lambda: encode_u16(-1, "ac.steer"), r"ac\.steer = -1 .*0\.\.65535"),
        (lambda: encode_s32(2**31, "pos.x"), r"pos\.x = 2147483648"),
        (lambda: Vm(100, 40000, 0), r"vm\.steer = 40000"),
        (lambda: Ac(-1, 0, 0), r"ac\.trans = -1"),
        (lambda: ConfTm(256), r"conf_tm\.timeout = 256"),
        (lambda: ConfSn(15, (0, 16)), r"conf_sn\.order\[1\] = 16"),
        (lambda: ConfSn(15, (*range(16), 0)), r"17 entries"),
        (lambda: ConfCp(3), r"conf_cp\.mode = 3 is not one of 0 OFF"),
        (lambda: MvAxis(9, 0), r"mv axis mode = 9"),
        (lambda: Ws(2, 0, 0, 1), r"ws\.trans = 2"),
        (lambda: Tk("caf\u00e9"), r"non-ASCII"),
        (lambda: Tk("a\0b"), r"NUL at index 1"),
        (lambda: StateMask(sonar={16}), r"mask\.sonar sensor index = 16"),
    ],
)
def test_out_of_range_values_raise_value_error_naming_field_and_value(make, pattern):
    with pytest.raises(ValueError, match=pattern) as caught:
        make()
    assert not isinstance(caught.value, ProtocolError)  # a caller's mistake, not a wire fault


# --- round trips of every message ---------------------------------------------------------------

u8s = st.integers(0, 255)
u16s = st.integers(0, 65535)
s16s = st.integers(-32767, 32767)
u32s = st.integers(0, 2**32 - 1)
s32s = st.integers(-(2**31 - 1), 2**31 - 1)
sensor_sets = st.frozensets(st.integers(0, 15))
orders = st.lists(st.integers(0, 15), max_size=16).map(tuple)
FLAGS = [
    "bumper",
    "x",
    "y",
    "steer",
    "turret",
    "vel_trans",
    "vel_steer",
    "vel_turret",
    "laser",
    "compass",
    "pos_ir",
    "pos_sonar",
    "pos_bumper",
    "pos_laser",
    "pos_compass",
]
masks = st.builds(StateMask, ir=sensor_sets, sonar=sensor_sets, **{f: st.booleans() for f in FLAGS})
pos_data = st.builds(PosData, s32s, s32s, s32s, s32s, s32s, s32s, s32s, u32s, u32s)
mv_axes = st.builds(MvAxis, st.sampled_from(MvMode), s16s)
ascii_text = st.text(st.characters(min_codepoint=1, max_codepoint=127), max_size=40)

COMMAND_STRATEGIES = {
    Ac: st.builds(Ac, u16s, u16s, u16s),
    Sp: st.builds(Sp, u16s, u16s, u16s),
    Pr: st.builds(Pr, s16s, s16s, s16s),
    Pa: st.builds(Pa, s16s, s16s, s16s),
    Vm: st.builds(Vm, s16s, s16s, s16s),
    Ct: st.builds(Ct, masks),
    Tk: st.builds(Tk, ascii_text),
    Dp: st.builds(Dp, s16s, s16s),
    Da: st.builds(Da, s16s, s16s),
    ConfIr: st.builds(ConfIr, u8s, orders),
    ConfSn: st.builds(ConfSn, u8s, orders),
    ConfCp: st.builds(ConfCp, st.sampled_from(CompassMode)),
    ConfTm: st.builds(ConfTm, u8s),
    Ws: st.builds(Ws, st.booleans(), st.booleans(), st.booleans(), u8s),
    Mv: st.builds(Mv, mv_axes, mv_axes, mv_axes),
    **{cls: st.just(cls()) for cls in (Gs, Nak, St, Lp, Zr, GetIr, GetSn, GetRc, GetRv)},
    **{cls: st.just(cls()) for cls in (GetRa, GetCp, GetBp)},
    **{cls: st.builds(cls, st.binary(max_size=64)) for cls in (ConfLs, GetLs, SetupLs, ConfSg)},
    **{cls: st.builds(cls, st.binary(max_size=64)) for cls in (GetSg, Special)},
}


def test_every_opcode_of_the_table_has_a_command_and_a_strategy():
    assert set(COMMANDS) == set(Opcode)
    assert len(Opcode) == 33
    assert set(COMMAND_STRATEGIES) == set(COMMANDS.values())


@FUZZ
@given(st.one_of(*COMMAND_STRATEGIES.values()))
def test_every_command_round_trips(command):
    wire = encode_request(command)
    assert decode_request(wire) == command
    assert wire[3] == command.OPCODE


# Drawing with module-level strategies only: building strategies per example is what makes
# hypothesis slow, and the mask-dependent shapes need no strategy of their own.
ir_values = st.integers(0, 15)
bumpers = st.integers(0, 2**24 - 1)
laser_points = st.lists(u16s, max_size=20).map(tuple)
ir16 = st.lists(ir_values, min_size=16, max_size=16).map(tuple)
u8x16 = st.lists(u8s, min_size=16, max_size=16).map(tuple)
pos16 = st.lists(pos_data, min_size=16, max_size=16).map(tuple)


MOTION_FIELDS = ("x", "y", "steer", "turret", "vel_trans", "vel_steer", "vel_turret")


def maybe(draw, flag, strategy):
    return draw(strategy) if flag else None


def draw_state(draw, mask: StateMask) -> State:
    def per_sensor(chosen, flag, strategy):
        return tuple(maybe(draw, flag and i in chosen, strategy) for i in range(16))

    return State(
        motor_status=draw(st.integers(0, 7)),
        clock_ms=draw(u32s),
        cpu_voltage_raw=draw(u8s),
        motor_voltage_raw=draw(u8s),
        ir=per_sensor(mask.ir, True, ir_values),
        ir_pos=per_sensor(mask.ir, mask.pos_ir, pos_data),
        sonar=per_sensor(mask.sonar, True, u8s),
        sonar_pos=per_sensor(mask.sonar, mask.pos_sonar, pos_data),
        bumper=maybe(draw, mask.bumper, bumpers),
        bumper_pos=maybe(draw, mask.bumper and mask.pos_bumper, pos_data),
        **{a: maybe(draw, getattr(mask, a), s16s) for a in MOTION_FIELDS},
        compass=maybe(draw, mask.compass, u16s),
        compass_pos=maybe(draw, mask.compass and mask.pos_compass, pos_data),
        laser=maybe(draw, mask.laser, laser_points),
        laser_pos=maybe(draw, mask.laser and mask.pos_laser, pos_data),
    )


STATE_OPCODES = st.sampled_from(
    sorted(
        set(Opcode)
        - {Opcode.NAK, Opcode.GET_IR, Opcode.GET_SN, Opcode.GET_RC, Opcode.GET_RV, Opcode.GET_RA}
        - {Opcode.GET_CP, Opcode.GET_LS, Opcode.GET_BP, Opcode.GET_SG, Opcode.SPECIAL}
    )
)
RAW_OPCODES = st.sampled_from([Opcode.GET_RA, Opcode.GET_LS, Opcode.GET_SG, Opcode.SPECIAL])

REPLY_KINDS = [
    lambda d, m: StateReply(d(STATE_OPCODES), draw_state(d, m)),
    lambda d, m: NakReply(),
    lambda d, m: IrReply(d(ir16), maybe(d, m.pos_ir, pos16), d(u32s)),
    lambda d, m: SonarReply(d(u8x16), maybe(d, m.pos_sonar, pos16), d(u32s)),
    lambda d, m: ConfigurationReply(d(s16s), d(s16s), d(s16s), d(s16s)),
    lambda d, m: VelocityReply(d(s16s), d(s16s), d(s16s)),
    lambda d, m: CompassReply(d(u16s), maybe(d, m.pos_compass, pos_data), d(u32s)),
    lambda d, m: BumperReply(d(bumpers), maybe(d, m.pos_bumper, pos_data), d(u32s)),
    lambda d, m: CompassCalibrationReply(d(u8s), d(u8s), d(u8s)),
    lambda d, m: RawReply(d(RAW_OPCODES), d(st.binary(max_size=64))),
]


@st.composite
def mask_and_reply(draw):
    mask = draw(masks)
    return mask, draw(st.sampled_from(REPLY_KINDS))(draw, mask)


@FUZZ
@given(mask_and_reply())
def test_every_reply_round_trips_under_its_mask(case):
    mask, reply = case
    wire = encode_reply(reply, mask)
    assert decode_reply(wire, mask, request=reply.opcode) == reply


@FUZZ
@given(masks)
def test_state_mask_round_trips_through_its_seven_bytes(mask):
    raw = mask.to_bytes()
    assert len(raw) == 7
    assert StateMask.from_bytes(raw) == mask


@st.composite
def mask_and_fixed_size_state(draw):
    mask = draw(masks.filter(lambda m: not m.laser))
    return mask, draw_state(draw, mask)


@FUZZ
@given(mask_and_fixed_size_state())
def test_state_layout_size_matches_what_it_encodes(case):
    mask, state = case
    layout = StateLayout(mask)
    payload = layout.encode(state)
    assert len(payload) == layout.size
    assert layout.decode(payload) == state


# --- the stream decoder -----------------------------------------------------------------------

GS = bytes.fromhex(GOLDEN[0][1])
VM = bytes.fromhex(GOLDEN[1][1])
TM = bytes.fromhex(GOLDEN[2][1])


def test_garbage_before_and_between_frames_is_skipped_and_counted():
    decoder = FrameDecoder()
    frames = decoder.feed(b"\xff\x00\x5c" + GS + b"junk" + VM)
    assert [decode_request(f) for f in frames] == [Gs(), Vm(100, -450, 0)]
    assert decoder.discarded == 3 + 4
    assert decoder.error_count == 2
    assert all(isinstance(e, FramingError) for e in decoder.errors)
    assert "expected start byte 0x01 at byte 0, got 0xFF; skipped 3" in str(decoder.errors[0])
    assert decoder.pending == 0


def test_frame_split_byte_by_byte():
    decoder = FrameDecoder()
    out = []
    for k, byte in enumerate(VM + TM):
        frames = decoder.feed(bytes([byte]))
        out += frames
        if k not in (len(VM) - 1, len(VM) + len(TM) - 1):
            assert frames == []
    assert out == [Frame(5, VM[4:-2]), Frame(18, b"\x05")]
    assert decoder.discarded == 0
    assert decoder.error_count == 0


def test_corrupted_checksum_then_good_frame():
    bad = bytearray(VM)
    bad[-2] ^= 0xFF
    decoder = FrameDecoder()
    frames = decoder.feed(bytes(bad) + GS)
    assert frames == [Frame(7)]
    first = decoder.errors[0]
    assert isinstance(first, ChecksumError)
    assert (first.expected, first.actual) == (0xB5, 0x4A)
    assert "expected 0xB5, got 0x4A" in str(first)
    assert "0x05 (VM)" in str(first)


def test_truncated_frame_followed_by_a_good_one():
    decoder = FrameDecoder()
    frames = decoder.feed(VM[:5] + VM)
    assert frames == [Frame(5, VM[4:-2])]
    assert isinstance(decoder.errors[0], FramingError)
    assert "expected end byte 0x5C" in str(decoder.errors[0])
    assert decoder.discarded == 5


def test_truncated_frame_waits_for_enough_bytes_or_a_reset():
    decoder = FrameDecoder()
    # The cut VM claims 12 bytes; 3 + 6 are not enough to show it is broken, so it waits...
    assert decoder.feed(VM[:3] + GS) == []
    assert decoder.pending == 9
    # ...and the next frame completes the claimed span, exposing it; both GS frames survive.
    assert decoder.feed(GS) == [Frame(7), Frame(7)]
    # On a reply timeout the owner resets instead, as the original client flushes its input.
    assert decoder.feed(VM[:7]) == []
    assert decoder.reset() == 7
    assert decoder.pending == 0
    assert "dropped by reset" in str(decoder.errors[-1])
    assert decoder.feed(TM) == [Frame(18, b"\x05")]


def test_over_long_and_too_short_length_fields_are_rejected_without_waiting():
    decoder = FrameDecoder(max_len=64)
    frames = decoder.feed(b"\x01\xff\xff" + GS + b"\x01\x00\x00" + TM)
    assert frames == [Frame(7), Frame(18, b"\x05")]
    lengths = [e for e in decoder.errors if isinstance(e, LengthError)]
    assert "LEN 0xFFFF (65535) at byte 0 exceeds the maximum 64" in str(lengths[0])
    assert "below the minimum 2" in str(lengths[1])
    assert decoder.pending == 0


def test_buffer_stays_bounded_and_filler_always_resynchronises():
    rng = random.Random(1234)
    decoder = FrameDecoder(max_len=64, keep_errors=8)
    for _ in range(400):
        decoder.feed(rng.randbytes(rng.randint(1, 300)))
        assert decoder.pending < decoder.max_frame_size
    assert len(decoder.errors) <= 8 < decoder.error_count
    # max_frame_size bytes with no start byte settle any frame the garbage seemed to begin.
    frames = decoder.feed(bytes(decoder.max_frame_size) + VM)
    assert frames[-1] == Frame(5, VM[4:-2])
    assert decoder.pending == 0


@FUZZ
@given(
    st.lists(st.sampled_from([GS, VM, TM, encode_request(Tk("\x01\x5c"))]), max_size=6),
    st.lists(st.binary(max_size=8).map(lambda b: b.replace(b"\x01", b"")), min_size=7, max_size=7),
    st.lists(st.integers(1, 7), min_size=1, max_size=40),
)
def test_any_split_with_garbage_between_frames_yields_the_frames(frames, garbage, cuts):
    stream = garbage[0] + b"".join(f + g for f, g in zip(frames, garbage[1:], strict=False))
    decoder = FrameDecoder()
    out, pos, k = [], 0, 0
    while pos < len(stream):
        size = cuts[k % len(cuts)]
        out += decoder.feed(stream[pos : pos + size])
        pos, k = pos + size, k + 1
    assert [f.encode() for f in out] == frames
    assert decoder.discarded == sum(map(len, garbage[: len(frames) + 1]))


# --- bad input raises the right error, saying what was wrong -----------------------------------


def corrupt(frame: bytes, index: int, value: int) -> bytes:
    out = bytearray(frame)
    out[index] = value
    return bytes(out)


@pytest.mark.parametrize(
    ("data", "error", "pattern"),
    [
        (b"", FramingError, "empty input"),
        (b"\x02" + GS[1:], FramingError, "expected start byte 0x01, got 0x02"),
        (corrupt(GS, 5, 0x5D), FramingError, "expected end byte 0x5C at byte 5, got 0x5D"),
        (corrupt(GS, 4, 0x0B), ChecksumError, r"0x07 \(GS\): checksum expected 0x0A, got 0x0B"),
        (GS[:4], FramingError, "truncated frame: got 4 bytes, needs 6 bytes"),
        (GS + b"\x00", FramingError, "1 unexpected byte"),
        (b"\x01\x01\x00\x07\x09\x5c", LengthError, "LEN 0x0001 .* below the minimum 2"),
        (b"\x01\x00\x20" + bytes(8194), LengthError, "LEN 0x2000 .* exceeds the maximum 4096"),
    ],
)
def test_bad_frames(data, error, pattern):
    with pytest.raises(error, match=pattern):
        decode_frame(data)


@pytest.mark.parametrize(
    ("wire", "error", "pattern"),
    [
        (hand_frame(42, []), UnknownOpcodeError, r"unknown request opcode 0x2A"),
        (hand_frame(5, [1, 0, 2, 0]), PayloadError, r"vm: payload too short for vm\.turret"),
        (hand_frame(7, [0]), PayloadError, r"gs: 1 unexpected byte"),
        (hand_frame(6, [0, 0, 0, 0, 0, 2, 0]), PayloadError, r"mask byte 5 = 0x02 sets unused"),
        (hand_frame(31, [1, 2, 0, 5]), PayloadError, r"ws\.steer flag must be 0 or 1, got 0x02"),
        (hand_frame(11, [104, 105]), PayloadError, r"tk: text must end with NUL .* 0x69"),
        (hand_frame(11, [0xE9, 0]), PayloadError, r"tk: byte 0xE9 at offset 0 is not ASCII"),
        (hand_frame(16, [3]), PayloadError, r"conf_cp\.mode = 3 is not one of"),
        (hand_frame(43, [9, 0] + [0] * 10), PayloadError, r"mv\.trans: mv axis mode = 9"),
        (hand_frame(15, [1, 3, 20, 255] + [0] * 13), PayloadError, r"conf_sn\.order\[1\] = 20"),
    ],
)
def test_bad_requests(wire, error, pattern):
    with pytest.raises(error, match=pattern):
        decode_request(wire)


def test_bad_replies():
    mask = StateMask(x=True)
    with pytest.raises(UnexpectedReplyError, match=r"reply to 0x05 \(VM\).*got type 0x07 \(GS\)"):
        decode_reply(hand_frame(7, [0, 0, *tail(0, 0, 0, 0)]), mask, request=Opcode.VM)
    with pytest.raises(UnknownOpcodeError, match="unknown reply opcode 0xC8") as caught:
        decode_reply(hand_frame(200, []), mask)
    assert caught.value.opcode == 200
    with pytest.raises(PayloadError, match=r"state reply to 0x07 \(GS\).*state\.clock_ms"):
        decode_reply(hand_frame(7, [0, 0, 0, 1, 2]), mask)
    with pytest.raises(PayloadError, match=r"get_sn: payload too short for get_sn\.pos\[0\]\.x"):
        decode_reply(hand_frame(20, list(range(16))), StateMask(pos_sonar=True))
    with pytest.raises(PayloadError, match=r"nak: 1 unexpected byte"):
        decode_reply(hand_frame(8, [0]), mask)


def test_encoding_a_state_that_disagrees_with_the_mask_names_the_field():
    mask = StateMask(sonar={3}, x=True)
    sonar = [None] * 16
    sonar[3] = 40
    with pytest.raises(ValueError, match=r"state\.x is None but the state mask includes it"):
        encode_reply(StateReply(Opcode.GS, State(sonar=tuple(sonar))), mask)
    sonar[4] = 41
    with pytest.raises(ValueError, match=r"state\.sonar\[4\] = 41 but the state mask leaves"):
        encode_reply(StateReply(Opcode.GS, State(sonar=tuple(sonar), x=1)), mask)
    with pytest.raises(ValueError, match=r"state\.sonar\[3\] = 256 is outside"):
        sonar = [None, None, None, 256] + [None] * 12
        encode_reply(StateReply(Opcode.GS, State(sonar=tuple(sonar), x=1)), mask)
    with pytest.raises(ValueError, match=r"get_sn\.pos is missing but mask\.pos_sonar is on"):
        encode_reply(SonarReply(tuple(range(16))), StateMask(pos_sonar=True))
    with pytest.raises(ValueError, match=r"0x15 \(GET_RC\) is not answered by state"):
        StateReply(Opcode.GET_RC, State())


def test_error_tree():
    for error in (FramingError, LengthError, ChecksumError, UnknownOpcodeError, PayloadError):
        assert issubclass(error, ProtocolError)
    assert issubclass(LengthError, FramingError)
    assert issubclass(UnexpectedReplyError, ProtocolError)
    assert issubclass(ProtocolError, ValueError)


# --- units ------------------------------------------------------------------------------------


def test_unit_constants_are_exact_definitions():
    assert units.INCH_M == 0.0254
    assert units.tenth_inch_to_m(10) == pytest.approx(0.0254, rel=1e-15)
    assert units.tenth_inch_to_m(200) == pytest.approx(0.508, rel=1e-15)  # 20 in/s
    assert units.inch_to_m(255) == pytest.approx(6.477, rel=1e-15)
    assert units.tenth_deg_to_rad(450) == pytest.approx(math.pi / 4, rel=1e-15)
    assert units.tenth_deg_to_rad(-3600) == pytest.approx(-2 * math.pi, rel=1e-15)


@FUZZ
@given(s16s)
def test_unit_conversions_round_trip_to_the_protocol_integer(n):
    assert units.m_to_tenth_inch(units.tenth_inch_to_m(n)) == n
    assert units.rad_to_tenth_deg(units.tenth_deg_to_rad(n)) == n
    assert units.m_to_inch(units.inch_to_m(n)) == n


def test_voltages_follow_the_reference_formula():
    assert units.cpu_voltage(0) == pytest.approx(2 * 12.0 / 5)
    assert units.cpu_voltage(255) == pytest.approx(12.0)
    assert units.motor_voltage(170) == pytest.approx((2 + 3 * 170 / 255) * 12.85 / 5)
    assert units.volts_to_raw(units.motor_voltage(170), units.MOTOR_VOLTAGE_RANGE) == 170
    with pytest.raises(ValueError, match=r"voltage = 20 V is outside the measurable 4.8..12 V"):
        units.volts_to_raw(20, units.CPU_VOLTAGE_RANGE)
    with pytest.raises(ValueError, match="raw voltage = 256"):
        units.cpu_voltage(256)


def test_the_codec_imports_nothing_that_does_io():
    import ast
    import pathlib

    package = pathlib.Path(units.__file__).parent
    # The driver's I/O side lives beside the codec (as the architecture asks: codec + a thin
    # device module); every other module of the package must stay pure.
    device_side = {"device.py", "link.py", "clock.py", "settings.py"}
    for path in package.glob("*.py"):
        if path.name in device_side:
            continue
        tree = ast.parse(path.read_text())
        names = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        names |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
        roots = {name.split(".")[0] for name in names}
        assert not roots & {"serial", "socket", "time", "threading", "asyncio", "os", "hal"}, path
        assert not re.search(r"\bopen\(", path.read_text()), path
