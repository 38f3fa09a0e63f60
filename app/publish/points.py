"""What the station publishes, and how a publisher reads and writes it.

The points are the tags of `tags.csv`, or where a station has none its symbols (an I/O or data bit
as a Boolean, a data address as an unsigned word). A publisher reads values and quality for all of
them at once from one snapshot (`PointReader`) and writes through the engine's queue, which
journals every write as an 'operator' record naming the client; `writable` patterns name what a
client may write at all, and a refused write is journaled too.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from netplc.address import IO_BITS, AddressError
from netplc.engine import Engine
from netplc.memory import Snapshot
from netplc.records import Record, RecordSink
from netplc.tags.tag import Tag, TagReader, TagType, check_address

MAX_PENDING_WRITES = 1000  # queued engine actions beyond which a client's write is refused, not queued


def symbol_tags(symbols: dict[str, int]) -> list[Tag]:
    """The symbols as tags: a bit (I/O bit or HMI data bit) is a BIT, a data address a WORD."""
    tags = []
    for name, addr in symbols.items():
        kind = TagType.BIT if addr < IO_BITS else TagType.WORD
        try:
            check_address(addr, kind)
        except (AddressError, ValueError):
            kind = TagType.BIT
            try:
                check_address(addr, kind)
            except (AddressError, ValueError):
                continue  # neither: not an address a client can read
        tags.append(Tag(name, addr, kind))
    return tags


def published_tags(table_tags: Sequence[Tag], symbols: dict[str, int]) -> list[Tag]:
    return list(table_tags) if table_tags else symbol_tags(symbols)


class Writable:
    """Tag names or shell-style patterns (`Valve*`, `SP_?`) a client may write; none by default."""

    def __init__(self, patterns: Iterable[str]) -> None:
        self.patterns = tuple(patterns)

    def __call__(self, name: str) -> bool:
        return any(fnmatch.fnmatchcase(name, p) for p in self.patterns)


QualitySource = Callable[[], np.ndarray | None]
PasswordCheck = Callable[[str, str], bool]  # (user, password) -> may this client in?


@dataclass(frozen=True)
class Reading:
    """One snapshot's worth of every point: physical values and quality codes (netplc.tags.quality)."""

    scan: int
    wall: float
    state: str
    values: np.ndarray
    quality: np.ndarray


class PointReader:
    """Values of every point from a snapshot, with the quality the runtime evaluated for that scan.

    The quality comes through one callable (today `runtime.alarms.quality`, read on the engine
    thread right after the scan, so it belongs to the same snapshot); a station without tags.csv
    publishes symbols, whose quality is that of the run state alone.
    """

    def __init__(self, tags: Sequence[Tag], quality: QualitySource) -> None:
        self.tags = list(tags)
        self.reader = TagReader(self.tags)
        self._quality = quality

    def quality_now(self, snapshot: Snapshot) -> np.ndarray:
        """On the engine thread, right after the scan: the quality codes of that scan."""
        q = self._quality()
        if q is None or len(q) != len(self.tags):
            from netplc.tags.quality import Quality
            code = Quality.GOOD if snapshot.state == "running" else Quality.NOT_RUNNING
            return np.full(len(self.tags), code, dtype=np.int8)
        return q

    def read(self, snapshot: Snapshot, quality: np.ndarray) -> Reading:
        return Reading(snapshot.scan, snapshot.wall, snapshot.state, self.reader.read(snapshot), quality)


def runtime_quality(runtime: object) -> QualitySource:
    """The one adapter to the runtime's per-scan quality (StationAlarms.quality today)."""
    def read() -> np.ndarray | None:
        alarms = getattr(runtime, "alarms", None)
        return None if alarms is None else alarms.quality
    return read


class WriteRefused(Exception):
    """A client's write that is not done; the text says why (and is journaled)."""


class Writer:
    """Client writes into the engine's queue, journaled as 'operator' records by the engine; refusals
    journaled here. `user` names the protocol, the user and the peer (`opcua:alice@10.0.0.5:51234`)."""

    def __init__(self, engine: Engine, tags: Sequence[Tag], writable: Writable, sink: RecordSink,
                 wallclock: Callable[[], float]) -> None:
        self.engine = engine
        self.by_name = {t.name: t for t in tags}
        self.writable = writable
        self.sink = sink
        self.wallclock = wallclock

    def can_write(self, name: str) -> bool:
        return name in self.by_name and self.writable(name)

    def write(self, name: str, value: float, user: str) -> None:
        """Queue the write of physical `value` to tag `name`; WriteRefused (journaled) if it may not."""
        tag = self.by_name.get(name)
        if tag is None:
            self.refuse(name, value, user, "no such tag")
        if not self.writable(name):
            self.refuse(name, value, user, "not writable")
        if len(self.engine._queue) >= MAX_PENDING_WRITES:  # back-pressure: refuse, never stall the client
            self.refuse(name, value, user, "write queue full")
        try:
            value = float(value)
        except (TypeError, ValueError):
            self.refuse(name, value, user, "not a number")
        if value != value:
            self.refuse(name, value, user, "not a number")
        assert tag is not None
        raw = tag.to_raw(value)
        try:
            if tag.type is TagType.BIT:
                self.engine.write_bit(tag.address, 1 if raw else 0, user=user, label=name)
            elif tag.type in (TagType.INT32, TagType.FLOAT32):
                self.engine.write_bytes(tag.address, tag.encode(raw), user=user)
            else:
                word = int.from_bytes(tag.encode(raw), "little")
                self.engine.write_word(tag.address, word, user=user, label=name)
        except Exception as e:  # the engine pushing back (its write budget): a refusal, never a stall
            self.refuse(name, value, user, f"write queue full ({e})" if str(e) else "write queue full")

    def refuse(self, name: str, value: object, user: str, why: str) -> None:
        self.sink.put(Record(self.wallclock(), "operator", source=user,
                             text=f"write refused {name} = {value!r}: {why}"))
        raise WriteRefused(why)
