"""Where element models send what they do: the operator's input, and the form's own behaviour.

Two channels, because they run in different places (docs/architecture.md section 9):
- `Target` (`write_bit`, `write_word`): operator input a widget forwards (a click, an entered
  setpoint). The engine queues it, applies it at the start of the next scan and journals it as an
  'operator' record naming the user. Views have it; the runtime does not need it.
- `Effects` (`set_bit`, `put`): what a form does to the station by itself: a sync generator's
  output and the RegData/RegMessages and limit records. Only the runtime has it: it evaluates the
  forms' models from every scan's snapshot on the engine thread (`hmi_forms/behaviour.py`), with
  or without a GUI, so a view never pulses or journals, and a view that lags loses nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

from netplc.records import Record
from netplc.tags.table import TagTable
from netplc.tags.tag import Tag, TagType

if TYPE_CHECKING:
    from netplc.engine import Engine


class Target(Protocol):
    """`write_*` return False when the station refuses the write: its queue of outside writes is
    full (the per-scan budget's back-pressure, docs/architecture.md section 1)."""

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None) -> bool: ...

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None) -> bool: ...


BUSY = "the station is busy (its queue of outside writes is full): not written, try again"


class Effects(Protocol):
    def set_bit(self, addr: int, value: int) -> None:
        """Set an HMI bit before the next scan, unjournaled (a generator is not an operator)."""
        ...

    def put(self, record: Record) -> None: ...


class EngineTarget:
    """The engine as the operator's Target: writes are queued and journaled by the engine. A write
    to a tag's address is journaled with the tag's name and, for a word, its physical values and
    unit besides the raw ones (`write Уставка температуры TEMP_SP: 0.0 -> 130.0 °C (raw ...)`)."""

    def __init__(self, engine: Engine, tags: TagTable | None = None,
                 on_busy: Callable[[str], None] | None = None) -> None:
        """`on_busy(text)` tells the operator when the engine refuses a write (a full queue)."""
        self.engine = engine
        self.on_busy = on_busy
        tags = tags or TagTable()
        self._bits = {t.address: t for t in tags.tags if t.type is TagType.BIT}
        self._words = {t.address: t for t in tags.tags if t.type in ONE_WORD}

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None) -> bool:
        tag = self._bits.get(addr)
        return self._told(self.engine.write_bit(addr, value, user=user, label=_named(label, tag)), label)

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None) -> bool:
        tag = self._words.get(addr)
        if tag is None:
            done = self.engine.write_word(addr, value, user=user, label=label)
        else:
            done = self.engine.write_word(addr, value, user=user, label=_named(label, tag),
                                          describe=tag.change)
        return self._told(done, label)

    def _told(self, accepted: bool, label: str | None) -> bool:
        if not accepted and self.on_busy is not None:
            self.on_busy(f"{label}: {BUSY}" if label else BUSY)
        return accepted


ONE_WORD = (TagType.WORD, TagType.INT16, TagType.BCD)


def _named(label: str | None, tag: Tag | None) -> str | None:
    if tag is None:
        return label
    return f"{label} {tag.name}" if label else tag.name


class NullTarget:
    """A form shown without a station (the viewer, a benchmark): the operator's writes go nowhere."""

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None) -> bool:
        return True

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None) -> bool:
        return True
