"""Where element models send writes and records: a protocol the workstation satisfies with the engine.

Operator writes (a click, an entered setpoint) go through `write_bit`/`write_word`, which the
engine queues, applies at the start of the next scan and journals as 'operator' records.
Sync generators are not operators: they write their output every tick through `set_bit`, which
must not journal (it maps to `engine.post`). RegData/RegMessages records go to `put`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

from netplc.memory import Memory
from netplc.records import Record, RecordSink

if TYPE_CHECKING:
    from netplc.engine import Engine


class Target(Protocol):
    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None) -> None: ...

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None) -> None: ...

    def set_bit(self, addr: int, value: int) -> None: ...

    def put(self, record: Record) -> None: ...


class EngineTarget:
    """The engine as a Target. Records go through the engine's queue, so the registrar sink is only
    ever called from the engine thread (the GUI thread never touches it)."""

    def __init__(self, engine: Engine, sink: RecordSink | None = None) -> None:
        self.engine = engine
        self.sink = sink

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None) -> None:
        self.engine.write_bit(addr, value, user=user, label=label)

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None) -> None:
        self.engine.write_word(addr, value, user=user, label=label)

    def set_bit(self, addr: int, value: int) -> None:
        def apply(mem: Memory) -> None:
            mem.set_hmi_bit(addr, value)

        self.engine.post(apply)

    def put(self, record: Record) -> None:
        sink = self.sink or self.engine.sink

        def apply(_mem: Memory) -> None:
            sink.put(record)

        self.engine.post(apply)


class NullTarget:
    """A form shown without a station (the viewer, a screenshot): writes go nowhere."""

    def write_bit(self, addr: int, value: int, *, user: str, label: str | None = None) -> None:
        pass

    def write_word(self, addr: int, value: int, *, user: str, label: str | None = None) -> None:
        pass

    def set_bit(self, addr: int, value: int) -> None:
        pass

    def put(self, record: Record) -> None:
        pass
