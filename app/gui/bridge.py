"""Hands runtime events to the GUI thread.

Records and snapshots are produced on the scan and exchange threads; Qt widgets may only be
touched on the GUI thread. A signal emitted from another thread is delivered through the GUI
thread's event loop. Snapshots are coalesced: if the GUI falls behind, it skips to the newest
scan instead of queueing a backlog it can never catch up with. That is safe because the views
only show: nothing of the station's behaviour (sync pulses, element records) runs on this path;
the runtime evaluates it from every snapshot on the engine thread.
"""

from __future__ import annotations

import threading

from PySide6.QtCore import QObject, Signal

from app.runtime import Runtime
from netplc.memory import Snapshot
from netplc.records import Record


class RuntimeBridge(QObject):
    snapshot = Signal(object)  # Snapshot, at most one waiting at a time
    record = Signal(object)  # Record, every one
    _ready = Signal()  # a snapshot is waiting; emitted on the scan thread, delivered on the GUI thread

    def __init__(self, runtime: Runtime, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.runtime = runtime
        self._latest: Snapshot | None = None
        self._lock = threading.Lock()
        self._ready.connect(self._deliver)
        runtime.subscribe(self._on_record)
        if runtime.engine is not None:
            runtime.engine.subscribe(self._on_snapshot)

    def detach(self) -> None:
        self.runtime.unsubscribe(self._on_record)
        engine = self.runtime.engine
        if engine is not None:
            engine.unsubscribe(self._on_snapshot)

    def _on_record(self, record: Record) -> None:
        self.record.emit(record)

    def _on_snapshot(self, snapshot: Snapshot) -> None:
        with self._lock:
            pending = self._latest is not None
            self._latest = snapshot
        if not pending:
            self._ready.emit()

    def _deliver(self) -> None:
        with self._lock:
            snapshot, self._latest = self._latest, None
        if snapshot is not None:
            self.snapshot.emit(snapshot)

