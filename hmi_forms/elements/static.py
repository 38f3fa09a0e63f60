"""Static elements (a picture, a text) and the date-and-time element.

Static elements read no memory; they still honour QualityAddr, so a caption such as "Node 0" can
be greyed out with the data it labels.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from hmi_forms.elements import formats
from hmi_forms.elements import props as p
from hmi_forms.elements.base import Element
from netplc.memory import Snapshot


@dataclass(eq=False)
class StaticText(Element):
    TYPE = "StaticText"

    Text: str = field(default="", metadata=p.prop(p.text, required=True))


@dataclass(eq=False)
class StaticPicture(Element):
    """`Image` (the manual's UObject-Image) is a file in the form's folder."""

    TYPE = "StaticPicture"

    Image: Path | None = field(default=None, metadata=p.prop(p.image_file, required=True))
    SizeMode: str = field(default="Zoom", metadata=p.prop(p.choice("Normal", "Stretch", "Zoom")))


def format_span(seconds: float) -> str:
    """Time since start in the console's one time format (HH:MM:SS, where the manual printed
    HH.MM.SS), with days in front once past 24 h."""
    s = int(max(seconds, 0))
    days, s = divmod(s, 86400)
    hms = f"{s // 3600:02d}:{s // 60 % 60:02d}:{s % 60:02d}"
    return f"{days} d {hms}" if days else hms


@dataclass(eq=False)
class DateTime(Element):
    """Current time as HH:MM:SS (local; the console's one time format) and the time since the
    station started.

    The start is the engine-clock time given by `started`; without it, the first snapshot seen."""

    TYPE = "DateTime"

    ShowDate: bool = field(default=True, metadata=p.prop(p.boolean))
    ShowUptime: bool = field(default=True, metadata=p.prop(p.boolean))

    started: float | None = field(default=None, init=False)
    clock: str = field(default="", init=False)
    date: str = field(default="", init=False)
    uptime: str = field(default="", init=False)

    def refresh(self, snap: Snapshot) -> bool:
        if self.started is None:
            self.started = snap.time
        since = format_span(snap.time - self.started)
        shown = (formats.clock(snap.wall), formats.date(snap.wall), since)
        if shown == (self.clock, self.date, self.uptime):
            return False
        self.clock, self.date, self.uptime = shown
        return True
