"""Records the engine and its helpers hand to the registrar.

The registrar owns storage; NetPlc only needs somewhere to put records, so the sink is a protocol
and tests use ListSink. Columns mirror the archive table (docs/architecture.md section 8).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, Protocol

Kind = Literal["data", "message", "operator", "system", "alarm"]  # alarm: app/scada/alarms.py


@dataclass(frozen=True, slots=True)
class Record:
    ts: float  # wall clock, seconds since the epoch (UTC)
    kind: Kind
    grp: int | None = None
    type: int | None = None
    source: str | None = None  # octal address, element name, user@peer...
    number: int | None = None  # message number for NMSG
    value: float | None = None
    text: str | None = None  # None for NMSG: the registrar resolves it from the catalog
    # the record's identity in a hot-standby pair (app/station/pair.py gives it to a record its
    # standby may archive too): the same in both stations' archives, so the plant archive keeps one
    pid: int | None = None


class RecordSink(Protocol):
    def put(self, record: Record) -> None: ...


class DurableSink(RecordSink, Protocol):
    """A sink that can say when records are on disk (the registrar's Store): the engine answers an
    outside writer only then (DESIGN 1), and applies no write whose record it has no room for.
    A sink without these methods counts a record as journaled once `put`."""

    def after_commit(self, callback: Callable[[], None]) -> None: ...

    def room(self) -> int: ...


class ListSink:
    """Keeps records in a list: for tests and for `python -m netplc run`."""

    def __init__(self) -> None:
        self.records: list[Record] = []

    def put(self, record: Record) -> None:
        self.records.append(record)


class NullSink:
    def put(self, record: Record) -> None:
        pass
