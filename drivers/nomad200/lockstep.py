"""Lockstep time for an emulated Nomad 200, carried in SPECIAL (user) packets. Pure codec.

A real robot's clock runs by itself. An emulator in lockstep mode lets simulated time pass only
when the host says so, which makes a run through driver, pty and emulator as reproducible as one
in process. The protocol already has a slot for "on-board user code": SPECIAL (opcode 128) with an
opaque payload, so the step request travels there instead of in an invented opcode.

* request: ``LSTP`` + target controller time, unsigned 32-bit ms (little-endian). The target is
  absolute, so a retransmitted step (after a lost reply) cannot let time pass twice.
* reply: ``LSTP`` + a state payload laid out by the current state mask, taken at the target time,
  so the next control cycle needs no separate ``gs``.

A robot that does not know the packet answers NAK or with its own user reply; the driver only
sends it when configured for lockstep.
"""

from __future__ import annotations

from drivers.nomad200.commands import Special
from drivers.nomad200.errors import PayloadError
from drivers.nomad200.integers import U32_MAX, decode_u32, encode_u32
from drivers.nomad200.opcodes import Opcode
from drivers.nomad200.replies import RawReply
from drivers.nomad200.state import State, StateLayout, StateMask

MAGIC = b"LSTP"


def step_request(target_ms: int) -> Special:
    """Ask the emulator to run its simulation until controller time ``target_ms``."""
    return Special(MAGIC + encode_u32(target_ms % (U32_MAX + 1), "lockstep target_ms"))


def parse_step_request(command: Special) -> int | None:
    """The target time of a step request, or None if the packet is some other user packet."""
    data = command.data
    if not data.startswith(MAGIC):
        return None
    if len(data) != len(MAGIC) + 4:
        raise PayloadError(f"lockstep step request: payload of {len(data)} bytes, expected 8")
    return decode_u32(data[len(MAGIC) :])


def step_reply(state: State, mask: StateMask) -> RawReply:
    """The emulator's answer: the state at the target time, laid out for ``mask``."""
    return RawReply(Opcode.SPECIAL, MAGIC + StateLayout(mask).encode(state))


def parse_step_reply(reply: RawReply, mask: StateMask) -> State:
    """The state carried by a step reply; PayloadError if it is not one."""
    if not reply.data.startswith(MAGIC):
        raise PayloadError("lockstep step reply: the SPECIAL reply does not start with LSTP")
    return StateLayout(mask).decode(reply.data[len(MAGIC) :], "lockstep step reply")
