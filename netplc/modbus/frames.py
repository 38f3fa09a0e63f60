"""Modbus TCP requests encoded once and answers checked where they lie: the wire of the exchange's
hot path (netplc/tcp_exchange.py).

An instruction asks for the same block at every scan, so its request frames are built once and
sent with only the transaction id patched; an answer is checked in the connection's receive buffer
(header, unit, function, byte count or echo) and only its data is copied out. Anything that is not
the answer to the request in flight is a `FrameError` naming what was wrong, a failed attempt like
no answer at all: the connection is dropped and made again, the exchange goes on.
"""

from __future__ import annotations

import struct

from netplc.modbus.map import BIT_TABLES, MapError, Table, bytes_from_bits
from netplc.modbus.pdu import ADDRESS_REQUEST, MBAP, READ_CODES, DeviceError, ProtocolError

HEADER = 7  # MBAP: transaction, protocol, length, unit
LENGTH = struct.Struct(">HH")  # protocol id and length, at offset 2 of the header


class FrameError(ProtocolError):
    """Bytes that are not the answer to the request in flight: not Modbus TCP at all, or another
    unit, function code, byte count or echo."""


def read_pdu(table: Table, address: int, count: int) -> bytes:
    return ADDRESS_REQUEST.pack(READ_CODES[table], address, count)


def write_pdu(table: Table, address: int, values: list[int]) -> bytes:
    """Write Multiple Coils (15) or Registers (16); MapError for a read-only table."""
    n = len(values)
    if table == "coils":
        data = bytes_from_bits(values)
        return struct.pack(">BHHB", 15, address, n, len(data)) + data
    if table == "holding":
        return struct.pack(f">BHHB{n}H", 16, address, n, 2 * n, *values)
    raise MapError(f"{table} is a read-only table")


class Frame:
    """One transaction of a block request, as it goes on the wire, built once (`stamped` patches the
    transaction id); what it asks is kept too, for the clients that encode requests themselves."""

    __slots__ = ("address", "adu", "count", "echo", "fc", "nbytes", "table", "unit", "values", "what")

    def __init__(self, unit: int, table: Table, address: int, count: int, values: list[int] | None) -> None:
        self.unit, self.table, self.address, self.count, self.values = unit, table, address, count, values
        if values is None:
            pdu = read_pdu(table, address, count)
            self.nbytes = (count + 7) // 8 if table in BIT_TABLES else 2 * count
            self.what = f"read {table} {address}+{count}"
        else:
            pdu = write_pdu(table, address, values)
            self.nbytes = -1  # a write: answered by an echo of its first five bytes
            self.what = f"write {table} {address}+{count}"
        self.adu = bytearray(MBAP.pack(0, 0, len(pdu) + 1, unit) + pdu)
        self.fc = pdu[0]
        self.echo = bytes(pdu[:5])

    @classmethod
    def read(cls, unit: int, table: Table, address: int, count: int) -> Frame:
        return cls(unit, table, address, count, None)

    @classmethod
    def write(cls, unit: int, table: Table, address: int, values: list[int]) -> Frame:
        return cls(unit, table, address, len(values), values)

    def stamped(self, tid: int) -> bytearray:
        adu = self.adu
        adu[0] = tid >> 8
        adu[1] = tid & 0xFF
        return adu


def frame_size(buf: bytearray, at: int) -> int:
    """Size of the Modbus TCP frame at `buf[at:]`, 0 while it is incomplete; FrameError when the
    bytes are not Modbus TCP (protocol id not 0, a length no PDU has)."""
    if len(buf) - at < HEADER + 1:
        return 0
    proto, length = LENGTH.unpack_from(buf, at + 2)
    if proto != 0 or not 2 <= length <= 254:
        raise FrameError(f"not a Modbus TCP answer: {bytes(buf[at : at + HEADER + 1]).hex(' ')}")
    size = 6 + length
    return size if len(buf) - at >= size else 0


def answer_data(frame: Frame, buf: bytearray, at: int, size: int) -> bytes:
    """The data of the answer to `frame` lying at `buf[at:at + size]` (a complete frame with the
    request's transaction id): registers big-endian and coils packed, as the wire carries them;
    b"" for a write. DeviceError for a Modbus exception, FrameError for anything else that is not
    the request's answer."""
    unit, fc = buf[at + 6], buf[at + 7]
    if unit != frame.unit:
        raise FrameError(f"{frame.what}: answer from unit {unit}, not {frame.unit}")
    if fc != frame.fc:
        if fc == frame.fc | 0x80 and size == HEADER + 2:
            raise DeviceError(buf[at + 8], frame.what)
        pdu = bytes(buf[at + 7 : at + size]).hex(" ")
        raise FrameError(f"{frame.what}: answer with function {fc} ({pdu})")
    nbytes = frame.nbytes
    if nbytes < 0:
        if size != HEADER + 5 or buf[at + 7 : at + 12] != frame.echo:
            raise FrameError(f"{frame.what}: the answer {bytes(buf[at + 7 : at + size]).hex(' ')} does not "
                             f"echo {frame.echo.hex(' ')}")
        return b""
    if size != HEADER + 2 + nbytes or buf[at + 8] != nbytes:
        raise FrameError(f"{frame.what}: answer of {size - HEADER} bytes "
                         f"({bytes(buf[at + 7 : at + min(size, 15)]).hex(' ')}), not {nbytes} bytes of data")
    return bytes(buf[at + 9 : at + size])
