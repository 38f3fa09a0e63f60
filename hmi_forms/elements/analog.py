"""Analog elements (manual 2.4.3): a word converted to a physical value, and the operator's setpoint.

Conversion is linear between the hardware range AppMin..AppMax and the physical range
PhyMin..PhyMax, taken from a named Device of the form or from the element's own four properties
(docs/architecture.md section 9), or from the tag of tags.csv the element's address names
(`"InAddr": "LEVEL"`): the tag gives the conversion, Units, Precision and, for the analog input,
PhyLow/PhyHigh from its L/H alarm limits, each unless the form gives it. Decisions where the
manual is silent:
- PhyLow/PhyHigh split the value into zones low/normal/high; a zone is left only when the value is
  back by Hysteresis (physical units, default 0), so a noisy value at a limit does not flood the
  journal. RegMessages records each zone change (kind "message": NormalMessage with type 0,
  LowMessage/HighMessage with type 2 = alarm, which the operator must acknowledge); a value
  already outside the limits at start is reported too.
- RegData records the value whenever its displayed text (Precision decimals) changes.
- KeepMaxValue keeps the largest physical value seen until `reset_max` (the widget: double-click).

What a word shows (its physical value, text, zone and place on the scale) is computed in one place,
`Scaled.shows`, into a `Shown`: the element's own update, `settle` (the form's bank of plain
gauges) and every view read that, so no path can show a word otherwise than another.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from itertools import repeat
from operator import attrgetter
from typing import Any, NamedTuple

from app.scada.table import TagTable
from app.scada.tag import Tag
from app.scada.words import Phrase, phrase
from hmi_forms.elements import props as p
from hmi_forms.elements.base import Element, Reader, Writer, word_reader
from hmi_forms.elements.sentence import Sentence
from hmi_forms.elements.trend import Trend
from netplc.address import IO_BITS, fmt_octal
from netplc.lazy import lazy
from netplc.memory import Snapshot

logger = logging.getLogger(__name__)
np = lazy("numpy")  # loaded at first use: only a station with forms needs it

APPEARANCES = ("digital", "hbar", "dial", "semidial", "graph", "tank")  # tank: an extension
ZONE_TYPES = {"low": 2, "normal": 0, "high": 2}
# what an AnalogOutput says of an entry (the widget lists them for the translations)
DISABLED = "Input is disabled for this element"
NOT_A_NUMBER = '"{0}" is not a number'
OUT_OF_RANGE = "{0} is out of range {1} … {2}{3}"
SET_TO = "Set to {0}{1}"
MAX_SHOWN = 4096  # words remembered per conversion (`remembered`), then forgotten: memory stays flat


class Shown(NamedTuple):
    """What an analog element shows of one word (`Scaled.shows` makes every one). Immutable: a
    view reads it and cannot change it; a named tuple: made for every new word of a plant's
    thousands (several times faster to make than a frozen dataclass), its parts read by name."""

    hw: int | None  # None: no word read yet
    phy: float
    text: str  # Precision decimals; "" while unknown
    zone: str | None  # low, normal or high; None without limits
    fraction: float  # the place on the scale PhyMin..PhyMax, clamped to 0..1 (pointers, bars)


UNKNOWN = Shown(None, math.nan, "", None, 0.0)
ZONES = ("normal", "low", "high", None)  # by the codes `Settler` computes
SHOWN: dict[tuple[object, ...], dict[int, Shown]] = {}  # `AnalogBase.remembered`, by conversion


@dataclass(eq=False)
class Scaled(Element):
    """The conversion and number format shared by the analog input and output."""

    Device: str | None = field(default=None, metadata=p.prop(p.text))
    AppMin: float | None = field(default=None, metadata=p.prop(p.number))
    AppMax: float | None = field(default=None, metadata=p.prop(p.number))
    PhyMin: float | None = field(default=None, metadata=p.prop(p.number))
    PhyMax: float | None = field(default=None, metadata=p.prop(p.number))
    Precision: int = field(default=1, metadata=p.prop(p.integer(0, 6)))
    Units: str = field(default="", metadata=p.prop(p.text))

    scaling: p.Scaling = field(default=p.Scaling(0, 1, 0, 1), init=False)
    shown: Shown = field(default=UNKNOWN, init=False)  # what its word shows now

    def take_tag(self, raw: Mapping[str, Any], tags: TagTable) -> Tag | None:
        """Fill from the tag named by the element's address what the form's `raw` properties leave
        out (the loader calls it before `check`)."""
        tag = super().take_tag(raw, tags)
        if tag is None:
            return None
        ranges = ("Device", "AppMin", "AppMax", "PhyMin", "PhyMax")
        if not any(k in raw for k in ranges):
            lo, hi = tag.limits
            sc = tag.scaling or p.Scaling(lo, hi, lo, hi)
            self.AppMin, self.AppMax, self.PhyMin, self.PhyMax = sc.AppMin, sc.AppMax, sc.PhyMin, sc.PhyMax
        if "Units" not in raw:
            self.Units = tag.unit
        if "Precision" not in raw:
            self.Precision = tag.decimals
        alarms = tags.alarms.get(tag.name)
        if alarms is not None and isinstance(self, AnalogBase):
            if "PhyLow" not in raw and alarms.l is not None:
                self.PhyLow = alarms.l
            if "PhyHigh" not in raw and alarms.h is not None:
                self.PhyHigh = alarms.h
        return tag

    def disagreements(self, raw: Mapping[str, Any], tags: TagTable) -> list[tuple[str, Phrase]]:
        """Where the form's own conversion or unit (`raw`, checked) contradicts the tag the element
        is bound to: the tag is the station's truth (alarms, journal, OPC UA read it), so an element
        scaling otherwise shows a wrong number with the right unit. Warnings: the form still opens."""
        tag = tags.by_name.get(self.tag)
        if tag is None:
            return []
        out: list[tuple[str, Phrase]] = []
        lo, hi = tag.limits
        truth = tag.scaling or p.Scaling(lo, hi, lo, hi)
        own = self.scaling
        span = abs(truth.PhyMax - truth.PhyMin) or 1.0
        if any(k in raw for k in ("Device", "AppMin", "AppMax", "PhyMin", "PhyMax")) and any(
                abs(own.to_phy(w) - truth.to_phy(w)) > 1e-6 * span for w in (truth.AppMin, truth.AppMax)):
            key = "Device" if "Device" in raw else next(
                (k for k in ("AppMin", "AppMax", "PhyMin", "PhyMax") if getattr(own, k) != getattr(truth, k)),
                "AppMin")
            word = truth.AppMax
            out.append((key, phrase("form contradicts", own=_ranges(own), tag=tag.name, truth=_ranges(truth),
                                    word=word, here=self.format(own.to_phy(word)),
                                    there=f"{self.format(truth.to_phy(word))} {tag.unit}".rstrip())))
        if "Units" in raw and tag.unit and self.Units != tag.unit:
            out.append(("Units", phrase("form unit contradicts", units=self.Units, tag=tag.name,
                                        unit=tag.unit)))
        return out

    def check(self, ctx: p.Context) -> list[tuple[str, Phrase]]:
        inline = {k: getattr(self, k) for k in ("AppMin", "AppMax", "PhyMin", "PhyMax")}
        given = [k for k, v in inline.items() if v is not None]
        if self.Device is not None:
            if given:
                return [(given[0], phrase("form device or ranges"))]
            if self.Device not in ctx.devices:
                known = ", ".join(sorted(ctx.devices)) or phrase("form no devices")
                return [("Device", phrase("form unknown device", device=self.Device, known=known))]
            self.scaling = ctx.devices[self.Device]
            return []
        missing = [k for k, v in inline.items() if v is None]
        if len(missing) == 4:
            return [("Device", phrase("form no conversion"))]
        if missing:
            return [(k, phrase("form range missing")) for k in missing]
        problems = scaling_problems(inline)
        if not problems:
            self.scaling = p.Scaling(**inline)
        return problems

    def format(self, phy: float) -> str:
        return f"{phy:.{self.Precision}f}"

    def shows(self, hw: int) -> Shown:
        """What the word `hw` shows: the one place where a word becomes a physical value, a text, a
        zone and a place on the scale."""
        phy = self.scaling.to_phy(hw)
        return Shown(hw, phy, self.format(phy), self.zone_of(phy), self.scaling.fraction(phy))

    def zone_of(self, phy: float) -> str | None:
        """The zone `phy` lies in; None: the element has no limits."""
        return None

    # what it shows now, by part (read only: `shows` makes them all at once)
    hw = property(attrgetter("shown.hw"))
    phy = property(attrgetter("shown.phy"))
    text = property(attrgetter("shown.text"))
    zone = property(attrgetter("shown.zone"))
    fraction = property(attrgetter("shown.fraction"))


def _ranges(sc: p.Scaling) -> str:
    return f"{sc.AppMin:g}..{sc.AppMax:g} -> {sc.PhyMin:g}..{sc.PhyMax:g}"


def scaling_problems(ranges: dict[str, Any]) -> list[tuple[str, Phrase]]:
    """Ranges that would divide by zero; shared by elements and the form's Devices table."""
    problems = []
    if ranges["AppMax"] == ranges["AppMin"]:
        problems.append(("AppMax", phrase("form equals", key="AppMin", value=ranges["AppMin"])))
    if ranges["PhyMax"] == ranges["PhyMin"]:
        problems.append(("PhyMax", phrase("form equals", key="PhyMin", value=ranges["PhyMin"])))
    return problems


@dataclass(eq=False)
class AnalogBase(Scaled):
    TYPE = "AnalogBase"

    InAddr: int | None = field(default=None, metadata=p.prop(p.word, required=True, alias="Address"))
    KeepMaxValue: bool = field(default=False, metadata=p.prop(p.boolean))
    PhyLow: float | None = field(default=None, metadata=p.prop(p.number))
    PhyHigh: float | None = field(default=None, metadata=p.prop(p.number))
    Hysteresis: float = field(default=0.0, metadata=p.prop(p.number))
    LowMessage: str = field(default="", metadata=p.prop(p.text))
    NormalMessage: str = field(default="", metadata=p.prop(p.text))
    HighMessage: str = field(default="", metadata=p.prop(p.text))
    Appearance: str = field(default="digital", metadata=p.prop(p.choice(*APPEARANCES), alias="Arreragance"))
    Elements: int = field(default=200, metadata=p.prop(p.integer(2, 100_000)))
    Colors: p.Color | None = field(default=None, metadata=p.prop(p.color))
    LineWidth: int = field(default=1, metadata=p.prop(p.integer(1, 10)))
    LabelInt: int = field(default=50, metadata=p.prop(p.integer(1, 100_000)))

    maximum: float | None = field(default=None, init=False)
    # what each word shows, as `shows` made it, shared by every element with the same conversion
    # (a form of a thousand gauges shows few distinct words); none are remembered for an element
    # with Hysteresis, whose zone depends on the last one
    remembered: dict[int, Shown] = field(default_factory=dict, init=False, repr=False)
    trend: Trend | None = field(default=None, init=False, repr=False)
    last_scan: int = field(default=-1, init=False)

    def check(self, ctx: p.Context) -> list[tuple[str, Phrase]]:
        problems = super().check(ctx)
        if self.PhyLow is not None and self.PhyHigh is not None and self.PhyLow >= self.PhyHigh:
            problems.append(("PhyHigh", phrase("form above", high=self.PhyHigh, low=self.PhyLow)))
        if self.Hysteresis < 0:
            problems.append(("Hysteresis", phrase("form negative")))
        key = (self.scaling, self.Precision, self.PhyLow, self.PhyHigh, self.Hysteresis)
        self.remembered = SHOWN.setdefault(key, {})  # shared once the conversion is known
        return problems

    def __post_init__(self) -> None:
        if self.Appearance == "graph":
            self.trend = Trend(self.Elements)

    @cached_property
    def _in(self) -> Reader:
        assert self.InAddr is not None
        return word_reader(self.InAddr)

    def sources(self) -> tuple[tuple[int, int], ...]:
        return ((self.InAddr, 2),) if self.InAddr is not None else ()

    def zone_of(self, phy: float) -> str | None:
        """Zone with hysteresis: leaving the current zone needs the value to be Hysteresis inside."""
        lo, hi, hy = self.PhyLow, self.PhyHigh, self.Hysteresis
        if lo is None and hi is None:
            return None
        zone = self.zone
        if zone == "low" and lo is not None and phy < lo + hy:
            return "low"
        if zone == "high" and hi is not None and phy > hi - hy:
            return "high"
        if lo is not None and phy < lo:
            return "low"
        if hi is not None and phy > hi:
            return "high"
        return "normal"

    @property
    def message(self) -> str:
        return {"low": self.LowMessage, "high": self.HighMessage, "normal": self.NormalMessage}.get(
            self.zone or "", "")

    @property
    def plain(self) -> bool:
        """Its word at a data address, with no trend, maximum, hysteresis, gating or effects."""
        return (self.InAddr is not None and self.InAddr >= IO_BITS and self.trend is None
                and not self.KeepMaxValue and self.Hysteresis == 0 and self.SyncType is None
                and self.QualityAddr is None and (self.effects is None or not self.acts))

    def settle(self, hw: int) -> Shown:
        """A new word of a plain element read by its form's bank, while its data are good: what
        `refresh` would show (a plain element records nothing and keeps no maximum)."""
        shown = self.remembered.get(hw) or self._remember(hw)  # (a plant's words miss as often as not)
        self.shown = shown
        self.stale = False
        return shown

    @classmethod
    def settler(cls, models: Sequence[Element]) -> Settler:
        return Settler(models)  # type: ignore[arg-type]

    def _remember(self, hw: int) -> Shown:
        """`shows`, remembered (a `Shown` is never false: `remembered.get(hw) or ...`)."""
        shown = self.shows(hw)
        remembered = self.remembered
        if len(remembered) >= MAX_SHOWN:
            remembered.clear()
        remembered[hw] = shown
        return shown

    def refresh(self, snap: Snapshot) -> bool:
        hw = self._in(snap)
        was = self.shown
        changed = hw != was.hw
        if changed:
            shown = self.shows(hw) if self.Hysteresis else self.remembered.get(hw) or self._remember(hw)
            self.shown = shown
            if self.RegData and shown.text != was.text:
                self.record(snap, "data", value=shown.phy)
            if self.KeepMaxValue and (self.maximum is None or shown.phy > self.maximum):
                self.maximum = shown.phy
            zone = shown.zone
            if zone != was.zone and self.RegMessages and (was.zone is not None or zone != "normal"):
                text = self.message or f"{zone}: {shown.text}"
                self.record(snap, "message", type=ZONE_TYPES[zone], value=shown.phy, text=text)
        return self._sample(snap, self.phy) or changed

    def refresh_stale(self, snap: Snapshot) -> bool:
        return self._sample(snap, math.nan)

    def _sample(self, snap: Snapshot, phy: float) -> bool:
        """One trend sample per scan (NaN while stale, drawn as a gap)."""
        if self.trend is None or snap.scan == self.last_scan:
            return False
        self.last_scan = snap.scan
        self.trend.add(phy, snap.wall)
        return True

    def reset_max(self) -> None:
        self.maximum = None if math.isnan(self.phy) else self.phy


class Settler:
    """`AnalogBase.settle` of the plain gauges a form's bank serves, many words at once: what
    `shows` makes of each word not remembered is computed for all of them in one pass of numpy
    (`Scaling.to_phy` itself on arrays, the same arithmetic; a plain gauge has no Hysteresis, so
    its zone is where the value lies), then remembered and shared as `shows`' are. A plant's
    words over their whole range are new at nearly every tick: one pass over a thousand costs
    less than a thousand calls. Tested equal to `shows` word for word (tests/hmi_forms/test_bank.py)."""

    def __init__(self, models: Sequence[AnalogBase]) -> None:
        self.models = list(models)
        self.remembered = [m.remembered for m in models]
        sc = [m.scaling for m in models]
        self.scaling = p.Scaling(*(np.array([getattr(s, k) for s in sc], dtype=np.float64)
                                   for k in ("AppMin", "AppMax", "PhyMin", "PhyMax")))
        self.low = np.array([-math.inf if m.PhyLow is None else m.PhyLow for m in models])
        self.high = np.array([math.inf if m.PhyHigh is None else m.PhyHigh for m in models])
        self.zoned = np.array([m.PhyLow is not None or m.PhyHigh is not None for m in models])
        self.specs = [f".{m.Precision}f" for m in models]
        # one precision for all (the usual form): their texts made by one % of a joined format
        precisions = {m.Precision for m in models}
        self.percent = f"%.{precisions.pop()}f" if len(precisions) == 1 else None

    def __call__(self, positions: list[int], words: list[int]) -> list[Shown]:
        """What each of the models at `positions` shows of its new word, each model settled."""
        remembered = self.remembered
        shown = [remembered[i].get(w) for i, w in zip(positions, words)]
        missed = [k for k, s in enumerate(shown) if s is None]
        if missed:
            at = np.array([positions[k] for k in missed], dtype=np.intp)
            hw = [words[k] for k in missed]
            sc = self.scaling
            scaling = p.Scaling(sc.AppMin[at], sc.AppMax[at], sc.PhyMin[at], sc.PhyMax[at])
            phy = scaling.to_phy(np.array(hw, dtype=np.float64))
            place = (phy - scaling.PhyMin) / (scaling.PhyMax - scaling.PhyMin)  # as `Scaling.fraction`
            fraction = np.minimum(np.maximum(place, 0.0), 1.0)
            zone = np.where(phy < self.low[at], 1, np.where(phy > self.high[at], 2, 0))
            zone[~self.zoned[at]] = 3
            phys = phy.tolist()
            zones = map(ZONES.__getitem__, zone.tolist())
            parts = zip(hw, phys, self._texts(phys, at), zones, fraction.tolist())
            made = map(tuple.__new__, repeat(Shown), parts)  # as `_make` makes them, with no Python call
            for k, new in zip(missed, made):
                i = positions[k]
                table = remembered[i]
                if len(table) >= MAX_SHOWN:
                    table.clear()
                shown[k] = table.setdefault(new.hw, new)
        models = self.models
        for i, s in zip(positions, shown):
            model = models[i]
            model.shown = s
            model.stale = False
        return shown

    def _texts(self, phys: list[float], at: np.ndarray) -> list[str]:
        """The values' texts, as `format` makes each ("%.1f" is `format(v, ".1f")`, and a text
        holds no separator)."""
        if self.percent is not None:
            return ("\x1f".join([self.percent] * len(phys)) % tuple(phys)).split("\x1f")
        specs = self.specs
        return list(map(format, phys, [specs[i] for i in at.tolist()]))


@dataclass(eq=False)
class AnalogOutput(Scaled, Writer):
    """The operator enters a physical value; it is checked, converted, clamped and written."""

    TYPE = "AnalogOutput"

    OutAddr: int | None = field(default=None, metadata=p.prop(p.word, required=True))
    InAddr: int | None = field(default=None, metadata=p.prop(p.word, alias="Address"))
    Enabled: bool = field(default=True, metadata=p.prop(p.boolean))

    def sources(self) -> tuple[tuple[int, int], ...]:
        addr = self.InAddr if self.InAddr is not None else self.OutAddr
        return ((addr, 2),) if addr is not None else ()

    def refresh(self, snap: Snapshot) -> bool:
        addr = self.InAddr if self.InAddr is not None else self.OutAddr
        assert addr is not None
        hw = snap.get_word(addr)
        if hw == self.hw:
            return False
        self.shown = self.shows(hw)
        return True

    def change(self, old: int, new: int) -> str:
        """A write of its word as the journal says it: the physical values and unit ("20.0 -> 50.0 °C")."""
        units = f" {self.Units}" if self.Units else ""
        return f"{self.format(self.scaling.to_phy(old))} -> {self.format(self.scaling.to_phy(new))}{units}"

    def submit(self, entry: str) -> tuple[bool, str]:
        """Validate the operator's entry and write it; returns (accepted, message to show)."""
        lo, hi = self.scaling.phy_range
        units = f" {self.Units}" if self.Units else ""
        if not self.Enabled:
            return False, Sentence(DISABLED)
        try:
            phy = float(entry.strip().replace(",", "."))
        except ValueError:
            return False, Sentence(NOT_A_NUMBER, entry.strip())
        if not math.isfinite(phy):
            return False, Sentence(NOT_A_NUMBER, entry.strip())
        if not lo <= phy <= hi:
            return False, Sentence(OUT_OF_RANGE, entry.strip(), self.format(lo), self.format(hi), units)
        hw = self.scaling.to_hw(phy)
        assert self.OutAddr is not None
        label = self.label or fmt_octal(self.OutAddr)
        if why := self.refused(f"{label} \u2192 {self.format(self.scaling.to_phy(hw))}{units}"):
            return False, why
        if self.target is not None and (why := self.target.write_word(
                self.OutAddr, hw, user=self.user, label=self.label or None, at_least=self.Role,
                describe=self.change)) is not None:
            return False, why
        return True, Sentence(SET_TO, self.format(self.scaling.to_phy(hw)), units)
