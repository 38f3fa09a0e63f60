"""Discrete elements (manual 2.4.3): a bit shown as text, image and colours, toggled by a click.

Each type extends the previous one, as in the manual: base -> colour label -> controlled enable
-> animation. Decisions where the manual is silent:
- a click on an Enabled element writes the inverse of the shown value to OutAddr (InAddr if no
  OutAddr); nothing is written while the value is unknown or stale, or while the indication of a
  controlled-enable element is switched off, since the operator cannot see what would be toggled;
- RegMessages records TextTrue/TextFalse on every transition (kind "message", type 0), RegData
  records the new value (kind "data").
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from functools import cached_property

from app.scada.words import Phrase, phrase
from hmi_forms.elements import props as p
from hmi_forms.elements.base import Element, Reader, Writer, bit_reader
from netplc.address import BitRef
from netplc.memory import Snapshot

logger = logging.getLogger(__name__)


@dataclass(eq=False)
class DiscreteBase(Element, Writer):
    TYPE = "DiscreteBase"

    InAddr: BitRef | None = field(default=None, metadata=p.prop(p.bit, required=True, alias="Address"))
    OutAddr: BitRef | None = field(default=None, metadata=p.prop(p.bit))
    Enabled: bool = field(default=False, metadata=p.prop(p.boolean))
    TextFalse: str = field(default="", metadata=p.prop(p.text))
    TextTrue: str = field(default="", metadata=p.prop(p.text))
    ImageFalse: int = field(default=-1, metadata=p.prop(p.image_index))
    ImageTrue: int = field(default=-1, metadata=p.prop(p.image_index))

    value: int | None = field(default=None, init=False)

    @cached_property
    def _in(self) -> Reader:
        assert self.InAddr is not None
        return bit_reader(self.InAddr)

    def sources(self) -> tuple[tuple[int, int], ...]:
        return ((self.InAddr.hmi, 0),) if self.InAddr is not None else ()

    @property
    def text(self) -> str:
        return self.TextTrue if self.value else self.TextFalse

    @property
    def image(self) -> int:
        return self.ImageTrue if self.value else self.ImageFalse

    @property
    def indicating(self) -> bool:
        return True

    @property
    def clickable(self) -> bool:
        return self.Enabled and self.value is not None and not self.stale and self.indicating

    @property
    def plain(self) -> bool:
        """One bit shown (not a controlled-enable or animated element), with no gating or effects."""
        return (type(self) in (DiscreteBase, DiscreteColorLabel) and self.InAddr is not None
                and self.SyncType is None and self.QualityAddr is None
                and (self.effects is None or not self.acts))

    def settle(self, value: int) -> int:
        self.value = value
        self.stale = False
        return value

    def refresh(self, snap: Snapshot) -> bool:
        v = self._in(snap)
        if v == self.value:
            return False
        first = self.value is None
        self.value = v
        if not first:
            if self.RegMessages:  # the state, also while its indication is switched off
                self.record(snap, "message", type=0, text=self.TextTrue if v else self.TextFalse)
            if self.RegData:
                self.record(snap, "data", value=float(v))
        return True

    def click(self) -> bool:
        """Toggle the bit through the operator write path (the station's command layer, asking at
        least the element's Role); False when the click is refused."""
        if not self.clickable or self.target is None:
            return False
        out = self.OutAddr or self.InAddr
        assert out is not None
        new = 0 if self.value else 1
        state = (self.TextTrue if new else self.TextFalse) or str(new)  # in the element's words
        if self.refused(f"{self.label or out} \u2192 {state}"):
            return False
        why = self.target.write_bit(out.hmi, new, user=self.user, label=self.label or None,
                                    at_least=self.Role)
        return why is None


@dataclass(eq=False)
class DiscreteColorLabel(DiscreteBase):
    """Background and text colours per state; None falls back to BackColor/ForeColor."""

    TYPE = "DiscreteColorLabel"

    BackColorFalse: p.Color | None = field(default=None, metadata=p.prop(p.color))
    BackColorTrue: p.Color | None = field(default=None, metadata=p.prop(p.color))
    ForeColorFalse: p.Color | None = field(default=None, metadata=p.prop(p.color))
    ForeColorTrue: p.Color | None = field(default=None, metadata=p.prop(p.color))

    @property
    def back_color(self) -> p.Color | None:
        if not self.indicating or self.value is None:
            return self.BackColor
        return (self.BackColorTrue if self.value else self.BackColorFalse) or self.BackColor

    @property
    def fore_color(self) -> p.Color | None:
        if not self.indicating or self.value is None:
            return self.ForeColor
        return (self.ForeColorTrue if self.value else self.ForeColorFalse) or self.ForeColor


@dataclass(eq=False)
class DiscreteControlledEnable(DiscreteColorLabel):
    """While the bit EnableAddr is 0 the state is not indicated: neutral colours, no state text."""

    TYPE = "DiscreteControlledEnable"

    EnableAddr: BitRef | None = field(default=None, metadata=p.prop(p.bit, required=True))

    enable: int = field(default=1, init=False)

    @property
    def indicating(self) -> bool:
        return bool(self.enable)

    @property
    def text(self) -> str:
        return super().text if self.enable else ""

    @property
    def image(self) -> int:
        return super().image if self.enable else -1

    def refresh(self, snap: Snapshot) -> bool:
        assert self.EnableAddr is not None
        enable = snap.get_hmi_bit(self.EnableAddr)
        changed = enable != self.enable
        self.enable = enable
        return super().refresh(snap) or changed


@dataclass(eq=False)
class DiscreteAnimation(DiscreteControlledEnable):
    """While the bit is 1 the image steps through ImageFirst..ImageLast, one frame per FrameTicks."""

    TYPE = "DiscreteAnimation"

    ImageFirst: int = field(default=-1, metadata=p.prop(p.image_index, required=True))
    ImageLast: int = field(default=-1, metadata=p.prop(p.image_index, required=True))
    FrameTicks: int = field(default=1, metadata=p.prop(p.integer(1, 1000)))

    frame: int = field(default=0, init=False)
    ticks: int = field(default=0, init=False)

    def check(self, ctx: p.Context) -> list[tuple[str, Phrase]]:
        if self.ImageLast < self.ImageFirst:
            return [("ImageLast", phrase("form image before", last=self.ImageLast, first=self.ImageFirst))]
        return []

    @property
    def image(self) -> int:
        if self.enable and self.value:
            return self.ImageFirst + self.frame
        return super().image

    def refresh(self, snap: Snapshot) -> bool:
        changed = super().refresh(snap)
        if not (self.enable and self.value):
            changed = changed or self.frame != 0
            self.frame = self.ticks = 0
            return changed
        self.ticks += 1
        if self.ticks >= self.FrameTicks:
            self.ticks = 0
            self.frame = (self.frame + 1) % (self.ImageLast - self.ImageFirst + 1)
            return True
        return changed
