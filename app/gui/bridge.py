"""Hands runtime events and the command layer's answers to the GUI thread.

Records, readings and answers are produced on the scan, exchange and archive threads; Qt widgets
may only be touched on the GUI thread. A signal emitted from another thread is delivered through
the GUI thread's event loop.

Readings are coalesced: if the GUI falls behind, it skips to the newest scan instead of queueing a
backlog it can never catch up with. That is safe because the views only show: nothing of the
station's behaviour (sync pulses, element records) runs on this path; the runtime evaluates it
from every snapshot on the engine thread. Each delivery is one scan's `Readings`, its values and
their quality together (`readings.snapshot` is that scan's snapshot), from the station's public
feed `Runtime.watch`: a view never pairs the memory of one scan with the quality of another.

A command's ticket is answered on the engine's or the archive's thread (or at once, when refused);
`Answers` brings each answer to the GUI thread, so a view says a refusal where the operator looks
and never waits for an answer.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from PySide6.QtCore import QObject, Signal

from app.authority import Answer, Ticket
from app.scada.readings import Readings
from app.station.runtime import Runtime
from netplc.records import Record


class RuntimeBridge(QObject):
    readings = Signal(object)  # Readings of one scan, at most one waiting at a time
    record = Signal(object)  # Record, every one
    _ready = Signal()  # readings are waiting; emitted on the scan thread, delivered on the GUI thread

    def __init__(self, runtime: Runtime, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.runtime = runtime
        self._latest: Readings | None = None
        self._lock = threading.Lock()
        self._ready.connect(self._deliver)
        runtime.subscribe(self._on_record)
        started = runtime.engine is not None
        self._unwatch = runtime.watch(self._on_readings, "workstation") if started else None

    def detach(self) -> None:
        self.runtime.unsubscribe(self._on_record)
        if self._unwatch is not None:
            self._unwatch()
            self._unwatch = None

    def _on_record(self, record: Record) -> None:
        self.record.emit(record)

    def _on_readings(self, readings: Readings) -> None:
        with self._lock:
            pending = self._latest is not None
            self._latest = readings
        if not pending:
            self._ready.emit()

    def _deliver(self) -> None:
        with self._lock:
            readings, self._latest = self._latest, None
        if readings is not None:
            self.readings.emit(readings)


Then = Callable[[Answer], None]


class Answers(QObject):
    """The command layer's answers, on the GUI thread: `answered(what, answer)` for every ticket
    followed, `what` being the view's words for what was asked. A ticket refused at once is
    answered before `follow` returns (the refusal shows under the operator's hand); the others
    when the engine applied them and the archive committed their record. Made without a parent,
    it lives as long as a ticket still to be answered refers to it."""

    answered = Signal(str, object)  # what was asked, the layer's Answer
    _done = Signal(str, object, object)  # from whichever thread answers the ticket

    def __init__(self) -> None:
        super().__init__()
        self._done.connect(self._deliver)

    def follow(self, what: str, ticket: Ticket, then: Then | None = None) -> Ticket:
        """Say the answer of `ticket` (and call `then(answer)` first), on the GUI thread."""
        ticket.add_done_callback(lambda t: self._done.emit(what, t.result(), then))
        return ticket

    def _deliver(self, what: str, answer: Answer, then: Then | None) -> None:
        if then is not None:
            then(answer)
        self.answered.emit(what, answer)
