"""Our Modbus TCP server: connections, the limits a client is held to, and the order of answers.

It is our own small protocol rather than pymodbus's server: NetPlc memory must be served from the
snapshot and written through the station's queue, journaled with the peer's address, and the
pymodbus 3.16 server offers none of that (its datastore is copied into an internal SimCore, the
context API gets no peer, and it echoes FC5/FC6 writes by reading the value back, which a queued
write has not reached yet). What is served is the handler's (`pdu.ServeHandler`).
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from netplc.modbus.map import MAX_READ_REGISTERS, MapError
from netplc.modbus.pdu import (
    ADDRESS_COUNT,
    ADU_MAX,
    DEVICE_FAILURE,
    ILLEGAL_ADDRESS,
    ILLEGAL_VALUE,
    MBAP,
    READ_HEAD,
    Refuse,
    ServeHandler,
    answer,
)
from netplc.words import Say, english

logger = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class ServerLimits:
    """What one Modbus TCP server grants its clients (station.toml [modbus_server])."""

    max_connections: int = 16  # the next connection is closed at once
    idle_timeout: float = 60.0  # s without a whole request (silent, or a half frame): closed
    max_inflight: int = 32  # answers (of the longest size) a connection may leave unread or waiting
    max_per_peer: int = 4  # connections from one address (within max_connections); the next is closed


TURN = 128  # requests a connection is answered in a row before every other connection's turn


class Throttle:
    """One journal line per cause per minute: a flood of refused connections, malformed frames or
    loop errors must not flood the journal or the log (issue 18). What was held back is counted in
    the cause's next line."""

    def __init__(self, emit: Callable[[str], None], period: float = 60.0,
                 clock: Callable[[], float] = time.monotonic, words: Say = english) -> None:
        self.emit = emit
        self.words = words
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
        self.emit(self.words("more like it", text=text, n=held) if held else text)


class _Connection(asyncio.Protocol):
    """One client. Answers leave in the order of the requests: behind a write waiting for its
    scan and journal record, later answers wait too. A connection stops being read while more
    than `max_inflight` answers' worth of bytes wait to be read by the client or wait behind a
    write; the writes themselves are bounded by the station's queue (exception 6 when it is full).

    Service is fair: a connection is answered at most TURN requests in a row, then stops being
    read and waits for the next turn of the event loop, after every other connection with data
    has had its own; so a client pipelining requests as fast as it can delays another by a
    turn of each connection (well under a millisecond each), never by its whole backlog."""

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
        self.queued = False  # its next turn is due on the loop
        self.host = ""  # the peer's address, once the connection is counted against its limits
        self.last = 0.0  # loop time of the last data

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        server = self.server
        peer = transport.get_extra_info("peername")
        self.peer = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) else str(peer)
        host = str(peer[0]) if isinstance(peer, tuple) else self.peer
        limits, peers = server.limits, server.peers
        if peers.get(host, 0) >= limits.max_per_peer:
            transport.close()
            server.note("peer", server.words("peer refused", peer=self.peer, n=limits.max_per_peer,
                                             host=host))
            return
        if len(server.connections) >= limits.max_connections:
            transport.close()
            server.note("connections", server.words("server full", peer=self.peer, n=limits.max_connections))
            return
        self.transport = transport
        self.host = host
        self.last = server.loop_time()
        server.connections.add(self)
        peers[host] = peers.get(host, 0) + 1
        transport.set_write_buffer_limits(high=self.high)

    def connection_lost(self, exc: Exception | None) -> None:
        self.transport = None
        self.held.clear()
        self.held_bytes = 0
        server = self.server
        if self in server.connections:
            server.connections.discard(self)
            left = server.peers[self.host] - 1
            if left:
                server.peers[self.host] = left
            else:
                del server.peers[self.host]

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

    def _turn(self) -> None:
        self.queued = False
        self._serve()

    def _serve(self) -> None:
        """Answer the whole requests in the buffer, as many as the limits and a turn allow."""
        transport = self.transport
        if transport is None:
            return
        server = self.server
        handler, only, limit = server.handler, server.unit, server.limits.max_inflight
        buf, held = self.buf, self.held
        pos, end, out, n = 0, len(self.buf), bytearray(), 0
        while end - pos >= 8 and n < TURN and not self.blocked and self.held_bytes < self.high:
            tid, proto, length, unit = MBAP.unpack_from(buf, pos)
            if proto != 0 or not 2 <= length <= 254:
                server.note("frames", server.words("not modbus tcp", peer=self.peer, proto=proto,
                                                   length=length))
                transport.close()
                self.transport = None
                return
            nxt = pos + 6 + length
            if nxt > end:
                break
            fc = buf[pos + 7]
            if only is not None and unit != only:
                out += MBAP.pack(tid, 0, 3, unit) + bytes((fc | 0x80, 0x0B))  # gateway: no such unit
            elif (fc == 3 or fc == 4) and length == 6:  # the hot path: registers from the snapshot
                address, count = ADDRESS_COUNT.unpack_from(buf, pos + 8)
                try:
                    if not 1 <= count <= MAX_READ_REGISTERS:
                        raise Refuse(ILLEGAL_VALUE)
                    data = handler.registers(address, count)
                except Refuse as e:
                    out += MBAP.pack(tid, 0, 3, unit) + bytes((fc | 0x80, e.code))
                except MapError:
                    out += MBAP.pack(tid, 0, 3, unit) + bytes((fc | 0x80, ILLEGAL_ADDRESS))
                except Exception:  # a handler's bug answers "device failure", as in `answer`
                    logger.exception("Modbus read of %d registers at %d from %s failed", count, address,
                                     self.peer)
                    out += MBAP.pack(tid, 0, 3, unit) + bytes((fc | 0x80, DEVICE_FAILURE))
                else:
                    out += READ_HEAD.pack(tid, 0, len(data) + 3, unit, fc, len(data))
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
                    out += MBAP.pack(tid, 0, len(response) + 1, unit) + response
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
        waits = self.blocked or self.held_bytes >= self.high  # resume_writing or answered goes on
        if n >= TURN and not waits and not self.queued:  # the others' turn first, then ours again
            self.queued = True
            server.next_turn(self._turn)
        stop = waits or n >= TURN
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
        slot[0] = frame = MBAP.pack(slot[1], 0, len(response) + 1, slot[2]) + response
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
                 note: Callable[[str], None] | None = None, words: Say = english) -> None:
        self.handler = handler
        self.unit = unit
        self.limits = limits or ServerLimits()
        self.words = words  # the station's words for its records (netplc/words.py)
        self.note = Throttle(note or logger.warning, words=words)
        self.connections: set[_Connection] = set()
        self.peers: dict[str, int] = {}  # open connections by the peer's address
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

    def next_turn(self, serve: Callable[[], None]) -> None:
        assert self._loop is not None
        self._loop.call_soon(serve)

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
                self.note("idle", self.words("idle half" if conn.buf else "idle nothing", peer=conn.peer,
                                             idle=idle))
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
