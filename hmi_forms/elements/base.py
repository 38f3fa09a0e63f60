"""What every HMI element shares: geometry, the UObject look, SyncType gating and data quality.

An element model reads snapshots and keeps what its widget must draw; `update` says whether that
changed, so the form repaints only those widgets. The same model, bound to the runtime's
`Effects`, is what a form does to the station: an element that `acts` (a sync generator, RegData,
RegMessages) is evaluated by the runtime from every snapshot, and its records and writes go there;
a view's copy has no effects and only shows (hmi_forms/elements/target.py). Gating and quality are
decided here once, for both:
- SyncType 0 updates every tick; otherwise only while that bit is 1 (the manual's level sync).
- QualityAddr (an extension) names a bit such as an NREAD link output: while it is 0 the element
  keeps its last value and marks it stale, so frozen data never looks live.
- The data quality of what the element shows (`sources()`: its InAddr) comes from the runtime
  (app/scada/quality.py, judged by the view through `Readings`): anything but good is marked
  the same way, its word in `quality`; a bad or not yet known value is kept, not refreshed
  (trends sample NaN, a gap), while a forced value is shown as it is, marked forced.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, ClassVar

from app.authority.policy import ROLES
from app.scada.quality import Quality
from app.scada.table import TagTable
from app.scada.tag import Tag
from app.scada.words import Phrase
from hmi_forms.elements import props as p
from hmi_forms.elements.target import Effects, Target
from netplc.address import IO_BITS, BitRef, data_index
from netplc.memory import Snapshot
from netplc.records import Kind, Record

Reader = Callable[[Snapshot], int]


def bit_reader(ref: BitRef) -> Reader:
    """A reader of one bit, with the address decoded once (a form reads hundreds per tick)."""
    hmi = ref.hmi
    if hmi < IO_BITS:
        return lambda s: 1 if s.bits[hmi] else 0
    i, k = data_index(hmi >> 3), hmi & 7
    return lambda s: (s.data[i] >> k) & 1


def word_reader(addr: int) -> Reader:
    """A reader of the little-endian word at byte address `addr` (validated by the loader)."""
    if addr < IO_BITS:
        return lambda s: s.get_word(addr)
    i = data_index(addr)
    return lambda s: s.data[i] | s.data[i + 1] << 8


BORDER_STYLES = ("None", "FixedSingle", "Fixed3D")
CURSORS = ("Default", "Hand", "Cross", "IBeam", "No")


@dataclass(eq=False)
class Element:
    TYPE: ClassVar[str] = ""

    Name: str = field(default="", metadata=p.prop(p.text, required=True))
    x: int = field(default=0, metadata=p.prop(p.integer(0, 10000), required=True))
    y: int = field(default=0, metadata=p.prop(p.integer(0, 10000), required=True))
    w: int = field(default=1, metadata=p.prop(p.integer(1, 10000), required=True))
    h: int = field(default=1, metadata=p.prop(p.integer(1, 10000), required=True))
    SyncType: BitRef | None = field(default=None, metadata=p.prop(p.sync_type))
    QualityAddr: BitRef | None = field(default=None, metadata=p.prop(p.bit))
    RegData: bool = field(default=False, metadata=p.prop(p.boolean))
    RegMessages: bool = field(default=False, metadata=p.prop(p.boolean))
    BackColor: p.Color | None = field(default=None, metadata=p.prop(p.color))
    ForeColor: p.Color | None = field(default=None, metadata=p.prop(p.color))
    BorderStyle: str = field(default="None", metadata=p.prop(p.choice(*BORDER_STYLES)))
    TextAlign: str = field(default="MiddleCenter", metadata=p.prop(p.alignment))
    Font: p.Font | None = field(default=None, metadata=p.prop(p.font))
    Cursor: str = field(default="Default", metadata=p.prop(p.choice(*CURSORS)))
    BackgroundImage: Any = field(default=None, metadata=p.prop(p.image_file))
    ImageAlign: str = field(default="MiddleCenter", metadata=p.prop(p.alignment))

    stale: bool = field(default=False, init=False)  # marked: the value shown is not good
    quality: str = field(default="", init=False)  # why, as the quality word; "" while good
    target: Target | None = field(default=None, init=False, repr=False)  # the operator's writes
    effects: Effects | None = field(default=None, init=False, repr=False)  # the runtime's copy only
    user: str = field(default="operator", init=False)
    tag: str = field(default="", init=False)  # the tag of tags.csv the element's address names
    described: str = field(default="", init=False)  # that tag's description

    ADDRESS_KEYS: ClassVar[tuple[str, ...]] = ("InAddr", "Address", "OutAddr")  # where a tag is named

    def take_tag(self, raw: Mapping[str, Any], tags: TagTable) -> Tag | None:
        """The tag of tags.csv the element's address (in the form's `raw` properties) names, kept
        by name and description (the loader calls it before `check`); None: no tag is named."""
        named = (raw.get(k) for k in self.ADDRESS_KEYS)
        name = next((v for v in named if isinstance(v, str) and v in tags.by_name), None)
        if name is None:
            return None
        tag = tags.by_name[name]
        self.tag, self.described = tag.name, tag.description
        return tag

    @property
    def label(self) -> str:
        """What a person reads for the element in a confirmation and in the journal: its Name, unless
        that only repeats its type (the designer's "DiscreteBase 2"), then its tag's description or
        name; "" when it has neither (the caller names its address)."""
        if self.Name.rstrip("0123456789").rstrip() not in ("", self.TYPE):
            return self.Name
        return self.described or self.tag

    def check(self, ctx: p.Context) -> list[tuple[str, Phrase]]:
        """Problems between properties, as (property, problem); resolves references to the context."""
        return []

    def bind(self, target: Target, user: str = "operator") -> None:
        """Forward the operator's input (clicks, setpoints) to `target` under `user`."""
        self.target = target
        self.user = user

    @property
    def acts(self) -> bool:
        """Whether the element does something to the station by itself (records, writes): the
        runtime evaluates exactly these, from every snapshot."""
        return self.RegData or self.RegMessages

    @property
    def plain(self) -> bool:
        """Whether what it shows follows from one operand alone, so that a view may read it with
        others' at once and `settle` it (hmi_forms/elements/bank.py); none by default."""
        return False

    def settle(self, value: int) -> object:
        """Take a new value of its operand, read by its form's bank while its data are good, as
        `update` would, for a `plain` element; what it shows now (what its face draws)."""
        raise NotImplementedError(f"{self.TYPE} reads its own operands")

    @classmethod
    def settler(cls, models: Sequence[Element]) -> Callable[[list[int], list[int]], list[object]]:
        """`settle` of many plain elements of its kind at once, as the form's bank calls it:
        (positions in `models`, their new values) -> what each shows now. One by one, unless a
        kind does better."""
        return lambda positions, values: [models[i].settle(v) for i, v in zip(positions, values)]

    def failed(self) -> None:
        """Updating or drawing it raised: marked stale until its next good value."""
        self.stale = True

    def sources(self) -> tuple[tuple[int, int], ...]:
        """The operands whose value the element shows, as (address, bytes), bytes 0 for one HMI
        bit: what its data quality is judged on; none by default (static elements)."""
        return ()

    def update(self, snap: Snapshot, quality: Quality | None = None) -> bool:
        """Read one snapshot; True when what the widget shows has changed. `quality` is the worst
        quality of `sources()` in that scan (None: not judged, as in the runtime's own copy)."""
        sync, gate = self._gates
        if sync is not None and not sync(snap):
            return False
        word = quality.word if quality is not None and quality is not Quality.GOOD else ""
        if not word and gate is not None and not gate(snap):  # the derived quality says more
            word = Quality.STALE.word
        changed = word != self.quality
        self.quality, self.stale = word, bool(word)
        if word and quality is not Quality.FORCED:
            return self.refresh_stale(snap) or changed
        return self.refresh(snap) or changed

    @cached_property
    def _gates(self) -> tuple[Reader | None, Reader | None]:
        return (bit_reader(self.SyncType) if self.SyncType is not None else None,
                bit_reader(self.QualityAddr) if self.QualityAddr is not None else None)

    def refresh(self, snap: Snapshot) -> bool:
        return False

    def refresh_stale(self, snap: Snapshot) -> bool:
        """Called instead of `refresh` while the data are stale: by default everything is kept."""
        return False

    def record(self, snap: Snapshot, kind: Kind, **fields: Any) -> None:
        if self.effects is not None:
            self.effects.put(Record(snap.wall, kind, source=self.label or self.Name, **fields))


@dataclass(eq=False)
class Writer:
    """What an element that writes adds: the role needed (an extension, default operator) and
    whether the operator confirms first (`Confirm: true`: two steps, for a command that cannot be
    taken back). A view's `guard` decides both before anything is written; it returns why the
    write is refused (role, cancelled), or None. Without a guard (tests, benchmarks) nothing asks."""

    Role: str = field(default="operator", metadata=p.prop(p.choice(*ROLES)))
    Confirm: bool = field(default=False, metadata=p.prop(p.boolean))

    guard: Guard | None = field(default=None, init=False, repr=False)

    def refused(self, what: str) -> str | None:
        """Why `what` (the write, in words for the confirmation) may not be done now, or None."""
        return self.guard(self, what) if self.guard is not None else None


Guard = Callable[[Writer, str], "str | None"]
