"""NetPlc memory served over Modbus TCP, or Modbus RTU on a serial line, with the cpu165 profile
(docs/architecture.md sections 1 and 7).

Other SCADAs and debugging tools read what the HMI reads: the snapshot published after the last
scan, never the live memory (registers are answered straight from its bytes: a slice and a byte
swap, no list of ints). What a write does is the handler's: the station's goes through its
command layer (app/authority/modbus.py), a simulated CPU-165's straight to its engine
(netplc/simulator.py). This package knows neither: the Modbus stack imports no engine.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Iterable
from typing import Protocol

from netplc.address import fmt_octal
from netplc.memory import Snapshot
from netplc.modbus.endpoint import Endpoint
from netplc.modbus.map import (
    MemoryWrite,
    Table,
    bytes_from_bits,
    memory_write,
    read_bits,
    register_slice,
)
from netplc.modbus.pdu import ILLEGAL_ADDRESS, Done, ServeHandler
from netplc.modbus.reactor import Reactor
from netplc.modbus.rtu import RtuServer, SerialLine, open_line
from netplc.modbus.tcp_server import ServerLimits, TcpServer
from netplc.records import Record, RecordSink
from netplc.words import Say, english

logger = logging.getLogger(__name__)

ALL_MEMORY: list[tuple[int, int]] = [(0, 0o77777)]  # every I/O bit and every data byte


class Published(Protocol):
    """Where served memory is read: the snapshot published after the last scan (an engine's)."""

    @property
    def snapshot(self) -> Snapshot: ...


class MemoryServed:
    """A handler serving NetPlc memory with the cpu165 profile: reads from `source`'s snapshot, a
    write decoded into NetPlc terms (`MemoryWrite`) and held to the `writable` ranges (inclusive
    NetPlc addresses: I/O bits for coils, data bytes for registers; the two never overlap; none:
    read-only). What a write that may go ahead does is the subclass's `take`."""

    def __init__(self, source: Published, writable: Iterable[tuple[int, int]] = ()) -> None:
        self.source = source
        self.writable = list(writable)
        for lo, hi in self.writable:
            if not 0 <= lo <= hi <= 0o77777:
                raise ValueError(f"writable range {fmt_octal(lo)}-{fmt_octal(hi)} is not within 00000-077777")

    def registers(self, address: int, count: int) -> bytes:
        return register_slice(self.source.snapshot.data, address, count)

    def bits(self, address: int, count: int) -> bytes:
        return bytes_from_bits(read_bits(self.source.snapshot, address, count))

    def write(self, table: Table, address: int, values: list[int], peer: str, done: Done) -> int | None:
        change = memory_write(table, address, values)
        if not any(lo <= change.first and change.last <= hi for lo, hi in self.writable):
            return self.not_writable(change, peer)
        return self.take(change, peer, done)

    def not_writable(self, change: MemoryWrite, peer: str) -> int:
        """A write outside the writable ranges: exception 2, as an address that does not exist."""
        return ILLEGAL_ADDRESS

    def take(self, change: MemoryWrite, peer: str, done: Done) -> int | None:
        """Do a writable change (ServeHandler.write's answer)."""
        raise NotImplementedError


class ModbusServer:
    """`start()` binds `host:port` (port 0: an ephemeral port, see `.port`) on a thread of its own,
    or, given `serial` (an rtu:// endpoint), opens that port and answers as an RTU slave.

    `handler` is what is served (`ServeHandler`: usually a `MemoryServed`).
    `unit` None answers every unit id; otherwise other unit ids get exception 0x0B.
    `limits` bounds what clients may hold (connections, per peer, idle time, requests in flight).
    `reactor`: the thread to answer on, shared with other servers (many simulated nodes in one
    process); by default the server has a thread of its own.
    `sink` takes the server's own 'system' records (refused connections, a serial port fault);
    without one they go to the log.
    """

    def __init__(self, handler: ServeHandler, host: str = "127.0.0.1", port: int = 0,
                 unit: int | None = None, serial: Endpoint | None = None,
                 limits: ServerLimits | None = None, reactor: Reactor | None = None,
                 sink: RecordSink | None = None, words: Say = english) -> None:
        self.handler = handler
        self.words = words  # the station's words for its records (netplc/words.py)
        self.host = host
        self.requested_port = port
        self.unit = unit
        self.serial = serial
        self.sink = sink
        self.rtu: RtuServer | None = None
        self._server = TcpServer(handler, unit, limits, self.journal, words)
        self._own_thread = reactor is None
        self._thread = reactor or Reactor(f"modbus-server-{host}:{port}")

    @property
    def port(self) -> int:
        return self._server.port

    @property
    def fault(self) -> str:
        """The serial port's failure while it lasts ("" when it works, and always over TCP)."""
        return self.rtu.fault if self.rtu is not None else ""

    def journal(self, text: str) -> None:
        """A 'system' record of the server's own (refused connections, a serial port fault)."""
        if self.sink is None:
            logger.warning("%s", text)
        else:
            self.sink.put(Record(time.time(), "system", source="modbus server", text=text))

    def start(self, retry: bool = False) -> None:
        """OSError if the port cannot be bound or the serial port opened. `retry`: a serial port
        that cannot be opened is no error: the server starts without it, `fault` says why until it
        opens, and it is tried every REOPEN seconds (an adapter plugged in later, a permission
        granted)."""
        if self.serial is not None:
            serial = self.serial
            line: SerialLine | None = None
            fault = ""
            try:
                line = open_line(serial)
            except OSError as e:
                if not retry:
                    raise
                why = os.strerror(e.errno) if e.errno else str(e)  # pyserial repeats the port in its text
                fault = self.words("rtu cannot open", port=serial.device, error=why)
            self.rtu = RtuServer(self.handler, self.unit, line, serial.device,
                                 reopen=lambda: open_line(serial), note=self.journal, words=self.words)
            self.rtu.start(fault)
            return
        self._server.bind(self.host, self.requested_port)
        if self._own_thread:
            self._thread.start()
        try:
            self._thread.run(lambda: self._server.listen(self._thread))
        except Exception:
            self._server.close()
            if self._own_thread:
                self._thread.stop()
            raise

    def stop(self) -> None:
        if self.rtu is not None:
            self.rtu.stop()
            self.rtu = None
        if self._thread.running:
            self._thread.run(self._server.close)
        else:
            self._server.close()
        if self._own_thread:
            self._thread.stop()
