"""The Modbus wire: endpoints, one client per node, a Modbus TCP server, and their event-loop thread.

pymodbus changes its API at every minor release (docs/architecture.md section 7), so
this is the only module that imports it, and nothing of pymodbus leaks out: callers see
`LinkError` (the transport failed: refused, timed out, lost) and `DeviceError` (the device answered
with a Modbus exception). Retries and reconnect back-off belong to the exchange, so the pymodbus
clients are built with `retries=0` and `reconnect_delay=0` (no reconnect task of their own).

The server is our own small Modbus TCP protocol rather than pymodbus's: NetPlc memory must be
served from the engine's snapshot and written through the engine's queue, journaled with the
peer's address, and the pymodbus 3.16 server offers none of that (its datastore is copied into an
internal SimCore, the context API gets no peer, and it echoes FC5/FC6 writes by reading the value
back, which a queued write has not reached yet).
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import struct
import threading
import time
from collections import deque
from collections.abc import Awaitable, Callable, Coroutine
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar
from urllib.parse import parse_qsl, urlsplit

from pymodbus.client import AsyncModbusSerialClient, AsyncModbusTcpClient
from pymodbus.exceptions import ModbusException
from pymodbus.framer import FramerType

from netplc.modbus.map import (
    BIT_TABLES,
    MAX_READ_BITS,
    MAX_READ_REGISTERS,
    MAX_WRITE_BITS,
    MAX_WRITE_REGISTERS,
    MapError,
    Table,
    bits_from_bytes,
    bytes_from_bits,
)

# pymodbus logs every refused connect and every timeout; the exchange reports link changes itself
# (node statistics and 'system' records), so a dead node must not flood the log.
logging.getLogger("pymodbus").setLevel(logging.CRITICAL)

T = TypeVar("T")


class LinkError(Exception):
    """The transport failed: connection refused or lost, or no answer within the timeout."""


class ProtocolError(LinkError):
    """An answer that is not the request's: too short, another function code or unit, a wrong
    byte count or echo. It counts as a failed attempt, like no answer at all."""


class DeviceError(Exception):
    """The device answered with a Modbus exception (2 = illegal data address, ...)."""

    def __init__(self, code: int, what: str) -> None:
        self.code = code
        super().__init__(f"{what}: Modbus exception {code}")


# --- endpoints -----------------------------------------------------------------------------------

PARITIES = ("N", "E", "O")


@dataclass(frozen=True, slots=True)
class Endpoint:
    """`tcp://host:port` or `rtu:///dev/ttyX?baudrate=19200&parity=N&bytesize=8&stopbits=1`."""

    scheme: str  # "tcp" | "rtu"
    host: str = ""
    port: int = 502
    device: str = ""
    baudrate: int = 19200
    parity: str = "N"
    bytesize: int = 8
    stopbits: int = 1

    def __str__(self) -> str:
        if self.scheme == "tcp":
            return f"tcp://{self.host}:{self.port}"
        return f"rtu://{self.device}?baudrate={self.baudrate}&parity={self.parity}"


def parse_endpoint(text: str) -> Endpoint:
    """Parse an endpoint; ValueError says what is wrong with it and shows the expected form."""
    forms = "expected tcp://host:port, rtu:///dev/ttyX?baudrate=19200&parity=N or rtu://COM3?baudrate=..."
    try:
        url = urlsplit(text.strip())
        port = url.port
    except ValueError as e:
        raise ValueError(f"endpoint {text!r}: {e} ({forms})") from None
    if url.scheme == "tcp":
        if not url.hostname:
            raise ValueError(f"endpoint {text!r}: no host ({forms})")
        if url.path not in ("", "/") or url.query:
            raise ValueError(f"endpoint {text!r}: a tcp endpoint has no path or options ({forms})")
        try:
            url.hostname.encode("idna")
        except UnicodeError:
            raise ValueError(f"endpoint {text!r}: {url.hostname!r} is not a valid host name") from None
        return Endpoint("tcp", host=url.hostname, port=port if port is not None else 502)
    if url.scheme == "rtu":
        # rtu:///dev/ttyS0 names a device path; rtu://COM3 a Windows port (the URL's "host")
        device = url.path if not url.netloc else url.netloc if not url.path else ""
        if not device:
            raise ValueError(f"endpoint {text!r}: the serial device must follow rtu:// ({forms})")
        options: dict[str, Any] = {}
        for key, value in parse_qsl(url.query, keep_blank_values=True):
            if key == "parity":
                if value.upper() not in PARITIES:
                    raise ValueError(f"endpoint {text!r}: parity {value!r} is not N, E or O")
                options[key] = value.upper()
            elif key in ("baudrate", "bytesize", "stopbits"):
                if not value.isdigit() or int(value) <= 0:
                    raise ValueError(f"endpoint {text!r}: {key} {value!r} is not a positive number")
                options[key] = int(value)
            else:
                raise ValueError(f"endpoint {text!r}: unknown option {key!r} "
                                 "(baudrate, parity, bytesize, stopbits)")
        return Endpoint("rtu", device=device, **options)
    raise ValueError(f"endpoint {text!r}: unknown scheme {url.scheme!r} ({forms})")


# --- clients -------------------------------------------------------------------------------------

_MBAP = struct.Struct(">HHHB")  # Modbus TCP header: transaction, protocol 0, length, unit
_READ_CODES: dict[str, int] = {"coils": 1, "discrete": 2, "holding": 3, "input": 4}
_ADDRESS_REQUEST = struct.Struct(">BHH")  # function code, address, count (or value)


def take_frames(buf: bytearray) -> list[tuple[int, int, bytes]] | None:
    """Remove the complete Modbus TCP frames from the front of `buf`: (transaction, unit, PDU)
    each; a partial frame stays for the next data. None: the bytes are not Modbus TCP."""
    frames = []
    while len(buf) >= 8:
        tid, proto, length, unit = _MBAP.unpack_from(buf)
        if proto != 0 or not 2 <= length <= 254:
            return None
        if len(buf) < 6 + length:
            break
        frames.append((tid, unit, bytes(buf[7 : 6 + length])))
        del buf[: 6 + length]
    return frames


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
    return PymodbusClient(endpoint, timeout)


class PymodbusClient:
    """A node's connection through pymodbus (TCP or RTU)."""

    def __init__(self, endpoint: Endpoint, timeout: float) -> None:
        self.endpoint = endpoint
        self.timeout = timeout
        self._client: AsyncModbusTcpClient | AsyncModbusSerialClient | None = None
        self._malformed = ""  # what the last TCP frame received had wrong (pymodbus decodes leniently)

    def _make(self) -> AsyncModbusTcpClient | AsyncModbusSerialClient:
        ep = self.endpoint
        if ep.scheme == "tcp":
            return AsyncModbusTcpClient(ep.host, port=ep.port, timeout=self.timeout, retries=0,
                                        reconnect_delay=0, trace_packet=self._inspect)
        return AsyncModbusSerialClient(ep.device, framer=FramerType.RTU, baudrate=ep.baudrate,
                                       parity=ep.parity, bytesize=ep.bytesize, stopbits=ep.stopbits,
                                       timeout=self.timeout, retries=0, reconnect_delay=0)

    @property
    def connected(self) -> bool:
        return self._client is not None and self._client.connected

    async def connect(self) -> None:
        self.close()
        self._client = self._make()
        if not await self._client.connect():
            self.close()
            raise LinkError(f"cannot connect to {self.endpoint}")

    def close(self) -> None:
        if self._client is not None:
            self._client.close()
            self._client = None

    def _inspect(self, sending: bool, data: bytes) -> bytes:
        """pymodbus hands over what a TCP connection received: a read answer whose byte count is
        not what its frame holds is malformed, though pymodbus would decode what it can of it."""
        if not sending:
            pos = 0
            while len(data) - pos >= 9:
                length = _MBAP.unpack_from(data, pos)[2]
                pdu = data[pos + 7 : pos + 6 + length]
                if len(pdu) < length - 1:
                    break
                if pdu[0] in _READ_TABLES and (len(pdu) != 2 + pdu[1] or (pdu[0] > 2 and pdu[1] % 2)):
                    self._malformed = f"answer of {len(pdu)} bytes with byte count {pdu[1]}"
                pos += 6 + length
        return data

    async def _call(self, what: str, request: Awaitable[Any], fc: int) -> Any:
        """The answer to a request of function `fc`: a DeviceError for a Modbus exception, a
        LinkError for no answer, a ProtocolError for an answer to another function."""
        self._malformed = ""
        try:
            response = await request
        except (TimeoutError, ModbusException, OSError) as e:
            raise LinkError(f"{what}: {e}") from None
        if self._malformed:
            raise ProtocolError(f"{what}: {self._malformed}")
        if response.isError():
            raise DeviceError(getattr(response, "exception_code", 4), what)
        if getattr(response, "function_code", None) != fc:
            raise ProtocolError(f"{what}: answer with function {getattr(response, 'function_code', '?')}")
        return response

    async def read(self, unit: int, table: Table, address: int, count: int) -> list[int]:
        """`count` registers or bits of `table` from `address` of device `unit`."""
        c = self._client
        if c is None:
            raise LinkError(f"not connected to {self.endpoint}")
        what = f"read {table} {address}+{count}"
        calls = {"coils": c.read_coils, "discrete": c.read_discrete_inputs,
                 "holding": c.read_holding_registers, "input": c.read_input_registers}
        rr = await self._call(what, calls[table](address, count=count, device_id=unit), _READ_CODES[table])
        if table in BIT_TABLES:
            if len(rr.bits) != 8 * ((count + 7) // 8):
                raise ProtocolError(f"{what}: {len(rr.bits)} coils in the answer")
            return [1 if b else 0 for b in rr.bits[:count]]
        if len(rr.registers) != count:
            raise ProtocolError(f"{what}: {len(rr.registers)} registers in the answer")
        return list(rr.registers)

    async def read_bytes(self, unit: int, table: Table, address: int, count: int) -> bytes:
        values = await self.read(unit, table, address, count)
        if table in BIT_TABLES:
            return bytes_from_bits(values)
        return struct.pack(f">{count}H", *values)

    async def write(self, unit: int, table: Table, address: int, values: list[int]) -> None:
        c = self._client
        if c is None:
            raise LinkError(f"not connected to {self.endpoint}")
        what = f"write {table} {address}+{len(values)}"
        if table == "coils":
            rr = await self._call(what, c.write_coils(address, [bool(v) for v in values], device_id=unit), 15)
        elif table == "holding":
            rr = await self._call(what, c.write_registers(address, values, device_id=unit), 16)
        else:
            raise MapError(f"{table} is a read-only table")
        if (rr.address, rr.count) != (address, len(values)):
            raise ProtocolError(f"{what}: the answer echoes {rr.address}+{rr.count}")


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
    """A Modbus TCP client of our own for the exchange's hot path: one request at a time per
    connection, an MBAP frame in and out, no per-request objects beyond the bytes and a future,
    and the answer's data handed over as bytes (no list of ints). pymodbus's client spends most
    of NetPlc's CPU at a few thousand block reads per second (bench/exchange.py shows both); this
    one also fails a request the moment its connection drops.

    It has one waiter slot: the exchange holds its line's lock around every transaction, and a
    second transaction started while one is in flight is refused (RuntimeError), never mixed up.
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
        proto.transport.write(_MBAP.pack(tid, 0, len(pdu) + 1, unit) + pdu)
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
        reply = await self._transact(unit, _ADDRESS_REQUEST.pack(_READ_CODES[table], address, count), what)
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
        n = len(values)
        if table == "coils":
            data = bytes_from_bits(values)
            request = struct.pack(">BHHB", 15, address, n, len(data)) + data
        elif table == "holding":
            request = struct.pack(f">BHHB{n}H", 16, address, n, 2 * n, *values)
        else:
            raise MapError(f"{table} is a read-only table")
        reply = await self._transact(unit, request, what)
        if reply != request[:5]:
            raise ProtocolError(f"{what}: the answer {reply.hex(' ')} does not echo {request[:5].hex(' ')}")


# --- server --------------------------------------------------------------------------------------

ADU_MAX = 260  # the longest Modbus TCP frame: MBAP header 7 + PDU 253
BUSY = 6  # Modbus exception 6, server device busy: the engine's queue of outside writes is full
_READ_HEAD = struct.Struct(">HHHBBB")  # MBAP + function code + byte count of a read answer
_ADDRESS_COUNT = struct.Struct(">HH")

Answer = Callable[[bytes], None]  # takes the response PDU of a write once it is journaled


@dataclass(frozen=True, slots=True)
class ServerLimits:
    """What one Modbus TCP server grants its clients (station.toml [modbus_server])."""

    max_connections: int = 16  # the next connection is closed at once
    idle_timeout: float = 60.0  # s without a whole request (silent, or a half frame): closed
    max_inflight: int = 32  # answers (of the longest size) a connection may leave unread or waiting


class ServeHandler(Protocol):
    """What a Modbus server serves; MapError from any method answers exception 2."""

    def registers(self, address: int, count: int) -> bytes:
        """`count` registers from `address` as the answer carries them (big-endian words)."""
        ...

    def bits(self, address: int, count: int) -> bytes:
        """`count` coils from `address`, packed as the answer carries them."""
        ...

    def write(self, table: Table, address: int, values: list[int], peer: str,
              done: Callable[[bool], None]) -> bool:
        """Queue a write; `done(ok)` once it is applied and journaled. False: busy (exception 6)."""
        ...


_READ_TABLES: dict[int, Table] = {1: "coils", 2: "discrete", 3: "holding", 4: "input"}


class _Refuse(Exception):
    def __init__(self, code: int) -> None:
        self.code = code


def answer(handler: ServeHandler, pdu: bytes, peer: str, later: Answer) -> bytes | None:
    """The response PDU to one request PDU (function codes 1-6, 15, 16; others: exception 1), or
    None for an accepted write, whose response goes to `later` once the write is applied and its
    journal record is durable (or exception 4 if it could not be applied)."""
    fc = pdu[0]
    try:
        if fc in _READ_TABLES:
            if len(pdu) != 5:
                raise _Refuse(3)
            address, count = _ADDRESS_COUNT.unpack_from(pdu, 1)
            if not 1 <= count <= (MAX_READ_BITS if fc <= 2 else MAX_READ_REGISTERS):
                raise _Refuse(3)
            data = handler.bits(address, count) if fc <= 2 else handler.registers(address, count)
            return bytes((fc, len(data))) + data
        if fc in (5, 6, 15, 16):
            table, address, values, echo = _write_request(pdu)
            failed = bytes((fc | 0x80, 4))
            if handler.write(table, address, values, peer, lambda ok: later(echo if ok else failed)):
                return None
            raise _Refuse(BUSY)
        code = 1
    except _Refuse as e:
        code = e.code
    except MapError:
        code = 2
    except Exception:  # a server bug answers "device failure" and the server goes on
        logging.getLogger(__name__).exception("Modbus request %s from %s failed", pdu.hex(" "), peer)
        code = 4
    return bytes((fc | 0x80, code))


def _write_request(pdu: bytes) -> tuple[Table, int, list[int], bytes]:
    """(table, address, values, echo) of a write request; _Refuse(3) if it is malformed."""
    fc = pdu[0]
    if fc in (5, 6):
        if len(pdu) != 5:
            raise _Refuse(3)
        address, value = _ADDRESS_COUNT.unpack_from(pdu, 1)
        if fc == 6:
            return "holding", address, [value], pdu
        if value not in (0, 0xFF00):
            raise _Refuse(3)
        return "coils", address, [1 if value else 0], pdu
    if len(pdu) < 6:
        raise _Refuse(3)
    address, count, nbytes = struct.unpack_from(">HHB", pdu, 1)
    data = pdu[6:]
    echo = pdu[:5]
    if fc == 15:
        if not 1 <= count <= MAX_WRITE_BITS or nbytes != (count + 7) // 8 or len(data) != nbytes:
            raise _Refuse(3)
        return "coils", address, bits_from_bytes(data)[:count], echo
    if not 1 <= count <= MAX_WRITE_REGISTERS or nbytes != 2 * count or len(data) != nbytes:
        raise _Refuse(3)
    return "holding", address, list(struct.unpack(f">{count}H", data)), echo


class Throttle:
    """One journal line per cause per minute: a flood of refused connections, malformed frames or
    loop errors must not flood the journal or the log (issue 18). What was held back is counted in
    the cause's next line."""

    def __init__(self, emit: Callable[[str], None], period: float = 60.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.emit = emit
        self.period = period
        self.clock = clock
        self._last: dict[str, float] = {}
        self._held: dict[str, int] = {}

    def __call__(self, cause: str, text: str) -> None:
        now = self.clock()
        last = self._last.get(cause)
        if last is not None and now - last < self.period:
            self._held[cause] = self._held.get(cause, 0) + 1
            return
        self._last[cause] = now
        held = self._held.pop(cause, 0)
        self.emit(f"{text} (and {held} more like it in the last minute)" if held else text)


class _Connection(asyncio.Protocol):
    """One client. Answers leave in the order of the requests: behind a write waiting for its
    scan and journal record, later answers wait too. A connection stops being read while more
    than `max_inflight` answers' worth of bytes wait to be read by the client or wait behind a
    write; the writes themselves are bounded by the engine's queue (exception 6 when it is full)."""

    def __init__(self, server: TcpServer) -> None:
        self.server = server
        self.buf = bytearray()
        self.transport: asyncio.Transport | None = None
        self.peer = "?"
        self.held: deque[list[Any]] = deque()  # [frame or None (waiting), tid, unit] behind a write
        self.held_bytes = 0  # of the answers ready in `held`
        self.high = server.limits.max_inflight * ADU_MAX  # answer bytes that may wait unread
        self.blocked = False  # the client does not read its answers (the transport's buffer is full)
        self.reading = True
        self.last = 0.0  # loop time of the last data

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        server = self.server
        peer = transport.get_extra_info("peername")
        self.peer = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) else str(peer)
        limit = server.limits.max_connections
        if len(server.connections) >= limit:
            transport.close()
            server.note("connections", f"Modbus server refused a connection from {self.peer}: "
                                       f"{limit} connections are open (max_connections)")
            return
        self.transport = transport
        self.last = server.loop_time()
        server.connections.add(self)
        transport.set_write_buffer_limits(high=self.high)

    def connection_lost(self, exc: Exception | None) -> None:
        self.transport = None
        self.held.clear()
        self.held_bytes = 0
        self.server.connections.discard(self)

    def pause_writing(self) -> None:
        self.blocked = True

    def resume_writing(self) -> None:
        self.blocked = False
        self._serve()

    def data_received(self, data: bytes) -> None:
        if self.transport is None:
            return
        self.buf += data
        self.last = self.server.last_data = self.server.loop_time()
        self._serve()

    def _serve(self) -> None:
        """Answer the whole requests in the buffer, as many as the limits allow."""
        transport = self.transport
        if transport is None:
            return
        server = self.server
        handler, only, limit = server.handler, server.unit, server.limits.max_inflight
        buf, held = self.buf, self.held
        pos, end, out, n = 0, len(self.buf), bytearray(), 0
        while end - pos >= 8 and not self.blocked and self.held_bytes < self.high:
            tid, proto, length, unit = _MBAP.unpack_from(buf, pos)
            if proto != 0 or not 2 <= length <= 254:
                server.note("frames", f"Modbus server closed the connection of {self.peer}: "
                                      f"not Modbus TCP (protocol {proto}, length {length})")
                transport.close()
                self.transport = None
                return
            nxt = pos + 6 + length
            if nxt > end:
                break
            fc = buf[pos + 7]
            if only is not None and unit != only:
                out += _MBAP.pack(tid, 0, 3, unit) + bytes((fc | 0x80, 0x0B))  # gateway: no such unit
            elif (fc == 3 or fc == 4) and length == 6:  # the hot path: registers from the snapshot
                address, count = _ADDRESS_COUNT.unpack_from(buf, pos + 8)
                try:
                    if not 1 <= count <= MAX_READ_REGISTERS:
                        raise _Refuse(3)
                    data = handler.registers(address, count)
                except _Refuse as e:
                    out += _MBAP.pack(tid, 0, 3, unit) + bytes((fc | 0x80, e.code))
                except MapError:
                    out += _MBAP.pack(tid, 0, 3, unit) + bytes((fc | 0x80, 2))
                else:
                    out += _READ_HEAD.pack(tid, 0, len(data) + 3, unit, fc, len(data))
                    out += data
            else:
                slot: list[Any] = [None, tid, unit]
                response = answer(handler, bytes(buf[pos + 7 : nxt]), self.peer,
                                  functools.partial(server.finished, self, slot))
                if response is None:  # a write waiting for its scan: what follows waits behind it
                    if out:
                        self._send(out)
                        out = bytearray()
                    held.append(slot)
                else:
                    out += _MBAP.pack(tid, 0, len(response) + 1, unit) + response
            pos = nxt
            n += 1
            if n % limit == 0 and out:  # a client that does not read stops us here (pause_writing)
                self._send(out)
                out = bytearray()
        if pos:
            del buf[:pos]
        if out:
            self._send(out)
        if self.transport is None:
            return
        stop = self.blocked or self.held_bytes >= self.high
        if stop and self.reading:
            self.reading = False
            transport.pause_reading()
        elif not stop and not self.reading:
            self.reading = True
            transport.resume_reading()

    def _send(self, frames: bytearray | bytes) -> None:
        if self.held:
            self.held.append([bytes(frames), 0, 0])
            self.held_bytes += len(frames)
        elif self.transport is not None:
            self.transport.write(frames)

    def answered(self, slot: list[Any], response: bytes) -> None:
        """A held write is journaled (server loop): send it and the answers held behind it."""
        if self.transport is None:
            return
        slot[0] = frame = _MBAP.pack(slot[1], 0, len(response) + 1, slot[2]) + response
        self.held_bytes += len(frame)
        held = self.held
        out = bytearray()
        while held and held[0][0] is not None:
            out += held.popleft()[0]
        self.held_bytes -= len(out)
        if out:
            self.transport.write(out)
        if self.buf or not self.reading:
            self._serve()


class TcpServer:
    """A listening Modbus TCP server on the running loop; `close()` also drops its connections,
    so clients see a stopped server at once, as they would a switched-off device.

    `note(text)` journals what the operator should know (refused connections, idle connections
    closed, loop errors), at most one line per cause per minute."""

    def __init__(self, handler: ServeHandler, unit: int | None, limits: ServerLimits | None = None,
                 note: Callable[[str], None] | None = None) -> None:
        self.handler = handler
        self.unit = unit
        self.limits = limits or ServerLimits()
        self.note = Throttle(note or logging.getLogger(__name__).warning)
        self.connections: set[_Connection] = set()
        self._server: asyncio.Server | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._sweep: asyncio.TimerHandle | None = None
        self._finished: deque[tuple[_Connection, list[Any], bytes]] = deque()
        self._wake = False
        self.last_data = 0.0
        self.port = 0

    def loop_time(self) -> float:
        assert self._loop is not None
        return self._loop.time()

    async def listen(self, host: str, port: int) -> None:
        loop = self._loop = asyncio.get_running_loop()
        loop.set_exception_handler(self._loop_error)
        self._server = await loop.create_server(lambda: _Connection(self), host, port)
        self.port = self._server.sockets[0].getsockname()[1]
        self._schedule_sweep()

    def _loop_error(self, loop: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        """asyncio's own errors (accept() out of file descriptors, ...): one line per cause a minute."""
        message = context.get("message", "error")
        error = context.get("exception")
        self.note(f"loop: {message}", f"Modbus server: {message}{f': {error}' if error else ''}")

    def _schedule_sweep(self) -> None:
        assert self._loop is not None
        self._sweep = self._loop.call_later(min(1.0, self.limits.idle_timeout / 4), self._close_idle)

    def _close_idle(self) -> None:
        """One timer for the whole server: connections silent (or holding half a frame) for
        idle_timeout are closed."""
        now, idle = self.loop_time(), self.limits.idle_timeout
        for conn in list(self.connections):
            if now - conn.last > idle and conn.transport is not None:
                what = "half a frame" if conn.buf else "nothing"
                self.note("idle", f"Modbus server closed the connection of {conn.peer}: {what} "
                                  f"received for {idle:g} s (idle_timeout)")
                conn.transport.abort()
        self._schedule_sweep()

    def finished(self, conn: _Connection, slot: list[Any], response: bytes) -> None:
        """A write's answer is due (any thread): handed to the loop, one wake-up per batch."""
        self._finished.append((conn, slot, response))
        if not self._wake and self._loop is not None:
            self._wake = True
            with contextlib.suppress(RuntimeError):  # a closed loop: the server stopped, nobody to answer
                self._loop.call_soon_threadsafe(self._deliver)

    def _deliver(self) -> None:
        self._wake = False
        finished = self._finished
        while finished:
            conn, slot, response = finished.popleft()
            conn.answered(slot, response)

    async def close(self) -> None:
        if self._sweep is not None:
            self._sweep.cancel()
        if self._server is not None:
            self._server.close()
        for conn in list(self.connections):
            if conn.transport is not None:
                conn.transport.abort()
        if self._server is not None:
            await self._server.wait_closed()
            self._server = None


# --- the event-loop thread ----------------------------------------------------------------------


class LoopThread:
    """An asyncio event loop on a thread of its own: the exchange and the server run there, so
    neither the scan thread nor the GUI thread ever waits on a socket."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        loop = asyncio.new_event_loop()
        self.loop = loop
        self._thread = threading.Thread(target=self._run, args=(loop,), name=self.name, daemon=True)
        self._thread.start()

    @staticmethod
    def _run(loop: asyncio.AbstractEventLoop) -> None:
        asyncio.set_event_loop(loop)
        loop.run_forever()
        loop.run_until_complete(loop.shutdown_asyncgens())
        loop.close()

    def run(self, coro: Coroutine[Any, Any, T], timeout: float = 10.0) -> T:
        """Run `coro` on the loop and wait for its result (from another thread)."""
        if self.loop is None:
            raise RuntimeError(f"{self.name} is not started")
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result(timeout)

    def call(self, fn: Callable[..., object], *args: object) -> None:
        """Schedule `fn(*args)` on the loop (thread-safe, does not wait)."""
        if self.loop is not None:
            self.loop.call_soon_threadsafe(fn, *args)

    def stop(self, timeout: float = 5.0) -> None:
        loop, self.loop = self.loop, None
        if loop is None:
            return

        async def cancel_all() -> None:
            # Cancel again while anything is left: on Python 3.11 asyncio.wait_for (used inside
            # pymodbus) swallows a cancellation that arrives as its inner future completes.
            for _ in range(20):
                tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task() and not t.done()]
                if not tasks:
                    return
                for t in tasks:
                    t.cancel()
                await asyncio.wait(tasks, timeout=0.1)

        try:
            asyncio.run_coroutine_threadsafe(cancel_all(), loop).result(timeout)
        finally:
            loop.call_soon_threadsafe(loop.stop)
            if self._thread is not None:
                self._thread.join(timeout)
