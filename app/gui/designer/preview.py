"""Preview live: the canvas reads a running station's memory through its Modbus server.

Only what the form shows is read (the bits and words its elements name, in as few requests as
the Modbus limits allow), with the project's lean Modbus TCP client, read-only: the designer never
writes, and a sync generator on the canvas writes nowhere (its target is a NullTarget). Each poll
becomes a Snapshot with its own scan counter, so trends advance one sample per poll.
"""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import Iterable
from dataclasses import fields

from PySide6.QtCore import QObject, Signal

from hmi_forms.elements import Element
from hmi_forms.elements import props as p
from netplc.address import IO_BITS, BitRef
from netplc.memory import Memory
from netplc.modbus import (
    MAX_READ_BITS,
    MAX_READ_REGISTERS,
    DeviceError,
    Endpoint,
    LeanTcpClient,
    LinkError,
    Table,
    bytes_from_words,
)

PERIOD = 0.2  # seconds between polls
GAP_BITS, GAP_REGISTERS = 64, 16  # read across a gap this small rather than send another request
Request = tuple[Table, int, int]  # table, address, count


def memory_of(models: Iterable[Element]) -> tuple[set[int], set[int]]:
    """The I/O bits and data bytes the elements read."""
    bits: set[int] = set()
    data: set[int] = set()
    for model in models:
        for f in fields(model):
            parser = f.metadata.get("parser")
            value = getattr(model, f.name)
            if parser in (p.bit, p.sync_type) and isinstance(value, BitRef):
                if value.hmi < IO_BITS:
                    bits.add(value.hmi)
                else:
                    data.add(value.byte)
            elif parser is p.word and isinstance(value, int):
                if value < IO_BITS:
                    bits.update(range(value, value + 16))
                else:
                    data.update((value, value + 1))
    return bits, data


def _spans(numbers: Iterable[int], gap: int, limit: int, same_block: int = 0) -> list[tuple[int, int]]:
    """(first, count) runs covering `numbers`, joined across small gaps, at most `limit` long and
    (with `same_block`) never crossing a multiple of it."""
    out: list[tuple[int, int]] = []
    for n in sorted(numbers):
        if out:
            first, count = out[-1]
            end = first + count
            joined = n - end <= gap and n - first < limit
            if same_block and n // same_block != first // same_block:
                joined = False
            if joined:
                out[-1] = (first, max(count, n - first + 1))
                continue
        out.append((n, 1))
    return out


def plan(models: Iterable[Element]) -> list[Request]:
    """The Modbus reads (cpu165 profile: coil n = bit n, register n = bytes 2n, 2n+1)."""
    bits, data = memory_of(models)
    requests: list[Request] = [("coils", a, n) for a, n in _spans(bits, GAP_BITS, MAX_READ_BITS)]
    registers = {b // 2 for b in data}
    requests += [("holding", a, n) for a, n in _spans(registers, GAP_REGISTERS, MAX_READ_REGISTERS,
                                                       same_block=0o10000 // 2)]
    return requests


class Preview(QObject):
    """Polls on a thread of its own; snapshots and link problems arrive as Qt signals."""

    snapshot = Signal(object)
    status = Signal(str)

    def __init__(self, host: str, port: int, unit: int = 1) -> None:
        super().__init__()
        self.endpoint = Endpoint("tcp", host=host, port=port)
        self.unit = unit
        self.requests: list[Request] = []
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        self._stop.clear()
        self._thread = threading.Thread(target=lambda: asyncio.run(self._run()), name="designer-preview",
                                        daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=3)
            self._thread = None

    async def _run(self) -> None:
        client = LeanTcpClient(self.endpoint, timeout=1.0)
        mem = Memory()
        scan = 0
        up = False
        while not self._stop.is_set():
            try:
                if not client.connected:
                    await client.connect()
                for table, address, count in list(self.requests):
                    values = await client.read(self.unit, table, address, count)
                    if table == "coils":
                        mem.bits[address : address + count] = values
                    else:
                        mem.write(2 * address, bytes_from_words(values))
                scan += 1
                self.snapshot.emit(mem.snapshot(scan, time.monotonic(), time.time(), "preview"))
                if not up:
                    self.status.emit(f"Preview live: {self.endpoint}")
                up = True
            except (LinkError, DeviceError) as e:
                client.close()
                up = False
                self.status.emit(f"Preview: {e}")
            await asyncio.sleep(PERIOD)
        client.close()
