"""Our Modbus TCP server: connections, the limits a client is held to, and the order of answers.

It is our own small protocol rather than pymodbus's server: NetPlc memory must be served from the
snapshot and written through the station's queue, journaled with the peer's address, and the
pymodbus 3.16 server offers none of that (its datastore is copied into an internal SimCore, the
context API gets no peer, and it echoes FC5/FC6 writes by reading the value back, which a queued
write has not reached yet). What is served is the handler's (`pdu.ServeHandler`).
"""

from __future__ import annotations

import errno
import functools
import logging
import os
import socket
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
from netplc.modbus.reactor import READ, WRITE, Reactor, Timer
from netplc.words import Say, english

logger = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class ServerLimits:
    """What one Modbus TCP server grants its clients (station.toml [modbus_server])."""

    max_connections: int = 16  # the next connection is closed at once
    idle_timeout: float = 60.0  # s without a whole request (silent, or a half frame): closed
    max_inflight: int = 32  # answers (of the longest size) a connection may leave unread or waiting
    max_per_peer: int = 4  # connections from one address (within max_connections); the next is closed


ACCEPT_RETRY = 1.0  # s without accepting after accept() ran out of descriptors or memory
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


class _Connection:
    """One client on its non-blocking socket. Answers leave in the order of the requests: behind a
    write waiting for its scan and journal record, later answers wait too. A connection stops being
    read while more than `max_inflight` answers' worth of bytes wait to be read by the client or
    wait behind a write; the writes themselves are bounded by the station's queue (exception 6
    when it is full).

    Service is fair: a connection is answered at most TURN requests in a row, then stops being
    read and waits for the next round of the reactor, after every other connection with data
    has had its own; so a client pipelining requests as fast as it can delays another by a
    turn of each connection (well under a millisecond each), never by its whole backlog."""

    def __init__(self, server: TcpServer, sock: socket.socket, peer: str, host: str) -> None:
        self.server = server
        self.sock: socket.socket | None = sock
        self.peer = peer
        self.host = host
        self.buf = bytearray()
        self.out = bytearray()  # answers the socket did not take yet
        self.held: deque[list[Any]] = deque()  # [frame or None (waiting), tid, unit] behind a write
        self.held_bytes = 0  # of the answers ready in `held`
        self.high = server.limits.max_inflight * ADU_MAX  # answer bytes that may wait unread
        self.blocked = False  # the client does not read its answers (`out` is over `high`)
        self.reading = True
        self.closing = False  # closed once `out` is sent
        self.queued = False  # its next turn is due on the reactor
        self.events = READ  # what the selector watches for
        self.last = server.reactor.time()  # of the last data

    # --- the socket ------------------------------------------------------------------------------

    def ready(self, events: int) -> None:
        if events & WRITE:
            self._flush()
        if events & READ and self.sock is not None and self.reading:
            self._receive()

    def _receive(self) -> None:
        assert self.sock is not None
        try:
            data = self.sock.recv(65536)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self.abort()
            return
        if not data:  # the client is done sending: what it asked is answered, then closed
            self.close()
            return
        self.buf += data
        self.last = self.server.last_data = self.server.reactor.time()
        self._serve()

    def _write(self, frames: bytearray | bytes) -> None:
        sock = self.sock
        if sock is None:
            return
        if not self.out:
            try:
                sent = sock.send(frames)
            except (BlockingIOError, InterruptedError):
                sent = 0
            except OSError:
                self.abort()
                return
            if sent == len(frames):
                return
            frames = frames[sent:]
        self.out += frames
        if len(self.out) > self.high:
            self.blocked = True
        self._watch()

    def _flush(self) -> None:
        sock = self.sock
        if sock is None or not self.out:
            return
        try:
            sent = sock.send(self.out)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self.abort()
            return
        del self.out[:sent]
        if self.closing and not self.out:
            self.abort()
            return
        self._watch()
        if self.blocked and len(self.out) <= self.high // 4:
            self.blocked = False
            self._serve()

    def _watch(self) -> None:
        """Tell the selector what this connection waits for now."""
        if self.sock is None:
            return
        events = (READ if self.reading and not self.closing else 0) | (WRITE if self.out else 0)
        if events != self.events:
            selector = self.server.reactor.selector
            if not self.events:
                selector.register(self.sock, events, self)
            elif not events:
                selector.unregister(self.sock)
            else:
                selector.modify(self.sock, events, self)
            self.events = events

    def close(self) -> None:
        """Closed once the answers given are sent; nothing more is read."""
        self.closing = True
        if not self.out:
            self.abort()
        else:
            self._watch()

    def abort(self) -> None:
        """Closed at once: what was not sent is dropped."""
        sock, self.sock = self.sock, None
        if sock is None:
            return
        if self.events:
            self.server.reactor.selector.unregister(sock)
            self.events = 0
        sock.close()
        self.held.clear()
        self.held_bytes = 0
        self.out.clear()
        self.server.lost(self)

    # --- requests --------------------------------------------------------------------------------

    def _turn(self) -> None:
        self.queued = False
        self._serve()

    def _serve(self) -> None:
        """Answer the whole requests in the buffer, as many as the limits and a turn allow."""
        if self.sock is None or self.closing:
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
                if out:
                    self._send(out)
                self.close()
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
            if n % limit == 0 and out:  # a client that does not read stops us here (`blocked`)
                self._send(out)
                out = bytearray()
        if pos:
            del buf[:pos]
        if out:
            self._send(out)
        if self.sock is None:
            return
        waits = self.blocked or self.held_bytes >= self.high  # _flush or answered goes on
        if n >= TURN and not waits and not self.queued:  # the others' turn first, then ours again
            self.queued = True
            server.reactor.soon(self._turn)
        reading = not (waits or n >= TURN)
        if reading != self.reading:
            self.reading = reading
            self._watch()

    def _send(self, frames: bytearray | bytes) -> None:
        if self.held:
            self.held.append([bytes(frames), 0, 0])
            self.held_bytes += len(frames)
        else:
            self._write(frames)

    def answered(self, slot: list[Any], response: bytes) -> None:
        """A held write is journaled (reactor thread): send it and the answers held behind it."""
        if self.sock is None:
            return
        slot[0] = frame = MBAP.pack(slot[1], 0, len(response) + 1, slot[2]) + response
        self.held_bytes += len(frame)
        held = self.held
        out = bytearray()
        while held and held[0][0] is not None:
            out += held.popleft()[0]
        self.held_bytes -= len(out)
        if out:
            self._write(out)
        if self.buf or not self.reading:
            self._serve()


class TcpServer:
    """A listening Modbus TCP server on a reactor thread; `close()` also drops its connections,
    so clients see a stopped server at once, as they would a switched-off device.

    `note(text)` journals what the operator should know (refused connections, idle connections
    closed, accept() failing), at most one line per cause per minute."""

    def __init__(self, handler: ServeHandler, unit: int | None, limits: ServerLimits | None = None,
                 note: Callable[[str], None] | None = None, words: Say = english) -> None:
        self.handler = handler
        self.unit = unit
        self.limits = limits or ServerLimits()
        self.words = words  # the station's words for its records (netplc/words.py)
        self.note = Throttle(note or logger.warning, words=words)
        self.connections: set[_Connection] = set()
        self.peers: dict[str, int] = {}  # open connections by the peer's address
        self.reactor: Reactor = None  # type: ignore[assignment]  # set by listen
        self._sock: socket.socket | None = None
        self._accepting = False  # the listening socket is registered with the reactor
        self._sweep: Timer | None = None
        self._finished: deque[tuple[_Connection, list[Any], bytes]] = deque()
        self._wake = False
        self.last_data = 0.0
        self.port = 0

    def bind(self, host: str, port: int) -> None:
        """Any thread: OSError if the address cannot be bound (a name: its first address)."""
        family, _, _, _, address = socket.getaddrinfo(host or None, port, type=socket.SOCK_STREAM,
                                                      flags=socket.AI_PASSIVE)[0]
        sock = socket.socket(family, socket.SOCK_STREAM)
        try:
            if os.name == "posix":  # as asyncio: a restart binds at once; on Windows it would share the port
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind(address)
            sock.listen(128)
            sock.setblocking(False)
        except OSError:
            sock.close()
            raise
        self._sock = sock
        self.port = sock.getsockname()[1]

    def listen(self, reactor: Reactor) -> None:
        """On the reactor's thread: accept connections there from now on."""
        assert self._sock is not None
        self.reactor = reactor
        reactor.selector.register(self._sock, READ, self)
        self._accepting = True
        self._schedule_sweep()

    def ready(self, events: int) -> None:
        """The listening socket: accept what is waiting."""
        assert self._sock is not None
        limits, peers = self.limits, self.peers
        for _ in range(limits.max_connections + 8):  # then the other sockets' turn
            try:
                sock, address = self._sock.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as e:  # out of file descriptors, ...: one line per cause a minute
                self.note(f"accept {e.errno}", self.words("accept failed", error=e))
                if e.errno in (errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM):
                    self._pause_accepting()  # as asyncio does: not a busy loop until one is free
                    return
                continue
            peer = f"{address[0]}:{address[1]}"
            host = str(address[0])
            if peers.get(host, 0) >= limits.max_per_peer:
                sock.close()
                self.note("peer", self.words("peer refused", peer=peer, n=limits.max_per_peer, host=host))
                continue
            if len(self.connections) >= limits.max_connections:
                sock.close()
                self.note("connections", self.words("server full", peer=peer, n=limits.max_connections))
                continue
            sock.setblocking(False)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            conn = _Connection(self, sock, peer, host)
            self.connections.add(conn)
            peers[host] = peers.get(host, 0) + 1
            self.reactor.selector.register(sock, READ, conn)

    def _pause_accepting(self) -> None:
        """Accept nothing for ACCEPT_RETRY seconds: the listening socket stays readable meanwhile."""
        sock, selector = self._sock, self.reactor.selector
        selector.unregister(sock)
        self._accepting = False

        def resume() -> None:
            if self._sock is sock:  # else closed meanwhile
                selector.register(sock, READ, self)
                self._accepting = True

        self.reactor.later(ACCEPT_RETRY, resume)

    def lost(self, conn: _Connection) -> None:
        if conn in self.connections:
            self.connections.discard(conn)
            left = self.peers[conn.host] - 1
            if left:
                self.peers[conn.host] = left
            else:
                del self.peers[conn.host]

    def _schedule_sweep(self) -> None:
        self._sweep = self.reactor.later(min(1.0, self.limits.idle_timeout / 4), self._close_idle)

    def _close_idle(self) -> None:
        """One timer for the whole server: connections silent (or holding half a frame) for
        idle_timeout are closed."""
        now, idle = self.reactor.time(), self.limits.idle_timeout
        for conn in list(self.connections):
            if now - conn.last > idle and conn.sock is not None:
                self.note("idle", self.words("idle half" if conn.buf else "idle nothing", peer=conn.peer,
                                             idle=idle))
                conn.abort()
        self._schedule_sweep()

    def finished(self, conn: _Connection, slot: list[Any], response: bytes) -> None:
        """A write's answer is due (any thread): handed to the reactor, one wake-up per batch."""
        self._finished.append((conn, slot, response))
        if not self._wake:
            self._wake = True
            self.reactor.call(self._deliver)  # a stopped reactor: nobody left to answer

    def _deliver(self) -> None:
        self._wake = False
        finished = self._finished
        while finished:
            conn, slot, response = finished.popleft()
            conn.answered(slot, response)

    def close(self) -> None:
        """On the reactor's thread (or once it has stopped)."""
        if self._sweep is not None:
            self._sweep.cancel()
        sock, self._sock = self._sock, None
        if sock is not None:
            if self._accepting:
                self.reactor.selector.unregister(sock)
                self._accepting = False
            sock.close()
        for conn in list(self.connections):
            conn.abort()
