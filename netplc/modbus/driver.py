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
import logging
import struct
import threading
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

    def _make(self) -> AsyncModbusTcpClient | AsyncModbusSerialClient:
        ep = self.endpoint
        if ep.scheme == "tcp":
            return AsyncModbusTcpClient(ep.host, port=ep.port, timeout=self.timeout, retries=0,
                                        reconnect_delay=0)
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

    async def _call(self, what: str, request: Awaitable[Any]) -> Any:
        try:
            response = await request
        except (TimeoutError, ModbusException, OSError) as e:
            raise LinkError(f"{what}: {e}") from None
        if response.isError():
            raise DeviceError(getattr(response, "exception_code", 4), what)
        return response

    async def read(self, unit: int, table: Table, address: int, count: int) -> list[int]:
        """`count` registers or bits of `table` from `address` of device `unit`."""
        c = self._client
        if c is None:
            raise LinkError(f"not connected to {self.endpoint}")
        what = f"read {table} {address}+{count}"
        if table == "coils":
            rr = await self._call(what, c.read_coils(address, count=count, device_id=unit))
        elif table == "discrete":
            rr = await self._call(what, c.read_discrete_inputs(address, count=count, device_id=unit))
        elif table == "holding":
            rr = await self._call(what, c.read_holding_registers(address, count=count, device_id=unit))
        else:
            rr = await self._call(what, c.read_input_registers(address, count=count, device_id=unit))
        if table in BIT_TABLES:
            return [1 if b else 0 for b in rr.bits[:count]]
        if len(rr.registers) != count:
            raise LinkError(f"{what}: {len(rr.registers)} registers in the answer")
        return list(rr.registers)

    async def write(self, unit: int, table: Table, address: int, values: list[int]) -> None:
        c = self._client
        if c is None:
            raise LinkError(f"not connected to {self.endpoint}")
        what = f"write {table} {address}+{len(values)}"
        if table == "coils":
            await self._call(what, c.write_coils(address, [bool(v) for v in values], device_id=unit))
        elif table == "holding":
            await self._call(what, c.write_registers(address, values, device_id=unit))
        else:
            raise MapError(f"{table} is a read-only table")


class _Answers(asyncio.Protocol):
    """Collects Modbus TCP answers on a client connection and hands the awaited one over."""

    def __init__(self) -> None:
        self.buf = bytearray()
        self.transport: asyncio.Transport | None = None
        self.waiter: asyncio.Future[bytes] | None = None
        self.tid = 0  # the transaction awaited; late answers to abandoned ones are dropped

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport

    def data_received(self, data: bytes) -> None:
        self.buf += data
        frames = take_frames(self.buf)
        if frames is None:  # not Modbus TCP: the next request reconnects
            assert self.transport is not None
            self.transport.abort()
            return
        for tid, _, pdu in frames:
            waiter = self.waiter
            if tid == self.tid and waiter is not None and not waiter.done():
                waiter.set_result(pdu)

    def connection_lost(self, exc: Exception | None) -> None:
        self.transport = None
        waiter = self.waiter
        if waiter is not None and not waiter.done():
            waiter.set_exception(LinkError(f"connection lost{f': {exc}' if exc else ''}"))


class LeanTcpClient:
    """A Modbus TCP client of our own for the exchange's hot path: one request at a time per
    connection, an MBAP frame in and out, no per-request objects beyond the bytes. pymodbus's
    client spends most of NetPlc's CPU at a few thousand block reads per second (bench/exchange.py
    shows both); this one also fails a request the moment its connection drops."""

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
        self._tid = tid = self._tid % 0xFFFF + 1
        waiter = asyncio.get_running_loop().create_future()
        proto.tid, proto.waiter = tid, waiter
        proto.transport.write(_MBAP.pack(tid, 0, len(pdu) + 1, unit) + pdu)
        try:
            reply = await asyncio.wait_for(waiter, self.timeout)
        except TimeoutError:
            raise LinkError(f"{what}: no answer within {self.timeout:g} s") from None
        finally:
            proto.waiter = None
        if reply[0] == pdu[0] | 0x80 and len(reply) == 2:
            raise DeviceError(reply[1], what)
        if reply[0] != pdu[0]:
            raise LinkError(f"{what}: answer with function {reply[0]}")
        return reply

    async def read(self, unit: int, table: Table, address: int, count: int) -> list[int]:
        what = f"read {table} {address}+{count}"
        fc = _READ_CODES[table]
        reply = await self._transact(unit, struct.pack(">BHH", fc, address, count), what)
        data = reply[2:]
        if table in BIT_TABLES:
            if len(data) != reply[1] or len(data) != (count + 7) // 8:
                raise LinkError(f"{what}: {len(data)} bytes of coils in the answer")
            return bits_from_bytes(data)[:count]
        if len(data) != reply[1] or len(data) != 2 * count:
            raise LinkError(f"{what}: {len(data) // 2} registers in the answer")
        return list(struct.unpack(f">{count}H", data))

    async def write(self, unit: int, table: Table, address: int, values: list[int]) -> None:
        what = f"write {table} {address}+{len(values)}"
        n = len(values)
        if table == "coils":
            data = bytes_from_bits(values)
            await self._transact(unit, struct.pack(">BHHB", 15, address, n, len(data)) + data, what)
        elif table == "holding":
            await self._transact(unit, struct.pack(f">BHHB{n}H", 16, address, n, 2 * n, *values), what)
        else:
            raise MapError(f"{table} is a read-only table")


# --- server --------------------------------------------------------------------------------------


class ServeHandler(Protocol):
    """What a Modbus server serves; MapError from either method answers exception 2."""

    def read(self, table: Table, address: int, count: int) -> list[int]: ...

    def write(self, table: Table, address: int, values: list[int], peer: str) -> None: ...


_READ_TABLES: dict[int, Table] = {1: "coils", 2: "discrete", 3: "holding", 4: "input"}


class _Refuse(Exception):
    def __init__(self, code: int) -> None:
        self.code = code


def answer(handler: ServeHandler, pdu: bytes, peer: str) -> bytes:
    """The response PDU to one request PDU (function codes 1-6, 15, 16; others: exception 1)."""
    fc = pdu[0]
    try:
        if fc in _READ_TABLES:
            if len(pdu) != 5:
                raise _Refuse(3)
            address, count = struct.unpack_from(">HH", pdu, 1)
            if not 1 <= count <= (MAX_READ_BITS if fc <= 2 else MAX_READ_REGISTERS):
                raise _Refuse(3)
            values = handler.read(_READ_TABLES[fc], address, count)
            data = bytes_from_bits(values) if fc <= 2 else struct.pack(f">{count}H", *values)
            return bytes((fc, len(data))) + data
        if fc in (5, 6):
            if len(pdu) != 5:
                raise _Refuse(3)
            address, value = struct.unpack_from(">HH", pdu, 1)
            if fc == 5:
                if value not in (0, 0xFF00):
                    raise _Refuse(3)
                handler.write("coils", address, [1 if value else 0], peer)
            else:
                handler.write("holding", address, [value], peer)
            return pdu
        if fc in (15, 16):
            if len(pdu) < 6:
                raise _Refuse(3)
            address, count, nbytes = struct.unpack_from(">HHB", pdu, 1)
            data = pdu[6:]
            if fc == 15:
                if not 1 <= count <= MAX_WRITE_BITS or nbytes != (count + 7) // 8 or len(data) != nbytes:
                    raise _Refuse(3)
                handler.write("coils", address, bits_from_bytes(data)[:count], peer)
            else:
                if not 1 <= count <= MAX_WRITE_REGISTERS or nbytes != 2 * count or len(data) != nbytes:
                    raise _Refuse(3)
                handler.write("holding", address, list(struct.unpack(f">{count}H", data)), peer)
            return struct.pack(">BHH", fc, address, count)
        code = 1
    except _Refuse as e:
        code = e.code
    except MapError:
        code = 2
    except Exception:  # a server bug answers "device failure" and the server goes on
        logging.getLogger(__name__).exception("Modbus request %s from %s failed", pdu.hex(" "), peer)
        code = 4
    return bytes((fc | 0x80, code))


class _Connection(asyncio.Protocol):
    def __init__(self, server: TcpServer) -> None:
        self.server = server
        self.buf = bytearray()
        self.transport: asyncio.Transport | None = None
        self.peer = "?"

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        peer = transport.get_extra_info("peername")
        self.peer = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) else str(peer)
        self.server.connections.add(self)

    def connection_lost(self, exc: Exception | None) -> None:
        self.server.connections.discard(self)

    def data_received(self, data: bytes) -> None:
        self.buf += data
        frames = take_frames(self.buf)
        if frames is None:  # not Modbus TCP: drop the peer, as devices do
            assert self.transport is not None
            self.transport.close()
            return
        out = bytearray()
        for tid, unit, pdu in frames:
            if self.server.unit is not None and unit != self.server.unit:
                response = bytes((pdu[0] | 0x80, 0x0B))  # gateway: target device failed to respond
            else:
                response = answer(self.server.handler, pdu, self.peer)
            out += _MBAP.pack(tid, 0, len(response) + 1, unit) + response
        if out and self.transport is not None:
            self.transport.write(bytes(out))


class TcpServer:
    """A listening Modbus TCP server on the running loop; `close()` also drops its connections,
    so clients see a stopped server at once, as they would a switched-off device."""

    def __init__(self, handler: ServeHandler, unit: int | None) -> None:
        self.handler = handler
        self.unit = unit
        self.connections: set[_Connection] = set()
        self._server: asyncio.Server | None = None
        self.port = 0

    async def listen(self, host: str, port: int) -> None:
        loop = asyncio.get_running_loop()
        self._server = await loop.create_server(lambda: _Connection(self), host, port)
        self.port = self._server.sockets[0].getsockname()[1]

    async def close(self) -> None:
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
