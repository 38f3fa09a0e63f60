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

from typing import TYPE_CHECKING, Protocol

from netplc.records import Record

if TYPE_CHECKING:
    from netplc.engine import Engine


class Target(Protocol):
    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None) -> None: ...

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None) -> None: ...


class Effects(Protocol):
    def set_bit(self, addr: int, value: int) -> None:
        """Set an HMI bit before the next scan, unjournaled (a generator is not an operator)."""
        ...

    def put(self, record: Record) -> None: ...


class EngineTarget:
    """The engine as the operator's Target: writes are queued and journaled by the engine."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None) -> None:
        self.engine.write_bit(addr, value, user=user, label=label)

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None) -> None:
        self.engine.write_word(addr, value, user=user, label=label)


class NullTarget:
    """A form shown without a station (the viewer, a benchmark): the operator's writes go nowhere."""

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None) -> None:
        pass

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None) -> None:
        pass
