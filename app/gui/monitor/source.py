"""Where the Program view gets memory from, and what it acts through: the station's own runtime
(the workstation's Station -> Program), a running station over its OPC UA endpoint as a user of that
station (`main.py monitor opc.tcp://...`), or a running station's Modbus server (`main.py monitor
HOST:PORT`, read-only).

Every action of the view (write, force, unforce, step) is a command of the station's command layer:
the local source sends it as the user at the workstation, from the Program view
(`Source.PROGRAM_VIEW`); the OPC UA source sends it over the station's methods and tag variables as
the user logged in there (app/publish/client.py), which the station takes as its commands with that
session's user (`opcua:<user>@<peer>` in its journal). Either way the layer checks the role, journals
it and answers with a `Ticket`. What the user may do is the layer's answer too (`denial`): the local
layer's, or the station's (UserExecutable and UserAccessLevel); no source checks a role itself.
Over OPC UA only tags are written (through their variables): a raw address is not written from a
remote monitor, there being no method for it.

The Modbus monitor is read-only: Modbus has no users, so a write or a force sent over it would be
an action of nobody, journaled with an address and checked against no role. Nor can it see the
station's forces (the Modbus map has no channel for them): `forces()` answers None, unknown.

All give the view a `Snapshot` and nothing live, so the monitor never touches the scan: the local
source hands over the engine's last published snapshot; the remote ones read the station on a
thread of their own (OPC UA: the whole of NetPlc's memory and its forces at the view's refresh
rate; Modbus: the I/O bits, and only the data registers the view says it needs) and build a
snapshot from the answers.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Iterable
from concurrent.futures import Future
from typing import TYPE_CHECKING, Protocol

from app.authority import Action, Answer, Commands, Reason, Refusal, Ticket, Who
from app.authority import Source as Seat
from app.scada.tag import Tag
from app.station.runtime import Runtime
from netplc.address import DATA_SIZE, IO_BITS, data_index, fmt_octal, is_data_byte
from netplc.forcing import Force, Kind
from netplc.memory import Snapshot
from netplc.modbus import DeviceError, LinkError, LoopThread, open_client, parse_endpoint
from netplc.program import Program, parse

if TYPE_CHECKING:  # the workstation's Program view loads no OPC UA client
    from app.publish.client import StationClient

logger = logging.getLogger(__name__)

POLL_S = 0.2  # the remote monitor's poll period: 5 reads of the station per second
TIMEOUT_S = 2.0
READ_ONLY = ("read-only: Modbus has no users; write, force and step as a user of the station, over its "
             "OPC UA endpoint (main.py monitor opc.tcp://...) or at its own workstation")
NO_PROGRAM = "<no program: give --program (the program, or the station folder) to see its listing>"
RAW_WRITE = ("over OPC UA only tags are written, through their variables; an address is written at the "
             "station's own workstation")


class Source(Protocol):
    """What the view reads."""

    title: str
    program: Program
    symbols: dict[str, int]
    tags: dict[str, Tag]  # tags.csv by name: watched in physical units (forced word by word)
    read_only: str  # why nothing can be done through this source ("" when it acts: `acting`)

    @property
    def acting(self) -> Acting | None: ...  # the source itself when it acts, else None

    def snapshot(self) -> Snapshot | None: ...

    def state(self) -> str: ...

    def timer(self, c: int) -> float | None: ...

    def counter(self, c: int) -> int | None: ...

    def forces(self) -> tuple[Force, ...] | None: ...  # None: this source cannot see them

    def need(self, addrs: Iterable[int]) -> None: ...

    def close(self) -> None: ...


class Acting(Source, Protocol):
    """A source the view acts through: each action a command of the station's layer."""

    rights: int  # changes whenever what the user may do may have changed (the view asks again)

    def denial(self, action: Action, user: str, what: str, tag: Tag | None = None) -> Refusal | str | None:
        """Why `user` may not do `action` (`what`: the view's words for it; for a write, `tag` is the
        tag written, None for an address), as the station's layer says; None when they may."""
        ...

    def write(self, kind: Kind, addr: int, value: int, user: str) -> Ticket: ...

    def write_tag(self, tag: Tag, phy: float, user: str) -> Ticket: ...

    def force(self, kind: Kind, addr: int, value: int | None, user: str) -> Ticket: ...

    def unforce(self, kind: Kind, addr: int, user: str) -> Ticket: ...

    def force_tag(self, tag: Tag, phy: float | None, user: str) -> Ticket: ...

    def unforce_tag(self, tag: Tag, user: str) -> Ticket: ...

    def unforce_all(self, user: str) -> Ticket: ...

    def step(self, user: str) -> Ticket: ...


class LocalSource:
    """The workstation's own runtime: snapshots; writes, forces and single scans as commands."""

    read_only = ""
    rights = 0  # a change of user at the workstation is told to the view (update_rights)

    def __init__(self, runtime: Runtime) -> None:
        assert runtime.engine is not None and runtime.commands is not None, \
            "the runtime is started before its monitor opens"
        self.runtime = runtime
        self.engine = runtime.engine
        self.commands: Commands = runtime.commands
        self.program = runtime.program
        self.symbols = runtime.symbols
        self.tags = runtime.tags.by_name
        self.title = f"{runtime.station.name}: {runtime.program.source}"

    @property
    def acting(self) -> LocalSource:
        return self

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

    def denial(self, action: Action, user: str, what: str, tag: Tag | None = None) -> Refusal | None:
        return self.commands.denial(self.who(user), action, what=what)

    def write(self, kind: Kind, addr: int, value: int, user: str) -> Ticket:
        """An operator write like any other: queued to the next scan, journaled with the user."""
        if kind == "bit":
            return self.commands.write_bit(self.who(user), addr, value)
        if kind == "word":
            return self.commands.write_word(self.who(user), addr, value)
        return self.commands.write_bytes(self.who(user), addr, bytes((value,)))

    def write_tag(self, tag: Tag, phy: float, user: str) -> Ticket:
        """Checked for the tag's type and physical range, journaled with its name and unit."""
        return self.commands.write_tag(self.who(user), tag.name, phy)

    def force(self, kind: Kind, addr: int, value: int | None, user: str) -> Ticket:
        return self.commands.force(self.who(user), kind, addr, value)

    def unforce(self, kind: Kind, addr: int, user: str) -> Ticket:
        return self.commands.unforce(self.who(user), kind, addr)

    def force_tag(self, tag: Tag, phy: float | None, user: str) -> Ticket:
        return self.commands.force_tag(self.who(user), tag.name, phy)

    def unforce_tag(self, tag: Tag, user: str) -> Ticket:
        return self.commands.unforce_tag(self.who(user), tag.name)

    def unforce_all(self, user: str) -> Ticket:
        return self.commands.unforce_all(self.who(user))

    def step(self, user: str) -> Ticket:
        """One scan of the stopped program, between two scans of the scan thread."""
        thread = self.runtime.scan_thread
        return self.commands.step(self.who(user), thread.lock if thread is not None else None)

    def close(self) -> None:
        pass


class OpcUaSource:
    """A running station over its OPC UA endpoint, as the user logged in there (`client`, opened)."""

    read_only = ""

    def __init__(self, client: StationClient, *, program: Program | None = None,
                 symbols: dict[str, int] | None = None, tags: dict[str, Tag] | None = None) -> None:
        self.client = client
        self.program = program or parse("", source=NO_PROGRAM)
        self.symbols = symbols or {}
        self.tags = tags or {}
        self.title = f"{client.user} at {client.url}" + (f": {self.program.source}" if program else "")

    @property
    def acting(self) -> OpcUaSource:
        return self

    @property
    def rights(self) -> int:
        return self.client.rights

    def snapshot(self) -> Snapshot | None:
        return self.client.snapshot

    def state(self) -> str:
        return self.client.state()

    def timer(self, c: int) -> float | None:
        return None  # not published

    def counter(self, c: int) -> int | None:
        return None

    def forces(self) -> tuple[Force, ...]:
        snap = self.client.snapshot
        return snap.forces if snap is not None else ()

    def need(self, addrs: Iterable[int]) -> None:
        pass  # the whole of memory is read

    def denial(self, action: Action, user: str, what: str, tag: Tag | None = None) -> str | None:
        """The station's answer: UserExecutable of its method for `action`, UserAccessLevel of a
        tag's variable for a write (asked from the first time it is wanted)."""
        client = self.client
        if action is Action.WRITE and tag is None:
            return f"{what}: {RAW_WRITE}"
        may = client.may_write(tag.name) if tag is not None else client.may(action)
        if may:
            return None
        if may is None:
            return f"{what}: asking the station what {client.user} may do…"
        return f"{what}: the station does not let {client.user} do this"

    def write(self, kind: Kind, addr: int, value: int, user: str) -> Ticket:
        ticket: Ticket = Future()
        ticket.set_result(Answer(Reason.NOT_WRITABLE, RAW_WRITE))
        return ticket

    def write_tag(self, tag: Tag, phy: float, user: str) -> Ticket:
        return self.client.write_tag(tag, phy)

    def force(self, kind: Kind, addr: int, value: int | None, user: str) -> Ticket:
        return self.client.call("Force", kind, fmt_octal(addr), value)

    def unforce(self, kind: Kind, addr: int, user: str) -> Ticket:
        return self.client.call("Unforce", kind, fmt_octal(addr))

    def force_tag(self, tag: Tag, phy: float | None, user: str) -> Ticket:
        return self.client.call("ForceTag", tag.name, phy)

    def unforce_tag(self, tag: Tag, user: str) -> Ticket:
        return self.client.call("UnforceTag", tag.name)

    def unforce_all(self, user: str) -> Ticket:
        return self.client.call("UnforceAll")

    def step(self, user: str) -> Ticket:
        return self.client.call("Step")

    def close(self) -> None:
        self.client.close()


class RemoteSource:
    """A running station over its Modbus server (cpu165 profile): watched, read-only."""

    read_only = READ_ONLY
    acting = None

    def __init__(self, host: str, port: int, *, unit: int = 1, program: Program | None = None,
                 symbols: dict[str, int] | None = None, tags: dict[str, Tag] | None = None,
                 poll: float = POLL_S) -> None:
        self.endpoint = parse_endpoint(f"tcp://{host}:{port}")
        self.unit = unit
        self.program = program or parse("", source="<no program: give the station folder to see its listing>")
        self.symbols = symbols or {}
        self.tags = tags or {}
        self.title = f"{host}:{port}" + (f": {self.program.source}" if program else "")
        self.poll = poll
        self._client = open_client(self.endpoint, TIMEOUT_S)  # the lean client
        self._loop = LoopThread(f"monitor-{host}:{port}")
        self._snapshot: Snapshot | None = None
        self._regs: list[tuple[int, int]] = []  # (first register, count) of the data read each poll
        self._polls = 0
        self.phase = "connecting"  # then "reading", until the first snapshot (the poll thread sets it)
        self.error = ""
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
                if not self._client.connected:
                    self.phase = "connecting"
                    await self._client.connect()
                self.phase = "reading"
                self._snapshot = await self._read()
                self.error = ""
            except (LinkError, DeviceError, OSError) as e:
                why = str(e) or type(e).__name__
                if why != self.error:
                    logger.warning("%s: %s", self.endpoint, why)  # once per cause, not every poll
                self.error = why
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
        """What the monitor is doing: connecting, reading, or why the link is down (retrying)."""
        if self.error:
            return f"link down: {self.error}; retrying every {self.poll:g} s"
        if self._snapshot is None and self.phase == "reading":
            return f"reading {self.endpoint}…"
        if self._snapshot is None:
            return f"connecting to {self.endpoint}…"
        return f"connected to {self.endpoint}: {self._polls} reads"

    def timer(self, c: int) -> float | None:
        return None  # not in the Modbus map

    def counter(self, c: int) -> int | None:
        return None

    def forces(self) -> tuple[Force, ...] | None:
        return None  # not in the Modbus map: the station's forces are unknown here

    def close(self) -> None:
        self._loop.call(self._client.close)  # on the loop, before the loop stops
        self._task.cancel()
        self._loop.stop()
