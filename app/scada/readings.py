"""What every reader of the station gets: a value with its quality and time, per snapshot.

The HMI, the journal, the Modbus/OPC side and the publishers (app/publish/) never work out a
quality themselves: after each scan the runtime publishes one immutable `Readings` (the
snapshot, each tag's quality code, and the `LinkView` the scan was judged with), and a reader
asks it for a tag (`tag("LEVEL")`: physical and raw value, unit, quality, time) or for any
address (`address(0o4010, 2)`). It is a plain reference swapped after every scan, so any thread
may read the latest one without a lock; addresses are judged lazily, so a scan costs nothing for
the addresses nobody asks about.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from app.scada.quality import LinkView, Operands, Quality, QualityMap
from netplc.lazy import lazy
from netplc.memory import Snapshot

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it


@dataclass(frozen=True, slots=True)
class Reading:
    """One value as a reader shows or sends it."""

    value: float  # physical (the tag's conversion); the hardware value for a bare address
    quality: Quality
    time: float  # wall clock of the scan, seconds since the epoch
    raw: float | None = None  # the hardware value, for a tag
    name: str = ""  # the tag's name; "" for a bare address
    unit: str = ""

    @property
    def good(self) -> bool:
        return self.quality is Quality.GOOD

    def text(self, decimals: int = 0) -> str:
        """The value as an operator reads it; "?" instead when it is not good and not forced."""
        if math.isnan(self.value):
            return "?"
        shown = f"{self.value:.{decimals}f}" + (f" {self.unit}" if self.unit else "")
        return shown if self.quality in (Quality.GOOD, Quality.FORCED) else f"{shown} ?"


@dataclass(frozen=True)
class Readings:
    """The station as of one scan: values, qualities and the time they held."""

    snapshot: Snapshot
    quality_map: QualityMap
    links: LinkView
    codes: np.ndarray  # each tag's quality code, in the order of quality_map.tags

    @property
    def time(self) -> float:
        return self.snapshot.wall

    def quality(self, name: str) -> Quality:
        """A tag's quality (KeyError for a tag the station does not have)."""
        return Quality(int(self.codes[self.quality_map.position(name)]))

    def tag(self, name: str) -> Reading:
        """A tag's physical and raw value with its quality (KeyError for an unknown tag)."""
        i = self.quality_map.position(name)
        tag = self.quality_map.tags[i]
        raw = tag.raw(self.snapshot)
        phy = raw if tag.scaling is None else tag.scaling.to_phy(raw)
        return Reading(phy, Quality(int(self.codes[i])), self.time, raw, tag.name, tag.unit)

    def address(self, address: int, nbytes: int = 2) -> Quality:
        """The quality of any operand: `nbytes` bytes at an I/O bit or data address, or with
        `nbytes` 0 the one bit of an HMI bit address (02042, 040005)."""
        return self.quality_map.at(address, nbytes, self.snapshot, self.links)

    def judge(self, operands: Operands) -> np.ndarray:
        """The quality code of every operand of a set made by `quality_map.operands` (what a
        large form shows, judged at once), but for link output bits, which `address` judges."""
        return self.quality_map.judge(operands, self.snapshot, self.links)

    def live(self, snapshot: Snapshot) -> Snapshot:
        """`snapshot` with every NREAD/NWRITE link output bit (C+1) showing its node's link as it
        is now rather than the program's copy, which is frozen while NetPlc is stopped; the same
        snapshot when they agree (always, while the program runs and the link holds)."""
        links = self.links.links
        if links is None:
            return snapshot
        wrong = {bit: links.get(node, False) for bit, node in self.quality_map.link_bits.items()
                 if bool(snapshot.bits[bit]) != links.get(node, False)}
        if not wrong:
            return snapshot
        bits = list(snapshot.bits)
        for bit, up in wrong.items():
            bits[bit] = 1 if up else 0
        return replace(snapshot, bits=tuple(bits))

    def word(self, address: int) -> Reading:
        """An unsigned word of memory with its quality: for a reader that knows no tag."""
        value = float(self.snapshot.get_word(address))
        return Reading(value, self.address(address, 2), self.time, value)
