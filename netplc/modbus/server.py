"""NetPlc memory served over Modbus TCP, or Modbus RTU on a serial line, with the cpu165 profile
(docs/architecture.md sections 1 and 7).

Other SCADAs and debugging tools read what the HMI reads: the snapshot published after the last
scan, never the live memory (registers are answered straight from its bytes: a slice and a byte
swap, no list of ints). Writes are accepted only inside the configured ranges (exception 2
outside, like an address that does not exist), go through the engine's bounded queue of outside
writes to be applied at the start of a scan (exception 6, server busy, when it is full), are
journaled by the engine as 'operator' records whose source is the peer's address, and are
answered only once that record is durable in the archive.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from netplc.address import IO_BITS, fmt_octal
from netplc.engine import Engine
from netplc.modbus.endpoint import Endpoint
from netplc.modbus.loop import LoopThread
from netplc.modbus.map import (
    MapError,
    Table,
    bits_target,
    bytes_from_bits,
    bytes_from_words,
    read_bits,
    register_slice,
    registers_target,
)
from netplc.modbus.rtu import RtuServer, open_line
from netplc.modbus.tcp_server import ServerLimits, TcpServer
from netplc.records import Record

ALL_MEMORY: list[tuple[int, int]] = [(0, 0o77777)]  # every I/O bit and every data byte


class ModbusServer:
    """`start()` binds `host:port` (port 0: an ephemeral port, see `.port`) on a thread of its own,
    or, given `serial` (an rtu:// endpoint), opens that port and answers as an RTU slave.

    `writable` lists inclusive NetPlc address ranges a client may write: I/O bit addresses for
    coils, data byte addresses for registers (the two never overlap). None: read-only.
    `unit` None answers every unit id; otherwise other unit ids get exception 0x0B.
    `limits` bounds what clients may hold (connections, idle time, requests in flight).
    `loop`: an event-loop thread to listen on, shared with other servers (many simulated nodes in
    one process); by default the server has a thread of its own.
    """

    def __init__(self, engine: Engine, host: str = "127.0.0.1", port: int = 0,
                 writable: list[tuple[int, int]] | None = None, unit: int | None = None,
                 serial: Endpoint | None = None, limits: ServerLimits | None = None,
                 loop: LoopThread | None = None) -> None:
        self.engine = engine
        self.host = host
        self.requested_port = port
        self.writable = list(writable or [])
        for lo, hi in self.writable:
            if not 0 <= lo <= hi <= 0o77777:
                raise ValueError(f"writable range {fmt_octal(lo)}-{fmt_octal(hi)} is not within 00000-077777")
        self.unit = unit
        self.serial = serial
        self.rtu: RtuServer | None = None
        self._server = TcpServer(self, unit, limits, self.journal)
        self._own_thread = loop is None
        self._thread = loop or LoopThread(f"modbus-server-{host}:{port}")

    @property
    def port(self) -> int:
        return self._server.port

    @property
    def fault(self) -> str:
        """The serial port's failure while it lasts ("" when it works, and always over TCP)."""
        return self.rtu.fault if self.rtu is not None else ""

    def journal(self, text: str) -> None:
        """A 'system' record of the server's own (refused connections, a serial port fault)."""
        self.engine.sink.put(Record(time.time(), "system", source="modbus server", text=text))

    def start(self) -> None:
        """OSError if the port cannot be bound or the serial port opened."""
        if self.serial is not None:
            serial = self.serial
            self.rtu = RtuServer(self, self.unit, open_line(serial), serial.device,
                                 reopen=lambda: open_line(serial), note=self.journal)
            self.rtu.start()
            return
        if self._own_thread:
            self._thread.start()
        try:
            self._thread.run(self._server.listen(self.host, self.requested_port))
        except BaseException:
            if self._own_thread:
                self._thread.stop()
            raise

    def stop(self) -> None:
        if self.rtu is not None:
            self.rtu.stop()
            self.rtu = None
        if self._thread.loop is not None:
            self._thread.run(self._server.close())
        if self._own_thread:
            self._thread.stop()

    # --- ServeHandler (on the server's loop) ------------------------------------------------------

    def registers(self, address: int, count: int) -> bytes:
        return register_slice(self.engine.snapshot.data, address, count)

    def bits(self, address: int, count: int) -> bytes:
        return bytes_from_bits(read_bits(self.engine.snapshot, address, count))

    def write(self, table: Table, address: int, values: list[int], peer: str,
              done: Callable[[bool], None]) -> bool:
        user = f"modbus {peer}"
        engine = self.engine
        if table == "coils":
            first = bits_target(address, len(values))
            self._check(first, first + len(values) - 1)
            if len(values) == 1:
                return engine.write_bit(first, values[0], user=user, done=done)
            return engine.write_bits(first, values, user=user, done=done)
        first = registers_target(address, len(values))
        self._check(first, first + 2 * len(values) - 1)
        if len(values) == 1:
            return engine.write_word(first, values[0], user=user, done=done)
        return engine.write_bytes(first, bytes_from_words(values), user=user, done=done)

    def _check(self, lo: int, hi: int) -> None:
        if not any(a <= lo and hi <= b for a, b in self.writable):
            what = "bits" if lo < IO_BITS else "bytes"
            raise MapError(f"{what} {fmt_octal(lo)}-{fmt_octal(hi)} are not writable over Modbus")
