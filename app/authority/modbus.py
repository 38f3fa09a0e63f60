"""The station's Modbus server as an entry point of the command layer (docs/architecture.md section 7).

Modbus has no users: a client acts as `Who("", Source.MODBUS, peer)`, with the role
`[modbus_server] role` grants it (operator by default; viewer makes the server read-only), and may
write only what `[modbus_server] writable` names. Every write is a command: checked against the one
policy, journaled once naming the peer, answered once applied and committed. Each `Reason` becomes
a Modbus exception (`EXCEPTION_OF`):
- applied: the normal response;
- denied: 01 illegal function (the role allows this client no writes: not a function it may use);
- not writable, unknown: 02 illegal data address, as an address that does not exist, and the
  refusal journaled (one record per cause per peer per minute, with the count);
- type mismatch, out of range, invalid: 03 illegal data value;
- busy, journal full, not running: 06 server device busy, answered at once (nothing was done: the
  client may try again, and a full archive no longer leaves it waiting for an answer);
- failed: 04 server device failure.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable

from app.authority.layer import Answer, Commands, Reason, Ticket, Who
from app.authority.policy import Action, Source
from netplc.modbus import (
    APPLIED,
    BUSY,
    DEVICE_FAILURE,
    ILLEGAL_ADDRESS,
    ILLEGAL_FUNCTION,
    ILLEGAL_VALUE,
    Done,
    MemoryServed,
    MemoryWrite,
)

logger = logging.getLogger(__name__)

EXCEPTION_OF: dict[Reason, int] = {
    Reason.APPLIED: APPLIED,
    Reason.DENIED: ILLEGAL_FUNCTION,
    Reason.NOT_WRITABLE: ILLEGAL_ADDRESS,
    Reason.UNKNOWN: ILLEGAL_ADDRESS,
    Reason.TYPE_MISMATCH: ILLEGAL_VALUE,
    Reason.OUT_OF_RANGE: ILLEGAL_VALUE,
    Reason.INVALID: ILLEGAL_VALUE,
    Reason.BUSY: BUSY,
    Reason.JOURNAL_FULL: BUSY,
    Reason.NOT_RUNNING: BUSY,
    Reason.STANDBY: BUSY,  # 06: the write belongs to the primary; the refusal's record names it
    Reason.FAILED: DEVICE_FAILURE,
}


def exception_of(answer: Answer) -> int:
    return EXCEPTION_OF[answer.reason]


class ModbusCommands(MemoryServed):
    """What the station's Modbus server serves: NetPlc memory read from the snapshot of the last
    scan, every write a command of `commands`."""

    def __init__(self, commands: Commands, writable: Iterable[tuple[int, int]]) -> None:
        super().__init__(commands.engine, writable)
        self.commands = commands

    def not_writable(self, change: MemoryWrite, peer: str) -> int:
        ticket = self.commands.refuse(Who("", Source.MODBUS, peer), Action.WRITE, str(change),
                                      Reason.NOT_WRITABLE,
                                      "not writable over Modbus (station.toml [modbus_server] writable)")
        return exception_of(ticket.result())

    def take(self, change: MemoryWrite, peer: str, done: Done) -> int | None:
        who, commands, first = Who("", Source.MODBUS, peer), self.commands, change.first
        ticket: Ticket
        if change.bits is not None:
            ticket = (commands.write_bit(who, first, change.bits[0]) if len(change.bits) == 1
                      else commands.write_bits(who, first, change.bits))
        elif len(change.data) == 2:
            ticket = commands.write_word(who, first, int.from_bytes(change.data, "little"))
        else:
            ticket = commands.write_bytes(who, first, change.data)
        if ticket.done() and not (answer := ticket.result()).ok:
            return exception_of(answer)  # refused at once: no need to hold the connection's answers
        ticket.add_done_callback(lambda t: done(exception_of(t.result())))
        return None
