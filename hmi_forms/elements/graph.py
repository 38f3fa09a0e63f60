"""The Graph element (manual 2.4.3): a bit trend, one sample per NetPlc scan.

`Elements` samples are kept; `LabelInt` is the spacing of the time-axis labels in samples. While
the data are stale the samples are NaN, so the trace shows a gap instead of a flat line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

from hmi_forms.elements import props as p
from hmi_forms.elements.base import Element, Reader, bit_reader
from hmi_forms.elements.trend import Trend
from netplc.address import BitRef
from netplc.memory import Snapshot


@dataclass(eq=False)
class Graph(Element):
    TYPE = "Graph"

    Address: BitRef | None = field(default=None, metadata=p.prop(p.bit, required=True, alias="InAddr"))
    Colors: p.Color | None = field(default=None, metadata=p.prop(p.color))
    Elements: int = field(default=100, metadata=p.prop(p.integer(2, 100_000)))
    LabelInt: int = field(default=10, metadata=p.prop(p.integer(1, 100_000)))
    LineWidth: int = field(default=1, metadata=p.prop(p.integer(1, 10)))

    trend: Trend = field(default_factory=lambda: Trend(1), init=False, repr=False)
    last_scan: int = field(default=-1, init=False)

    def __post_init__(self) -> None:
        self.trend = Trend(self.Elements)

    def refresh(self, snap: Snapshot) -> bool:
        return self._sample(snap, float(self._bit(snap)))

    @cached_property
    def _bit(self) -> Reader:
        assert self.Address is not None
        return bit_reader(self.Address)

    def sources(self) -> tuple[tuple[int, int], ...]:
        return ((self.Address.hmi, 0),) if self.Address is not None else ()

    def refresh_stale(self, snap: Snapshot) -> bool:
        return self._sample(snap, math.nan)

    def _sample(self, snap: Snapshot, value: float) -> bool:
        if snap.scan == self.last_scan:
            return False
        self.last_scan = snap.scan
        self.trend.add(value, snap.wall)
        return True
