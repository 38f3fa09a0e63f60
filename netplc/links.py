"""What a node of the exchange is, whichever path serves it (docs/architecture.md section 7): its
statistics, a block request, and the link state a transaction's outcome sets (back-off, the run of
exception answers, the journaled link records). The Modbus TCP hot path (netplc/tcp_exchange.py)
and the asyncio path of serial lines and pymodbus's client (netplc/exchange.py) share it, so a node
behaves the same over either.
"""

from __future__ import annotations

import time
from collections.abc import Generator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from netplc.modbus import (
    ILLEGAL_VALUE,
    WRITABLE_TABLES,
    Block,
    DeviceError,
    Frame,
    LinkError,
    MapError,
    describe,
    exception_text,
    locate,
)

if TYPE_CHECKING:
    from netplc.exchange import NodeConfig

PROBE_IDLE = 1.0  # seconds without a request before a node's link is probed


@dataclass
class NodeStats:
    """What the status bar shows of a node."""

    node: int
    endpoint: str
    up: bool = False
    reads: int = 0  # completed block reads
    writes: int = 0  # completed block writes
    errors: int = 0  # failed block requests
    last_error: str = ""
    probes: int = 0  # liveness probes sent while NetPlc asked the node nothing
    changed: float = 0.0  # monotonic time of the last link-state change
    age: int = 0  # scans from the request of the last completed read to its data in memory
    age_max: int = 0


@dataclass(eq=False, slots=True)
class Request:
    """A block request of one instruction. A read's is made once per instruction and sent again
    whenever the instruction asks anew (one in flight per instruction), so a read costs no new
    object; `plan` is what the serving path built for it once."""

    key: int  # the FON instruction index; -1 a liveness probe
    node: int
    remote: int
    local: int = 0
    length: int = 0
    payload: bytes | None = None  # None: a read
    scan: int = 0  # the scan that asked
    data: bytes | None = None  # the outcome, handed to the engine thread
    error: str = ""
    plan: Any = None


# A request as its transactions: each Frame yielded is sent, the answer's data (as the wire carries
# it) comes back; the value returned is the block's bytes (b"" for a write). Either path drives it.
Steps = Generator[Frame, bytes, bytes]


def read_frames(unit: int, block: Block) -> tuple[Frame, ...]:
    """The transactions of a block read, built once per instruction."""
    return tuple(Frame.read(unit, block.table, a, n) for a, n in block.spans(write=False))


def read_steps(frames: tuple[Frame, ...], block: Block) -> Steps:
    if len(frames) == 1:
        return block.decode_wire((yield frames[0]))
    parts = []
    for frame in frames:
        parts.append((yield frame))
    return block.decode_wire(b"".join(parts))


def write_steps(unit: int, block: Block, payload: bytes) -> Steps:
    """A block write; an odd edge register is read first, so its byte outside the block is kept."""
    table = block.table
    if table not in WRITABLE_TABLES:
        raise MapError(f"{table} is a read-only table")
    first = last = 0
    if block.skip:
        first = int.from_bytes((yield Frame.read(unit, table, block.address, 1)), "big")
    if block.odd_end:
        last = int.from_bytes((yield Frame.read(unit, table, block.address + block.count - 1, 1)), "big")
    values = block.encode(payload, first, last)
    offset = 0
    for address, count in block.spans(write=True):
        yield Frame.write(unit, table, address, values[offset : offset + count])
        offset += count
    return b""


def probe_steps(frame: Frame) -> Steps:
    """A liveness probe: one register (or coil) 0 of the node's table, its value unused."""
    yield frame
    return b""


class Outcomes(Protocol):
    """Where a node's outcomes go (the Exchange): link changes are journaled and reach the
    presence list, finished requests reach memory."""

    def link_changed(self, node: LinkState, up: bool, error: str) -> None: ...

    def complete(self, node: LinkState, req: Request) -> None: ...


class LinkState:
    """A node's link as its transactions' outcomes set it: up with a normal answer; down (with a
    back-off doubling up to backoff_max) when every attempt failed or the node answers only
    exceptions; the first outcome is reported either way."""

    def __init__(self, config: NodeConfig, exchange: Outcomes, stats: NodeStats) -> None:
        self.config = config
        self.exchange = exchange
        self.stats = stats
        self.delay = config.backoff
        self.retry_at = 0.0  # monotonic time before which requests fail without trying
        self.reported = False
        self.idle = max(config.timeout, PROBE_IDLE)
        self.active = time.monotonic()  # when the last request or probe ended
        self.blocks: dict[tuple[int, int], tuple[Block, str]] = {}  # (remote, length) -> where it is
        # the answers since the last normal one, all exceptions: how many, to which requests, which codes
        self.refusals = 0
        self.refused: set[int] = set()  # request keys (a probe's too)
        self.repeated = False  # a request of the run was refused twice: the node refuses them all
        self.codes: set[int] = set()
        self.probe = Request(-1, config.node, 0)  # the queue item of a liveness probe
        self.probe_frame = Frame.read(config.unit, config.table, 0, 1)  # type: ignore[arg-type]

    def steps(self, req: Request) -> tuple[Steps | None, str]:
        """The transactions of a request and where it goes, or (None, why it cannot be sent)."""
        if req is self.probe:
            return probe_steps(self.probe_frame), "probe"
        if req.payload is None:
            plan = req.plan
            if plan is None:  # an instruction asks for the same block every scan: built once
                block, where = self.block(req)
                if block is None:
                    return None, where
                plan = req.plan = block, where, read_frames(self.config.unit, block)
            return read_steps(plan[2], plan[0]), plan[1]
        block, where = self.block(req)
        if block is None:
            return None, where
        return write_steps(self.config.unit, block, req.payload), where

    def block(self, req: Request) -> tuple[Block | None, str]:
        """(block, where) of a request in the node's map, mapped once per (remote, length);
        (None, what is wrong) when it is outside the map (nothing is sent)."""
        length = req.length if req.payload is None else len(req.payload)
        located = self.blocks.get((req.remote, length))
        if located is None:
            where = describe(self.config.profile, req.remote)
            try:
                located = locate(self.config.profile, self.config.table, req.remote, length), where
            except MapError as e:
                return None, f"{where}: {e}"
            self.blocks[req.remote, length] = located
        return located

    def failed(self, error: Exception, where: str, key: int) -> str:
        """What a failed request (DeviceError, MapError or LinkError after the node's retries) does
        to the link, and its text."""
        if isinstance(error, DeviceError):  # the device answered, with an exception
            if key == -1 and error.code <= ILLEGAL_VALUE:  # a probe: no register 0 there, an answer
                self.answered()
            elif self.only_exceptions(key, error.code):
                self.down(self.exceptions())
            else:
                self.link(True, "")
            return f"{where}: {error}"
        if isinstance(error, MapError):  # the block does not fit the node's table: nothing was sent
            self.link(True, "")
            return f"{where}: {error}"
        assert isinstance(error, LinkError), error  # no answer, or one that is not the request's
        self.down(str(error))
        return str(error)

    def answered(self) -> None:
        """A normal answer: the link is up, the back-off and the run of exceptions start over."""
        if self.stats.up and not self.refusals and self.delay == self.config.backoff:
            return  # the usual case: nothing to start over
        self.delay = self.config.backoff
        self.refusals, self.repeated = 0, False
        self.refused.clear()
        self.codes.clear()
        self.link(True, "")

    def only_exceptions(self, key: int, code: int) -> bool:
        """Count an exception in answer to request `key`: does the node now answer only those?"""
        self.refusals += 1
        self.repeated = self.repeated or key in self.refused
        self.refused.add(key)
        self.codes.add(code)
        return self.repeated and self.refusals >= self.config.retries + 1

    def exceptions(self) -> str:
        codes = sorted(self.codes)
        if len(codes) == 1:
            return f"answers only exception {exception_text(codes[0])}"
        return f"answers only exceptions {', '.join(exception_text(c) for c in codes)}"

    def down(self, error: str) -> None:
        """Every attempt failed: the link is down and the node backs off."""
        self.retry_at = time.monotonic() + self.delay
        self.delay = min(2 * self.delay, self.config.backoff_max)
        self.link(False, error)

    def link(self, up: bool, error: str) -> None:
        stats = self.stats
        if error:
            stats.last_error = error
        if stats.up == up and self.reported:
            return
        self.reported = True  # the first outcome is reported either way: a node down from the start too
        stats.up = up
        stats.changed = time.monotonic()
        self.exchange.link_changed(self, up, error)
