"""What the station publishes, and how a publisher reads it.

The points are the tags of `tags.csv`, or where a station has none its symbols (an I/O or data bit
as a Boolean, a data address as an unsigned word). A publisher reads values and quality for all of
them at once from the station's `Readings` of one scan (`PointReader`). A client's write goes
through the station's command layer (app/authority/), which checks, journals and answers it;
`writable` patterns are the station's naming of what a client may write at all.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from app.authority import Action, Commands, Reason, Ticket, Who
from app.scada.quality import Operands, QualityMap
from app.scada.readings import Readings
from app.scada.tag import Tag, TagReader, TagType, check_address
from netplc.address import IO_BITS, AddressError
from netplc.lazy import lazy

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it


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


@dataclass(frozen=True)
class Reading:
    """One scan's worth of every point: physical values and quality codes (app.scada.quality)."""

    scan: int
    wall: float
    state: str
    values: np.ndarray
    quality: np.ndarray


class PointReader:
    """Values of every point with their quality, from the `Readings` of one scan.

    The station's tags are judged by the station itself every scan (`Readings.codes`); symbols
    published where there is no tags.csv are judged here, all at once, by the same quality map
    (which NREADs fill them, their links, run state and forcing).
    """

    def __init__(self, tags: Sequence[Tag]) -> None:
        self.tags = list(tags)
        self.reader = TagReader(self.tags)
        self._map: QualityMap | None = None
        self._judge: np.ndarray | Operands = np.zeros(0, dtype=np.intp)

    def quality(self, readings: Readings) -> np.ndarray:
        qm = readings.quality_map
        if qm is not self._map:  # once: where each point's quality comes from
            self._map = qm
            try:
                self._judge = np.array([qm.position(t.name) for t in self.tags], dtype=np.intp)
            except KeyError:
                self._judge = qm.operands([t.operand for t in self.tags])
        if isinstance(self._judge, Operands):
            return readings.judge(self._judge)
        return readings.codes[self._judge]

    def read(self, readings: Readings) -> Reading:
        snapshot = readings.snapshot
        return Reading(snapshot.scan, snapshot.wall, snapshot.state, self.reader.read(snapshot),
                       self.quality(readings))


class PointWriter:
    """A client's write of a published point, as the station's command: the layer checks the role
    and the tag's physical range, journals it and answers once applied and committed. What is
    never writable (`writable` does not name it) and a value of another type than the point's
    (each protocol says which: `mismatch`) are refused here, journaled by the layer like every
    refusal."""

    def __init__(self, commands: Commands, writable: Writable, section: str) -> None:
        self.commands = commands
        self.writable = writable
        self.section = section  # the station.toml section naming the writable points: "[opcua]"

    def write(self, who: Who, tag: Tag, value: object, mismatch: str = "") -> Ticket:
        commands = self.commands
        if not self.writable(tag.name):
            return commands.refuse(who, Action.WRITE, tag.name, Reason.NOT_WRITABLE,
                                   commands.say("not writable point", section=self.section))
        if mismatch:
            if (why := commands.denial(who, Action.WRITE)) is not None:  # the role first, as the layer
                return commands.refuse(who, Action.WRITE, tag.name, Reason.DENIED, commands.refusal_text(why),
                                       why)
            return commands.refuse(who, Action.WRITE, tag.name, Reason.TYPE_MISMATCH, mismatch)
        if tag.name in commands.tags:
            return commands.write_tag(who, tag.name, value)
        # a symbol published where there is no tags.csv: a bit or an unsigned word
        lo, hi = tag.limits
        if not isinstance(value, int):
            return commands.refuse(who, Action.WRITE, tag.name, Reason.TYPE_MISMATCH,
                                   commands.say("not whole", value=value))
        if not lo <= value <= hi:
            return commands.refuse(who, Action.WRITE, tag.name, Reason.OUT_OF_RANGE,
                                   commands.say("outside g", value=value, lo=lo, hi=hi))
        if tag.type is TagType.BIT:
            return commands.write_bit(who, tag.address, 1 if value else 0, label=tag.name)
        return commands.write_word(who, tag.address, value, label=tag.name)
