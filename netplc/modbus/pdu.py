"""Modbus as bytes, for our clients and our servers alike: the MBAP header of Modbus TCP, the function
codes and exceptions, and how a server answers one request PDU from what it serves (its handler),
over TCP (`tcp_server.py`) or a serial line (`rtu.py`).

Callers of a client see `LinkError` (the transport failed: refused, timed out, lost) and
`DeviceError` (the device answered with a Modbus exception), never a pymodbus type.
"""

from __future__ import annotations

import logging
import struct
from collections.abc import Callable
from typing import Protocol

from netplc.modbus.map import (
    MAX_READ_BITS,
    MAX_READ_REGISTERS,
    MAX_WRITE_BITS,
    MAX_WRITE_REGISTERS,
    MapError,
    Table,
    bits_from_bytes,
)

logger = logging.getLogger(__name__)


class LinkError(Exception):
    """The transport failed: connection refused or lost, or no answer within the timeout."""


class ProtocolError(LinkError):
    """An answer that is not the request's: too short, another function code or unit, a wrong
    byte count or echo. It counts as a failed attempt, like no answer at all."""


# Modbus exception codes (Modbus Application Protocol 1.1b3, section 7) and what they mean
APPLIED = 0  # not an exception: what a server's write outcome is when the write was done
ILLEGAL_FUNCTION, ILLEGAL_ADDRESS, ILLEGAL_VALUE, DEVICE_FAILURE, BUSY = 1, 2, 3, 4, 6
EXCEPTIONS = {1: "illegal function", 2: "illegal data address", 3: "illegal data value",
              4: "server device failure", 5: "acknowledge", 6: "server device busy",
              8: "memory parity error", 10: "gateway path unavailable",
              11: "gateway target device failed to respond"}


def exception_text(code: int) -> str:
    """`4 (server device failure)`: a code as the journal and the status bar say it."""
    return f"{code} ({EXCEPTIONS.get(code, 'unknown')})"


class DeviceError(Exception):
    """The device answered with a Modbus exception (2 = illegal data address, ...)."""

    def __init__(self, code: int, what: str) -> None:
        self.code = code
        super().__init__(f"{what}: Modbus exception {exception_text(code)}")


MBAP = struct.Struct(">HHHB")  # Modbus TCP header: transaction, protocol 0, length, unit
READ_CODES: dict[str, int] = {"coils": 1, "discrete": 2, "holding": 3, "input": 4}
ADDRESS_REQUEST = struct.Struct(">BHH")  # function code, address, count (or value)


def take_frames(buf: bytearray) -> list[tuple[int, int, bytes]] | None:
    """Remove the complete Modbus TCP frames from the front of `buf`: (transaction, unit, PDU)
    each; a partial frame stays for the next data. None: the bytes are not Modbus TCP."""
    frames = []
    while len(buf) >= 8:
        tid, proto, length, unit = MBAP.unpack_from(buf)
        if proto != 0 or not 2 <= length <= 254:
            return None
        if len(buf) < 6 + length:
            break
        frames.append((tid, unit, bytes(buf[7 : 6 + length])))
        del buf[: 6 + length]
    return frames


ADU_MAX = 260  # the longest Modbus TCP frame: MBAP header 7 + PDU 253
READ_HEAD = struct.Struct(">HHHBBB")  # MBAP + function code + byte count of a read answer
ADDRESS_COUNT = struct.Struct(">HH")
READ_TABLES: dict[int, Table] = {1: "coils", 2: "discrete", 3: "holding", 4: "input"}

Answer = Callable[[bytes], None]  # takes the response PDU of a write once it is journaled
Done = Callable[[int], None]  # takes a write's outcome: APPLIED, or the exception code refusing it


class ServeHandler(Protocol):
    """What a Modbus server serves: the server knows frames and connections, the handler what the
    addresses are and who may write them (the station's command layer, a simulated node's engine).
    MapError from any method answers exception 2."""

    def registers(self, address: int, count: int) -> bytes:
        """`count` registers from `address` as the answer carries them (big-endian words)."""
        ...

    def bits(self, address: int, count: int) -> bytes:
        """`count` coils from `address`, packed as the answer carries them."""
        ...

    def write(self, table: Table, address: int, values: list[int], peer: str, done: Done) -> int | None:
        """Refuse a write at once (its exception code), or take it (None) and call `done(outcome)`
        once it is applied and journaled (APPLIED) or failed, from any thread, possibly before
        `write` returns."""
        ...


class Refuse(Exception):
    def __init__(self, code: int) -> None:
        self.code = code


def answer(handler: ServeHandler, pdu: bytes, peer: str, later: Answer) -> bytes | None:
    """The response PDU to one request PDU (function codes 1-6, 15, 16; others: exception 1), or
    None for a write the handler took, whose response goes to `later` once the write is applied
    and its journal record is durable (or the exception that failed it)."""
    fc = pdu[0]
    try:
        if fc in READ_TABLES:
            if len(pdu) != 5:
                raise Refuse(ILLEGAL_VALUE)
            address, count = ADDRESS_COUNT.unpack_from(pdu, 1)
            if not 1 <= count <= (MAX_READ_BITS if fc <= 2 else MAX_READ_REGISTERS):
                raise Refuse(ILLEGAL_VALUE)
            data = handler.bits(address, count) if fc <= 2 else handler.registers(address, count)
            return bytes((fc, len(data))) + data
        if fc in (5, 6, 15, 16):
            table, address, values, echo = _write_request(pdu)
            refused = handler.write(table, address, values, peer,
                                    lambda code: later(bytes((fc | 0x80, code)) if code else echo))
            if refused is None:
                return None
            raise Refuse(refused)
        code = ILLEGAL_FUNCTION
    except Refuse as e:
        code = e.code
    except MapError:
        code = ILLEGAL_ADDRESS
    except Exception:  # a server bug answers "device failure" and the server goes on
        logger.exception("Modbus request %s from %s failed", pdu.hex(" "), peer)
        code = DEVICE_FAILURE
    return bytes((fc | 0x80, code))


def _write_request(pdu: bytes) -> tuple[Table, int, list[int], bytes]:
    """(table, address, values, echo) of a write request; Refuse(3) if it is malformed."""
    fc = pdu[0]
    if fc in (5, 6):
        if len(pdu) != 5:
            raise Refuse(ILLEGAL_VALUE)
        address, value = ADDRESS_COUNT.unpack_from(pdu, 1)
        if fc == 6:
            return "holding", address, [value], pdu
        if value not in (0, 0xFF00):
            raise Refuse(ILLEGAL_VALUE)
        return "coils", address, [1 if value else 0], pdu
    if len(pdu) < 6:
        raise Refuse(ILLEGAL_VALUE)
    address, count, nbytes = struct.unpack_from(">HHB", pdu, 1)
    data = pdu[6:]
    echo = pdu[:5]
    if fc == 15:
        if not 1 <= count <= MAX_WRITE_BITS or nbytes != (count + 7) // 8 or len(data) != nbytes:
            raise Refuse(ILLEGAL_VALUE)
        return "coils", address, bits_from_bytes(data)[:count], echo
    if not 1 <= count <= MAX_WRITE_REGISTERS or nbytes != 2 * count or len(data) != nbytes:
        raise Refuse(ILLEGAL_VALUE)
    return "holding", address, list(struct.unpack(f">{count}H", data)), echo
