"""Asyncio Modbus clients (`open_client`): our lean TCP client, for the Program view's and the
designer's reads of a station, and pymodbus's, through which the exchange reaches serial RTU lines
(and TCP nodes when bench/exchange.py compares it). The exchange's own TCP nodes do not use these:
they are served by its selector thread (netplc/tcp_exchange.py).

Retries and reconnect back-off belong to the exchange (netplc/exchange.py), not to a client.
"""

from __future__ import annotations

import asyncio
import struct
from typing import Protocol

from netplc.modbus.endpoint import Endpoint
from netplc.modbus.frames import read_pdu, write_pdu
from netplc.modbus.map import BIT_TABLES, Table, bits_from_bytes
from netplc.modbus.pdu import (
    MBAP,
    DeviceError,
    LinkError,
    ProtocolError,
    take_frames,
)


class ModbusClient(Protocol):
    """One node's connection: connect, read and write a table, close."""

    endpoint: Endpoint

    @property
    def connected(self) -> bool: ...

    async def connect(self) -> None: ...

    def close(self) -> None: ...

    async def read(self, unit: int, table: Table, address: int, count: int) -> list[int]: ...

    async def read_bytes(self, unit: int, table: Table, address: int, count: int) -> bytes: ...

    async def write(self, unit: int, table: Table, address: int, values: list[int]) -> None: ...


def open_client(endpoint: Endpoint, timeout: float, lean: bool = True) -> ModbusClient:
    """The client for an endpoint: serial RTU through pymodbus's serial framer; TCP through our
    lean client (`lean=False`: pymodbus's, which bench/exchange.py compares it with). The unit id
    goes with each request, so the nodes of one RS-485 line can share one client."""
    if endpoint.scheme == "tcp" and lean:
        return LeanTcpClient(endpoint, timeout)
    from netplc.modbus.pymodbus_client import PymodbusClient  # pymodbus loads only for the nodes it serves

    return PymodbusClient(endpoint, timeout)


class _Answers(asyncio.Protocol):
    """Collects Modbus TCP answers on a client connection and hands the awaited one over.

    One timer per connection watches the transaction in flight: it is armed once and, when it
    fires, fails the transaction whose deadline has passed or re-arms for the one now in flight,
    so a request costs no timer handle of its own (asyncio.wait_for costs one, a future and an
    extra turn of the event loop per request)."""

    def __init__(self) -> None:
        self.buf = bytearray()
        self.transport: asyncio.Transport | None = None
        self.waiter: asyncio.Future[bytes] | None = None
        self.tid = 0  # the transaction awaited; late answers to abandoned ones are dropped
        self.unit = 0  # the unit it was sent to: an answer from another unit is a failed attempt
        self.deadline = 0.0  # loop time by which the transaction in flight must be answered
        self.timer: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport

    def arm(self, loop: asyncio.AbstractEventLoop, timeout: float) -> None:
        self.deadline = loop.time() + timeout
        if self.timer is None:
            self.timer = loop.call_at(self.deadline, self._expire, loop)

    def _expire(self, loop: asyncio.AbstractEventLoop) -> None:
        self.timer = None
        waiter = self.waiter
        if waiter is None or waiter.done():
            return
        if loop.time() + 1e-3 >= self.deadline:  # call_at may run up to the clock's resolution early
            waiter.set_exception(TimeoutError())
        else:
            self.timer = loop.call_at(self.deadline, self._expire, loop)

    def data_received(self, data: bytes) -> None:
        self.buf += data
        frames = take_frames(self.buf)
        if frames is None:  # not Modbus TCP: the next request reconnects
            assert self.transport is not None
            self.transport.abort()
            return
        for tid, unit, pdu in frames:
            waiter = self.waiter
            if tid == self.tid and waiter is not None and not waiter.done():
                if unit == self.unit:
                    waiter.set_result(pdu)
                else:
                    waiter.set_exception(ProtocolError(f"answer from unit {unit}, not {self.unit}"))

    def connection_lost(self, exc: Exception | None) -> None:
        self.transport = None
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None
        waiter = self.waiter
        if waiter is not None and not waiter.done():
            waiter.set_exception(LinkError(f"connection lost{f': {exc}' if exc else ''}"))


class LeanTcpClient:
    """A Modbus TCP client of our own for asyncio callers: one request at a time per connection, an
    MBAP frame in and out, no per-request objects beyond the bytes and a future, and the answer's
    data handed over as bytes (no list of ints); it fails a request the moment its connection drops.

    It has one waiter slot: a second transaction started while one is in flight is refused
    (RuntimeError), never mixed up.
    Every answer is checked against its request (unit id, function code, byte count, the echo of
    a write); one that does not match is a ProtocolError."""

    def __init__(self, endpoint: Endpoint, timeout: float) -> None:
        self.endpoint = endpoint
        self.timeout = timeout
        self._proto: _Answers | None = None
        self._tid = 0

    @property
    def connected(self) -> bool:
        return self._proto is not None and self._proto.transport is not None

    async def connect(self) -> None:
        self.close()
        loop = asyncio.get_running_loop()
        try:
            _, proto = await asyncio.wait_for(
                loop.create_connection(_Answers, self.endpoint.host, self.endpoint.port), self.timeout)
        except (OSError, TimeoutError) as e:
            raise LinkError(f"cannot connect to {self.endpoint}: {e or 'timed out'}") from None
        self._proto = proto

    def close(self) -> None:
        proto, self._proto = self._proto, None
        if proto is not None and proto.transport is not None:
            proto.transport.abort()

    async def _transact(self, unit: int, pdu: bytes, what: str) -> bytes:
        proto = self._proto
        if proto is None or proto.transport is None:
            raise LinkError(f"{what}: not connected to {self.endpoint}")
        if proto.waiter is not None:
            raise RuntimeError(f"{what}: a transaction with {self.endpoint} is already in flight")
        self._tid = tid = self._tid % 0xFFFF + 1
        loop = asyncio.get_running_loop()
        waiter = loop.create_future()
        proto.tid, proto.unit, proto.waiter = tid, unit, waiter
        proto.arm(loop, self.timeout)
        proto.transport.write(MBAP.pack(tid, 0, len(pdu) + 1, unit) + pdu)
        try:
            reply = await waiter
        except TimeoutError:
            raise LinkError(f"{what}: no answer within {self.timeout:g} s") from None
        except ProtocolError as e:
            raise ProtocolError(f"{what}: {e}") from None
        finally:
            proto.waiter = None
        if len(reply) == 2 and reply[0] == pdu[0] | 0x80:
            raise DeviceError(reply[1], what)
        if reply[0] != pdu[0]:
            raise ProtocolError(f"{what}: answer with function {reply[0]} ({reply.hex(' ')})")
        return reply

    async def read_bytes(self, unit: int, table: Table, address: int, count: int) -> bytes:
        """The answer's data as the wire carries it: registers big-endian, coils packed."""
        what = f"read {table} {address}+{count}"
        reply = await self._transact(unit, read_pdu(table, address, count), what)
        size = (count + 7) // 8 if table in BIT_TABLES else 2 * count
        if len(reply) != size + 2 or reply[1] != size:
            raise ProtocolError(f"{what}: answer of {len(reply)} bytes ({reply[:8].hex(' ')}), "
                                f"not {size} bytes of data")
        return reply[2:]

    async def read(self, unit: int, table: Table, address: int, count: int) -> list[int]:
        data = await self.read_bytes(unit, table, address, count)
        if table in BIT_TABLES:
            return bits_from_bytes(data)[:count]
        return list(struct.unpack(f">{count}H", data))

    async def write(self, unit: int, table: Table, address: int, values: list[int]) -> None:
        what = f"write {table} {address}+{len(values)}"
        request = write_pdu(table, address, values)
        reply = await self._transact(unit, request, what)
        if reply != request[:5]:
            raise ProtocolError(f"{what}: the answer {reply.hex(' ')} does not echo {request[:5].hex(' ')}")
