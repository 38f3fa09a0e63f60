"""Preview live: the canvas reads a running station's memory through its Modbus server.

Only what the form shows is read (the bits and words its elements name, in as few requests as
the Modbus limits allow), with the project's lean Modbus TCP client, read-only: the designer never
writes, and a sync generator on the canvas writes nowhere (its target is a NullTarget). Each poll
becomes a Snapshot with its own scan counter, so trends advance one sample per poll. The polls run
one after the other in the preview's worker thread (hmi_forms/widgets/worker.py), the next
PERIOD after the last one answered, so a station slow to answer is never asked twice at once.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterable
from dataclasses import fields
from functools import partial

from PySide6.QtCore import QObject, QTimer, Signal

from hmi_forms.elements import Element
from hmi_forms.elements import props as p
from hmi_forms.widgets.worker import Worker
from netplc.address import IO_BITS, BitRef
from netplc.memory import Memory, Snapshot
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


class Poller:
    """The station as the preview's worker thread reads it: one connection on an event loop of
    that thread, opened at the first poll and again after a failed one, closed with the worker."""

    def __init__(self, endpoint: Endpoint, unit: int) -> None:
        self.client = LeanTcpClient(endpoint, timeout=1.0)
        self.unit = unit
        self.loop: asyncio.AbstractEventLoop | None = None
        self.mem = Memory()
        self.scan = 0

    def poll(self, requests: list[Request]) -> Snapshot:
        if self.loop is None:
            self.loop = asyncio.new_event_loop()
        try:
            return self.loop.run_until_complete(self._read(requests))
        except (LinkError, DeviceError):
            self.client.close()  # the next poll connects anew
            raise

    async def _read(self, requests: list[Request]) -> Snapshot:
        if not self.client.connected:
            await self.client.connect()
        for table, address, count in requests:
            values = await self.client.read(self.unit, table, address, count)
            if table == "coils":
                self.mem.bits[address : address + count] = values
            else:
                self.mem.write(2 * address, bytes_from_words(values))
        self.scan += 1
        return self.mem.snapshot(self.scan, time.monotonic(), time.time(), "preview")

    def close(self) -> None:
        self.client.close()
        loop, self.loop = self.loop, None
        if loop is not None:
            loop.run_until_complete(asyncio.sleep(0))  # the aborted connection's socket closes
            loop.close()


class Preview(QObject):
    """Polls in a worker thread; snapshots and link problems arrive as Qt signals."""

    snapshot = Signal(object)
    status = Signal(str)

    def __init__(self, host: str, port: int, unit: int = 1) -> None:
        super().__init__()
        self.endpoint = Endpoint("tcp", host=host, port=port)
        self.unit = unit
        self.requests: list[Request] = []
        self.worker: Worker | None = None
        self._poller: Poller | None = None
        self._up = False
        self._next = QTimer(self)
        self._next.setSingleShot(True)
        self._next.setInterval(round(PERIOD * 1000))
        self._next.timeout.connect(self._poll)

    def start(self) -> None:
        self.stop()
        self._poller = Poller(self.endpoint, self.unit)
        self.worker = Worker("designer-preview", (LinkError, DeviceError), self, on_close=self._poller.close)
        self.worker.answered.connect(self._read)
        self.worker.failed.connect(self._failed)
        self._poll()

    def stop(self) -> None:
        self._next.stop()
        worker, self.worker = self.worker, None
        if worker is not None:
            worker.close()

    def _poll(self) -> None:
        if self.worker is not None and self._poller is not None:
            self.worker.submit(partial(self._poller.poll, list(self.requests)))

    def _read(self, _token: int, snap: Snapshot) -> None:
        if self.worker is None:
            return  # stopped while the answer was on its way
        self.snapshot.emit(snap)
        if not self._up:
            self._up = True
            self.status.emit(self.tr("Preview live: {0}").format(self.endpoint))
        self._next.start()

    def _failed(self, _token: int, why: str) -> None:
        if self.worker is None:
            return
        self._up = False
        self.status.emit(self.tr("Preview: {0}").format(why))
        self._next.start()
