"""The TYPE byte of a frame: one opcode per command; a reply echoes its request's opcode."""

from __future__ import annotations

from enum import IntEnum


class Opcode(IntEnum):
    AC = 1
    SP = 2
    PR = 3
    PA = 4
    VM = 5
    CT = 6
    GS = 7
    NAK = 8
    ST = 9
    LP = 10
    TK = 11
    DP = 12
    ZR = 13
    CONF_IR = 14
    CONF_SN = 15
    CONF_CP = 16
    CONF_LS = 17
    CONF_TM = 18
    GET_IR = 19
    GET_SN = 20
    GET_RC = 21
    GET_RV = 22
    GET_RA = 23
    GET_CP = 24
    GET_LS = 25
    SETUP_LS = 26
    GET_BP = 27
    CONF_SG = 28
    GET_SG = 29
    DA = 30
    WS = 31
    MV = 43
    SPECIAL = 128


#: Requests the robot answers with a state reply laid out by the current state mask. SETUP_LS is
#: not in the reference's list but the original client parses its reply as state; CONF_CP answers
#: with three calibration bytes instead, which ``replies`` tells apart by size.
STATE_REPLY_OPCODES = frozenset(
    {
        Opcode.AC,
        Opcode.SP,
        Opcode.PR,
        Opcode.PA,
        Opcode.VM,
        Opcode.MV,
        Opcode.CT,
        Opcode.GS,
        Opcode.ST,
        Opcode.LP,
        Opcode.DP,
        Opcode.DA,
        Opcode.WS,
        Opcode.ZR,
        Opcode.TK,
        Opcode.CONF_IR,
        Opcode.CONF_SN,
        Opcode.CONF_CP,
        Opcode.CONF_LS,
        Opcode.CONF_TM,
        Opcode.CONF_SG,
        Opcode.SETUP_LS,
    }
)


def describe(opcode: int) -> str:
    """``0x05 (VM)`` for error messages; unknown values show only the hex."""
    try:
        return f"0x{opcode:02X} ({Opcode(opcode).name})"
    except ValueError:
        return f"0x{opcode:02X}"
