"""Where the Program view gets memory from and sends writes to: the station's own runtime (the
workstation's Station -> Program), or a running station's Modbus server (`main.py monitor`).

Every action of the local view (write, force, unforce, step) is a command of the station's command
layer as the user at the workstation, from the Program view (`Source.PROGRAM_VIEW`): the layer
checks the role, journals it naming them, and answers with a `Ticket`, as every other seat's
actions are; the remote view's writes are answered by the station over Modbus (a ticket too, so
the view says both alike).

Both give the view a `Snapshot` and nothing live, so the monitor never touches the scan: the
local source hands over the engine's last published snapshot; the remote one polls the cpu165
map of the station's server on its own thread (the I/O bits, and only the data registers the view
says it needs) and builds a snapshot from the answers.

Forcing and "step one scan" need the local runtime: the Modbus map has no channel for them, and a
force that a client could set over a plain Modbus port would bypass the journal of the user who
forced. So the remote monitor watches and writes (each write journaled by the station with the
peer's address, and refused where the station's `writable` ranges do not open it), and does not
force in this version.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Iterable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Protocol

from app.authority import APPLIED, Answer, Commands, Reason, Ticket, Who
from app.authority import Source as Seat
from app.runtime import Runtime
from netplc.address import DATA_SIZE, IO_BITS, data_index, is_data_byte
from netplc.forcing import Force, Kind, tag_forces
from netplc.memory import Snapshot
from netplc.modbus import DeviceError, LinkError, LoopThread, MapError, locate, open_client, parse_endpoint
from netplc.program import Program, parse
from netplc.tags.tag import Tag

logger = logging.getLogger(__name__)

POLL_S = 0.2  # the remote monitor's poll period: 5 reads of the station per second
TIMEOUT_S = 2.0


@dataclass(frozen=True)
class Caps:
    force: bool
    step: bool
    why_not: str = ""  # shown on the disabled buttons


class Source(Protocol):
    title: str
    program: Program
    symbols: dict[str, int]
    tags: dict[str, Tag]  # tags.csv by name: watched in physical units, forced word by word
    caps: Caps
    commands: Commands | None  # the station's command layer, when it is this process's

    def who(self, user: str) -> Who: ...

    def snapshot(self) -> Snapshot | None: ...

    def state(self) -> str: ...

    def timer(self, c: int) -> float | None: ...

    def counter(self, c: int) -> int | None: ...

    def forces(self) -> tuple[Force, ...]: ...

    def need(self, addrs: Iterable[int]) -> None: ...

    def write(self, kind: Kind, addr: int, value: int, user: str) -> Ticket: ...

    def write_tag(self, tag: Tag, phy: float, user: str) -> Ticket: ...

    def force(self, kind: Kind, addr: int, value: int | None, user: str) -> Ticket: ...

    def unforce(self, kind: Kind, addr: int, user: str) -> Ticket: ...

    def force_tag(self, tag: Tag, phy: float | None, user: str) -> Ticket: ...

    def unforce_tag(self, tag: Tag, user: str) -> Ticket: ...

    def unforce_all(self, user: str) -> Ticket: ...

    def step(self, user: str) -> Ticket: ...

    def close(self) -> None: ...


class LocalSource:
    """The workstation's own runtime: snapshots; writes, forces and single scans as commands."""

    caps = Caps(force=True, step=True)

    def __init__(self, runtime: Runtime) -> None:
        assert runtime.engine is not None and runtime.commands is not None, \
            "the runtime is started before its monitor opens"
        self.runtime = runtime
        self.engine = runtime.engine
        self.commands: Commands | None = runtime.commands
        self.layer = runtime.commands  # the same, known here not to be None
        self.program = runtime.program
        self.symbols = runtime.symbols
        self.tags = runtime.tags.by_name
        self.title = f"{runtime.station.name}: {runtime.program.source}"

    def snapshot(self) -> Snapshot | None:
        return self.engine.snapshot

    def state(self) -> str:
        return self.engine.snapshot.state

    def timer(self, c: int) -> float | None:
        return self.engine.tim_ticks[c]

    def counter(self, c: int) -> int | None:
        return self.engine.ctr_values[c]

    def forces(self) -> tuple[Force, ...]:
        return self.engine.snapshot.forces  # those of the scan shown

    def need(self, addrs: Iterable[int]) -> None:
        pass  # the whole snapshot is at hand

    def who(self, user: str) -> Who:
        return Who(user, Seat.PROGRAM_VIEW)

    def write(self, kind: Kind, addr: int, value: int, user: str) -> Ticket:
        """An operator write like any other: queued to the next scan, journaled with the user."""
        if kind == "bit":
            return self.layer.write_bit(self.who(user), addr, value)
        if kind == "word":
            return self.layer.write_word(self.who(user), addr, value)
        return self.layer.write_bytes(self.who(user), addr, bytes((value,)))

    def write_tag(self, tag: Tag, phy: float, user: str) -> Ticket:
        """Checked for the tag's type and physical range, journaled with its name and unit."""
        return self.layer.write_tag(self.who(user), tag.name, phy)

    def force(self, kind: Kind, addr: int, value: int | None, user: str) -> Ticket:
        return self.layer.force(self.who(user), kind, addr, value)

    def unforce(self, kind: Kind, addr: int, user: str) -> Ticket:
        return self.layer.unforce(self.who(user), kind, addr)

    def force_tag(self, tag: Tag, phy: float | None, user: str) -> Ticket:
        return self.layer.force_tag(self.who(user), tag.name, phy)

    def unforce_tag(self, tag: Tag, user: str) -> Ticket:
        return self.layer.unforce_tag(self.who(user), tag.name)

    def unforce_all(self, user: str) -> Ticket:
        return self.layer.unforce_all(self.who(user))

    def step(self, user: str) -> Ticket:
        """One scan of the stopped program, between two scans of the scan thread."""
        thread = self.runtime.scan_thread
        return self.layer.step(self.who(user), thread.lock if thread is not None else None)

    def close(self) -> None:
        pass


class RemoteSource:
    """A running station over its Modbus server (cpu165 profile): watch and write, no forcing."""

    caps = Caps(force=False, step=False,
                why_not="forcing and single scans need the station's own workstation (not over Modbus)")
    commands: Commands | None = None  # the station's layer is in the station's process: it answers

    def __init__(self, host: str, port: int, *, unit: int = 1, program: Program | None = None,
                 symbols: dict[str, int] | None = None, tags: dict[str, Tag] | None = None,
                 poll: float = POLL_S) -> None:
        self.endpoint = parse_endpoint(f"tcp://{host}:{port}")
        self.unit = unit
        self.program = program or parse("", source="<no program: give the station to see its listing>")
        self.symbols = symbols or {}
        self.tags = tags or {}
        self.title = f"{host}:{port}" + (f": {self.program.source}" if program else "")
        self.poll = poll
        self._client = open_client(self.endpoint, TIMEOUT_S)  # the lean client
        self._loop = LoopThread(f"monitor-{host}:{port}")
        self._snapshot: Snapshot | None = None
        self._regs: list[tuple[int, int]] = []  # (first register, count) of the data read each poll
        self._polls = 0
        self.error = ""
        self._lock = asyncio.Lock()  # one transaction at a time on the connection: polls and writes
        self._loop.start()
        self._task = asyncio.run_coroutine_threadsafe(self._run(), self._loop.loop)  # type: ignore[arg-type]

    def need(self, addrs: Iterable[int]) -> None:
        """Read these data bytes (and the words they start) from now on, besides every I/O bit."""
        wanted = {a >> 1 for x in addrs if x >= IO_BITS for a in (x, x + 1) if is_data_byte(a)}
        wanted |= {first + k for first, count in self._regs for k in range(count)}
        runs: list[tuple[int, int]] = []
        for reg in sorted(wanted):
            if runs and reg == runs[-1][0] + runs[-1][1] and runs[-1][1] < 125:
                runs[-1] = (runs[-1][0], runs[-1][1] + 1)
            else:
                runs.append((reg, 1))
        self._regs = runs

    async def _run(self) -> None:
        while True:
            try:
                async with self._lock:
                    if not self._client.connected:
                        await self._client.connect()
                    self._snapshot = await self._read()
                self.error = ""
            except (LinkError, DeviceError, OSError) as e:
                self.error = str(e)
                self._client.close()
            await asyncio.sleep(self.poll)

    async def _read(self) -> Snapshot:
        bits = await self._client.read(self.unit, "coils", 0, 2000)
        bits += await self._client.read(self.unit, "coils", 2000, IO_BITS - 2000)
        data = bytearray(DATA_SIZE)
        for first, count in list(self._regs):
            words = await self._client.read(self.unit, "holding", first, count)
            for k, w in enumerate(words):
                i = data_index(2 * (first + k))
                data[i], data[i + 1] = w & 0xFF, w >> 8
        self._polls += 1
        return Snapshot(tuple(bits), bytes(data), self._polls, time.monotonic(), time.time(), "remote")

    def snapshot(self) -> Snapshot | None:
        return self._snapshot

    def state(self) -> str:
        return f"link down: {self.error}" if self.error else f"connected to {self.endpoint}"

    def timer(self, c: int) -> float | None:
        return None  # not in the Modbus map

    def counter(self, c: int) -> int | None:
        return None

    def forces(self) -> tuple[Force, ...]:
        return ()

    def who(self, user: str) -> Who:
        return Who(user, Seat.MONITOR)

    def write(self, kind: Kind, addr: int, value: int, user: str) -> Ticket:
        """Write over Modbus (the station journals it with this peer's address), answered when the
        station has: not writable (a MapError, exception 2 outside the writable ranges) or failed
        (the link, another exception), with the reason."""
        ticket: Ticket = Future()
        where = Force(kind, addr, 0).where
        try:
            self._loop.run(self._write(kind, addr, value), TIMEOUT_S * 3)
        except (MapError, DeviceError) as e:
            logger.warning("%s: write %s refused by the station: %s", self.endpoint, where, e)
            ticket.set_result(Answer(Reason.NOT_WRITABLE, str(e)))
        except (LinkError, OSError, TimeoutError) as e:
            logger.warning("%s: write %s failed: %s", self.endpoint, where, e)
            ticket.set_result(Answer(Reason.FAILED, str(e) or type(e).__name__))
        else:
            ticket.set_result(APPLIED)
        return ticket

    def write_tag(self, tag: Tag, phy: float, user: str) -> Ticket:
        """A tag's physical value written as its raw bit or words, each a Modbus write; the first
        that is not done answers for all."""
        answers = [self.write(f.kind, f.addr, f.value, user) for f in tag_forces(tag, phy)]
        return next((a for a in answers if not a.result().ok), answers[-1])

    async def _write(self, kind: Kind, addr: int, value: int) -> None:
        async with self._lock:
            await self._write_unlocked(kind, addr, value)

    async def _write_unlocked(self, kind: Kind, addr: int, value: int) -> None:
        client, unit = self._client, self.unit
        if not client.connected:
            await client.connect()
        if kind == "bit" and addr < IO_BITS:
            await client.write(unit, "coils", addr, [value])
            return
        if kind == "bit":  # a data bit: read-modify-write of its byte
            byte_addr, mask = addr >> 3, 1 << (addr & 7)
            old = (await self._read_bytes(byte_addr, 1))[0]
            await self._write_bytes(byte_addr, bytes(((old | mask) if value else (old & ~mask & 0xFF),)))
            return
        size = 1 if kind == "byte" else 2
        await self._write_bytes(addr, value.to_bytes(size, "little"))

    async def _read_bytes(self, addr: int, length: int) -> bytes:
        block = locate("cpu165", "holding", addr, length)
        values: list[int] = []
        for first, count in block.spans(False):
            values += await self._client.read(self.unit, block.table, first, count)
        return block.decode(values)

    async def _write_bytes(self, addr: int, payload: bytes) -> None:
        block = locate("cpu165", "holding", addr, len(payload))
        if block.bits:
            values = block.encode(payload)
        else:
            first = last = 0
            if block.skip:
                first = (await self._client.read(self.unit, "holding", block.address, 1))[0]
            if block.odd_end:
                last = (await self._client.read(self.unit, "holding", block.address + block.count - 1, 1))[0]
            values = block.encode(payload, first, last)
        for start, count in block.spans(True):
            await self._client.write(self.unit, block.table, start, values[start - block.address:][:count])

    def _cannot(self) -> Ticket:
        ticket: Ticket = Future()
        ticket.set_result(Answer(Reason.NOT_WRITABLE, self.caps.why_not))
        return ticket

    def force(self, kind: Kind, addr: int, value: int | None, user: str) -> Ticket:
        return self._cannot()

    def unforce(self, kind: Kind, addr: int, user: str) -> Ticket:
        return self._cannot()

    def force_tag(self, tag: Tag, phy: float | None, user: str) -> Ticket:
        return self._cannot()

    def unforce_tag(self, tag: Tag, user: str) -> Ticket:
        return self._cannot()

    def unforce_all(self, user: str) -> Ticket:
        return self._cannot()

    def step(self, user: str) -> Ticket:
        return self._cannot()

    def close(self) -> None:
        self._loop.call(self._client.close)  # on the loop, before the loop stops
        self._task.cancel()
        self._loop.stop()

