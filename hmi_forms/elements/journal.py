"""The message journal element (manual 2.4.3): the registrar archive, filtered, for a chosen day.

The model keeps what the operator has chosen (day, kinds, group, minimum type) and when the view
of today should be re-read; the widget runs the queries through `registrar.query.Archive`, in its
worker thread (hmi_forms/widgets/journal.py).
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field
from typing import Any

from hmi_forms.elements import props as p
from hmi_forms.elements.base import Element
from netplc.memory import Snapshot

KINDS = ("message", "alarm", "operator", "system", "data")
# what a journal lists by default (alarm: the alarm system's transitions); data is for plots
EVENT_KINDS = ("message", "alarm", "operator", "system")


_KIND = p.choice(*KINDS)


def kinds(value: Any, ctx: p.Context) -> tuple[str, ...]:
    if not isinstance(value, list) or not value:
        raise p.PropError("form record kinds", options=", ".join(KINDS))
    return tuple(_KIND(v, ctx) for v in value)


def optional_int(lo: int, hi: int) -> p.Parser:
    bounded = p.integer(lo, hi)

    def parse(value: Any, ctx: p.Context) -> int | None:
        return None if value is None else bounded(value, ctx)

    return parse


@dataclass(eq=False)
class MessageJournal(Element):
    TYPE = "MessageJournal"

    Kinds: tuple[str, ...] = field(default=EVENT_KINDS, metadata=p.prop(kinds))
    Group: int | None = field(default=None, metadata=p.prop(optional_int(0, 65535)))
    MinType: int | None = field(default=None, metadata=p.prop(optional_int(0, 3)))
    Rows: int = field(default=500, metadata=p.prop(p.integer(10, 100_000)))
    RefreshTicks: int = field(default=10, metadata=p.prop(p.integer(1, 100_000)))

    day: dt.date | None = field(default=None, init=False)  # None = today (follows midnight)
    kinds: tuple[str, ...] = field(default=(), init=False)
    group: int | None = field(default=None, init=False)
    min_type: int | None = field(default=None, init=False)
    ticks: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        self.kinds, self.group, self.min_type = self.Kinds, self.Group, self.MinType

    def refresh(self, snap: Snapshot) -> bool:
        """True every RefreshTicks ticks while today is shown (a past day does not change)."""
        if self.day is not None:
            return False
        self.ticks += 1
        if self.ticks >= self.RefreshTicks:
            self.ticks = 0
            return True
        return False
